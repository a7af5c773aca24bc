//! The landmark-SLAM state both Kalman filters keep (thesis `000` Eq. 3.1-3.2, 3.9-3.10).

use super::{FilterConfig, FilterError};
use crate::belief::{self, JointGaussian, LandmarkBelief, LandmarkEstimate, PoseBelief};
use crate::geometry::Pose2;
use crate::motion::Control;
use crate::range_bearing::{MIN_RANGE, MeasurementError, RangeBearing};
use nalgebra::{DMatrix, DVector, Matrix2, Matrix3, MatrixXx2, MatrixXx3, Vector2};
use std::collections::HashMap;

/// `M = [x, y, θ, L¹x, L¹y, …]`, its covariance `P`, and which landmark id sits in
/// which slot (landmarks in order of discovery).
#[derive(Clone, Debug)]
pub(crate) struct SlamState {
    pub(crate) mean: DVector<f64>,
    pub(crate) covariance: DMatrix<f64>,
    landmark_ids: Vec<usize>,
    slot_of: HashMap<usize, usize>,
}

/// A Kalman filter whose belief is the [`SlamState`] it keeps (EKF-SLAM and
/// UKF-SLAM): its joint Gaussian is the state's `(M, P)`, the robot's belief the
/// first 3x3 block, each landmark's the 2x2 block of its slot.
pub(crate) trait KeepsSlamState {
    /// The state the filter keeps.
    fn slam_state(&self) -> &SlamState;
}

impl<T: KeepsSlamState> JointGaussian for T {
    fn mean(&self) -> &DVector<f64> {
        &self.slam_state().mean
    }

    fn covariance(&self) -> &DMatrix<f64> {
        &self.slam_state().covariance
    }
}

impl<T: KeepsSlamState> PoseBelief for T {
    fn robot_pose(&self) -> Pose2 {
        belief::joint_robot_pose(self)
    }

    fn robot_covariance(&self) -> Matrix3<f64> {
        belief::joint_robot_covariance(self)
    }
}

impl<T: KeepsSlamState> LandmarkBelief for T {
    fn landmark_ids(&self) -> &[usize] {
        self.slam_state().landmark_ids()
    }

    fn landmarks(&self) -> Vec<LandmarkEstimate> {
        belief::joint_landmarks(self, self.slam_state().landmark_ids())
    }
}

impl SlamState {
    /// The robot at `start` with zero covariance and no landmarks (thesis Eq. 3.5),
    /// after checking the configuration.
    pub(crate) fn new(config: &FilterConfig, start: Pose2) -> Result<Self, FilterError> {
        config.noise.validate()?;
        if !start.is_finite() {
            return Err(FilterError::InvalidParameter {
                name: "start pose",
                value: f64::NAN,
            });
        }
        Ok(Self {
            mean: DVector::from_column_slice(&[start.x, start.y, start.theta]),
            covariance: DMatrix::zeros(3, 3),
            landmark_ids: Vec::new(),
            slot_of: HashMap::new(),
        })
    }

    /// State dimension `3 + 2 · landmarks`.
    pub(crate) fn len(&self) -> usize {
        self.mean.len()
    }

    /// Landmark ids in state order.
    pub(crate) fn landmark_ids(&self) -> &[usize] {
        &self.landmark_ids
    }

    /// The slot of landmark `id`, if it is in the state.
    pub(crate) fn slot(&self, id: usize) -> Option<usize> {
        self.slot_of.get(&id).copied()
    }

    /// Appends a landmark (thesis Eq. 3.9-3.10): its position, its covariance with
    /// the existing state (`n x 2`) and its own 2x2 covariance (symmetrized).
    pub(crate) fn push_landmark(
        &mut self,
        id: usize,
        position: Vector2<f64>,
        cross: &MatrixXx2<f64>,
        covariance: &Matrix2<f64>,
    ) {
        let n = self.len();
        let mut p =
            std::mem::replace(&mut self.covariance, DMatrix::zeros(0, 0)).resize(n + 2, n + 2, 0.0);
        p.view_mut((0, n), (n, 2)).copy_from(cross);
        p.view_mut((n, 0), (2, n)).copy_from(&cross.transpose());
        p.fixed_view_mut::<2, 2>(n, n)
            .copy_from(&(0.5 * (covariance + covariance.transpose())));
        self.covariance = p;
        let mut m =
            std::mem::replace(&mut self.mean, DVector::zeros(0)).resize_vertically(n + 2, 0.0);
        m[n] = position[0];
        m[n + 1] = position[1];
        self.mean = m;
        self.slot_of.insert(id, self.landmark_ids.len());
        self.landmark_ids.push(id);
    }
}

impl SlamState {
    /// Adds a landmark given with the map: uncorrelated with everything in the
    /// state (checked first by [`super::check_known_landmark`]).
    pub(crate) fn insert_known(
        &mut self,
        id: usize,
        position: Vector2<f64>,
        covariance: &Matrix2<f64>,
    ) -> Result<(), FilterError> {
        if self.slot(id).is_some() {
            return Err(FilterError::InvalidLandmark {
                id,
                why: "it is already in the state",
            });
        }
        super::check_known_landmark(id, &position, covariance)?;
        let cross = MatrixXx2::zeros(self.len());
        self.push_landmark(id, position, &cross, covariance);
        Ok(())
    }

    /// Sets the landmark-robot cross-covariance `P_LR` (`(n − 3) x 3`) and its
    /// transpose `P_RL`, as a prediction leaves them.
    pub(crate) fn set_landmark_robot_covariance(&mut self, p_lr: &MatrixXx3<f64>) {
        let m = self.len() - 3;
        if m > 0 {
            self.covariance.view_mut((3, 0), (m, 3)).copy_from(p_lr);
            self.covariance
                .view_mut((0, 3), (3, m))
                .copy_from(&p_lr.transpose());
        }
    }
}

/// Checks a control and time step before a prediction.
pub(crate) fn check_control(control: &Control, dt: f64) -> Result<(), FilterError> {
    if !control.is_finite() || !dt.is_finite() || dt < 0.0 {
        return Err(FilterError::InvalidControl {
            v: control.v,
            w: control.w,
            dt,
        });
    }
    Ok(())
}

/// Checks a measurement before it is used: finite, and for a first sighting far
/// enough from the robot to have a bearing.
pub(crate) fn check_measurement(
    id: usize,
    z: &RangeBearing,
    first_sighting: bool,
) -> Result<(), FilterError> {
    if !z.is_finite() {
        return Err(FilterError::Measurement {
            id,
            source: MeasurementError::NotFinite,
        });
    }
    if first_sighting && z.range < MIN_RANGE {
        return Err(FilterError::Measurement {
            id,
            source: MeasurementError::NoDistance { range: z.range },
        });
    }
    Ok(())
}
