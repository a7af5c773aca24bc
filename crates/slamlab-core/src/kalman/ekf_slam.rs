//! EKF-SLAM (thesis `000` Sec. 3.2 and 3.4.1; slides `001` "EKF-SLAM").

use super::state::{SlamState, check_control, check_measurement};
use super::{FilterConfig, FilterError, LandmarkSlam, PredictReport, UpdateReport, symmetrize};
use crate::geometry::Pose2;
use crate::motion::Control;
use crate::range_bearing::{self, RangeBearing};
use nalgebra::{DMatrix, DVector, Matrix2, Matrix2x3, Matrix3};

/// EKF-SLAM with known data association.
///
/// * Initialization (thesis Eq. 3.5): the robot starts at a known pose with zero
///   covariance; the map is empty.
/// * Prediction (Eq. 3.17-3.19, 3.34-3.35): only the robot block `P_RR` and the
///   robot-landmark cross terms `P_RL` change, `P_RR ← F P_RR Fᵀ + G Q_u Gᵀ` and
///   `P_RL ← F P_RL`, with `F = ∂f/∂x` and `G = ∂f/∂u`.
/// * New landmark (Eq. 3.8-3.16): placed with the inverse observation model
///   `L = g(R, z)`, covariance `P_LL = G_R P_RR G_Rᵀ + G_z V G_zᵀ` and cross terms
///   `P_LM = G_R P_RM`.
/// * Update (Eq. 3.18-3.20, 3.37-3.39): one landmark at a time with the sparse
///   Jacobian `H`, the covariance updated in Joseph form and symmetrized.
#[derive(Clone, Debug)]
pub struct EkfSlam {
    config: FilterConfig,
    state: SlamState,
}

impl EkfSlam {
    /// A filter whose robot starts at `start` with zero covariance (thesis Eq. 3.5).
    pub fn new(config: FilterConfig, start: Pose2) -> Result<Self, FilterError> {
        let state = SlamState::new(&config, start)?;
        Ok(Self { config, state })
    }

    /// The configuration it runs with.
    pub fn config(&self) -> &FilterConfig {
        &self.config
    }

    /// The Kalman update for landmark `slot` with measurement `z`.
    fn correct(
        &mut self,
        id: usize,
        slot: usize,
        z: &RangeBearing,
    ) -> Result<UpdateReport, FilterError> {
        let n = self.state.mean.len();
        let j = 3 + 2 * slot;
        let pose = self.robot_pose();
        let landmark = self.state.mean.fixed_rows::<2>(j).into_owned();
        let pred = range_bearing::predict(&pose, &landmark)
            .map_err(|source| FilterError::Measurement { id, source })?;
        let innovation = z.difference(&pred.measurement);

        // H has non-zero columns only at the robot (0..3) and the landmark (j..j+2):
        // M = P Hᵀ (n x 2) costs O(n), S = H P Hᵀ + V costs O(1).
        let h_r: Matrix2x3<f64> = pred.jacobian_pose;
        let h_l: Matrix2<f64> = pred.jacobian_landmark;
        let p_cols_r = self.state.covariance.columns(0, 3);
        let p_cols_l = self.state.covariance.columns(j, 2);
        let m = p_cols_r * h_r.transpose() + p_cols_l * h_l.transpose();
        let m_r = m.fixed_view::<3, 2>(0, 0).into_owned();
        let m_l = m.fixed_view::<2, 2>(j, 0).into_owned();
        let s = h_r * m_r + h_l * m_l + self.config.noise.measurement_covariance();
        let s = 0.5 * (s + s.transpose());
        let s_chol = s.cholesky().ok_or(FilterError::NotPositiveDefinite {
            what: "innovation covariance S",
        })?;
        let s_inv = s_chol.inverse();
        let gain = &m * s_inv;
        let nis = innovation.dot(&(s_inv * innovation));

        let correction = &gain * innovation;
        if !correction.iter().all(|v| v.is_finite()) {
            return Err(FilterError::NotPositiveDefinite {
                what: "innovation covariance S",
            });
        }
        self.state.mean += correction;
        self.state.mean[2] = crate::geometry::wrap_angle(self.state.mean[2]);

        // Joseph form (I - KH) P (I - KH)ᵀ + K V Kᵀ, expanded with M = P Hᵀ so that
        // it costs O(n²) and needs no n x n temporary: P - K Mᵀ - M Kᵀ + (K S) Kᵀ,
        // as six in-place rank-1 updates.
        let k_s = &gain * s;
        for c in 0..2 {
            let (k, mc, ksc) = (gain.column(c), m.column(c), k_s.column(c));
            self.state.covariance.ger(-1.0, &k, &mc, 1.0);
            self.state.covariance.ger(-1.0, &mc, &k, 1.0);
            self.state.covariance.ger(1.0, &ksc, &k, 1.0);
        }
        symmetrize(&mut self.state.covariance);
        debug_assert_eq!(self.state.covariance.nrows(), n);

        let robot_gain_norm = gain.rows(0, 3).norm();
        Ok(UpdateReport::Corrected {
            id,
            innovation,
            innovation_covariance: s,
            nis,
            robot_gain_norm,
            gain_norm: gain.norm(),
        })
    }

    /// Adds landmark `id` from its first measurement (thesis Eq. 3.8-3.16).
    fn initialize(&mut self, id: usize, z: &RangeBearing) -> Result<UpdateReport, FilterError> {
        let pose = self.robot_pose();
        let g = range_bearing::inverse(&pose, z)
            .map_err(|source| FilterError::Measurement { id, source })?;
        let p_rr: Matrix3<f64> = self.state.covariance.fixed_view::<3, 3>(0, 0).into_owned();
        let p_ll = g.jacobian_pose * p_rr * g.jacobian_pose.transpose()
            + g.jacobian_measurement
                * self.config.noise.measurement_covariance()
                * g.jacobian_measurement.transpose();
        // P_LM = G_R P_RM: the new landmark's correlation with everything known so far.
        let p_lm = g.jacobian_pose * self.state.covariance.rows(0, 3);

        self.state
            .push_landmark(id, g.landmark, &p_lm.transpose(), &p_ll);
        Ok(UpdateReport::Initialized {
            id,
            position: g.landmark,
        })
    }
}

impl LandmarkSlam for EkfSlam {
    fn name(&self) -> &'static str {
        "ekf"
    }

    fn predict(&mut self, control: &Control, dt: f64) -> Result<PredictReport, FilterError> {
        check_control(control, dt)?;
        let robot_det_before = self.robot_covariance().determinant();
        let step = self
            .config
            .motion_model
            .step(&self.robot_pose(), control, dt);
        let f = step.jacobian_pose;
        let g = step.jacobian_control;
        self.state.mean[0] = step.pose.x;
        self.state.mean[1] = step.pose.y;
        self.state.mean[2] = step.pose.theta;

        let p_rr: Matrix3<f64> = self.state.covariance.fixed_view::<3, 3>(0, 0).into_owned();
        // A robot commanded to stop does not move: the control noise is on the
        // executed wheel speeds of a moving robot (the simulator does the same).
        let q = if *control == Control::default() {
            Matrix3::zeros()
        } else {
            g * self.config.noise.control_covariance() * g.transpose()
        };
        let new_rr = f * p_rr * f.transpose() + q;
        self.state
            .covariance
            .fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(0.5 * (new_rr + new_rr.transpose())));
        // P_RL ← F P_RL: the landmarks stay put, their correlation with the robot moves with it.
        let p_lr = self
            .state
            .covariance
            .view((3, 0), (self.state.len() - 3, 3))
            * f.transpose();
        self.state.set_landmark_robot_covariance(&p_lr);
        Ok(PredictReport {
            control: *control,
            robot_det_before,
            robot_det_after: self.robot_covariance().determinant(),
        })
    }

    fn update(&mut self, id: usize, z: &RangeBearing) -> Result<UpdateReport, FilterError> {
        let slot = self.state.slot(id);
        check_measurement(id, z, slot.is_none())?;
        match slot {
            Some(slot) => self.correct(id, slot, z),
            None => self.initialize(id, z),
        }
    }

    fn mean(&self) -> &DVector<f64> {
        &self.state.mean
    }

    fn covariance(&self) -> &DMatrix<f64> {
        &self.state.covariance
    }

    fn landmark_ids(&self) -> &[usize] {
        self.state.landmark_ids()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kalman::FilterNoise;
    use crate::motion::MotionModel;
    use nalgebra::Vector2;

    fn config() -> FilterConfig {
        FilterConfig {
            motion_model: MotionModel::ExactArc,
            noise: FilterNoise {
                v_std: 0.1,
                w_std: 0.1,
                range_std: 0.2,
                bearing_std: 0.05,
            },
        }
    }

    #[test]
    fn starts_certain_and_prediction_grows_only_the_robot_block() {
        let mut ekf = EkfSlam::new(config(), Pose2::IDENTITY).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(ekf.robot_covariance(), Matrix3::zeros());
        let z = range_bearing::predict(&Pose2::IDENTITY, &Vector2::new(3.0, 1.0))
            .map(|p| p.measurement);
        let z = z.unwrap_or_else(|e| panic!("{e}"));
        ekf.update(7, &z).unwrap_or_else(|e| panic!("{e}"));
        // With a certain robot the landmark's covariance is G_z V G_zᵀ and uncorrelated.
        assert!(ekf.covariance().view((0, 3), (3, 2)).norm() < 1e-15);
        let before_ll = ekf.covariance().fixed_view::<2, 2>(3, 3).into_owned();
        ekf.predict(&Control::new(1.0, 0.2), 0.1)
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(ekf.robot_covariance().determinant() > 0.0 || ekf.robot_covariance().trace() > 0.0);
        assert_eq!(
            ekf.covariance().fixed_view::<2, 2>(3, 3).into_owned(),
            before_ll
        );
    }

    #[test]
    fn landmark_initialization_matches_the_jacobian_formula() {
        let mut ekf =
            EkfSlam::new(config(), Pose2::new(1.0, 2.0, 0.5)).unwrap_or_else(|e| panic!("{e}"));
        for _ in 0..5 {
            ekf.predict(&Control::new(1.0, 0.3), 0.1)
                .unwrap_or_else(|e| panic!("{e}"));
        }
        let z = RangeBearing::new(4.0, 0.3);
        let pose = ekf.robot_pose();
        let p_rr = ekf.robot_covariance();
        ekf.update(3, &z).unwrap_or_else(|e| panic!("{e}"));
        let g = range_bearing::inverse(&pose, &z).unwrap_or_else(|e| panic!("{e}"));
        let expected_ll = g.jacobian_pose * p_rr * g.jacobian_pose.transpose()
            + g.jacobian_measurement
                * config().noise.measurement_covariance()
                * g.jacobian_measurement.transpose();
        let lm = ekf.landmarks()[0];
        assert_eq!(lm.id, 3);
        assert!((lm.mean - g.landmark).norm() < 1e-12);
        assert!((lm.covariance - expected_ll).norm() < 1e-12);
        let expected_lr = g.jacobian_pose * p_rr;
        assert!((ekf.covariance().view((3, 0), (2, 3)) - expected_lr).norm() < 1e-12);
    }

    #[test]
    fn a_measurement_on_the_robot_is_rejected_without_changing_the_state() {
        let mut ekf = EkfSlam::new(config(), Pose2::IDENTITY).unwrap_or_else(|e| panic!("{e}"));
        ekf.predict(&Control::new(1.0, 0.3), 0.1)
            .unwrap_or_else(|e| panic!("{e}"));
        let before = ekf.clone();
        assert!(ekf.update(1, &RangeBearing::new(0.0, 0.0)).is_err());
        assert!(
            ekf.update(
                1,
                &RangeBearing {
                    range: f64::NAN,
                    bearing: 0.0
                }
            )
            .is_err()
        );
        assert!(ekf.predict(&Control::new(f64::INFINITY, 0.0), 0.1).is_err());
        assert_eq!(before.mean(), ekf.mean());
        assert_eq!(before.covariance(), ekf.covariance());
        assert!(ekf.landmark_ids().is_empty());
    }

    #[test]
    fn invalid_noise_is_rejected() {
        let mut c = config();
        c.noise.range_std = 0.0;
        assert!(EkfSlam::new(c, Pose2::IDENTITY).is_err());
        c.noise.range_std = f64::NAN;
        assert!(EkfSlam::new(c, Pose2::IDENTITY).is_err());
    }
}
