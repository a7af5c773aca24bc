//! The Euclidean distance field of a grid: for every cell, the distance from its
//! centre to the centre of the nearest occupied cell, capped at a maximum (ROS
//! amcl's `laser_likelihood_max_dist`). The likelihood-field model reads it
//! (Probabilistic Robotics Sec. 6.4, Table 6.3).
//!
//! Computed exactly with the two-pass squared distance transform of Felzenszwalb
//! and Huttenlocher ("Distance transforms of sampled functions", Theory of
//! Computing 8, 2012): a 1-D lower envelope of parabolas along every column,
//! then along every row. Linear in the number of cells.

use super::{Cell, OccupancyGrid};
use serde::{Deserialize, Serialize};

/// "No obstacle" in the squared transform: larger than any squared distance on
/// a map of [`super::MAX_CELLS`] cells.
const FAR: f64 = 1e20;

/// One-dimensional squared distance transform (Felzenszwalb–Huttenlocher
/// Algorithm DT(f)): `d[q] = min_p (q − p)² + f[p]`. Samples with `f ≥ FAR`
/// (no obstacle) never enter the lower envelope; if every sample is one, `d`
/// is `FAR` everywhere. `v` and `z` are scratch buffers of length at least `n`
/// and `n + 1`.
fn dt_1d(f: &[f64], d: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    // Number of parabolas in the envelope.
    let mut count = 0usize;
    for q in 0..n {
        if f[q] >= FAR {
            continue;
        }
        if count == 0 {
            v[0] = q;
            z[0] = f64::NEG_INFINITY;
            z[1] = f64::INFINITY;
            count = 1;
            continue;
        }
        let mut k = count - 1;
        loop {
            let p = v[k];
            // Where the parabolas from p and q intersect (exact: squared
            // distances of at most 5e7 cells are integers well inside f64).
            let s = ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q - p) as f64);
            if s <= z[k] {
                // z[0] is −∞, so this never runs below k = 0.
                k -= 1;
            } else {
                k += 1;
                v[k] = q;
                z[k] = s;
                z[k + 1] = f64::INFINITY;
                count = k + 1;
                break;
            }
        }
    }
    if count == 0 {
        d[..n].fill(FAR);
        return;
    }
    let mut k = 0;
    for (q, dq) in d.iter_mut().enumerate().take(n) {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        let diff = q as f64 - p as f64;
        *dq = diff * diff + f[p];
    }
}

/// The exact squared Euclidean distance transform of a `width x height` grid
/// (row-major), in squared cells: `0` on a seed cell, `≥ 1e20` where there is
/// no seed at all.
pub fn squared_distance_transform(seeds: &[bool], width: usize, height: usize) -> Vec<f64> {
    let mut out: Vec<f64> = seeds.iter().map(|&s| if s { 0.0 } else { FAR }).collect();
    let n = width.max(height);
    let mut f = vec![0.0; n];
    let mut d = vec![0.0; n];
    let mut v = vec![0usize; n];
    let mut z = vec![0.0; n + 1];
    // Columns.
    for i in 0..width {
        for j in 0..height {
            f[j] = out[j * width + i];
        }
        dt_1d(&f[..height], &mut d[..height], &mut v, &mut z);
        for j in 0..height {
            out[j * width + i] = d[j].min(FAR);
        }
    }
    // Rows.
    for j in 0..height {
        let row = &mut out[j * width..(j + 1) * width];
        f[..width].copy_from_slice(row);
        dt_1d(&f[..width], &mut d[..width], &mut v, &mut z);
        for (o, &dv) in row.iter_mut().zip(&d[..width]) {
            *o = dv.min(FAR);
        }
    }
    out
}

/// The distance from every cell to the nearest occupied cell, capped at
/// `max_distance` (amcl's `laser_likelihood_max_dist`, default 2 m).
///
/// Stored as squared distances in cells (exact integers), so a model can
/// tabulate its likelihood per squared distance instead of evaluating `exp`
/// for every beam.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DistanceField {
    width: usize,
    height: usize,
    resolution: f64,
    max_distance: f64,
    /// Squared distance in cells, capped at `cap_sq`.
    squared: Vec<u32>,
    cap_sq: u32,
    /// The grid's frame, for world lookups.
    grid_frame: OccupancyGrid,
}

impl DistanceField {
    /// The distance field of `grid`'s occupied cells, capped at `max_distance`
    /// metres (a non-positive or NaN cap is taken as one cell).
    pub fn new(grid: &OccupancyGrid, max_distance: f64) -> Self {
        let res = grid.resolution();
        let max_distance = if max_distance > 0.0 && max_distance.is_finite() {
            max_distance
        } else {
            res
        };
        let cap_cells = (max_distance / res).ceil().min(60_000.0);
        let cap_sq = (cap_cells * cap_cells) as u32;
        let seeds: Vec<bool> = grid.cells().iter().map(|c| *c == Cell::Occupied).collect();
        let sq = squared_distance_transform(&seeds, grid.width(), grid.height());
        let squared = sq.iter().map(|&d| d.min(cap_sq as f64) as u32).collect();
        // Only the frame is needed for lookups; keep a one-cell grid with the
        // same origin and resolution instead of a copy of the map.
        let grid_frame = OccupancyGrid::filled(1, 1, res, grid.origin(), Cell::Unknown)
            .unwrap_or_else(|_| grid.clone());
        Self {
            width: grid.width(),
            height: grid.height(),
            resolution: res,
            max_distance,
            squared,
            cap_sq,
            grid_frame,
        }
    }

    /// The cap, metres.
    pub fn max_distance(&self) -> f64 {
        self.max_distance
    }

    /// The largest squared distance stored, in squared cells (the cap).
    pub fn cap_squared_cells(&self) -> u32 {
        self.cap_sq
    }

    /// Side of a cell, metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// Cells per row and rows.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Squared distance of cell `(i, j)` in squared cells, capped; the cap
    /// outside the map.
    #[inline]
    pub fn squared_cells(&self, i: i64, j: i64) -> u32 {
        if i >= 0 && j >= 0 && (i as usize) < self.width && (j as usize) < self.height {
            self.squared[j as usize * self.width + i as usize]
        } else {
            self.cap_sq
        }
    }

    /// Squared distance (squared cells, capped) at a world point.
    #[inline]
    pub fn squared_cells_at(&self, x: f64, y: f64) -> u32 {
        let (i, j) = self.grid_frame.world_to_cell(x, y);
        self.squared_cells(i, j)
    }

    /// The distance of cell `(i, j)` in metres, capped at
    /// [`max_distance`](Self::max_distance).
    pub fn distance(&self, i: i64, j: i64) -> f64 {
        self.metres(self.squared_cells(i, j))
    }

    /// The distance at a world point, metres, capped.
    pub fn distance_at(&self, x: f64, y: f64) -> f64 {
        self.metres(self.squared_cells_at(x, y))
    }

    /// A world point in the grid frame, in cells (so cell `(i, j)` covers
    /// `[i, i+1) x [j, j+1)`).
    #[inline]
    pub fn world_to_cells(&self, x: f64, y: f64) -> (f64, f64) {
        let (gx, gy) = self.grid_frame.world_to_grid_frame(x, y);
        (gx / self.resolution, gy / self.resolution)
    }

    /// The heading of the grid frame in the world, radians.
    pub fn frame_yaw(&self) -> f64 {
        self.grid_frame.origin().theta
    }

    /// Converts a squared cell distance to metres, capped.
    #[inline]
    pub fn metres(&self, squared_cells: u32) -> f64 {
        ((squared_cells as f64).sqrt() * self.resolution).min(self.max_distance)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Pose2;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn brute_force(seeds: &[bool], w: usize, h: usize) -> Vec<f64> {
        let pts: Vec<(usize, usize)> = (0..w * h)
            .filter(|&k| seeds[k])
            .map(|k| (k % w, k / w))
            .collect();
        (0..w * h)
            .map(|k| {
                let (i, j) = (k % w, k / w);
                pts.iter()
                    .map(|&(a, b)| {
                        let dx = a as f64 - i as f64;
                        let dy = b as f64 - j as f64;
                        dx * dx + dy * dy
                    })
                    .fold(FAR, f64::min)
            })
            .collect()
    }

    #[test]
    fn matches_brute_force_on_random_grids() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for (w, h, density) in [
            (1, 1, 0.5),
            (7, 1, 0.3),
            (1, 9, 0.3),
            (23, 17, 0.02),
            (31, 29, 0.2),
            (40, 40, 0.005),
        ] {
            for _ in 0..5 {
                let seeds: Vec<bool> = (0..w * h).map(|_| rng.random::<f64>() < density).collect();
                let fast = squared_distance_transform(&seeds, w, h);
                let slow = brute_force(&seeds, w, h);
                for k in 0..w * h {
                    if slow[k] >= FAR {
                        assert!(fast[k] >= FAR, "{w}x{h} cell {k}");
                    } else {
                        assert_eq!(fast[k], slow[k], "{w}x{h} cell {k}");
                    }
                }
            }
        }
    }

    #[test]
    fn field_is_capped_and_world_lookups_work() {
        let mut g =
            OccupancyGrid::filled(50, 20, 0.1, Pose2::new(1.0, 0.0, 0.0), Cell::Free).unwrap();
        g.set(10, 10, Cell::Occupied);
        let f = DistanceField::new(&g, 0.5);
        assert_eq!(f.distance(10, 10), 0.0);
        assert!((f.distance(13, 14) - 0.5).abs() < 1e-12);
        assert!((f.distance(12, 11) - 0.05_f64.sqrt()).abs() < 1e-12);
        assert_eq!(f.distance(40, 10), 0.5);
        // World: cell (13, 10) is at x = 1 + 1.35.
        assert!((f.distance_at(2.35, 1.05) - 0.3).abs() < 1e-12);
        assert_eq!(f.distance_at(-5.0, 0.0), 0.5);
    }
}
