//! Chi-square statistics for filter consistency: NEES, NIS and their bands.

use crate::math;
use nalgebra::{DMatrix, DVector};

/// `ln Γ(x)` for `x > 0` (Lanczos approximation, g = 7, n = 9; relative error < 1e-14).
pub fn ln_gamma(x: f64) -> f64 {
    const COEFFS: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection formula.
        let pi = std::f64::consts::PI;
        return math::ln(pi / math::sin(pi * x)) - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut sum = COEFFS[0];
    for (i, c) in COEFFS.iter().enumerate().skip(1) {
        sum += c / (x + i as f64);
    }
    let t = x + 7.5;
    0.5 * math::ln(2.0 * std::f64::consts::PI) + (x + 0.5) * math::ln(t) - t + math::ln(sum)
}

/// The regularized lower incomplete gamma function `P(a, x)`.
pub fn regularized_gamma_p(a: f64, x: f64) -> f64 {
    if !(a > 0.0) || x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 0.0;
    }
    let log_prefactor = -x + a * math::ln(x) - ln_gamma(a);
    if x < a + 1.0 {
        // Series expansion.
        let mut term = 1.0 / a;
        let mut sum = term;
        let mut n = a;
        for _ in 0..1000 {
            n += 1.0;
            term *= x / n;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        math::exp(math::ln(sum) + log_prefactor).clamp(0.0, 1.0)
    } else {
        // Continued fraction for Q(a, x) (modified Lentz).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (1.0 - (math::exp(log_prefactor) * h)).clamp(0.0, 1.0)
    }
}

/// The chi-square cumulative distribution function with `dof` degrees of freedom.
pub fn chi2_cdf(x: f64, dof: f64) -> f64 {
    regularized_gamma_p(0.5 * dof, 0.5 * x)
}

/// The `p`-quantile of the chi-square distribution with `dof` degrees of freedom,
/// found by bisection on [`chi2_cdf`] to 1e-12 relative accuracy.
pub fn chi2_quantile(p: f64, dof: f64) -> f64 {
    if !(p > 0.0 && p < 1.0 && dof > 0.0) {
        return f64::NAN;
    }
    let mut lo = 0.0;
    let mut hi = dof.max(1.0);
    while chi2_cdf(hi, dof) < p {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi2_cdf(mid, dof) < p {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-12 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// The two-sided 95% band for the average of `runs` independent chi-square
/// statistics of `dof` degrees of freedom each: `[χ²(0.025), χ²(0.975)] / runs`
/// with `runs · dof` degrees of freedom (Bar-Shalom et al., Sec. 5.4.2).
pub fn chi2_band_95(dof: f64, runs: usize) -> (f64, f64) {
    let n = runs.max(1) as f64;
    (
        chi2_quantile(0.025, dof * n) / n,
        chi2_quantile(0.975, dof * n) / n,
    )
}

/// The normalized (estimation or innovation) squared error `eᵀ P⁻¹ e`.
///
/// Returns `None` when `P` is not positive definite or is nearly singular
/// (smallest eigenvalue below `1e-6` times the largest). The robot's covariance is
/// zero at the start of a run and has rank 2 after the first prediction (three
/// states, two noise inputs); the unscented transform's curvature leaves a third
/// eigenvalue of 1e-11..1e-10 relative, and a NEES against it measures that
/// sliver, not the filter. Full-rank robot covariances in SLAM Lab's runs have
/// ratios of 2.5e-3 and above.
pub fn normalized_squared_error(error: &DVector<f64>, covariance: &DMatrix<f64>) -> Option<f64> {
    let eigenvalues = covariance.clone().symmetric_eigenvalues();
    let (min, max) = (eigenvalues.min(), eigenvalues.max());
    if !(max > 0.0 && min > 1e-6 * max) {
        return None;
    }
    let chol = covariance.clone().cholesky()?;
    let solved = chol.solve(error);
    let value = error.dot(&solved);
    value.is_finite().then_some(value)
}

/// The effective sample size `N_eff = 1 / Σ wᵢ²` of normalized weights: `M` for
/// uniform weights, 1 when one particle holds all the weight (slides, "adaptive
/// resampling"). Zero for an empty set. Takes any sequence of weights (a
/// slice, or the weights of a particle set) in order.
pub fn effective_sample_size<'a>(weights: impl IntoIterator<Item = &'a f64>) -> f64 {
    let sum_sq: f64 = weights.into_iter().map(|w| w * w).sum();
    if sum_sq > 0.0 { 1.0 / sum_sq } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln_gamma_matches_factorials() {
        let mut fact = 1.0_f64;
        for n in 1..20 {
            assert!(
                (ln_gamma(n as f64) - math::ln(fact)).abs() < 1e-12,
                "Γ({n})"
            );
            fact *= n as f64;
        }
        assert!((ln_gamma(0.5) - math::ln(std::f64::consts::PI.sqrt())).abs() < 1e-13);
    }

    #[test]
    fn chi2_quantiles_match_tables() {
        // Reference values from scipy.stats.chi2.ppf.
        assert!((chi2_quantile(0.95, 2.0) - 5.991_464_547).abs() < 1e-8);
        assert!((chi2_quantile(0.975, 3.0) - 9.348_403_604).abs() < 1e-8);
        assert!((chi2_quantile(0.025, 3.0) - 0.215_795_282).abs() < 1e-8);
        assert!((chi2_quantile(0.975, 150.0) - 185.800_447).abs() < 1e-5);
        assert!((chi2_quantile(0.025, 150.0) - 117.984_515_4).abs() < 1e-5);
        // The 2-dof CDF has the closed form 1 - exp(-x/2).
        for x in [0.1, 1.0, 4.0, 12.0] {
            assert!((chi2_cdf(x, 2.0) - (1.0 - math::exp(-0.5 * x))).abs() < 1e-14);
        }
        assert!(chi2_quantile(1.5, 2.0).is_nan());
    }

    #[test]
    fn band_for_fifty_runs_of_three_dof() {
        let (lo, hi) = chi2_band_95(3.0, 50);
        assert!((lo - 117.984_515_4 / 50.0).abs() < 1e-6);
        assert!((hi - 185.800_447 / 50.0).abs() < 1e-6);
    }

    #[test]
    fn nees_of_a_known_case() {
        let p = DMatrix::from_row_slice(2, 2, &[4.0, 0.0, 0.0, 1.0]);
        let e = DVector::from_row_slice(&[2.0, 1.0]);
        assert!((normalized_squared_error(&e, &p).unwrap_or(f64::NAN) - 2.0).abs() < 1e-12);
        assert!(normalized_squared_error(&e, &DMatrix::zeros(2, 2)).is_none());
        // Rank deficient up to round-off: undefined, not huge.
        let nearly = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1e-8]);
        assert!(normalized_squared_error(&e, &nearly).is_none());
    }
}
