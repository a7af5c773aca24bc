//! Every file SLAM Lab reads or writes, each reader with a size cap and typed
//! errors that name the file's line: pose graphs (g2o, TORO), ROS maps (YAML with
//! PGM/PNG), laser logs (CARMEN, plain or compressed, with their true poses, and the
//! corrected logs that serve as their reference trajectories), ROS 2 bags (MCAP),
//! the landmark data sets, scenario files, and a student's estimates (trajectories,
//! landmarks, a relative pose of two views). What a reader returns is plain data; the lessons and the
//! command line decide what to do with it.

pub mod archive;
pub mod graph;
pub mod landmark_data;
pub mod laser_log;
pub mod laser_reference;
pub mod map_archive;
pub mod relative_pose;
pub mod ros2_bag;
pub mod ros_map;
pub mod scenario_file;
pub mod trajectory;
