//! The simulated landmark world, shared by the lessons that run a robot among
//! landmarks: the landmark-SLAM lesson itself, the sensor-fusion lesson (its
//! SLAM pose comes from EKF-SLAM in this world) and the pose-graph lesson's
//! thesis experiment (EKF-SLAM's path becomes the graph).
//!
//! - [`landmarks`]: the landmark layouts and the true world.
//! - [`landmark_scenario`]: the scenario as data (world, robot, sensor, controller,
//!   estimators, seed); its parameter table is the landmark lesson's
//!   ([`crate::landmark_slam::scenario`]).
//! - [`landmark_session`]: the stepped run, truth and filters side by side.

pub mod landmark_scenario;
pub mod landmark_session;
pub mod landmarks;
pub mod recorded;
