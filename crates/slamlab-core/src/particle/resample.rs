//! Resamplers: draw `M` particle indices with probabilities given by normalized
//! weights.
//!
//! Every method here is unbiased (particle `i` gets `M wᵢ` copies on average);
//! they differ in how much the copy counts scatter around that mean, which is the
//! noise resampling adds to a filter:
//!
//! - **multinomial**: `M` independent draws (thesis `000` Algorithm 6, the "naive
//!   sampler"; its search loop is inverted in the text, the correct rule is the
//!   first `i` with `cᵢ ≥ r`, found here by binary search). Copy counts are
//!   binomial: variance `M wᵢ (1 − wᵢ)`.
//! - **low-variance** (systematic; thesis Algorithm 7, Probabilistic Robotics
//!   Table 4.4): one random offset `r ∈ [0, 1/M)`, then the points
//!   `r + m/M`. A particle gets `⌊M wᵢ⌋` or `⌈M wᵢ⌉` copies.
//! - **stratified**: one independent draw in each stratum `[m/M, (m+1)/M)`.
//! - **residual**: `⌊M wᵢ⌋` copies deterministically, the remaining
//!   `M − Σ⌊M wᵢ⌋` drawn multinomially from the residual weights.

use rand::Rng;
use serde::{Deserialize, Serialize};

/// Which resampling method to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Resampler {
    /// Independent draws (thesis Algorithm 6, corrected).
    Multinomial,
    /// One random offset and `M` evenly spaced pointers (thesis Algorithm 7).
    #[default]
    LowVariance,
    /// One draw per stratum of width `1/M`.
    Stratified,
    /// Deterministic integer parts, multinomial remainder.
    Residual,
}

impl Resampler {
    /// Every method, in the order the lessons list them.
    pub const ALL: [Resampler; 4] = [
        Resampler::Multinomial,
        Resampler::LowVariance,
        Resampler::Stratified,
        Resampler::Residual,
    ];

    /// The name used in URLs, CLI flags and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Resampler::Multinomial => "multinomial",
            Resampler::LowVariance => "low-variance",
            Resampler::Stratified => "stratified",
            Resampler::Residual => "residual",
        }
    }

    /// Parses a name as written by [`Resampler::name`].
    pub fn from_name(name: &str) -> Option<Resampler> {
        Resampler::ALL.into_iter().find(|r| r.name() == name)
    }
}

/// Draws `count` indices into `weights` (normalized: non-negative, summing to 1)
/// with `method`, writing them to `out` in increasing order.
///
/// Weights that do not sum exactly to one (rounding) are handled: the pointers
/// run over `[0, Σw)`. An empty or all-zero weight vector gives uniform indices,
/// so a caller never ends up with an empty particle set.
pub fn resample_indices<R: Rng + ?Sized>(
    method: Resampler,
    weights: &[f64],
    count: usize,
    rng: &mut R,
    out: &mut Vec<usize>,
) {
    out.clear();
    if count == 0 {
        return;
    }
    let total: f64 = weights.iter().copied().filter(|w| *w > 0.0).sum();
    if weights.is_empty() || !(total > 0.0) || !total.is_finite() {
        let n = weights.len().max(1);
        out.extend((0..count).map(|m| m * n / count));
        return;
    }
    match method {
        Resampler::Multinomial => {
            let cumulative = cumulative_sum(weights);
            let mut draws: Vec<f64> = (0..count).map(|_| rng.random::<f64>() * total).collect();
            draws.sort_by(f64::total_cmp);
            walk_pointers(&cumulative, draws.into_iter(), out);
        }
        Resampler::LowVariance => {
            let cumulative = cumulative_sum(weights);
            let step = total / count as f64;
            let offset = rng.random::<f64>() * step;
            walk_pointers(
                &cumulative,
                (0..count).map(|m| offset + m as f64 * step),
                out,
            );
        }
        Resampler::Stratified => {
            let cumulative = cumulative_sum(weights);
            let step = total / count as f64;
            let pointers: Vec<f64> = (0..count)
                .map(|m| (m as f64 + rng.random::<f64>()) * step)
                .collect();
            walk_pointers(&cumulative, pointers.into_iter(), out);
        }
        Resampler::Residual => {
            let mut residual = Vec::with_capacity(weights.len());
            for (i, &w) in weights.iter().enumerate() {
                let expected = positive(w) / total * count as f64;
                // A product that is an integer up to rounding (M × 1/M) counts
                // whole, so every particle gets at least ⌊M w⌋ copies.
                let copies = (expected + 1e-9).floor();
                out.extend(std::iter::repeat_n(i, copies as usize));
                residual.push((expected - copies).max(0.0));
            }
            let remaining = count.saturating_sub(out.len());
            if remaining > 0 {
                let mut rest = Vec::with_capacity(remaining);
                resample_indices(Resampler::Multinomial, &residual, remaining, rng, &mut rest);
                out.extend(rest);
                out.sort_unstable();
            }
            out.truncate(count);
        }
    }
}

fn positive(w: f64) -> f64 {
    if w > 0.0 && w.is_finite() { w } else { 0.0 }
}

/// `cᵢ = Σ_{j ≤ i} wⱼ`, negative and NaN weights counted as zero.
fn cumulative_sum(weights: &[f64]) -> Vec<f64> {
    let mut sum = 0.0;
    weights
        .iter()
        .map(|&w| {
            sum += positive(w);
            sum
        })
        .collect()
}

/// For each pointer (in increasing order), the first index `i` with `cᵢ > r`
/// (so zero-weight particles are never chosen); pointers past the end, which
/// rounding can produce, take the last particle with positive weight.
fn walk_pointers(cumulative: &[f64], pointers: impl Iterator<Item = f64>, out: &mut Vec<usize>) {
    let last_positive = cumulative
        .iter()
        .enumerate()
        .rev()
        .find(|(i, c)| **c > if *i == 0 { 0.0 } else { cumulative[i - 1] })
        .map_or(0, |(i, _)| i);
    let mut i = 0;
    for r in pointers {
        while i < cumulative.len() && cumulative[i] <= r {
            i += 1;
        }
        out.push(i.min(last_positive));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn copies(
        method: Resampler,
        weights: &[f64],
        count: usize,
        rng: &mut ChaCha8Rng,
    ) -> Vec<usize> {
        let mut idx = Vec::new();
        resample_indices(method, weights, count, rng, &mut idx);
        assert_eq!(idx.len(), count);
        assert!(idx.windows(2).all(|w| w[0] <= w[1]), "indices in order");
        let mut c = vec![0; weights.len()];
        for i in idx {
            c[i] += 1;
        }
        c
    }

    #[test]
    fn every_method_is_unbiased_and_low_variance_has_the_least_spread() {
        let weights = [0.5, 0.25, 0.125, 0.0625, 0.0625, 0.0];
        let m = 10;
        let trials = 20_000;
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut variances = Vec::new();
        for method in Resampler::ALL {
            let mut sum = [0.0; 6];
            let mut sum_sq = [0.0; 6];
            for _ in 0..trials {
                for (i, c) in copies(method, &weights, m, &mut rng)
                    .into_iter()
                    .enumerate()
                {
                    sum[i] += c as f64;
                    sum_sq[i] += (c * c) as f64;
                }
            }
            let mut total_var = 0.0;
            for i in 0..6 {
                let mean = sum[i] / trials as f64;
                let expected = m as f64 * weights[i];
                // Standard error of the mean is at most sqrt(M w (1-w) / trials) < 0.012.
                assert!(
                    (mean - expected).abs() < 0.05,
                    "{method:?} particle {i}: {mean} vs {expected}"
                );
                total_var += sum_sq[i] / trials as f64 - mean * mean;
            }
            assert_eq!(sum[5], 0.0, "{method:?} chose a particle of weight zero");
            variances.push((method, total_var));
        }
        let var = |r| {
            variances
                .iter()
                .find(|(m, _)| *m == r)
                .map(|(_, v)| *v)
                .unwrap()
        };
        // Multinomial: Σ M w (1 - w) = 10 (1 - Σw²) = 6.48.
        assert!(
            (var(Resampler::Multinomial) - 6.484_375).abs() < 0.2,
            "{variances:?}"
        );
        assert!(
            var(Resampler::LowVariance) < 0.5 * var(Resampler::Multinomial),
            "{variances:?}"
        );
        assert!(
            var(Resampler::Stratified) < var(Resampler::Multinomial),
            "{variances:?}"
        );
        assert!(
            var(Resampler::Residual) < var(Resampler::Multinomial),
            "{variances:?}"
        );
    }

    #[test]
    fn low_variance_and_residual_give_at_least_the_integer_part() {
        let weights = [0.37, 0.21, 0.19, 0.13, 0.1];
        let m = 17;
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        for _ in 0..2000 {
            for method in [Resampler::LowVariance, Resampler::Residual] {
                let c = copies(method, &weights, m, &mut rng);
                for (i, w) in weights.iter().enumerate() {
                    let expected = m as f64 * w;
                    assert!(c[i] >= expected.floor() as usize, "{method:?}: {c:?}");
                    if method == Resampler::LowVariance {
                        assert!(c[i] <= expected.ceil() as usize, "{c:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn degenerate_weights_still_give_a_full_set() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for method in Resampler::ALL {
            assert_eq!(
                copies(method, &[0.0, 0.0, 0.0, 0.0], 8, &mut rng),
                vec![2, 2, 2, 2]
            );
            assert_eq!(
                copies(method, &[f64::NAN, 1.0, -3.0], 5, &mut rng),
                vec![0, 5, 0]
            );
            assert_eq!(copies(method, &[0.0, 0.0, 1.0], 4, &mut rng), vec![0, 0, 4]);
            let mut out = vec![1, 2, 3];
            resample_indices(method, &[0.5, 0.5], 0, &mut rng, &mut out);
            assert!(out.is_empty());
        }
        // Weights that do not quite sum to one, and a particle at the very end.
        assert_eq!(
            copies(
                Resampler::LowVariance,
                &[0.3, 0.3, 0.4 + 1e-12],
                10,
                &mut rng
            ),
            vec![3, 3, 4]
        );
    }

    #[test]
    fn names_round_trip() {
        for r in Resampler::ALL {
            assert_eq!(Resampler::from_name(r.name()), Some(r));
        }
        assert_eq!(Resampler::from_name("systematic"), None);
    }
}
