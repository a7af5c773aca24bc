//! The planar omnidirectional motion model and the pose-difference Jacobians of
//! the fusion EKF.
//!
//! The state is `[x, y, ψ, v_x, v_y, ψ̇, a_x, a_y]` (see [`StateIndex`]): the pose
//! in the filter's world frame and the velocity and acceleration in the robot's
//! body frame, as robot_localization's 15-dimensional state restricted to the
//! plane (`ekf.cpp`, `EKF::predict`).

use crate::geometry::{Pose2, wrap_angle};
use crate::math;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// Number of state variables.
pub const STATE_SIZE: usize = 8;
/// The state vector `[x, y, ψ, v_x, v_y, ψ̇, a_x, a_y]`.
pub type StateVector = SVector<f64, STATE_SIZE>;
/// An 8x8 state matrix (covariance, Jacobian).
pub type StateMatrix = SMatrix<f64, STATE_SIZE, STATE_SIZE>;

/// One state variable: its position in the state vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum StateIndex {
    /// x position in the world frame, metres.
    X = 0,
    /// y position in the world frame, metres.
    Y = 1,
    /// Heading ψ, radians, wrapped to (-π, π].
    Yaw = 2,
    /// Forward velocity in the body frame, m/s.
    VX = 3,
    /// Sideways velocity in the body frame, m/s (zero for a differential drive).
    VY = 4,
    /// Yaw rate ψ̇, rad/s.
    YawRate = 5,
    /// Forward acceleration in the body frame, m/s².
    AX = 6,
    /// Sideways acceleration in the body frame, m/s².
    AY = 7,
}

impl StateIndex {
    /// Every state variable in state order.
    pub const ALL: [StateIndex; STATE_SIZE] = [
        StateIndex::X,
        StateIndex::Y,
        StateIndex::Yaw,
        StateIndex::VX,
        StateIndex::VY,
        StateIndex::YawRate,
        StateIndex::AX,
        StateIndex::AY,
    ];

    /// A short name ("x", "yaw rate", ...), for reports.
    pub fn label(self) -> &'static str {
        match self {
            StateIndex::X => "x",
            StateIndex::Y => "y",
            StateIndex::Yaw => "yaw",
            StateIndex::VX => "v_x",
            StateIndex::VY => "v_y",
            StateIndex::YawRate => "yaw rate",
            StateIndex::AX => "a_x",
            StateIndex::AY => "a_y",
        }
    }

    /// Whether the variable is an angle (its innovation is wrapped).
    pub fn is_angle(self) -> bool {
        self == StateIndex::Yaw
    }
}

/// The prediction `f(x, Δt)` of the omnidirectional constant-acceleration model
/// (robot_localization `ekf.cpp`, `EKF::predict`, with roll = pitch = 0):
///
/// ```text
/// x' = x + (cψ v_x − sψ v_y) Δt + ½ (cψ a_x − sψ a_y) Δt²
/// y' = y + (sψ v_x + cψ v_y) Δt + ½ (sψ a_x + cψ a_y) Δt²
/// ψ' = ψ + ψ̇ Δt
/// v_x' = v_x + a_x Δt,  v_y' = v_y + a_y Δt,  ψ̇' = ψ̇,  a' = a
/// ```
///
/// With the accelerations held at zero (and no process noise on them) this is the
/// constant-velocity model.
pub fn predict_state(x: &StateVector, dt: f64) -> StateVector {
    let (s, c) = math::sin_cos(x[2]);
    let (vx, vy, ax, ay) = (x[3], x[4], x[6], x[7]);
    let half_dt2 = 0.5 * dt * dt;
    let mut out = *x;
    out[0] += (c * vx - s * vy) * dt + (c * ax - s * ay) * half_dt2;
    out[1] += (s * vx + c * vy) * dt + (s * ax + c * ay) * half_dt2;
    out[2] = wrap_angle(x[2] + x[5] * dt);
    out[3] += ax * dt;
    out[4] += ay * dt;
    out
}

/// The Jacobian `F = ∂f/∂x` of [`predict_state`], analytic.
pub fn predict_jacobian(x: &StateVector, dt: f64) -> StateMatrix {
    let (s, c) = math::sin_cos(x[2]);
    let (vx, vy, ax, ay) = (x[3], x[4], x[6], x[7]);
    let half_dt2 = 0.5 * dt * dt;
    let mut f = StateMatrix::identity();
    // Position rows.
    f[(0, 2)] = (-s * vx - c * vy) * dt + (-s * ax - c * ay) * half_dt2;
    f[(0, 3)] = c * dt;
    f[(0, 4)] = -s * dt;
    f[(0, 6)] = c * half_dt2;
    f[(0, 7)] = -s * half_dt2;
    f[(1, 2)] = (c * vx - s * vy) * dt + (c * ax - s * ay) * half_dt2;
    f[(1, 3)] = s * dt;
    f[(1, 4)] = c * dt;
    f[(1, 6)] = s * half_dt2;
    f[(1, 7)] = c * half_dt2;
    // Heading and velocities.
    f[(2, 5)] = dt;
    f[(3, 6)] = dt;
    f[(4, 7)] = dt;
    f
}

/// The motion between two poses in the first one's frame, `Δ = P₁⁻¹ ∘ P₂ =
/// [R₁ᵀ (t₂ − t₁); wrap(ψ₂ − ψ₁)]`, with its Jacobians `∂Δ/∂P₁` and `∂Δ/∂P₂`.
///
/// robot_localization's differential mode (`ros_filter.cpp`, `preparePose`, step 7a)
/// takes this delta between consecutive readings of one pose sensor and divides it
/// by their time difference to get a body-frame velocity.
pub fn pose_delta(first: &Pose2, second: &Pose2) -> (Vector3<f64>, Matrix3<f64>, Matrix3<f64>) {
    let (s, c) = math::sin_cos(first.theta);
    let (dx, dy) = (second.x - first.x, second.y - first.y);
    let delta = Vector3::new(
        c * dx + s * dy,
        -s * dx + c * dy,
        wrap_angle(second.theta - first.theta),
    );
    let d_first = Matrix3::new(
        -c,
        -s,
        -s * dx + c * dy,
        s,
        -c,
        -c * dx - s * dy,
        0.0,
        0.0,
        -1.0,
    );
    let d_second = Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
    (delta, d_first, d_second)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn states() -> Vec<StateVector> {
        vec![
            StateVector::from_column_slice(&[0.0, 0.0, 0.0, 0.5, 0.0, 0.1, 0.0, 0.0]),
            StateVector::from_column_slice(&[1.0, -2.0, 2.9, 0.3, -0.05, -0.4, 0.2, -0.1]),
            StateVector::from_column_slice(&[-3.0, 0.5, -1.7, -0.2, 0.1, 0.8, -0.3, 0.25]),
        ]
    }

    /// Central finite differences of `f` at `x`, the yaw output wrapped.
    fn numeric_jacobian(x: &StateVector, dt: f64) -> StateMatrix {
        let h = 1e-6;
        let mut j = StateMatrix::zeros();
        for k in 0..STATE_SIZE {
            let mut plus = *x;
            let mut minus = *x;
            plus[k] += h;
            minus[k] -= h;
            let mut diff = predict_state(&plus, dt) - predict_state(&minus, dt);
            diff[2] = wrap_angle(diff[2]);
            j.set_column(k, &(diff / (2.0 * h)));
        }
        j
    }

    #[test]
    fn prediction_jacobian_matches_central_differences() {
        for x in states() {
            for dt in [0.01, 0.1, 1.3] {
                let analytic = predict_jacobian(&x, dt);
                let numeric = numeric_jacobian(&x, dt);
                let err = (analytic - numeric).abs().max();
                assert!(
                    err < 1e-8,
                    "dt {dt}: max error {err}\n{analytic}\n{numeric}"
                );
            }
        }
    }

    #[test]
    fn prediction_drives_along_the_heading() {
        // Heading 90°, 0.5 m/s forward for 2 s: 1 m along +y; constant yaw rate.
        let x = StateVector::from_column_slice(&[
            1.0,
            2.0,
            std::f64::consts::FRAC_PI_2,
            0.5,
            0.0,
            0.0,
            0.0,
            0.0,
        ]);
        let out = predict_state(&x, 2.0);
        assert!((out[0] - 1.0).abs() < 1e-12);
        assert!((out[1] - 3.0).abs() < 1e-12);
        // With an acceleration of 0.1 m/s² forward: ½ a t² = 0.2 m more, v grows by 0.2.
        let mut xa = x;
        xa[6] = 0.1;
        let out = predict_state(&xa, 2.0);
        assert!((out[1] - 3.2).abs() < 1e-12);
        assert!((out[3] - 0.7).abs() < 1e-12);
    }

    #[test]
    fn pose_delta_jacobians_match_central_differences() {
        let pairs = [
            (Pose2::new(0.0, 0.0, 0.0), Pose2::new(0.1, 0.02, 0.05)),
            (Pose2::new(1.0, -2.0, 3.0), Pose2::new(1.3, -1.9, -3.1)),
            (Pose2::new(-0.5, 4.0, -1.2), Pose2::new(-0.2, 3.5, -0.7)),
        ];
        let h = 1e-6;
        for (a, b) in pairs {
            let (delta, ja, jb) = pose_delta(&a, &b);
            // The delta composes back: a ∘ Δ = b.
            let back = a.compose(&Pose2::from_vector(&delta));
            assert!((back.x - b.x).abs() < 1e-12 && (back.y - b.y).abs() < 1e-12);
            assert!(wrap_angle(back.theta - b.theta).abs() < 1e-12);
            for k in 0..3 {
                let mut e = Vector3::zeros();
                e[k] = h;
                let shift = |p: &Pose2, s: f64| Pose2 {
                    x: p.x + s * e[0],
                    y: p.y + s * e[1],
                    theta: p.theta + s * e[2],
                };
                let mut da = pose_delta(&shift(&a, 1.0), &b).0 - pose_delta(&shift(&a, -1.0), &b).0;
                da[2] = wrap_angle(da[2]);
                let mut db = pose_delta(&a, &shift(&b, 1.0)).0 - pose_delta(&a, &shift(&b, -1.0)).0;
                db[2] = wrap_angle(db[2]);
                let ea = (ja.column(k) - da / (2.0 * h)).abs().max();
                let eb = (jb.column(k) - db / (2.0 * h)).abs().max();
                assert!(ea < 1e-8 && eb < 1e-8, "column {k}: {ea} {eb}");
            }
        }
    }
}
