//! UKF-SLAM (thesis `000` Sec. 3.3, with the errata in the seeds' README).

use super::state::{KeepsSlamState, SlamState, check_control, check_measurement};
use super::unscented::{UnscentedOutput, UnscentedParams, sigma_points, unscented_transform};
use super::{FilterConfig, FilterError, LandmarkSlam, PredictReport, UpdateReport, symmetrize};
use crate::belief::{JointGaussian, PoseBelief};
use crate::geometry::{Pose2, wrap_angle};
use crate::linalg::psd_cholesky;
use crate::motion::{Control, RecordedMotion};
use crate::range_bearing::{self, MeasurementError, RangeBearing};
use nalgebra::{DMatrix, DVector, Dim, Matrix, Matrix2, RawStorage, Vector2};

/// UKF-SLAM with known data association.
///
/// * Prediction (Eq. 3.26-3.30): sigma points over the robot and the control
///   noise together (the augmented form), so the control noise is propagated
///   once; the thesis's Eq. 3.28 adds it twice. The robot-landmark cross terms
///   come from the same sigma points (Eq. 3.29); `P_LL` is unchanged (Eq. 3.30).
/// * New landmark (Eq. 3.21-3.25): the inverse observation model through sigma
///   points over the robot and the measurement noise; the cross-covariance uses
///   the covariance weights `Wᶜ` (Eq. 3.24 prints `Wᵐ`).
/// * Update (Sec. 3.3.3): sigma points over the robot and the measured landmark;
///   bearing averaged on the circle and differenced with wrapping; gain
///   `K = P_My P_yy⁻¹` and `P = P̄ − K P_yy Kᵀ` (the thesis prints `P_yM P_yyᵀ`
///   and `+`), followed by symmetrization.
#[derive(Clone, Debug)]
pub struct UkfSlam {
    config: FilterConfig,
    params: UnscentedParams,
    state: SlamState,
}

fn pose_of(a: &DVector<f64>) -> Pose2 {
    Pose2 {
        x: a[0],
        y: a[1],
        theta: a[2],
    }
}

impl UkfSlam {
    /// A filter whose robot starts at `start` with zero covariance (thesis Eq. 3.5).
    pub fn new(
        config: FilterConfig,
        params: UnscentedParams,
        start: Pose2,
    ) -> Result<Self, FilterError> {
        let state = SlamState::new(&config, start)?;
        // Check every dimension the filter uses: 3 for drawing, 5 for its phases.
        params.weights(3)?;
        params.weights(5)?;
        Ok(Self {
            config,
            params,
            state,
        })
    }

    /// The robot's mean and covariance extended by the `k` noise components of
    /// the `k x k` covariance `noise` (zero mean, independent of the robot): the
    /// augmented state the predictions (control or recorded-input noise) and the
    /// landmark initialization (measurement noise) draw sigma points from.
    fn robot_with_noise<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &self,
        noise: &Matrix<f64, R, C, S>,
    ) -> (DVector<f64>, DMatrix<f64>) {
        let k = noise.nrows();
        let mut mean = DVector::zeros(3 + k);
        mean.rows_mut(0, 3).copy_from(&self.state.mean.rows(0, 3));
        let mut cov = DMatrix::zeros(3 + k, 3 + k);
        cov.view_mut((0, 0), (3, 3))
            .copy_from(&self.state.covariance.view((0, 0), (3, 3)));
        for i in 0..k {
            for j in 0..k {
                cov[(3 + i, 3 + j)] = noise[(i, j)];
            }
        }
        (mean, cov)
    }

    /// Writes the robot's predicted mean, covariance and its cross-covariance with
    /// the landmarks (`out`, the unscented transform of the robot block) into the
    /// state; a prediction that is not finite changes nothing.
    fn take_robot_prediction(
        &mut self,
        out: &UnscentedOutput,
        control: Control,
        robot_det_before: f64,
    ) -> Result<PredictReport, FilterError> {
        if !out.is_finite() {
            return Err(FilterError::NonFinite {
                what: "the predicted robot pose or covariance",
            });
        }
        self.state.mean.rows_mut(0, 3).copy_from(&out.mean);
        self.state.mean[2] = wrap_angle(self.state.mean[2]);
        self.state
            .covariance
            .view_mut((0, 0), (3, 3))
            .copy_from(&out.covariance);
        self.state
            .set_landmark_robot_covariance(&out.cross_other.fixed_columns::<3>(0).into_owned());
        Ok(PredictReport {
            control,
            robot_det_before,
            robot_det_after: self.robot_covariance().determinant(),
        })
    }

    /// The unscented-transform parameters.
    pub fn params(&self) -> &UnscentedParams {
        &self.params
    }

    fn initialize(&mut self, id: usize, z: &RangeBearing) -> Result<UpdateReport, FilterError> {
        let n = self.state.len();
        let (mean_a, p_aa) = self.robot_with_noise(&self.config.noise.measurement_covariance());
        let mut p_oa = DMatrix::zeros(n, 5);
        p_oa.view_mut((0, 0), (n, 3))
            .copy_from(&self.state.covariance.columns(0, 3));
        let out = unscented_transform(&self.params, &mean_a, &p_aa, &p_oa, &[], |a| {
            let zi = RangeBearing {
                range: z.range + a[3],
                bearing: z.bearing + a[4],
            };
            match range_bearing::inverse(&pose_of(a), &zi) {
                Ok(g) => DVector::from_column_slice(g.landmark.as_slice()),
                Err(_) => DVector::from_element(2, f64::NAN),
            }
        })?;
        if !out.is_finite() {
            return Err(FilterError::Measurement {
                id,
                source: MeasurementError::NotFinite,
            });
        }
        let position = Vector2::new(out.mean[0], out.mean[1]);
        let covariance = Matrix2::from_iterator(out.covariance.iter().copied());
        self.state.push_landmark(
            id,
            position,
            &out.cross_other.fixed_columns::<2>(0).into_owned(),
            &covariance,
        );
        Ok(UpdateReport::Initialized { id, position })
    }

    fn correct(
        &mut self,
        id: usize,
        slot: usize,
        z: &RangeBearing,
    ) -> Result<UpdateReport, FilterError> {
        let n = self.state.mean.len();
        let j = 3 + 2 * slot;
        let active = [0, 1, 2, j, j + 1];
        let mean_a = DVector::from_iterator(5, active.iter().map(|&i| self.state.mean[i]));
        let p_aa = DMatrix::from_fn(5, 5, |r, c| self.state.covariance[(active[r], active[c])]);
        let p_oa = DMatrix::from_fn(n, 5, |r, c| self.state.covariance[(r, active[c])]);
        // The mean itself must be measurable.
        range_bearing::predict(&pose_of(&mean_a), &Vector2::new(mean_a[3], mean_a[4]))
            .map_err(|source| FilterError::Measurement { id, source })?;
        let out = unscented_transform(&self.params, &mean_a, &p_aa, &p_oa, &[1], |a| {
            match range_bearing::predict(&pose_of(a), &Vector2::new(a[3], a[4])) {
                Ok(p) => DVector::from_column_slice(p.measurement.to_vector().as_slice()),
                Err(_) => DVector::from_element(2, f64::NAN),
            }
        })?;
        if !out.covariance.iter().all(|v| v.is_finite()) {
            return Err(FilterError::NonFinite {
                what: "the predicted measurement (a sigma point puts the landmark on the robot)",
            });
        }
        let s: Matrix2<f64> = Matrix2::from_iterator(out.covariance.iter().copied())
            + self.config.noise.measurement_covariance();
        let s_chol = s.cholesky().ok_or(FilterError::NotPositiveDefinite {
            what: "innovation covariance P_yy",
        })?;
        let s_inv = s_chol.inverse();
        let predicted = RangeBearing {
            range: out.mean[0],
            bearing: out.mean[1],
        };
        let innovation = z.difference(&predicted);
        let gain = &out.cross_other * s_inv;
        let correction = &gain * innovation;
        if !correction.iter().all(|v| v.is_finite()) {
            return Err(FilterError::NonFinite {
                what: "the correction K (z - y)",
            });
        }
        let mut covariance = &self.state.covariance - &gain * s * gain.transpose();
        symmetrize(&mut covariance);
        if (0..n).any(|i| !(covariance[(i, i)] >= -1e-12)) {
            return Err(FilterError::NotPositiveDefinite {
                what: "updated covariance",
            });
        }
        self.state.covariance = covariance;
        self.state.mean += correction;
        self.state.mean[2] = wrap_angle(self.state.mean[2]);
        Ok(UpdateReport::Corrected {
            id,
            innovation,
            innovation_covariance: s,
            nis: innovation.dot(&(s_inv * innovation)),
            robot_gain_norm: gain.rows(0, 3).norm(),
            gain_norm: gain.norm(),
        })
    }
}

impl LandmarkSlam for UkfSlam {
    fn name(&self) -> &'static str {
        "ukf"
    }

    fn predict(&mut self, control: &Control, dt: f64) -> Result<PredictReport, FilterError> {
        check_control(control, dt)?;
        let robot_det_before = self.robot_covariance().determinant();
        let n = self.state.len();
        // A robot commanded to stop does not move (as in EKF-SLAM and the simulator).
        let control_noise = if *control == Control::default() {
            Matrix2::zeros()
        } else {
            self.config.noise.control_covariance()
        };
        let (mean_a, p_aa) = self.robot_with_noise(&control_noise);
        let mut p_oa = DMatrix::zeros(n - 3, 5);
        p_oa.view_mut((0, 0), (n - 3, 3))
            .copy_from(&self.state.covariance.view((3, 0), (n - 3, 3)));
        let model = self.config.motion_model;
        let out = unscented_transform(&self.params, &mean_a, &p_aa, &p_oa, &[2], |a| {
            let u = Control::new(control.v + a[3], control.w + a[4]);
            let p = model.predict(&pose_of(a), &u, dt);
            DVector::from_column_slice(&[p.x, p.y, p.theta])
        })?;
        self.take_robot_prediction(&out, *control, robot_det_before)
    }

    /// The same prediction with a recorded motion: sigma points over the robot and
    /// the motion's input noise together (3 + 3 dimensions for an odometry
    /// reading, 3 + 2 for the car), each moved by `x ⊕ δ(u + ε)`.
    fn predict_recorded(&mut self, motion: &RecordedMotion) -> Result<PredictReport, FilterError> {
        motion
            .validate()
            .map_err(|e| FilterError::InvalidMotion(e.to_string()))?;
        let robot_det_before = self.robot_covariance().determinant();
        let n = self.state.len();
        let k = motion.input_dim();
        let std = motion.input_std();
        let input_noise = DMatrix::from_fn(k, k, |i, j| if i == j { std[i] * std[i] } else { 0.0 });
        let (mean_a, p_aa) = self.robot_with_noise(&input_noise);
        let mut p_oa = DMatrix::zeros(n - 3, 3 + k);
        p_oa.view_mut((0, 0), (n - 3, 3))
            .copy_from(&self.state.covariance.view((3, 0), (n - 3, 3)));
        let out = unscented_transform(&self.params, &mean_a, &p_aa, &p_oa, &[2], |a| {
            let mut noise = [0.0; 3];
            for i in 0..k {
                noise[i] = a[3 + i];
            }
            match motion.apply(&pose_of(a), &noise) {
                Ok(p) => DVector::from_column_slice(&[p.x, p.y, p.theta]),
                Err(_) => DVector::from_element(3, f64::NAN),
            }
        })?;
        self.take_robot_prediction(
            &out,
            motion.velocity().unwrap_or_default(),
            robot_det_before,
        )
    }

    fn insert_landmark(
        &mut self,
        id: usize,
        position: Vector2<f64>,
        covariance: Matrix2<f64>,
    ) -> Result<(), FilterError> {
        self.state.insert_known(id, position, &covariance)
    }

    fn update(&mut self, id: usize, z: &RangeBearing) -> Result<UpdateReport, FilterError> {
        let slot = self.state.slot(id);
        check_measurement(id, z, slot.is_none())?;
        match slot {
            Some(slot) => self.correct(id, slot, z),
            None => self.initialize(id, z),
        }
    }

    fn gaussian(&self) -> Option<&dyn JointGaussian> {
        Some(self)
    }

    /// The robot part of the sigma points the next prediction uses: the pose
    /// augmented with the two control-noise components, so the spread is that of
    /// 5 dimensions. The four points along the noise directions share the mean's
    /// pose and are not repeated: 7 points.
    fn robot_sigma_points(&self) -> Vec<Pose2> {
        let Ok(w) = self.params.weights(5) else {
            return Vec::new();
        };
        let Ok(l) = psd_cholesky(&self.state.covariance.view((0, 0), (3, 3)).into_owned()) else {
            return Vec::new();
        };
        sigma_points(&self.state.mean.rows(0, 3).into_owned(), &l, w.spread)
            .iter()
            .map(|v| Pose2::new(v[0], v[1], v[2]))
            .collect()
    }
}

impl KeepsSlamState for UkfSlam {
    fn slam_state(&self) -> &SlamState {
        &self.state
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::belief::LandmarkBelief;
    use crate::kalman::{EkfSlam, FilterNoise};
    use crate::motion::MotionModel;

    /// Exact-arc motion; 0.1 m/s, 0.05 rad/s, 0.2 m and 0.02 rad of noise.
    pub(crate) fn config() -> FilterConfig {
        FilterConfig {
            motion_model: MotionModel::ExactArc,
            noise: FilterNoise {
                v_std: 0.1,
                w_std: 0.05,
                range_std: 0.2,
                bearing_std: 0.02,
            },
        }
    }

    #[test]
    fn agrees_with_the_ekf_when_the_models_are_nearly_linear() {
        // Small noise: the unscented and linearized filters must nearly coincide.
        let start = Pose2::new(0.0, 0.0, 0.3);
        let mut ekf = EkfSlam::new(config(), start).unwrap_or_else(|e| panic!("{e}"));
        let mut ukf = UkfSlam::new(config(), UnscentedParams::default(), start)
            .unwrap_or_else(|e| panic!("{e}"));
        let landmarks = [
            Vector2::new(3.0, 1.0),
            Vector2::new(2.0, -2.0),
            Vector2::new(5.0, 3.0),
        ];
        let mut truth = start;
        for _ in 0..20 {
            let u = Control::new(1.0, 0.2);
            truth = MotionModel::ExactArc.predict(&truth, &u, 0.1);
            ekf.predict(&u, 0.1).unwrap_or_else(|e| panic!("{e}"));
            ukf.predict(&u, 0.1).unwrap_or_else(|e| panic!("{e}"));
            for (id, l) in landmarks.iter().enumerate() {
                let z = range_bearing::predict(&truth, l)
                    .map(|p| p.measurement)
                    .unwrap_or_else(|e| panic!("{e}"));
                ekf.update(id, &z).unwrap_or_else(|e| panic!("{e}"));
                ukf.update(id, &z).unwrap_or_else(|e| panic!("{e}"));
            }
        }
        let dm = (ekf.mean() - ukf.mean()).norm();
        let dp = (ekf.covariance() - ukf.covariance()).norm() / ekf.covariance().norm();
        assert!(dm < 1e-3, "means differ by {dm}");
        assert!(dp < 0.05, "covariances differ by {dp} (relative)");
    }

    #[test]
    fn landmark_initialization_is_the_unscented_image_of_robot_and_noise() {
        // With a certain robot, the landmark covariance is the UT of the noise alone:
        // close to G_z V G_zᵀ for small bearing noise.
        let mut ukf = UkfSlam::new(config(), UnscentedParams::default(), Pose2::IDENTITY)
            .unwrap_or_else(|e| panic!("{e}"));
        let z = RangeBearing::new(4.0, 0.5);
        ukf.update(0, &z).unwrap_or_else(|e| panic!("{e}"));
        let g = range_bearing::inverse(&Pose2::IDENTITY, &z).unwrap_or_else(|e| panic!("{e}"));
        let lin = g.jacobian_measurement
            * config().noise.measurement_covariance()
            * g.jacobian_measurement.transpose();
        let lm = ukf.landmarks()[0];
        assert!((lm.covariance - lin).norm() / lin.norm() < 0.01);
        assert!(ukf.covariance().view((0, 3), (3, 2)).norm() < 1e-15);
    }

    #[test]
    fn extreme_parameters_and_bad_measurements_are_errors() {
        let bad = UnscentedParams {
            alpha: 0.1,
            beta: 2.0,
            kappa: -5.0,
        };
        assert!(UkfSlam::new(config(), bad, Pose2::IDENTITY).is_err());
        let mut ukf = UkfSlam::new(config(), UnscentedParams::default(), Pose2::IDENTITY)
            .unwrap_or_else(|e| panic!("{e}"));
        // A first sighting at range 0, or below it, places nothing: refused, nothing added.
        for range in [0.0, -0.3] {
            let error = ukf
                .update(0, &RangeBearing::new(range, 0.0))
                .expect_err("no landmark from a reading without distance");
            assert!(
                error.to_string().starts_with(&format!(
                    "landmark 0: its first reading has range {range:.2} m, which cannot place it"
                )),
                "{error}"
            );
        }
        assert!(ukf.landmark_ids().is_empty());
        assert_eq!(ukf.mean().len(), 3);
        ukf.update(1, &RangeBearing::new(2.0, 0.0))
            .unwrap_or_else(|e| panic!("{e}"));
        // A measurement of landmark 1 taken from on top of it: the mean is not measurable.
        ukf.state.mean[0] = 2.0;
        let mut moved = ukf.clone();
        assert!(moved.update(1, &RangeBearing::new(0.5, 0.0)).is_err());
        // The refused update leaves the state exactly as it was.
        assert_eq!(moved.mean(), ukf.mean());
        assert_eq!(moved.covariance(), ukf.covariance());
        assert_eq!(moved.landmark_ids(), &[1]);
    }

    #[test]
    fn sigma_points_of_the_robot_have_its_covariance() {
        let mut ukf = UkfSlam::new(config(), UnscentedParams::default(), Pose2::IDENTITY)
            .unwrap_or_else(|e| panic!("{e}"));
        for _ in 0..5 {
            ukf.predict(&Control::new(1.0, 0.4), 0.1)
                .unwrap_or_else(|e| panic!("{e}"));
        }
        let pts = ukf.robot_sigma_points();
        assert_eq!(pts.len(), 7);
        // Weighted as in the prediction (pose and control noise, 5 dimensions).
        let w = UnscentedParams::default()
            .weights(5)
            .unwrap_or_else(|e| panic!("{e}"));
        let c = ukf.robot_pose().to_vector();
        let mut cov = nalgebra::Matrix3::zeros();
        for (i, p) in pts.iter().enumerate() {
            let mut d = p.to_vector() - c;
            d[2] = wrap_angle(d[2]);
            cov += d * d.transpose() * if i == 0 { 0.0 } else { w.other };
        }
        assert!((cov - ukf.robot_covariance()).norm() < 1e-12);
    }
}
