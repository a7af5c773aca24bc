//! The lessons `slamlab run` runs, one module each (listed in
//! [`crate::registry::LESSONS`]).

pub mod cartographer;
pub mod kidnap;
pub mod landmark;
pub mod mapping;
pub mod visual_odometry;
