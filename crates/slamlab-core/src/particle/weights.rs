//! Log-space importance weights: normalization by log-sum-exp and the effective
//! sample size.

use crate::math;
use thiserror::Error;

/// Why a set of log weights cannot be normalized.
#[derive(Clone, Copy, Debug, PartialEq, Error)]
pub enum WeightError {
    /// There are no particles.
    #[error("there are no particles to weight")]
    Empty,
    /// Every weight is zero (every log weight is −∞): the measurement contradicts
    /// every particle.
    #[error("every particle has weight zero: the measurement contradicts them all")]
    AllZero,
    /// A log weight is NaN or +∞.
    #[error("particle {index} has a log weight of {value}, which is not a probability")]
    NotANumber {
        /// The first offending particle.
        index: usize,
        /// Its log weight.
        value: f64,
    },
}

/// Turns log weights `ℓᵢ` into normalized weights `wᵢ = e^(ℓᵢ − L)` with
/// `L = log Σⱼ e^(ℓⱼ)` (log-sum-exp, computed around the largest `ℓ` so that
/// nothing underflows to an all-zero set), written into `weights`.
///
/// Returns `L`, the log of the sum of the unnormalized weights (for a particle
/// filter, the log of the average likelihood times the particle count), which
/// Augmented MCL's `w_slow` and `w_fast` follow.
///
/// A log weight of −∞ is a weight of zero and is allowed; NaN and +∞ are errors.
/// On an error `weights` is left untouched.
pub fn normalize_log_weights(
    log_weights: &[f64],
    weights: &mut Vec<f64>,
) -> Result<f64, WeightError> {
    let max = largest_log_weight(log_weights)?;
    // Shifting by the largest log weight keeps every exponent ≤ 0 and the sum ≥ 1.
    weights.clear();
    weights.extend(log_weights.iter().map(|&l| math::exp(l - max)));
    let sum: f64 = weights.iter().sum();
    for w in weights.iter_mut() {
        *w /= sum;
    }
    Ok(max + math::ln(sum))
}

/// `L = log Σⱼ e^(ℓⱼ)` alone: what [`normalize_log_weights`] returns (the same
/// number, bit for bit, and the same errors), without writing the weights.
pub fn log_sum_exp(log_weights: &[f64]) -> Result<f64, WeightError> {
    let max = largest_log_weight(log_weights)?;
    let sum: f64 = log_weights.iter().map(|&l| math::exp(l - max)).sum();
    Ok(max + math::ln(sum))
}

/// The largest log weight, or why the set cannot be normalized.
fn largest_log_weight(log_weights: &[f64]) -> Result<f64, WeightError> {
    if log_weights.is_empty() {
        return Err(WeightError::Empty);
    }
    let mut max = f64::NEG_INFINITY;
    for (index, &value) in log_weights.iter().enumerate() {
        if value.is_nan() || value == f64::INFINITY {
            return Err(WeightError::NotANumber { index, value });
        }
        max = max.max(value);
    }
    if max == f64::NEG_INFINITY {
        return Err(WeightError::AllZero);
    }
    Ok(max)
}

pub use crate::stats::effective_sample_size;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalizes_weights_far_below_the_smallest_double() {
        // e^-1000 and e^-1001 are both 0.0 as f64; their ratio is e.
        let mut w = Vec::new();
        let log_sum = normalize_log_weights(&[-1000.0, -1001.0], &mut w).unwrap();
        let e = std::f64::consts::E;
        assert!((w[0] - e / (1.0 + e)).abs() < 1e-15);
        assert!((w[1] - 1.0 / (1.0 + e)).abs() < 1e-15);
        assert!((log_sum - (-1000.0 + math::ln(1.0 + 1.0 / e))).abs() < 1e-12);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn zero_weights_stay_zero_and_all_zero_is_an_error() {
        let mut w = vec![9.0];
        normalize_log_weights(&[f64::NEG_INFINITY, 0.0, 0.0], &mut w).unwrap();
        assert_eq!(w, vec![0.0, 0.5, 0.5]);
        let mut untouched = vec![7.0];
        assert_eq!(
            normalize_log_weights(&[f64::NEG_INFINITY; 3], &mut untouched),
            Err(WeightError::AllZero)
        );
        assert!(matches!(
            normalize_log_weights(&[0.0, f64::NAN], &mut untouched),
            Err(WeightError::NotANumber { index: 1, value }) if value.is_nan()
        ));
        assert!(matches!(
            normalize_log_weights(&[0.0, f64::INFINITY], &mut untouched),
            Err(WeightError::NotANumber { index: 1, .. })
        ));
        assert_eq!(
            normalize_log_weights(&[], &mut untouched),
            Err(WeightError::Empty)
        );
        assert_eq!(untouched, vec![7.0]);
    }

    #[test]
    fn log_sum_exp_is_the_normalizations_sum() {
        let logs = [-1000.0, -1001.5, f64::NEG_INFINITY, -998.25, -1003.0];
        let mut w = Vec::new();
        let expected = normalize_log_weights(&logs, &mut w).unwrap();
        assert_eq!(log_sum_exp(&logs).unwrap().to_bits(), expected.to_bits());
        assert_eq!(
            log_sum_exp(&[f64::NEG_INFINITY; 2]),
            Err(WeightError::AllZero)
        );
        assert_eq!(log_sum_exp(&[]), Err(WeightError::Empty));
    }

    #[test]
    fn effective_sample_size_spans_one_to_m() {
        assert!((effective_sample_size(&[0.25; 4]) - 4.0).abs() < 1e-12);
        assert!((effective_sample_size(&[1.0, 0.0, 0.0]) - 1.0).abs() < 1e-12);
        assert!((effective_sample_size(&[0.5, 0.5, 0.0, 0.0]) - 2.0).abs() < 1e-12);
        assert_eq!(effective_sample_size(&[]), 0.0);
    }
}
