//! The grid world of the Monte Carlo localization lessons: ROS map files, the
//! built-in maps, the simulated lidar, the round robot that cannot drive through
//! walls, and the explorer that tours any map.

pub mod builtin;
pub mod explorer;
pub mod lidar;
pub mod map_io;
pub mod robot;

pub use builtin::BuiltinMap;
pub use explorer::Explorer;
pub use lidar::Lidar;
pub use map_io::{ImageFormat, MapError, MapYaml};
pub use robot::{GridRobot, OdometrySensor};
