//! The grid world of the Monte Carlo localization lessons: ROS map files, the
//! built-in maps, the simulated lidar, the round robot that cannot drive through
//! walls, and the explorer that tours any map.

pub mod builtin;
pub mod explorer;
pub mod lidar;
pub mod robot;
pub mod simulated_log;

pub use builtin::BuiltinMap;
pub use explorer::Explorer;
pub use lidar::Lidar;
pub use robot::{GridRobot, OdometrySensor};
pub use simulated_log::{SimLogError, SimulatedLogConfig, simulate_log};
