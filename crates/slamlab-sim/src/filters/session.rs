//! The filters lesson (`lesson=filters`): the estimators before any SLAM
//! (thesis `000` ch. 2; thesis `002` ch. 2).
//!
//! - [`one_step`]: one prior Gaussian through one nonlinear function by the EKF's
//!   linearization, the unscented transform and `N` particles, each measured
//!   against the moments of many samples (the "truth" of the transformed
//!   distribution);
//! - [`CorridorSim`]: a robot in a corridor with doors, tracked by a histogram
//!   Bayes filter and by a 1-D Kalman filter on the same motions and sensor
//!   readings, stepped by the generic [`Stepper`](crate::stepper::Stepper).
//!
//! [`FiltersScenario`] is the lesson's one parameter table.

use crate::params::{Param, ParamIssue, Scenario, choose, count_field, number_field};
use crate::stepper::Simulation;
use nalgebra::{Matrix2, Vector2};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use slamlab_core::filters::histogram::{Corridor, Histogram};
use slamlab_core::filters::one_step::{
    self, Cloud, Comparison, Gaussian2, Linearized, OneStepError, StepFunction, Unscented,
};
use slamlab_core::filters::{Kalman1, KalmanUpdate};
use slamlab_core::kalman::unscented::UnscentedParams;
use slamlab_core::random::gaussian;

/// The functions a student can choose.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FunctionKind {
    /// Polar to Cartesian.
    #[default]
    Polar,
    /// A landmark's position to range and bearing.
    RangeBearing,
    /// The robot's control to its position after one step (exact arc).
    Motion,
    /// `y = [[1, c], [0, 1]] x`.
    Linear,
    /// `y = (x₁, x₂ + c x₁²)`.
    Quadratic,
    /// `y = (x₁, e^(c x₂))`.
    Exp,
}

/// The functions' names, in menu order.
pub const FUNCTION_NAMES: &[&str] = &[
    "polar",
    "range-bearing",
    "motion",
    "linear",
    "quadratic",
    "exp",
];

impl FunctionKind {
    /// Every function, in menu order.
    pub const ALL: [FunctionKind; 6] = [
        FunctionKind::Polar,
        FunctionKind::RangeBearing,
        FunctionKind::Motion,
        FunctionKind::Linear,
        FunctionKind::Quadratic,
        FunctionKind::Exp,
    ];

    /// The name in URLs and the CLI.
    pub fn name(self) -> &'static str {
        FUNCTION_NAMES[self as usize]
    }

    /// The prior this function opens with: mean, standard deviations, correlation.
    pub fn default_prior(self) -> ([f64; 2], [f64; 2], f64) {
        match self {
            FunctionKind::Polar => ([1.0, 0.0], [0.1, 30f64.to_radians()], 0.0),
            FunctionKind::RangeBearing => ([2.0, 0.5], [0.6, 0.6], 0.0),
            FunctionKind::Motion => ([1.0, 0.5], [0.1, 0.6], 0.0),
            FunctionKind::Linear => ([0.0, 0.0], [1.0, 0.5], 0.3),
            FunctionKind::Quadratic => ([0.0, 0.0], [1.0, 0.3], 0.0),
            FunctionKind::Exp => ([0.0, 0.0], [0.5, 0.5], 0.0),
        }
    }
}

/// The lesson's parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FiltersScenario {
    /// Seed of every random stream (samples, particles, corridor noise).
    pub seed: u64,
    /// The function of the one-step comparison.
    pub function: FunctionKind,
    /// The coefficient `c` of the typed forms.
    pub coefficient: f64,
    /// The motion function's time step, s.
    pub dt: f64,
    /// The prior mean, in the input's units.
    pub mean: [f64; 2],
    /// The prior standard deviations, in the input's units.
    pub std: [f64; 2],
    /// The prior correlation coefficient.
    pub rho: f64,
    /// The unscented transform's `α`.
    pub alpha: f64,
    /// `β`.
    pub beta: f64,
    /// `κ`.
    pub kappa: f64,
    /// Samples of the reference distribution.
    pub samples: usize,
    /// Particles of the particle approximation.
    pub particles: usize,
    /// Corridor: distance moved per step, m.
    pub step: f64,
    /// Corridor: standard deviation of the motion per step, m.
    pub motion_std: f64,
    /// Corridor: the robot's true start, m.
    pub start: f64,
    /// Corridor: `p(door seen | at a door)`.
    pub p_hit: f64,
    /// Corridor: `p(door seen | at a wall)`.
    pub p_false: f64,
    /// Corridor: the Kalman filter's measurement deviation for a door sighting, m.
    pub measurement_std: f64,
    /// Corridor: the histogram's cell width, m.
    pub cell: f64,
}

impl Default for FiltersScenario {
    fn default() -> Self {
        let (mean, std, rho) = FunctionKind::Polar.default_prior();
        Self {
            seed: 1,
            function: FunctionKind::Polar,
            coefficient: 0.5,
            dt: 1.0,
            mean,
            std,
            rho,
            alpha: 1.0,
            beta: 2.0,
            kappa: 0.0,
            samples: 100_000,
            particles: 200,
            step: 0.5,
            motion_std: 0.1,
            start: 1.0,
            p_hit: 0.8,
            p_false: 0.1,
            measurement_std: 0.4,
            cell: 0.05,
        }
    }
}

impl FiltersScenario {
    /// The prior belief.
    pub fn prior(&self) -> Gaussian2 {
        Gaussian2::from_std(self.mean, self.std, self.rho)
    }

    /// The chosen function with its parameters.
    pub fn step_function(&self) -> StepFunction {
        let c = self.coefficient;
        match self.function {
            FunctionKind::Polar => StepFunction::Polar,
            FunctionKind::RangeBearing => StepFunction::RangeBearing,
            FunctionKind::Motion => StepFunction::Motion { dt: self.dt },
            FunctionKind::Linear => StepFunction::Linear {
                a: Matrix2::new(1.0, c, 0.0, 1.0),
                b: Vector2::zeros(),
            },
            FunctionKind::Quadratic => StepFunction::Quadratic { c },
            FunctionKind::Exp => StepFunction::Exponential { c },
        }
    }

    /// The unscented parameters.
    pub fn unscented(&self) -> UnscentedParams {
        UnscentedParams {
            alpha: self.alpha,
            beta: self.beta,
            kappa: self.kappa,
        }
    }

    /// The corridor of the Bayes-filter example.
    pub fn corridor(&self) -> Corridor {
        Corridor::default()
    }
}

/// Largest sample count.
pub const MAX_SAMPLES: u64 = 1_000_000;

/// The lesson's parameter table.
pub static PARAMS: &[Param<FiltersScenario>] = &[
    count_field!(
        "seed",
        "seed of the samples, the particles and the corridor's noise",
        (0, u64::MAX),
        seed
    ),
    Param::words(
        "function",
        "the nonlinear function of the one-step comparison (choosing one resets the prior to its own)",
        FUNCTION_NAMES,
        |s| Some(s.function.name().to_owned()),
        |s, v| {
            let f = FunctionKind::ALL[choose(FUNCTION_NAMES, v)?];
            if f != s.function {
                s.function = f;
                (s.mean, s.std, s.rho) = f.default_prior();
            }
            Ok(())
        },
    ),
    number_field!(
        "coefficient",
        "",
        "c of the typed forms: linear [[1, c], [0, 1]] x, quadratic (x₁, x₂ + c x₁²), exp (x₁, e^(c x₂))",
        (-100.0, 100.0),
        coefficient
    ),
    number_field!(
        "dt",
        "s",
        "time step of the motion function",
        (0.01, 10.0),
        dt
    ),
    number_field!(
        "mean-1",
        "",
        "prior mean, first input (range m, x m, speed m/s, x₁)",
        (-1e6, 1e6),
        mean[0]
    ),
    number_field!(
        "mean-2",
        "",
        "prior mean, second input (bearing rad, y m, turn rate rad/s, x₂)",
        (-1e6, 1e6),
        mean[1]
    ),
    number_field!(
        "std-1",
        "",
        "prior standard deviation, first input (0 is refused by the lesson with a note)",
        (0.0, 1e6),
        std[0]
    ),
    number_field!(
        "std-2",
        "",
        "prior standard deviation, second input",
        (0.0, 1e6),
        std[1]
    ),
    // Polar's own names for its deviations (write-only: links carry std-1, std-2).
    Param::number(
        "range-std",
        "m",
        "polar: the range's standard deviation (sets std-1)",
        (0.0, 1e6),
        |_| None,
        |s, v| {
            s.std[0] = v;
            Ok(())
        },
    ),
    Param::number(
        "bearing-std-deg",
        "deg",
        "polar: the bearing's standard deviation (sets std-2 in radians)",
        (0.0, 360.0),
        |_| None,
        |s, v| {
            s.std[1] = v.to_radians();
            Ok(())
        },
    ),
    number_field!(
        "rho",
        "",
        "prior correlation coefficient (±1 is singular: refused with a note)",
        (-1.0, 1.0),
        rho
    ),
    number_field!(
        "alpha",
        "",
        "unscented α: spread of the sigma points",
        (1e-4, 10.0),
        alpha
    ),
    number_field!(
        "beta",
        "",
        "unscented β: 2 is optimal for a Gaussian prior",
        (-10.0, 10.0),
        beta
    ),
    number_field!(
        "kappa",
        "",
        "unscented κ: secondary scaling; α²(2 + κ) must stay positive",
        (-10.0, 10.0),
        kappa
    ),
    count_field!(
        "samples",
        "samples of the true transformed distribution",
        (2, MAX_SAMPLES),
        samples
    ),
    count_field!(
        "particles",
        "particles of the particle approximation (0 is refused with a note)",
        (0, 100_000),
        particles
    ),
    number_field!(
        "step",
        "m",
        "corridor: distance the robot moves per step",
        (-5.0, 5.0),
        step
    ),
    number_field!(
        "motion-std",
        "m",
        "corridor: standard deviation of each step's motion (Q = motion-std²)",
        (0.0, 5.0),
        motion_std
    ),
    number_field!(
        "start",
        "m",
        "corridor: where the robot really starts (the filters do not know)",
        (0.0, 20.0),
        start
    ),
    number_field!(
        "p-hit",
        "",
        "corridor: probability the sensor says door in front of a door",
        (0.0, 1.0),
        p_hit
    ),
    number_field!(
        "p-false",
        "",
        "corridor: probability the sensor says door in front of a wall",
        (0.0, 1.0),
        p_false
    ),
    number_field!(
        "measurement-std",
        "m",
        "corridor: the Kalman filter's measurement deviation for a door sighting (R = std²)",
        (0.0, 10.0),
        measurement_std
    ),
    number_field!(
        "cell",
        "m",
        "corridor: the histogram's cell width",
        (0.01, 1.0),
        cell
    ),
];

impl Scenario for FiltersScenario {
    const LESSON: &'static str = "filters";

    fn params() -> &'static [Param<Self>] {
        PARAMS
    }

    fn seed(&self) -> u64 {
        self.seed
    }

    /// The function first: it resets the prior, which the other pairs then set.
    fn apply_rank(name: &str) -> u8 {
        match name {
            "preset" => 0,
            "function" => 1,
            _ => 2,
        }
    }

    fn check(&mut self) -> Vec<ParamIssue> {
        Vec::new()
    }
}

/// Seed offsets of the random streams (one per consumer).
const SAMPLES_STREAM: u64 = 0x5a3d_0001;
const PARTICLES_STREAM: u64 = 0x5a3d_0002;
const CORRIDOR_STREAM: u64 = 0x5a3d_0003;

/// One method's Gaussian and how far it is from the samples' moments.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodRow {
    /// `ekf`, `ukf` or `particles`.
    pub method: &'static str,
    /// The method's Gaussian.
    #[serde(skip)]
    pub gaussian: Gaussian2,
    /// The distances.
    #[serde(flatten)]
    pub comparison: Comparison,
}

/// The one-step comparison.
#[derive(Clone, Debug)]
pub struct OneStep {
    /// The prior.
    pub prior: Gaussian2,
    /// The function.
    pub function: StepFunction,
    /// The reference samples and their moments.
    pub truth: Cloud,
    /// The EKF's linearization.
    pub ekf: Linearized,
    /// The unscented transform.
    pub ukf: Unscented,
    /// The particle approximation.
    pub particles: Cloud,
    /// EKF, UKF, particles against the samples.
    pub rows: Vec<MethodRow>,
}

/// Runs the one-step comparison. Every stream is seeded from `scenario.seed`, so
/// the same scenario gives the same numbers natively and in the browser.
pub fn one_step(scenario: &FiltersScenario) -> Result<OneStep, OneStepError> {
    one_step_with(scenario, &mut Draws::default())
}

/// The standard normal draws behind the samples and the particles, kept between
/// recomputations. They depend only on the seed and the counts, not on the prior
/// or the function, so a student dragging the prior needs only `x̄ + L n`, `f`
/// and the moments of each sample, not 200,000 new draws
/// ([`one_step::sample_from_normals`]).
#[derive(Clone, Debug, Default)]
pub struct Draws {
    samples: Stream,
    particles: Stream,
}

/// One stream's first draws. A seeded stream's first `n` draws are the same
/// whatever is drawn after them, so fewer samples use the front of the kept ones.
#[derive(Clone, Debug, Default)]
struct Stream {
    seed: u64,
    normals: Vec<Vector2<f64>>,
}

impl Stream {
    /// The first `count` draws of the stream seeded with `seed`, drawn only when
    /// the seed changed or more are asked for than are kept.
    fn first(&mut self, seed: u64, count: usize) -> &[Vector2<f64>] {
        if seed != self.seed || count > self.normals.len() {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            self.normals = one_step::standard_normals(count, &mut rng);
            self.seed = seed;
        }
        &self.normals[..count]
    }
}

/// [`one_step`] with the draws kept in `draws` (drawn first when the seed or a
/// count changed): the same result, bit for bit, without drawing again.
pub fn one_step_with(
    scenario: &FiltersScenario,
    draws: &mut Draws,
) -> Result<OneStep, OneStepError> {
    let prior = scenario.prior();
    let function = scenario.step_function();
    let ekf = one_step::linearize(&prior, &function)?;
    let ukf = one_step::unscented(&prior, &function, &scenario.unscented())?;
    let normals = draws
        .samples
        .first(scenario.seed ^ SAMPLES_STREAM, scenario.samples);
    let truth = one_step::sample_from_normals(&prior, &function, normals, "samples")?;
    let normals = draws
        .particles
        .first(scenario.seed ^ PARTICLES_STREAM, scenario.particles);
    let particles = one_step::sample_from_normals(&prior, &function, normals, "particles")?;
    let rows = [
        ("ekf", ekf.gaussian),
        ("ukf", ukf.gaussian),
        ("particles", particles.moments),
    ]
    .into_iter()
    .map(|(method, gaussian)| MethodRow {
        method,
        gaussian,
        comparison: one_step::compare(&gaussian, &truth.moments),
    })
    .collect();
    Ok(OneStep {
        prior,
        function,
        truth,
        ekf,
        ukf,
        particles,
        rows,
    })
}

/// The corridor's two phases.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CorridorPhase {
    /// The robot moves; both filters predict.
    Predict,
    /// The sensor looks; both filters update.
    Update,
}

impl CorridorPhase {
    /// The phase's name on screen.
    pub fn name(self) -> &'static str {
        match self {
            CorridorPhase::Predict => "predict",
            CorridorPhase::Update => "update",
        }
    }
}

/// The corridor run (a 20 m loop): the truth, the histogram filter and the
/// Kalman filter.
#[derive(Clone, Debug)]
pub struct CorridorSim {
    scenario: FiltersScenario,
    corridor: Corridor,
    /// The robot's true position (only the metrics see it).
    truth: f64,
    histogram: Histogram,
    kalman: Kalman1,
    rng: ChaCha8Rng,
    tick: u64,
    next: CorridorPhase,
    /// What the last sensor reading said.
    saw_door: Option<bool>,
    /// The Kalman filter's last update (a door sighting), with the door it assumed;
    /// kept through the wall readings after it, until the next sighting.
    last_update: Option<(KalmanUpdate, f64)>,
    /// The step of that update.
    last_update_tick: u64,
    /// Why the last step could not be taken.
    note: Option<String>,
}

impl CorridorSim {
    /// The corridor at its start: the histogram uniform, the Kalman filter
    /// centred on the corridor with a variance as wide as the corridor's.
    pub fn new(scenario: FiltersScenario) -> Self {
        let corridor = scenario.corridor();
        let cells = (corridor.length / scenario.cell).round().max(1.0) as usize;
        let (histogram, note) = match Histogram::uniform(0.0, scenario.cell, cells) {
            Ok(h) => (h, None),
            Err(e) => (Histogram::default(), Some(e.to_string())),
        };
        // The uniform distribution's variance, L²/12.
        let kalman = Kalman1::new(
            0.5 * corridor.length,
            corridor.length * corridor.length / 12.0,
        );
        Self {
            truth: corridor.wrap(scenario.start),
            rng: ChaCha8Rng::seed_from_u64(scenario.seed ^ CORRIDOR_STREAM),
            scenario,
            corridor,
            histogram,
            kalman,
            tick: 0,
            next: CorridorPhase::Predict,
            saw_door: None,
            last_update: None,
            last_update_tick: 0,
            note,
        }
    }

    /// The scenario.
    pub fn scenario(&self) -> &FiltersScenario {
        &self.scenario
    }
    /// The corridor.
    pub fn corridor(&self) -> &Corridor {
        &self.corridor
    }
    /// The true position (for drawing and metrics only).
    pub fn truth(&self) -> f64 {
        self.truth
    }
    /// The histogram filter.
    pub fn histogram(&self) -> &Histogram {
        &self.histogram
    }
    /// The Kalman filter.
    pub fn kalman(&self) -> &Kalman1 {
        &self.kalman
    }
    /// The next phase.
    pub fn next_phase(&self) -> CorridorPhase {
        self.next
    }
    /// The last sensor reading.
    pub fn saw_door(&self) -> Option<bool> {
        self.saw_door
    }
    /// The Kalman filter's last update (its last door sighting, however many wall
    /// readings ago) and the door it assumed it saw.
    pub fn last_update(&self) -> Option<&(KalmanUpdate, f64)> {
        self.last_update.as_ref()
    }
    /// The step of [`last_update`](Self::last_update).
    pub fn last_update_tick(&self) -> u64 {
        self.last_update_tick
    }
    /// Why the last step was refused.
    pub fn note(&self) -> Option<&str> {
        self.note.as_deref()
    }

    fn predict(&mut self) {
        let s = &self.scenario;
        let moved = s.step + gaussian(&mut self.rng, s.motion_std);
        self.truth = self.corridor.wrap(self.truth + moved);
        self.note = None;
        if let Err(e) = self.histogram.predict(s.step, s.motion_std) {
            self.note = Some(e.to_string());
        }
        if let Err(e) = self.kalman.predict(s.step, s.motion_std * s.motion_std) {
            self.note = Some(e.to_string());
        }
        // The loop: the Gaussian's mean comes back in at the other end.
        self.kalman.mean = self.corridor.wrap(self.kalman.mean);
    }

    fn update(&mut self) {
        let s = &self.scenario;
        let at_door = self.corridor.at_door(self.truth);
        let p = if at_door { s.p_hit } else { s.p_false };
        let u: f64 = rand::Rng::random(&mut self.rng);
        let saw = u < p;
        self.saw_door = Some(saw);
        let (corridor, p_hit, p_false) = (&self.corridor, s.p_hit, s.p_false);
        if let Err(e) = self
            .histogram
            .update(|x| corridor.door_likelihood(x, saw, p_hit, p_false))
        {
            self.note = Some(e.to_string());
        }
        // A Gaussian filter can only use "door" as a position: the door nearest its
        // mean (the association a unimodal belief has to make). "No door" tells it
        // nothing it can write as a Gaussian (its last update stays on record).
        if saw && let Some(door) = self.corridor.nearest_door(self.kalman.mean) {
            match self
                .kalman
                .update(door, s.measurement_std * s.measurement_std)
            {
                Ok(report) => {
                    self.kalman.mean = self.corridor.wrap(self.kalman.mean);
                    self.last_update = Some((report, door));
                    self.last_update_tick = self.tick;
                }
                Err(e) => self.note = Some(e.to_string()),
            }
        }
    }
}

impl Simulation for CorridorSim {
    type Phase = CorridorPhase;
    type Event = ();
    type Records = ();

    fn step_phase(&mut self, _records: &mut ()) -> CorridorPhase {
        let phase = self.next;
        match phase {
            CorridorPhase::Predict => {
                self.tick += 1;
                self.predict();
                self.next = CorridorPhase::Update;
            }
            CorridorPhase::Update => {
                self.update();
                self.next = CorridorPhase::Predict;
            }
        }
        phase
    }

    fn is_mid_tick(&self) -> bool {
        self.next == CorridorPhase::Update
    }

    fn tick(&self) -> u64 {
        self.tick
    }

    fn apply_event(&mut self, _event: &()) {}

    fn checkpoint_bytes(&self) -> usize {
        std::mem::size_of::<Self>() + 8 * self.histogram.belief().len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{apply_pairs, set, to_pairs};
    use crate::stepper::Stepper;

    #[test]
    fn the_table_round_trips() {
        let s = FiltersScenario {
            function: FunctionKind::Motion,
            mean: [1.5, -0.25],
            alpha: 0.5,
            particles: 17,
            ..Default::default()
        };
        let pairs = to_pairs(&s);
        let mut back = FiltersScenario::default();
        let issues = apply_pairs(&mut back, pairs.iter().map(|(k, v)| (*k, v.as_str())), &[]);
        assert!(issues.is_empty(), "{issues:?}");
        assert_eq!(to_pairs(&back), pairs);
        assert_eq!(
            (back.function, back.mean, back.particles),
            (s.function, s.mean, s.particles)
        );
    }

    #[test]
    fn the_cli_names_set_the_polar_prior_and_bad_values_say_so() {
        let mut s = FiltersScenario::default();
        let issues = apply_pairs(
            &mut s,
            [
                ("bearing-std-deg", "45"),
                ("range-std", "0.2"),
                ("function", "polar"),
            ],
            &[],
        );
        assert!(issues.is_empty(), "{issues:?}");
        assert!((s.std[1] - 45f64.to_radians()).abs() < 1e-15 && s.std[0] == 0.2);
        assert!(set(&mut s, "function", "banana").is_some());
        assert_eq!(s.function, FunctionKind::Polar);
        assert!(set(&mut s, "alpha", "NaN").is_some());
        assert_eq!(s.alpha, 1.0);
    }

    #[test]
    fn bad_beliefs_are_refused_with_a_reason() {
        let s = FiltersScenario {
            rho: 1.0,
            ..Default::default()
        };
        assert!(matches!(
            one_step(&s),
            Err(OneStepError::NotPositiveDefinite { .. })
        ));
        let s = FiltersScenario {
            particles: 0,
            ..Default::default()
        };
        assert!(
            one_step(&s)
                .unwrap_err()
                .to_string()
                .contains("0 particles")
        );
        let s = FiltersScenario {
            kappa: -2.0,
            ..Default::default()
        };
        assert!(matches!(one_step(&s), Err(OneStepError::Unscented(_))));
    }

    #[test]
    fn the_polar_comparison_is_seeded_and_the_ukf_beats_the_ekf() {
        let s = FiltersScenario {
            samples: 20_000,
            ..Default::default()
        };
        let a = one_step(&s).unwrap();
        let b = one_step(&s).unwrap();
        assert_eq!(a.rows, b.rows);
        let (ekf, ukf) = (&a.rows[0].comparison, &a.rows[1].comparison);
        assert!(ukf.mean_error < ekf.mean_error, "{ukf:?} {ekf:?}");
        assert!(
            ukf.covariance_error < ekf.covariance_error,
            "{ukf:?} {ekf:?}"
        );
    }

    /// Every number of a one-step result that the lesson shows, as bits.
    fn bits(r: &OneStep) -> Vec<u64> {
        let cloud = |c: &Cloud| {
            c.points
                .iter()
                .flat_map(|p| p.iter().copied())
                .chain(c.moments.mean.iter().copied())
                .chain(c.moments.covariance.iter().copied())
                .collect::<Vec<f64>>()
        };
        let mut v = cloud(&r.truth);
        v.extend(cloud(&r.particles));
        for row in &r.rows {
            v.extend(
                row.gaussian
                    .mean
                    .iter()
                    .chain(row.gaussian.covariance.iter()),
            );
            v.extend([row.comparison.mean_error, row.comparison.covariance_error]);
            v.extend(row.comparison.kl_divergence);
        }
        v.into_iter().map(f64::to_bits).collect()
    }

    #[test]
    fn kept_draws_give_the_comparison_of_drawing_afresh_bit_for_bit() {
        // A drag of the prior, then the changes that must draw again (seed, more
        // samples, more particles) or may use the front of the kept draws (fewer),
        // and a refused count in between: each equals a fresh `one_step`.
        let base = FiltersScenario {
            samples: 20_000,
            ..Default::default()
        };
        let mut steps = Vec::new();
        for k in 0..5 {
            let d = 0.01 * f64::from(k);
            steps.push(FiltersScenario {
                mean: [base.mean[0] + d, base.mean[1] - 0.5 * d],
                rho: 0.1 * f64::from(k),
                ..base.clone()
            });
        }
        steps.push(FiltersScenario {
            seed: 2,
            ..base.clone()
        });
        steps.push(FiltersScenario {
            seed: 2,
            samples: 5_000,
            ..base.clone()
        });
        steps.push(FiltersScenario {
            seed: 2,
            samples: 30_000,
            particles: 0,
            ..base.clone()
        });
        steps.push(FiltersScenario {
            seed: 2,
            samples: 30_000,
            particles: 500,
            function: FunctionKind::Motion,
            ..base.clone()
        });
        let mut draws = Draws::default();
        for s in &steps {
            match (one_step_with(s, &mut draws), one_step(s)) {
                (Ok(kept), Ok(fresh)) => assert_eq!(bits(&kept), bits(&fresh), "{s:?}"),
                (kept, fresh) => assert_eq!(kept.err(), fresh.err(), "{s:?}"),
            }
        }
        assert!(one_step_with(&steps[7], &mut draws).is_err());
    }

    #[test]
    fn the_corridor_localizes_and_stepping_back_is_exact() {
        let s = FiltersScenario::default();
        let mut stepper = Stepper::new(CorridorSim::new(s), ());
        stepper.run_ticks(14);
        let sim = stepper.sim();
        let h = sim.histogram();
        assert!((h.belief().iter().sum::<f64>() - 1.0).abs() < 1e-12);
        // 14 steps of 0.5 m from 1 m: past the doors at 3 and 6 m, whose gap of
        // 3 m fits no other pair of doors on the loop. Seed 1: the mode is 8 mm
        // from the truth and 75.1% of the belief within 1 m of it (the sensor's
        // false alarms keep some mass elsewhere).
        let mass = h.mass_within(sim.truth() - 1.0, sim.truth() + 1.0);
        assert!(
            mass > 0.7 && (h.mode() - sim.truth()).abs() < 0.25,
            "truth {} mode {} mass {mass}",
            sim.truth(),
            h.mode()
        );
        let belief = h.belief().to_vec();
        let kalman = *sim.kalman();
        stepper.step_phase();
        assert!(stepper.step_back());
        assert_eq!(stepper.sim().histogram().belief(), &belief[..]);
        assert_eq!(*stepper.sim().kalman(), kalman);
    }
}
