//! Exact grid ray casting: Amanatides and Woo, "A fast voxel traversal algorithm
//! for ray tracing" (Eurographics 1987), in two dimensions. The ray visits every
//! cell it passes through, in order, and stops at the first occupied one; the
//! range is the distance to where the ray enters that cell.

use super::OccupancyGrid;
use crate::math;

/// Two cell-boundary crossings this close (in cells) are one corner crossing.
const CORNER_EPS: f64 = 1e-9;

impl OccupancyGrid {
    /// The distance from the world point `(x, y)` along the world direction
    /// `angle` to the first occupied cell, or `max_range` if there is none within
    /// it (or the ray leaves the map first). A ray starting in an occupied cell
    /// has range 0.
    ///
    /// Only occupied cells stop a ray; unknown cells are seen through, so what
    /// lies beyond a map's unknown border is nothing.
    ///
    /// Corners: a ray passing exactly through a cell corner touches the two cells
    /// beside it in a single point. Grazing one occupied cell that way is not a
    /// hit; when both are occupied (a closed diagonal wall) it is, so no ray leaks
    /// through a one-pixel staircase wall.
    pub fn raycast(&self, x: f64, y: f64, angle: f64, max_range: f64) -> f64 {
        if !(max_range > 0.0) {
            return 0.0;
        }
        if !x.is_finite() || !y.is_finite() || !angle.is_finite() {
            return max_range;
        }
        let (gx, gy) = self.world_to_grid_frame(x, y);
        let (sin, cos) = math::sin_cos(self.world_angle_to_grid(angle));
        // Work in cell units: the ray is p + t d with t in cells.
        let res = self.resolution();
        let (px, py) = (gx / res, gy / res);
        let t_max_range = max_range / res;
        let mut i = px.floor() as i64;
        let mut j = py.floor() as i64;
        let step_i: i64 = if cos > 0.0 { 1 } else { -1 };
        let step_j: i64 = if sin > 0.0 { 1 } else { -1 };
        let delta_i = if cos != 0.0 {
            (1.0 / cos).abs()
        } else {
            f64::INFINITY
        };
        let delta_j = if sin != 0.0 {
            (1.0 / sin).abs()
        } else {
            f64::INFINITY
        };
        let mut next_i = if cos > 0.0 {
            (i as f64 + 1.0 - px) * delta_i
        } else if cos < 0.0 {
            (px - i as f64) * delta_i
        } else {
            f64::INFINITY
        };
        let mut next_j = if sin > 0.0 {
            (j as f64 + 1.0 - py) * delta_j
        } else if sin < 0.0 {
            (py - j as f64) * delta_j
        } else {
            f64::INFINITY
        };
        let (w, h) = (self.width() as i64, self.height() as i64);
        let mut t = 0.0;
        loop {
            if self.is_occupied(i, j) {
                return (t * res).min(max_range);
            }
            // Once outside the map and moving away from it, nothing can be hit.
            if (i < 0 && step_i < 0)
                || (i >= w && step_i > 0)
                || (j < 0 && step_j < 0)
                || (j >= h && step_j > 0)
            {
                return max_range;
            }
            // Crossings closer than CORNER_EPS (in cells) count as one corner
            // crossing, so a ray meant to pass through a corner does so despite
            // rounding in sin and cos.
            if next_i < next_j - CORNER_EPS {
                t = next_i;
                next_i += delta_i;
                i += step_i;
            } else if next_j < next_i - CORNER_EPS {
                t = next_j;
                next_j += delta_j;
                j += step_j;
            } else {
                // Exactly through a corner.
                t = next_i;
                if t > t_max_range {
                    return max_range;
                }
                if self.is_occupied(i + step_i, j) && self.is_occupied(i, j + step_j) {
                    return (t * res).min(max_range);
                }
                next_i += delta_i;
                next_j += delta_j;
                i += step_i;
                j += step_j;
            }
            if t > t_max_range {
                return max_range;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Cell, OccupancyGrid};
    use crate::geometry::Pose2;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    /// A 10 x 10 grid of 0.1 m cells, origin (0, 0), with occupied cells given.
    fn grid(occupied: &[(i64, i64)]) -> OccupancyGrid {
        let mut g = OccupancyGrid::filled(10, 10, 0.1, Pose2::IDENTITY, Cell::Free).unwrap();
        for &(i, j) in occupied {
            g.set(i, j, Cell::Occupied);
        }
        g
    }

    #[test]
    fn axis_aligned_rays_hit_the_near_face() {
        let g = grid(&[(7, 2), (2, 8), (0, 2)]);
        // From the centre of cell (2, 2): the wall cell (7, 2) starts at x = 0.7.
        assert!((g.raycast(0.25, 0.25, 0.0, 5.0) - 0.45).abs() < 1e-12);
        // Up to (2, 8), whose face is y = 0.8.
        assert!((g.raycast(0.25, 0.25, FRAC_PI_2, 5.0) - 0.55).abs() < 1e-12);
        // Left to (0, 2), face x = 0.1.
        assert!((g.raycast(0.25, 0.25, PI, 5.0) - 0.15).abs() < 1e-12);
        // Down: nothing, the ray leaves the map.
        assert_eq!(g.raycast(0.25, 0.25, -FRAC_PI_2, 5.0), 5.0);
        // Inside an occupied cell.
        assert_eq!(g.raycast(0.75, 0.25, 1.0, 5.0), 0.0);
    }

    #[test]
    fn diagonal_ray_hits_at_the_corner_distance() {
        // From (0.05, 0.05) at 45°, the ray enters cell (5, 5) at its corner
        // (0.5, 0.5): sqrt(2) * 0.45.
        let g = grid(&[(5, 5)]);
        let r = g.raycast(0.05, 0.05, FRAC_PI_4, 5.0);
        assert!((r - 0.45 * 2.0_f64.sqrt()).abs() < 1e-9, "{r}");
        // A shallow diagonal: from (0.05, 0.25) with slope 1/2 (angle atan 0.5)
        // the ray reaches y = 0.5 at x = 0.55, i.e. enters cell (5, 5) from below.
        let angle = crate::math::atan2(1.0, 2.0);
        let r = g.raycast(0.05, 0.25, angle, 5.0);
        let expected = crate::math::hypot(0.5, 0.25);
        assert!((r - expected).abs() < 1e-9, "{r} vs {expected}");
    }

    #[test]
    fn grazing_a_corner_passes_but_a_closed_diagonal_wall_does_not() {
        // The ray from (0.05, 0.05) at 45° passes through the corner (0.3, 0.3)
        // shared by cells (2, 3) and (3, 2).
        let one = grid(&[(3, 2)]);
        assert_eq!(one.raycast(0.05, 0.05, FRAC_PI_4, 0.5), 0.5);
        let both = grid(&[(3, 2), (2, 3)]);
        let r = both.raycast(0.05, 0.05, FRAC_PI_4, 0.5);
        assert!((r - 0.25 * 2.0_f64.sqrt()).abs() < 1e-9, "{r}");
    }

    #[test]
    fn nothing_within_max_range_gives_max_range() {
        let g = grid(&[(9, 2)]);
        // The wall is 0.65 m away; with a 0.5 m range it is not seen.
        assert_eq!(g.raycast(0.25, 0.25, 0.0, 0.5), 0.5);
        assert!((g.raycast(0.25, 0.25, 0.0, 0.7) - 0.65).abs() < 1e-12);
        // A ray starting outside the map that crosses it.
        assert!((g.raycast(-1.0, 0.25, 0.0, 5.0) - 1.9).abs() < 1e-12);
    }

    #[test]
    fn a_rotated_map_rotates_its_rays() {
        let mut g = OccupancyGrid::filled(10, 10, 0.1, Pose2::new(0.0, 0.0, FRAC_PI_2), Cell::Free)
            .unwrap();
        g.set(7, 2, Cell::Occupied);
        // Grid x is world +y; grid y is world -x. The cell centre (2.5, 2.5)
        // cells is world (-0.25, 0.25).
        let r = g.raycast(-0.25, 0.25, FRAC_PI_2, 5.0);
        assert!((r - 0.45).abs() < 1e-12, "{r}");
    }
}
