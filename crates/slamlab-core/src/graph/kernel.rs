//! Robust kernels: how much an edge with a large error still pulls.
//!
//! A kernel maps an edge's squared Mahalanobis error `s = eᵀ Ω e` to its cost
//! `ρ(s)`. Without a kernel `ρ(s) = s`. The solvers weight each edge's contribution
//! to the normal equations with `w = ρ'(s)` (iteratively reweighted least squares,
//! as g2o does), so an edge far outside its noise counts less.

use crate::math;
use serde::{Deserialize, Serialize};

/// A robust kernel applied to every edge's `s = eᵀ Ω e`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum RobustKernel {
    /// Plain least squares: `ρ(s) = s`.
    #[default]
    None,
    /// Huber, thesis 000 Eq. 5.9 with `a = √s` and scaled by 2 so that it equals `s`
    /// inside the threshold: `ρ = a²` for `a ≤ δ`, `2δa − δ²` otherwise.
    Huber {
        /// Threshold δ on the Mahalanobis distance `a = √(eᵀΩe)`.
        delta: f64,
    },
    /// Cauchy: `ρ(s) = c² ln(1 + s / c²)`.
    Cauchy {
        /// Scale `c` on the Mahalanobis distance.
        c: f64,
    },
}

impl RobustKernel {
    /// The robust cost `ρ(s)` of a squared Mahalanobis error `s ≥ 0`.
    pub fn cost(&self, s: f64) -> f64 {
        match *self {
            RobustKernel::None => s,
            RobustKernel::Huber { delta } => {
                let a = s.sqrt();
                if a <= delta {
                    s
                } else {
                    2.0 * delta * a - delta * delta
                }
            }
            RobustKernel::Cauchy { c } => {
                let c2 = c * c;
                c2 * math::ln_1p(s / c2)
            }
        }
    }

    /// The weight `ρ'(s)` this kernel gives an edge in the normal equations.
    pub fn weight(&self, s: f64) -> f64 {
        match *self {
            RobustKernel::None => 1.0,
            RobustKernel::Huber { delta } => {
                let a = s.sqrt();
                if a <= delta { 1.0 } else { delta / a }
            }
            RobustKernel::Cauchy { c } => 1.0 / (1.0 + s / (c * c)),
        }
    }

    /// The kernel's name as the CLI and the lesson show it.
    pub fn name(&self) -> &'static str {
        match self {
            RobustKernel::None => "none",
            RobustKernel::Huber { .. } => "huber",
            RobustKernel::Cauchy { .. } => "cauchy",
        }
    }

    /// Is the kernel's parameter usable (finite and positive)?
    pub fn is_valid(&self) -> bool {
        match *self {
            RobustKernel::None => true,
            RobustKernel::Huber { delta: p } | RobustKernel::Cauchy { c: p } => {
                p.is_finite() && p > 0.0
            }
        }
    }
}
