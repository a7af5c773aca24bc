//! The sensor-fusion lesson's world (thesis `002` ch. 3.5 and 5): a seeded drive
//! of the two-wheel robot, wheel odometry at 50 Hz, an IMU at 100 Hz and a SLAM
//! pose at 1 Hz, fused by [`slamlab_core::kalman::fusion::FusionEkf`] in each of
//! robot_localization's pose modes on the same data, and the RMSE of thesis
//! Table 5.3.
//!
//! ```
//! use slamlab_sim::fusion::{FusionMode, FusionScenario, ModeRun, simulate};
//! let scenario = FusionScenario { drive: slamlab_sim::fusion::DriveParams {
//!     duration: 20.0, ..Default::default() }, ..Default::default() };
//! let log = simulate(&scenario).unwrap();
//! let mut run = ModeRun::new(&scenario, FusionMode::Differential).unwrap();
//! run.advance_to(&log, 5.0, |step| println!("{}", step.label()));
//! run.run_to_end(&log);
//! assert!(run.rmse().x.is_finite());
//! ```

pub mod assignment;
mod experiment;
mod landmark_pose;
mod log;
pub mod params;
mod runner;
mod scenario;
mod sensors;
pub mod session;
#[cfg(test)]
mod tests;

pub use experiment::{
    FusionAverage, FusionExperiment, FusionTrial, THESIS_TABLE_5_3, fusion_experiment,
    parameters_json,
};
pub use log::{Arrival, IMU, ODOMETRY, SLAM, SensorLog, TruthSample};
pub use runner::{FusionMode, ModeRun, Rmse, SENSORS, Sample, SlamJump, filter_for, run_modes};
pub use scenario::{
    DriveKind, DriveParams, FusionScenario, ImuParams, MAX_TRUTH_TICKS, OdometryParams,
    ScenarioError, SlamParams, SlamSource,
};
pub use sensors::simulate;
