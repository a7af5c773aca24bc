//! The range-bearing landmark sensor (thesis `000` Eq. 3.36-3.39).
//!
//! Measurements are ordered `[range, bearing]` as in the thesis. Bearing is
//! measured counter-clockwise from the robot's heading and always wrapped to
//! (-π, π]; innovations on bearing are wrapped too.

use crate::geometry::{Pose2, wrap_angle};
use crate::math;
use nalgebra::{Matrix2, Matrix2x3, Vector2};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Below this distance (metres) a landmark sits on the robot and its bearing is
/// undefined, so the measurement model and its Jacobians are not used.
pub const MIN_RANGE: f64 = 1e-3;

/// A range-bearing measurement of one landmark.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RangeBearing {
    /// Distance from the robot centre, metres.
    pub range: f64,
    /// Angle from the robot's heading, radians in (-π, π].
    pub bearing: f64,
}

impl RangeBearing {
    /// A measurement with its bearing wrapped.
    pub fn new(range: f64, bearing: f64) -> Self {
        Self {
            range,
            bearing: wrap_angle(bearing),
        }
    }

    /// As a vector `[range, bearing]`.
    pub fn to_vector(&self) -> Vector2<f64> {
        Vector2::new(self.range, self.bearing)
    }

    /// `self - other` with the bearing difference wrapped: the innovation.
    pub fn difference(&self, other: &RangeBearing) -> Vector2<f64> {
        Vector2::new(
            self.range - other.range,
            wrap_angle(self.bearing - other.bearing),
        )
    }

    /// True when both components are finite.
    pub fn is_finite(&self) -> bool {
        self.range.is_finite() && self.bearing.is_finite()
    }
}

/// Why a measurement model could not be evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Error)]
pub enum MeasurementError {
    /// The landmark is closer than [`MIN_RANGE`] to the robot.
    #[error(
        "landmark is {range:.2e} m from the robot, too close for a bearing (minimum {MIN_RANGE} m)"
    )]
    TooClose {
        /// The distance, metres.
        range: f64,
    },
    /// A first sighting whose range is no distance (below [`MIN_RANGE`]; Gaussian
    /// range noise gives such readings of landmarks close by): the inverse observation
    /// model would place the landmark on or behind the robot.
    #[error(
        "its first reading has range {range:.2} m, which cannot place it (the inverse \
         observation model needs a range above {MIN_RANGE} m); it waits for its next sighting"
    )]
    NoDistance {
        /// The measured range, metres.
        range: f64,
    },
    /// An input was NaN or infinite.
    #[error("measurement or state is not finite")]
    NotFinite,
}

/// The predicted measurement `h(x, l)` and its Jacobians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction {
    /// `h(x, l)` (thesis Eq. 3.37).
    pub measurement: RangeBearing,
    /// `∂h/∂x`, 2x3 (thesis Eq. 3.38, corrected: the range row is `[-dx/r, -dy/r, 0]`).
    pub jacobian_pose: Matrix2x3<f64>,
    /// `∂h/∂l`, 2x2 (thesis Eq. 3.39): the negative of the first two columns of `∂h/∂x`.
    pub jacobian_landmark: Matrix2<f64>,
}

/// Predicts what the robot at `pose` measures of a landmark at `landmark`.
pub fn predict(pose: &Pose2, landmark: &Vector2<f64>) -> Result<Prediction, MeasurementError> {
    if !pose.is_finite() || !landmark.iter().all(|v| v.is_finite()) {
        return Err(MeasurementError::NotFinite);
    }
    let dx = landmark[0] - pose.x;
    let dy = landmark[1] - pose.y;
    let q = dx * dx + dy * dy;
    let r = q.sqrt();
    if r < MIN_RANGE {
        return Err(MeasurementError::TooClose { range: r });
    }
    let measurement = RangeBearing::new(r, math::atan2(dy, dx) - pose.theta);
    // The thesis prints (L_x^i y - y_t) in Eq. 3.38/3.39; it is (L_y^i - y_t).
    let jacobian_landmark = Matrix2::new(dx / r, dy / r, -dy / q, dx / q);
    let jacobian_pose = Matrix2x3::new(-dx / r, -dy / r, 0.0, dy / q, -dx / q, -1.0);
    Ok(Prediction {
        measurement,
        jacobian_pose,
        jacobian_landmark,
    })
}

/// A landmark placed from one measurement, with the Jacobians of the inverse
/// observation model `g(x, z)` (thesis Eq. 3.8, 3.12, 3.36).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InverseObservation {
    /// `g(x, z) = [x + r cos(θ + b), y + r sin(θ + b)]`.
    pub landmark: Vector2<f64>,
    /// `∂g/∂x`, 2x3.
    pub jacobian_pose: Matrix2x3<f64>,
    /// `∂g/∂z`, 2x2.
    pub jacobian_measurement: Matrix2<f64>,
}

/// Where the measured landmark is, seen from `pose` (the inverse observation model).
pub fn inverse(pose: &Pose2, z: &RangeBearing) -> Result<InverseObservation, MeasurementError> {
    if !pose.is_finite() || !z.is_finite() {
        return Err(MeasurementError::NotFinite);
    }
    let angle = pose.theta + z.bearing;
    let (s, c) = math::sin_cos(angle);
    let landmark = Vector2::new(pose.x + z.range * c, pose.y + z.range * s);
    let jacobian_pose = Matrix2x3::new(1.0, 0.0, -z.range * s, 0.0, 1.0, z.range * c);
    let jacobian_measurement = Matrix2::new(c, -z.range * s, s, z.range * c);
    Ok(InverseObservation {
        landmark,
        jacobian_pose,
        jacobian_measurement,
    })
}

/// What the sensor can see and how noisy it is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RangeBearingSensor {
    /// Full field of view, radians, centred on the heading (2π sees all around).
    pub fov: f64,
    /// Maximum range, metres.
    pub max_range: f64,
    /// Standard deviation of the range noise, metres.
    pub range_std: f64,
    /// Standard deviation of the bearing noise, radians.
    pub bearing_std: f64,
}

impl RangeBearingSensor {
    /// The measurement noise covariance `V = diag(σ_r², σ_b²)`.
    pub fn noise_covariance(&self) -> Matrix2<f64> {
        Matrix2::new(self.range_std.powi(2), 0.0, 0.0, self.bearing_std.powi(2))
    }

    /// True when a landmark at `landmark` lies inside the field of view and range.
    pub fn sees(&self, pose: &Pose2, landmark: &Vector2<f64>) -> bool {
        let dx = landmark[0] - pose.x;
        let dy = landmark[1] - pose.y;
        let r = (dx * dx + dy * dy).sqrt();
        if !(r <= self.max_range) {
            return false;
        }
        let bearing = wrap_angle(math::atan2(dy, dx) - pose.theta);
        bearing.abs() <= 0.5 * self.fov
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cases() -> Vec<(Pose2, Vector2<f64>)> {
        vec![
            (Pose2::new(0.0, 0.0, 0.0), Vector2::new(3.0, 1.0)),
            (Pose2::new(1.0, -2.0, 2.5), Vector2::new(-1.0, 0.5)),
            (Pose2::new(-3.0, 4.0, -2.9), Vector2::new(-6.0, 3.9)),
            (Pose2::new(0.2, 0.1, 1.0), Vector2::new(0.25, 0.12)),
        ]
    }

    #[test]
    fn observation_jacobians_match_central_differences() {
        let h = 1e-6;
        for (pose, lm) in cases() {
            let p = predict(&pose, &lm).unwrap_or_else(|e| panic!("{e}"));
            for k in 0..3 {
                let mut plus = pose.to_vector();
                let mut minus = pose.to_vector();
                plus[k] += h;
                minus[k] -= h;
                let zp = predict(
                    &Pose2 {
                        x: plus[0],
                        y: plus[1],
                        theta: plus[2],
                    },
                    &lm,
                )
                .unwrap_or_else(|e| panic!("{e}"));
                let zm = predict(
                    &Pose2 {
                        x: minus[0],
                        y: minus[1],
                        theta: minus[2],
                    },
                    &lm,
                )
                .unwrap_or_else(|e| panic!("{e}"));
                let numeric = zp.measurement.difference(&zm.measurement) / (2.0 * h);
                assert!(
                    (numeric - p.jacobian_pose.column(k)).norm() < 1e-6,
                    "{pose:?} {lm:?} col {k}"
                );
            }
            for k in 0..2 {
                let mut plus = lm;
                let mut minus = lm;
                plus[k] += h;
                minus[k] -= h;
                let zp = predict(&pose, &plus).unwrap_or_else(|e| panic!("{e}"));
                let zm = predict(&pose, &minus).unwrap_or_else(|e| panic!("{e}"));
                let numeric = zp.measurement.difference(&zm.measurement) / (2.0 * h);
                assert!(
                    (numeric - p.jacobian_landmark.column(k)).norm() < 1e-6,
                    "{pose:?} {lm:?} lm col {k}"
                );
            }
            // The landmark columns are the negatives of the robot's position columns.
            assert!((p.jacobian_landmark + p.jacobian_pose.fixed_columns::<2>(0)).norm() < 1e-15);
        }
    }

    #[test]
    fn inverse_jacobians_match_central_differences() {
        let h = 1e-6;
        for (pose, lm) in cases() {
            let z = predict(&pose, &lm)
                .unwrap_or_else(|e| panic!("{e}"))
                .measurement;
            let g = inverse(&pose, &z).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                (g.landmark - lm).norm() < 1e-12,
                "inverse of the observation recovers the landmark"
            );
            for k in 0..3 {
                let mut plus = pose.to_vector();
                let mut minus = pose.to_vector();
                plus[k] += h;
                minus[k] -= h;
                let gp = inverse(
                    &Pose2 {
                        x: plus[0],
                        y: plus[1],
                        theta: plus[2],
                    },
                    &z,
                )
                .unwrap_or_else(|e| panic!("{e}"));
                let gm = inverse(
                    &Pose2 {
                        x: minus[0],
                        y: minus[1],
                        theta: minus[2],
                    },
                    &z,
                )
                .unwrap_or_else(|e| panic!("{e}"));
                let numeric = (gp.landmark - gm.landmark) / (2.0 * h);
                assert!((numeric - g.jacobian_pose.column(k)).norm() < 1e-7);
            }
            let zv = z.to_vector();
            for k in 0..2 {
                let mut plus = zv;
                let mut minus = zv;
                plus[k] += h;
                minus[k] -= h;
                let gp = inverse(
                    &pose,
                    &RangeBearing {
                        range: plus[0],
                        bearing: plus[1],
                    },
                )
                .unwrap_or_else(|e| panic!("{e}"));
                let gm = inverse(
                    &pose,
                    &RangeBearing {
                        range: minus[0],
                        bearing: minus[1],
                    },
                )
                .unwrap_or_else(|e| panic!("{e}"));
                let numeric = (gp.landmark - gm.landmark) / (2.0 * h);
                assert!((numeric - g.jacobian_measurement.column(k)).norm() < 1e-7);
            }
        }
    }

    #[test]
    fn bearing_innovation_wraps_across_pi() {
        let a = RangeBearing::new(1.0, std::f64::consts::PI - 0.01);
        let b = RangeBearing::new(1.0, -std::f64::consts::PI + 0.01);
        assert!((a.difference(&b)[1] + 0.02).abs() < 1e-12);
        assert!((b.difference(&a)[1] - 0.02).abs() < 1e-12);
    }

    #[test]
    fn a_landmark_on_the_robot_is_an_error_not_a_nan() {
        let pose = Pose2::new(1.0, 1.0, 0.0);
        assert!(matches!(
            predict(&pose, &Vector2::new(1.0, 1.0)),
            Err(MeasurementError::TooClose { .. })
        ));
        assert!(matches!(
            predict(&pose, &Vector2::new(f64::NAN, 1.0)),
            Err(MeasurementError::NotFinite)
        ));
        assert!(matches!(
            inverse(
                &pose,
                &RangeBearing {
                    range: f64::INFINITY,
                    bearing: 0.0
                }
            ),
            Err(MeasurementError::NotFinite)
        ));
    }

    #[test]
    fn field_of_view_and_range_limit_what_is_seen() {
        let sensor = RangeBearingSensor {
            fov: std::f64::consts::FRAC_PI_2,
            max_range: 5.0,
            range_std: 0.1,
            bearing_std: 0.1,
        };
        let pose = Pose2::new(0.0, 0.0, 0.0);
        assert!(sensor.sees(&pose, &Vector2::new(3.0, 0.0)));
        assert!(sensor.sees(&pose, &Vector2::new(3.0, 2.9)));
        assert!(!sensor.sees(&pose, &Vector2::new(3.0, 3.1)));
        assert!(!sensor.sees(&pose, &Vector2::new(-3.0, 0.0)));
        assert!(!sensor.sees(&pose, &Vector2::new(5.1, 0.0)));
        assert!(!sensor.sees(&pose, &Vector2::new(f64::NAN, 0.0)));
    }
}
