//! Motions as data sets record them, beside the velocity commands of
//! [`MotionModel`](super::MotionModel): the odometry reading `(δrot1, δtrans,
//! δrot2)` of the Freiburg Robot Mapping course (Probabilistic Robotics Sec. 5.4),
//! and the ACFR car model of Victoria Park (Guivant and Nebot 2001).
//!
//! Both move the robot by an increment `δ(u)` in its own frame, which depends on
//! the input `u` only:
//!
//! ```text
//! x' = x ⊕ δ(u):   [x', y'] = [x, y] + R(θ) [δx, δy],   θ' = θ + δθ
//! F = ∂x'/∂x = [1 0 −Δy; 0 1 Δx; 0 0 1]   with [Δx, Δy] = R(θ) [δx, δy]
//! G = ∂x'/∂u = diag(R(θ), 1) ∂δ/∂u
//! ```
//!
//! The input carries independent Gaussian noise (a standard deviation per
//! component), so a filter's process noise is `G diag(σ²) Gᵀ`; the unscented
//! filter and the particle filters push perturbed inputs through `δ` itself. A
//! robot standing still (a zero odometry reading, a car at zero speed) gets no
//! noise, as a commanded stop gets none in the simulated world.

use crate::geometry::{Pose2, wrap_angle};
use crate::math;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// One odometry reading of the Freiburg course's files: rotate `rot1` towards
/// the direction of travel, translate `trans`, rotate `rot2` (Probabilistic
/// Robotics Sec. 5.4, Eq. 5.34-5.36 read forwards; the course's
/// `prediction_step`), with the standard deviation the filter assumes on each.
///
/// `δ = [trans cos rot1, trans sin rot1, rot1 + rot2]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OdometryStep {
    /// First rotation, radians.
    pub rot1: f64,
    /// Translation, metres.
    pub trans: f64,
    /// Second rotation, radians.
    pub rot2: f64,
    /// Standard deviation of each rotation, radians.
    pub rot_std: f64,
    /// Standard deviation of the translation, metres.
    pub trans_std: f64,
}

/// The geometry of the ACFR car (Victoria Park's `acfr-info.txt`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CarGeometry {
    /// Wheelbase `L`: rear axle to front axle, metres.
    pub wheelbase: f64,
    /// `H`: the encoder wheel's offset to the left of the rear axle's centre, metres.
    pub encoder_offset: f64,
    /// `a`: the laser's distance ahead of the rear axle, metres.
    pub laser_ahead: f64,
    /// `b`: the laser's distance to the left of the car's centre line, metres.
    pub laser_left: f64,
}

impl CarGeometry {
    /// Victoria Park's car (`acfr-info.txt`): `L = 2.83 m`, `H = 0.76 m`,
    /// `b = 0.5 m`, and the laser `a = 3.78 m` ahead of the rear axle: the file's
    /// `a = 0.95 m` is measured from the front axle (the laser sits on the front
    /// bumper), as Guivant's own code and the usual implementations take it. The
    /// data agree: the trees of consecutive scans, placed by dead reckoning, lie
    /// closer together with 3.78 m than with 0.95 m (`docs/real-landmark-data.md`).
    pub const VICTORIA_PARK: CarGeometry = CarGeometry {
        wheelbase: 2.83,
        encoder_offset: 0.76,
        laser_ahead: 3.78,
        laser_left: 0.5,
    };
}

/// The ACFR car's input over `dt` seconds: the encoder's speed and the steering
/// angle (Guivant and Nebot, IEEE T-RA 17(3), 2001, Sec. II), with the standard
/// deviations the filter assumes on them. The pose it moves is the laser's.
///
/// The encoder's speed is first moved to the rear axle's centre,
/// `v_c = v / (1 − tan(α) H / L)`, the car turns at `ω = v_c tan(α) / L`, and the
/// laser at `(a, b)` in the car's frame moves with the rigid body (the paper's
/// model, Euler-integrated over `dt` as there):
///
/// ```text
/// x' = x + dt (v_c cos φ − (v_c / L) tan α (a sin φ + b cos φ))
/// y' = y + dt (v_c sin φ + (v_c / L) tan α (a cos φ − b sin φ))
/// φ' = φ + dt (v_c / L) tan α
/// ```
///
/// that is `δ = dt [v_c − ω b, ω a, ω]` in the laser's frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CarStep {
    /// The encoder's speed, m/s.
    pub speed: f64,
    /// Steering angle, radians (positive to the left).
    pub steering: f64,
    /// Time the input is held, seconds.
    pub dt: f64,
    /// The car.
    pub car: CarGeometry,
    /// Standard deviation of the speed, m/s.
    pub speed_std: f64,
    /// Standard deviation of the steering angle, radians.
    pub steering_std: f64,
}

/// The steering angle beyond which the speed cannot be moved to the rear axle:
/// `1 − tan(α) H / L` must stay above this.
const MIN_AXLE_FACTOR: f64 = 0.1;

/// A motion as a data set records it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum RecordedMotion {
    /// An odometry reading `(δrot1, δtrans, δrot2)`.
    Odometry(OdometryStep),
    /// The ACFR car's speed and steering over a time step.
    Car(CarStep),
}

/// Why a recorded motion cannot move a pose.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RecordedMotionError {
    /// A value is NaN or infinite, a standard deviation negative, or a time step negative.
    #[error(
        "the recorded motion has a value that is not finite, a negative standard deviation or a negative time step: {0:?}"
    )]
    NotFinite(RecordedMotion),
    /// The steering is so sharp that the encoder's speed cannot be moved to the axle.
    #[error(
        "steering {steering} rad is too sharp for the car model (1 − tan(α) H / L = {factor:.3} must exceed 0.1)"
    )]
    SteeringTooSharp {
        /// The steering angle, radians.
        steering: f64,
        /// `1 − tan(α) H / L`.
        factor: f64,
    },
}

/// The pose after a recorded motion, with its Jacobians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordedStep {
    /// The new pose `x ⊕ δ(u)`.
    pub pose: Pose2,
    /// `F = ∂x'/∂x`.
    pub jacobian_pose: Matrix3<f64>,
    /// `G = ∂x'/∂u` (its first [`RecordedMotion::input_dim`] columns; the rest zero).
    pub jacobian_input: Matrix3<f64>,
    /// The input's noise covariance `diag(σ²)` (zero where unused, and zero when
    /// the robot stands still).
    pub input_covariance: Matrix3<f64>,
}

impl RecordedMotion {
    /// The number of input components: 3 for odometry, 2 for the car.
    pub fn input_dim(&self) -> usize {
        match self {
            RecordedMotion::Odometry(_) => 3,
            RecordedMotion::Car(_) => 2,
        }
    }

    /// The input `u` as recorded (unused components zero).
    pub fn input(&self) -> [f64; 3] {
        match self {
            RecordedMotion::Odometry(o) => [o.rot1, o.trans, o.rot2],
            RecordedMotion::Car(c) => [c.speed, c.steering, 0.0],
        }
    }

    /// True when the robot stands still: a zero odometry reading, a car at zero speed.
    pub fn is_still(&self) -> bool {
        match self {
            RecordedMotion::Odometry(o) => o.rot1 == 0.0 && o.trans == 0.0 && o.rot2 == 0.0,
            RecordedMotion::Car(c) => c.speed == 0.0,
        }
    }

    /// The standard deviation of each input component (unused ones zero; all
    /// zero when the robot stands still).
    pub fn input_std(&self) -> [f64; 3] {
        if self.is_still() {
            return [0.0; 3];
        }
        match self {
            RecordedMotion::Odometry(o) => [o.rot_std, o.trans_std, o.rot_std],
            RecordedMotion::Car(c) => [c.speed_std, c.steering_std, 0.0],
        }
    }

    /// The robot's forward speed and turn rate, for motions that have them: the
    /// car's `(v_c, ω)` at the rear axle. `None` for an odometry reading (it has
    /// no duration).
    pub fn velocity(&self) -> Option<crate::motion::Control> {
        match self {
            RecordedMotion::Odometry(_) => None,
            RecordedMotion::Car(c) => {
                let (v_c, w) = car_velocity(c, c.speed, c.steering).ok()?;
                Some(crate::motion::Control::new(v_c, w))
            }
        }
    }

    /// Checks that every value is finite, every standard deviation and time step
    /// not negative, and the steering not too sharp.
    pub fn validate(&self) -> Result<(), RecordedMotionError> {
        let values: &[f64] = match self {
            RecordedMotion::Odometry(o) => &[o.rot1, o.trans, o.rot2, o.rot_std, o.trans_std],
            RecordedMotion::Car(c) => &[
                c.speed,
                c.steering,
                c.dt,
                c.speed_std,
                c.steering_std,
                c.car.wheelbase,
                c.car.encoder_offset,
                c.car.laser_ahead,
                c.car.laser_left,
            ],
        };
        let negative = match self {
            RecordedMotion::Odometry(o) => o.rot_std < 0.0 || o.trans_std < 0.0,
            RecordedMotion::Car(c) => {
                c.dt < 0.0 || c.speed_std < 0.0 || c.steering_std < 0.0 || !(c.car.wheelbase > 0.0)
            }
        };
        if negative || !values.iter().all(|v| v.is_finite()) {
            return Err(RecordedMotionError::NotFinite(*self));
        }
        if let RecordedMotion::Car(c) = self {
            car_velocity(c, c.speed, c.steering)?;
        }
        Ok(())
    }

    /// The increment `δ(u)` in the robot's frame for input `u` (the recorded one,
    /// or a perturbed one), with `∂δ/∂u`.
    pub fn increment(
        &self,
        u: &[f64; 3],
    ) -> Result<(Vector3<f64>, Matrix3<f64>), RecordedMotionError> {
        match self {
            RecordedMotion::Odometry(_) => {
                let [rot1, trans, rot2] = *u;
                let (s, c) = math::sin_cos(rot1);
                let delta = Vector3::new(trans * c, trans * s, rot1 + rot2);
                #[rustfmt::skip]
                let jacobian = Matrix3::new(
                    -trans * s, c,   0.0,
                    trans * c,  s,   0.0,
                    1.0,        0.0, 1.0,
                );
                Ok((delta, jacobian))
            }
            RecordedMotion::Car(step) => {
                let [speed, steering, _] = *u;
                let CarGeometry {
                    wheelbase: l,
                    encoder_offset: h,
                    laser_ahead: a,
                    laser_left: b,
                } = step.car;
                let (v_c, w) = car_velocity(step, speed, steering)?;
                let k = math::tan(steering);
                let sec2 = 1.0 + k * k;
                let factor = 1.0 - k * h / l;
                // ∂v_c/∂v = 1/s, ∂v_c/∂α = v (H/L) sec²α / s², ∂ω/∂· = (∂v_c k + v_c ∂k) / L.
                let dvc_dv = 1.0 / factor;
                let dvc_da = speed * (h / l) * sec2 / (factor * factor);
                let dw_dv = dvc_dv * k / l;
                let dw_da = (dvc_da * k + v_c * sec2) / l;
                let dt = step.dt;
                let delta = Vector3::new(dt * (v_c - w * b), dt * w * a, dt * w);
                #[rustfmt::skip]
                let jacobian = Matrix3::new(
                    dt * (dvc_dv - dw_dv * b), dt * (dvc_da - dw_da * b), 0.0,
                    dt * dw_dv * a,            dt * dw_da * a,            0.0,
                    dt * dw_dv,                dt * dw_da,                0.0,
                );
                Ok((delta, jacobian))
            }
        }
    }

    /// Moves `pose` by the recorded input perturbed by `noise` (added to `u`).
    pub fn apply(&self, pose: &Pose2, noise: &[f64; 3]) -> Result<Pose2, RecordedMotionError> {
        let u = self.input();
        let perturbed = [u[0] + noise[0], u[1] + noise[1], u[2] + noise[2]];
        let (delta, _) = self.increment(&perturbed)?;
        Ok(compose(pose, &delta))
    }

    /// Moves `pose` by the recorded input, with the Jacobians and the input's noise.
    pub fn step(&self, pose: &Pose2) -> Result<RecordedStep, RecordedMotionError> {
        self.validate()?;
        let (delta, d_delta) = self.increment(&self.input())?;
        let (s, c) = math::sin_cos(pose.theta);
        let moved = Vector3::new(
            c * delta[0] - s * delta[1],
            s * delta[0] + c * delta[1],
            delta[2],
        );
        #[rustfmt::skip]
        let rotation = Matrix3::new(
            c,   -s,  0.0,
            s,   c,   0.0,
            0.0, 0.0, 1.0,
        );
        #[rustfmt::skip]
        let jacobian_pose = Matrix3::new(
            1.0, 0.0, -moved[1],
            0.0, 1.0, moved[0],
            0.0, 0.0, 1.0,
        );
        let std = self.input_std();
        Ok(RecordedStep {
            pose: Pose2::new(
                pose.x + moved[0],
                pose.y + moved[1],
                wrap_angle(pose.theta + moved[2]),
            ),
            jacobian_pose,
            jacobian_input: rotation * d_delta,
            input_covariance: Matrix3::from_diagonal(&Vector3::new(
                std[0] * std[0],
                std[1] * std[1],
                std[2] * std[2],
            )),
        })
    }
}

/// `pose ⊕ δ`.
fn compose(pose: &Pose2, delta: &Vector3<f64>) -> Pose2 {
    let (s, c) = math::sin_cos(pose.theta);
    Pose2::new(
        pose.x + c * delta[0] - s * delta[1],
        pose.y + s * delta[0] + c * delta[1],
        wrap_angle(pose.theta + delta[2]),
    )
}

/// The car's speed at the rear axle's centre and its turn rate:
/// `v_c = v / (1 − tan(α) H / L)`, `ω = v_c tan(α) / L`.
fn car_velocity(
    step: &CarStep,
    speed: f64,
    steering: f64,
) -> Result<(f64, f64), RecordedMotionError> {
    let k = math::tan(steering);
    let factor = 1.0 - k * step.car.encoder_offset / step.car.wheelbase;
    if !(factor > MIN_AXLE_FACTOR) {
        return Err(RecordedMotionError::SteeringTooSharp { steering, factor });
    }
    let v_c = speed / factor;
    Ok((v_c, v_c * k / step.car.wheelbase))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::motion::{Control, MotionModel};

    /// An odometry reading with 0.01 rad and 0.02 m of noise.
    pub(crate) fn odometry(rot1: f64, trans: f64, rot2: f64) -> RecordedMotion {
        RecordedMotion::Odometry(OdometryStep {
            rot1,
            trans,
            rot2,
            rot_std: 0.01,
            trans_std: 0.02,
        })
    }

    /// A Victoria Park car input of 25 ms, 0.5 m/s and 0.05 rad of noise.
    pub(crate) fn car(speed: f64, steering: f64) -> RecordedMotion {
        RecordedMotion::Car(CarStep {
            speed,
            steering,
            dt: 0.025,
            car: CarGeometry::VICTORIA_PARK,
            speed_std: 0.5,
            steering_std: 0.05,
        })
    }

    fn poses() -> [Pose2; 3] {
        [
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(1.5, -2.0, 2.8),
            Pose2::new(-4.0, 3.0, -1.2),
        ]
    }

    fn motions() -> Vec<RecordedMotion> {
        vec![
            odometry(0.1, 0.1, 0.0002),
            odometry(-2.0, 0.7, 1.1),
            odometry(0.3, 0.0, -0.2),
            car(3.0, 0.05),
            car(2.0, -0.4),
            car(-1.0, 0.3),
            car(5.0, 0.0),
        ]
    }

    fn difference(a: &Pose2, b: &Pose2) -> Vector3<f64> {
        Vector3::new(a.x - b.x, a.y - b.y, wrap_angle(a.theta - b.theta))
    }

    #[test]
    fn odometry_moves_as_the_course_prediction_step() {
        // The course's prediction: x + t cos(θ + r1), y + t sin(θ + r1), θ + r1 + r2.
        let pose = Pose2::new(1.0, 2.0, 0.4);
        let step = odometry(0.3, 0.8, -0.1).step(&pose).unwrap();
        assert!((step.pose.x - (1.0 + 0.8 * math::cos(0.7))).abs() < 1e-15);
        assert!((step.pose.y - (2.0 + 0.8 * math::sin(0.7))).abs() < 1e-15);
        assert!((step.pose.theta - 0.6).abs() < 1e-15);
    }

    #[test]
    fn the_car_model_is_the_papers_equations() {
        let (speed, steering, dt) = (3.0, 0.2, 0.025);
        let CarGeometry {
            wheelbase: l,
            encoder_offset: h,
            laser_ahead: a,
            laser_left: b,
        } = CarGeometry::VICTORIA_PARK;
        let pose = Pose2::new(2.0, -1.0, 0.7);
        let step = car(speed, steering).step(&pose).unwrap();
        let tan = math::tan(steering);
        let v_c = speed / (1.0 - tan * h / l);
        let phi = pose.theta;
        let x = pose.x
            + dt * (v_c * math::cos(phi)
                - v_c / l * tan * (a * math::sin(phi) + b * math::cos(phi)));
        let y = pose.y
            + dt * (v_c * math::sin(phi)
                + v_c / l * tan * (a * math::cos(phi) - b * math::sin(phi)));
        let theta = phi + dt * v_c / l * tan;
        assert!((step.pose.x - x).abs() < 1e-14, "{} {x}", step.pose.x);
        assert!((step.pose.y - y).abs() < 1e-14);
        assert!((step.pose.theta - theta).abs() < 1e-14);
        let velocity = car(speed, steering).velocity().unwrap();
        assert!((velocity.v - v_c).abs() < 1e-14 && (velocity.w - v_c * tan / l).abs() < 1e-14);
    }

    #[test]
    fn a_car_with_its_laser_on_the_axle_moves_like_the_euler_velocity_model() {
        // With a = b = H = 0 the laser is the axle's centre and the model is the
        // unicycle's Euler step with (v, v tan α / L).
        let step = CarStep {
            car: CarGeometry {
                wheelbase: 2.83,
                encoder_offset: 0.0,
                laser_ahead: 0.0,
                laser_left: 0.0,
            },
            ..match car(3.0, 0.2) {
                RecordedMotion::Car(c) => c,
                RecordedMotion::Odometry(_) => unreachable!(),
            }
        };
        let pose = Pose2::new(2.0, -1.0, 0.7);
        let ours = RecordedMotion::Car(step).step(&pose).unwrap().pose;
        let w = 3.0 * math::tan(0.2) / 2.83;
        let euler = MotionModel::Euler.predict(&pose, &Control::new(3.0, w), 0.025);
        assert!(difference(&ours, &euler).norm() < 1e-15);
    }

    #[test]
    fn jacobians_match_central_differences() {
        let h = 1e-6;
        for motion in motions() {
            for pose in poses() {
                let step = motion.step(&pose).unwrap();
                for k in 0..3 {
                    let mut plus = pose;
                    let mut minus = pose;
                    match k {
                        0 => (plus.x, minus.x) = (pose.x + h, pose.x - h),
                        1 => (plus.y, minus.y) = (pose.y + h, pose.y - h),
                        _ => (plus.theta, minus.theta) = (pose.theta + h, pose.theta - h),
                    }
                    let numeric = difference(
                        &motion.apply(&plus, &[0.0; 3]).unwrap(),
                        &motion.apply(&minus, &[0.0; 3]).unwrap(),
                    ) / (2.0 * h);
                    assert!(
                        (numeric - step.jacobian_pose.column(k)).norm() < 1e-7,
                        "{motion:?} {pose:?} pose column {k}"
                    );
                }
                for k in 0..3 {
                    let mut e = [0.0; 3];
                    e[k] = h;
                    let numeric = difference(
                        &motion.apply(&pose, &e).unwrap(),
                        &motion.apply(&pose, &e.map(|v| -v)).unwrap(),
                    ) / (2.0 * h);
                    let analytic = if k < motion.input_dim() {
                        step.jacobian_input.column(k).into_owned()
                    } else {
                        Vector3::zeros()
                    };
                    assert!(
                        (numeric - analytic).norm() < 1e-7,
                        "{motion:?} {pose:?} input column {k}: {numeric} vs {analytic}"
                    );
                }
            }
        }
    }

    #[test]
    fn standing_still_has_no_noise_and_bad_inputs_are_refused() {
        assert_eq!(odometry(0.0, 0.0, 0.0).input_std(), [0.0; 3]);
        assert_eq!(car(0.0, 0.3).input_std(), [0.0; 3]);
        assert_eq!(odometry(0.1, 0.0, 0.0).input_std(), [0.01, 0.02, 0.01]);
        assert_eq!(car(1.0, 0.0).input_std(), [0.5, 0.05, 0.0]);
        let still = car(0.0, 0.3).step(&Pose2::new(1.0, 2.0, 0.3)).unwrap();
        assert_eq!(still.pose, Pose2::new(1.0, 2.0, 0.3));
        assert_eq!(still.input_covariance, Matrix3::zeros());
        assert!(matches!(
            odometry(f64::NAN, 0.1, 0.0).step(&Pose2::IDENTITY),
            Err(RecordedMotionError::NotFinite(_))
        ));
        // tan(α) H / L ≥ 0.9: α ≥ 73.4°.
        assert!(matches!(
            car(1.0, 1.3).step(&Pose2::IDENTITY),
            Err(RecordedMotionError::SteeringTooSharp { .. })
        ));
        assert!(car(1.0, 1.2).step(&Pose2::IDENTITY).is_ok());
        let mut negative = car(1.0, 0.1);
        if let RecordedMotion::Car(c) = &mut negative {
            c.dt = -0.1;
        }
        assert!(negative.validate().is_err());
    }
}
