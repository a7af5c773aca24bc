//! Putting an estimate in the reference's frame before comparing them: the
//! least-squares similarity of Umeyama (1991), in the plane.
//!
//! An estimator's map frame is its own: it starts wherever its first pose is, and
//! a monocular one even has its own scale. Before the absolute error means
//! anything, the estimate's positions `x_i` are moved onto the reference's `y_i`
//! by the transform that minimizes `Σ ‖y_i − (c R x_i + t)‖²` (Umeyama, "Least-
//! squares estimation of transformation parameters between two point patterns",
//! IEEE PAMI 13(4), 1991, Eqs. 34-42). In the plane the rotation has a closed form:
//! with the centred points `a_i = x_i − x̄`, `b_i = y_i − ȳ` and `C = (1/n) Σ b_i a_iᵀ`,
//!
//! ```text
//! θ = atan2(C₂₁ − C₁₂, C₁₁ + C₂₂),   c = √((C₁₁ + C₂₂)² + (C₂₁ − C₁₂)²) / σ_x²,
//! t = ȳ − c R(θ) x̄,                  σ_x² = (1/n) Σ ‖a_i‖²
//! ```
//!
//! which is Umeyama's `R = U S Vᵀ` and `c = tr(D S) / σ_x²` for 2x2 matrices
//! (the rotation that maximizes `Σ b_iᵀ R a_i`). evo's `--align` (SE(3)) and
//! `--align --correct_scale` (Sim(3)) compute the same on planar trajectories,
//! with one difference: in 3D evo may turn a mirrored path over (a rotation of
//! 180° about an axis in the plane); SLAM Lab keeps the plane and its sense of
//! rotation, and aligns a straight path too (evo refuses it as degenerate).

use super::MetricsError;
use slamlab_core::{Pose2, math, wrap_angle};

/// How an estimate is aligned to the reference before the absolute error.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Alignment {
    /// As it is: the estimate claims the reference's frame (evo without `--align`).
    None,
    /// The rotation and translation that fit best (evo's `--align`).
    #[default]
    Se2,
    /// Rotation, translation and scale (evo's `--align --correct_scale`): for
    /// monocular estimates, whose scale is their own.
    Sim2,
}

impl Alignment {
    /// Every alignment, as the command line spells them.
    pub const NAMES: [&'static str; 3] = ["none", "se2", "sim2"];

    /// The name on the command line and in the JSON.
    pub fn name(self) -> &'static str {
        match self {
            Alignment::None => "none",
            Alignment::Se2 => "se2",
            Alignment::Sim2 => "sim2",
        }
    }

    /// Reads a name: `none`, `se2` or `sim2`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "none" | "off" => Some(Alignment::None),
            "se2" | "se(2)" => Some(Alignment::Se2),
            "sim2" | "sim(2)" => Some(Alignment::Sim2),
            _ => None,
        }
    }
}

/// A planar similarity: `p ↦ c R(θ) p + t`, and a heading turned by `θ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity {
    /// The rotation, radians.
    pub rotation: f64,
    /// The translation, metres.
    pub translation: [f64; 2],
    /// The scale (1 for a rigid alignment).
    pub scale: f64,
}

impl Similarity {
    /// The transform that changes nothing.
    pub const IDENTITY: Similarity = Similarity {
        rotation: 0.0,
        translation: [0.0, 0.0],
        scale: 1.0,
    };

    /// A pose moved by the transform: its position scaled, rotated and moved, its
    /// heading turned.
    pub fn apply(&self, pose: &Pose2) -> Pose2 {
        let (s, c) = math::sin_cos(self.rotation);
        let (x, y) = (self.scale * pose.x, self.scale * pose.y);
        Pose2::new(
            c * x - s * y + self.translation[0],
            s * x + c * y + self.translation[1],
            wrap_angle(pose.theta + self.rotation),
        )
    }
}

/// The similarity (with `with_scale`) or rigid transform that moves the points
/// `x` onto `y` in the least-squares sense (see the module's documentation).
/// Refused when `x` has fewer than two distinct points, which fixes no rotation.
pub fn umeyama(
    x: &[[f64; 2]],
    y: &[[f64; 2]],
    with_scale: bool,
) -> Result<Similarity, MetricsError> {
    let n = x.len().min(y.len());
    if n == 0 {
        return Err(MetricsError::CannotAlign(
            "no pairs of poses to align".to_owned(),
        ));
    }
    let nf = n as f64;
    let mean = |p: &[[f64; 2]]| {
        let (sx, sy) = p[..n]
            .iter()
            .fold((0.0, 0.0), |(a, b), q| (a + q[0], b + q[1]));
        [sx / nf, sy / nf]
    };
    let (mx, my) = (mean(x), mean(y));
    let (mut c11, mut c12, mut c21, mut c22, mut var_x) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (p, q) in x[..n].iter().zip(&y[..n]) {
        let (ax, ay) = (p[0] - mx[0], p[1] - mx[1]);
        let (bx, by) = (q[0] - my[0], q[1] - my[1]);
        c11 += bx * ax;
        c12 += bx * ay;
        c21 += by * ax;
        c22 += by * ay;
        var_x += ax * ax + ay * ay;
    }
    let (a, b) = ((c11 + c22) / nf, (c21 - c12) / nf);
    let var_x = var_x / nf;
    let norm = math::hypot(a, b);
    if !(var_x > 0.0) || !(norm > 1e-12 * var_x) {
        return Err(MetricsError::CannotAlign(
            "the estimate's aligned positions are all one point (or the reference's are), which fixes no rotation"
                .to_owned(),
        ));
    }
    let rotation = math::atan2(b, a);
    let scale = if with_scale { norm / var_x } else { 1.0 };
    let (s, c) = math::sin_cos(rotation);
    let translation = [
        my[0] - scale * (c * mx[0] - s * mx[1]),
        my[1] - scale * (s * mx[0] + c * mx[1]),
    ];
    Ok(Similarity {
        rotation,
        translation,
        scale,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_known_similarity_exactly() {
        let truth = Similarity {
            rotation: 2.3,
            translation: [4.0, -1.5],
            scale: 0.37,
        };
        let x: Vec<[f64; 2]> = (0..20)
            .map(|k| {
                let t = k as f64 * 0.4;
                [
                    math::cos(t) * (1.0 + 0.1 * t),
                    0.3 * math::sin(t) + 0.05 * t * t,
                ]
            })
            .collect();
        let y: Vec<[f64; 2]> = x
            .iter()
            .map(|p| {
                let q = truth.apply(&Pose2::new(p[0], p[1], 0.0));
                [q.x, q.y]
            })
            .collect();
        let sim = umeyama(&x, &y, true).unwrap();
        assert!((sim.rotation - 2.3).abs() < 1e-12);
        assert!((sim.scale - 0.37).abs() < 1e-12);
        assert!(
            (sim.translation[0] - 4.0).abs() < 1e-12 && (sim.translation[1] + 1.5).abs() < 1e-12
        );
        // Without scale: the rotation is still found, the scale stays 1.
        let rigid = umeyama(&x, &y, false).unwrap();
        assert!((rigid.rotation - 2.3).abs() < 1e-12);
        assert_eq!(rigid.scale, 1.0);
    }

    /// The closed form agrees with Umeyama's SVD form `R = U S Vᵀ`,
    /// `c = tr(D S)/σ²`, also for points that fit best with a reflection (where
    /// `S` flips the smaller singular value).
    #[test]
    fn the_closed_form_equals_the_svd_form() {
        use nalgebra::{Matrix2, Vector2};
        type Points<'a> = &'a [[f64; 2]];
        let sets: [(Points, Points); 2] = [
            (
                &[[0.0, 0.0], [1.0, 0.2], [2.5, 1.0], [3.0, -0.7]],
                &[[1.0, 1.0], [1.5, 2.1], [2.2, 3.4], [4.1, 3.0]],
            ),
            // The mirror image: a reflection would fit exactly.
            (
                &[[0.0, 0.0], [1.0, 0.0], [0.0, 2.0], [1.0, 3.0]],
                &[[0.0, 0.0], [1.0, 0.0], [0.0, -2.0], [1.0, -3.0]],
            ),
        ];
        for (x, y) in sets {
            let n = x.len() as f64;
            let mx = x
                .iter()
                .fold(Vector2::zeros(), |a, p| a + Vector2::new(p[0], p[1]))
                / n;
            let my = y
                .iter()
                .fold(Vector2::zeros(), |a, p| a + Vector2::new(p[0], p[1]))
                / n;
            let mut cov = Matrix2::zeros();
            let mut var = 0.0;
            for (p, q) in x.iter().zip(y) {
                let a = Vector2::new(p[0], p[1]) - mx;
                let b = Vector2::new(q[0], q[1]) - my;
                cov += b * a.transpose();
                var += a.norm_squared();
            }
            cov /= n;
            var /= n;
            let svd = cov.svd(true, true);
            let (u, v_t) = (svd.u.unwrap(), svd.v_t.unwrap());
            let mut s = Matrix2::identity();
            if u.determinant() * v_t.determinant() < 0.0 {
                s[(1, 1)] = -1.0;
            }
            let r = u * s * v_t;
            let c = (Matrix2::from_diagonal(&svd.singular_values) * s).trace() / var;
            let sim = umeyama(x, y, true).unwrap();
            assert!((math::atan2(r[(1, 0)], r[(0, 0)]) - sim.rotation).abs() < 1e-12);
            assert!((c - sim.scale).abs() < 1e-12, "{c} {}", sim.scale);
        }
    }

    #[test]
    fn one_point_fixes_no_rotation() {
        assert!(
            umeyama(
                &[[1.0, 1.0]; 4],
                &[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]],
                false
            )
            .is_err()
        );
        assert!(umeyama(&[], &[], false).is_err());
        assert_eq!(Alignment::from_name("SE2"), Some(Alignment::Se2));
        assert_eq!(Alignment::from_name("rigid"), None);
    }
}
