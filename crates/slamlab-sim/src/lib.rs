//! # slamlab-sim
//!
//! The world SLAM Lab's estimators run in: ground truth, noise injection, the
//! sensors, controllers, scenarios, metrics and experiments.
//!
//! Only this crate holds the truth. Estimators from `slamlab-core` receive the
//! commanded controls and the noisy measurements; metrics compare their output
//! with the truth afterwards.
//!
//! One folder per lesson, named as the lesson's id and as its folder in the app
//! (`landmark_slam/`, `kidnap/`, `pose_graph/`, `resampling/`, `fusion/`,
//! `mapping/`, `cartographer/`, `filters/`, `visual_odometry/`), each with its
//! scenario and parameter table, its stepped run and its experiments. A lesson
//! folder imports the shared pieces and never another lesson's folder:
//!
//! - [`world`]: the simulated landmark world and its stepped run,
//! - [`grid`]: the grid world (built-in maps, lidar, robot, explorer, simulated
//!   logs) and the laser lessons' input,
//! - [`io`]: every file reader and writer,
//! - [`coursework`]: assignments, students' variants, their inputs and grades
//!   ([`assignments`] lists the built-in ones and the lessons that run them),
//! - [`params`] (parameter tables), [`stepper`] (the generic stepper and its
//!   checkpoints), [`noise`] (seeded random streams).

pub mod assignments;
pub mod cartographer;
pub mod coursework;
pub mod filters;
pub mod fusion;
pub mod grid;
pub mod io;
pub mod kidnap;
pub mod landmark_slam;
pub mod mapping;
pub mod metrics;
pub mod noise;
pub mod params;
pub mod pose_graph;
pub mod resampling;
pub mod stepper;
pub mod visual_odometry;
pub mod world;

#[cfg(test)]
mod fuzz_tests;

pub use world::landmark_scenario::{ControllerKind, EstimatorKind, LandmarkScenario};
pub use world::landmark_session::{LandmarkSession, Phase};
