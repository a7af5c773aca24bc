//! Two-wheel differential-drive motion (thesis `000` Sec. 2.5 and 3.4.1; slides `001`),
//! and motions as data sets record them ([`recorded`]: odometry readings, the ACFR car).

pub mod recorded;

pub use recorded::{
    CarGeometry, CarStep, OdometryStep, RecordedMotion, RecordedMotionError, RecordedStep,
};

use crate::geometry::{Pose2, wrap_angle};
use crate::math;
use nalgebra::{Matrix2, Matrix3, Matrix3x2, Vector2};
use serde::{Deserialize, Serialize};

/// A velocity command: forward speed `v` (m/s) and turn rate `w` (rad/s, counter-clockwise).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Control {
    /// Forward speed of the robot centre, m/s.
    pub v: f64,
    /// Turn rate, rad/s.
    pub w: f64,
}

impl Control {
    /// A command from forward speed and turn rate.
    pub fn new(v: f64, w: f64) -> Self {
        Self { v, w }
    }

    /// The command that wheel speeds `v_l`, `v_r` (m/s) produce on a robot whose
    /// wheels are `wheel_base` metres apart: `v = (v_l + v_r) / 2`,
    /// `w = (v_r - v_l) / D` (thesis Eq. 2.65, 2.66).
    ///
    /// A non-positive or non-finite wheel base gives `None`.
    pub fn from_wheel_speeds(v_l: f64, v_r: f64, wheel_base: f64) -> Option<Self> {
        (wheel_base.is_finite() && wheel_base > 0.0).then(|| Self {
            v: 0.5 * (v_l + v_r),
            w: (v_r - v_l) / wheel_base,
        })
    }

    /// The wheel speeds `(v_l, v_r)` that produce this command.
    pub fn to_wheel_speeds(&self, wheel_base: f64) -> (f64, f64) {
        let half = 0.5 * self.w * wheel_base;
        (self.v - half, self.v + half)
    }

    /// True when both components are finite.
    pub fn is_finite(&self) -> bool {
        self.v.is_finite() && self.w.is_finite()
    }
}

/// How a control moves the robot over one time step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MotionModel {
    /// Exact motion along a circular arc (thesis Eq. 2.70), with the straight-line
    /// limit when `w → 0`.
    #[default]
    ExactArc,
    /// First-order Euler step (thesis Eq. 2.68, the slides' model):
    /// `x += v cos θ Δt`, `y += v sin θ Δt`, `θ += w Δt`.
    Euler,
}

impl MotionModel {
    /// Every model, in menu order.
    pub const ALL: [MotionModel; 2] = [MotionModel::ExactArc, MotionModel::Euler];

    /// A short human-readable name.
    pub fn label(&self) -> &'static str {
        match self {
            MotionModel::ExactArc => "exact arc (thesis Eq. 2.70)",
            MotionModel::Euler => "Euler (slides)",
        }
    }
}

/// Below this `|w Δt|` the arc functions use their Taylor series, which are exact
/// to machine precision there and avoid dividing by a tiny angle.
const SMALL_ANGLE: f64 = 1e-4;

/// `A(φ) = sin φ / φ`, `B(φ) = (1 - cos φ) / φ` and their derivatives.
///
/// The arc displacement is `[Δx, Δy] = v Δt R(θ) [A(φ), B(φ)]` with `φ = w Δt`,
/// which is thesis Eq. 2.70 rearranged so that `w = 0` is an ordinary point:
/// `(v/w)(sin(θ+φ) - sin θ) = v Δt (cos θ A - sin θ B)` and
/// `(v/w)(cos θ - cos(θ+φ)) = v Δt (sin θ A + cos θ B)`.
fn arc_functions(phi: f64) -> (f64, f64, f64, f64) {
    if phi.abs() < SMALL_ANGLE {
        let p2 = phi * phi;
        let a = 1.0 - p2 / 6.0 + p2 * p2 / 120.0;
        let b = phi * (0.5 - p2 / 24.0 + p2 * p2 / 720.0);
        let da = phi * (-1.0 / 3.0 + p2 / 30.0);
        let db = 0.5 - p2 / 8.0 + p2 * p2 / 144.0;
        (a, b, da, db)
    } else {
        let (s, c) = math::sin_cos(phi);
        let a = s / phi;
        let b = (1.0 - c) / phi;
        let da = (phi * c - s) / (phi * phi);
        let db = (phi * s - (1.0 - c)) / (phi * phi);
        (a, b, da, db)
    }
}

/// The pose after one step, with its Jacobians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionStep {
    /// The new pose `f(x, u)`.
    pub pose: Pose2,
    /// `∂f/∂x`, 3x3 (thesis Eq. 3.34).
    pub jacobian_pose: Matrix3<f64>,
    /// `∂f/∂u` with `u = [v, w]`, 3x2.
    pub jacobian_control: Matrix3x2<f64>,
}

impl MotionModel {
    /// Moves `pose` by `control` for `dt` seconds.
    pub fn predict(&self, pose: &Pose2, control: &Control, dt: f64) -> Pose2 {
        self.step(pose, control, dt).pose
    }

    /// Moves `pose` by `control` for `dt` seconds and returns the Jacobians of the
    /// motion with respect to the pose and to the control.
    pub fn step(&self, pose: &Pose2, control: &Control, dt: f64) -> MotionStep {
        let phi = control.w * dt;
        let (a, b, da, db) = match self {
            MotionModel::ExactArc => arc_functions(phi),
            MotionModel::Euler => (1.0, 0.0, 0.0, 0.0),
        };
        let (s, c) = math::sin_cos(pose.theta);
        let rot = Matrix2::new(c, -s, s, c);
        let dist = control.v * dt;
        let delta = rot * Vector2::new(a, b) * dist;
        let new_pose = Pose2::new(
            pose.x + delta[0],
            pose.y + delta[1],
            wrap_angle(pose.theta + phi),
        );

        // ∂[Δx, Δy]/∂θ = R'(θ)[A, B] v Δt = [-Δy, Δx].
        let jacobian_pose = Matrix3::new(1.0, 0.0, -delta[1], 0.0, 1.0, delta[0], 0.0, 0.0, 1.0);
        // ∂/∂v = Δt R [A, B]; ∂/∂w = v Δt² R [A', B'] (chain rule through φ = w Δt).
        let d_dv = rot * Vector2::new(a, b) * dt;
        let d_dw = rot * Vector2::new(da, db) * (dist * dt);
        let jacobian_control = Matrix3x2::new(d_dv[0], d_dw[0], d_dv[1], d_dw[1], 0.0, dt);
        MotionStep {
            pose: new_pose,
            jacobian_pose,
            jacobian_control,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use std::f64::consts::PI;

    fn poses() -> Vec<Pose2> {
        vec![
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(1.5, -2.0, 2.8),
            Pose2::new(-4.0, 3.0, -1.2),
        ]
    }

    fn controls() -> Vec<Control> {
        vec![
            Control::new(1.0, PI / 10.0),
            Control::new(0.7, -2.5),
            Control::new(1.2, 0.0),
            Control::new(-0.5, 1e-7),
            Control::new(2.0, 3e-4),
            Control::new(0.0, 1.0),
        ]
    }

    fn pose_difference(a: &Pose2, b: &Pose2) -> Vector3<f64> {
        Vector3::new(a.x - b.x, a.y - b.y, wrap_angle(a.theta - b.theta))
    }

    #[test]
    fn exact_arc_matches_the_closed_form_of_eq_2_70() {
        let dt = 0.1;
        for pose in poses() {
            for u in controls().into_iter().filter(|u| u.w.abs() > 1e-2) {
                let p = MotionModel::ExactArc.predict(&pose, &u, dt);
                let r = u.v / u.w;
                let th = pose.theta;
                let x = pose.x - r * math::sin(th) + r * math::sin(th + u.w * dt);
                let y = pose.y + r * math::cos(th) - r * math::cos(th + u.w * dt);
                assert!(
                    (p.x - x).abs() < 1e-12 && (p.y - y).abs() < 1e-12,
                    "{pose:?} {u:?}"
                );
                assert!(wrap_angle(p.theta - (th + u.w * dt)).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn exact_arc_tends_to_the_straight_line() {
        let pose = Pose2::new(1.0, 2.0, 0.6);
        let straight = MotionModel::Euler.predict(&pose, &Control::new(1.3, 0.0), 0.5);
        let arc = MotionModel::ExactArc.predict(&pose, &Control::new(1.3, 0.0), 0.5);
        assert!(pose_difference(&arc, &straight).norm() < 1e-15);
        // Continuity across the series/closed-form switch.
        let below = MotionModel::ExactArc.predict(
            &pose,
            &Control::new(1.3, 0.999 * SMALL_ANGLE / 0.5),
            0.5,
        );
        let above = MotionModel::ExactArc.predict(
            &pose,
            &Control::new(1.3, 1.001 * SMALL_ANGLE / 0.5),
            0.5,
        );
        assert!(pose_difference(&below, &above).norm() < 1e-6);
    }

    #[test]
    fn a_full_circle_returns_to_the_start() {
        // Thesis Experiment 1: u = (1 m/s, π/10 rad/s); 200 steps of 0.1 s is one lap.
        let mut pose = Pose2::new(0.0, 0.0, 0.0);
        for _ in 0..200 {
            pose = MotionModel::ExactArc.predict(&pose, &Control::new(1.0, PI / 10.0), 0.1);
        }
        assert!(
            pose_difference(&pose, &Pose2::IDENTITY).norm() < 1e-9,
            "{pose:?}"
        );
    }

    #[test]
    fn jacobians_match_central_differences() {
        let h = 1e-6;
        for model in MotionModel::ALL {
            for pose in poses() {
                for u in controls() {
                    let dt = 0.1;
                    let step = model.step(&pose, &u, dt);
                    for k in 0..3 {
                        let mut plus = pose.to_vector();
                        let mut minus = pose.to_vector();
                        plus[k] += h;
                        minus[k] -= h;
                        // Build poses without wrapping the perturbed heading twice.
                        let fp = model.predict(
                            &Pose2 {
                                x: plus[0],
                                y: plus[1],
                                theta: plus[2],
                            },
                            &u,
                            dt,
                        );
                        let fm = model.predict(
                            &Pose2 {
                                x: minus[0],
                                y: minus[1],
                                theta: minus[2],
                            },
                            &u,
                            dt,
                        );
                        let numeric = pose_difference(&fp, &fm) / (2.0 * h);
                        let analytic = step.jacobian_pose.column(k);
                        assert!(
                            (numeric - analytic).norm() < 1e-7,
                            "{model:?} {pose:?} {u:?} col {k}"
                        );
                    }
                    for k in 0..2 {
                        let mut plus = u;
                        let mut minus = u;
                        if k == 0 {
                            plus.v += h;
                            minus.v -= h;
                        } else {
                            plus.w += h;
                            minus.w -= h;
                        }
                        let numeric = pose_difference(
                            &model.predict(&pose, &plus, dt),
                            &model.predict(&pose, &minus, dt),
                        ) / (2.0 * h);
                        let analytic = step.jacobian_control.column(k);
                        assert!(
                            (numeric - analytic).norm() < 1e-7,
                            "{model:?} {pose:?} {u:?} control col {k}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn wheel_speeds_round_trip() {
        let u = Control::from_wheel_speeds(0.8, 1.2, 0.4).unwrap_or_default();
        assert!((u.v - 1.0).abs() < 1e-12 && (u.w - 1.0).abs() < 1e-12);
        let (l, r) = u.to_wheel_speeds(0.4);
        assert!((l - 0.8).abs() < 1e-12 && (r - 1.2).abs() < 1e-12);
        assert!(Control::from_wheel_speeds(1.0, 1.0, 0.0).is_none());
        assert!(Control::from_wheel_speeds(1.0, 1.0, f64::NAN).is_none());
    }

    #[test]
    fn euler_and_arc_agree_to_first_order() {
        let pose = Pose2::new(0.0, 0.0, 0.3);
        let u = Control::new(1.0, 1.0);
        for dt in [1e-2, 1e-3] {
            let d = pose_difference(
                &MotionModel::ExactArc.predict(&pose, &u, dt),
                &MotionModel::Euler.predict(&pose, &u, dt),
            );
            // The difference is O(dt²): v w dt² / 2 in the lateral direction.
            assert!(
                (d.norm() - 0.5 * dt * dt).abs() < 0.1 * dt * dt,
                "dt {dt}: {}",
                d.norm()
            );
        }
    }
}
