//! # slamlab-core
//!
//! The models and estimators behind SLAM Lab. Everything here is pure and
//! deterministic: no UI, no file or network I/O, no clock and no global random
//! number generator. Estimators see only controls and measurements, never the
//! simulator's ground truth.
//!
//! Conventions follow ROS REP-103: x forward, y left, angles counter-clockwise,
//! metres and radians. A range-bearing measurement is ordered `[range, bearing]`
//! as in the thesis (`000`, Eq. 3.37); the slides use `[bearing, range]`.

pub mod association;
pub mod belief;
pub mod filters;
pub mod geometry;
pub mod graph;
pub mod grid;
pub mod kalman;
pub mod laser;
pub mod linalg;
pub mod math;
pub mod motion;
pub mod odometry;
pub mod particle;
pub mod random;
pub mod range_bearing;
pub mod scan;
pub mod stats;
pub mod vision;

pub use geometry::{CovarianceEllipse, Pose2, wrap_angle};
pub use motion::{Control, MotionModel};
pub use range_bearing::RangeBearing;
