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
//!
//! Optionally ([`EarlyRejection::Sprt`]) each hypothesis is verified by Wald's
//! sequential probability ratio test as Matas and Chum ("Randomized RANSAC with
//! Sequential Probability Ratio Test", ICCV 2005; Chum and Matas, "Optimal
//! Randomized RANSAC", PAMI 2008) do it: the matches are checked in a random
//! order and a hypothesis is rejected as soon as the evidence says it is bad,
//! usually after a dozen matches instead of all of them. See [`Sprt`].

use nalgebra::{Matrix3, Vector3};
use rand::Rng;
use serde::{Deserialize, Serialize};

use super::decompose::RelativePose;
use super::decompose::{Decomposition, choose_by_cheirality};
use super::eight_point::{EIGHT, essential_from_fundamental, fundamental_eight_point, svd3};
use super::five_point::{FIVE, MAX_SOLUTIONS, essential_five_point_array};
use super::refine::{FULL, Stop, essential_of_pose, refine_pose_until};
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
    /// Whether a hypothesis may be rejected before all matches are checked.
    #[serde(default)]
    pub early_rejection: EarlyRejection,
    /// The SPRT's costs and starting guesses (used with [`EarlyRejection::Sprt`]).
    #[serde(default)]
    pub sprt: SprtSettings,
    /// After the linear refit, refine `(R, t)` by Levenberg-Marquardt on the
    /// Sampson distances of the inliers ([`super::refine`]), with the inlier
    /// band narrowed from 3τ to τ ([`REFINE_BANDS`]); the eight-point method
    /// also ends each local optimization so ([`Ransac::lo_trigger`]). On by
    /// default; off, the estimate is linear throughout.
    #[serde(default = "default_refine")]
    pub refine: bool,
}

fn default_refine() -> bool {
    true
}

/// The inlier bands of the refinement, as multiples of the threshold τ: the
/// pose is refined on the matches within 3τ, then 2.5τ, 2τ, 1.5τ, and within
/// τ until the inliers stop changing (at most [`REFINE_FINAL_ROUNDS`] times).
/// This is the "iterative" local optimization of Chum, Matas and Kittler
/// ("Locally optimized RANSAC", 2003: least squares on the matches within
/// K·θ, K falling to 1). On the seeded trials of
/// `docs/visual-odometry.md` a refinement on the τ-inliers alone stays in the
/// basin of the linear estimate, whose inliers exclude a tenth of the right
/// matches: one pass leaves 96 of 100 five-point runs and 92 of 100
/// eight-point runs within 1°, repeated until the τ-inliers settle 100 and
/// 95; with the wider bands first, 100 and 99.
pub const REFINE_BANDS: [f64; 4] = [3.0, 2.5, 2.0, 1.5];

/// At most this many refinements within τ after [`REFINE_BANDS`].
pub const REFINE_FINAL_ROUNDS: usize = 5;

/// How a hypothesis is verified.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum EarlyRejection {
    /// Every hypothesis is checked against every match (the thesis's RANSAC).
    #[default]
    None,
    /// Wald's sequential probability ratio test (Matas and Chum 2005): a
    /// hypothesis is rejected once the likelihood ratio of "bad" to "good"
    /// exceeds the threshold A.
    Sprt,
}

impl EarlyRejection {
    /// The name used in URLs, flags and JSON.
    pub fn name(self) -> &'static str {
        match self {
            EarlyRejection::None => "none",
            EarlyRejection::Sprt => "sprt",
        }
    }

    /// Parses [`EarlyRejection::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "none" => Some(EarlyRejection::None),
            "sprt" => Some(EarlyRejection::Sprt),
            _ => None,
        }
    }
}

/// The SPRT's parameters (Chum and Matas 2008, Sec. 3): the two costs that fix
/// the threshold A and the starting guesses of ε and δ, which the run then
/// estimates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SprtSettings {
    /// `t_M`: the time to compute one sample's hypotheses, in units of the
    /// time to check one match against one hypothesis. `None`: the method's
    /// measured default ([`SprtSettings::model_time_for`]).
    pub model_time: Option<f64>,
    /// `m_S`: hypotheses per sample on average. `None`: the method's default.
    pub models_per_sample: Option<f64>,
    /// ε before the first hypothesis is accepted: the share of matches a good
    /// hypothesis agrees with (then the best consensus share).
    pub initial_inlier_ratio: f64,
    /// δ before the first rejection: the share of matches a bad hypothesis
    /// agrees with (then the mean over the rejected hypotheses).
    pub initial_bad_agreement: f64,
}

impl Default for SprtSettings {
    fn default() -> Self {
        Self {
            model_time: None,
            models_per_sample: None,
            initial_inlier_ratio: 0.1,
            initial_bad_agreement: 0.05,
        }
    }
}

impl SprtSettings {
    /// `t_M` for `method`: the given value or the measured default. One
    /// eight-point sample's solver takes about 1 µs and one Sampson check
    /// about 3 ns (2-core Xeon VM, 2026-11-26: `docs/visual-odometry.md`), so
    /// 330; one five-point sample's solver about 8 µs, so 2,700.
    pub fn model_time_for(&self, method: Method) -> f64 {
        self.model_time
            .filter(|t| t.is_finite() && *t > 0.0)
            .unwrap_or(match method {
                Method::EightPoint => 330.0,
                Method::FivePoint => 2700.0,
            })
    }

    /// `m_S` for `method`: the given value or the default: 1 for the
    /// eight-point solver, 4 for the five-point (its mean number of real
    /// solutions on the benchmark's scene is 3.9).
    pub fn models_per_sample_for(&self, method: Method) -> f64 {
        self.models_per_sample
            .filter(|m| m.is_finite() && *m > 0.0)
            .unwrap_or(match method {
                Method::EightPoint => 1.0,
                Method::FivePoint => 4.0,
            })
    }
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
            early_rejection: EarlyRejection::None,
            sprt: SprtSettings::default(),
            refine: true,
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
    /// With [`EarlyRejection::Sprt`]: the test this sample's hypotheses went
    /// through and what it decided for each.
    pub sprt: Option<SprtSample>,
}

/// One sample under the SPRT: the test's design and each hypothesis's check.
#[derive(Debug, Clone, PartialEq)]
pub struct SprtSample {
    /// ε of the test: the share of matches a good hypothesis agrees with.
    pub epsilon: f64,
    /// δ of the test: the share of matches a bad hypothesis agrees with.
    pub delta: f64,
    /// The threshold A (infinite when ε ≤ δ: the test cannot tell).
    pub threshold: f64,
    /// Each hypothesis's check, in the solver's order.
    pub checks: Vec<SprtCheck>,
}

/// What the SPRT did with one hypothesis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SprtCheck {
    /// Matches checked before the decision (all of them when accepted).
    pub evaluated: usize,
    /// Of those, how many agree with the hypothesis (its inliers when accepted).
    pub consistent: usize,
    /// Whether the hypothesis was rejected before the last match.
    pub rejected: bool,
}

/// Counts over one run of the SPRT.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SprtStats {
    /// Hypotheses tested.
    pub tested: usize,
    /// Of those, rejected early.
    pub rejected: usize,
    /// Matches checked by the rejected hypotheses, summed.
    pub evaluated_in_rejected: usize,
    /// Matches checked by every hypothesis, summed.
    pub evaluated: usize,
    /// Tests designed (a new A each time ε or δ changed).
    pub designs: usize,
}

impl SprtStats {
    /// Mean matches checked by a rejected hypothesis (0 without rejections).
    pub fn mean_evaluated_when_rejected(&self) -> f64 {
        if self.rejected == 0 {
            0.0
        } else {
            self.evaluated_in_rejected as f64 / self.rejected as f64
        }
    }
}

/// The SPRT's threshold A (Matas and Chum 2005, the optimal A; Chum and Matas
/// 2008): the A that minimises the expected time of the whole run satisfies
/// `A = K₁/K₂ + 1 + ln A` with `K₁/K₂ = t_M · C / m_S`, where
/// `C = (1 − δ) ln((1 − δ)/(1 − ε)) + δ ln(δ/ε)` is the expected gain of
/// `ln λ` per match checked against a bad hypothesis (the Kullback-Leibler
/// divergence of the two Bernoulli distributions). Solved by the fixed-point
/// iteration `A₀ = K₁/K₂ + 1`, `Aₙ₊₁ = K₁/K₂ + 1 + ln Aₙ` (its slope `1/A` is
/// below 1, so it converges in a few steps). Infinite (no rejection) when
/// `ε ≤ δ`: then agreeing with a match is no evidence of a good hypothesis.
pub fn sprt_threshold(epsilon: f64, delta: f64, model_time: f64, models_per_sample: f64) -> f64 {
    let epsilon = epsilon.clamp(1e-9, 1.0 - 1e-9);
    let delta = delta.clamp(1e-9, 1.0 - 1e-9);
    if !(epsilon > delta) || !(model_time > 0.0) || !(models_per_sample > 0.0) {
        return f64::INFINITY;
    }
    let c = (1.0 - delta) * crate::math::ln((1.0 - delta) / (1.0 - epsilon))
        + delta * crate::math::ln(delta / epsilon);
    let k = model_time * c / models_per_sample;
    if !k.is_finite() {
        return f64::INFINITY;
    }
    let mut a = k + 1.0;
    for _ in 0..100 {
        let next = k + 1.0 + crate::math::ln(a);
        let converged = (next - a).abs() < 1e-9 * a;
        a = next;
        if converged {
            break;
        }
    }
    a
}

/// The SPRT's state during one run (Matas and Chum 2005, Alg. 1; Chum and
/// Matas 2008, R-RANSAC with SPRT).
///
/// A hypothesis is checked against the matches in a random order (one
/// shuffle per run, a random starting point per hypothesis). After each match
/// the likelihood ratio of "the hypothesis is bad" to "it is good" is updated,
///
/// `λⱼ = λⱼ₋₁ · δ/ε` when match j agrees with it, `λⱼ = λⱼ₋₁ · (1 − δ)/(1 − ε)`
/// when not,
///
/// where ε is the share of matches a good hypothesis agrees with (estimated
/// as the best consensus share so far) and δ the share a bad one agrees with
/// (estimated as the mean share among the hypotheses rejected so far). The
/// hypothesis is rejected once `λⱼ > A` ([`sprt_threshold`]); one that
/// survives every match is accepted, and its count is exact. A good
/// hypothesis is rejected with probability about `1/A`, which the stopping
/// rule pays for: after `kᵢ` samples under tests with thresholds `Aᵢ`, no
/// all-inlier sample has been accepted with probability
///
/// `η = Πᵢ (1 − P_g (1 − 1/Aᵢ))^kᵢ`, `P_g = εˢ`,
///
/// and RANSAC stops when `η ≤ 1 − p` (Chum and Matas 2008, the stopping rule
/// with a test redesigned whenever ε or δ changes; with no rejection,
/// `1/A = 0`, it is the adaptive bound of [`adaptive_bound`]).
/// SLAM Lab computes `ln λ`, adding `ln(δ/ε)` or `ln((1 − δ)/(1 − ε))`.
#[derive(Debug, Clone, PartialEq)]
pub struct Sprt {
    epsilon: f64,
    delta: f64,
    threshold: f64,
    log_threshold: f64,
    log_consistent: f64,
    log_inconsistent: f64,
    model_time: f64,
    models_per_sample: f64,
    /// `(Aᵢ, kᵢ)` of the tests before the current one.
    history: Vec<(f64, usize)>,
    /// The last [`Sprt::bound`] and what it was computed from (`w`'s bits,
    /// `s`, `p`'s bits, the cap, the tests closed): the bound changes only
    /// when one of them does, and its sum over the closed tests costs a
    /// logarithm per test, so it is not recomputed after every sample.
    bound_cache: Option<(BoundKey, usize)>,
    /// Samples drawn before the current test was designed.
    design_start: usize,
    /// The sum and number of the consistent shares of rejected hypotheses: δ̂.
    delta_sum: f64,
    delta_count: usize,
    stats: SprtStats,
}

/// δ is re-estimated after every rejection; a new test is designed when the
/// estimate moves by more than this share of the δ in use (Matas and Chum
/// 2005 use 5 %).
const DELTA_CHANGE: f64 = 0.05;

impl Sprt {
    fn new(settings: &SprtSettings, method: Method) -> Self {
        let mut sprt = Self {
            epsilon: settings.initial_inlier_ratio,
            delta: settings.initial_bad_agreement,
            threshold: f64::INFINITY,
            log_threshold: f64::INFINITY,
            log_consistent: 0.0,
            log_inconsistent: 0.0,
            model_time: settings.model_time_for(method),
            models_per_sample: settings.models_per_sample_for(method),
            history: Vec::new(),
            bound_cache: None,
            design_start: 0,
            delta_sum: 0.0,
            delta_count: 0,
            stats: SprtStats::default(),
        };
        sprt.design(
            finite_or(settings.initial_inlier_ratio, 0.1),
            finite_or(settings.initial_bad_agreement, 0.05),
        );
        sprt
    }

    /// ε in use.
    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }

    /// δ in use.
    pub fn delta(&self) -> f64 {
        self.delta
    }

    /// The threshold A in use.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// The counts so far.
    pub fn stats(&self) -> SprtStats {
        self.stats
    }

    /// A new test for ε and δ: A and the two steps of `ln λ`.
    fn design(&mut self, epsilon: f64, delta: f64) {
        self.epsilon = epsilon.clamp(1e-6, 1.0 - 1e-6);
        self.delta = delta.clamp(1e-3, 0.5);
        self.threshold = sprt_threshold(
            self.epsilon,
            self.delta,
            self.model_time,
            self.models_per_sample,
        );
        self.log_threshold = crate::math::ln(self.threshold);
        self.log_consistent = crate::math::ln(self.delta / self.epsilon);
        self.log_inconsistent = crate::math::ln((1.0 - self.delta) / (1.0 - self.epsilon));
        self.stats.designs += 1;
    }

    /// Closes the current test after `iteration` samples and designs the next.
    fn redesign(&mut self, iteration: usize, epsilon: f64, delta: f64) {
        self.history
            .push((self.threshold, iteration - self.design_start));
        self.design_start = iteration;
        self.design(epsilon, delta);
    }

    /// Counts one check and updates δ̂ with a rejected hypothesis's share.
    fn record(&mut self, check: &SprtCheck) {
        self.stats.tested += 1;
        self.stats.evaluated += check.evaluated;
        if check.rejected {
            self.stats.rejected += 1;
            self.stats.evaluated_in_rejected += check.evaluated;
            self.delta_sum += check.consistent as f64 / check.evaluated.max(1) as f64;
            self.delta_count += 1;
        }
    }

    /// After sample `iteration`: a new ε when a new best was found (its
    /// consensus share `best_share`), a new δ when δ̂ moved by more than 5 %.
    fn after_sample(&mut self, iteration: usize, best_share: Option<f64>) {
        let mut epsilon = self.epsilon;
        let mut delta = self.delta;
        let mut changed = false;
        if let Some(w) = best_share {
            epsilon = w;
            changed = true;
        }
        if self.delta_count > 0 {
            let estimate = self.delta_sum / self.delta_count as f64;
            if (estimate - self.delta).abs() > DELTA_CHANGE * self.delta {
                delta = estimate;
                changed = true;
            }
        }
        if changed {
            self.redesign(iteration, epsilon, delta);
        }
    }

    /// The number of samples after which `η ≤ 1 − p` for a consensus share
    /// `w` (so `P_g = wˢ`), capped at `max`.
    fn bound(&mut self, w: f64, sample_size: usize, confidence: f64, max: usize) -> usize {
        let key = (
            w.to_bits(),
            sample_size,
            confidence.to_bits(),
            max,
            self.history.len(),
        );
        if let Some((cached, bound)) = self.bound_cache
            && cached == key
        {
            return bound;
        }
        let bound = self.bound_uncached(w, sample_size, confidence, max);
        self.bound_cache = Some((key, bound));
        bound
    }

    /// [`Sprt::bound`] computed.
    fn bound_uncached(&self, w: f64, sample_size: usize, confidence: f64, max: usize) -> usize {
        let p_good = crate::math::powf(w.clamp(0.0, 1.0), sample_size as f64);
        let p = confidence.clamp(0.0, 1.0 - 1e-12);
        let per_sample = |a: f64| crate::math::ln_1p(-p_good * (1.0 - 1.0 / a));
        let spent: f64 = self
            .history
            .iter()
            .map(|&(a, k)| k as f64 * per_sample(a))
            .sum();
        let step = per_sample(self.threshold);
        if !(step < 0.0) {
            return max;
        }
        let remaining = (crate::math::ln(1.0 - p) - spent) / step;
        if !remaining.is_finite() {
            return max;
        }
        let total = self.design_start as f64 + remaining.max(0.0).ceil();
        if total > max as f64 {
            max
        } else {
            (total as usize).max(1)
        }
    }
}

/// What [`Sprt::bound`] depends on: `w`'s bits, `s`, `p`'s bits, the cap and
/// the number of closed tests (a new test changes A and the design's start).
type BoundKey = (u64, usize, u64, usize, usize);

fn finite_or(value: f64, default: f64) -> f64 {
    if value.is_finite() { value } else { default }
}

/// Upper limit on the refits of one local optimization. It stops earlier, as
/// soon as a refit no longer lowers the truncated cost; on 500 matches with half
/// of them wrong a new best from a noisy eight-point sample takes up to ten
/// refits to gather the inliers (101, 134, 152, 176, 182, 207, 210, 216, 218,
/// 221 for the benchmark's scene), and stopping after three left the best at
/// 176, the adaptive bound at its cap.
const LO_MAX_ROUNDS: usize = 20;

/// How the refinement inside the eight-point method's local optimization
/// runs ([`Ransac::essential_optimized`]): on the matches within 3τ, then 2τ,
/// then within τ until the inliers stop changing (at most twice), each band's
/// Levenberg-Marquardt stopped once a step lowers the cost by less than a
/// relative 1e-4 or after 10 iterations. Local optimization only needs the
/// pose close enough to sort the matches into inliers, and it runs at every
/// new best sample hypothesis (about ten times a run); the refinement that
/// ends the run keeps [`REFINE_BANDS`] and goes on to a relative 1e-12
/// ([`FULL`]). Measured on the 1,000 seeded trials of
/// `docs/visual-odometry.md` (with [`LO_LINEAR_ROUNDS`]): 996 of 1,000 within
/// 1° (999 with the SPRT), against 994 (995) with the end's full schedule and
/// 20 eight-point refits before it, which took 40 % more time.
const LO_SCHEDULE: Schedule = Schedule {
    bands: &[3.0, 2.0],
    final_rounds: 2,
    stop: Stop {
        relative_decrease: 1e-4,
        max_iterations: 10,
    },
};

/// The refinement that ends the run ([`Ransac::refined`]).
const FINAL_SCHEDULE: Schedule = Schedule {
    bands: &REFINE_BANDS,
    final_rounds: REFINE_FINAL_ROUNDS,
    stop: FULL,
};

/// With the refinement on, the eight-point method's local optimization refits
/// F at most this many times before refining on the essential constraint: the
/// refits only gather a start for it.
const LO_LINEAR_ROUNDS: usize = 3;

/// The bands of a refinement (multiples of τ), the rounds within τ after
/// them, and when each band's Levenberg-Marquardt stops.
#[derive(Debug, Clone, Copy)]
struct Schedule {
    bands: &'static [f64],
    final_rounds: usize,
    stop: Stop,
}

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
    /// The most inliers of a sample's own hypothesis so far, before local
    /// optimization: with the eight-point method a sample's hypothesis is
    /// locally optimized when it beats this ([`Ransac::lo_trigger`]).
    best_sample_inliers: usize,
    /// The SPRT's state, with [`EarlyRejection::Sprt`].
    sprt: Option<Sprt>,
    /// The order in which the SPRT checks matches: the pixels (left x, left
    /// y, right x, right y), shuffled by the run's generator at its first sample.
    shuffled: Vec<[f64; 4]>,
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
            best_sample_inliers: 0,
            sprt: match config.early_rejection {
                EarlyRejection::None => None,
                EarlyRejection::Sprt => Some(Sprt::new(&config.sprt, config.method)),
            },
            shuffled: Vec::new(),
        })
    }

    /// The SPRT's state, with [`EarlyRejection::Sprt`].
    pub fn sprt(&self) -> Option<&Sprt> {
        self.sprt.as_ref()
    }

    /// The SPRT's check of `f`, starting at position `start` of the shuffled
    /// order and going round: `ln λ` grows by `ln((1 − δ)/(1 − ε))` for a
    /// match that disagrees and by `ln(δ/ε)` (negative) for one that agrees;
    /// the hypothesis is rejected as soon as `ln λ > ln A`. Without the SPRT
    /// (or before the first sample has shuffled the matches) every match is
    /// checked.
    pub fn sprt_check(&self, f: &Matrix3<f64>, start: usize) -> SprtCheck {
        let test = SampsonTest::new(f, self.config.threshold_px);
        let (Some(sprt), false) = (&self.sprt, self.shuffled.is_empty()) else {
            let (_, consistent) = self.classify(f);
            return SprtCheck {
                evaluated: self.matches.len(),
                consistent,
                rejected: false,
            };
        };
        let n = self.shuffled.len();
        let start = start % n;
        let (after, before) = self.shuffled.split_at(start);
        let mut log_lambda = 0.0;
        let mut consistent = 0;
        for (j, &[x, y, u, v]) in before.iter().chain(after).enumerate() {
            let agrees = test.inlier_at(x, y, u, v);
            consistent += usize::from(agrees);
            log_lambda += if agrees {
                sprt.log_consistent
            } else {
                sprt.log_inconsistent
            };
            if log_lambda > sprt.log_threshold {
                return SprtCheck {
                    evaluated: j + 1,
                    consistent,
                    rejected: true,
                };
            }
        }
        SprtCheck {
            evaluated: n,
            consistent,
            rejected: false,
        }
    }

    /// Shuffles the matches for the SPRT (Fisher-Yates with the run's generator).
    fn shuffle_for_sprt<R: Rng + ?Sized>(&mut self, rng: &mut R) {
        let mut order: Vec<[f64; 4]> = self
            .matches
            .iter()
            .map(|m| [m.left.x, m.left.y, m.right.x, m.right.y])
            .collect();
        for i in (1..order.len()).rev() {
            let j = rng.random_range(0..=i);
            order.swap(i, j);
        }
        self.shuffled = order;
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
            sprt: drawn.design.map(|(epsilon, delta, threshold)| SprtSample {
                epsilon,
                delta,
                threshold,
                checks: drawn.checks[..drawn.hypotheses].to_vec(),
            }),
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
        if self.sprt.is_some() && self.shuffled.is_empty() {
            self.shuffle_for_sprt(rng);
        }
        self.iteration += 1;
        let n = self.matches.len();
        let (sample, size) = distinct_indices(rng, n, self.config.method.sample_size());
        let (hypotheses, count) = self.hypotheses_array(&sample[..size]);
        let design = self
            .sprt
            .as_ref()
            .map(|sprt| (sprt.epsilon, sprt.delta, sprt.threshold));
        let mut checks = [SprtCheck::default(); MAX_SOLUTIONS];
        // The sample's best hypothesis: the most inliers, a tie broken by the
        // lower truncated cost. Only it is locally optimized, and only if it
        // beats the best so far (LO-RANSAC; for the eight-point method the
        // best sample hypothesis so far: `lo_trigger`), so the outcome does
        // not depend on the order in which the solver returns its (up to ten)
        // hypotheses.
        let trigger = self.lo_trigger();
        let mut sample_best: usize = 0;
        let mut chosen: Option<&Matrix3<f64>> = None;
        for (f, check) in hypotheses[..count].iter().zip(&mut checks) {
            let inliers = if self.sprt.is_some() {
                // The SPRT decides alone, in both modes: a hypothesis it
                // accepts has seen every match, so its count is exact.
                *check = self.sprt_check(f, rng.random_range(0..n));
                if check.rejected {
                    continue;
                }
                check.consistent
            } else {
                // A count above `beat` is exact; below it a hypothesis can
                // neither beat the best so far nor tie this sample's best.
                let beat = if exact {
                    0
                } else {
                    trigger.max(sample_best.saturating_sub(1))
                };
                self.count_inliers(f, beat)
            };
            if inliers > trigger {
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
        let mut improved = false;
        if let Some(f) = chosen {
            let (inliers, count) = self.classify(f);
            self.best_sample_inliers = count;
            let optimized = self.locally_optimized(Best {
                fundamental: *f,
                inliers,
                count,
            });
            // Five-point: the sample beat the best, so its optimized model
            // (never fewer inliers) does too. Eight-point: the sample beat the
            // best sample so far, and its optimized model may or may not beat
            // the best model.
            improved = match &self.best {
                None => true,
                Some(b) => self.beats(&optimized, b),
            };
            if improved {
                self.best = Some(optimized);
            }
        }
        let w = self.best_inliers() as f64 / n as f64;
        let max = self.config.max_iterations.max(1);
        let s = self.config.method.sample_size();
        if let Some(sprt) = &mut self.sprt {
            for check in &checks[..count] {
                sprt.record(check);
            }
            sprt.after_sample(self.iteration, improved.then_some(w));
            if self.best.is_some() {
                // A changes with ε and δ, so the bound is recomputed after
                // every sample and may rise as well as fall.
                self.bound = sprt.bound(w, s, self.config.confidence, max);
            }
        } else if improved {
            let bound = adaptive_bound(w, s, self.config.confidence, max);
            self.bound = self.bound.min(bound);
        }
        Some(Drawn {
            sample,
            size,
            hypotheses: count,
            inliers: sample_best,
            improved,
            design,
            checks,
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
        let essential_after = self.config.method == Method::EightPoint && self.config.refine;
        let rounds = if essential_after {
            LO_LINEAR_ROUNDS
        } else {
            LO_MAX_ROUNDS
        };
        for _ in 0..rounds {
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
        if essential_after
            && let Some(essential) = self.essential_optimized(&best)
            && self.beats(&essential, &best)
        {
            best = essential;
        }
        best
    }

    /// RANSAC's order of models: more inliers, a tie broken by the lower
    /// truncated cost.
    fn beats(&self, a: &Best, b: &Best) -> bool {
        a.count > b.count
            || (a.count == b.count
                && self.truncated_cost(&a.fundamental) < self.truncated_cost(&b.fundamental))
    }

    /// The inlier count a sample's hypothesis must beat to be locally
    /// optimized. Five-point: the best model's (LO-RANSAC's rule: a new best
    /// is optimized). Eight-point: the best *sample hypothesis* so far
    /// (before optimization). Its local optimization (with the refinement on)
    /// ends on the essential manifold ([`Ransac::essential_optimized`]) and
    /// can lift a model well
    /// above what any minimal, noisy F reaches: on the seeded trials of
    /// `docs/visual-odometry.md` the hypotheses of all-inlier samples keep
    /// 10-80 of about 90 inliers, and a model optimized into a wrong basin
    /// (57 of 92 inliers, 3° off) would otherwise outrank every later sample,
    /// so the good samples drawn after it were never optimized.
    fn lo_trigger(&self) -> usize {
        match self.config.method {
            Method::EightPoint => self.best_sample_inliers,
            Method::FivePoint => self.best_inliers(),
        }
    }

    /// The eight-point method's local optimization on the essential
    /// constraint, with [`RansacConfig::refine`]: the F refitted by [`Ransac::locally_optimized`] projected
    /// onto the essential matrices, its `(R, t)` chosen by cheirality on the
    /// F's inliers, and refined by Levenberg-Marquardt on the Sampson
    /// distances with the inlier band narrowed from 3τ to τ
    /// ([`Ransac::refined_pose`], as at the end of the run). The F's eight
    /// degrees of freedom fit the noise of a minimal sample and of the
    /// partial inlier set it gathers; the essential matrix has five. As F in
    /// pixels, with its inliers; `None` when too few matches are left.
    fn essential_optimized(&self, best: &Best) -> Option<Best> {
        let essential = essential_from_fundamental(&best.fundamental, &self.k);
        let left = select(&self.left, &best.inliers);
        let right = select(&self.right, &best.inliers);
        let start = choose_by_cheirality(&essential, &left, &right)?.pose();
        let (pose, _, _) = self.refined_pose(&start, LO_SCHEDULE)?;
        let fundamental = fundamental_from_essential(&essential_of_pose(&pose), &self.k);
        let (inliers, count) = self.classify(&fundamental);
        Some(Best {
            fundamental,
            inliers,
            count,
        })
    }

    /// The Sampson RMS (pixels) of `f` over its τ-inliers, and how many.
    fn inlier_rms(&self, f: &Matrix3<f64>) -> (f64, usize) {
        let limit = self.config.threshold_px * self.config.threshold_px;
        let (sum, count) = self
            .matches
            .iter()
            .map(|m| sampson_squared(f, m))
            .filter(|d| *d <= limit)
            .fold((0.0, 0), |(sum, count), d| (sum + d, count + 1));
        ((sum / count.max(1) as f64).sqrt(), count)
    }

    /// The nonlinear refinement of `start` ([`super::refine::refine_pose`]):
    /// Levenberg-Marquardt on the matches within each band of
    /// [`REFINE_BANDS`] in turn, then within τ until the inliers stop
    /// changing. The refined pose is applied only when its truncated cost
    /// `Σ min(d², τ²)` over all matches is lower than the linear estimate's
    /// (as an essential matrix). `None` when a band holds fewer than five
    /// matches.
    fn refined(&self, start: &RelativePose) -> Option<(RelativePose, RefinementSummary)> {
        let fundamental_of =
            |pose: &RelativePose| fundamental_from_essential(&essential_of_pose(pose), &self.k);
        let linear = fundamental_of(start);
        let (rms_before_px, inliers_before) = self.inlier_rms(&linear);
        let (pose, steps, rounds) = self.refined_pose(start, FINAL_SCHEDULE)?;
        let refined = fundamental_of(&pose);
        let (rms_after_px, inliers_after) = self.inlier_rms(&refined);
        let applied = self.truncated_cost(&refined) < self.truncated_cost(&linear);
        Some((
            pose,
            RefinementSummary {
                rms_before_px,
                rms_after_px,
                inliers_before,
                inliers_after,
                steps,
                rounds,
                applied,
            },
        ))
    }

    /// The refined pose, with the Levenberg-Marquardt steps taken and the
    /// rounds run: the bands of `schedule` ([`REFINE_BANDS`] at the end of
    /// the run), then τ until the inliers stop changing. `None` when a band
    /// holds fewer than five matches.
    fn refined_pose(
        &self,
        start: &RelativePose,
        schedule: Schedule,
    ) -> Option<(RelativePose, usize, usize)> {
        let fundamental_of =
            |pose: &RelativePose| fundamental_from_essential(&essential_of_pose(pose), &self.k);
        let tau = self.config.threshold_px;
        let bands = schedule
            .bands
            .iter()
            .copied()
            .chain(std::iter::repeat_n(1.0, schedule.final_rounds));
        let mut pose = *start;
        let (mut steps, mut rounds) = (0, 0);
        let mut previous: Option<Vec<bool>> = None;
        let mut chosen = Vec::with_capacity(self.matches.len());
        for band in bands {
            let f = fundamental_of(&pose);
            let limit = (band * tau) * (band * tau);
            let mask: Vec<bool> = self
                .matches
                .iter()
                .map(|m| sampson_squared(&f, m) <= limit)
                .collect();
            if band == 1.0 && previous.as_ref() == Some(&mask) {
                break;
            }
            chosen.clear();
            chosen.extend(
                self.matches
                    .iter()
                    .zip(&mask)
                    .filter(|(_, inside)| **inside)
                    .map(|(m, _)| *m),
            );
            if chosen.len() < FIVE {
                return None;
            }
            let result = refine_pose_until(&pose, &chosen, &self.k, schedule.stop);
            pose = result.pose;
            steps += result.accepted_steps;
            rounds += 1;
            if band == 1.0 {
                previous = Some(mask);
            }
        }
        Some((pose, steps, rounds))
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
        // Compared as the essential matrices they end as: the eight-point
        // method's F (refit or best) is projected onto them below, and its
        // best may already be an essential matrix from local optimization.
        let as_essential = |f: &Matrix3<f64>| match self.config.method {
            Method::EightPoint => {
                fundamental_from_essential(&essential_from_fundamental(f, &self.k), &self.k)
            }
            Method::FivePoint => *f,
        };
        if let Some(refit) = self.refit(&inliers)
            && self.truncated_cost(&as_essential(&refit))
                < self.truncated_cost(&as_essential(&fundamental))
        {
            (inliers, count) = self.classify(&refit);
            fundamental = refit;
            refitted = true;
        }
        let mut essential = essential_from_fundamental(&fundamental, &self.k);
        let mut left: Vec<Vector3<f64>> = select(&self.left, &inliers);
        let mut right: Vec<Vector3<f64>> = select(&self.right, &inliers);
        let mut decomposition = choose_by_cheirality(&essential, &left, &right)
            .ok_or(VisionError::Degenerate("the essential matrix has no SVD"))?;
        let (rotation_only, parallax_px) = rotation_only_fit(&left, &right, self.k.fx);
        let mut refinement = None;
        let (motion, rotation, translation) = if parallax_px < self.config.min_parallax_px {
            (Motion::PureRotation, rotation_only, None)
        } else {
            let mut pose = decomposition.pose();
            if self.config.refine
                && let Some((refined, summary)) = self.refined(&pose)
            {
                refinement = Some(summary);
                if summary.applied {
                    pose = refined;
                    essential = essential_of_pose(&refined);
                    fundamental = fundamental_from_essential(&essential, &self.k);
                    (inliers, count) = self.classify(&fundamental);
                    left = select(&self.left, &inliers);
                    right = select(&self.right, &inliers);
                    if let Some(d) = choose_by_cheirality(&essential, &left, &right) {
                        decomposition = d;
                    }
                }
            }
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
            refinement,
            sprt: self.sprt.as_ref().map(Sprt::stats),
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
    /// eight-point method the estimated F, for the five-point `K⁻ᵀ E K⁻¹`;
    /// after a nonlinear refinement `K⁻ᵀ E K⁻¹` for both), for epipolar lines.
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
    /// The SPRT's counts, with [`EarlyRejection::Sprt`].
    pub sprt: Option<SprtStats>,
    /// What the nonlinear refinement did ([`RansacConfig::refine`]); `None`
    /// when it is off, for a pure rotation, or when too few matches were
    /// left to refine on.
    pub refinement: Option<RefinementSummary>,
}

/// The nonlinear refinement of [`Ransac::finish`], before and after.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefinementSummary {
    /// Sampson RMS (pixels) over the τ-inliers of the linear estimate (its
    /// E as F in pixels).
    pub rms_before_px: f64,
    /// The same for the refined pose.
    pub rms_after_px: f64,
    /// τ-inliers of the linear estimate's E.
    pub inliers_before: usize,
    /// τ-inliers of the refined pose's E.
    pub inliers_after: usize,
    /// Levenberg-Marquardt steps that lowered the cost, over all rounds.
    pub steps: usize,
    /// Refinements run (one per band).
    pub rounds: usize,
    /// Whether the refined pose replaced the linear one (its truncated cost
    /// over all matches is lower).
    pub applied: bool,
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
    /// `(ε, δ, A)` of the SPRT this sample went through.
    design: Option<(f64, f64, f64)>,
    checks: [SprtCheck; MAX_SOLUTIONS],
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
