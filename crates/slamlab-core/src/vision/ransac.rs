//! RANSAC for the essential matrix (thesis `000` Sec. 4.3, "Random Sample
//! Consensus"), stepped one iteration at a time so a lesson can show each
//! sample, with the adaptive iteration bound, the Sampson-distance inlier test,
//! a final refit on the inliers, the choice of `(R, t)` by cheirality and a
//! test for pure rotation.
//!
//! Departure from the thesis's listing: it stops at the first hypothesis whose
//! inlier share exceeds a preset threshold; this keeps the best hypothesis and
//! stops when `N = log(1 − p) / log(1 − wˢ)` samples have been drawn, with `w`
//! the best inlier share so far (Fischler and Bolles 1981; Hartley and
//! Zisserman Sec. 4.7.1), so it needs no guess of the outlier share.

use nalgebra::{Matrix3, Vector3};
use rand::Rng;
use serde::{Deserialize, Serialize};

use super::decompose::{Decomposition, choose_by_cheirality};
use super::eight_point::{EIGHT, essential_from_fundamental, fundamental_eight_point, svd3};
use super::five_point::{FIVE, MAX_SOLUTIONS, essential_five_point_array};
use super::{
    Correspondence, Intrinsics, VisionError, check_finite, fundamental_from_essential,
    sampson_squared,
};

/// The Sampson inlier test `d² ≤ τ²` of [`sampson_squared`] for one F, written
/// without the division, `(x_rᵀ F x_l)² ≤ τ² · den` with `den > 0`, and with
/// F's entries in locals: RANSAC evaluates it for every match and hypothesis.
#[derive(Debug, Clone, Copy)]
struct SampsonTest {
    f: [f64; 9],
    limit: f64,
}

impl SampsonTest {
    fn new(f: &Matrix3<f64>, threshold_px: f64) -> Self {
        Self {
            f: [
                f[(0, 0)],
                f[(0, 1)],
                f[(0, 2)],
                f[(1, 0)],
                f[(1, 1)],
                f[(1, 2)],
                f[(2, 0)],
                f[(2, 1)],
                f[(2, 2)],
            ],
            limit: threshold_px * threshold_px,
        }
    }

    #[inline]
    fn inlier(&self, m: &Correspondence) -> bool {
        self.inlier_at(m.left.x, m.left.y, m.right.x, m.right.y)
    }

    /// Inliers among one block of matches.
    #[inline]
    fn count_block(&self, block: &[[f64; BLOCK]; 4]) -> usize {
        let mut count = 0;
        for i in 0..BLOCK {
            count +=
                usize::from(self.inlier_at(block[0][i], block[1][i], block[2][i], block[3][i]));
        }
        count
    }

    #[inline]
    fn inlier_at(&self, x: f64, y: f64, u: f64, v: f64) -> bool {
        let [f00, f01, f02, f10, f11, f12, f20, f21, f22] = self.f;
        // F x_l and the first two entries of Fᵀ x_r.
        let a0 = f00 * x + f01 * y + f02;
        let a1 = f10 * x + f11 * y + f12;
        let a2 = f20 * x + f21 * y + f22;
        let b0 = f00 * u + f10 * v + f20;
        let b1 = f01 * u + f11 * v + f21;
        let algebraic = u * a0 + v * a1 + a2;
        let denominator = a0 * a0 + a1 * a1 + b0 * b0 + b1 * b1;
        denominator > 0.0 && algebraic * algebraic <= self.limit * denominator
    }
}

/// Matches per block of [`Ransac::count_inliers`].
const BLOCK: usize = 16;

/// The matches' pixels as blocks of four columns; the last block is padded with
/// non-finite pixels, which are never inliers.
fn columns_of(matches: &[Correspondence]) -> Vec<[[f64; BLOCK]; 4]> {
    matches
        .chunks(BLOCK)
        .map(|chunk| {
            let mut block = [[f64::NAN; BLOCK]; 4];
            for (i, m) in chunk.iter().enumerate() {
                block[0][i] = m.left.x;
                block[1][i] = m.left.y;
                block[2][i] = m.right.x;
                block[3][i] = m.right.y;
            }
            block
        })
        .collect()
}

/// The minimal solver inside RANSAC.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Method {
    /// Eight matches, linear (Eq. 4.18-4.21).
    EightPoint,
    /// Five matches, up to ten hypotheses (Eq. 4.22-4.25).
    FivePoint,
}

impl Method {
    /// Matches per sample, `s`.
    pub fn sample_size(self) -> usize {
        match self {
            Method::EightPoint => EIGHT,
            Method::FivePoint => FIVE,
        }
    }

    /// The name used in URLs, flags and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Method::EightPoint => "eight-point",
            Method::FivePoint => "five-point",
        }
    }

    /// Parses [`Method::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "eight-point" => Some(Method::EightPoint),
            "five-point" => Some(Method::FivePoint),
            _ => None,
        }
    }
}

/// RANSAC's settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RansacConfig {
    /// The minimal solver.
    pub method: Method,
    /// Hartley normalization in the eight-point solver (hypotheses and refit).
    pub normalize: bool,
    /// A match is an inlier when its Sampson distance is at most this, pixels.
    pub threshold_px: f64,
    /// `p`: the wanted probability of drawing at least one all-inlier sample.
    pub confidence: f64,
    /// Upper limit on the number of samples.
    pub max_iterations: usize,
    /// Below this median parallax (pixels) the motion is a pure rotation and
    /// the translation is reported unobservable.
    pub min_parallax_px: f64,
    /// Fewer inliers than this share of the matches is no consensus.
    pub min_inlier_ratio: f64,
}

impl Default for RansacConfig {
    fn default() -> Self {
        Self {
            method: Method::FivePoint,
            normalize: true,
            threshold_px: 2.0,
            confidence: 0.99,
            max_iterations: 2000,
            min_parallax_px: 2.0,
            min_inlier_ratio: 0.1,
        }
    }
}

/// The adaptive bound `N = ⌈log(1 − p) / log(1 − wˢ)⌉`, capped at `max`:
/// after N samples, at least one was all inliers with probability `p` when the
/// inlier share is `w` and a sample has `s` matches.
pub fn adaptive_bound(inlier_ratio: f64, sample_size: usize, confidence: f64, max: usize) -> usize {
    let w_s = crate::math::powf(inlier_ratio.clamp(0.0, 1.0), sample_size as f64);
    if !(w_s > 0.0) {
        return max;
    }
    if w_s >= 1.0 {
        return 1.min(max);
    }
    let p = confidence.clamp(0.0, 1.0 - 1e-12);
    let n = crate::math::ln(1.0 - p) / crate::math::ln_1p(-w_s);
    if !(n.is_finite()) || n > max as f64 {
        return max;
    }
    (n.ceil() as usize).max(1)
}

/// What one RANSAC iteration did.
#[derive(Debug, Clone, PartialEq)]
pub struct IterationReport {
    /// 1 for the first sample.
    pub iteration: usize,
    /// Indices of the matches drawn.
    pub sample: Vec<usize>,
    /// Hypotheses the solver returned (eight-point: 0 or 1; five-point: 0-10).
    pub hypotheses: usize,
    /// Inliers of this sample's best hypothesis.
    pub inliers: usize,
    /// Inliers of the best hypothesis so far.
    pub best_inliers: usize,
    /// The adaptive bound after this iteration.
    pub bound: usize,
    /// Whether this sample gave a new best.
    pub improved: bool,
}

/// Upper limit on the refits of one local optimization. It stops earlier, as
/// soon as a refit no longer lowers the truncated cost; on 500 matches with half
/// of them wrong a new best from a noisy eight-point sample takes up to ten
/// refits to gather the inliers (101, 134, 152, 176, 182, 207, 210, 216, 218,
/// 221 for the benchmark's scene), and stopping after three left the best at
/// 176, the adaptive bound at its cap.
const LO_MAX_ROUNDS: usize = 20;

/// The best hypothesis so far.
#[derive(Debug, Clone, PartialEq)]
struct Best {
    /// In pixels: F for the eight-point method, `K⁻ᵀ E K⁻¹` for the five-point.
    fundamental: Matrix3<f64>,
    inliers: Vec<bool>,
    count: usize,
}

/// A RANSAC run over one set of matches, advanced by [`Ransac::step`].
#[derive(Debug, Clone)]
pub struct Ransac {
    matches: Vec<Correspondence>,
    /// The pixels as four columns (left x, left y, right x, right y) in blocks
    /// of [`BLOCK`] matches, for the inlier count's inner loop.
    columns: Vec<[[f64; BLOCK]; 4]>,
    left: Vec<Vector3<f64>>,
    right: Vec<Vector3<f64>>,
    k: Intrinsics,
    config: RansacConfig,
    iteration: usize,
    bound: usize,
    best: Option<Best>,
}

impl Ransac {
    /// Checks the input and prepares the run: enough matches for the method,
    /// finite pixels, usable intrinsics.
    pub fn new(
        matches: &[Correspondence],
        k: &Intrinsics,
        config: RansacConfig,
    ) -> Result<Self, VisionError> {
        k.validate()?;
        check_finite(matches)?;
        let s = config.method.sample_size();
        if matches.len() < s {
            return Err(VisionError::TooFewMatches {
                method: match config.method {
                    Method::EightPoint => "the eight-point algorithm",
                    Method::FivePoint => "the five-point algorithm",
                },
                needed: s,
                got: matches.len(),
            });
        }
        Ok(Self {
            matches: matches.to_vec(),
            columns: columns_of(matches),
            left: matches.iter().map(|m| k.normalize(&m.left)).collect(),
            right: matches.iter().map(|m| k.normalize(&m.right)).collect(),
            k: *k,
            config,
            iteration: 0,
            bound: config.max_iterations.max(1),
            best: None,
        })
    }

    /// Samples drawn so far.
    pub fn iteration(&self) -> usize {
        self.iteration
    }

    /// The current adaptive bound N.
    pub fn bound(&self) -> usize {
        self.bound
    }

    /// Whether N samples have been drawn.
    pub fn is_done(&self) -> bool {
        self.iteration >= self.bound
    }

    /// Inliers of the best hypothesis so far.
    pub fn best_inliers(&self) -> usize {
        self.best.as_ref().map_or(0, |b| b.count)
    }

    /// The best essential matrix so far.
    pub fn best_essential(&self) -> Option<Matrix3<f64>> {
        self.best
            .as_ref()
            .map(|b| essential_from_fundamental(&b.fundamental, &self.k))
    }

    /// The best hypothesis so far as a fundamental matrix in pixels (for
    /// epipolar lines).
    pub fn best_fundamental(&self) -> Option<Matrix3<f64>> {
        self.best.as_ref().map(|b| b.fundamental)
    }

    /// The settings.
    pub fn config(&self) -> &RansacConfig {
        &self.config
    }

    /// The hypotheses of one sample, as fundamental matrices in pixels. The
    /// eight-point method estimates F (eight unknowns up to scale: it does not
    /// use K) and is scored as F; projecting a minimal, noisy F onto the
    /// essential matrices moves it off most inliers. The five-point method
    /// returns essential matrices, scored through `F = K⁻ᵀ E K⁻¹`.
    pub fn hypotheses(&self, sample: &[usize]) -> Vec<Matrix3<f64>> {
        let (hypotheses, count) = self.hypotheses_array(sample);
        hypotheses[..count].to_vec()
    }

    /// [`Ransac::hypotheses`] in a fixed array (the first `count` entries), so
    /// RANSAC's loop allocates nothing per sample.
    fn hypotheses_array(&self, sample: &[usize]) -> ([Matrix3<f64>; MAX_SOLUTIONS], usize) {
        let mut out = [Matrix3::zeros(); MAX_SOLUTIONS];
        match self.config.method {
            Method::EightPoint => {
                if sample.len() != EIGHT {
                    return (out, 0);
                }
                let chosen: [Correspondence; EIGHT] =
                    std::array::from_fn(|i| self.matches[sample[i]]);
                match fundamental_eight_point(&chosen, self.config.normalize) {
                    Ok(f) => {
                        out[0] = f;
                        (out, 1)
                    }
                    Err(_) => (out, 0),
                }
            }
            Method::FivePoint => {
                if sample.len() != FIVE {
                    return (out, 0);
                }
                let left: [Vector3<f64>; 5] = std::array::from_fn(|i| self.left[sample[i]]);
                let right: [Vector3<f64>; 5] = std::array::from_fn(|i| self.right[sample[i]]);
                let (essentials, count) = essential_five_point_array(&left, &right);
                for (f, e) in out.iter_mut().zip(&essentials[..count]) {
                    *f = fundamental_from_essential(e, &self.k);
                }
                (out, count)
            }
        }
    }

    /// Which matches are inliers of the fundamental matrix `f` (Sampson
    /// distance in pixels at most the threshold), and how many.
    pub fn classify(&self, f: &Matrix3<f64>) -> (Vec<bool>, usize) {
        let test = SampsonTest::new(f, self.config.threshold_px);
        let inliers: Vec<bool> = self.matches.iter().map(|m| test.inlier(m)).collect();
        let count = inliers.iter().filter(|&&b| b).count();
        (inliers, count)
    }

    /// The truncated squared Sampson cost `Σ min(d², τ²)` of `f` (MSAC, Torr
    /// and Zisserman 2000), pixels²: lower is better. Used to compare a
    /// least-squares refit with the minimal hypothesis it came from, where
    /// inlier counts alone favour the hypothesis that happens to graze one more
    /// noisy match.
    pub fn truncated_cost(&self, f: &Matrix3<f64>) -> f64 {
        let limit = self.config.threshold_px * self.config.threshold_px;
        self.matches
            .iter()
            .map(|m| sampson_squared(f, m).min(limit))
            .sum()
    }

    /// The eight-point fit on the marked matches, as the method's model: F
    /// for the eight-point method, the nearest essential matrix (as F in pixels)
    /// for the five-point method.
    fn refit(&self, mask: &[bool]) -> Option<Matrix3<f64>> {
        let chosen: Vec<Correspondence> = self
            .matches
            .iter()
            .zip(mask)
            .filter(|(_, inlier)| **inlier)
            .map(|(m, _)| *m)
            .collect();
        let normalize = self.config.normalize || self.config.method == Method::FivePoint;
        let f = fundamental_eight_point(&chosen, normalize).ok()?;
        Some(match self.config.method {
            Method::EightPoint => f,
            Method::FivePoint => {
                fundamental_from_essential(&essential_from_fundamental(&f, &self.k), &self.k)
            }
        })
    }

    /// How many matches are inliers of `f`, counting only while the count can
    /// still exceed `beat`: once more than `n − beat − 1` matches have failed,
    /// it returns early with a count of at most `beat`. With `beat = 0` the
    /// count is exact.
    pub fn count_inliers(&self, f: &Matrix3<f64>, beat: usize) -> usize {
        let test = SampsonTest::new(f, self.config.threshold_px);
        let n = self.matches.len();
        let allowed_misses = n.saturating_sub(beat + 1);
        let (mut count, mut seen) = (0, 0);
        for block in &self.columns {
            // A whole block at a time, without branches; the last block is
            // padded with matches that are never inliers.
            count += test.count_block(block);
            seen = (seen + BLOCK).min(n);
            if seen - count > allowed_misses {
                return count;
            }
        }
        count
    }

    /// Draws one sample, scores its hypotheses, keeps the best and lowers the
    /// bound. `None` once the bound is reached.
    pub fn step<R: Rng + ?Sized>(&mut self, rng: &mut R) -> Option<IterationReport> {
        let drawn = self.draw(rng, true)?;
        Some(IterationReport {
            iteration: self.iteration,
            sample: drawn.sample[..drawn.size].to_vec(),
            hypotheses: drawn.hypotheses,
            inliers: drawn.inliers,
            best_inliers: self.best_inliers(),
            bound: self.bound,
            improved: drawn.improved,
        })
    }

    /// One sample. With `exact`, every hypothesis's inliers are counted (the
    /// lesson shows them); without, a hypothesis's count stops once it can
    /// neither beat the best so far nor tie the sample's best
    /// ([`Ransac::count_inliers`]), which changes neither the best hypothesis
    /// nor the bound, only [`IterationReport::inliers`].
    fn draw<R: Rng + ?Sized>(&mut self, rng: &mut R, exact: bool) -> Option<Drawn> {
        if self.is_done() {
            return None;
        }
        self.iteration += 1;
        let n = self.matches.len();
        let (sample, size) = distinct_indices(rng, n, self.config.method.sample_size());
        let (hypotheses, count) = self.hypotheses_array(&sample[..size]);
        // The sample's best hypothesis: the most inliers, a tie broken by the
        // lower truncated cost. Only it is locally optimized, and only if it
        // beats the best so far (LO-RANSAC), so the outcome does not depend on
        // the order in which the solver returns its (up to ten) hypotheses.
        let best = self.best_inliers();
        let mut sample_best: usize = 0;
        let mut chosen: Option<&Matrix3<f64>> = None;
        for f in &hypotheses[..count] {
            // A count above `beat` is exact; below it a hypothesis can neither
            // beat the best so far nor tie this sample's best.
            let beat = if exact {
                0
            } else {
                best.max(sample_best.saturating_sub(1))
            };
            let inliers = self.count_inliers(f, beat);
            if inliers > best {
                let wins = match chosen {
                    None => true,
                    Some(g) => {
                        inliers > sample_best
                            || (inliers == sample_best
                                && self.truncated_cost(f) < self.truncated_cost(g))
                    }
                };
                if wins {
                    chosen = Some(f);
                }
            }
            sample_best = sample_best.max(inliers);
        }
        let improved = chosen.is_some();
        if let Some(f) = chosen {
            let (inliers, count) = self.classify(f);
            self.best = Some(self.locally_optimized(Best {
                fundamental: *f,
                inliers,
                count,
            }));
        }
        if improved {
            let w = self.best_inliers() as f64 / n as f64;
            let bound = adaptive_bound(
                w,
                self.config.method.sample_size(),
                self.config.confidence,
                self.config.max_iterations.max(1),
            );
            self.bound = self.bound.min(bound);
        }
        Some(Drawn {
            sample,
            size,
            hypotheses: count,
            inliers: sample_best,
            improved,
        })
    }

    /// Local optimization (Chum, Matas and Kittler, "Locally optimized
    /// RANSAC", 2003): a new best hypothesis from a minimal sample carries that
    /// sample's noise, so it is refitted by the eight-point algorithm on all its
    /// inliers, re-scored, and refitted again while the truncated cost falls
    /// (at most [`LO_MAX_ROUNDS`] times). It runs only when a sample gives a
    /// new best, as in LO-RANSAC. Without it the best minimal hypothesis keeps only part
    /// of the true inliers and the adaptive bound, computed from that share,
    /// stays far too high.
    fn locally_optimized(&self, mut best: Best) -> Best {
        let mut best_cost = self.truncated_cost(&best.fundamental);
        for _ in 0..LO_MAX_ROUNDS {
            let Some(refit) = self.refit(&best.inliers) else {
                break;
            };
            let (inliers, count) = self.classify(&refit);
            if count < best.count {
                break;
            }
            let cost = self.truncated_cost(&refit);
            if cost >= best_cost {
                break;
            }
            best_cost = cost;
            best = Best {
                fundamental: refit,
                inliers,
                count,
            };
        }
        best
    }

    /// Steps until the bound is reached. The same samples, best hypothesis and
    /// bound as [`Ransac::step`] repeated, faster: hypotheses that cannot beat
    /// the best stop being scored early.
    pub fn run<R: Rng + ?Sized>(&mut self, rng: &mut R) {
        while self.draw(rng, false).is_some() {}
    }

    /// The estimate from the best hypothesis: refit by the eight-point
    /// algorithm on its inliers (kept when its truncated cost is lower),
    /// the inliers again, `(R, t)` by cheirality, and the pure-rotation test.
    pub fn finish(&self) -> Result<TwoViewEstimate, VisionError> {
        let n = self.matches.len();
        let best = self
            .best
            .as_ref()
            .ok_or(VisionError::NoConsensus { best: 0, total: n })?;
        let needed = (self.config.min_inlier_ratio * n as f64)
            .ceil()
            .max(2.0 * self.config.method.sample_size() as f64) as usize;
        if best.count < needed {
            return Err(VisionError::NoConsensus {
                best: best.count,
                total: n,
            });
        }
        let mut fundamental = best.fundamental;
        let (mut inliers, mut count) = (best.inliers.clone(), best.count);
        let mut refitted = false;
        if let Some(refit) = self.refit(&inliers)
            && self.truncated_cost(&refit) < self.truncated_cost(&fundamental)
        {
            (inliers, count) = self.classify(&refit);
            fundamental = refit;
            refitted = true;
        }
        let essential = essential_from_fundamental(&fundamental, &self.k);
        let left: Vec<Vector3<f64>> = select(&self.left, &inliers);
        let right: Vec<Vector3<f64>> = select(&self.right, &inliers);
        let decomposition = choose_by_cheirality(&essential, &left, &right)
            .ok_or(VisionError::Degenerate("the essential matrix has no SVD"))?;
        let (rotation_only, parallax_px) = rotation_only_fit(&left, &right, self.k.fx);
        let (motion, rotation, translation) = if parallax_px < self.config.min_parallax_px {
            (Motion::PureRotation, rotation_only, None)
        } else {
            let pose = decomposition.pose();
            (Motion::General, pose.rotation, Some(pose.translation))
        };
        Ok(TwoViewEstimate {
            essential,
            fundamental,
            inliers,
            inlier_count: count,
            iterations: self.iteration,
            bound: self.bound,
            refitted,
            decomposition,
            motion,
            rotation,
            translation,
            parallax_px,
        })
    }
}

/// Whether the two views can fix a translation direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Motion {
    /// Enough parallax: R and the direction of t.
    General,
    /// The matches are explained by a rotation alone (median parallax below
    /// the threshold): t is unobservable and not reported.
    PureRotation,
}

/// The result of [`estimate_two_view`].
#[derive(Debug, Clone, PartialEq)]
pub struct TwoViewEstimate {
    /// The essential matrix, `‖E‖_F = 1`.
    pub essential: Matrix3<f64>,
    /// The fundamental matrix in pixels that classified the inliers (for the
    /// eight-point method the estimated F, for the five-point `K⁻ᵀ E K⁻¹`),
    /// for epipolar lines.
    pub fundamental: Matrix3<f64>,
    /// Which matches are inliers of the final E.
    pub inliers: Vec<bool>,
    /// How many.
    pub inlier_count: usize,
    /// Samples drawn.
    pub iterations: usize,
    /// The final adaptive bound.
    pub bound: usize,
    /// Whether the eight-point refit on the inliers replaced the best sample's E.
    pub refitted: bool,
    /// The four decompositions and their cheirality counts.
    pub decomposition: Decomposition,
    /// General motion or pure rotation.
    pub motion: Motion,
    /// The rotation (right from left).
    pub rotation: Matrix3<f64>,
    /// The unit translation direction, `None` for a pure rotation.
    pub translation: Option<Vector3<f64>>,
    /// Median angle in pixels between a right bearing and its left bearing
    /// rotated by the best rotation-only fit.
    pub parallax_px: f64,
}

/// RANSAC to the bound, then [`Ransac::finish`].
pub fn estimate_two_view<R: Rng + ?Sized>(
    matches: &[Correspondence],
    k: &Intrinsics,
    config: RansacConfig,
    rng: &mut R,
) -> Result<TwoViewEstimate, VisionError> {
    let mut ransac = Ransac::new(matches, k, config)?;
    ransac.run(rng);
    ransac.finish()
}

/// `count` distinct indices below `n`, by rejection (`count` is 5 or 8, `n` at
/// least `count`), in the first `size` entries of an array: no allocation.
fn distinct_indices<R: Rng + ?Sized>(
    rng: &mut R,
    n: usize,
    count: usize,
) -> ([usize; EIGHT], usize) {
    let mut out = [0; EIGHT];
    let count = count.min(EIGHT);
    if n < count {
        for (i, slot) in out.iter_mut().enumerate().take(n) {
            *slot = i;
        }
        return (out, n);
    }
    let mut size = 0;
    while size < count {
        let i = rng.random_range(0..n);
        if !out[..size].contains(&i) {
            out[size] = i;
            size += 1;
        }
    }
    (out, size)
}

/// What [`Ransac::draw`] did with one sample.
struct Drawn {
    sample: [usize; EIGHT],
    size: usize,
    hypotheses: usize,
    inliers: usize,
    improved: bool,
}

fn select(points: &[Vector3<f64>], mask: &[bool]) -> Vec<Vector3<f64>> {
    points
        .iter()
        .zip(mask)
        .filter(|(_, keep)| **keep)
        .map(|(p, _)| *p)
        .collect()
}

/// The rotation that best maps left bearings onto right ones (Kabsch / Wahba:
/// `R = U diag(1, 1, det(U Vᵀ)) Vᵀ` from the SVD of `Σ b_r b_lᵀ`) and the median
/// angle between `R b_l` and `b_r`, times the focal length (pixels): the parallax
/// a rotation cannot explain.
pub fn rotation_only_fit(
    left: &[Vector3<f64>],
    right: &[Vector3<f64>],
    focal_px: f64,
) -> (Matrix3<f64>, f64) {
    let mut h = Matrix3::zeros();
    for (l, r) in left.iter().zip(right) {
        h += r.normalize() * l.normalize().transpose();
    }
    let Some(mut rotation) = kabsch(&h) else {
        return (Matrix3::identity(), f64::INFINITY);
    };
    let residuals = |rotation: &Matrix3<f64>| -> Vec<f64> {
        left.iter()
            .zip(right)
            .map(|(l, r)| super::angle_between(&(rotation * l), r) * focal_px)
            .collect()
    };
    // Matches that fit the essential matrix may still be wrong: refit twice on
    // the matches within three times the median residual.
    for _ in 0..2 {
        let current = residuals(&rotation);
        let cut = 3.0 * median(current.clone());
        let mut h = Matrix3::zeros();
        for ((l, r), e) in left.iter().zip(right).zip(&current) {
            if *e <= cut {
                h += r.normalize() * l.normalize().transpose();
            }
        }
        match kabsch(&h) {
            Some(r) => rotation = r,
            None => break,
        }
    }
    (rotation, median(residuals(&rotation)))
}

/// The rotation `U diag(1, 1, det(U Vᵀ)) Vᵀ` of the SVD of `H = Σ b_r b_lᵀ`.
fn kabsch(h: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let (u, _, v_t) = svd3(h)?;
    let d = (u * v_t).determinant().signum();
    Some(u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * v_t)
}

/// The median (upper middle), infinity for no values.
fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return f64::INFINITY;
    }
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}
