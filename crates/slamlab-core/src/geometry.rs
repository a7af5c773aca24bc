//! SE(2) poses, angle wrapping and covariance ellipses.

use crate::math;
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Wraps an angle to the interval (-π, π].
///
/// Non-finite input is returned unchanged so that the caller's NaN checks see it.
pub fn wrap_angle(angle: f64) -> f64 {
    if !angle.is_finite() {
        return angle;
    }
    let wrapped = (angle + PI).rem_euclid(2.0 * PI) - PI;
    // rem_euclid maps +π to -π; the convention here keeps +π.
    if wrapped <= -PI {
        wrapped + 2.0 * PI
    } else {
        wrapped
    }
}

/// A rigid transform in the plane (an element of SE(2)): translation `(x, y)` in
/// metres and heading `theta` in radians, counter-clockwise from the x axis.
///
/// Read `world_from_robot.compose(&robot_from_sensor)` as "world from sensor".
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose2 {
    /// Translation along x, metres.
    pub x: f64,
    /// Translation along y, metres.
    pub y: f64,
    /// Heading, radians, kept in (-π, π] by the constructors.
    pub theta: f64,
}

impl Pose2 {
    /// The identity transform.
    pub const IDENTITY: Self = Self {
        x: 0.0,
        y: 0.0,
        theta: 0.0,
    };

    /// A pose with its heading wrapped to (-π, π].
    pub fn new(x: f64, y: f64, theta: f64) -> Self {
        Self {
            x,
            y,
            theta: wrap_angle(theta),
        }
    }

    /// Builds a pose from a vector `[x, y, theta]`.
    pub fn from_vector(v: &Vector3<f64>) -> Self {
        Self::new(v[0], v[1], v[2])
    }

    /// The pose as a vector `[x, y, theta]`.
    pub fn to_vector(&self) -> Vector3<f64> {
        Vector3::new(self.x, self.y, self.theta)
    }

    /// The translation part.
    pub fn translation(&self) -> Vector2<f64> {
        Vector2::new(self.x, self.y)
    }

    /// The rotation part as a 2x2 matrix.
    pub fn rotation(&self) -> Matrix2<f64> {
        let (s, c) = math::sin_cos(self.theta);
        Matrix2::new(c, -s, s, c)
    }

    /// `self ∘ other`: applies `other` first, then `self`.
    pub fn compose(&self, other: &Pose2) -> Pose2 {
        let t = self.transform_point(&other.translation());
        Pose2::new(t[0], t[1], self.theta + other.theta)
    }

    /// The inverse transform, so that `p.compose(&p.inverse())` is the identity.
    pub fn inverse(&self) -> Pose2 {
        let (s, c) = math::sin_cos(self.theta);
        Pose2::new(
            -c * self.x - s * self.y,
            s * self.x - c * self.y,
            -self.theta,
        )
    }

    /// The relative transform from `self` to `other`: `self⁻¹ ∘ other`.
    pub fn between(&self, other: &Pose2) -> Pose2 {
        self.inverse().compose(other)
    }

    /// Maps a point given in this pose's frame into the parent frame.
    pub fn transform_point(&self, point: &Vector2<f64>) -> Vector2<f64> {
        self.rotation() * point + self.translation()
    }

    /// The homogeneous 3x3 matrix of this transform.
    pub fn to_matrix(&self) -> Matrix3<f64> {
        let (s, c) = math::sin_cos(self.theta);
        Matrix3::new(c, -s, self.x, s, c, self.y, 0.0, 0.0, 1.0)
    }

    /// True when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.theta.is_finite()
    }
}

/// The chi-square value with 2 degrees of freedom that bounds 95% of the
/// probability mass: the default size of every covariance ellipse in SLAM Lab.
pub const CHI2_2DOF_95: f64 = 5.991_464_547_107_979;

/// An ellipse drawn for a 2x2 covariance: `{p : (p - c)ᵀ Σ⁻¹ (p - c) ≤ k}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CovarianceEllipse {
    /// Centre, metres.
    pub center: Vector2<f64>,
    /// Semi-axis along `angle`, metres.
    pub semi_major: f64,
    /// Semi-axis perpendicular to `angle`, metres.
    pub semi_minor: f64,
    /// Orientation of the major axis, radians.
    pub angle: f64,
}

impl CovarianceEllipse {
    /// The ellipse `(p - center)ᵀ Σ⁻¹ (p - center) = chi2` of a 2x2 covariance.
    ///
    /// The covariance is symmetrized first; negative eigenvalues from round-off are
    /// clamped to zero, so a degenerate covariance draws as a line or a point.
    pub fn from_covariance(center: Vector2<f64>, covariance: &Matrix2<f64>, chi2: f64) -> Self {
        let a = covariance[(0, 0)];
        let b = 0.5 * (covariance[(0, 1)] + covariance[(1, 0)]);
        let d = covariance[(1, 1)];
        // Closed-form eigen-decomposition of a symmetric 2x2 matrix.
        let mean = 0.5 * (a + d);
        let radius = (0.25 * (a - d) * (a - d) + b * b).sqrt();
        let major = (mean + radius).max(0.0);
        let minor = (mean - radius).max(0.0);
        let angle = 0.5 * math::atan2(2.0 * b, a - d);
        let k = chi2.max(0.0);
        Self {
            center,
            semi_major: (k * major).sqrt(),
            semi_minor: (k * minor).sqrt(),
            angle,
        }
    }

    /// `count` points along the ellipse, for drawing.
    pub fn boundary(&self, count: usize) -> Vec<Vector2<f64>> {
        let (s, c) = math::sin_cos(self.angle);
        (0..count)
            .map(|i| {
                let t = 2.0 * PI * i as f64 / count as f64;
                let (ex, ey) = (
                    self.semi_major * math::cos(t),
                    self.semi_minor * math::sin(t),
                );
                self.center + Vector2::new(c * ex - s * ey, s * ex + c * ey)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOL: f64 = 1e-12;

    fn assert_pose_close(a: &Pose2, b: &Pose2) {
        assert!((a.x - b.x).abs() < TOL, "{a:?} vs {b:?}");
        assert!((a.y - b.y).abs() < TOL, "{a:?} vs {b:?}");
        assert!(wrap_angle(a.theta - b.theta).abs() < TOL, "{a:?} vs {b:?}");
    }

    fn sample_poses() -> Vec<Pose2> {
        vec![
            Pose2::new(1.0, 2.0, 0.3),
            Pose2::new(-3.5, 0.25, -2.9),
            Pose2::new(0.0, 0.0, PI),
            Pose2::new(10.0, -7.0, 1.5),
        ]
    }

    #[test]
    fn wrap_angle_keeps_the_half_open_interval() {
        assert!((wrap_angle(PI) - PI).abs() < TOL);
        assert!((wrap_angle(-PI) - PI).abs() < TOL);
        assert!((wrap_angle(3.0 * PI) - PI).abs() < TOL);
        assert!((wrap_angle(PI + 1e-9) - (-PI + 1e-9)).abs() < 1e-9);
        assert!((wrap_angle(-PI - 1e-9) - (PI - 1e-9)).abs() < 1e-9);
        assert!((wrap_angle(7.0) - (7.0 - 2.0 * PI)).abs() < TOL);
        assert!((wrap_angle(-7.0) - (-7.0 + 2.0 * PI)).abs() < TOL);
        assert_eq!(wrap_angle(0.0), 0.0);
        assert!(wrap_angle(f64::NAN).is_nan());
        for k in -20..=20 {
            let a = 0.1 * k as f64 * PI;
            let w = wrap_angle(a);
            assert!(w > -PI && w <= PI, "{a} -> {w}");
            assert!(
                ((a - w) / (2.0 * PI)).fract().abs() < 1e-9
                    || ((a - w) / (2.0 * PI)).fract().abs() > 1.0 - 1e-9
            );
        }
    }

    #[test]
    fn compose_with_inverse_is_identity() {
        for p in sample_poses() {
            assert_pose_close(&p.compose(&p.inverse()), &Pose2::IDENTITY);
            assert_pose_close(&p.inverse().compose(&p), &Pose2::IDENTITY);
            assert_pose_close(&p.inverse().inverse(), &p);
        }
    }

    #[test]
    fn compose_is_associative_and_matches_matrices() {
        let poses = sample_poses();
        for a in &poses {
            for b in &poses {
                let ab = a.compose(b);
                let m = a.to_matrix() * b.to_matrix();
                assert!((ab.to_matrix() - m).abs().max() < 1e-12);
                for c in &poses {
                    assert_pose_close(&a.compose(b).compose(c), &a.compose(&b.compose(c)));
                }
            }
        }
    }

    #[test]
    fn between_recovers_the_relative_pose() {
        let poses = sample_poses();
        for a in &poses {
            for b in &poses {
                assert_pose_close(&a.compose(&a.between(b)), b);
            }
            assert_pose_close(&a.between(a), &Pose2::IDENTITY);
        }
    }

    #[test]
    fn transform_point_matches_compose() {
        let world_from_robot = Pose2::new(2.0, -1.0, 0.7);
        let landmark_in_robot = Vector2::new(3.0, 0.5);
        let via_pose = world_from_robot.compose(&Pose2::new(3.0, 0.5, 0.0));
        let p = world_from_robot.transform_point(&landmark_in_robot);
        assert!((p[0] - via_pose.x).abs() < TOL && (p[1] - via_pose.y).abs() < TOL);
    }

    #[test]
    fn ellipse_axes_are_scaled_eigenvalues() {
        let angle: f64 = 0.4;
        let r = Pose2::new(0.0, 0.0, angle).rotation();
        let cov = r * Matrix2::new(4.0, 0.0, 0.0, 1.0) * r.transpose();
        let e = CovarianceEllipse::from_covariance(Vector2::zeros(), &cov, CHI2_2DOF_95);
        assert!((e.semi_major - (4.0 * CHI2_2DOF_95).sqrt()).abs() < 1e-12);
        assert!((e.semi_minor - CHI2_2DOF_95.sqrt()).abs() < 1e-12);
        assert!((e.angle - angle).abs() < 1e-12);
        // Every boundary point has Mahalanobis distance chi2.
        let inv = cov.try_inverse().unwrap_or_else(Matrix2::identity);
        for p in e.boundary(16) {
            assert!(((p.transpose() * inv * p)[0] - CHI2_2DOF_95).abs() < 1e-9);
        }
    }

    #[test]
    fn degenerate_covariance_gives_a_point() {
        let e = CovarianceEllipse::from_covariance(
            Vector2::new(1.0, 1.0),
            &Matrix2::zeros(),
            CHI2_2DOF_95,
        );
        assert_eq!(e.semi_major, 0.0);
        assert_eq!(e.semi_minor, 0.0);
        let e = CovarianceEllipse::from_covariance(
            Vector2::zeros(),
            &Matrix2::new(1.0, 0.0, 0.0, -1e-18),
            1.0,
        );
        assert!(e.semi_minor == 0.0 && (e.semi_major - 1.0).abs() < 1e-12);
    }
}
