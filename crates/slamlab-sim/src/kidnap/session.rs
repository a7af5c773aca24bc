//! The Monte Carlo localization lesson's run under the generic [`Stepper`]
//! ([`crate::stepper`]): the phases are the runner's (move, predict, weight,
//! resample), and the live events a student causes (a kidnap by button or click,
//! scattering the particles, resetting them around the truth) are recorded, so
//! stepping back and share links replay them exactly.
//!
//! [`Stepper`]: crate::stepper::Stepper

use crate::grid::builtin::BuiltinMap;
use crate::grid::scans::{MappingInput, builtin_map};
use crate::io::ros_map::{load_lone_image, load_map, parse_map_yaml};
use crate::kidnap::{MclPhase, MclRun, MclScenario};
use crate::params;
use crate::stepper::Simulation;
use slamlab_core::Pose2;
use slamlab_core::grid::OccupancyGrid;

/// The resolution a lone dropped image is read at, metres per pixel (a ROS
/// map's YAML gives its own).
pub const LONE_IMAGE_RESOLUTION: f64 = 0.05;

/// A live change to the lesson's run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KidnapEvent {
    /// Teleport the robot to this pose (a click on the map). The filters are not told.
    KidnapTo(Pose2),
    /// Teleport the robot to a random free pose at least `kidnap-distance` away.
    KidnapRandom,
    /// Scatter every filter's particles uniformly over the free space.
    GlobalLocalization,
    /// Put every filter's particles around the true pose (tracking).
    ResetAroundTruth,
    /// Drive by hand with `(v, w)` from the next move on (m/s, rad/s).
    Drive(f64, f64),
    /// Give the wheel back to the explorer.
    Explore,
}

impl KidnapEvent {
    /// What happened, for the lesson's note.
    pub fn describe(&self) -> String {
        match self {
            KidnapEvent::KidnapTo(p) => format!(
                "Kidnapped to ({:.2}, {:.2}) m, heading {:.0}°: the filters were not told",
                p.x,
                p.y,
                p.theta.to_degrees()
            ),
            KidnapEvent::KidnapRandom => {
                "Kidnapped to a random free pose: the filters were not told".to_owned()
            }
            KidnapEvent::GlobalLocalization => {
                "Particles scattered over the whole free space: global localization".to_owned()
            }
            KidnapEvent::ResetAroundTruth => "Particles reset around the true pose".to_owned(),
            KidnapEvent::Drive(v, w) => {
                format!("Driving by hand: v = {v:.2} m/s, w = {w:.2} rad/s")
            }
            KidnapEvent::Explore => "The explorer drives again".to_owned(),
        }
    }
}

/// The lesson's simulation: the runner, cloned as a checkpoint.
#[derive(Clone, Debug)]
pub struct KidnapSim {
    run: MclRun,
}

impl KidnapSim {
    /// Opens a run of `scenario` on `grid`, or on the built-in map the scenario
    /// names. Parameters out of range are clamped (with a notice); a map on which
    /// the robot cannot be placed falls back to the maze. Returns the notices for
    /// the user, or why not even the maze could open.
    pub fn open(
        mut scenario: MclScenario,
        grid: Option<OccupancyGrid>,
    ) -> Result<(Self, Vec<String>), String> {
        let mut notices = params::sanitize_notices(&mut scenario);
        let grid = match grid {
            Some(grid) => Ok(grid),
            None => builtin_map(&scenario.map),
        };
        let run = grid.and_then(|g| MclRun::new(scenario.clone(), g).map_err(|e| e.to_string()));
        let run = match run {
            Ok(run) => run,
            Err(why) => {
                notices.push(format!("{why}; the maze opens instead"));
                let maze = MclScenario {
                    map: "maze".to_owned(),
                    ..scenario
                };
                let grid = BuiltinMap::Maze.load().map_err(|e| e.to_string())?;
                MclRun::new(maze, grid).map_err(|e| e.to_string())?
            }
        };
        notices.extend(run.notes().iter().cloned());
        Ok((Self { run }, notices))
    }

    /// Opens a replay of a recorded robot's `input` (a CARMEN log or a ROS 2
    /// bag through [`crate::grid::LaserFile`]) in `grid`, or in the built-in
    /// map the scenario names ([`MclRun::from_log`]). Parameters out of range
    /// are clamped (with a notice); a log that cannot be replayed is refused
    /// with the reason, and the caller keeps its run.
    pub fn open_log(
        mut scenario: MclScenario,
        grid: Option<OccupancyGrid>,
        input: MappingInput,
    ) -> Result<(Self, Vec<String>), String> {
        let mut notices = params::sanitize_notices(&mut scenario);
        let grid = match grid {
            Some(grid) => grid,
            None => builtin_map(&scenario.map)?,
        };
        let run = MclRun::from_log(scenario, grid, input).map_err(|e| e.to_string())?;
        notices.extend(run.notes().iter().cloned());
        Ok((Self { run }, notices))
    }

    /// The runner: truth, map, scan and filters.
    pub fn run(&self) -> &MclRun {
        &self.run
    }

    /// Can the robot be kidnapped to `pose` (is its disc clear of the walls)?
    pub fn check_kidnap(&self, pose: &Pose2) -> Result<(), String> {
        if !pose.is_finite() {
            return Err("that pose is not a number".to_owned());
        }
        if self.run.collision_map().is_valid_at(pose.x, pose.y) {
            Ok(())
        } else {
            Err(format!(
                "({:.2}, {:.2}) is inside a wall or closer to one than the robot's radius",
                pose.x, pose.y
            ))
        }
    }
}

impl Simulation for KidnapSim {
    type Phase = MclPhase;
    type Event = KidnapEvent;
    /// The runner keeps its per-update records itself, so a checkpoint copies
    /// them; they are small beside the particles.
    type Records = ();

    fn step_phase(&mut self, _records: &mut ()) -> MclPhase {
        self.run.step_phase()
    }

    fn is_mid_tick(&self) -> bool {
        self.run.next_phase() != MclPhase::Move
    }

    fn tick(&self) -> u64 {
        self.run.tick_count()
    }

    fn apply_event(&mut self, event: &KidnapEvent) {
        match *event {
            KidnapEvent::KidnapTo(pose) => {
                // Refused kidnaps change nothing (the lesson says why before recording).
                let _refused = self.run.kidnap_to(pose);
            }
            KidnapEvent::KidnapRandom => self.run.kidnap_random(),
            KidnapEvent::GlobalLocalization => {
                for f in self.run.filters_mut() {
                    f.filter.mcl_mut().init_global();
                }
            }
            KidnapEvent::ResetAroundTruth => {
                // A log without truth has nothing to reset around.
                let Some(truth) = self.run.truth_now() else {
                    return;
                };
                let s = self.run.scenario().clone();
                for f in self.run.filters_mut() {
                    s.init_tracking(&mut f.filter, truth);
                }
            }
            KidnapEvent::Drive(v, w) => self.run.set_manual(Some((v, w))),
            KidnapEvent::Explore => self.run.set_manual(None),
        }
    }

    fn checkpoint_bytes(&self) -> usize {
        let particles: usize = self.run.filters().iter().map(|f| f.mcl().count()).sum();
        let records: usize = self
            .run
            .filters()
            .iter()
            .map(|f| f.updates.len() * 80 + f.ticks.len() * 16)
            .sum();
        particles * 48 + records + self.run.path().len() * 24 + 4096
    }
}

/// Reads a map dropped on the app: a ROS map_server YAML together with the image
/// it names, or a lone PGM/PNG image read at [`LONE_IMAGE_RESOLUTION`]. Returns
/// the map's name, its grid and notes; errors name the problem.
pub fn load_dropped_map(
    files: &[(String, Vec<u8>)],
) -> Result<(String, OccupancyGrid, Vec<String>), String> {
    let ext = |name: &str| {
        name.rsplit('.')
            .next()
            .map(str::to_ascii_lowercase)
            .unwrap_or_default()
    };
    let yaml = files
        .iter()
        .find(|(name, _)| matches!(ext(name).as_str(), "yaml" | "yml"));
    let images: Vec<&(String, Vec<u8>)> = files
        .iter()
        .filter(|(name, _)| matches!(ext(name).as_str(), "pgm" | "png"))
        .collect();
    match yaml {
        Some((yaml_name, bytes)) => {
            let text = std::str::from_utf8(bytes).map_err(|e| {
                format!(
                    "{yaml_name} is not text (byte {} is not UTF-8)",
                    e.valid_up_to()
                )
            })?;
            let parsed = parse_map_yaml(text).map_err(|e| format!("{yaml_name}: {e}"))?;
            let wanted = parsed.image.rsplit('/').next().unwrap_or(&parsed.image);
            let image = images
                .iter()
                .find(|(name, _)| name == wanted || name.rsplit('/').next() == Some(wanted))
                .ok_or_else(|| {
                    format!(
                        "{yaml_name} names the image '{}': drop or open it together with the YAML",
                        parsed.image
                    )
                })?;
            let (grid, _) = load_map(text, &image.1).map_err(|e| format!("{yaml_name}: {e}"))?;
            Ok((yaml_name.clone(), grid, Vec::new()))
        }
        None => match images.as_slice() {
            [(name, bytes)] => {
                let grid = load_lone_image(bytes, LONE_IMAGE_RESOLUTION)
                    .map_err(|e| format!("{name}: {e}"))?;
                Ok((
                    name.clone(),
                    grid,
                    vec![format!(
                        "an image without its YAML is read at {LONE_IMAGE_RESOLUTION} m per pixel with its origin at (0, 0); drop the YAML with it to use its own"
                    )],
                ))
            }
            [] => Err("drop a ROS map: its .yaml and its .pgm or .png image".to_owned()),
            _ => Err(
                "several images and no YAML: drop one image, or a YAML with its image".to_owned(),
            ),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kidnap::InitMode;
    use crate::stepper::Stepper;

    fn lesson_run(seed: u64) -> Stepper<KidnapSim> {
        let scenario = MclScenario {
            seed,
            max_particles: 300,
            init: InitMode::Tracking,
            ..MclScenario::default()
        };
        let (sim, notices) = KidnapSim::open(scenario, None).unwrap();
        assert!(notices.is_empty(), "{notices:?}");
        Stepper::new(sim, ())
    }

    fn fingerprint(s: &Stepper<KidnapSim>) -> (Pose2, Vec<Pose2>, u64) {
        let run = s.sim().run();
        let particles = run.filters()[0]
            .mcl()
            .particles()
            .iter()
            .map(|p| p.pose)
            .collect();
        (run.robot().pose, particles, run.tick_count())
    }

    /// Steps back to tick `tick`, then forward phase by phase to where the
    /// run was, and asserts it is the same run; returns the robot's pose at
    /// `tick`.
    fn back_and_forth(s: &mut Stepper<KidnapSim>, tick: u64) -> Pose2 {
        let end = fingerprint(s);
        let phases = s.phases_run();
        while s.sim().run().tick_count() > tick {
            assert!(s.step_back());
        }
        let back = s.sim().run().robot().pose;
        while s.phases_run() < phases {
            s.step_phase();
        }
        assert_eq!(fingerprint(s), end, "the run replays from tick {tick}");
        back
    }

    #[test]
    fn stepping_back_over_a_kidnap_and_a_scatter_replays_exactly() {
        let mut s = lesson_run(3);
        s.run_ticks(30);
        s.apply(KidnapEvent::KidnapRandom);
        let kidnapped = s.sim().run().robot().pose;
        s.run_ticks(5);
        s.apply(KidnapEvent::GlobalLocalization);
        s.run_ticks(10);
        // Back to before the kidnap, then forward again: the same run.
        let back = back_and_forth(&mut s, 25);
        assert_ne!(back, kidnapped);
    }

    #[test]
    fn driving_by_hand_moves_the_robot_as_told_and_replays_exactly() {
        let mut s = lesson_run(2);
        s.run_ticks(3);
        // Turn on the spot for five ticks: the position stays, the heading turns
        // by w · dt per tick.
        let before = s.sim().run().robot().pose;
        s.apply(KidnapEvent::Drive(0.0, 0.5));
        s.run_ticks(5);
        let turned = s.sim().run().robot().pose;
        let dt = s.sim().run().scenario().dt;
        assert!((turned.x - before.x).abs() < 1e-12 && (turned.y - before.y).abs() < 1e-12);
        let turn = slamlab_core::wrap_angle(turned.theta - before.theta);
        assert!((turn - 5.0 * 0.5 * dt).abs() < 1e-9, "{turn}");
        // Straight on; a wall stops the robot with one note, not one per tick.
        s.apply(KidnapEvent::Drive(1.0, 0.0));
        s.run_ticks(200);
        let wall_notes = s.sim().run().notes().len();
        assert!(wall_notes >= 1, "the robot never met a wall");
        s.run_ticks(20);
        assert_eq!(s.sim().run().notes().len(), wall_notes);
        s.apply(KidnapEvent::Explore);
        s.run_ticks(20);
        // The drive commands replay.
        back_and_forth(&mut s, 4);
        // NaN commands count as zero.
        s.apply(KidnapEvent::Drive(f64::NAN, f64::INFINITY));
        assert_eq!(s.sim().run().manual(), Some((0.0, 0.0)));
    }

    #[test]
    fn a_kidnap_into_a_wall_is_refused_and_changes_nothing() {
        let mut s = lesson_run(1);
        s.run_ticks(3);
        let grid = s.sim().run().map().grid().clone();
        let (w, h) = grid.size_m();
        let origin = grid.origin();
        // The maze's border is a wall.
        let wall = Pose2::new(origin.x + 0.01, origin.y + 0.5 * h, 0.0);
        assert!(s.sim().check_kidnap(&wall).is_err());
        assert!(
            s.sim()
                .check_kidnap(&Pose2::new(f64::NAN, 0.0, 0.0))
                .is_err()
        );
        let before = s.sim().run().robot().pose;
        s.apply(KidnapEvent::KidnapTo(wall));
        assert_eq!(s.sim().run().robot().pose, before);
        assert!(w > 5.0);
    }

    #[test]
    fn dropped_maps_load_or_say_why() {
        let yaml = BuiltinMap::Maze.yaml().as_bytes().to_vec();
        let image = BuiltinMap::Maze.image().to_vec();
        let image_name = parse_map_yaml(BuiltinMap::Maze.yaml())
            .map(|y| y.image)
            .unwrap_or_default();
        let (name, grid, notes) = load_dropped_map(&[
            ("maze.yaml".to_owned(), yaml.clone()),
            (image_name.clone(), image.clone()),
        ])
        .unwrap();
        assert_eq!(name, "maze.yaml");
        assert!(notes.is_empty());
        assert_eq!(
            (grid.width(), grid.height()),
            (
                BuiltinMap::Maze.load().unwrap().width(),
                BuiltinMap::Maze.load().unwrap().height()
            )
        );
        let err = load_dropped_map(&[("maze.yaml".to_owned(), yaml)]).unwrap_err();
        assert!(err.contains("drop or open it together"), "{err}");
        let (_, lone, notes) = load_dropped_map(&[("x.png".to_owned(), image)]).unwrap();
        assert!((lone.resolution() - LONE_IMAGE_RESOLUTION).abs() < 1e-12 && notes.len() == 1);
        let err = load_dropped_map(&[("x.png".to_owned(), vec![1, 2, 3])]).unwrap_err();
        assert!(err.starts_with("x.png:"), "{err}");
        assert!(load_dropped_map(&[("notes.txt".to_owned(), vec![])]).is_err());
    }
}
