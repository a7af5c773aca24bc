//! The landmark-SLAM lesson (`lesson=landmark-slam`, `slamlab run landmark-slam`):
//! EKF-SLAM, UKF-SLAM, FEJ-EKF and FastSLAM among landmarks. The world and the
//! stepped run are shared with other lessons ([`crate::world`]); this folder
//! holds what is the lesson's own.
//!
//! - [`scenario`]: the parameter table of [`LandmarkScenario`] and [`presets`].
//! - [`summary`]: a headless run's per-filter summary.
//! - [`experiment`], [`consistency`], [`fastslam`]: the sources' experiments
//!   (thesis Table 3.1, NEES over many runs, FastSLAM 1.0 against 2.0).
//! - [`real_data`]: the filters on recorded data sets, scored against the truth.
//! - [`reference_map`]: Victoria Park's pose graph solved as the reference map.
//!
//! [`LandmarkScenario`]: crate::world::landmark_scenario::LandmarkScenario

pub mod consistency;
pub mod experiment;
pub mod export;
pub mod fastslam;
pub mod presets;
pub mod real_data;
pub mod reference_map;
pub mod scenario;
pub mod summary;
