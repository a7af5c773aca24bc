//! The pose-graph lesson (`lesson=pose-graph`): a graph of poses, odometry and
//! loop closures optimized one solver iteration at a time.
//!
//! - [`session`]: the scenario, its parameter table and the stepped session.
//! - [`experiment`]: the graph-based SLAM simulation of thesis Sec. 4.2.
//! - [`assignment`]: the `pose-graph` assignment's runner (a student's g2o
//!   problem, their optimized graph graded by cost and ATE).

pub mod assignment;
pub mod experiment;
pub mod export;
pub mod session;

pub use session::{PoseGraphScenario, PoseGraphSession};
