//! Occupancy-grid maps: cells that are free, occupied or unknown, laid out as
//! ROS `nav_msgs/OccupancyGrid` lays them out (Probabilistic Robotics ch. 9; thesis
//! `000` Sec. 3.5).
//!
//! Cell `(0, 0)` is the lower-left cell of the map: the first pixel of the
//! *last* row of a map_server image. Cell `(i, j)` covers the square
//! `[i r, (i+1) r) x [j r, (j+1) r)` of the grid frame (`r` the resolution), and
//! the grid frame sits at `origin` in the world (its heading honoured: a map
//! whose YAML says `origin: [x, y, yaw]` with `yaw != 0` is rotated about its
//! lower-left corner).
//!
//! - [`OccupancyGrid::raycast`]: exact cell traversal (Amanatides and Woo 1987).
//! - [`DistanceField`]: the exact Euclidean distance transform (Felzenszwalb and
//!   Huttenlocher 2012), capped, for the likelihood-field model.
//! - [`Costmap`]: the free cells farther than a robot radius from every occupied
//!   cell (thesis `000` Sec. 5.1.3).
//! - [`FreeCells`]: uniform sampling over free cells (global localization).

mod costmap;
mod distance;
mod probability;
mod raycast;

pub use costmap::{Costmap, FreeCells};
pub use distance::{DistanceField, squared_distance_transform};
pub use probability::{
    BeamCell, BeamUpdate, InsertParams, InsertReport, LogOddsSteps, ProbabilityGrid, TABLE_ENTRIES,
    TABLE_LOG_ODDS, TILE, UNKNOWN_ENTRY, UpdateRule, log_odds, probability, segment_cells,
    table_entry, table_log_odds,
};

use crate::geometry::Pose2;
use crate::math;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// The largest map SLAM Lab accepts: 50 million cells (a 7,000 x 7,000 image,
/// 350 x 350 m at 0.05 m per cell). Map readers check a header against this
/// before they allocate anything.
pub const MAX_CELLS: usize = 50_000_000;

/// The state of one grid cell (ROS: 0 free, 100 occupied, -1 unknown).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[repr(u8)]
pub enum Cell {
    /// Known to be empty.
    Free = 0,
    /// Known to hold an obstacle.
    Occupied = 1,
    /// Never observed.
    #[default]
    Unknown = 2,
}

/// Why a grid cannot be built.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum GridError {
    /// Width or height is zero.
    #[error("the map is empty ({width} x {height} cells)")]
    Empty {
        /// Cells per row.
        width: usize,
        /// Rows.
        height: usize,
    },
    /// More cells than [`MAX_CELLS`].
    #[error(
        "the map claims {width} x {height} cells, more than the {MAX_CELLS} cells SLAM Lab accepts"
    )]
    TooLarge {
        /// Cells per row.
        width: usize,
        /// Rows.
        height: usize,
    },
    /// The resolution is zero, negative or not a number.
    #[error("resolution {0} m per cell is not a positive number")]
    BadResolution(f64),
    /// The origin has a non-finite coordinate.
    #[error("the map origin ({x}, {y}, {yaw}) is not finite")]
    BadOrigin {
        /// x, metres.
        x: f64,
        /// y, metres.
        y: f64,
        /// yaw, radians.
        yaw: f64,
    },
    /// The cell vector does not have `width * height` entries.
    #[error("{got} cells given for a {width} x {height} map")]
    WrongCellCount {
        /// Cells per row.
        width: usize,
        /// Rows.
        height: usize,
        /// Cells given.
        got: usize,
    },
}

/// `⌊v⌋` as an integer, without a call into the C library (`f64::floor` is a
/// library call on baseline x86-64). Exact for every finite `v` in the `i64`
/// range; NaN gives 0, out-of-range values saturate.
#[inline]
pub fn floor_to_i64(v: f64) -> i64 {
    let t = v as i64;
    if (t as f64) > v {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// Checks a claimed map size against [`MAX_CELLS`] without allocating.
pub fn check_size(width: usize, height: usize) -> Result<(), GridError> {
    if width == 0 || height == 0 {
        return Err(GridError::Empty { width, height });
    }
    match width.checked_mul(height) {
        Some(n) if n <= MAX_CELLS => Ok(()),
        _ => Err(GridError::TooLarge { width, height }),
    }
}

/// An occupancy grid: `width x height` cells of side `resolution` metres, row
/// `j = 0` at the bottom (ROS convention), placed in the world at `origin`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OccupancyGrid {
    width: usize,
    height: usize,
    resolution: f64,
    origin: Pose2,
    /// `cos` and `sin` of the origin's yaw, cached for the conversions.
    cos_yaw: f64,
    sin_yaw: f64,
    cells: Vec<Cell>,
}

impl OccupancyGrid {
    /// A grid from its cells, row-major with row 0 at the bottom
    /// (`cells[j * width + i]` is cell `(i, j)`).
    pub fn new(
        width: usize,
        height: usize,
        resolution: f64,
        origin: Pose2,
        cells: Vec<Cell>,
    ) -> Result<Self, GridError> {
        check_size(width, height)?;
        if !(resolution > 0.0) || !resolution.is_finite() {
            return Err(GridError::BadResolution(resolution));
        }
        if !origin.is_finite() {
            return Err(GridError::BadOrigin {
                x: origin.x,
                y: origin.y,
                yaw: origin.theta,
            });
        }
        if cells.len() != width * height {
            return Err(GridError::WrongCellCount {
                width,
                height,
                got: cells.len(),
            });
        }
        let (sin_yaw, cos_yaw) = math::sin_cos(origin.theta);
        Ok(Self {
            width,
            height,
            resolution,
            origin,
            cos_yaw,
            sin_yaw,
            cells,
        })
    }

    /// A grid with every cell set to `fill`.
    pub fn filled(
        width: usize,
        height: usize,
        resolution: f64,
        origin: Pose2,
        fill: Cell,
    ) -> Result<Self, GridError> {
        check_size(width, height)?;
        Self::new(
            width,
            height,
            resolution,
            origin,
            vec![fill; width * height],
        )
    }

    /// Cells per row.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Side of a cell, metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// Where the lower-left corner of cell `(0, 0)` is in the world, and the
    /// grid's heading.
    pub fn origin(&self) -> Pose2 {
        self.origin
    }

    /// Every cell, row-major with row 0 at the bottom.
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// The index of cell `(i, j)` into [`cells`](Self::cells), if it is inside.
    #[inline]
    pub fn index(&self, i: i64, j: i64) -> Option<usize> {
        if i >= 0 && j >= 0 && (i as usize) < self.width && (j as usize) < self.height {
            Some(j as usize * self.width + i as usize)
        } else {
            None
        }
    }

    /// Cell `(i, j)`, or `None` outside the map.
    #[inline]
    pub fn get(&self, i: i64, j: i64) -> Option<Cell> {
        self.index(i, j).map(|k| self.cells[k])
    }

    /// Sets cell `(i, j)`; ignored outside the map.
    pub fn set(&mut self, i: i64, j: i64, cell: Cell) {
        if let Some(k) = self.index(i, j) {
            self.cells[k] = cell;
        }
    }

    /// Whether cell `(i, j)` is occupied (outside the map: no).
    #[inline]
    pub fn is_occupied(&self, i: i64, j: i64) -> bool {
        self.get(i, j) == Some(Cell::Occupied)
    }

    /// A world point in the grid frame (metres from the lower-left corner of
    /// cell `(0, 0)`, along the grid's rows and columns).
    #[inline]
    pub fn world_to_grid_frame(&self, x: f64, y: f64) -> (f64, f64) {
        let dx = x - self.origin.x;
        let dy = y - self.origin.y;
        (
            self.cos_yaw * dx + self.sin_yaw * dy,
            -self.sin_yaw * dx + self.cos_yaw * dy,
        )
    }

    /// A grid-frame point in the world.
    #[inline]
    pub fn grid_frame_to_world(&self, gx: f64, gy: f64) -> (f64, f64) {
        (
            self.origin.x + self.cos_yaw * gx - self.sin_yaw * gy,
            self.origin.y + self.sin_yaw * gx + self.cos_yaw * gy,
        )
    }

    /// A direction (an angle in the world) in the grid frame.
    #[inline]
    pub fn world_angle_to_grid(&self, angle: f64) -> f64 {
        angle - self.origin.theta
    }

    /// The cell holding a world point (it may lie outside the map).
    #[inline]
    pub fn world_to_cell(&self, x: f64, y: f64) -> (i64, i64) {
        let (gx, gy) = self.world_to_grid_frame(x, y);
        (
            floor_to_i64(gx / self.resolution),
            floor_to_i64(gy / self.resolution),
        )
    }

    /// The world position of the centre of cell `(i, j)`.
    pub fn cell_center(&self, i: i64, j: i64) -> (f64, f64) {
        self.grid_frame_to_world(
            (i as f64 + 0.5) * self.resolution,
            (j as f64 + 0.5) * self.resolution,
        )
    }

    /// The cell under a world point, `None` outside the map.
    pub fn cell_at(&self, x: f64, y: f64) -> Option<Cell> {
        let (i, j) = self.world_to_cell(x, y);
        self.get(i, j)
    }

    /// Whether a world point lies in a free cell.
    pub fn is_free_at(&self, x: f64, y: f64) -> bool {
        self.cell_at(x, y) == Some(Cell::Free)
    }

    /// `(free, occupied, unknown)` cell counts.
    pub fn counts(&self) -> (usize, usize, usize) {
        let mut c = (0, 0, 0);
        for cell in &self.cells {
            match cell {
                Cell::Free => c.0 += 1,
                Cell::Occupied => c.1 += 1,
                Cell::Unknown => c.2 += 1,
            }
        }
        c
    }

    /// Width and height of the map, metres.
    pub fn size_m(&self) -> (f64, f64) {
        (
            self.width as f64 * self.resolution,
            self.height as f64 * self.resolution,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_follow_the_ros_convention_and_honour_yaw() {
        let mut g =
            OccupancyGrid::filled(4, 3, 0.5, Pose2::new(-1.0, 2.0, 0.0), Cell::Free).unwrap();
        g.set(0, 0, Cell::Occupied);
        assert_eq!(g.world_to_cell(-0.9, 2.1), (0, 0));
        assert_eq!(g.cell_at(-0.9, 2.1), Some(Cell::Occupied));
        assert_eq!(g.world_to_cell(0.99, 3.49), (3, 2));
        assert_eq!(g.cell_at(1.01, 3.0), None);
        let (x, y) = g.cell_center(3, 2);
        assert!((x - 0.75).abs() < 1e-12 && (y - 3.25).abs() < 1e-12);

        // Rotated a quarter turn: the grid's x axis points along world +y.
        let r = OccupancyGrid::filled(
            4,
            3,
            0.5,
            Pose2::new(1.0, 1.0, std::f64::consts::FRAC_PI_2),
            Cell::Free,
        )
        .unwrap();
        let (x, y) = r.cell_center(3, 0);
        assert!(
            (x - 0.75).abs() < 1e-12 && (y - 2.75).abs() < 1e-12,
            "{x} {y}"
        );
        assert_eq!(r.world_to_cell(0.75, 2.75), (3, 0));
    }

    #[test]
    fn floor_matches_the_library_floor() {
        for v in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.999_999,
            -2.000_001,
            1e15 + 0.5,
            -7.0,
        ] {
            assert_eq!(floor_to_i64(v), v.floor() as i64, "{v}");
        }
        assert_eq!(floor_to_i64(f64::NAN), 0);
        // Far outside the range: saturates, never overflows.
        assert_eq!(floor_to_i64(-1e30), i64::MIN);
        assert_eq!(floor_to_i64(f64::NEG_INFINITY), i64::MIN);
        assert_eq!(floor_to_i64(1e30), i64::MAX);
    }

    #[test]
    fn bad_grids_are_refused() {
        let o = Pose2::IDENTITY;
        assert!(matches!(
            OccupancyGrid::filled(0, 3, 0.1, o, Cell::Free),
            Err(GridError::Empty { .. })
        ));
        assert!(matches!(
            OccupancyGrid::filled(100_000, 100_000, 0.1, o, Cell::Free),
            Err(GridError::TooLarge { .. })
        ));
        for r in [0.0, -0.1, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                OccupancyGrid::filled(2, 2, r, o, Cell::Free),
                Err(GridError::BadResolution(_))
            ));
        }
        assert!(matches!(
            OccupancyGrid::new(2, 2, 0.1, o, vec![Cell::Free; 3]),
            Err(GridError::WrongCellCount { got: 3, .. })
        ));
        assert!(check_size(usize::MAX, 2).is_err());
    }
}
