//! Two-view geometry for monocular visual odometry (thesis `000` Sec. 4.3).
//!
//! Conventions follow the thesis's Eq. 4.9: the left camera is `[I | 0]` and a
//! point seen by both cameras satisfies `X_r = R X_l + t`, where `X_l` and `X_r`
//! are the point in the left and right camera frames. Camera frames are the
//! computer-vision ones: z along the optical axis, x right, y down. The
//! essential matrix is `E = [t]x R` (Eq. 4.13) and corresponding normalized
//! image points satisfy `x_rᵀ E x_l = 0` (Eq. 4.14); in pixels, `F = K⁻ᵀ E K⁻¹`
//! (Eq. 4.17, with one camera for both views).
//!
//! - [`eight_point`]: Hartley's normalized eight-point algorithm (Eq. 4.18-4.21)
//!   with the rank-2 projection, for F in pixels and E from it;
//! - [`five_point`]: the calibrated five-point solver (Eq. 4.22-4.25,
//!   Nistér's degree-10 polynomial with Sturm-sequence root finding), up to
//!   10 candidates;
//! - [`decompose`]: the four `(R, t)` in an essential matrix (Eq. 4.26-4.28) and
//!   the choice by cheirality;
//! - [`ransac`]: RANSAC with the adaptive iteration bound and the Sampson
//!   distance, stepped one iteration at a time, with the final refit and the
//!   pure-rotation test;
//! - [`refine`]: Levenberg-Marquardt on the Sampson distances over the five
//!   degrees of freedom of `(R, t)`, which ends RANSAC's estimate.

pub mod decompose;
pub mod eight_point;
pub mod five_point;
mod linear;
mod poly;
pub mod ransac;
pub mod refine;
mod sturm;
#[cfg(test)]
mod tests;

use nalgebra::{Matrix3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

pub use decompose::{Decomposition, RelativePose, decompose_essential, triangulate_midpoint};
pub use eight_point::{essential_eight_point, fundamental_eight_point, project_to_essential};
pub use five_point::essential_five_point;
pub use ransac::{
    EarlyRejection, IterationReport, Method, Motion, Ransac, RansacConfig, RefinementSummary, Sprt,
    SprtCheck, SprtSample, SprtSettings, SprtStats, TwoViewEstimate, estimate_two_view,
    sprt_threshold,
};
pub use refine::{Refinement, refine_pose};

/// Why a two-view estimate could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VisionError {
    /// The method needs more correspondences than were given.
    #[error("{method} needs at least {needed} matches, got {got}")]
    TooFewMatches {
        /// The method's name.
        method: &'static str,
        /// Its minimal number of matches.
        needed: usize,
        /// How many were given.
        got: usize,
    },
    /// A pixel coordinate is NaN or infinite.
    #[error("match {index} has a pixel coordinate that is not a finite number")]
    NonFinite {
        /// Index of the first bad match.
        index: usize,
    },
    /// The camera intrinsics are unusable (zero or non-finite focal length).
    #[error("camera intrinsics are not usable: {0}")]
    BadIntrinsics(&'static str),
    /// The points determine no unique model (for example all on one plane for
    /// the eight-point method, or a numerical breakdown).
    #[error("degenerate configuration: {0}")]
    Degenerate(&'static str),
    /// No hypothesis had enough inliers.
    #[error("no consensus: the best hypothesis had {best} inliers of {total} matches")]
    NoConsensus {
        /// Inliers of the best hypothesis.
        best: usize,
        /// Number of matches.
        total: usize,
    },
}

/// Pinhole intrinsics: focal lengths and principal point in pixels, image size.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    /// Focal length along x, in pixels.
    pub fx: f64,
    /// Focal length along y, in pixels.
    pub fy: f64,
    /// Principal point x, in pixels.
    pub cx: f64,
    /// Principal point y, in pixels.
    pub cy: f64,
    /// Image width, in pixels.
    pub width: f64,
    /// Image height, in pixels.
    pub height: f64,
}

impl Intrinsics {
    /// A camera of the given size and horizontal field of view (degrees), square
    /// pixels and the principal point at the image centre:
    /// `f = (w / 2) / tan(fov / 2)`.
    pub fn from_fov(width: f64, height: f64, horizontal_fov_deg: f64) -> Self {
        let half = horizontal_fov_deg.to_radians() / 2.0;
        let f = (width / 2.0) / crate::math::tan(half);
        Self {
            fx: f,
            fy: f,
            cx: width / 2.0,
            cy: height / 2.0,
            width,
            height,
        }
    }

    /// Checks that the intrinsics can be inverted.
    pub fn validate(&self) -> Result<(), VisionError> {
        let all = [self.fx, self.fy, self.cx, self.cy, self.width, self.height];
        if all.iter().any(|v| !v.is_finite()) {
            return Err(VisionError::BadIntrinsics("a value is not finite"));
        }
        if !(self.fx > 0.0 && self.fy > 0.0) {
            return Err(VisionError::BadIntrinsics("focal lengths must be positive"));
        }
        Ok(())
    }

    /// The calibration matrix `K`.
    pub fn matrix(&self) -> Matrix3<f64> {
        Matrix3::new(self.fx, 0.0, self.cx, 0.0, self.fy, self.cy, 0.0, 0.0, 1.0)
    }

    /// `K⁻¹`.
    pub fn inverse_matrix(&self) -> Matrix3<f64> {
        Matrix3::new(
            1.0 / self.fx,
            0.0,
            -self.cx / self.fx,
            0.0,
            1.0 / self.fy,
            -self.cy / self.fy,
            0.0,
            0.0,
            1.0,
        )
    }

    /// The normalized image point `K⁻¹ [u, v, 1]ᵀ` (third coordinate 1).
    pub fn normalize(&self, pixel: &Vector2<f64>) -> Vector3<f64> {
        Vector3::new(
            (pixel.x - self.cx) / self.fx,
            (pixel.y - self.cy) / self.fy,
            1.0,
        )
    }

    /// The pixel where a point in the camera frame projects, or `None` behind
    /// the camera (z ≤ 0). The point may fall outside the image.
    pub fn project(&self, point_in_camera: &Vector3<f64>) -> Option<Vector2<f64>> {
        if !(point_in_camera.z > 1e-9) {
            return None;
        }
        Some(Vector2::new(
            self.fx * point_in_camera.x / point_in_camera.z + self.cx,
            self.fy * point_in_camera.y / point_in_camera.z + self.cy,
        ))
    }

    /// Whether a pixel lies inside the image.
    pub fn contains(&self, pixel: &Vector2<f64>) -> bool {
        pixel.x >= 0.0 && pixel.y >= 0.0 && pixel.x < self.width && pixel.y < self.height
    }
}

/// One feature match: the same scene point seen at `left` in the first image and
/// `right` in the second, in pixels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Correspondence {
    /// Pixel in the left (earlier) image.
    pub left: Vector2<f64>,
    /// Pixel in the right (later) image.
    pub right: Vector2<f64>,
}

impl Correspondence {
    /// A match from two pixels.
    pub fn new(left: Vector2<f64>, right: Vector2<f64>) -> Self {
        Self { left, right }
    }
}

/// The index of the first match with a non-finite coordinate.
pub(crate) fn check_finite(matches: &[Correspondence]) -> Result<(), VisionError> {
    match matches.iter().position(|m| {
        !(m.left.x.is_finite()
            && m.left.y.is_finite()
            && m.right.x.is_finite()
            && m.right.y.is_finite())
    }) {
        Some(index) => Err(VisionError::NonFinite { index }),
        None => Ok(()),
    }
}

/// The cross-product matrix `[a]x` with `[a]x b = a × b`.
pub fn skew(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

/// The epipolar line `l_r = F x_l` in the right image of a left pixel, as
/// `(a, b, c)` with `a u + b v + c = 0`, scaled so that `a² + b² = 1` (then
/// `a u + b v + c` is a distance in pixels). `None` at the epipole.
pub fn epipolar_line(fundamental: &Matrix3<f64>, pixel: &Vector2<f64>) -> Option<Vector3<f64>> {
    let line = fundamental * Vector3::new(pixel.x, pixel.y, 1.0);
    let norm = (line.x * line.x + line.y * line.y).sqrt();
    if !(norm > 1e-300) {
        return None;
    }
    Some(line / norm)
}

/// The fundamental matrix of an essential matrix for one camera: `F = K⁻ᵀ E K⁻¹`
/// (thesis Eq. 4.17).
pub fn fundamental_from_essential(essential: &Matrix3<f64>, k: &Intrinsics) -> Matrix3<f64> {
    let k_inv = k.inverse_matrix();
    k_inv.transpose() * essential * k_inv
}

/// The squared Sampson distance of a match to the epipolar geometry `F`, in
/// pixels²: the first-order approximation of the squared reprojection distance,
/// `(x_rᵀ F x_l)² / ((F x_l)₁² + (F x_l)₂² + (Fᵀ x_r)₁² + (Fᵀ x_r)₂²)`
/// (Hartley and Zisserman, Eq. 11.9).
pub fn sampson_squared(fundamental: &Matrix3<f64>, m: &Correspondence) -> f64 {
    let t = SampsonTerms::new(fundamental, m);
    if !(t.denominator > 0.0) {
        return f64::INFINITY;
    }
    t.algebraic * t.algebraic / t.denominator
}

/// The pieces of the Sampson distance of a match under `F` (see
/// [`sampson_squared`]): the homogeneous points, the epipolar lines `F x_l`
/// and `Fᵀ x_r`, the algebraic error `x_rᵀ F x_l` and the denominator
/// `(F x_l)₁² + (F x_l)₂² + (Fᵀ x_r)₁² + (Fᵀ x_r)₂²`. The refinement
/// differentiates them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SampsonTerms {
    pub xl: Vector3<f64>,
    pub xr: Vector3<f64>,
    pub f_xl: Vector3<f64>,
    pub ft_xr: Vector3<f64>,
    pub algebraic: f64,
    pub denominator: f64,
}

impl SampsonTerms {
    pub(crate) fn new(fundamental: &Matrix3<f64>, m: &Correspondence) -> Self {
        let xl = Vector3::new(m.left.x, m.left.y, 1.0);
        let xr = Vector3::new(m.right.x, m.right.y, 1.0);
        let f_xl = fundamental * xl;
        let ft_xr = fundamental.tr_mul(&xr);
        Self {
            xl,
            xr,
            f_xl,
            ft_xr,
            algebraic: xr.dot(&f_xl),
            denominator: f_xl.x * f_xl.x + f_xl.y * f_xl.y + ft_xr.x * ft_xr.x + ft_xr.y * ft_xr.y,
        }
    }
}

/// The angle in radians of the rotation `R`: `atan2(‖vee(R − Rᵀ)‖ / 2, (tr R − 1) / 2)`,
/// accurate for small and large angles alike.
pub fn rotation_angle(rotation: &Matrix3<f64>) -> f64 {
    let axis = Vector3::new(
        rotation[(2, 1)] - rotation[(1, 2)],
        rotation[(0, 2)] - rotation[(2, 0)],
        rotation[(1, 0)] - rotation[(0, 1)],
    );
    crate::math::atan2(axis.norm() / 2.0, (rotation.trace() - 1.0) / 2.0)
}

/// The angle in radians between two directions, `atan2(‖a × b‖, a · b)`,
/// ignoring their lengths; π/2 if either is zero.
pub fn angle_between(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    if !(a.norm() > 0.0 && b.norm() > 0.0) {
        return std::f64::consts::FRAC_PI_2;
    }
    crate::math::atan2(a.cross(b).norm(), a.dot(b))
}
