//! The transcendental functions every SLAM Lab computation uses.
//!
//! `f64::sin` and friends call the platform's C library natively (glibc on Linux)
//! and a port of musl's libm in WebAssembly. The two agree to an ulp or so, and a
//! particle filter turns that last bit into a different particle cloud after a few
//! hundred resamplings. Routing every call through the `libm` crate gives one
//! implementation everywhere, so a seed replays bit for bit natively and in the
//! browser. `clippy.toml` forbids the `f64` methods in the whole workspace.
//!
//! `sqrt`, `abs`, `floor`, `mul_add` and friends are exactly rounded by IEEE 754
//! and need no wrapper.

/// Sine of `x` (radians).
#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

/// Cosine of `x` (radians).
#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

/// Tangent of `x` (radians).
#[inline]
pub fn tan(x: f64) -> f64 {
    libm::tan(x)
}

/// The angle of the point `(x, y)`, in (-π, π].
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

/// Arc tangent, in (-π/2, π/2).
#[inline]
pub fn atan(x: f64) -> f64 {
    libm::atan(x)
}

/// Arc cosine, in [0, π]; NaN outside [-1, 1].
#[inline]
pub fn acos(x: f64) -> f64 {
    libm::acos(x)
}

/// Arc sine, in [-π/2, π/2]; NaN outside [-1, 1].
#[inline]
pub fn asin(x: f64) -> f64 {
    libm::asin(x)
}

/// `e^x`.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// `e^x - 1`, accurate near zero.
#[inline]
pub fn exp_m1(x: f64) -> f64 {
    libm::expm1(x)
}

/// Natural logarithm.
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// `ln(1 + x)`, accurate near zero.
#[inline]
pub fn ln_1p(x: f64) -> f64 {
    libm::log1p(x)
}

/// Base-10 logarithm.
#[inline]
pub fn log10(x: f64) -> f64 {
    libm::log10(x)
}

/// `x^y`.
#[inline]
pub fn powf(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

/// `sqrt(x² + y²)` without overflow or underflow in between.
#[inline]
pub fn hypot(x: f64, y: f64) -> f64 {
    libm::hypot(x, y)
}

/// The error function `erf(x) = 2/√π ∫₀ˣ e^(−t²) dt` (for the normal CDF).
#[inline]
pub fn erf(x: f64) -> f64 {
    libm::erf(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    #[test]
    fn agrees_with_known_values() {
        assert_eq!(sin(0.0), 0.0);
        assert!((sin(FRAC_PI_2) - 1.0).abs() < 1e-16);
        assert!((cos(PI) + 1.0).abs() < 1e-16);
        assert!((atan2(1.0, 1.0) - FRAC_PI_4).abs() < 1e-16);
        assert_eq!(atan2(0.0, -1.0), PI);
        assert!((exp(1.0) - std::f64::consts::E).abs() < 1e-15);
        assert!((ln(std::f64::consts::E) - 1.0).abs() < 1e-16);
        assert_eq!(hypot(3.0, 4.0), 5.0);
        let (s, c) = sin_cos(0.3);
        assert_eq!((s, c), (sin(0.3), cos(0.3)));
        assert!(ln(0.0).is_infinite() && ln(-1.0).is_nan());
    }
}
