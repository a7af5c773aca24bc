//! The two maps SLAM Lab ships, authored by this project (see
//! `crates/slamlab-sim/tests/builtin_maps.rs`, which generates them
//! deterministically and checks the committed files still match):
//!
//! - **maze**: 10.1 x 10.1 m at 0.05 m per cell, a seeded 10 x 10 labyrinth with
//!   0.9 m corridors, dead ends, a few loops, two rooms and pillars, so global
//!   localization is possible but not trivial.
//! - **office**: 55 x 55 m at 0.1 m per cell, a floor of the Willow Garage
//!   class: a grid of 2 m corridors, rows of offices with doors, suites, tables,
//!   a hall with pillars, and much repeated structure.
//!
//! Both are ROS map_server files under `assets/maps/`, compiled in.

use crate::io::ros_map::{MapError, load_map};
use slamlab_core::grid::OccupancyGrid;

/// A built-in map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BuiltinMap {
    /// The 10 x 10 m labyrinth.
    Maze,
    /// The 55 x 55 m office floor.
    Office,
}

impl BuiltinMap {
    /// Every built-in map.
    pub const ALL: [BuiltinMap; 2] = [BuiltinMap::Maze, BuiltinMap::Office];

    /// The name used in URLs and CLI flags.
    pub fn name(self) -> &'static str {
        match self {
            BuiltinMap::Maze => "maze",
            BuiltinMap::Office => "office",
        }
    }

    /// Parses a name as written by [`BuiltinMap::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// The map's YAML file.
    pub fn yaml(self) -> &'static str {
        match self {
            BuiltinMap::Maze => include_str!("../../../../assets/maps/maze.yaml"),
            BuiltinMap::Office => include_str!("../../../../assets/maps/office.yaml"),
        }
    }

    /// The map's PNG image.
    pub fn image(self) -> &'static [u8] {
        match self {
            BuiltinMap::Maze => include_bytes!("../../../../assets/maps/maze.png"),
            BuiltinMap::Office => include_bytes!("../../../../assets/maps/office.png"),
        }
    }

    /// Decodes the map.
    pub fn load(self) -> Result<OccupancyGrid, MapError> {
        load_map(self.yaml(), self.image()).map(|(g, _)| g)
    }
}
