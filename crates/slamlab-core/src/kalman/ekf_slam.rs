//! EKF-SLAM (thesis `000` Sec. 3.2 and 3.4.1; slides `001` "EKF-SLAM").

use super::state::{KeepsSlamState, SlamState, check_control, check_measurement};
use super::{FilterConfig, FilterError, LandmarkSlam, PredictReport, UpdateReport, symmetrize};
use crate::belief::{JointGaussian, PoseBelief};
use crate::geometry::Pose2;
use crate::motion::{Control, RecordedMotion};
use crate::range_bearing::{self, RangeBearing};
use nalgebra::{Matrix2, Matrix2x3, Matrix3, Vector2};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Where the EKF evaluates its Jacobians.
///
/// The textbook EKF linearizes at the latest estimate. Each landmark update then
/// uses a slightly different robot heading, and together they give the filter
/// information about the absolute heading that the range-bearing measurements do
/// not contain (the global position and heading of a SLAM map are unobservable).
/// Over a long run the EKF grows overconfident: its NEES leaves the consistency band
/// (Bailey et al. 2006; Huang, Mourikis and Roumeliotis 2008).
///
/// The first-estimates Jacobian (FEJ) EKF (Huang, Mourikis and Roumeliotis 2008)
/// evaluates every Jacobian at the first estimate of each state: the robot pose as
/// predicted for this tick, before any update, and each landmark where it was first
/// initialized. The residuals still use the latest estimate. With these Jacobians
/// the linearized system keeps the three unobservable directions of the true one.
///
/// A supplied linearization evaluates them where the caller says, before every
/// predict ([`EkfSlam::supply_linearization_point`]): the robot's move of the tick
/// and the landmarks' positions. A simulator that supplies its true state gets the
/// "ideal EKF", the yardstick of Huang et al.: its linearization is exact, so any
/// inconsistency it shows comes from the noise models or the nonlinearity of the
/// innovation, not from where the Jacobians were taken.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Linearization {
    /// Jacobians at the latest estimate (thesis Sec. 3.2, the slides).
    #[default]
    LatestEstimate,
    /// First-estimates Jacobians (FEJ-EKF).
    FirstEstimates,
    /// Jacobians at a point supplied from outside before every predict
    /// ([`EkfSlam::supply_linearization_point`]); until one is, and for a landmark
    /// it does not list, first estimates.
    Supplied,
}

/// A linearization point supplied from outside: the robot's move of the tick
/// and the landmarks' positions.
#[derive(Clone, Debug, Default)]
struct SuppliedPoint {
    robot_before: Pose2,
    robot: Pose2,
    landmarks: HashMap<usize, Vector2<f64>>,
}

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
    linearization: Linearization,
    /// The robot pose as predicted for the current tick, before its updates
    /// (`x̂_{k|k-1}`); the robot start at tick 0. Used by [`Linearization::FirstEstimates`].
    robot_prior: Pose2,
    /// Each landmark's position when it was initialized, in slot order.
    first_estimates: Vec<Vector2<f64>>,
    /// The supplied linearization point, for [`Linearization::Supplied`]; `None`
    /// until one is given.
    supplied: Option<SuppliedPoint>,
}

impl EkfSlam {
    /// A filter whose robot starts at `start` with zero covariance (thesis Eq. 3.5).
    pub fn new(config: FilterConfig, start: Pose2) -> Result<Self, FilterError> {
        Self::with_linearization(config, start, Linearization::LatestEstimate)
    }

    /// A filter that evaluates its Jacobians as `linearization` says.
    pub fn with_linearization(
        config: FilterConfig,
        start: Pose2,
        linearization: Linearization,
    ) -> Result<Self, FilterError> {
        let state = SlamState::new(&config, start)?;
        Ok(Self {
            config,
            state,
            linearization,
            robot_prior: start,
            first_estimates: Vec::new(),
            supplied: None,
        })
    }

    /// For [`Linearization::Supplied`]: the point at which the Jacobians of the
    /// tick that is starting are evaluated. The prediction's at the move from
    /// `robot_before` to `robot`, the updates' at `robot` and the landmarks'
    /// positions, which are read on the first call only (they do not move); a
    /// landmark not among them is linearized at its first estimate. Other
    /// linearizations ignore it.
    pub fn supply_linearization_point(
        &mut self,
        robot_before: Pose2,
        robot: Pose2,
        landmarks: &mut dyn Iterator<Item = (usize, Vector2<f64>)>,
    ) {
        if self.linearization != Linearization::Supplied {
            return;
        }
        let point = self.supplied.get_or_insert_with(SuppliedPoint::default);
        point.robot_before = robot_before;
        point.robot = robot;
        if point.landmarks.is_empty() {
            point.landmarks.extend(landmarks);
        }
    }

    /// Where the Jacobians of landmark `id` are evaluated when they are not at the
    /// latest estimate: the robot pose and the landmark position. `current` is the
    /// landmark's latest estimate (or, for a new landmark, its first).
    fn linearization_point(
        &self,
        id: usize,
        slot: Option<usize>,
        current: Vector2<f64>,
    ) -> (Pose2, Vector2<f64>) {
        let supplied = self
            .supplied
            .as_ref()
            .filter(|_| self.linearization == Linearization::Supplied);
        match supplied {
            Some(point) => (
                point.robot,
                point.landmarks.get(&id).copied().unwrap_or(current),
            ),
            None => (
                self.robot_prior,
                slot.and_then(|s| self.first_estimates.get(s).copied())
                    .unwrap_or(current),
            ),
        }
    }

    /// Where this filter evaluates its Jacobians.
    pub fn linearization(&self) -> Linearization {
        self.linearization
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
        let (h_r, h_l) = match self.linearization {
            Linearization::LatestEstimate => (pred.jacobian_pose, pred.jacobian_landmark),
            Linearization::FirstEstimates | Linearization::Supplied => {
                let (at_pose, at_landmark) = self.linearization_point(id, Some(slot), landmark);
                let first = range_bearing::predict(&at_pose, &at_landmark)
                    .map_err(|source| FilterError::Measurement { id, source })?;
                (first.jacobian_pose, first.jacobian_landmark)
            }
        };

        // H has non-zero columns only at the robot (0..3) and the landmark (j..j+2):
        // M = P Hᵀ (n x 2) costs O(n), S = H P Hᵀ + V costs O(1).
        let (h_r, h_l): (Matrix2x3<f64>, Matrix2<f64>) = (h_r, h_l);
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
            return Err(FilterError::NonFinite {
                what: "the correction K (z - h(x))",
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
        // ∂g/∂R = [I | J (L - p)] with J the 90° rotation; FEJ evaluates it at the
        // robot pose predicted for this tick (the landmark's first estimate is this one).
        let g_r = match self.linearization {
            Linearization::LatestEstimate => g.jacobian_pose,
            Linearization::FirstEstimates | Linearization::Supplied => {
                let (p, l) = self.linearization_point(id, None, g.landmark);
                Matrix2x3::new(1.0, 0.0, -(l[1] - p.y), 0.0, 1.0, l[0] - p.x)
            }
        };
        let p_rr: Matrix3<f64> = self.state.covariance.fixed_view::<3, 3>(0, 0).into_owned();
        let p_ll = g_r * p_rr * g_r.transpose()
            + g.jacobian_measurement
                * self.config.noise.measurement_covariance()
                * g.jacobian_measurement.transpose();
        // P_LM = G_R P_RM: the new landmark's correlation with everything known so far.
        let p_lm = g_r * self.state.covariance.rows(0, 3);

        self.state
            .push_landmark(id, g.landmark, &p_lm.transpose(), &p_ll);
        self.first_estimates.push(g.landmark);
        Ok(UpdateReport::Initialized {
            id,
            position: g.landmark,
        })
    }
    /// Moves the robot's mean to `pose` and its covariance by the motion's
    /// Jacobian `f` and process noise `q` (thesis Eq. 3.17-3.19, 3.34-3.35):
    /// `P_RR ← F P_RR Fᵀ + Q` and `P_RL ← F P_RL`; the landmarks stay put.
    fn propagate(&mut self, pose: Pose2, mut f: Matrix3<f64>, q: &Matrix3<f64>) {
        // ∂f/∂θ = J (p' - p) for every motion model here. FEJ takes the displacement
        // from the previous *predicted* position, so that the products of F over time
        // telescope as they do for the true system; a supplied point gives the move.
        let displacement = match (self.linearization, &self.supplied) {
            (Linearization::LatestEstimate, _) => None,
            (Linearization::Supplied, Some(point)) => Some((point.robot_before, point.robot)),
            _ => Some((self.robot_prior, pose)),
        };
        if let Some((from, to)) = displacement {
            f[(0, 2)] = -(to.y - from.y);
            f[(1, 2)] = to.x - from.x;
        }
        self.state.mean[0] = pose.x;
        self.state.mean[1] = pose.y;
        self.state.mean[2] = pose.theta;

        let p_rr: Matrix3<f64> = self.state.covariance.fixed_view::<3, 3>(0, 0).into_owned();
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
        self.robot_prior = pose;
    }
}

impl LandmarkSlam for EkfSlam {
    fn name(&self) -> &'static str {
        match self.linearization {
            Linearization::LatestEstimate => "ekf",
            Linearization::FirstEstimates => "fej-ekf",
            Linearization::Supplied => "ekf-supplied",
        }
    }

    fn predict(&mut self, control: &Control, dt: f64) -> Result<PredictReport, FilterError> {
        check_control(control, dt)?;
        let robot_det_before = self.robot_covariance().determinant();
        let step = self
            .config
            .motion_model
            .step(&self.robot_pose(), control, dt);
        let g = step.jacobian_control;
        // A robot commanded to stop does not move: the control noise is on the
        // executed wheel speeds of a moving robot (the simulator does the same).
        let q = if *control == Control::default() {
            Matrix3::zeros()
        } else {
            g * self.config.noise.control_covariance() * g.transpose()
        };
        self.propagate(step.pose, step.jacobian_pose, &q);
        Ok(PredictReport {
            control: *control,
            robot_det_before,
            robot_det_after: self.robot_covariance().determinant(),
        })
    }

    /// The same prediction with a recorded motion: `F` and `G = ∂f/∂u` of the
    /// motion, and `G diag(σ²) Gᵀ` for the input's noise.
    fn predict_recorded(&mut self, motion: &RecordedMotion) -> Result<PredictReport, FilterError> {
        let robot_det_before = self.robot_covariance().determinant();
        let step = motion
            .step(&self.robot_pose())
            .map_err(|e| FilterError::InvalidMotion(e.to_string()))?;
        let g = step.jacobian_input;
        let q = g * step.input_covariance * g.transpose();
        self.propagate(step.pose, step.jacobian_pose, &q);
        Ok(PredictReport {
            control: motion.velocity().unwrap_or_default(),
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

    fn insert_landmark(
        &mut self,
        id: usize,
        position: Vector2<f64>,
        covariance: Matrix2<f64>,
    ) -> Result<(), FilterError> {
        self.state.insert_known(id, position, &covariance)?;
        self.first_estimates.push(position);
        Ok(())
    }

    fn gaussian(&self) -> Option<&dyn JointGaussian> {
        Some(self)
    }
}

impl KeepsSlamState for EkfSlam {
    fn slam_state(&self) -> &SlamState {
        &self.state
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::belief::LandmarkBelief;
    use crate::kalman::FilterNoise;
    use crate::math;
    use crate::motion::MotionModel;
    use nalgebra::DVector;

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
        let error = ekf
            .update(1, &RangeBearing::new(-0.25, 0.1))
            .expect_err("a first sighting at a negative range places nothing");
        assert_eq!(
            error.to_string(),
            "landmark 1: its first reading has range -0.25 m, which cannot place it (the \
             inverse observation model needs a range above 0.001 m); it waits for its next \
             sighting"
        );
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
        let backwards = ekf.predict(&Control::new(1.0, 0.0), -0.1);
        assert!(
            backwards.is_err_and(|e| e.to_string().contains("dt = -0.1 finite and not negative")),
            "a negative time step is refused and named"
        );
        assert_eq!(before.mean(), ekf.mean());
        assert_eq!(before.covariance(), ekf.covariance());
        assert!(ekf.landmark_ids().is_empty());
    }

    /// Drives both linearizations with the same commands and measurements.
    fn drive(ekf: &mut EkfSlam, ticks: usize, corrections: bool) {
        let truth_landmarks = [Vector2::new(3.0, 1.0), Vector2::new(1.0, 3.5)];
        let mut truth = Pose2::IDENTITY;
        let control = Control::new(1.0, 0.3);
        for tick in 0..ticks {
            ekf.predict(&control, 0.1).unwrap_or_else(|e| panic!("{e}"));
            truth = MotionModel::ExactArc.step(&truth, &control, 0.1).pose;
            for (id, lm) in truth_landmarks.iter().enumerate() {
                if !corrections && ekf.state.slot(id).is_some() {
                    continue;
                }
                let exact = range_bearing::predict(&truth, lm).unwrap_or_else(|e| panic!("{e}"));
                // A fixed, deterministic "noise" so that corrections move the estimate.
                let wobble = 0.05 * math::sin((tick * 7 + id * 3) as f64);
                let z = RangeBearing::new(
                    exact.measurement.range + wobble,
                    exact.measurement.bearing - 0.5 * wobble,
                );
                ekf.update(id, &z).unwrap_or_else(|e| panic!("{e}"));
            }
        }
    }

    #[test]
    fn first_estimates_equal_the_latest_until_an_update_moves_the_estimate() {
        // With landmarks initialized but never corrected, the first estimates are
        // the latest ones, so both linearizations must agree to rounding.
        let mut ekf = EkfSlam::new(config(), Pose2::IDENTITY).unwrap_or_else(|e| panic!("{e}"));
        let mut fej =
            EkfSlam::with_linearization(config(), Pose2::IDENTITY, Linearization::FirstEstimates)
                .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((ekf.name(), fej.name()), ("ekf", "fej-ekf"));
        drive(&mut ekf, 8, false);
        drive(&mut fej, 8, false);
        assert!((ekf.mean() - fej.mean()).norm() < 1e-12);
        assert!((ekf.covariance() - fej.covariance()).norm() < 1e-12);

        // With corrections the Jacobians differ, and so do the covariances.
        let mut ekf = EkfSlam::new(config(), Pose2::IDENTITY).unwrap_or_else(|e| panic!("{e}"));
        let mut fej =
            EkfSlam::with_linearization(config(), Pose2::IDENTITY, Linearization::FirstEstimates)
                .unwrap_or_else(|e| panic!("{e}"));
        drive(&mut ekf, 30, true);
        drive(&mut fej, 30, true);
        let diff = (ekf.covariance() - fej.covariance()).norm();
        assert!(diff > 1e-6, "covariances differ by {diff}");
        let eig = nalgebra::SymmetricEigen::new(fej.covariance().clone());
        assert!(eig.eigenvalues.min() > -1e-12, "{}", eig.eigenvalues);
    }

    /// Updates every landmark in the state with exactly the measurement the filter
    /// predicts for it (a zero innovation), returning the reports.
    fn update_with_predicted_measurements(ekf: &mut EkfSlam) -> Vec<(usize, UpdateReport)> {
        let pose = ekf.robot_pose();
        let landmarks = ekf.landmarks();
        landmarks
            .iter()
            .map(|l| {
                let z = range_bearing::predict(&pose, &l.mean).unwrap_or_else(|e| panic!("{e}"));
                let report = ekf
                    .update(l.id, &z.measurement)
                    .unwrap_or_else(|e| panic!("{e}"));
                (l.id, report)
            })
            .collect()
    }

    #[test]
    fn first_estimates_jacobians_learn_nothing_about_the_global_heading() {
        // Rotating the whole map (robot and landmarks) about the origin changes no
        // range or bearing: the direction N = [-p_y, p_x, 1, -L1_y, L1_x, ...] is
        // unobservable. Give the filter uncertainty only along N (at its
        // linearization points), then predict and update: a filter whose Jacobians
        // respect the unobservable direction keeps that uncertainty, exactly.
        let mut fej =
            EkfSlam::with_linearization(config(), Pose2::IDENTITY, Linearization::FirstEstimates)
                .unwrap_or_else(|e| panic!("{e}"));
        drive(&mut fej, 10, true);
        let moved = (fej.robot_prior.translation() - fej.robot_pose().translation()).norm();
        let landmark_moved =
            (fej.first_estimates[0] - fej.state.mean.fixed_rows::<2>(3).into_owned()).norm();
        assert!(
            moved > 1e-4 && landmark_moved > 1e-4,
            "{moved} {landmark_moved}"
        );

        let rotation = |p: Vector2<f64>, landmarks: &[Vector2<f64>]| {
            let mut n = DVector::zeros(3 + 2 * landmarks.len());
            n[0] = -p[1];
            n[1] = p[0];
            n[2] = 1.0;
            for (slot, l) in landmarks.iter().enumerate() {
                n[3 + 2 * slot] = -l[1];
                n[4 + 2 * slot] = l[0];
            }
            n
        };
        let first = fej.first_estimates.clone();
        let n_before = rotation(fej.robot_prior.translation(), &first);
        fej.state.covariance = 0.01 * &n_before * n_before.transpose();

        // A stopped robot adds no process noise; the measurements are exactly what
        // the filter predicts, so only the covariance can change.
        fej.predict(&Control::default(), 0.1)
            .unwrap_or_else(|e| panic!("{e}"));
        for (id, report) in update_with_predicted_measurements(&mut fej) {
            let UpdateReport::Corrected { gain_norm, .. } = report else {
                panic!("landmark {id} was known");
            };
            assert!(gain_norm < 1e-10, "landmark {id}: gain {gain_norm}");
        }
        let n_after = rotation(fej.robot_prior.translation(), &first);
        let expected = 0.01 * &n_after * n_after.transpose();
        let diff = (fej.covariance() - &expected).norm();
        assert!(
            diff < 1e-12,
            "covariance moved off the rotation direction by {diff}"
        );

        // The textbook EKF linearizes at the latest estimates, which the updates
        // have moved: with the same covariance it gains heading information it
        // cannot have. Each such update gains little (here 4e-5 of the variance);
        // over hundreds of updates it adds up to the overconfidence of EKF-SLAM.
        let mut ekf = EkfSlam::new(config(), Pose2::IDENTITY).unwrap_or_else(|e| panic!("{e}"));
        drive(&mut ekf, 10, true);
        ekf.state.covariance = 0.01 * &n_before * n_before.transpose();
        ekf.predict(&Control::default(), 0.1)
            .unwrap_or_else(|e| panic!("{e}"));
        let heading_before = ekf.robot_covariance()[(2, 2)];
        update_with_predicted_measurements(&mut ekf);
        let heading_after = ekf.robot_covariance()[(2, 2)];
        assert!(
            heading_before - heading_after > 1e-5 * heading_before,
            "textbook EKF heading variance {heading_before} -> {heading_after}"
        );
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
