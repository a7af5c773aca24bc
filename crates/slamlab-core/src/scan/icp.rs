//! Iterative closest point (ICP) registration of two 2-D point sets: find the
//! pose `reference_from_scan` that lays the scan's points on the reference's
//! (slides 001, "Iterative closest point algorithm"; Besl and McKay 1992,
//! thesis 000 reference [3]; Lu and Milios 1994 for laser scans, reference [14]).
//!
//! Each iteration does what the slides list:
//! 1. transform the scan's points into the reference frame with the current pose;
//! 2. pair each with its nearest reference point, found with a k-d tree
//!    ([`super::kdtree::PointTree`]); when the nearest point is provably among a
//!    few candidates (the point's previous partner and that partner's
//!    neighbours) the tree is not asked (`Neighbourhoods`);
//! 3. reject doubtful pairs: a **distance gate** (pairs farther apart than
//!    [`IcpConfig::max_correspondence_distance`]) and **trimming**, keeping only
//!    the best [`IcpConfig::trim_fraction`] of the pairs that pass the gate, as in
//!    Chetverikov et al.'s trimmed ICP (thesis 000 reference [8]: "The trimmed
//!    iterative closest point algorithm", ICPR 2002, least trimmed squares);
//! 4. solve for the pose that minimises the error of the kept pairs, in one of
//!    two ways ([`IcpVariant`]):
//!    - **point-to-point**: the mean squared distance between paired points,
//!      `(1/N) Σ |R sᵢ + t − mᵢ|²` (slides: `f(R, T)`), solved in closed form
//!      ([`closed_form_point_to_point`]; Arun, Huang and Blostein 1987 in 2-D);
//!    - **point-to-line**: the squared distance of each point to the line through
//!      its reference point along the reference's local surface, `(nᵢ·(R sᵢ + t −
//!      mᵢ))²`, with normals `nᵢ` estimated from each reference point's
//!      neighbours. We implement the *linearised* step of Low (2004, "Linear
//!      least-squares optimization for point-to-plane ICP surface registration",
//!      UNC TR04-004, Eq. 6-8, in 2-D): the rotation is linearised about the
//!      current pose and one 3×3 system of normal equations is solved per
//!      iteration. (Censi's PLICP, ICRA 2008, minimises the same point-to-line
//!      error exactly with a Lagrange multiplier and takes the line through the
//!      two nearest reference points; we estimate the line from more neighbours
//!      and take a Gauss-Newton step instead.)
//! 5. stop when a step moves the pose by less than both
//!    [`IcpConfig::translation_tolerance`] and [`IcpConfig::rotation_tolerance`],
//!    or after [`IcpConfig::max_iterations`].
//!
//! Point-to-point slides slowly along walls: a nearest neighbour on a wall
//! pulls a point back towards where it already is, so each iteration moves only
//! part of the way. Point-to-line lets points slide along the wall freely and
//! converges in a few iterations where the surfaces are smooth, which is why
//! the lidar lessons use it.
//!
//! [`IcpState`] runs one iteration per [`IcpState::step`] and returns its record
//! ([`IcpIteration`]: every pair with its verdict, the error, the pose after),
//! so a lesson can step through ICP and draw the pairs; [`align`] runs to the
//! end. Everything is deterministic; the buffers of the inner loop are reused
//! between iterations.

use super::kdtree::{Neighbour, PointTree, PointTreeError};
use super::{Point2, Scan, ScanMatch};
use crate::geometry::{Pose2, wrap_angle};
use crate::math;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Which error ICP minimises (module docs, step 4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum IcpVariant {
    /// Squared distance between paired points; closed-form step.
    PointToPoint,
    /// Squared distance from each point to its reference point's tangent line;
    /// linearised least-squares step (Low 2004).
    #[default]
    PointToLine,
}

/// ICP's settings. The defaults suit 2-D laser scans of rooms a few metres
/// across taken a few centimetres to decimetres apart.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct IcpConfig {
    /// Point-to-point or point-to-line.
    pub variant: IcpVariant,
    /// Most iterations before giving up (at least 1).
    pub max_iterations: usize,
    /// Distance gate, metres: pairs farther apart are rejected (positive;
    /// `f64::INFINITY` disables the gate).
    pub max_correspondence_distance: f64,
    /// Trimming: the share of the gated pairs kept, those with the smallest
    /// error (Chetverikov's overlap `ξ`, in (0, 1]; 1 keeps all).
    pub trim_fraction: f64,
    /// Convergence: a step that moves the pose less than this, metres...
    pub translation_tolerance: f64,
    /// ...and turns it less than this, radians, ends the run (both ≥ 0).
    pub rotation_tolerance: f64,
    /// Point-to-line: how many nearest reference points (the point itself
    /// included) define its tangent line (at least 2).
    pub normal_neighbours: usize,
    /// Point-to-line: neighbours farther than this from the reference point,
    /// metres, do not count towards its line (positive).
    pub normal_radius: f64,
    /// Fewest kept pairs to take a step (at least 2 for point-to-point, 3 for
    /// point-to-line: the number of unknowns it must pin down).
    pub min_correspondences: usize,
}

impl Default for IcpConfig {
    fn default() -> Self {
        Self {
            variant: IcpVariant::PointToLine,
            max_iterations: 50,
            max_correspondence_distance: 0.5,
            trim_fraction: 0.9,
            translation_tolerance: 1e-4,
            rotation_tolerance: 1e-4,
            normal_neighbours: 5,
            normal_radius: 0.5,
            min_correspondences: 3,
        }
    }
}

impl IcpConfig {
    /// Checks every setting; the error names the first bad one.
    pub fn validate(&self) -> Result<(), IcpError> {
        let bad = |what: &str| Err(IcpError::InvalidConfig(what.to_owned()));
        if self.max_iterations == 0 {
            return bad("max_iterations must be at least 1");
        }
        if !(self.max_correspondence_distance > 0.0) {
            return bad("max_correspondence_distance must be a positive number of metres");
        }
        if !(self.trim_fraction > 0.0 && self.trim_fraction <= 1.0) {
            return bad("trim_fraction must be in (0, 1]");
        }
        if !(self.translation_tolerance >= 0.0 && self.translation_tolerance.is_finite()) {
            return bad("translation_tolerance must be a finite number of metres, at least 0");
        }
        if !(self.rotation_tolerance >= 0.0 && self.rotation_tolerance.is_finite()) {
            return bad("rotation_tolerance must be a finite number of radians, at least 0");
        }
        let unknowns = match self.variant {
            IcpVariant::PointToPoint => 2,
            IcpVariant::PointToLine => 3,
        };
        if self.min_correspondences < unknowns {
            return Err(IcpError::InvalidConfig(format!(
                "min_correspondences must be at least {unknowns} for {:?}",
                self.variant
            )));
        }
        if self.variant == IcpVariant::PointToLine {
            if self.normal_neighbours < 2 {
                return bad("normal_neighbours must be at least 2");
            }
            if !(self.normal_radius > 0.0) {
                return bad("normal_radius must be a positive number of metres");
            }
        }
        Ok(())
    }
}

/// Why ICP could not start or take a step.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum IcpError {
    /// A setting is out of range.
    #[error("ICP settings: {0}")]
    InvalidConfig(String),
    /// The initial pose has a NaN or infinite component.
    #[error("the initial pose is not finite")]
    NonFiniteInitialPose,
    /// Too few finite points in the scan or the reference.
    #[error("the {which} has {count} usable points; ICP needs at least {needed}")]
    NotEnoughPoints {
        /// `"scan"` or `"reference"`.
        which: &'static str,
        /// Finite points found.
        count: usize,
        /// Points needed.
        needed: usize,
    },
    /// The k-d tree could not be built.
    #[error(transparent)]
    Tree(#[from] PointTreeError),
    /// After the gate and trimming, too few pairs are left to take a step.
    #[error("only {kept} correspondences survive the gate and trimming; {needed} are needed")]
    TooFewCorrespondences {
        /// Pairs kept.
        kept: usize,
        /// Pairs needed ([`IcpConfig::min_correspondences`]).
        needed: usize,
    },
    /// The kept pairs do not determine the pose (all points at one place,
    /// or every line parallel so a slide along them is free).
    #[error("the correspondences do not determine the pose: {0}")]
    Degenerate(&'static str),
}

/// What became of one scan point in an iteration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum PairStatus {
    /// Used in the step.
    Kept,
    /// Its nearest reference point is beyond the distance gate.
    Gated,
    /// Passed the gate but its error is among the worst `1 − trim_fraction`.
    Trimmed,
    /// Point-to-line: its reference point has no tangent line (no neighbours
    /// within [`IcpConfig::normal_radius`], or all of them at one place).
    NoNormal,
}

/// One scan point's pair in an iteration.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Correspondence {
    /// Index of the scan point in the slice given to [`IcpState::new`].
    pub scan_index: usize,
    /// Index of its nearest reference point in the reference slice.
    pub reference_index: usize,
    /// The scan point in the reference frame at the iteration's starting pose,
    /// metres (the end of the line a lesson draws).
    pub scan_point: Point2,
    /// Squared distance between the two points, m².
    pub distance_squared: f64,
    /// The pair's squared error in the variant's metric, m² (point-to-point:
    /// the squared distance; point-to-line: the squared distance to the line).
    pub error_squared: f64,
    /// Kept or why rejected.
    pub status: PairStatus,
}

/// The record of one ICP iteration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IcpIteration {
    /// 1 for the first iteration.
    pub iteration: usize,
    /// The pose the iteration started from (`reference_from_scan`).
    pub pose_before: Pose2,
    /// The pose after the iteration's step.
    pub pose: Pose2,
    /// One entry per usable scan point, in scan order.
    pub correspondences: Vec<Correspondence>,
    /// How many pairs were kept.
    pub kept: usize,
    /// Mean squared error of the kept pairs at `pose_before`, m² (the
    /// variant's metric).
    pub mean_squared_error: f64,
    /// Length of the step's translation, metres.
    pub step_translation: f64,
    /// Size of the step's rotation, radians.
    pub step_rotation: f64,
    /// Whether the step was below both tolerances.
    pub converged: bool,
}

/// One pair during an iteration, in the reusable buffer.
#[derive(Clone, Copy, Debug)]
struct Pair {
    scan: usize,
    reference: usize,
    transformed: Point2,
    distance_squared: f64,
    error_squared: f64,
    status: PairStatus,
}

/// ICP between a fixed reference and a scan, one iteration at a time.
#[derive(Debug)]
pub struct IcpState {
    config: IcpConfig,
    /// Finite reference points and their indices in the caller's slice.
    reference: Vec<Point2>,
    reference_index: Vec<usize>,
    /// Point-to-line: the unit normal of each reference point, if it has one.
    normals: Vec<Option<Point2>>,
    tree: PointTree,
    /// Finite scan points (scan frame) and their indices in the caller's slice.
    scan: Vec<Point2>,
    scan_index: Vec<usize>,
    pose: Pose2,
    iterations: usize,
    converged: bool,
    // Reused between iterations.
    pairs: Vec<Pair>,
    /// The kept pairs' indices in `pairs`, in scan order.
    order: Vec<usize>,
    /// Scratch for trimming's selection.
    errors: Vec<f64>,
    /// Per scan point, its partner in the last iteration (the certificate's
    /// guess, see [`Neighbourhoods`]).
    partner: Vec<Option<usize>>,
    neighbourhoods: Neighbourhoods,
    /// Nearest-neighbour answers so far: certified, and asked of the tree.
    certified: usize,
    tree_queries: usize,
    neighbours: Vec<Neighbour>,
}

/// How many guesses a nearest-neighbour search tries before it asks the tree.
const CERTIFICATE_WALK: usize = 3;

/// Each reference point's nearest fellow reference points, which let most
/// nearest-neighbour queries be answered without the tree, exactly.
///
/// The **certificate**: let `N(c)` be reference point `c`'s `k` nearest fellows
/// and `ρ(c)` the distance to the farthest of them, so every reference point
/// outside `N(c)` lies at least `ρ(c)` from `c`. For a query point `q` at `d_c`
/// from `c`, every such point lies at least `ρ(c) − d_c` from `q` (triangle
/// inequality). So if the nearest of `{c} ∪ N(c)` to `q` is closer than
/// `ρ(c) − d_c`, it is the nearest reference point of all. As a *guess* `c` we
/// take the scan point's partner in the previous iteration, or in the first
/// iteration the previous scan point's partner (consecutive beams hit
/// neighbouring places). Along a wall sampled every few centimetres, with `k = 4`
/// and points a centimetre off the wall, the certificate holds for nearly every
/// point; where it fails (corners, gaps, the first point) the tree is asked.
///
/// This is the idea of Nüchter, Lingemann and Hertzberg's cached k-d tree search
/// for ICP ("Cached k-d tree search for ICP algorithms", 3DIM 2007) made exact:
/// the pairs are the ones a tree query per point and iteration gives.
/// A guess the certificate cannot prove is replaced by the nearest point of its
/// list, which is closer to the query, for up to [`CERTIFICATE_WALK`] guesses.
/// A reference point's list is found (one k-d tree query, with its normal for
/// point-to-line) the first time it is a guess or a partner.
#[derive(Debug)]
struct Neighbourhoods {
    /// How many fellows each list holds (`k`).
    k: usize,
    /// `k` fellows per reference point, nearest first; `u32::MAX` pads lists of
    /// a reference with fewer than `k + 1` points.
    fellows: Vec<u32>,
    /// `ρ(c)` per reference point: infinite when the list holds every other
    /// point, negative while the list is not yet known.
    reach: Vec<f64>,
    /// The most recently found `ρ`, a guess of the next one.
    last_reach: f64,
}

impl Neighbourhoods {
    fn new(points: usize, k: usize) -> Self {
        Self {
            k,
            fellows: vec![u32::MAX; points * k],
            reach: vec![-1.0; points],
            last_reach: f64::NAN,
        }
    }

    fn is_known(&self, c: usize) -> bool {
        self.reach[c] >= 0.0
    }

    /// Records reference point `c`'s neighbours as a k-d tree query at `c`
    /// returned them, nearest first (`c` itself, or a copy of it, among them).
    fn set(&mut self, c: usize, neighbours: &[Neighbour], reference_len: usize) {
        let list = &mut self.fellows[c * self.k..(c + 1) * self.k];
        list.fill(u32::MAX);
        let mut fellows = neighbours.iter().filter(|n| n.index != c);
        for (slot, n) in list.iter_mut().zip(fellows.by_ref()) {
            *slot = n.index as u32;
        }
        // Every point outside the list is at least as far as the first returned
        // point that did not fit in it, or else as the farthest point returned;
        // if the query returned every point, none is outside.
        self.reach[c] = match fellows.next() {
            Some(n) => n.distance_squared.sqrt(),
            None if neighbours.len() >= reference_len => f64::INFINITY,
            None => neighbours
                .last()
                .map_or(f64::INFINITY, |n| n.distance_squared.sqrt()),
        };
        self.last_reach = self.reach[c];
    }

    /// The nearest of `{c} ∪ N(c)` to `q`, and whether the certificate around
    /// the guess `c` proves it the nearest of all.
    fn nearest(&self, c: usize, q: Point2, reference: &[Point2]) -> (Neighbour, bool) {
        let reach = self.reach[c];
        let d_c_squared = squared_distance(q, reference[c]);
        let mut best = Neighbour {
            index: c,
            distance_squared: d_c_squared,
        };
        for &f in &self.fellows[c * self.k..(c + 1) * self.k] {
            let Some(r) = reference.get(f as usize) else {
                break;
            };
            let d = squared_distance(q, *r);
            if d < best.distance_squared {
                best = Neighbour {
                    index: f as usize,
                    distance_squared: d,
                };
            }
        }
        // A nanometre absorbs the square roots' rounding. The best is no farther
        // than `c`, so `2 d_c < ρ(c)` proves it without a square root (the
        // usual case); else the exact test `d_best < ρ(c) − d_c`.
        let reach = reach - 1e-9;
        let proven = reach > 0.0
            && (4.0 * d_c_squared < reach * reach
                || best.distance_squared.sqrt() + d_c_squared.sqrt() < reach);
        (best, proven)
    }
}

fn squared_distance(a: Point2, b: Point2) -> f64 {
    (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1])
}

/// Finite points and their original indices.
fn finite_points(points: &[Point2]) -> (Vec<Point2>, Vec<usize>) {
    points
        .iter()
        .enumerate()
        .filter(|(_, p)| p[0].is_finite() && p[1].is_finite())
        .map(|(i, p)| (*p, i))
        .unzip()
}

/// The unit normal at a reference point from its nearest `neighbours` (itself
/// among them): those within [`IcpConfig::normal_radius`] define the line.
fn normal_from(
    points: &[Point2],
    neighbours: &mut Vec<Neighbour>,
    config: &IcpConfig,
) -> Option<Point2> {
    let radius_squared = config.normal_radius * config.normal_radius;
    neighbours.retain(|n| n.distance_squared <= radius_squared);
    line_normal(points, neighbours)
}

/// The unit normal of the line through `neighbours` (total least squares: the
/// direction of least spread of their 2×2 covariance), or `None` if they are
/// fewer than two or all at one place. The principal axis of a covariance
/// `[[a, b], [b, c]]` lies at `φ = ½ atan2(2b, a − c)`; the normal is
/// perpendicular to it.
fn line_normal(points: &[Point2], neighbours: &[Neighbour]) -> Option<Point2> {
    if neighbours.len() < 2 {
        return None;
    }
    let n = neighbours.len() as f64;
    let (mut mx, mut my) = (0.0, 0.0);
    for nb in neighbours {
        mx += points[nb.index][0];
        my += points[nb.index][1];
    }
    mx /= n;
    my /= n;
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for nb in neighbours {
        let dx = points[nb.index][0] - mx;
        let dy = points[nb.index][1] - my;
        a += dx * dx;
        b += dx * dy;
        c += dy * dy;
    }
    // All neighbours at one place (to within a micrometre): no line.
    if a + c <= 1e-12 * n {
        return None;
    }
    let phi = 0.5 * math::atan2(2.0 * b, a - c);
    let (s, co) = math::sin_cos(phi);
    Some([-s, co])
}

/// The closed-form point-to-point solution (Arun et al. 1987; Besl and McKay
/// 1992, in 2-D): the pose `(R, t)` minimising `Σ |R sᵢ + t − mᵢ|²` over pairs
/// `(sᵢ, mᵢ)`.
///
/// With the centroids `s̄`, `m̄` and the centred points `s'ᵢ = sᵢ − s̄`,
/// `m'ᵢ = mᵢ − m̄`, the optimal translation is `t = m̄ − R s̄`, which leaves
/// `Σ |R s'ᵢ − m'ᵢ|² = Σ |s'ᵢ|² + Σ |m'ᵢ|² − 2 Σ m'ᵢ·R s'ᵢ` to minimise. With
/// `R = [[cos θ, −sin θ], [sin θ, cos θ]]` and the cross-covariance sums
/// `S_xx = Σ s'ₓ m'ₓ`, `S_xy = Σ s'ₓ m'ᵧ`, `S_yx = Σ s'ᵧ m'ₓ`, `S_yy = Σ s'ᵧ m'ᵧ`,
/// `Σ m'ᵢ·R s'ᵢ = cos θ (S_xx + S_yy) + sin θ (S_xy − S_yx)`, largest at
///
/// `θ = atan2(S_xy − S_yx, S_xx + S_yy)`.
///
/// (In 3-D the same maximisation needs an SVD or a quaternion eigenproblem;
/// in 2-D it is one `atan2`.) Errors if the pairs are fewer than two or either
/// set is concentrated at one point, where the rotation is undetermined.
pub fn closed_form_point_to_point(pairs: &[(Point2, Point2)]) -> Result<Pose2, IcpError> {
    closed_form(pairs.iter().copied())
}

/// [`closed_form_point_to_point`] over any re-iterable sequence of pairs
/// `(scan point, reference point)`, so ICP needs no buffer for them.
fn closed_form<I>(pairs: I) -> Result<Pose2, IcpError>
where
    I: Iterator<Item = (Point2, Point2)> + Clone,
{
    let (mut count, mut sx, mut sy, mut mx, mut my) = (0usize, 0.0, 0.0, 0.0, 0.0);
    for (s, m) in pairs.clone() {
        count += 1;
        sx += s[0];
        sy += s[1];
        mx += m[0];
        my += m[1];
    }
    if count < 2 {
        return Err(IcpError::TooFewCorrespondences {
            kept: count,
            needed: 2,
        });
    }
    let n = count as f64;
    let (sx, sy, mx, my) = (sx / n, sy / n, mx / n, my / n);
    let (mut sxx, mut sxy, mut syx, mut syy) = (0.0, 0.0, 0.0, 0.0);
    let (mut spread_s, mut spread_m) = (0.0, 0.0);
    for (s, m) in pairs {
        let (a, b) = (s[0] - sx, s[1] - sy);
        let (c, d) = (m[0] - mx, m[1] - my);
        sxx += a * c;
        sxy += a * d;
        syx += b * c;
        syy += b * d;
        spread_s += a * a + b * b;
        spread_m += c * c + d * d;
    }
    // Mean squared spread below a square micrometre: one place, no rotation.
    if spread_s <= 1e-12 * n || spread_m <= 1e-12 * n {
        return Err(IcpError::Degenerate(
            "the paired points are all at one place, so the rotation is undetermined",
        ));
    }
    let theta = math::atan2(sxy - syx, sxx + syy);
    let (s, c) = math::sin_cos(theta);
    Ok(Pose2::new(
        mx - (c * sx - s * sy),
        my - (s * sx + c * sy),
        theta,
    ))
}

/// Solves the symmetric positive-definite 3×3 system `H x = g` by Cholesky
/// (`H = L Lᵀ`), or `None` if a pivot is below `1e-10` times the largest
/// diagonal entry (a direction the pairs do not constrain).
fn solve_spd3(h: &[[f64; 3]; 3], g: &[f64; 3]) -> Option<[f64; 3]> {
    let scale = h[0][0].max(h[1][1]).max(h[2][2]);
    if !(scale > 0.0) || !scale.is_finite() {
        return None;
    }
    let floor = 1e-10 * scale;
    let mut l = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..=i {
            let mut sum = h[i][j];
            for k in 0..j {
                sum -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(sum > floor) {
                    return None;
                }
                l[i][i] = sum.sqrt();
            } else {
                l[i][j] = sum / l[j][j];
            }
        }
    }
    // L y = g, then Lᵀ x = y.
    let mut y = [0.0; 3];
    for i in 0..3 {
        let mut sum = g[i];
        for k in 0..i {
            sum -= l[i][k] * y[k];
        }
        y[i] = sum / l[i][i];
    }
    let mut x = [0.0; 3];
    for i in (0..3).rev() {
        let mut sum = y[i];
        for k in i + 1..3 {
            sum -= l[k][i] * x[k];
        }
        x[i] = sum / l[i][i];
    }
    Some(x)
}

impl IcpState {
    /// Prepares ICP of `scan` (points in the scan's frame) against `reference`
    /// (points in the reference frame) from the guess `initial`
    /// (`reference_from_scan`): builds the k-d tree and, for point-to-line, the
    /// reference's normals. Points with a NaN or infinite coordinate are left
    /// out; the records keep the indices of the slices given here.
    pub fn new(
        reference: &[Point2],
        scan: &[Point2],
        initial: Pose2,
        config: IcpConfig,
    ) -> Result<Self, IcpError> {
        config.validate()?;
        if !initial.is_finite() {
            return Err(IcpError::NonFiniteInitialPose);
        }
        let (reference, reference_index) = finite_points(reference);
        let (scan, scan_index) = finite_points(scan);
        let needed = config.min_correspondences;
        if reference.len() < needed {
            return Err(IcpError::NotEnoughPoints {
                which: "reference",
                count: reference.len(),
                needed,
            });
        }
        if scan.len() < needed {
            return Err(IcpError::NotEnoughPoints {
                which: "scan",
                count: scan.len(),
                needed,
            });
        }
        let tree = PointTree::new(&reference)?;
        // The certificate's lists (see `Neighbourhoods`) hold the normals'
        // neighbours less the point itself; both are found when a reference
        // point is first needed, so points nothing pairs with cost nothing.
        let neighbourhoods =
            Neighbourhoods::new(reference.len(), config.normal_neighbours.max(2) - 1);
        let normals = match config.variant {
            IcpVariant::PointToPoint => Vec::new(),
            IcpVariant::PointToLine => vec![None; reference.len()],
        };
        let pose = Pose2::new(initial.x, initial.y, initial.theta);
        Ok(Self {
            config,
            pairs: Vec::with_capacity(scan.len()),
            order: Vec::with_capacity(scan.len()),
            errors: Vec::with_capacity(scan.len()),
            reference,
            reference_index,
            normals,
            tree,
            scan,
            scan_index,
            pose,
            iterations: 0,
            converged: false,
            partner: Vec::new(),
            neighbourhoods,
            certified: 0,
            tree_queries: 0,
            neighbours: Vec::new(),
        })
    }

    /// The reference point nearest to `q`, the `i`-th scan point at the current
    /// pose: certified around a guess when possible, else from the tree (see
    /// [`Neighbourhoods`]).
    fn nearest(&mut self, i: usize, q: Point2) -> Option<Neighbour> {
        let mut guess = self.partner[i].or(if i > 0 { self.partner[i - 1] } else { None });
        // A guess that cannot be proven is replaced by the nearest of its
        // neighbours, which is closer to `q`: a short walk towards the answer.
        for _ in 0..CERTIFICATE_WALK {
            let Some(c) = guess else { break };
            self.know_neighbourhood(c);
            let (found, proven) = self.neighbourhoods.nearest(c, q, &self.reference);
            if proven {
                self.certified += 1;
                self.partner[i] = Some(found.index);
                self.know_neighbourhood(found.index);
                return Some(found);
            }
            guess = (found.index != c).then_some(found.index);
        }
        self.tree_queries += 1;
        let found = self.tree.nearest(q)?;
        self.partner[i] = Some(found.index);
        self.know_neighbourhood(found.index);
        Some(Neighbour {
            index: found.index,
            distance_squared: squared_distance(q, self.reference[found.index]),
        })
    }

    /// Finds reference point `c`'s neighbours (the certificate's list and, for
    /// point-to-line, its normal) unless already known: one k-d tree query.
    fn know_neighbourhood(&mut self, c: usize) {
        if self.neighbourhoods.is_known(c) {
            return;
        }
        let k = self.neighbourhoods.k + 1;
        // The last neighbourhood's size is a good guess of this one's.
        self.tree.nearest_k_near(
            self.reference[c],
            k,
            1.25 * self.neighbourhoods.last_reach,
            &mut self.neighbours,
        );
        self.neighbourhoods
            .set(c, &self.neighbours, self.reference.len());
        if let Some(normal) = self.normals.get_mut(c) {
            *normal = normal_from(&self.reference, &mut self.neighbours, &self.config);
        }
    }

    /// How many nearest-neighbour answers so far were certified without the
    /// tree, and how many were asked of it (see [`Neighbourhoods`]).
    pub fn query_counts(&self) -> (usize, usize) {
        (self.certified, self.tree_queries)
    }

    /// The settings.
    pub fn config(&self) -> &IcpConfig {
        &self.config
    }

    /// The current pose estimate (`reference_from_scan`).
    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// Iterations taken so far.
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// Whether the last step was below both tolerances.
    pub fn converged(&self) -> bool {
        self.converged
    }

    /// Whether ICP is finished: converged or at its iteration limit.
    pub fn is_done(&self) -> bool {
        self.converged || self.iterations >= self.config.max_iterations
    }

    /// Point-to-line: the unit normal at reference point `index` (an index of
    /// the slice given to [`IcpState::new`]), if it has one. Always `None`
    /// for point-to-point.
    pub fn reference_normal(&self, index: usize) -> Option<Point2> {
        let c = self.reference_index.binary_search(&index).ok()?;
        if self.config.variant == IcpVariant::PointToPoint {
            return None;
        }
        if self.neighbourhoods.is_known(c) {
            return self.normals.get(c).copied().flatten();
        }
        let mut neighbours = Vec::new();
        self.tree.nearest_k(
            self.reference[c],
            self.config.normal_neighbours,
            &mut neighbours,
        );
        normal_from(&self.reference, &mut neighbours, &self.config)
    }

    /// Pairs every scan point at the current pose, applies the gate and
    /// trimming, and returns the number kept and their mean squared error.
    fn pair_up(&mut self) -> Result<(usize, f64), IcpError> {
        let gate_squared =
            self.config.max_correspondence_distance * self.config.max_correspondence_distance;
        let point_to_line = self.config.variant == IcpVariant::PointToLine;
        self.pairs.clear();
        self.order.clear();
        self.partner.resize(self.scan.len(), None);
        // `transform_point` without a sine and cosine per point.
        let (sin, cos) = math::sin_cos(self.pose.theta);
        let (tx, ty) = (self.pose.x, self.pose.y);
        for i in 0..self.scan.len() {
            let p = self.scan[i];
            let q = [cos * p[0] - sin * p[1] + tx, sin * p[0] + cos * p[1] + ty];
            let Some(nearest) = self.nearest(i, q) else {
                continue;
            };
            let r = self.reference[nearest.index];
            let (status, error_squared) = if nearest.distance_squared > gate_squared {
                (PairStatus::Gated, nearest.distance_squared)
            } else if point_to_line {
                match self.normals.get(nearest.index).copied().flatten() {
                    Some(n) => {
                        let e = n[0] * (q[0] - r[0]) + n[1] * (q[1] - r[1]);
                        (PairStatus::Kept, e * e)
                    }
                    None => (PairStatus::NoNormal, nearest.distance_squared),
                }
            } else {
                (PairStatus::Kept, nearest.distance_squared)
            };
            if status == PairStatus::Kept {
                self.order.push(self.pairs.len());
            }
            self.pairs.push(Pair {
                scan: i,
                reference: nearest.index,
                transformed: q,
                distance_squared: nearest.distance_squared,
                error_squared,
                status,
            });
        }
        // Trimming (Chetverikov et al. 2002): keep the ⌈ξ N⌉ candidates with
        // the smallest error, ties by scan order (so the kept set is
        // deterministic). The `keep`-th smallest error is found by selection,
        // not a sort (O(N)); pairs below it are kept, then pairs equal to it in
        // scan order until `keep` are.
        let candidates = self.order.len();
        let keep =
            ((self.config.trim_fraction * candidates as f64).ceil() as usize).min(candidates);
        if keep > 0 && keep < candidates {
            self.errors.clear();
            self.errors
                .extend(self.order.iter().map(|&k| self.pairs[k].error_squared));
            let (_, &mut threshold, _) =
                self.errors.select_nth_unstable_by(keep - 1, f64::total_cmp);
            let below = self
                .errors
                .iter()
                .filter(|e| e.total_cmp(&threshold).is_lt())
                .count();
            let mut ties_kept = 0;
            let pairs = &mut self.pairs;
            self.order
                .retain(|&k| match pairs[k].error_squared.total_cmp(&threshold) {
                    std::cmp::Ordering::Less => true,
                    std::cmp::Ordering::Equal if below + ties_kept < keep => {
                        ties_kept += 1;
                        true
                    }
                    _ => {
                        pairs[k].status = PairStatus::Trimmed;
                        false
                    }
                });
        }
        if keep < self.config.min_correspondences {
            return Err(IcpError::TooFewCorrespondences {
                kept: keep,
                needed: self.config.min_correspondences,
            });
        }
        // Summed in scan order, whatever order the selection left.
        let sum: f64 = self
            .pairs
            .iter()
            .filter(|p| p.status == PairStatus::Kept)
            .map(|p| p.error_squared)
            .sum();
        Ok((keep, sum / keep as f64))
    }

    /// The pose that minimises the kept pairs' error, from the current pose.
    fn solve(&self) -> Result<Pose2, IcpError> {
        match self.config.variant {
            IcpVariant::PointToPoint => self.solve_point_to_point(),
            IcpVariant::PointToLine => self.solve_point_to_line(),
        }
    }

    /// Closed form over the kept pairs, from the scan's own frame (so the
    /// result is the new pose itself, not an increment).
    fn solve_point_to_point(&self) -> Result<Pose2, IcpError> {
        closed_form(self.order.iter().map(|&k| {
            let pair = &self.pairs[k];
            (self.scan[pair.scan], self.reference[pair.reference])
        }))
    }

    /// Low (2004) in 2-D: with `qᵢ = R sᵢ + t` the scan point at the current
    /// pose, `mᵢ` its reference point and `nᵢ` the unit normal there, a small
    /// increment `δ = (δx, δy, δθ)` applied on the left (`qᵢ ↦ R(δθ) qᵢ + δt`)
    /// changes the error `eᵢ = nᵢ·(qᵢ − mᵢ)` to first order by `aᵢ·δ` with
    /// `aᵢ = [nₓ, nᵧ, qₓ nᵧ − qᵧ nₓ]` (the last entry is `qᵢ × nᵢ`, since
    /// `d(R(δθ) q)/dδθ = [−qᵧ, qₓ]`). Minimising `Σ (eᵢ + aᵢ·δ)²` gives the
    /// normal equations `(Σ aᵢ aᵢᵀ) δ = −Σ aᵢ eᵢ`, solved by Cholesky; the new
    /// pose is `(δx, δy, δθ) ∘ pose` with the exact rotation.
    fn solve_point_to_line(&self) -> Result<Pose2, IcpError> {
        let mut h = [[0.0; 3]; 3];
        let mut g = [0.0; 3];
        for &k in &self.order {
            let pair = &self.pairs[k];
            let Some(n) = self.normals.get(pair.reference).copied().flatten() else {
                continue;
            };
            let q = pair.transformed;
            let m = self.reference[pair.reference];
            let e = n[0] * (q[0] - m[0]) + n[1] * (q[1] - m[1]);
            let a = [n[0], n[1], q[0] * n[1] - q[1] * n[0]];
            for i in 0..3 {
                for j in 0..=i {
                    h[i][j] += a[i] * a[j];
                }
                g[i] -= a[i] * e;
            }
        }
        for i in 0..3 {
            for j in i + 1..3 {
                h[i][j] = h[j][i];
            }
        }
        let delta = solve_spd3(&h, &g).ok_or(IcpError::Degenerate(
            "the kept points' lines leave a direction free (e.g. a corridor with parallel walls only)",
        ))?;
        Ok(Pose2::new(delta[0], delta[1], delta[2]).compose(&self.pose))
    }

    /// One ICP iteration: pair, reject, solve, move. Returns its record. An
    /// error leaves the pose where it was.
    pub fn step(&mut self) -> Result<IcpIteration, IcpError> {
        let (kept, mean_squared_error) = self.pair_up()?;
        let before = self.pose;
        let after = self.solve()?;
        if !after.is_finite() {
            return Err(IcpError::Degenerate("the step is not finite"));
        }
        let step_translation = math::hypot(after.x - before.x, after.y - before.y);
        let step_rotation = wrap_angle(after.theta - before.theta).abs();
        let converged = step_translation <= self.config.translation_tolerance
            && step_rotation <= self.config.rotation_tolerance;
        self.pose = after;
        self.iterations += 1;
        self.converged = converged;
        let correspondences = self
            .pairs
            .iter()
            .map(|p| Correspondence {
                scan_index: self.scan_index[p.scan],
                reference_index: self.reference_index[p.reference],
                scan_point: p.transformed,
                distance_squared: p.distance_squared,
                error_squared: p.error_squared,
                status: p.status,
            })
            .collect();
        Ok(IcpIteration {
            iteration: self.iterations,
            pose_before: before,
            pose: after,
            correspondences,
            kept,
            mean_squared_error,
            step_translation,
            step_rotation,
            converged,
        })
    }

    /// The mean squared error (variant's metric, m²) of the pairs kept at the
    /// current pose, without moving.
    pub fn cost(&mut self) -> Result<f64, IcpError> {
        self.pair_up().map(|(_, mse)| mse)
    }

    /// Steps until converged or at the iteration limit, then measures the cost
    /// at the final pose. Returns the match and every iteration's record.
    pub fn run(&mut self) -> Result<(ScanMatch, Vec<IcpIteration>), IcpError> {
        let mut records = Vec::new();
        while !self.is_done() {
            records.push(self.step()?);
        }
        let cost = self.cost()?;
        Ok((
            ScanMatch {
                pose: self.pose,
                cost,
                iterations: self.iterations,
                converged: self.converged,
            },
            records,
        ))
    }
}

/// ICP of `scan` against `reference` from `initial` (`reference_from_scan`) to
/// the end: the match (pose, mean squared error of the kept pairs at that pose
/// in m², iterations, whether it converged) and every iteration's record.
pub fn align(
    reference: &[Point2],
    scan: &[Point2],
    initial: Pose2,
    config: &IcpConfig,
) -> Result<(ScanMatch, Vec<IcpIteration>), IcpError> {
    IcpState::new(reference, scan, initial, *config)?.run()
}

/// [`align`] on two scans' end points (max-range and invalid readings left
/// out); the records' indices are indices into [`Scan::points`].
pub fn align_scans(
    reference: &Scan,
    scan: &Scan,
    initial: Pose2,
    config: &IcpConfig,
) -> Result<(ScanMatch, Vec<IcpIteration>), IcpError> {
    align(&reference.points(), &scan.points(), initial, config)
}

#[cfg(test)]
pub(crate) mod tests;
