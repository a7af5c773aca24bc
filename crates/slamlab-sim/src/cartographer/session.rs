//! The Cartographer lesson's scenario, its parameter table and its run under
//! the generic [`Stepper`] (`lesson=cartographer`, thesis `000` Sec. 5.2):
//! a simulated robot in a built-in or loaded map (or a CARMEN log), mapped
//! scan by scan by [`CartographerSim`], with a kidnap at a chosen scan (the
//! URL's `kidnap-at=`, the lesson's Kidnap button, a click on the map).
//!
//! The parameters keep Cartographer's names (`num_range_data`,
//! `hit_probability`, `min_score`, ...) and the thesis's `T` and `f_size`,
//! the same names `slamlab run cartographer` takes as flags.
//!
//! [`Stepper`]: crate::stepper::Stepper

use crate::cartographer::input::{KidnapPlace, kidnap_input_to};
use crate::cartographer::{CartographerParams, CartographerPhase, CartographerSim};
use crate::grid::MappingInput;
use crate::grid::SimulatedLogConfig;
use crate::grid::SimulatedRun;
use crate::grid::run_params::{map_param, seed_param, steps_param};
use crate::params::{Param, Scenario, choose, count_field, number_field, switch_field};
use crate::stepper::Simulation;
use serde::{Deserialize, Serialize};
use slamlab_core::Pose2;
use slamlab_core::grid::OccupancyGrid;
use std::sync::Arc;

/// The lesson's id.
pub const LESSON: &str = "cartographer";

/// The lesson's scenario: where the scans come from and Cartographer's
/// parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CartographerScenario {
    /// Seed of every random stream.
    pub seed: u64,
    /// Built-in map name (`maze`, `office`) or a map file's location.
    pub map: String,
    /// Scans the simulated robot records.
    pub steps: usize,
    /// The scan before which the robot is carried elsewhere (None: never).
    pub kidnap_at: Option<usize>,
    /// Where the kidnap carries the robot (heading 0), metres; None: a random
    /// place chosen by `kidnap_place`.
    pub kidnap_to: Option<[f64; 2]>,
    /// Where a random kidnap goes: `mapped` (a place on the robot's path so
    /// far) or `anywhere` (any free place).
    pub kidnap_place: String,
    /// Kidnap detection (Algorithm 13) on or off.
    pub detection: bool,
    /// Loop closures on, or off: no branch-and-bound search at all, local
    /// SLAM alone (the open, doubled corridors of a long log).
    pub loop_closures: bool,
    /// Scans per submap before the next one starts.
    pub num_range_data: usize,
    /// Submap cell size, metres.
    pub resolution: f64,
    /// Probability of a hit cell.
    pub hit_probability: f64,
    /// Probability of a missed cell.
    pub miss_probability: f64,
    /// Loop-closure search half-width in x and y, metres.
    pub linear_search_window: f64,
    /// Loop-closure search half-width in heading, degrees.
    pub angular_search_window: f64,
    /// Submaps whose origin is farther than this from a node are not
    /// searched for loop closures with it, metres.
    pub max_constraint_distance: f64,
    /// The share of node-submap pairs searched for loop closures, sampled
    /// per submap.
    pub sampling_ratio: f64,
    /// Loop closures that tie two submaps before their pairs are searched
    /// no more (0: no limit).
    pub max_closures_per_submap_pair: usize,
    /// A loop closure must score above this.
    pub min_score: f64,
    /// A match between maps must score above this.
    pub global_min_score: f64,
    /// Optimize the pose graph every n nodes.
    pub optimize_every_n_nodes: usize,
    /// Huber scale of the optimization.
    pub huber_scale: f64,
    /// The thesis's trigger threshold `T`.
    pub t: f64,
    /// The thesis's average filter size `f_size`.
    pub f_size: usize,
}

impl Default for CartographerScenario {
    fn default() -> Self {
        let p = CartographerParams::default();
        Self {
            seed: 1,
            map: "maze".to_owned(),
            steps: 600,
            kidnap_at: None,
            kidnap_to: None,
            kidnap_place: KidnapPlace::Mapped.name().to_owned(),
            detection: p.detection,
            loop_closures: true,
            num_range_data: p.num_range_data,
            resolution: p.resolution,
            hit_probability: p.hit_probability,
            miss_probability: p.miss_probability,
            linear_search_window: p.linear_search_window,
            // Rounded to a nanodegree, so that 30° (stored in radians) reads 30, not
            // 29.999999999999996, in the panel and in share links.
            angular_search_window: (p.angular_search_window.to_degrees() * 1e9).round() / 1e9,
            max_constraint_distance: p.max_constraint_distance,
            sampling_ratio: p.sampling_ratio,
            max_closures_per_submap_pair: p.max_closures_per_submap_pair,
            min_score: p.min_score,
            global_min_score: p.global_min_score,
            optimize_every_n_nodes: p.optimize_every_n_nodes,
            huber_scale: p.huber_scale,
            t: p.kidnap.threshold,
            f_size: p.kidnap.filter_size,
        }
    }
}

impl CartographerScenario {
    /// The run's parameters: this scenario's over Cartographer's defaults.
    pub fn params(&self) -> CartographerParams {
        let mut p = CartographerParams {
            detection: self.detection,
            num_range_data: self.num_range_data,
            resolution: self.resolution,
            hit_probability: self.hit_probability,
            miss_probability: self.miss_probability,
            linear_search_window: self.linear_search_window,
            angular_search_window: self.angular_search_window.to_radians(),
            max_constraint_distance: self.max_constraint_distance,
            sampling_ratio: self.sampling_ratio,
            max_closures_per_submap_pair: self.max_closures_per_submap_pair,
            min_score: self.min_score,
            global_min_score: self.global_min_score,
            optimize_every_n_nodes: self.optimize_every_n_nodes,
            huber_scale: self.huber_scale,
            ..CartographerParams::default()
        };
        p.kidnap.threshold = self.t;
        p.kidnap.filter_size = self.f_size;
        if self.loop_closures {
            p
        } else {
            p.without_loop_closures()
        }
    }

    /// The simulated input on `map`: `steps` scans with this scenario's seed
    /// and kidnap (one past the last scan: none).
    pub fn simulate(&self, map: Arc<OccupancyGrid>, name: &str) -> Result<MappingInput, String> {
        let kidnap = self.kidnap_at.filter(|&k| k < self.steps);
        let place = match self.kidnap_to {
            Some([x, y]) => KidnapPlace::At(Pose2::new(x, y, 0.0)),
            None => KidnapPlace::from_name(&self.kidnap_place).unwrap_or_default(),
        };
        kidnap_input_to(
            map,
            name,
            self.steps,
            self.seed,
            kidnap.map(|k| (k, place)),
            &SimulatedLogConfig::default(),
        )
    }
}

/// Every parameter of the lesson, in the order `slamlab params --lesson
/// cartographer` lists them: Cartographer's names and the thesis's `T` and
/// `f_size`, as `slamlab run cartographer` takes them.
pub static PARAMS: &[Param<CartographerScenario>] = &[
    seed_param(),
    map_param(),
    steps_param(),
    Param::count(
        "kidnap-at",
        "",
        "carry the robot elsewhere just before this scan (0-based; absent: never)",
        (0, 20_000),
        |s| s.kidnap_at.map(|k| k as u64),
        |s, v| s.kidnap_at = usize::try_from(v).ok(),
    ),
    Param::number(
        "kidnap-x",
        "m",
        "where the kidnap carries the robot, x (absent: a random place, see kidnap-place)",
        (-1e4, 1e4),
        |s| s.kidnap_to.map(|p| p[0]),
        |s, v| {
            s.kidnap_to = Some([v, s.kidnap_to.map_or(0.0, |p| p[1])]);
            Ok(())
        },
    ),
    Param::number(
        "kidnap-y",
        "m",
        "where the kidnap carries the robot, y",
        (-1e4, 1e4),
        |s| s.kidnap_to.map(|p| p[1]),
        |s, v| {
            s.kidnap_to = Some([s.kidnap_to.map_or(0.0, |p| p[0]), v]);
            Ok(())
        },
    ),
    Param::words(
        "kidnap-place",
        "where a kidnap carries the robot: mapped (a random place on its path so far, where the maps can merge) or anywhere (any free place, often one it never maps again)",
        &KidnapPlace::NAMES,
        |s| Some(s.kidnap_place.clone()),
        |s, v| {
            choose(&KidnapPlace::NAMES, v)
                .map(|i| s.kidnap_place = KidnapPlace::NAMES[i].to_owned())
        },
    ),
    switch_field!(
        "detection",
        "kidnap detection (Xiang's thesis Algorithm 13): on, or off for the original behaviour (one corrupted map)",
        detection
    ),
    switch_field!(
        "loop-closures",
        "loop closures: on, or off for local SLAM alone (no branch-and-bound search)",
        loop_closures
    ),
    count_field!(
        "num_range_data",
        "scans per submap before the next starts (each takes twice as many)",
        (1, 10_000),
        num_range_data
    ),
    number_field!(
        "resolution",
        "m",
        "submap cell size",
        (0.02, 0.5),
        resolution
    ),
    number_field!(
        "hit_probability",
        "",
        "probability of a hit cell (Xiang's thesis Eq. 5.4)",
        (0.501, 0.999),
        hit_probability
    ),
    number_field!(
        "miss_probability",
        "",
        "probability of a missed cell (Xiang's thesis Eq. 5.4)",
        (0.001, 0.499),
        miss_probability
    ),
    number_field!(
        "linear_search_window",
        "m",
        "loop-closure search half-width in x and y",
        (0.0, 50.0),
        linear_search_window
    ),
    number_field!(
        "angular_search_window",
        "°",
        "loop-closure search half-width in heading",
        (0.0, 180.0),
        angular_search_window
    ),
    number_field!(
        "max_constraint_distance",
        "m",
        "search only submaps whose origin is this near a node",
        (0.0, 1000.0),
        max_constraint_distance
    ),
    number_field!(
        "sampling_ratio",
        "",
        "share of node-submap pairs searched for loop closures, sampled per submap (Cartographer's sampling_ratio)",
        (0.0, 1.0),
        sampling_ratio
    ),
    count_field!(
        "max_closures_per_submap_pair",
        "loop closures tying a node's submap to another before their node-submap pairs are searched no more (0: no limit)",
        (0, 10_000),
        max_closures_per_submap_pair
    ),
    number_field!(
        "min_score",
        "",
        "a loop closure must score above this",
        (0.0, 1.0),
        min_score
    ),
    number_field!(
        "global_min_score",
        "",
        "a match between maps (after a kidnap) must score above this",
        (0.0, 1.0),
        global_min_score
    ),
    count_field!(
        "optimize_every_n_nodes",
        "solve the pose graph every n nodes",
        (1, 10_000),
        optimize_every_n_nodes
    ),
    number_field!(
        "huber_scale",
        "",
        "Huber kernel's scale on a constraint's weighted error (Xiang's thesis Eq. 5.9)",
        (0.001, 1e6),
        huber_scale
    ),
    number_field!(
        "T",
        "",
        "kidnap trigger: the filtered cost exceeds T times its previous value (Xiang's thesis Algorithm 13)",
        (1.0, 100.0),
        t
    ),
    count_field!(
        "f_size",
        "kidnap average filter size, scans (Xiang's thesis Algorithm 13)",
        (1, 1000),
        f_size
    ),
];

impl SimulatedRun for CartographerScenario {
    fn run(&self) -> (&str, usize) {
        (&self.map, self.steps)
    }
    fn run_mut(&mut self) -> (&mut u64, &mut String, &mut usize) {
        (&mut self.seed, &mut self.map, &mut self.steps)
    }
}

impl Scenario for CartographerScenario {
    const LESSON: &'static str = LESSON;
    fn params() -> &'static [Param<Self>] {
        PARAMS
    }
    fn seed(&self) -> u64 {
        self.seed
    }
}

/// A live change to the run.
#[derive(Clone, Debug)]
pub enum CartographerEvent {
    /// From the next scan on, the scans of `input` (which agrees with the
    /// current input on every scan processed so far): a kidnap made live.
    Kidnap(Arc<MappingInput>),
}

/// The lesson's run: the mapper, cloned as a checkpoint; one tick is one
/// scan, its phases local SLAM, each branch-and-bound search and each
/// optimization ([`CartographerSim::step_phase`]).
#[derive(Clone, Debug)]
pub struct CartographerRun {
    sim: CartographerSim,
}

impl CartographerRun {
    /// A run of `input` with `scenario`'s parameters (and the notes on what
    /// had to be changed).
    pub fn new(scenario: &CartographerScenario, input: Arc<MappingInput>) -> (Self, Vec<String>) {
        let (sim, notes) = CartographerSim::new(input, scenario.params());
        (Self { sim }, notes)
    }

    /// The mapper.
    pub fn sim(&self) -> &CartographerSim {
        &self.sim
    }

    /// The mapper, to change what it records (not its results).
    pub fn sim_mut(&mut self) -> &mut CartographerSim {
        &mut self.sim
    }
}

impl Simulation for CartographerRun {
    type Phase = CartographerPhase;
    type Event = CartographerEvent;
    type Records = ();

    fn step_phase(&mut self, _records: &mut ()) -> CartographerPhase {
        self.sim.step_phase()
    }

    fn is_mid_tick(&self) -> bool {
        self.sim.is_mid_scan()
    }

    fn tick(&self) -> u64 {
        self.sim.scans_done() as u64
    }

    fn apply_event(&mut self, event: &CartographerEvent) {
        match event {
            CartographerEvent::Kidnap(input) => {
                self.sim.replace_input(input.clone());
            }
        }
    }

    fn checkpoint_bytes(&self) -> usize {
        let cells: usize = self.sim.submaps.iter().map(|s| s.grid.memory_bytes()).sum();
        cells + self.sim.nodes.len() * 1600 + self.sim.records.len() * 80
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params;

    #[test]
    fn the_table_round_trips() {
        let mut s = CartographerScenario {
            kidnap_at: Some(152),
            detection: false,
            t: 2.0,
            f_size: 7,
            ..CartographerScenario::default()
        };
        s.seed = 3;
        let pairs = params::to_pairs(&s);
        let mut back = CartographerScenario::default();
        let issues =
            params::apply_pairs(&mut back, pairs.iter().map(|(k, v)| (*k, v.as_str())), &[]);
        assert!(issues.is_empty(), "{issues:?}");
        assert_eq!(back, s);
        assert_eq!(params::to_pairs(&back), pairs);
    }

    /// The office runs with a kidnap at scan 152 (seeds 1 and 3) under the
    /// lesson's stepper, frame by frame as fast as the budget allows: before,
    /// whole scans until 25 ms were spent (a frame ends only after its last
    /// scan); now, phases until 12 ms were spent. Prints the worst frame and
    /// the longest scan and phase (docs/cartographer.md has the numbers).
    #[test]
    #[ignore = "a measurement: cargo test --release -p slamlab-sim --lib frame_times -- --ignored --nocapture"]
    fn frame_times_of_the_office_kidnap_runs() {
        use crate::stepper::{CheckpointPolicy, Stepper};
        use std::time::Instant;
        let policy = CheckpointPolicy {
            every_ticks: 20,
            max_checkpoints: 40,
            budget_bytes: 96 << 20,
        };
        for seed in [1, 3] {
            let scenario = CartographerScenario {
                seed,
                map: "office".to_owned(),
                kidnap_at: Some(152),
                ..CartographerScenario::default()
            };
            let grid = Arc::new(crate::grid::builtin_map("office").unwrap());
            let input = Arc::new(scenario.simulate(grid, "office").unwrap());
            for (by_phase, budget_ms) in [(false, 25.0), (true, 12.0)] {
                let (run, _) = CartographerRun::new(&scenario, input.clone());
                let mut stepper = Stepper::with_policy(run, (), policy);
                let (mut worst_frame, mut longest_step, mut frames) = (0.0f64, 0.0f64, 0);
                let mut longest = String::new();
                let started = Instant::now();
                while !stepper.sim().sim().is_done() {
                    let frame = Instant::now();
                    while !stepper.sim().sim().is_done()
                        && frame.elapsed().as_secs_f64() * 1e3 < budget_ms
                    {
                        let step = Instant::now();
                        let phase = if by_phase {
                            Some(stepper.step_phase())
                        } else {
                            stepper.step_tick();
                            None
                        };
                        let ms = step.elapsed().as_secs_f64() * 1e3;
                        if ms > longest_step {
                            longest_step = ms;
                            longest = format!("{phase:?}");
                        }
                    }
                    worst_frame = worst_frame.max(frame.elapsed().as_secs_f64() * 1e3);
                    frames += 1;
                }
                let total = started.elapsed().as_secs_f64();
                eprintln!(
                    "office seed {seed}, {}: worst frame {worst_frame:.1} ms, longest {} \
                     {longest_step:.1} ms ({longest}), {frames} frames, {total:.2} s",
                    if by_phase {
                        "phases, 12 ms"
                    } else {
                        "whole scans, 25 ms"
                    },
                    if by_phase { "phase" } else { "scan" },
                );
                assert_eq!(stepper.sim().sim().scans_done(), 600);
            }
        }
    }

    #[test]
    fn bad_values_are_clamped_with_a_message() {
        let mut s = CartographerScenario::default();
        let pairs = [("num_range_data", "0"), ("T", "nan"), ("min_score", "7")];
        let issues = params::apply_pairs(&mut s, pairs, &[]);
        assert_eq!(issues.len(), 3, "{issues:?}");
        assert_eq!(s.num_range_data, 1);
        assert_eq!(s.t, CartographerScenario::default().t);
        assert_eq!(s.min_score, 1.0);
    }
}
