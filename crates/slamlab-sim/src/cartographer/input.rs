//! A simulated log with a kidnap: the explorer drives the robot through a map
//! as `laser_log::simulate_log` does (the same random streams), and at scan
//! `kidnap_at` the robot is carried to a random free place at least
//! [`MIN_KIDNAP_DISTANCE`] away with a random heading. Odometry does not see
//! the jump (its pose moves only by the wheels), so the log looks like a
//! robot that drove on.

use crate::grid::explorer::Explorer;
use crate::grid::robot::{GridRobot, OdometrySensor};
use crate::laser_log::SimulatedLogConfig;
use crate::localization::run::stream_seed;
use crate::mapping::{InputScan, MappingInput};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use slamlab_core::Pose2;
use slamlab_core::grid::{Costmap, OccupancyGrid};
use std::sync::Arc;

/// The kidnap carries the robot at least this far, metres.
pub const MIN_KIDNAP_DISTANCE: f64 = 2.0;

/// The most scans a simulated run may have.
pub const MAX_STEPS: usize = 50_000;

/// Simulates `steps` scans in `map` (a 360-beam, 12 m lidar at 10 Hz and the
/// default odometry noise of `config`), with the robot carried elsewhere just
/// before scan `kidnap_at` (0-based; `None`: never). The truth and the map
/// travel beside the scans for the metrics.
pub fn kidnap_input(
    map: Arc<OccupancyGrid>,
    map_name: &str,
    steps: usize,
    seed: u64,
    kidnap_at: Option<usize>,
    config: &SimulatedLogConfig,
) -> Result<MappingInput, String> {
    kidnap_input_to(map, map_name, steps, seed, kidnap_at, None, config)
}

/// [`kidnap_input`] with the robot carried to `to` (a place chosen on the
/// map) instead of a random one; a place the robot does not fit refused.
pub fn kidnap_input_to(
    map: Arc<OccupancyGrid>,
    map_name: &str,
    steps: usize,
    seed: u64,
    kidnap_at: Option<usize>,
    to: Option<Pose2>,
    config: &SimulatedLogConfig,
) -> Result<MappingInput, String> {
    if steps > MAX_STEPS {
        return Err(format!("{steps} steps is over the limit of {MAX_STEPS}"));
    }
    let radius = config.robot_radius.max(0.0);
    let collision = Costmap::inflate(&map, radius);
    if let Some(p) = to
        && !(p.is_finite() && collision.is_valid_at(p.x, p.y))
    {
        return Err(format!(
            "the robot does not fit at ({:.2}, {:.2}): a wall or outside the map",
            p.x, p.y
        ));
    }
    let roomy = Costmap::inflate(&map, radius + 0.1).valid_cells();
    let cells = if roomy.is_empty() {
        collision.valid_cells()
    } else {
        roomy
    };
    let mut start_rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, 1));
    let start = cells
        .sample(&mut start_rng)
        .ok_or_else(|| format!("the robot (radius {radius} m) fits nowhere in the map"))?;
    let mut lidar_rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, 2));
    let mut odom_rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, 3));
    let mut kidnap_rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, 5));
    let mut explorer = Explorer::new(&map, radius, config.explorer, stream_seed(seed, 4));
    let mut robot = GridRobot {
        pose: start,
        radius,
    };
    let mut odometry = OdometrySensor::new(start, config.odom_noise);
    let mut scans = Vec::with_capacity(steps);
    let mut truth = Vec::with_capacity(steps);
    for k in 0..steps {
        let (v, w) = explorer.command(&robot.pose);
        let before = robot.pose;
        if robot.drive(&collision, v, w, config.dt).is_some() {
            explorer.replan();
        }
        let after = robot.pose;
        odometry.record(&before, &after, &mut odom_rng);
        if kidnap_at == Some(k)
            && let Some(p) = to
        {
            robot.pose = p;
            explorer.replan();
        } else if kidnap_at == Some(k) {
            // Up to 100 draws for a place far enough away; the last one
            // otherwise.
            for _ in 0..100 {
                let Some(p) = cells.sample(&mut kidnap_rng) else {
                    break;
                };
                robot.pose = p;
                if slamlab_core::math::hypot(p.x - after.x, p.y - after.y) >= MIN_KIDNAP_DISTANCE {
                    break;
                }
            }
            explorer.replan();
        }
        let scan = config.lidar.scan(&map, &robot.pose, &mut lidar_rng);
        scans.push(InputScan {
            time: (k + 1) as f64 * config.dt,
            scan,
            odometry: odometry.pose,
        });
        truth.push(robot.pose);
    }
    let kidnap = kidnap_at.map_or(String::new(), |k| format!(", kidnapped at scan {k}"));
    Ok(MappingInput {
        name: format!("simulated {map_name}, seed {seed}{kidnap}"),
        scans,
        truth: Some(truth),
        true_map: Some(map),
    })
}
