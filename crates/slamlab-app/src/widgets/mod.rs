//! Widgets every lesson shares: the map canvas (pan, zoom, follow, grid, scale
//! bar), the parameter panel built from a scenario's parameter table, plot helpers,
//! particle clouds as one mesh, the drive pad, file picking and drops, the laser file
//! (CARMEN log or ROS 2 bag) of the lidar lessons, the share link, the Sources window,
//! a student's estimates and the Assignment window.

pub mod assignment;
pub mod drive;
pub mod dropped_files;
pub mod estimates;
pub mod fetch;
pub mod file_picker;
pub mod grid_tiles;
pub mod laser_file;
pub mod laser_inputs;
pub mod layout;
pub mod map_canvas;
pub mod params_panel;
pub mod particles;
pub mod plots;
pub mod reference_track;
pub mod share;
pub mod sources;
