//! # slamlab-sim
//!
//! The world SLAM Lab's estimators run in: ground truth, noise injection, the
//! range-bearing sensor, controllers, scenarios, metrics and experiments.
//!
//! Only this crate holds the truth. Estimators from `slamlab-core` receive the
//! commanded controls and the noisy measurements; metrics compare their output
//! with the truth afterwards.

pub mod cartographer;
pub mod cartographer_lesson;
pub mod consistency;
pub mod experiments;
pub mod fastslam;
pub mod filters_lab;
pub mod fusion;
pub mod graph_io;
pub mod grid;
pub mod grid_fastslam;
pub mod ideal_ekf;
pub mod kidnap_session;
pub mod landmark_params;
pub mod laser_log;
pub mod localization;
pub mod mapping;
pub mod metrics;
pub mod noise;
pub mod params;
pub mod particle_estimator;
pub mod pose_graph_experiment;
pub mod pose_graph_lesson;
pub mod presets;
pub mod resampling;
pub mod resampling_lab;
pub mod scenario;
pub mod scenario_file;
pub mod session;
pub mod stepper;
pub mod vision;
pub mod world;

#[cfg(test)]
mod fuzz_tests;

pub use scenario::{ControllerKind, EstimatorKind, LandmarkScenario};
pub use session::{LandmarkSession, Phase};
