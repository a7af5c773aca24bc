//! Branch-and-bound scan matching (thesis `000` Sec. 5.2.1, Algorithm 12,
//! Eq. 5.10-5.14; Hess et al. 2016, "Real-time loop closure in 2D LIDAR SLAM";
//! Cartographer's `FastCorrelativeScanMatcher2D`): the pose in a search window
//! that puts the most scan points on likely-occupied cells of a finished
//! submap,
//!
//! ```text
//! ξ* = argmax_{ξ ∈ W} Σ_k M_nearest(T_ξ h_k)                      (5.10)
//! ```
//!
//! over a discretization of the window: translations one cell `r` apart and
//! headings `δθ = acos(1 − r² / (2 d_max²))` apart (Eq. 5.11-5.12), `d_max` the
//! farthest point (at least `3 r`, as Cartographer). A naive search scores
//! every one of those candidates. Branch and bound scores a candidate of height
//! `h` (a `2^h x 2^h` block of translations at one heading) with the
//! precomputed grid
//!
//! ```text
//! M^h_precomp(x, y) = max_{x' ∈ [x, x + r(2^h − 1)], y' ∈ [y, y + r(2^h − 1)]} M_nearest(x', y')   (5.13)
//! score(c) = Σ_k M^h_precomp(T_ξc h_k)                                                             (5.14)
//! ```
//!
//! which bounds the score of every translation in the block from above. It
//! walks the tree depth first, best-scored child first, and cuts every branch
//! whose bound is no better than the best leaf found so far; the answer is the
//! exhaustive search's answer (the bound never underestimates), found with a
//! small fraction of its work. The tree starts at the lowest height whose
//! boxes hold each heading's offsets in one box (at most the tallest grid):
//! Cartographer always starts at `branch_and_bound_depth − 1`, where a small
//! window's box has one child that is the same box again, so the answer is the
//! same and the repeated scoring is saved.
//!
//! Scores here are mean probabilities (the sum of Eq. 5.10 divided by the
//! number of points), as Cartographer's `min_score` reads them; cells never
//! observed, and cells outside the submap, read as
//! [`UNKNOWN_PROBABILITY`](super::scan_to_map::UNKNOWN_PROBABILITY).
//!
//! The precomputed grids hold each probability as a byte, as Cartographer's
//! `PrecomputationGrid2D` does: `v = round((p − 0.1) · 255 / 0.8)` for `p` in
//! Cartographer's range [0.1, 0.9] ([`cell_value`], [`cell_probability`]). A
//! candidate's score is then an integer sum over its points, exact in any order
//! and fast, and the maximum of bytes is the byte of the maximum; what a
//! student reads as a score is the mean probability the bytes stand for
//! (to 0.8/255 ≈ 0.003 per cell).
//!
//! The precomputed grids hold what Cartographer's `PrecomputationGrid2D` holds,
//! built by doubling rather than by its sliding-window maximum: a box of side
//! `2^h` is four boxes of side `2^(h−1)`, so each height is the maximum of two
//! cells of the height below along the rows, then two along the columns (the
//! same bytes; two comparisons a cell). Each grid covers the submap's known
//! cells widened by `2^h − 1` cells below and to the left, so that a box that
//! only overlaps the submap still has its value.

use super::scan_to_map::{UNKNOWN_PROBABILITY, angular_step};
use super::{Point2, PointTransform};
use crate::geometry::{Pose2, wrap_angle};
use crate::grid::ProbabilityGrid;
use crate::math;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// The tallest tree accepted: boxes of `2^10 = 1024` cells a side.
pub const MAX_HEIGHT: u32 = 10;

/// The lowest and highest probability a precomputed grid's byte stands for
/// (Cartographer's `kMinProbability` and `kMaxProbability`).
const P_MIN: f64 = 0.1;
const P_MAX: f64 = 0.9;

/// The byte a precomputed grid stores for probability `p` (clamped to
/// [0.1, 0.9]; Cartographer's `ComputeCellValue`): 0 for 0.1, 255 for 0.9.
pub fn cell_value(p: f64) -> u8 {
    let p = if p.is_nan() {
        P_MIN
    } else {
        p.clamp(P_MIN, P_MAX)
    };
    ((p - P_MIN) * 255.0 / (P_MAX - P_MIN)).round() as u8
}

/// The probability a precomputed grid's byte `v` stands for.
pub fn cell_probability(v: u8) -> f64 {
    P_MIN + f64::from(v) * (P_MAX - P_MIN) / 255.0
}

/// One precomputed grid: the maximum over the `2^h x 2^h` box of cells whose
/// lower-left cell is `(i, j)`, for every `(i, j)` whose box touches the
/// submap's known cells.
#[derive(Clone, Debug, PartialEq)]
struct MaxGrid {
    /// Lower-left cell held.
    i0: i64,
    j0: i64,
    width: usize,
    height: usize,
    /// [`cell_value`]s, row-major from the bottom.
    cells: Vec<u8>,
}

impl MaxGrid {
    #[inline]
    fn value(&self, i: i64, j: i64) -> u8 {
        let (di, dj) = (i - self.i0, j - self.j0);
        if di < 0 || dj < 0 || di >= self.width as i64 || dj >= self.height as i64 {
            return cell_value(UNKNOWN_PROBABILITY);
        }
        self.cells[dj as usize * self.width + di as usize]
    }
}

/// The precomputed max grids of heights `0..=max_height` of one finished
/// submap (thesis Eq. 5.13, Fig. 5.7). Height 0 is the submap itself.
#[derive(Clone, Debug, PartialEq)]
pub struct PrecomputedGrids {
    resolution: f64,
    /// The submap's known cells `(i_min, j_min, i_max, j_max)`, inclusive.
    bounds: (i64, i64, i64, i64),
    grids: Vec<MaxGrid>,
}

impl PrecomputedGrids {
    /// The grids of heights `0..=max_height` (clamped to [`MAX_HEIGHT`]) of
    /// `grid`'s known cells, each cell its occupancy probability
    /// ([`UNKNOWN_PROBABILITY`] where never observed). `None` for a grid with
    /// no known cell.
    pub fn new(grid: &ProbabilityGrid, max_height: u32) -> Option<Self> {
        let bounds = grid.known_bounds()?;
        let (i_min, j_min, i_max, j_max) = bounds;
        let (w, h) = ((i_max - i_min + 1) as usize, (j_max - j_min + 1) as usize);
        let unknown = cell_value(UNKNOWN_PROBABILITY);
        let mut base = vec![unknown; w * h];
        for (dj, row) in base.chunks_mut(w).enumerate() {
            for (di, cell) in row.iter_mut().enumerate() {
                if let Some(p) = grid.probability_at(i_min + di as i64, j_min + dj as i64) {
                    *cell = cell_value(p);
                }
            }
        }
        let max_height = max_height.min(MAX_HEIGHT);
        let mut grids = Vec::with_capacity(max_height as usize + 1);
        grids.push(MaxGrid {
            i0: i_min,
            j0: j_min,
            width: w,
            height: h,
            cells: base,
        });
        for height in 1..=max_height {
            if let Some(prev) = grids.last() {
                let next = Self::doubled(prev, height, unknown);
                grids.push(next);
            }
        }
        Some(Self {
            resolution: grid.resolution(),
            bounds,
            grids,
        })
    }

    /// The grid of height `height` from the one below it: a box of side
    /// `2^h` is four boxes of side `2^(h−1)`, so its maximum is the largest of
    /// theirs, taken along the rows and then along the columns (the same
    /// values as a sliding-window maximum over the submap, with two
    /// comparisons a cell instead of a window's worth).
    fn doubled(prev: &MaxGrid, height: u32, unknown: u8) -> MaxGrid {
        let half = 1usize << (height - 1);
        let (pw, ph) = (prev.width, prev.height);
        let (w, h) = (pw + half, ph + half);
        // Columns of the new grid p read the previous grid's columns p − half
        // and p (each box's left and right halves); rows likewise.
        let mut rows = vec![unknown; w * ph];
        for (q, row) in rows.chunks_mut(w).enumerate() {
            let src = &prev.cells[q * pw..(q + 1) * pw];
            for (p, cell) in row.iter_mut().enumerate() {
                let left = if p >= half { src[p - half] } else { unknown };
                let right = if p < pw { src[p] } else { unknown };
                *cell = left.max(right);
            }
        }
        let mut cells = vec![unknown; w * h];
        for (q, row) in cells.chunks_mut(w).enumerate() {
            let below = (q >= half).then(|| &rows[(q - half) * w..(q - half + 1) * w]);
            let above = (q < ph).then(|| &rows[q * w..(q + 1) * w]);
            match (below, above) {
                (Some(b), Some(a)) => {
                    for ((cell, &x), &y) in row.iter_mut().zip(b).zip(a) {
                        *cell = x.max(y);
                    }
                }
                (Some(only), None) | (None, Some(only)) => row.copy_from_slice(only),
                (None, None) => {}
            }
        }
        MaxGrid {
            i0: prev.i0 - half as i64,
            j0: prev.j0 - half as i64,
            width: w,
            height: h,
            cells,
        }
    }

    /// Metres per cell.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// The tallest height held (`branch_and_bound_depth − 1` in
    /// Cartographer's terms).
    pub fn max_height(&self) -> u32 {
        self.grids.len() as u32 - 1
    }

    /// The submap's known cells `(i_min, j_min, i_max, j_max)`, inclusive.
    pub fn bounds(&self) -> (i64, i64, i64, i64) {
        self.bounds
    }

    /// `M^h_precomp` at cell `(i, j)`: the largest probability in the
    /// `2^h x 2^h` box whose lower-left cell is `(i, j)` (Eq. 5.13). Heights
    /// above [`max_height`](Self::max_height) read the tallest grid.
    #[inline]
    pub fn value(&self, height: u32, i: i64, j: i64) -> f64 {
        let h = (height as usize).min(self.grids.len() - 1);
        cell_probability(self.grids[h].value(i, j))
    }

    /// The grid of height `h` over its held cells, for drawing Fig. 5.7:
    /// `(i0, j0, width, height, bytes)`, row-major from the bottom; each byte
    /// a [`cell_value`] ([`cell_probability`] reads it).
    pub fn grid(&self, height: u32) -> Option<(i64, i64, usize, usize, &[u8])> {
        let g = self.grids.get(height as usize)?;
        Some((g.i0, g.j0, g.width, g.height, &g.cells))
    }

    /// Bytes the grids hold.
    pub fn memory_bytes(&self) -> usize {
        self.grids.iter().map(|g| g.cells.len()).sum()
    }
}

/// Where branch and bound looks.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "kebab-case")]
pub enum SearchWindow {
    /// Around an initial pose (constraints near the current estimate):
    /// Cartographer's `linear_search_window` (half-width in x and y, metres;
    /// default 7 m) and `angular_search_window` (half-width, radians; default
    /// 30°).
    Around {
        /// The initial pose, `submap_from_scan`.
        initial: Pose2,
        /// Half-width in x and y, metres.
        linear: f64,
        /// Half-width in heading, radians.
        angular: f64,
    },
    /// The whole submap at every heading (a global search, Cartographer's
    /// `MatchFullSubmap`).
    WholeSubmap,
}

/// Cartographer's default linear search window for constraints, metres.
pub const DEFAULT_LINEAR_WINDOW: f64 = 7.0;
/// Cartographer's default angular search window for constraints, radians (30°).
pub const DEFAULT_ANGULAR_WINDOW: f64 = std::f64::consts::PI / 6.0;

/// The angular step of Eq. 5.12 for `points` (sensor frame) on a grid of
/// `resolution`: `δθ = acos(1 − r² / (2 d_max²))`, `d_max` the farthest point
/// (Eq. 5.11), at least `3 r` as Cartographer takes it.
pub fn search_angular_step(resolution: f64, points: &[Point2]) -> f64 {
    let d_max = points
        .iter()
        .map(|p| math::hypot(p[0], p[1]))
        .filter(|d| d.is_finite())
        .fold(3.0 * resolution, f64::max);
    angular_step(resolution, d_max)
}

/// A candidate of the search tree: a `2^height x 2^height` block of cell
/// offsets `[di, di + 2^h) x [dj, dj + 2^h)` at heading index `angle`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SearchNode {
    /// The height (0: a leaf, one pose).
    pub height: u32,
    /// The heading index (0 is the window's first heading).
    pub angle: usize,
    /// Cell offset in x of the block's lower-left candidate.
    pub di: i64,
    /// Cell offset in y.
    pub dj: i64,
    /// Its score: the bound of Eq. 5.14 (exact at a leaf), a mean probability.
    pub score: f64,
    /// Whether it was branched (or, a leaf, taken as the new best); false:
    /// pruned, its bound no better than the best so far.
    pub expanded: bool,
}

/// What a search did, for a lesson to draw.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SearchRecord {
    /// Candidates scored at each height (index = height; index 0: leaves).
    pub evaluated_per_height: Vec<usize>,
    /// Candidates at each height cut without being branched (their bound no
    /// better than the best leaf so far), with the whole subtrees under them.
    pub pruned_per_height: Vec<usize>,
    /// The best score as it improved: `(candidates evaluated so far, score)`.
    pub best_history: Vec<(usize, f64)>,
    /// The highest score of any leaf scored, above `min_score` or not
    /// (None: the bounds pruned every branch before a leaf).
    pub best_leaf_score: Option<f64>,
    /// Candidates an exhaustive search over the same discretization scores.
    pub exhaustive_candidates: usize,
    /// Headings searched.
    pub angles: usize,
    /// The angular step, radians (Eq. 5.12).
    pub angular_step: f64,
    /// The first window heading, radians.
    pub first_angle: f64,
    /// The translation the offsets are relative to (the window's centre).
    pub center: (f64, f64),
    /// The tree's first nodes in the order they were scored (at most
    /// [`BranchAndBoundParams::recorded_nodes`]).
    pub nodes: Vec<SearchNode>,
}

impl SearchRecord {
    /// Candidates scored at every height.
    pub fn evaluated(&self) -> usize {
        self.evaluated_per_height.iter().sum()
    }
}

/// Branch-and-bound parameters (Cartographer's names).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BranchAndBoundParams {
    /// A match must score above this mean probability (`min_score`; 0.55 for
    /// constraints, `global_localization_min_score` 0.6 for global searches).
    pub min_score: f64,
    /// Tree nodes kept in the record for drawing (0: none).
    pub recorded_nodes: usize,
}

impl Default for BranchAndBoundParams {
    fn default() -> Self {
        Self {
            min_score: 0.55,
            recorded_nodes: 0,
        }
    }
}

/// The search's answer.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BbsMatch {
    /// `submap_from_scan`.
    pub pose: Pose2,
    /// Its score: the mean probability of the points' cells (Eq. 5.10 / K).
    pub score: f64,
}

/// Why a search found no match.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum NoMatch {
    /// The scan has no finite point.
    #[error("the scan has no usable point to match")]
    NoPoints,
    /// The initial pose or a window is not a finite number.
    #[error("the search window is not finite")]
    BadWindow,
    /// No candidate scored above `min_score`.
    #[error(
        "no pose scored above the minimum score {min_score:.3} (none can score more than {best_bound:.3}): no loop closure"
    )]
    BelowMinScore {
        /// The threshold.
        min_score: f64,
        /// No candidate scores more than this: branch and bound's best bound
        /// at the top of the tree, the exhaustive search's best score. NaN
        /// when the window holds no candidate.
        best_bound: f64,
    },
}

/// The discretized search: each heading's points as cells, and the offsets
/// allowed at each heading.
struct Discretized {
    /// Per heading: the points' cells at zero offset.
    scans: Vec<Vec<(i64, i64)>>,
    /// Per heading: the smallest and largest cell `(i_min, i_max, j_min,
    /// j_max)` of its points, to score a candidate whose points all fall on a
    /// grid without checking each.
    extents: Vec<(i64, i64, i64, i64)>,
    /// Per heading: `(di_min, di_max, dj_min, dj_max)` inclusive, or `None`
    /// when no offset keeps any point on the submap.
    bounds: Vec<Option<(i64, i64, i64, i64)>>,
    first_angle: f64,
    step: f64,
    center: (f64, f64),
}

impl Discretized {
    fn new(
        grids: &PrecomputedGrids,
        points: &[Point2],
        window: &SearchWindow,
    ) -> Result<Self, NoMatch> {
        let points: Vec<Point2> = points
            .iter()
            .copied()
            .filter(|p| p[0].is_finite() && p[1].is_finite())
            .collect();
        if points.is_empty() {
            return Err(NoMatch::NoPoints);
        }
        let r = grids.resolution;
        let (bi0, bj0, bi1, bj1) = grids.bounds;
        let step = search_angular_step(r, &points);
        let (initial, linear, angular) = match *window {
            SearchWindow::Around {
                initial,
                linear,
                angular,
            } => {
                if !initial.is_finite() || !linear.is_finite() || !angular.is_finite() {
                    return Err(NoMatch::BadWindow);
                }
                (
                    initial,
                    linear.max(0.0),
                    angular.clamp(0.0, std::f64::consts::PI),
                )
            }
            SearchWindow::WholeSubmap => {
                // The submap's centre, a window that covers it all (shrunk to
                // the submap below) and every heading.
                let cx = (bi0 + bi1 + 1) as f64 * 0.5 * r;
                let cy = (bj0 + bj1 + 1) as f64 * 0.5 * r;
                let span = ((bi1 - bi0 + 1).max(bj1 - bj0 + 1)) as f64 * r;
                (Pose2::new(cx, cy, 0.0), span, std::f64::consts::PI)
            }
        };
        // A window bigger than any submap can use is cut to the submap below;
        // cap the cell count first so that the arithmetic stays small.
        let n_lin = (linear / r).ceil().min(1.0e6) as i64;
        let mut n_ang = (angular / step).ceil() as i64;
        // A full turn: do not search the same heading twice.
        if (2 * n_ang + 1) as f64 * step > std::f64::consts::TAU {
            n_ang = ((std::f64::consts::TAU / step).floor() as i64 - 1) / 2;
        }
        let mut scans = Vec::with_capacity((2 * n_ang + 1) as usize);
        let mut bounds = Vec::with_capacity(scans.capacity());
        let mut extents = Vec::with_capacity(scans.capacity());
        for a in -n_ang..=n_ang {
            let pose = Pose2::new(initial.x, initial.y, initial.theta + a as f64 * step);
            // The heading's sine and cosine once for all points (the same
            // bits as `transform_point`).
            let transform = PointTransform::new(&pose);
            let cells: Vec<(i64, i64)> = points
                .iter()
                .map(|p| {
                    let q = transform.apply(*p);
                    (
                        crate::grid::floor_to_i64(q[0] / r),
                        crate::grid::floor_to_i64(q[1] / r),
                    )
                })
                .collect();
            // Offsets that keep at least one point on the submap
            // (Cartographer's `ShrinkToFit`), within the window.
            let (mut lo_i, mut hi_i, mut lo_j, mut hi_j) = (i64::MAX, i64::MIN, i64::MAX, i64::MIN);
            for &(ci, cj) in &cells {
                lo_i = lo_i.min(bi0 - ci);
                hi_i = hi_i.max(bi1 - ci);
                lo_j = lo_j.min(bj0 - cj);
                hi_j = hi_j.max(bj1 - cj);
            }
            let b = (
                lo_i.max(-n_lin),
                hi_i.min(n_lin),
                lo_j.max(-n_lin),
                hi_j.min(n_lin),
            );
            bounds.push((b.0 <= b.1 && b.2 <= b.3).then_some(b));
            extents.push(
                cells
                    .iter()
                    .fold((i64::MAX, i64::MIN, i64::MAX, i64::MIN), |e, &(ci, cj)| {
                        (e.0.min(ci), e.1.max(ci), e.2.min(cj), e.3.max(cj))
                    }),
            );
            scans.push(cells);
        }
        Ok(Self {
            scans,
            extents,
            bounds,
            first_angle: initial.theta - n_ang as f64 * step,
            step,
            center: (initial.x, initial.y),
        })
    }

    /// The lowest height (at most `max_height`) whose `2^h x 2^h` boxes
    /// hold every heading's offsets in one box.
    fn top_height(&self, max_height: u32) -> u32 {
        let span = self
            .bounds
            .iter()
            .flatten()
            .map(|b| (b.1 - b.0 + 1).max(b.3 - b.2 + 1))
            .max()
            .unwrap_or(1);
        (0..=max_height)
            .find(|&h| (1i64 << h) >= span)
            .unwrap_or(max_height)
    }

    fn exhaustive_count(&self) -> usize {
        self.bounds
            .iter()
            .flatten()
            .map(|b| ((b.1 - b.0 + 1) * (b.3 - b.2 + 1)) as usize)
            .sum()
    }

    /// Score of a candidate at `height`: the mean of `M^h` over the points,
    /// as the probability the grid's bytes stand for. The bytes are summed as
    /// integers (exact, so every order gives the same score); when every point
    /// falls on the grid, without checking each.
    #[inline]
    fn score(&self, grids: &PrecomputedGrids, height: u32, angle: usize, di: i64, dj: i64) -> f64 {
        let grid = &grids.grids[height as usize];
        let cells = &self.scans[angle];
        let (si, sj) = (di - grid.i0, dj - grid.j0);
        let e = self.extents[angle];
        let (w, h) = (grid.width as i64, grid.height as i64);
        let values = grid.cells.as_slice();
        let mut sum = 0u64;
        if e.0 + si >= 0 && e.1 + si < w && e.2 + sj >= 0 && e.3 + sj < h {
            for &(ci, cj) in cells {
                sum += u64::from(values[((cj + sj) * w + ci + si) as usize]);
            }
        } else {
            // Points off the grid read as never observed: probability 0.1,
            // byte 0, nothing to add. (A negative index turns into a huge
            // unsigned one, so one comparison per axis checks both ends.)
            let (uw, uh) = (w as u64, h as u64);
            for &(ci, cj) in cells {
                let (x, y) = ((ci + si) as u64, (cj + sj) as u64);
                if x < uw && y < uh {
                    sum += u64::from(values[(y * uw + x) as usize]);
                }
            }
        }
        P_MIN + (P_MAX - P_MIN) * sum as f64 / (255.0 * cells.len() as f64)
    }

    fn pose(&self, r: f64, angle: usize, di: i64, dj: i64) -> Pose2 {
        Pose2::new(
            self.center.0 + di as f64 * r,
            self.center.1 + dj as f64 * r,
            wrap_angle(self.first_angle + angle as f64 * self.step),
        )
    }

    fn record(&self, height_count: usize) -> SearchRecord {
        SearchRecord {
            evaluated_per_height: vec![0; height_count],
            pruned_per_height: vec![0; height_count],
            best_history: Vec::new(),
            best_leaf_score: None,
            exhaustive_candidates: self.exhaustive_count(),
            angles: self.scans.len(),
            angular_step: self.step,
            first_angle: self.first_angle,
            center: self.center,
            nodes: Vec::new(),
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Candidate {
    angle: usize,
    di: i64,
    dj: i64,
    score: f64,
}

/// The depth-first search of Algorithm 12 (Cartographer's `BranchAndBound`).
struct Search<'a> {
    grids: &'a PrecomputedGrids,
    disc: &'a Discretized,
    record: SearchRecord,
    recorded_nodes: usize,
    best: Option<Candidate>,
    best_score: f64,
}

impl Search<'_> {
    fn note(&mut self, height: u32, c: &Candidate, expanded: bool) {
        if self.record.nodes.len() < self.recorded_nodes {
            self.record.nodes.push(SearchNode {
                height,
                angle: c.angle,
                di: c.di,
                dj: c.dj,
                score: c.score,
                expanded,
            });
        }
    }

    /// Scores `candidates` at `height`, best first.
    fn score_all(&mut self, height: u32, candidates: &mut [Candidate]) {
        for c in candidates.iter_mut() {
            c.score = self.disc.score(self.grids, height, c.angle, c.di, c.dj);
        }
        self.record.evaluated_per_height[height as usize] += candidates.len();
        if height == 0 {
            let best = candidates.iter().map(|c| c.score).fold(f64::NAN, f64::max);
            if best.is_finite() {
                let seen = self.record.best_leaf_score.unwrap_or(best);
                self.record.best_leaf_score = Some(seen.max(best));
            }
        }
        // Best first; ties in a fixed order so that a run is repeatable.
        candidates.sort_by(|a, b| {
            b.score
                .total_cmp(&a.score)
                .then(a.angle.cmp(&b.angle))
                .then(a.di.cmp(&b.di))
                .then(a.dj.cmp(&b.dj))
        });
    }

    /// Branches `candidates` (scored at `height`, best first).
    fn branch(&mut self, height: u32, candidates: &[Candidate]) {
        for (k, c) in candidates.iter().enumerate() {
            if c.score <= self.best_score {
                // Sorted: every candidate from here on is cut.
                self.record.pruned_per_height[height as usize] += candidates.len() - k;
                for rest in &candidates[k..] {
                    self.note(height, rest, false);
                }
                return;
            }
            if height == 0 {
                self.note(0, c, true);
                self.best = Some(*c);
                self.best_score = c.score;
                let evaluated = self.record.evaluated();
                self.record.best_history.push((evaluated, c.score));
                continue;
            }
            self.note(height, c, true);
            let half = 1i64 << (height - 1);
            let Some(b) = self.disc.bounds[c.angle] else {
                continue;
            };
            let mut children = Vec::with_capacity(4);
            for dx in [0, half] {
                if c.di + dx > b.1 {
                    break;
                }
                for dy in [0, half] {
                    if c.dj + dy > b.3 {
                        break;
                    }
                    children.push(Candidate {
                        angle: c.angle,
                        di: c.di + dx,
                        dj: c.dj + dy,
                        score: 0.0,
                    });
                }
            }
            self.score_all(height - 1, &mut children);
            self.branch(height - 1, &children);
        }
    }
}

/// Branch-and-bound search (Algorithm 12) of `points` (sensor frame) against
/// a submap's precomputed grids within `window`. Returns the best pose and
/// its score, or why there is none, and what the search did.
pub fn branch_and_bound(
    grids: &PrecomputedGrids,
    points: &[Point2],
    window: &SearchWindow,
    params: &BranchAndBoundParams,
) -> (Result<BbsMatch, NoMatch>, SearchRecord) {
    let height_count = grids.grids.len();
    let disc = match Discretized::new(grids, points, window) {
        Ok(d) => d,
        Err(e) => {
            let record = SearchRecord {
                evaluated_per_height: vec![0; height_count],
                pruned_per_height: vec![0; height_count],
                ..SearchRecord::default()
            };
            return (Err(e), record);
        }
    };
    // The tree starts at the lowest height whose boxes cover every
    // heading's offsets: a taller box has a single child that is its own
    // box again, and scoring it only repeats work (a small window, such as
    // a loop-closure search around a good estimate, needs few heights).
    let top = disc.top_height(grids.max_height());
    let stride = 1i64 << top;
    // The lowest-resolution candidates: every heading, offsets from each
    // heading's lower bound in steps of 2^top.
    let mut initial = Vec::new();
    for (angle, b) in disc.bounds.iter().enumerate() {
        let Some(b) = *b else { continue };
        let mut di = b.0;
        while di <= b.1 {
            let mut dj = b.2;
            while dj <= b.3 {
                initial.push(Candidate {
                    angle,
                    di,
                    dj,
                    score: 0.0,
                });
                dj += stride;
            }
            di += stride;
        }
    }
    let min_score = if params.min_score.is_finite() {
        params.min_score
    } else {
        0.0
    };
    let mut search = Search {
        grids,
        disc: &disc,
        record: disc.record(height_count),
        recorded_nodes: params.recorded_nodes,
        best: None,
        best_score: min_score,
    };
    search.score_all(top, &mut initial);
    search.branch(top, &initial);
    let best = search.best;
    let record = search.record;
    let result = match best {
        Some(c) => Ok(BbsMatch {
            pose: disc.pose(grids.resolution, c.angle, c.di, c.dj),
            score: c.score,
        }),
        None => Err(NoMatch::BelowMinScore {
            min_score,
            best_bound: initial.first().map_or(f64::NAN, |c| c.score),
        }),
    };
    (result, record)
}

/// The naive search over the same discretization: every heading, every cell
/// offset, scored on the height-0 grid. Returns the best (the first found of
/// equal scores, in heading, x, y order) if it scores above `min_score`, and
/// the number of candidates scored. The yardstick branch and bound is tested
/// against.
pub fn exhaustive_search(
    grids: &PrecomputedGrids,
    points: &[Point2],
    window: &SearchWindow,
    min_score: f64,
) -> (Result<BbsMatch, NoMatch>, usize) {
    let disc = match Discretized::new(grids, points, window) {
        Ok(d) => d,
        Err(e) => return (Err(e), 0),
    };
    let mut best: Option<Candidate> = None;
    let mut count = 0;
    for (angle, b) in disc.bounds.iter().enumerate() {
        let Some(b) = *b else { continue };
        for di in b.0..=b.1 {
            for dj in b.2..=b.3 {
                count += 1;
                let score = disc.score(grids, 0, angle, di, dj);
                if best.is_none_or(|c| score > c.score) {
                    best = Some(Candidate {
                        angle,
                        di,
                        dj,
                        score,
                    });
                }
            }
        }
    }
    let result = match best {
        Some(c) if c.score > min_score => Ok(BbsMatch {
            pose: disc.pose(grids.resolution, c.angle, c.di, c.dj),
            score: c.score,
        }),
        other => Err(NoMatch::BelowMinScore {
            min_score,
            best_bound: other.map_or(f64::NAN, |c| c.score),
        }),
    };
    (result, count)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{InsertParams, UpdateRule};
    use crate::laser::test_room::{Segment, ray_cast};
    use crate::scan::Scan;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A submap of random walls seen from a few poses, and a scan function.
    fn random_world(seed: u64) -> (ProbabilityGrid, impl Fn(&Pose2) -> Scan) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut walls: Vec<[f64; 4]> = vec![
            [-5.0, -4.0, 6.0, -4.0],
            [6.0, -4.0, 6.0, 5.0],
            [6.0, 5.0, -5.0, 5.0],
            [-5.0, 5.0, -5.0, -4.0],
        ];
        for _ in 0..8 {
            let x = rng.random_range(-4.0..5.0);
            let y = rng.random_range(-3.0..4.0);
            let a: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            let l = rng.random_range(0.5..2.0);
            walls.push([x, y, x + l * math::cos(a), y + l * math::sin(a)]);
        }
        let walls: Vec<Segment> = walls.iter().map(|w| ([w[0], w[1]], [w[2], w[3]])).collect();
        let scan_at = move |pose: &Pose2| ray_cast(&walls, *pose, 180, 12.0, None);
        let mut grid = ProbabilityGrid::new(0.1);
        let params = InsertParams {
            rule: UpdateRule::CARTOGRAPHER,
            max_range_free: 0.0,
        };
        for k in 0..6 {
            let pose = Pose2::new(
                rng.random_range(-2.0..3.0),
                rng.random_range(-2.0..2.0),
                k as f64,
            );
            for _ in 0..3 {
                grid.insert_scan(&pose, &scan_at(&pose), &params).unwrap();
            }
        }
        (grid, scan_at)
    }

    #[test]
    fn the_height_h_grid_is_the_maximum_over_its_box() {
        let (grid, _) = random_world(3);
        let grids = PrecomputedGrids::new(&grid, 4).unwrap();
        let (i0, j0, i1, j1) = grids.bounds();
        let cell =
            |i: i64, j: i64| cell_value(grid.probability_at(i, j).unwrap_or(UNKNOWN_PROBABILITY));
        let mut checked = 0;
        for h in 0..=4u32 {
            let side = 1i64 << h;
            // Every box start that touches the submap, and a margin beyond.
            for j in (j0 - side - 1..=j1 + 2).step_by(3) {
                for i in (i0 - side - 1..=i1 + 2).step_by(2) {
                    let mut m = 0u8;
                    for dj in 0..side {
                        for di in 0..side {
                            m = m.max(cell(i + di, j + dj));
                        }
                    }
                    assert_eq!(
                        grids.value(h, i, j),
                        cell_probability(m),
                        "h {h} at ({i}, {j})"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 10_000, "{checked}");
        // Height 0 is the submap itself.
        assert_eq!(
            grids.value(0, i0 + 5, j0 + 7),
            cell_probability(cell(i0 + 5, j0 + 7))
        );
    }

    /// Cartographer's byte encoding: 0.1 is 0, 0.9 is 255, 0.5 is 128
    /// (127.5 rounded away from zero), outside values and NaN clamp; a byte
    /// reads back within half a step (0.8 / 510) of the probability.
    #[test]
    fn probabilities_are_stored_as_cartographer_bytes() {
        assert_eq!(cell_value(0.1), 0);
        // Scoring skips points off the grid: they must read as byte 0.
        assert_eq!(cell_value(UNKNOWN_PROBABILITY), 0);
        assert_eq!(cell_value(0.9), 255);
        assert_eq!(cell_value(0.5), 128);
        assert_eq!(cell_value(0.0), 0);
        assert_eq!(cell_value(1.0), 255);
        assert_eq!(cell_value(f64::NAN), 0);
        for k in 0..=800 {
            let p = 0.1 + f64::from(k) * 0.001;
            assert!(
                (cell_probability(cell_value(p)) - p).abs() <= 0.8 / 510.0 + 1e-12,
                "{p}"
            );
        }
        assert_eq!(cell_probability(255), 0.9);
    }

    #[test]
    fn the_angular_step_is_eq_5_12_by_hand() {
        // r = 0.05 m, d_max = 10 m: acos(1 − 0.0025 / 200) = acos(0.9999875)
        // = 0.00500000520833 rad (sqrt(2 · 1.25e-5) to first order).
        let step = search_angular_step(0.05, &[[6.0, 8.0], [1.0, 0.0]]);
        assert!((step - 0.005_000_005_208_3).abs() < 1e-12, "{step}");
        // Points nearer than 3 r count as 3 r: r = 0.1, d = 0.3:
        // acos(1 − 0.01 / 0.18) = acos(0.94444) = 0.33489 rad.
        let near = search_angular_step(0.1, &[[0.05, 0.0]]);
        assert!((near - 0.334_896_6).abs() < 1e-6, "{near}");
    }

    #[test]
    fn branch_and_bound_equals_exhaustive_search_with_far_fewer_candidates() {
        let mut ratios = Vec::new();
        for seed in 1..=6u64 {
            let (grid, scan_at) = random_world(seed);
            let grids = PrecomputedGrids::new(&grid, 5).unwrap();
            let mut rng = ChaCha8Rng::seed_from_u64(100 + seed);
            let truth = Pose2::new(
                rng.random_range(-1.5..2.5),
                rng.random_range(-1.5..1.5),
                rng.random_range(-3.0..3.0),
            );
            let points = scan_at(&truth).points();
            let initial = Pose2::new(truth.x + 0.7, truth.y - 0.5, truth.theta + 0.1);
            let window = SearchWindow::Around {
                initial,
                linear: 3.0,
                angular: 0.3,
            };
            let params = BranchAndBoundParams {
                min_score: 0.5,
                recorded_nodes: 100,
            };
            let (bbs, record) = branch_and_bound(&grids, &points, &window, &params);
            let (naive, count) = exhaustive_search(&grids, &points, &window, 0.5);
            let bbs = bbs.unwrap();
            let naive = naive.unwrap();
            assert_eq!(bbs.score, naive.score, "seed {seed}");
            assert_eq!(bbs.pose, naive.pose, "seed {seed}");
            assert_eq!(record.exhaustive_candidates, count);
            // It is found where the scan was taken (to a cell and a step).
            assert!(math::hypot(bbs.pose.x - truth.x, bbs.pose.y - truth.y) < 0.15);
            assert!(wrap_angle(bbs.pose.theta - truth.theta).abs() < 0.03);
            // The best score only grew, and the record adds up.
            assert!(record.best_history.windows(2).all(|w| w[1].1 > w[0].1));
            assert_eq!(record.best_history.last().unwrap().1, bbs.score);
            assert_eq!(record.best_leaf_score, Some(bbs.score));
            assert_eq!(record.nodes.len(), 100);
            // Asked for more than the best scores, the search finds no
            // match but says the best leaf it scored, which is no better
            // than the match (and none of it is above the minimum).
            let above = BranchAndBoundParams {
                min_score: bbs.score,
                recorded_nodes: 0,
            };
            let (none, below) = branch_and_bound(&grids, &points, &window, &above);
            assert!(none.is_err(), "seed {seed}");
            assert!(below.best_history.is_empty());
            let leaf = below.best_leaf_score.unwrap_or(f64::NAN);
            assert!(leaf <= bbs.score && leaf > 0.5, "seed {seed}: {leaf}");
            let ratio = count as f64 / record.evaluated() as f64;
            ratios.push(ratio);
            assert!(
                ratio > 50.0,
                "seed {seed}: {count} / {} = {ratio}",
                record.evaluated()
            );
        }
        eprintln!("exhaustive / branch-and-bound candidates: {ratios:?}");
    }

    /// A window of ±0.3 m at 0.1 m cells holds 7 offsets a side: the tree
    /// starts at height 3 (boxes of 8), the heights above score nothing, and
    /// the answer is still the exhaustive search's.
    #[test]
    fn a_small_window_starts_low_in_the_tree_with_the_exhaustive_answer() {
        for seed in 1..=6u64 {
            let (grid, scan_at) = random_world(seed);
            let grids = PrecomputedGrids::new(&grid, 6).unwrap();
            let truth = Pose2::new(0.4, -0.3, 0.2 * seed as f64);
            let points = scan_at(&truth).points();
            let window = SearchWindow::Around {
                initial: Pose2::new(truth.x + 0.15, truth.y - 0.12, truth.theta + 0.05),
                linear: 0.3,
                angular: 0.1,
            };
            let params = BranchAndBoundParams {
                min_score: 0.5,
                recorded_nodes: 0,
            };
            let (bbs, record) = branch_and_bound(&grids, &points, &window, &params);
            let (naive, count) = exhaustive_search(&grids, &points, &window, 0.5);
            let (bbs, naive) = (bbs.unwrap(), naive.unwrap());
            assert_eq!(
                (bbs.score, bbs.pose),
                (naive.score, naive.pose),
                "seed {seed}"
            );
            assert_eq!(record.exhaustive_candidates, count);
            assert_eq!(record.evaluated_per_height.len(), 7);
            assert!(record.evaluated_per_height[3] > 0, "{record:?}");
            assert!(
                record.evaluated_per_height[4..].iter().all(|&n| n == 0),
                "seed {seed}: {:?}",
                record.evaluated_per_height
            );
            // One box per heading at the top.
            assert_eq!(record.evaluated_per_height[3], record.angles);
        }
    }

    #[test]
    fn a_global_search_finds_the_scan_anywhere_in_the_submap() {
        let (grid, scan_at) = random_world(9);
        let grids = PrecomputedGrids::new(&grid, 6).unwrap();
        let truth = Pose2::new(1.2, -0.8, 2.5);
        let points = scan_at(&truth).points();
        let (m, record) = branch_and_bound(
            &grids,
            &points,
            &SearchWindow::WholeSubmap,
            &BranchAndBoundParams::default(),
        );
        let m = m.unwrap();
        assert!(
            math::hypot(m.pose.x - truth.x, m.pose.y - truth.y) < 0.15,
            "{m:?}"
        );
        assert!(wrap_angle(m.pose.theta - truth.theta).abs() < 0.03);
        let ratio = record.exhaustive_candidates as f64 / record.evaluated() as f64;
        assert!(ratio > 100.0, "{ratio}");
    }

    #[test]
    fn a_window_larger_than_the_map_and_an_unreachable_min_score_behave() {
        let (grid, scan_at) = random_world(4);
        let grids = PrecomputedGrids::new(&grid, 3).unwrap();
        let truth = Pose2::new(0.5, 0.5, 0.3);
        let points = scan_at(&truth).points();
        // A 1 km window is cut to the offsets that keep a point on the map.
        let huge = SearchWindow::Around {
            initial: truth,
            linear: 1000.0,
            angular: 0.05,
        };
        let (m, record) =
            branch_and_bound(&grids, &points, &huge, &BranchAndBoundParams::default());
        let (i0, j0, i1, j1) = grids.bounds();
        let cells = ((i1 - i0 + 1) * (j1 - j0 + 1)) as usize;
        // (The scan spans up to 24 m, the map about 11 m: at most three
        // map widths of offsets per axis keep a point on it.)
        assert!(record.exhaustive_candidates <= 9 * cells * record.angles);
        assert!(record.exhaustive_candidates < 20_001 * 20_001);
        let m = m.unwrap();
        assert!(math::hypot(m.pose.x - truth.x, m.pose.y - truth.y) < 0.15);
        // A minimum score of 1 (certain occupancy under every point) is
        // never reached: no match, said as such, and nothing branched past
        // the top.
        let strict = BranchAndBoundParams {
            min_score: 1.0,
            recorded_nodes: 0,
        };
        let (none, record) = branch_and_bound(&grids, &points, &huge, &strict);
        match none {
            Err(NoMatch::BelowMinScore {
                min_score,
                best_bound,
            }) => {
                assert_eq!(min_score, 1.0);
                assert!(best_bound <= 0.9 + 1e-6, "{best_bound}");
            }
            other => panic!("{other:?}"),
        }
        assert!(record.best_history.is_empty());
        assert_eq!(record.best_leaf_score, None);
        let top = grids.max_height() as usize;
        assert_eq!(record.evaluated(), record.evaluated_per_height[top]);
        assert_eq!(
            record.pruned_per_height[top],
            record.evaluated_per_height[top]
        );
        let message = branch_and_bound(&grids, &points, &huge, &strict)
            .0
            .unwrap_err()
            .to_string();
        assert!(message.contains("no loop closure"), "{message}");
        // No points, a NaN window.
        assert_eq!(
            branch_and_bound(&grids, &[], &huge, &strict).0,
            Err(NoMatch::NoPoints)
        );
        let nan = SearchWindow::Around {
            initial: Pose2::new(f64::NAN, 0.0, 0.0),
            linear: 1.0,
            angular: 0.1,
        };
        assert_eq!(
            branch_and_bound(&grids, &points, &nan, &strict).0,
            Err(NoMatch::BadWindow)
        );
        // An empty grid has no precomputed grids.
        assert!(PrecomputedGrids::new(&ProbabilityGrid::new(0.05), 3).is_none());
    }
}
