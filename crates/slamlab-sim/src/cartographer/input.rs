//! A simulated log with a kidnap: the explorer drives the robot through a map
//! as `grid::simulate_log` does (the same random streams), and at scan
//! `kidnap_at` the robot is carried at least [`MIN_KIDNAP_DISTANCE`] away
//! with a random heading ([`KidnapPlace`]): by default to a place it has
//! already been (as the thesis's cropped log lands the robot where it had
//! mapped before, so that the two maps can be merged), or to any free place
//! (in a large building often one the robot never comes back to: then no
//! merge exists). Odometry does not see the jump (its pose moves only by the
//! wheels), so the log looks like a robot that drove on.

use crate::grid::SimulatedLogConfig;
use crate::grid::simulated_log::ExploringRobot;
use crate::grid::{InputScan, MappingInput};
use crate::noise::stream_seed;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slamlab_core::Pose2;
use slamlab_core::grid::{Costmap, FreeCells, OccupancyGrid};
use std::sync::Arc;

/// The kidnap carries the robot at least this far, metres.
pub const MIN_KIDNAP_DISTANCE: f64 = 2.0;

/// The most scans a simulated run may have.
pub const MAX_STEPS: usize = 50_000;

/// Where a kidnap carries the robot.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum KidnapPlace {
    /// A random place on the robot's own path so far (so inside the part of
    /// the map it has mapped), at least [`MIN_KIDNAP_DISTANCE`] from where it
    /// is, with a random heading; [`KidnapPlace::Anywhere`] when no such place
    /// exists.
    #[default]
    Mapped,
    /// A random free place of the whole map, at least
    /// [`MIN_KIDNAP_DISTANCE`] away, with a random heading.
    Anywhere,
    /// This pose (refused when the robot does not fit there).
    At(Pose2),
}

impl KidnapPlace {
    /// The names `kidnap-place=` and `--kidnap-place` take.
    pub const NAMES: [&str; 2] = ["mapped", "anywhere"];

    /// `mapped` or `anywhere` (a chosen pose has no name).
    pub fn name(&self) -> &'static str {
        match self {
            KidnapPlace::Anywhere => "anywhere",
            KidnapPlace::Mapped | KidnapPlace::At(_) => "mapped",
        }
    }

    /// The place named `name` (`mapped` or `anywhere`).
    pub fn from_name(name: &str) -> Option<KidnapPlace> {
        match name {
            "mapped" => Some(KidnapPlace::Mapped),
            "anywhere" => Some(KidnapPlace::Anywhere),
            _ => None,
        }
    }
}

/// Simulates `steps` scans in `map` (a 360-beam, 12 m lidar at 10 Hz and the
/// default odometry noise of `config`), with the robot carried elsewhere just
/// before scan `kidnap_at` (0-based; `None`: never) to a place on its path so
/// far ([`KidnapPlace::Mapped`]). The truth and the map travel beside the
/// scans for the metrics.
pub fn kidnap_input(
    map: Arc<OccupancyGrid>,
    map_name: &str,
    steps: usize,
    seed: u64,
    kidnap_at: Option<usize>,
    config: &SimulatedLogConfig,
) -> Result<MappingInput, String> {
    kidnap_input_to(
        map,
        map_name,
        steps,
        seed,
        kidnap_at.map(|k| (k, KidnapPlace::Mapped)),
        config,
    )
}

/// [`kidnap_input`] with the kidnap's scan and place chosen: `kidnap` is
/// `(scan, place)`; a chosen pose the robot does not fit refused.
pub fn kidnap_input_to(
    map: Arc<OccupancyGrid>,
    map_name: &str,
    steps: usize,
    seed: u64,
    kidnap: Option<(usize, KidnapPlace)>,
    config: &SimulatedLogConfig,
) -> Result<MappingInput, String> {
    let kidnap_at = kidnap.map(|(k, _)| k);
    let place = kidnap.map_or(KidnapPlace::Mapped, |(_, p)| p);
    if steps > MAX_STEPS {
        return Err(format!("{steps} steps is over the limit of {MAX_STEPS}"));
    }
    let radius = config.robot_radius.max(0.0);
    let collision = Costmap::inflate(&map, radius);
    if let KidnapPlace::At(p) = place
        && !(p.is_finite() && collision.is_valid_at(p.x, p.y))
    {
        return Err(format!(
            "the robot does not fit at ({:.2}, {:.2}): a wall or outside the map",
            p.x, p.y
        ));
    }
    let mut drive = ExploringRobot::place(&map, collision, radius, config, seed)
        .ok_or_else(|| format!("the robot (radius {radius} m) fits nowhere in the map"))?;
    let mut lidar_rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, 2));
    let mut kidnap_rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, 5));
    let mut scans = Vec::with_capacity(steps);
    let mut truth = Vec::with_capacity(steps);
    for k in 0..steps {
        drive.step(config.dt);
        let after = drive.robot.pose;
        if kidnap_at == Some(k) {
            let cells = &drive.cells;
            let to = match place {
                KidnapPlace::At(p) => p,
                KidnapPlace::Mapped => on_path(&truth, &after, &mut kidnap_rng)
                    .unwrap_or_else(|| anywhere(cells, &after, &mut kidnap_rng)),
                KidnapPlace::Anywhere => anywhere(cells, &after, &mut kidnap_rng),
            };
            drive.carry_to(to);
        }
        let scan = config.lidar.scan(&map, &drive.robot.pose, &mut lidar_rng);
        scans.push(InputScan {
            time: (k + 1) as f64 * config.dt,
            scan,
            odometry: drive.odometry.pose,
        });
        truth.push(drive.robot.pose);
    }
    let kidnap = kidnap.map_or(String::new(), |(k, place)| match place {
        KidnapPlace::Anywhere => format!(", kidnapped at scan {k} to anywhere"),
        _ => format!(", kidnapped at scan {k}"),
    });
    Ok(MappingInput {
        name: format!("simulated {map_name}, seed {seed}{kidnap}"),
        scans,
        truth: Some(truth),
        true_map: Some(map),
        reference: None,
        time_origin: 0.0,
    })
}

/// A random pose of `path` at least [`MIN_KIDNAP_DISTANCE`] from `from`,
/// with a random heading (the robot stood there, so it fits); None when the
/// path never went that far.
fn on_path(path: &[Pose2], from: &Pose2, rng: &mut ChaCha8Rng) -> Option<Pose2> {
    let far: Vec<&Pose2> = path
        .iter()
        .filter(|p| slamlab_core::math::hypot(p.x - from.x, p.y - from.y) >= MIN_KIDNAP_DISTANCE)
        .collect();
    if far.is_empty() {
        return None;
    }
    let p = far[rng.random_range(0..far.len())];
    let heading = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
    Some(Pose2::new(p.x, p.y, heading))
}

/// A random free cell of `cells` at least [`MIN_KIDNAP_DISTANCE`] from
/// `from` (up to 100 draws; the last one otherwise), with a random heading;
/// `from` itself when no cell is free.
fn anywhere(cells: &FreeCells, from: &Pose2, rng: &mut ChaCha8Rng) -> Pose2 {
    let mut pose = *from;
    for _ in 0..100 {
        let Some(p) = cells.sample(rng) else {
            break;
        };
        pose = p;
        if slamlab_core::math::hypot(p.x - from.x, p.y - from.y) >= MIN_KIDNAP_DISTANCE {
            break;
        }
    }
    pose
}
