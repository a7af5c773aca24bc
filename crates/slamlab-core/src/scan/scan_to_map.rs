//! Scan-to-map matching as Cartographer's local SLAM does it (thesis `000`
//! Sec. 5.2.1): a coarse correlative search over a small window of poses
//! (Olson 2009, "Real-time correlative scan matching"; Cartographer's
//! `RealTimeCorrelativeScanMatcher2D`), then a local least-squares refinement
//! of thesis Eq. 5.5,
//!
//! ```text
//! argmin_ξ  Σ_k ( w_occ/√K · (1 − M_smooth(T_ξ h_k)) )²
//!           + ( w_t · (ξ_xy − t_predicted) )² + ( w_r · (ξ_θ − θ_initial) )²
//! ```
//!
//! where `M_smooth` is the probability grid interpolated bicubically (a
//! Catmull-Rom cubic convolution over cell centres, as Ceres'
//! `BiCubicInterpolator` that Cartographer's `CeresScanMatcher2D` uses), and
//! the two last terms (Cartographer's translation and rotation weights) keep
//! the answer near the starting pose where the map says little. Eq. 5.5 is the
//! first term alone. The heading is pulled towards the correlative search's
//! answer, where the refinement starts; the position either towards the
//! odometry prediction (`pull_to_prediction`, as Cartographer does:
//! `ceres_scan_matcher.Match(pose_prediction.translation(),
//! initial_ceres_pose, ...)`) or towards the search's answer too (the
//! default here). The two fail differently:
//!
//! - Pulled to the search's answer, a long corridor swallows the motion.
//!   Along a corridor the map only constrains the scan's far points, which
//!   fall just past the mapped walls and score higher one step back, so the
//!   estimate stays behind the robot scan after scan (the Cartographer
//!   lesson on the built-in office, seed 3: 4.9 m RMSE over 600 scans; 0.12 m
//!   pulled to the prediction).
//! - Pulled to the prediction with Cartographer's weights (translation 10,
//!   map term at most 1), the pull outweighs the map: a prediction 36 cm off
//!   stays 36 cm off although the search found the truth
//!   (`recovers_an_offset_of_30_cm_and_10_degrees` below). Cartographer
//!   relies on a good prediction here.
//!
//! The mapping lesson keeps the search's answer; the Cartographer lesson
//! pulls to the prediction, as Cartographer does. The refinement is
//! Levenberg-Marquardt on the three pose numbers, written out here instead of
//! calling a solver library.
//!
//! Cells never observed read as [`UNKNOWN_PROBABILITY`] (Cartographer reads
//! them at its largest correspondence cost, probability 0.1).

use super::{Point2, PointTransform, Scan, ScanMatch, ScanMatcher};
use crate::geometry::{Pose2, wrap_angle};
use crate::grid::{ProbabilityGrid, TABLE_ENTRIES, TILE, floor_to_i64, table_log_odds};
use crate::math;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// What a never-observed cell reads as.
pub const UNKNOWN_PROBABILITY: f64 = 0.1;

/// Scan-to-map parameters (Cartographer's names in the comments).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ScanToMapParams {
    /// Run the correlative search first (`use_online_correlative_scan_matching`).
    pub correlative: bool,
    /// Half-width of the correlative search in x and y, metres
    /// (`linear_search_window`).
    pub linear_search_window: f64,
    /// Half-width of the correlative search in heading, radians
    /// (`angular_search_window`).
    pub angular_search_window: f64,
    /// Weight of the map term (`occupied_space_weight`).
    pub occupied_space_weight: f64,
    /// Weight of the pull on the position (`translation_weight`).
    pub translation_weight: f64,
    /// Where the position is pulled: the prediction (true, as Cartographer's
    /// local SLAM does) or the correlative search's answer (false).
    pub pull_to_prediction: bool,
    /// Weight of the pull towards the initial heading (`rotation_weight`).
    pub rotation_weight: f64,
    /// Levenberg-Marquardt iterations at most (`max_num_iterations`).
    pub max_iterations: usize,
    /// At most this many scan points are used (evenly spread); 0: all.
    pub max_points: usize,
}

impl Default for ScanToMapParams {
    fn default() -> Self {
        Self {
            correlative: true,
            linear_search_window: 0.1,
            angular_search_window: 5f64.to_radians(),
            occupied_space_weight: 1.0,
            translation_weight: 10.0,
            pull_to_prediction: false,
            rotation_weight: 40.0,
            max_iterations: 20,
            max_points: 200,
        }
    }
}

/// One Levenberg-Marquardt iteration, for stepping and plotting.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RefineStep {
    /// The pose after the iteration.
    pub pose: Pose2,
    /// The cost (sum of squared residuals) after the iteration.
    pub cost: f64,
    /// Whether the step was taken (a step that raised the cost is refused and
    /// the damping raised).
    pub accepted: bool,
}

/// What the matcher did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ScanToMapRecord {
    /// The correlative search's best pose and score (mean probability of the
    /// points' cells, weighted by the distance from the prediction), if it ran.
    pub correlative: Option<(Pose2, f64)>,
    /// Candidate poses the correlative search scored.
    pub candidates: usize,
    /// The angular step of the correlative search, radians.
    pub angular_step: f64,
    /// The Levenberg-Marquardt iterations.
    pub steps: Vec<RefineStep>,
}

/// Probabilities of log-odds values from a table: the matcher reads cells
/// hundreds of thousands of times per scan, and an exponential for each would
/// dominate. 4096 entries over log odds in `[−16, 16]`, nearest entry
/// ([`table_entry`](crate::grid::table_entry), which the
/// grid keeps for every cell), and one more for a cell never seen.
#[derive(Clone, Debug)]
pub struct ProbabilityLookup {
    table: Vec<f64>,
}

impl Default for ProbabilityLookup {
    fn default() -> Self {
        let table = (0..TABLE_ENTRIES)
            .map(|k| crate::grid::probability(table_log_odds(k)))
            .chain([UNKNOWN_PROBABILITY])
            .collect();
        Self { table }
    }
}

impl ProbabilityLookup {
    /// The probability of cell `(i, j)`, [`UNKNOWN_PROBABILITY`] if never seen.
    #[inline]
    pub fn cell(&self, grid: &ProbabilityGrid, i: i64, j: i64) -> f64 {
        self.of_entry(grid.entry_at(i, j))
    }

    /// The probability of table entry `k` (the grid's [`table_entry`](crate::grid::table_entry) of a
    /// cell).
    #[inline]
    pub fn of_entry(&self, k: u16) -> f64 {
        self.table
            .get(usize::from(k))
            .copied()
            .unwrap_or(UNKNOWN_PROBABILITY)
    }

    /// The probabilities of cells `(i, j)` to `(i + 3, j)`, as
    /// [`cell`](Self::cell) gives them, read in one go when they share a tile.
    #[inline]
    fn row_of_four(&self, grid: &ProbabilityGrid, i: i64, j: i64) -> [f64; 4] {
        match grid.entries_in_row(i, j, 4) {
            Some(&[a, b, c, d]) => [a, b, c, d].map(|k| self.of_entry(k)),
            _ => [0, 1, 2, 3].map(|di| self.cell(grid, i + di, j)),
        }
    }

    /// `M_smooth` at the world point `(x, y)` and its gradient: bicubic
    /// (Catmull-Rom) interpolation of the cell probabilities, the cell
    /// centres being the samples.
    pub fn smooth(&self, grid: &ProbabilityGrid, x: f64, y: f64) -> (f64, [f64; 2]) {
        let r = grid.resolution();
        // Continuous cell coordinates with the cell centres at integers.
        let (u, v) = (x / r - 0.5, y / r - 0.5);
        let (i0, j0) = (floor_to_i64(u), floor_to_i64(v));
        let (tu, tv) = (u - i0 as f64, v - j0 as f64);
        let mut rows = [0.0; 4];
        let mut rows_du = [0.0; 4];
        // The 4 x 4 cells around the point, from one tile when they share one.
        let window = grid.entries_window(i0 - 1, j0 - 1, 4);
        for (n, dj) in (-1..=2).enumerate() {
            let p = match window {
                Some((entries, base)) => {
                    let start = base + n * TILE;
                    [0, 1, 2, 3].map(|di| self.of_entry(entries[start + di]))
                }
                None => self.row_of_four(grid, i0 - 1, j0 + dj),
            };
            let (f, df) = catmull_rom(p, tu);
            rows[n] = f;
            rows_du[n] = df;
        }
        let (f, df_dv) = catmull_rom(rows, tv);
        let (df_du, _) = catmull_rom(rows_du, tv);
        (f, [df_du / r, df_dv / r])
    }
}

/// The Catmull-Rom cubic through `p[1]` (t = 0) and `p[2]` (t = 1), and its
/// derivative in `t` (Keys' cubic convolution with a = −0.5).
#[inline]
fn catmull_rom(p: [f64; 4], t: f64) -> (f64, f64) {
    let a = -0.5 * p[0] + 1.5 * p[1] - 1.5 * p[2] + 0.5 * p[3];
    let b = p[0] - 2.5 * p[1] + 2.0 * p[2] - 0.5 * p[3];
    let c = -0.5 * p[0] + 0.5 * p[2];
    let d = p[1];
    (
        ((a * t + b) * t + c) * t + d,
        (3.0 * a * t + 2.0 * b) * t + c,
    )
}

/// At most `max` of `points`, evenly spread (all of them if `max` is 0).
pub fn spread_points(points: &[Point2], max: usize) -> Vec<Point2> {
    if max == 0 || points.len() <= max {
        return points.to_vec();
    }
    (0..max).map(|k| points[k * points.len() / max]).collect()
}

/// The correlative search's angular step for points up to `max_range` metres
/// from the sensor on a grid of `resolution`: the angle that moves the
/// farthest point by one cell (Cartographer's
/// `acos(1 − r² / (2 d_max²))`, Olson 2009).
pub fn angular_step(resolution: f64, max_range: f64) -> f64 {
    let d = max_range.max(resolution);
    math::acos((1.0 - resolution * resolution / (2.0 * d * d)).clamp(-1.0, 1.0))
}

/// Matches scan points (sensor frame, metres) against `grid`, starting from
/// the predicted pose `predicted` (`map_from_sensor`). Returns the match (its
/// cost is the final Eq. 5.5 sum with the weights, `converged` when the last
/// step was below 1e-6) and what the matcher did, or `None` when there are no
/// finite points.
pub fn match_scan_to_map(
    grid: &ProbabilityGrid,
    lookup: &ProbabilityLookup,
    points: &[Point2],
    predicted: Pose2,
    params: &ScanToMapParams,
) -> Option<(ScanMatch, ScanToMapRecord)> {
    let points: Vec<Point2> = spread_points(points, params.max_points)
        .into_iter()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
        .collect();
    if points.is_empty() || !predicted.is_finite() {
        return None;
    }
    let mut record = ScanToMapRecord::default();
    let mut initial = predicted;
    if params.correlative {
        let (best, score, candidates, step) =
            correlative_search(grid, lookup, &points, predicted, params);
        record.correlative = Some((best, score));
        record.candidates = candidates;
        record.angular_step = step;
        initial = best;
    }
    let problem = Problem {
        grid,
        lookup,
        points: &points,
        target_xy: if params.pull_to_prediction {
            [predicted.x, predicted.y]
        } else {
            [initial.x, initial.y]
        },
        target_theta: initial.theta,
        params,
    };
    let (pose, cost, converged) = problem.solve(initial, &mut record.steps);
    Some((
        ScanMatch {
            pose,
            cost,
            iterations: record.steps.len(),
            converged,
        },
        record,
    ))
}

/// Scan-to-map matching behind the [`ScanMatcher`] trait.
#[derive(Clone, Copy, Debug)]
pub struct GridMatcher<'a> {
    /// The map matched against.
    pub grid: &'a ProbabilityGrid,
    /// Its probability table.
    pub lookup: &'a ProbabilityLookup,
    /// The matcher's parameters.
    pub params: ScanToMapParams,
}

impl ScanMatcher for GridMatcher<'_> {
    fn name(&self) -> &'static str {
        "scan-to-map"
    }

    fn match_scan(&self, scan: &Scan, initial: Pose2) -> Option<ScanMatch> {
        match_scan_to_map(
            self.grid,
            self.lookup,
            &scan.points(),
            initial,
            &self.params,
        )
        .map(|(m, _)| m)
    }
}

/// The correlative search: every heading in the window at [`angular_step`],
/// every cell offset within the linear window; the score of a candidate is the
/// mean probability of the cells its points fall in, times
/// `exp(−(0.1 |Δt|² + 0.1 Δθ²))` (Cartographer's `translation_delta_cost_weight`
/// and `rotation_delta_cost_weight`, 0.1 each), which breaks ties towards the
/// prediction. Returns the best pose, its score, the candidates scored and the
/// angular step.
fn correlative_search(
    grid: &ProbabilityGrid,
    lookup: &ProbabilityLookup,
    points: &[Point2],
    predicted: Pose2,
    params: &ScanToMapParams,
) -> (Pose2, f64, usize, f64) {
    let r = grid.resolution();
    let max_range = points
        .iter()
        .map(|p| math::hypot(p[0], p[1]))
        .fold(0.0, f64::max);
    let step = angular_step(r, max_range);
    let angular_window = if params.angular_search_window.is_finite() {
        params
            .angular_search_window
            .clamp(0.0, std::f64::consts::PI)
    } else {
        0.0
    };
    let linear_window = if params.linear_search_window.is_finite() {
        params.linear_search_window.clamp(0.0, 5.0)
    } else {
        0.0
    };
    let n_angles = (angular_window / step).ceil() as i64;
    let n_cells = (linear_window / r).ceil() as i64;
    let inv_n = 1.0 / points.len() as f64;
    let mut best = (predicted, f64::NEG_INFINITY);
    let mut candidates = 0;
    // Per heading, every candidate offset's sum of cell probabilities, built
    // point by point (so each sum adds its points in order, as a sum per
    // candidate would); a point's window is read a tile row at a time.
    let side = (2 * n_cells + 1) as usize;
    let mut sums = vec![0.0_f64; side * side];
    for a in -n_angles..=n_angles {
        let dtheta = a as f64 * step;
        let rotated = PointTransform::new(&Pose2::new(
            predicted.x,
            predicted.y,
            predicted.theta + dtheta,
        ));
        sums.fill(0.0);
        for p in points {
            let q = rotated.apply(*p);
            let (ci, cj) = grid.cell_of(q[0], q[1]);
            let i0 = ci - n_cells;
            // The point's window in one tile (most points): its rows are
            // slices of that tile's entries.
            if let Some((entries, base)) = grid.entries_window(i0, cj - n_cells, side) {
                for (row, out) in sums.chunks_exact_mut(side).enumerate() {
                    let start = base + row * TILE;
                    for (sum, &k) in out.iter_mut().zip(&entries[start..start + side]) {
                        *sum += lookup.of_entry(k);
                    }
                }
                continue;
            }
            for (row, dj) in (-n_cells..=n_cells).enumerate() {
                let j = cj + dj;
                let out = &mut sums[row * side..(row + 1) * side];
                match grid.entries_in_row(i0, j, side) {
                    Some(entries) => {
                        for (sum, &k) in out.iter_mut().zip(entries) {
                            *sum += lookup.of_entry(k);
                        }
                    }
                    None => {
                        for (col, sum) in out.iter_mut().enumerate() {
                            *sum += lookup.cell(grid, i0 + col as i64, j);
                        }
                    }
                }
            }
        }
        for (row, dj) in (-n_cells..=n_cells).enumerate() {
            for (col, di) in (-n_cells..=n_cells).enumerate() {
                candidates += 1;
                let sum = sums[row * side + col];
                let (dx, dy) = (di as f64 * r, dj as f64 * r);
                let penalty = math::exp(-(0.1 * (dx * dx + dy * dy) + 0.1 * dtheta * dtheta));
                let score = sum * inv_n * penalty;
                if score > best.1 {
                    best = (
                        Pose2::new(
                            predicted.x + dx,
                            predicted.y + dy,
                            wrap_angle(predicted.theta + dtheta),
                        ),
                        score,
                    );
                }
            }
        }
    }
    (best.0, best.1, candidates, step)
}

/// The least-squares problem of Eq. 5.5 with its two pulls.
struct Problem<'a> {
    grid: &'a ProbabilityGrid,
    lookup: &'a ProbabilityLookup,
    points: &'a [Point2],
    target_xy: [f64; 2],
    target_theta: f64,
    params: &'a ScanToMapParams,
}

impl Problem<'_> {
    /// The cost at `pose` and, with `normal`, the Gauss-Newton system `JᵀJ`
    /// and `Jᵀr`.
    fn evaluate(
        &self,
        pose: &Pose2,
        normal: Option<(&mut Matrix3<f64>, &mut Vector3<f64>)>,
    ) -> f64 {
        let w = self.params.occupied_space_weight.max(0.0) / (self.points.len() as f64).sqrt();
        let (s, c) = math::sin_cos(pose.theta);
        let mut jtj = Matrix3::zeros();
        let mut jtr = Vector3::zeros();
        let mut cost = 0.0;
        for p in self.points {
            let x = c * p[0] - s * p[1] + pose.x;
            let y = s * p[0] + c * p[1] + pose.y;
            let (m, grad) = self.lookup.smooth(self.grid, x, y);
            let residual = w * (1.0 - m);
            cost += residual * residual;
            // d(x, y)/dθ = (−s px − c py, c px − s py).
            let dx_dt = -s * p[0] - c * p[1];
            let dy_dt = c * p[0] - s * p[1];
            let j = Vector3::new(
                -w * grad[0],
                -w * grad[1],
                -w * (grad[0] * dx_dt + grad[1] * dy_dt),
            );
            jtj += j * j.transpose();
            jtr += j * residual;
        }
        let tw = self.params.translation_weight.max(0.0);
        let rw = self.params.rotation_weight.max(0.0);
        let rx = tw * (pose.x - self.target_xy[0]);
        let ry = tw * (pose.y - self.target_xy[1]);
        let rt = rw * wrap_angle(pose.theta - self.target_theta);
        cost += rx * rx + ry * ry + rt * rt;
        jtj[(0, 0)] += tw * tw;
        jtj[(1, 1)] += tw * tw;
        jtj[(2, 2)] += rw * rw;
        jtr[0] += tw * rx;
        jtr[1] += tw * ry;
        jtr[2] += rw * rt;
        if let Some((a, b)) = normal {
            *a = jtj;
            *b = jtr;
        }
        cost
    }

    /// Levenberg-Marquardt from `initial`; records every iteration.
    fn solve(&self, initial: Pose2, steps: &mut Vec<RefineStep>) -> (Pose2, f64, bool) {
        let mut pose = initial;
        let mut jtj = Matrix3::zeros();
        let mut jtr = Vector3::zeros();
        let mut cost = self.evaluate(&pose, Some((&mut jtj, &mut jtr)));
        let mut lambda = 1e-3;
        let mut converged = false;
        for _ in 0..self.params.max_iterations.min(1000) {
            let mut damped = jtj;
            for k in 0..3 {
                damped[(k, k)] += lambda * jtj[(k, k)].max(1e-9);
            }
            let Some(delta) = damped.cholesky().map(|ch| ch.solve(&(-jtr))) else {
                break;
            };
            let candidate = Pose2::new(
                pose.x + delta[0],
                pose.y + delta[1],
                wrap_angle(pose.theta + delta[2]),
            );
            let mut cjtj = Matrix3::zeros();
            let mut cjtr = Vector3::zeros();
            let candidate_cost = self.evaluate(&candidate, Some((&mut cjtj, &mut cjtr)));
            let accepted = candidate_cost.is_finite() && candidate_cost <= cost;
            if accepted {
                pose = candidate;
                cost = candidate_cost;
                jtj = cjtj;
                jtr = cjtr;
                lambda = (lambda * 0.3).max(1e-9);
            } else {
                lambda *= 10.0;
            }
            steps.push(RefineStep {
                pose,
                cost,
                accepted,
            });
            if accepted && delta.norm() < 1e-6 {
                converged = true;
                break;
            }
            if lambda > 1e8 {
                // No step lowers the cost: a minimum up to the damping.
                converged = true;
                break;
            }
        }
        (pose, cost, converged)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{InsertParams, UpdateRule};
    use crate::laser::test_room::{Segment, ray_cast};

    /// A probability grid of a closed room with a few boxes, built from
    /// noise-free scans taken from known poses (ray cast against the shapes).
    fn room() -> (ProbabilityGrid, impl Fn(&Pose2) -> Scan) {
        // Walls as segments.
        let walls: Vec<[f64; 4]> = vec![
            [-4.0, -3.0, 5.0, -3.0],
            [5.0, -3.0, 5.0, 4.0],
            [5.0, 4.0, -4.0, 4.0],
            [-4.0, 4.0, -4.0, -3.0],
            [1.0, 1.0, 2.0, 1.0],
            [2.0, 1.0, 2.0, 2.5],
            [-2.5, -1.0, -1.5, -2.0],
            [3.0, -2.0, 3.5, -1.0],
        ];
        let walls: Vec<Segment> = walls.iter().map(|w| ([w[0], w[1]], [w[2], w[3]])).collect();
        let scan_at = move |pose: &Pose2| ray_cast(&walls, *pose, 360, 12.0, None);
        let mut grid = ProbabilityGrid::new(0.05);
        let params = InsertParams {
            rule: UpdateRule::CARTOGRAPHER,
            max_range_free: 0.0,
        };
        for k in 0..30 {
            let t = k as f64 / 30.0 * std::f64::consts::TAU;
            let pose = Pose2::new(0.5 + 1.5 * math::cos(t), 0.5 + 1.2 * math::sin(t), t);
            grid.insert_scan(&pose, &scan_at(&pose), &params).unwrap();
        }
        (grid, scan_at)
    }

    #[test]
    fn bicubic_interpolation_hits_cell_centres_and_its_gradient_matches_finite_differences() {
        let (grid, _) = room();
        let lookup = ProbabilityLookup::default();
        let r = grid.resolution();
        for (i, j) in [(100, -60), (20, 20), (-79, 10), (40, 30)] {
            let (x, y) = ((i as f64 + 0.5) * r, (j as f64 + 0.5) * r);
            let (m, _) = lookup.smooth(&grid, x, y);
            assert!((m - lookup.cell(&grid, i, j)).abs() < 1e-12);
        }
        let h = 1e-6;
        for (x, y) in [(4.93, 0.31), (1.51, 1.02), (-3.97, -2.2), (2.02, 1.7)] {
            let (_, g) = lookup.smooth(&grid, x, y);
            let fx =
                (lookup.smooth(&grid, x + h, y).0 - lookup.smooth(&grid, x - h, y).0) / (2.0 * h);
            let fy =
                (lookup.smooth(&grid, x, y + h).0 - lookup.smooth(&grid, x, y - h).0) / (2.0 * h);
            assert!((g[0] - fx).abs() < 1e-5 * (1.0 + fx.abs()), "{g:?} vs {fx}");
            assert!((g[1] - fy).abs() < 1e-5 * (1.0 + fy.abs()), "{g:?} vs {fy}");
        }
    }

    /// A 360-beam scan of a straight corridor, walls at y = ±1.025 (on cell
    /// centres) without end, seen up to `range_max` metres.
    fn corridor_scan(pose: &Pose2, range_max: f64) -> Scan {
        let n = 360;
        let angles: Vec<f64> = (0..n)
            .map(|k| -std::f64::consts::PI + std::f64::consts::TAU * k as f64 / n as f64)
            .collect();
        let ranges = angles
            .iter()
            .map(|a| {
                let s = math::sin(pose.theta + a);
                let wall = if s > 1e-9 { 1.025 } else { -1.025 };
                let t = if s.abs() > 1e-9 {
                    (wall - pose.y) / s
                } else {
                    f64::INFINITY
                };
                if t < range_max { t } else { range_max }
            })
            .collect();
        Scan {
            angles,
            ranges,
            range_min: 0.0,
            range_max,
        }
    }

    /// Along a corridor the map says nothing about x except where its
    /// mapped walls end, and a scan from a little further on has its far
    /// points just past them: the correlative search scores a step back
    /// higher. With the translation pulled to the prediction (as in
    /// Cartographer) the match stays with the robot; pulled towards the
    /// search's answer it stays 0.10 m behind.
    #[test]
    fn in_a_corridor_the_match_keeps_the_predicted_progress() {
        let mut grid = ProbabilityGrid::new(0.05);
        let params = InsertParams {
            rule: UpdateRule::CARTOGRAPHER,
            max_range_free: 0.0,
        };
        for k in 0..=30 {
            let pose = Pose2::new(-3.0 + 0.1 * k as f64, 0.0, 0.0);
            grid.insert_scan(&pose, &corridor_scan(&pose, 3.0), &params)
                .unwrap();
        }
        let lookup = ProbabilityLookup::default();
        let truth = Pose2::new(0.5, 0.0, 0.0);
        let points = corridor_scan(&truth, 3.0).points();
        let to_prediction = ScanToMapParams {
            pull_to_prediction: true,
            ..ScanToMapParams::default()
        };
        let (m, record) =
            match_scan_to_map(&grid, &lookup, &points, truth, &to_prediction).unwrap();
        let (searched, _) = record.correlative.unwrap();
        // The search did step back ...
        assert!(searched.x < truth.x - 0.04, "{searched:?}");
        // ... and the refinement came back to the prediction.
        assert!((m.pose.x - truth.x).abs() < 0.02, "{:?}", m.pose);
        assert!(
            m.pose.y.abs() < 0.01 && m.pose.theta.abs() < 0.005,
            "{:?}",
            m.pose
        );
        // Pulled to the search's answer, the match stays behind.
        let (behind, _) =
            match_scan_to_map(&grid, &lookup, &points, truth, &ScanToMapParams::default()).unwrap();
        assert!(behind.pose.x < truth.x - 0.05, "{:?}", behind.pose);
    }

    #[test]
    fn the_angular_step_moves_the_farthest_point_by_one_cell() {
        let step = angular_step(0.05, 10.0);
        // Chord length 2 d sin(step/2) = r.
        assert!((2.0 * 10.0 * math::sin(step / 2.0) - 0.05).abs() < 1e-12);
    }

    #[test]
    fn recovers_an_offset_of_30_cm_and_10_degrees() {
        let (grid, scan_at) = room();
        let lookup = ProbabilityLookup::default();
        let truth = Pose2::new(0.3, -0.4, 0.7);
        let points = scan_at(&truth).points();
        let predicted = Pose2::new(
            truth.x + 0.3,
            truth.y - 0.2,
            truth.theta + 10f64.to_radians(),
        );
        let params = ScanToMapParams {
            linear_search_window: 0.4,
            angular_search_window: 15f64.to_radians(),
            ..ScanToMapParams::default()
        };
        let (m, record) = match_scan_to_map(&grid, &lookup, &points, predicted, &params).unwrap();
        let err = math::hypot(m.pose.x - truth.x, m.pose.y - truth.y);
        let dtheta = wrap_angle(m.pose.theta - truth.theta).abs().to_degrees();
        assert!(
            err < 0.05 && dtheta < 1.0,
            "error {err:.4} m, {dtheta:.3} deg; {record:?}"
        );
        assert!(record.candidates > 1000);
        // Without the correlative search the refinement alone starts 36 cm
        // and 10 degrees off and does not get there.
        let local = ScanToMapParams {
            correlative: false,
            ..params
        };
        let (m2, _) = match_scan_to_map(&grid, &lookup, &points, predicted, &local).unwrap();
        let err2 = math::hypot(m2.pose.x - truth.x, m2.pose.y - truth.y);
        assert!(err2 > 0.05, "{err2}");
        // Pulled to the prediction with Cartographer's weights, the
        // refinement walks from the search's right answer back to the
        // prediction (measured 0.36 m off).
        let to_prediction = ScanToMapParams {
            pull_to_prediction: true,
            ..params
        };
        let (m3, _) =
            match_scan_to_map(&grid, &lookup, &points, predicted, &to_prediction).unwrap();
        let err3 = math::hypot(m3.pose.x - truth.x, m3.pose.y - truth.y);
        assert!(err3 > 0.3, "{err3}");
    }

    #[test]
    fn refinement_alone_converges_from_a_small_offset_and_lowers_the_cost() {
        let (grid, scan_at) = room();
        let lookup = ProbabilityLookup::default();
        let truth = Pose2::new(-0.5, 0.8, -1.2);
        let points = scan_at(&truth).points();
        let predicted = Pose2::new(truth.x + 0.04, truth.y - 0.03, truth.theta + 0.02);
        let params = ScanToMapParams {
            correlative: false,
            translation_weight: 0.0,
            rotation_weight: 0.0,
            max_points: 0,
            ..ScanToMapParams::default()
        };
        let (m, record) = match_scan_to_map(&grid, &lookup, &points, predicted, &params).unwrap();
        // The walls lie anywhere inside their cells and the interpolated map
        // peaks at cell centres: the answer is good to about half a cell.
        let err = math::hypot(m.pose.x - truth.x, m.pose.y - truth.y);
        assert!(err < 0.025, "{err}");
        assert!(wrap_angle(m.pose.theta - truth.theta).abs() < 0.2f64.to_radians());
        let costs: Vec<f64> = record.steps.iter().map(|s| s.cost).collect();
        assert!(costs.windows(2).all(|w| w[1] <= w[0]), "{costs:?}");
    }

    #[test]
    fn no_points_or_a_non_finite_prediction_give_none() {
        let grid = ProbabilityGrid::new(0.05);
        let lookup = ProbabilityLookup::default();
        let params = ScanToMapParams::default();
        assert!(match_scan_to_map(&grid, &lookup, &[], Pose2::IDENTITY, &params).is_none());
        assert!(
            match_scan_to_map(&grid, &lookup, &[[f64::NAN, 1.0]], Pose2::IDENTITY, &params)
                .is_none()
        );
        let bad = Pose2::new(f64::NAN, 0.0, 0.0);
        assert!(match_scan_to_map(&grid, &lookup, &[[1.0, 1.0]], bad, &params).is_none());
        // On a blank map it stays at the prediction (through the trait too).
        let matcher = GridMatcher {
            grid: &grid,
            lookup: &lookup,
            params,
        };
        let scan = Scan {
            angles: vec![0.0, 0.5],
            ranges: vec![1.0, 2.0],
            range_min: 0.0,
            range_max: 10.0,
        };
        let t = matcher
            .match_scan(&scan, Pose2::new(1.0, 2.0, 0.3))
            .unwrap();
        assert!((t.pose.x - 1.0).abs() < 1e-9 && (t.pose.theta - 0.3).abs() < 1e-9);
        let (m, _) = match_scan_to_map(
            &grid,
            &lookup,
            &[[1.0, 1.0], [2.0, 0.0]],
            Pose2::IDENTITY,
            &params,
        )
        .unwrap();
        assert!(m.pose.x.abs() < 1e-9 && m.pose.y.abs() < 1e-9 && m.pose.theta.abs() < 1e-9);
    }
}
