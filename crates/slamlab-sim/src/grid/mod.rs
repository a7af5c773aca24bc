//! The grid world of the lidar lessons (Monte Carlo localization, mapping,
//! Cartographer): the built-in maps, the simulated lidar, the round robot that
//! cannot drive through walls, the explorer that tours any map, simulated laser
//! logs, the scans every mapping run takes as its input (from a simulated
//! robot, a CARMEN log or a ROS 2 bag: [`laser_file`]), and a log's reference
//! trajectory (a corrected log) with the score of a trajectory against it.

pub mod builtin;
pub mod explorer;
pub mod laser_file;
pub mod lidar;
pub mod reference;
pub mod robot;
pub mod run_params;
pub mod scans;
pub mod simulated_log;

pub use builtin::BuiltinMap;
pub use explorer::Explorer;
pub use laser_file::{BagTopics, LaserFile, LaserFileError};
pub use lidar::Lidar;
pub use reference::{LogReference, TrajectoryScore};
pub use robot::{GridRobot, OdometrySensor};
pub use run_params::SimulatedRun;
pub use scans::{
    InputScan, MappingInput, builtin_map, log_input, map_agreement, occupancy_agreement,
    occupancy_coverage, trajectory_rmse,
};
pub use simulated_log::{SimLogError, SimulatedLogConfig, simulate_log};
