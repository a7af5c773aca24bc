//! The error functions of the graph's edges and their analytic Jacobians.
//!
//! Every error is `e = h(x) − z` (prediction minus measurement, angles wrapped), and
//! the cost of an edge is `eᵀ Ω e` (thesis 000 Eq. 4.2, with Ω the information
//! matrix). States are updated additively, `x ← x + Δx` on `[x, y, θ]` for a pose
//! (θ wrapped) and `[x, y]` for a point, so the Jacobians below are plain partial
//! derivatives with respect to those coordinates.

use crate::geometry::{Pose2, wrap_angle};
use crate::math;
use nalgebra::{Matrix2, Matrix2x3, Matrix3, Vector2, Vector3};

/// `d(Rᵀ)/dθ` for the rotation `R(θ)`: `[[-s, c], [-c, -s]]`.
fn rotation_transpose_derivative(theta: f64) -> Matrix2<f64> {
    let (s, c) = math::sin_cos(theta);
    Matrix2::new(-s, c, -c, -s)
}

/// Error of a pose-pose edge, thesis 000 Eq. 4.5 with the erratum of the seeds
/// README: `e = [R_zᵀ (R_iᵀ (t_j − t_i) − t_z); wrap(θ_j − θ_i − θ_z)]`.
///
/// The printed equation writes `R_zᵀ(R_iᵀ(t_j − t_i)) − t_z` and `θ_i − θ_j − θ_z`;
/// the form here is the one whose zero is `z = x_i⁻¹ x_j` (also g2o's `EDGE_SE2`).
pub fn pose_pose_error(xi: &Pose2, xj: &Pose2, z: &Pose2) -> Vector3<f64> {
    let d = xj.translation() - xi.translation();
    let t = z.rotation().transpose() * (xi.rotation().transpose() * d - z.translation());
    Vector3::new(t[0], t[1], wrap_angle(xj.theta - xi.theta - z.theta))
}

/// Jacobians `(A, B) = (∂e/∂x_i, ∂e/∂x_j)` of [`pose_pose_error`] (thesis 000 Eq. 4.8).
pub fn pose_pose_jacobians(xi: &Pose2, xj: &Pose2, z: &Pose2) -> (Matrix3<f64>, Matrix3<f64>) {
    let rz_t = z.rotation().transpose();
    let ri_t = xi.rotation().transpose();
    let d = xj.translation() - xi.translation();
    let rzri = rz_t * ri_t;
    let dtheta = rz_t * rotation_transpose_derivative(xi.theta) * d;
    let mut a = Matrix3::zeros();
    let mut b = Matrix3::zeros();
    a.fixed_view_mut::<2, 2>(0, 0).copy_from(&(-rzri));
    a[(0, 2)] = dtheta[0];
    a[(1, 2)] = dtheta[1];
    a[(2, 2)] = -1.0;
    b.fixed_view_mut::<2, 2>(0, 0).copy_from(&rzri);
    b[(2, 2)] = 1.0;
    (a, b)
}

/// Error of a pose-landmark edge measured as a point in the robot frame, thesis 000
/// Eq. 4.6: `e = R_iᵀ (l − t_i) − z`.
pub fn pose_point_error(xi: &Pose2, l: &Vector2<f64>, z: &Vector2<f64>) -> Vector2<f64> {
    xi.rotation().transpose() * (l - xi.translation()) - z
}

/// Jacobians `(∂e/∂x_i, ∂e/∂l)` of [`pose_point_error`].
pub fn pose_point_jacobians(xi: &Pose2, l: &Vector2<f64>) -> (Matrix2x3<f64>, Matrix2<f64>) {
    let ri_t = xi.rotation().transpose();
    let d = l - xi.translation();
    let dtheta = rotation_transpose_derivative(xi.theta) * d;
    let a = Matrix2x3::new(
        -ri_t[(0, 0)],
        -ri_t[(0, 1)],
        dtheta[0],
        -ri_t[(1, 0)],
        -ri_t[(1, 1)],
        dtheta[1],
    );
    (a, ri_t)
}

/// Error of a range-bearing edge (thesis 000 Eq. 3.37, ordered `[range, bearing]`):
/// `e = [‖l − t‖ − r; wrap(atan2(l_y − y, l_x − x) − θ − φ)]`.
pub fn range_bearing_error(xi: &Pose2, l: &Vector2<f64>, range: f64, bearing: f64) -> Vector2<f64> {
    let d = l - xi.translation();
    let r = math::hypot(d[0], d[1]);
    Vector2::new(
        r - range,
        wrap_angle(math::atan2(d[1], d[0]) - xi.theta - bearing),
    )
}

/// Jacobians `(∂e/∂x_i, ∂e/∂l)` of [`range_bearing_error`], with the erratum of the
/// seeds README for thesis 000 Eq. 3.38/3.39: range row `[−dx/r, −dy/r, 0]`, bearing
/// row `[dy/r², −dx/r², −1]`; the landmark columns are the negatives of the first
/// two. At `r = 0` the bearing is undefined and both Jacobians are returned as zero
/// (the solver then sees no information from this edge).
pub fn range_bearing_jacobians(xi: &Pose2, l: &Vector2<f64>) -> (Matrix2x3<f64>, Matrix2<f64>) {
    let d = l - xi.translation();
    let q = d.norm_squared();
    if !(q > 0.0) {
        return (Matrix2x3::zeros(), Matrix2::zeros());
    }
    let r = q.sqrt();
    let a = Matrix2x3::new(-d[0] / r, -d[1] / r, 0.0, d[1] / q, -d[0] / q, -1.0);
    let b = Matrix2::new(d[0] / r, d[1] / r, -d[1] / q, d[0] / q);
    (a, b)
}

/// Error of a pose prior: `e = [t − t_z; wrap(θ − θ_z)]` (Jacobian: identity).
pub fn pose_prior_error(x: &Pose2, z: &Pose2) -> Vector3<f64> {
    Vector3::new(x.x - z.x, x.y - z.y, wrap_angle(x.theta - z.theta))
}

/// Error of a point prior: `e = l − z` (Jacobian: identity).
pub fn point_prior_error(l: &Vector2<f64>, z: &Vector2<f64>) -> Vector2<f64> {
    l - z
}
