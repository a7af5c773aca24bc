//! Where a robot can be: the binary costmap (free cells farther than the robot
//! radius from every obstacle; thesis `000` Sec. 5.1.3, Fig. 5.1) and uniform
//! sampling over a set of cells (global localization, Probabilistic Robotics
//! Sec. 8.3; random-particle injection, Table 8.3).

use super::{Cell, OccupancyGrid, squared_distance_transform};
use crate::geometry::Pose2;
use crate::math;
use rand::Rng;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A binary costmap: a cell is *valid* when it is free and its centre is more
/// than `radius` from the centre of every occupied cell (the map inflated by the
/// robot radius). Unknown cells are invalid; so is everything outside the map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Costmap {
    width: usize,
    height: usize,
    radius: f64,
    valid: Vec<bool>,
    valid_count: usize,
    /// The grid's frame, for world lookups (a one-cell grid, not a copy).
    frame: OccupancyGrid,
}

impl Costmap {
    /// Inflates `grid` by `radius` metres (negative or NaN: 0).
    pub fn inflate(grid: &OccupancyGrid, radius: f64) -> Self {
        let radius = if radius > 0.0 && radius.is_finite() {
            radius
        } else {
            0.0
        };
        let seeds: Vec<bool> = grid.cells().iter().map(|c| *c == Cell::Occupied).collect();
        let sq = squared_distance_transform(&seeds, grid.width(), grid.height());
        let r_cells = radius / grid.resolution();
        let r_sq = r_cells * r_cells;
        let valid: Vec<bool> = grid
            .cells()
            .iter()
            .zip(&sq)
            .map(|(c, &d)| *c == Cell::Free && d > r_sq)
            .collect();
        let valid_count = valid.iter().filter(|v| **v).count();
        let frame = OccupancyGrid::filled(1, 1, grid.resolution(), grid.origin(), Cell::Unknown)
            .unwrap_or_else(|_| grid.clone());
        Self {
            width: grid.width(),
            height: grid.height(),
            radius,
            valid,
            valid_count,
            frame,
        }
    }

    /// The inflation radius, metres.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Cells per row and rows.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Whether cell `(i, j)` is valid (outside the map: no).
    #[inline]
    pub fn is_valid_cell(&self, i: i64, j: i64) -> bool {
        i >= 0
            && j >= 0
            && (i as usize) < self.width
            && (j as usize) < self.height
            && self.valid[j as usize * self.width + i as usize]
    }

    /// Whether the cell under a world point is valid.
    #[inline]
    pub fn is_valid_at(&self, x: f64, y: f64) -> bool {
        let (i, j) = self.frame.world_to_cell(x, y);
        self.is_valid_cell(i, j)
    }

    /// Whether the straight path between two world points stays in valid cells,
    /// checked at steps of at most half a cell (thesis `000` Sec. 5.1.3).
    pub fn is_path_valid(&self, x0: f64, y0: f64, x1: f64, y1: f64) -> bool {
        let length = math::hypot(x1 - x0, y1 - y0);
        let half_cell = 0.5 * self.frame.resolution();
        let steps = if length.is_finite() {
            (length / half_cell).ceil().min(1e6) as usize
        } else {
            return false;
        };
        (0..=steps).all(|k| {
            let s = if steps == 0 {
                1.0
            } else {
                k as f64 / steps as f64
            };
            self.is_valid_at(x0 + s * (x1 - x0), y0 + s * (y1 - y0))
        })
    }

    /// Every valid cell as a row-major flag.
    pub fn valid(&self) -> &[bool] {
        &self.valid
    }

    /// How many cells are valid.
    pub fn valid_count(&self) -> usize {
        self.valid_count
    }

    /// The valid cells, for uniform sampling.
    pub fn valid_cells(&self) -> FreeCells {
        FreeCells::from_flags(&self.frame, self.width, &self.valid)
    }
}

/// A set of cells to sample poses from uniformly: a position uniform inside a
/// uniformly chosen cell and a heading uniform in (−π, π].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FreeCells {
    cells: Vec<u32>,
    width: usize,
    frame: OccupancyGrid,
}

impl FreeCells {
    /// The free cells of `grid`.
    pub fn of(grid: &OccupancyGrid) -> Self {
        let flags: Vec<bool> = grid.cells().iter().map(|c| *c == Cell::Free).collect();
        Self::from_flags(grid, grid.width(), &flags)
    }

    fn from_flags(frame: &OccupancyGrid, width: usize, flags: &[bool]) -> Self {
        let cells = flags
            .iter()
            .enumerate()
            .filter(|(_, f)| **f)
            .map(|(k, _)| k as u32)
            .collect();
        let frame = OccupancyGrid::filled(1, 1, frame.resolution(), frame.origin(), Cell::Unknown)
            .unwrap_or_else(|_| frame.clone());
        Self {
            cells,
            width: width.max(1),
            frame,
        }
    }

    /// How many cells there are to sample from.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Whether there is no cell at all.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// A uniform random pose over the cells, `None` if there are none.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> Option<Pose2> {
        if self.cells.is_empty() {
            return None;
        }
        let k = self.cells[rng.random_range(0..self.cells.len())] as usize;
        let (i, j) = ((k % self.width) as f64, (k / self.width) as f64);
        let res = self.frame.resolution();
        let gx = (i + rng.random::<f64>()) * res;
        let gy = (j + rng.random::<f64>()) * res;
        let (x, y) = self.frame.grid_frame_to_world(gx, gy);
        let theta = (2.0 * rng.random::<f64>() - 1.0) * PI;
        Some(Pose2::new(x, y, theta))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn inflation_by_a_radius_on_a_hand_made_grid() {
        // 9 x 9 free cells of 0.1 m, one obstacle at (4, 4), radius 0.15 m: the
        // cells whose centres are within 1.5 cells of (4, 4) are invalid: the
        // 3 x 3 block around it (distances 0, 1, sqrt 2 < 1.5), and not (4, 6)
        // (distance 2) nor (5, 6) (sqrt 5).
        let mut g = OccupancyGrid::filled(9, 9, 0.1, Pose2::IDENTITY, Cell::Free).unwrap();
        g.set(4, 4, Cell::Occupied);
        g.set(0, 8, Cell::Unknown);
        let c = Costmap::inflate(&g, 0.15);
        let invalid: Vec<(i64, i64)> = (0..9)
            .flat_map(|j| (0..9).map(move |i| (i, j)))
            .filter(|&(i, j)| !c.is_valid_cell(i, j))
            .collect();
        let mut expected: Vec<(i64, i64)> =
            (3..=5).flat_map(|j| (3..=5).map(move |i| (i, j))).collect();
        expected.push((0, 8));
        expected.sort_by_key(|&(i, j)| (j, i));
        assert_eq!(invalid, expected);
        assert_eq!(c.valid_count(), 81 - 10);
        assert!(!c.is_valid_cell(-1, 0));
        assert!(c.is_path_valid(0.05, 0.05, 0.85, 0.05));
        assert!(!c.is_path_valid(0.05, 0.45, 0.85, 0.45));
    }

    #[test]
    fn uniform_samples_land_in_free_cells_only() {
        let mut g =
            OccupancyGrid::filled(10, 10, 0.5, Pose2::new(2.0, -1.0, 0.3), Cell::Occupied).unwrap();
        g.set(2, 7, Cell::Free);
        g.set(8, 1, Cell::Free);
        let free = FreeCells::of(&g);
        assert_eq!(free.len(), 2);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut in_first = 0;
        for _ in 0..2000 {
            let p = free.sample(&mut rng).unwrap();
            assert!(g.is_free_at(p.x, p.y));
            if g.world_to_cell(p.x, p.y) == (2, 7) {
                in_first += 1;
            }
        }
        // Binomial(2000, 1/2): sd 22.
        assert!((in_first - 1000_i32).abs() < 110, "{in_first}");
        let none = FreeCells::of(
            &OccupancyGrid::filled(2, 2, 1.0, Pose2::IDENTITY, Cell::Unknown).unwrap(),
        );
        assert!(none.sample(&mut rng).is_none());
    }
}
