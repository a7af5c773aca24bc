//! Data association: which landmark a range-bearing measurement belongs to.
//!
//! - **Known ids**: the sensor reports each landmark's identity (the simulator's
//!   default, and what EKF-SLAM in thesis `000` Sec. 3.2 assumes).
//! - **Maximum likelihood** (FastSLAM, Montemerlo et al. 2003; Probabilistic
//!   Robotics Sec. 13.6): each particle independently picks the landmark of its own
//!   map under which the measurement is most likely, and starts a new landmark when
//!   even the best one is farther than a Mahalanobis gate. Different particles may
//!   decide differently, which is how FastSLAM keeps several association
//!   hypotheses alive (slides `001`, "Feature Correspondence").
//! - **Nearest neighbour with a Mahalanobis gate** for a joint Gaussian filter
//!   (EKF-SLAM): [`nearest_neighbour`] over a [`GaussianMapView`], which any
//!   filter can provide without changing its own code.
//!
//! Measurements are `[range, bearing]`; bearing innovations are always wrapped.

use crate::geometry::Pose2;
use crate::math;
use crate::range_bearing::{self, RangeBearing};
use nalgebra::{DMatrix, DVector, Matrix2, Matrix3, Matrix3x2, Vector2};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The gate used when none is given: the 99.9 % quantile of χ² with 2 degrees of
/// freedom, `−2 ln(0.001) = 13.8155`.
pub const DEFAULT_GATE: f64 = 13.815_510_557_964_274;

/// How measurements are matched to landmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum AssociationMode {
    /// Trust the sensor's landmark id.
    #[default]
    KnownIds,
    /// Ignore the id; pick the most likely landmark, or start a new one when the
    /// best candidate's squared Mahalanobis distance exceeds `gate` (χ², 2 degrees
    /// of freedom). FastSLAM compares likelihoods instead: the best landmark's
    /// `N(ν; 0, S)` against the new-landmark likelihood `p₀` that the gate sets
    /// ([`new_landmark_log_likelihood`]; Montemerlo et al. 2003).
    MaximumLikelihood {
        /// The new-landmark threshold on the squared Mahalanobis distance.
        gate: f64,
    },
}

impl AssociationMode {
    /// Maximum-likelihood association with the default gate ([`DEFAULT_GATE`]).
    pub fn maximum_likelihood() -> Self {
        AssociationMode::MaximumLikelihood { gate: DEFAULT_GATE }
    }

    /// The name used in URLs, CLI flags and JSON.
    pub fn name(&self) -> &'static str {
        match self {
            AssociationMode::KnownIds => "known",
            AssociationMode::MaximumLikelihood { .. } => "ml",
        }
    }
}

/// The squared Mahalanobis distance `νᵀ S⁻¹ ν` of a 2-vector, or `None` when `S`
/// is not positive definite or a number is not finite.
pub fn mahalanobis_squared(innovation: &Vector2<f64>, covariance: &Matrix2<f64>) -> Option<f64> {
    let det = covariance.determinant();
    if !(det > 0.0) || !det.is_finite() || !(covariance[(0, 0)] > 0.0) {
        return None;
    }
    let inv = Matrix2::new(
        covariance[(1, 1)],
        -covariance[(0, 1)],
        -covariance[(1, 0)],
        covariance[(0, 0)],
    ) / det;
    let d2 = (innovation.transpose() * inv * innovation)[(0, 0)];
    (d2.is_finite() && d2 >= 0.0).then_some(d2)
}

/// `ln N(ν; 0, S) = −½ νᵀS⁻¹ν − ln 2π − ½ ln det S` for a 2-vector (slides `001`,
/// FastSLAM "Importance sampling"), or `None` when `S` is not positive definite.
pub fn log_gaussian(innovation: &Vector2<f64>, covariance: &Matrix2<f64>) -> Option<f64> {
    let d2 = mahalanobis_squared(innovation, covariance)?;
    Some(-0.5 * d2 - math::ln(2.0 * PI) - 0.5 * math::ln(covariance.determinant()))
}

/// The log likelihood a new landmark gets: that of a measurement exactly at the
/// gate under the measurement noise alone, `ln p₀ = −½ gate − ln 2π − ½ ln det Q`
/// (Montemerlo et al. 2003 weight new features with a constant `p₀`; SLAM Lab ties
/// it to the gate so that one number sets both).
pub fn new_landmark_log_likelihood(gate: f64, measurement_noise: &Matrix2<f64>) -> f64 {
    let det = measurement_noise.determinant().max(f64::MIN_POSITIVE);
    -0.5 * gate - math::ln(2.0 * PI) - 0.5 * math::ln(det)
}

/// What a data association decided for one measurement.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum AssociationDecision {
    /// Matched to a landmark already in the map.
    Matched {
        /// The landmark's id.
        id: usize,
        /// The squared Mahalanobis distance of the innovation (0 when the id was
        /// given by the sensor and not tested).
        mahalanobis_squared: f64,
    },
    /// A new landmark was started.
    New {
        /// The id the new landmark got.
        id: usize,
        /// The best existing candidate and its squared Mahalanobis distance, when
        /// there was one (it was outside the gate).
        nearest: Option<(usize, f64)>,
    },
}

impl AssociationDecision {
    /// The landmark id the measurement went to.
    pub fn id(&self) -> usize {
        match self {
            AssociationDecision::Matched { id, .. } | AssociationDecision::New { id, .. } => *id,
        }
    }

    /// True when a new landmark was started.
    pub fn is_new(&self) -> bool {
        matches!(self, AssociationDecision::New { .. })
    }
}

/// One landmark of a joint Gaussian (EKF-SLAM) state, as association needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussianLandmark {
    /// The landmark's id.
    pub id: usize,
    /// Its mean.
    pub mean: Vector2<f64>,
    /// Its 2x2 covariance `P_mm`.
    pub covariance: Matrix2<f64>,
    /// The robot-landmark cross covariance `P_xm`, 3x2.
    pub cross_covariance: Matrix3x2<f64>,
}

/// A read-only view of a joint Gaussian over the robot pose and the landmarks.
/// Implement it for a filter, or build a [`GaussianMap`] from its mean and
/// covariance.
pub trait GaussianMapView {
    /// The robot's mean pose.
    fn robot_mean(&self) -> Pose2;
    /// The robot's 3x3 covariance.
    fn robot_covariance(&self) -> Matrix3<f64>;
    /// The number of landmarks.
    fn landmark_count(&self) -> usize;
    /// Landmark `slot` (`0..landmark_count()`).
    fn landmark(&self, slot: usize) -> Option<GaussianLandmark>;
}

/// A [`GaussianMapView`] read out of a full state `[x, y, θ, L¹x, L¹y, …]` and its
/// covariance (thesis `000` Eq. 3.1), as EKF-SLAM and UKF-SLAM keep them.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussianMap {
    /// Robot mean.
    pub robot: Pose2,
    /// Robot covariance.
    pub robot_covariance: Matrix3<f64>,
    /// The landmarks in state order.
    pub landmarks: Vec<GaussianLandmark>,
}

impl GaussianMap {
    /// Reads the view from a state vector, its covariance and the landmark ids in
    /// state order. `None` when the sizes do not agree (`3 + 2 ids.len()`).
    pub fn from_joint(
        mean: &DVector<f64>,
        covariance: &DMatrix<f64>,
        ids: &[usize],
    ) -> Option<Self> {
        let n = 3 + 2 * ids.len();
        if mean.len() != n || covariance.nrows() != n || covariance.ncols() != n {
            return None;
        }
        let landmarks = ids
            .iter()
            .enumerate()
            .map(|(slot, &id)| {
                let j = 3 + 2 * slot;
                GaussianLandmark {
                    id,
                    mean: Vector2::new(mean[j], mean[j + 1]),
                    covariance: covariance.fixed_view::<2, 2>(j, j).into_owned(),
                    cross_covariance: covariance.fixed_view::<3, 2>(0, j).into_owned(),
                }
            })
            .collect();
        Some(Self {
            robot: Pose2::new(mean[0], mean[1], mean[2]),
            robot_covariance: covariance.fixed_view::<3, 3>(0, 0).into_owned(),
            landmarks,
        })
    }
}

impl GaussianMapView for GaussianMap {
    fn robot_mean(&self) -> Pose2 {
        self.robot
    }
    fn robot_covariance(&self) -> Matrix3<f64> {
        self.robot_covariance
    }
    fn landmark_count(&self) -> usize {
        self.landmarks.len()
    }
    fn landmark(&self, slot: usize) -> Option<GaussianLandmark> {
        self.landmarks.get(slot).copied()
    }
}

/// The result of nearest-neighbour association in a joint Gaussian map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NearestNeighbour {
    /// The nearest landmark (smallest Mahalanobis distance) is inside the gate.
    Matched {
        /// Its id.
        id: usize,
        /// Its slot in the view.
        slot: usize,
        /// The squared Mahalanobis distance.
        mahalanobis_squared: f64,
    },
    /// No landmark is inside the gate: the measurement is of a new landmark.
    New {
        /// The nearest landmark and its squared Mahalanobis distance, if any could
        /// be evaluated.
        nearest: Option<(usize, f64)>,
    },
}

/// The squared Mahalanobis distance `νᵀ S⁻¹ ν` of measurement `z` from landmark
/// `l` of a joint Gaussian, with `ν = z ⊖ h(x̄, m̄)` and `S = H P Hᵀ + Q` over the
/// robot (mean `robot`, covariance `pxx`) and the landmark, as in
/// [`nearest_neighbour`]. `None` when the model cannot be evaluated (the
/// landmark on the robot) or `S` is not positive definite. With a known id this
/// is the innovation gate that refuses an outlier (a misread id).
pub fn landmark_distance(
    robot: &Pose2,
    pxx: &Matrix3<f64>,
    l: &GaussianLandmark,
    z: &RangeBearing,
    measurement_noise: &Matrix2<f64>,
) -> Option<f64> {
    let p = range_bearing::predict(robot, &l.mean).ok()?;
    let hx = p.jacobian_pose;
    let hm = p.jacobian_landmark;
    let cross = hx * l.cross_covariance * hm.transpose();
    let s = hx * pxx * hx.transpose()
        + cross
        + cross.transpose()
        + hm * l.covariance * hm.transpose()
        + measurement_noise;
    let nu = z.difference(&p.measurement);
    mahalanobis_squared(&nu, &s)
}

/// Nearest-neighbour data association with a Mahalanobis gate for EKF-SLAM
/// (Probabilistic Robotics Sec. 10.3; Bar-Shalom's gating): for every landmark,
/// the innovation `ν = z ⊖ h(x̄, m̄)` and its covariance
/// `S = H P Hᵀ + Q` with `H = [H_x, H_m]` over the robot and that landmark
/// (thesis `000` Eq. 3.38/3.39, corrected), so `H P Hᵀ = H_x P_xx H_xᵀ +
/// H_x P_xm H_mᵀ + H_m P_mx H_xᵀ + H_m P_mm H_mᵀ`; the smallest `νᵀ S⁻¹ ν` wins if
/// it is at most `gate`. Landmarks whose model cannot be evaluated (on the robot,
/// or with a covariance that is not positive definite) are skipped.
pub fn nearest_neighbour(
    view: &dyn GaussianMapView,
    z: &RangeBearing,
    measurement_noise: &Matrix2<f64>,
    gate: f64,
) -> NearestNeighbour {
    let robot = view.robot_mean();
    let pxx = view.robot_covariance();
    let mut best: Option<(usize, usize, f64)> = None;
    for slot in 0..view.landmark_count() {
        let Some(l) = view.landmark(slot) else {
            continue;
        };
        if let Some(d2) = landmark_distance(&robot, &pxx, &l, z, measurement_noise)
            && best.is_none_or(|(_, _, b)| d2 < b)
        {
            best = Some((slot, l.id, d2));
        }
    }
    match best {
        Some((slot, id, d2)) if d2 <= gate => NearestNeighbour::Matched {
            id,
            slot,
            mahalanobis_squared: d2,
        },
        _ => NearestNeighbour::New {
            nearest: best.map(|(_, id, d2)| (id, d2)),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_helpers_match_closed_forms() {
        let s = Matrix2::new(4.0, 0.0, 0.0, 0.25);
        let nu = Vector2::new(2.0, 0.5);
        // 4/4 + 0.25/0.25 = 2.
        assert!((mahalanobis_squared(&nu, &s).unwrap() - 2.0).abs() < 1e-12);
        let expected = -1.0 - math::ln(2.0 * PI) - 0.5 * math::ln(1.0);
        assert!((log_gaussian(&nu, &s).unwrap() - expected).abs() < 1e-12);
        assert_eq!(mahalanobis_squared(&nu, &Matrix2::zeros()), None);
        assert_eq!(
            mahalanobis_squared(&nu, &Matrix2::new(f64::NAN, 0.0, 0.0, 1.0)),
            None
        );
        // The new-landmark likelihood is that of a point on the gate.
        let q = Matrix2::new(0.01, 0.0, 0.0, 0.003);
        let on_gate = Vector2::new(
            0.1 * (DEFAULT_GATE / 2.0).sqrt(),
            0.003f64.sqrt() * (DEFAULT_GATE / 2.0).sqrt(),
        );
        assert!(
            (log_gaussian(&on_gate, &q).unwrap() - new_landmark_log_likelihood(DEFAULT_GATE, &q))
                .abs()
                < 1e-9
        );
        // χ²(2) 99.9 % quantile.
        assert!((DEFAULT_GATE - -2.0 * math::ln(0.001)).abs() < 1e-12);
    }

    fn two_landmark_map() -> GaussianMap {
        // Robot at the origin facing +x; landmarks 1 m apart ahead of it.
        let ids = [7, 9];
        let mean = DVector::from_vec(vec![0.0, 0.0, 0.0, 3.0, 0.5, 3.0, -0.5]);
        let mut p = DMatrix::identity(7, 7) * 0.01;
        p[(0, 3)] = 0.004;
        p[(3, 0)] = 0.004;
        GaussianMap::from_joint(&mean, &p, &ids).unwrap()
    }

    #[test]
    fn nearest_neighbour_picks_the_closer_landmark_and_gates_outliers() {
        let map = two_landmark_map();
        let q = Matrix2::new(0.01, 0.0, 0.0, 0.001);
        let near_second = range_bearing::predict(&Pose2::IDENTITY, &Vector2::new(3.05, -0.45))
            .unwrap()
            .measurement;
        match nearest_neighbour(&map, &near_second, &q, DEFAULT_GATE) {
            NearestNeighbour::Matched {
                id,
                slot,
                mahalanobis_squared,
            } => {
                assert_eq!((id, slot), (9, 1));
                assert!(mahalanobis_squared < 1.0, "{mahalanobis_squared}");
            }
            other => panic!("{other:?}"),
        }
        let far = RangeBearing::new(3.0, 1.2);
        match nearest_neighbour(&map, &far, &q, DEFAULT_GATE) {
            NearestNeighbour::New {
                nearest: Some((id, d2)),
            } => {
                assert_eq!(id, 7);
                assert!(d2 > DEFAULT_GATE);
            }
            other => panic!("{other:?}"),
        }
        let empty =
            GaussianMap::from_joint(&DVector::zeros(3), &DMatrix::identity(3, 3), &[]).unwrap();
        assert_eq!(
            nearest_neighbour(&empty, &far, &q, DEFAULT_GATE),
            NearestNeighbour::New { nearest: None }
        );
        assert!(
            GaussianMap::from_joint(&DVector::zeros(4), &DMatrix::identity(4, 4), &[1]).is_none()
        );
    }

    #[test]
    fn innovation_covariance_matches_the_full_jacobian_form() {
        // S from the view equals H P Hᵀ + Q with the full 2x7 H for slot 0.
        let map = two_landmark_map();
        let q = Matrix2::new(0.01, 0.0, 0.0, 0.001);
        let mut p = DMatrix::identity(7, 7) * 0.01;
        p[(0, 3)] = 0.004;
        p[(3, 0)] = 0.004;
        let pred = range_bearing::predict(&Pose2::IDENTITY, &Vector2::new(3.0, 0.5)).unwrap();
        let mut h = DMatrix::zeros(2, 7);
        h.fixed_view_mut::<2, 3>(0, 0)
            .copy_from(&pred.jacobian_pose);
        h.fixed_view_mut::<2, 2>(0, 3)
            .copy_from(&pred.jacobian_landmark);
        let s_full = &h * &p * h.transpose();
        let s = Matrix2::new(
            s_full[(0, 0)],
            s_full[(0, 1)],
            s_full[(1, 0)],
            s_full[(1, 1)],
        ) + q;
        let z = RangeBearing::new(
            pred.measurement.range + 0.05,
            pred.measurement.bearing - 0.02,
        );
        let expected = mahalanobis_squared(&z.difference(&pred.measurement), &s).unwrap();
        match nearest_neighbour(&map, &z, &q, DEFAULT_GATE) {
            NearestNeighbour::Matched {
                slot: 0,
                mahalanobis_squared,
                ..
            } => {
                assert!((mahalanobis_squared - expected).abs() < 1e-9);
            }
            other => panic!("{other:?}"),
        }
    }
}
