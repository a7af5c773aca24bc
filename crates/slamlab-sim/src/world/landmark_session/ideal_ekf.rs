//! The ideal EKF of the landmark lesson: an EKF whose Jacobians are evaluated at
//! the true state, which only a simulator knows (Huang, Mourikis and Roumeliotis
//! 2008). Its linearization is exact, so any inconsistency it shows comes from
//! the noise models or the nonlinearity of the innovation, not from where the
//! Jacobians were taken: the yardstick for the EKF and the FEJ-EKF.
//!
//! The estimator in `slamlab-core` knows nothing of a truth: it is an [`EkfSlam`]
//! with a [`Linearization::Supplied`] point, and this adapter supplies the
//! simulator's true robot move and landmark positions before every tick
//! ([`IdealEkf::observe_truth`]).

use nalgebra::{DMatrix, DVector, Matrix2, Matrix3, Vector2};
use slamlab_core::belief::{JointGaussian, LandmarkBelief, LandmarkEstimate, PoseBelief};
use slamlab_core::kalman::{
    EkfSlam, FilterConfig, FilterError, LandmarkSlam, Linearization, PredictReport, UpdateReport,
};
use slamlab_core::motion::RecordedMotion;
use slamlab_core::range_bearing::RangeBearing;
use slamlab_core::{Control, Pose2};

/// An EKF linearized at the true state, fed by the simulator.
#[derive(Clone, Debug)]
pub struct IdealEkf {
    ekf: EkfSlam,
}

impl IdealEkf {
    /// A filter whose robot starts at `start` with zero covariance.
    pub fn new(config: FilterConfig, start: Pose2) -> Result<Self, FilterError> {
        EkfSlam::with_linearization(config, start, Linearization::Supplied).map(|ekf| Self { ekf })
    }

    /// The true state of the tick that is starting: the robot before and after its
    /// move, and every landmark (read once: they do not move). Until it is given,
    /// the filter linearizes at first estimates.
    pub fn observe_truth(
        &mut self,
        robot_before: Pose2,
        robot: Pose2,
        landmarks: &mut dyn Iterator<Item = (usize, Vector2<f64>)>,
    ) {
        self.ekf
            .supply_linearization_point(robot_before, robot, landmarks);
    }

    /// The EKF inside.
    pub fn inner(&self) -> &EkfSlam {
        &self.ekf
    }
}

impl LandmarkSlam for IdealEkf {
    fn name(&self) -> &'static str {
        "ideal-ekf"
    }

    fn predict(&mut self, control: &Control, dt: f64) -> Result<PredictReport, FilterError> {
        self.ekf.predict(control, dt)
    }

    fn update(&mut self, id: usize, z: &RangeBearing) -> Result<UpdateReport, FilterError> {
        self.ekf.update(id, z)
    }

    /// Recorded data has no truth to linearize at: the EKF then linearizes at
    /// first estimates (see [`IdealEkf::observe_truth`]).
    fn predict_recorded(&mut self, motion: &RecordedMotion) -> Result<PredictReport, FilterError> {
        self.ekf.predict_recorded(motion)
    }

    fn insert_landmark(
        &mut self,
        id: usize,
        position: Vector2<f64>,
        covariance: Matrix2<f64>,
    ) -> Result<(), FilterError> {
        self.ekf.insert_landmark(id, position, covariance)
    }

    fn gaussian(&self) -> Option<&dyn JointGaussian> {
        Some(&self.ekf)
    }
}

impl JointGaussian for IdealEkf {
    fn mean(&self) -> &DVector<f64> {
        self.ekf.mean()
    }

    fn covariance(&self) -> &DMatrix<f64> {
        self.ekf.covariance()
    }
}

impl PoseBelief for IdealEkf {
    fn robot_pose(&self) -> Pose2 {
        self.ekf.robot_pose()
    }

    fn robot_covariance(&self) -> Matrix3<f64> {
        self.ekf.robot_covariance()
    }
}

impl LandmarkBelief for IdealEkf {
    fn landmark_ids(&self) -> &[usize] {
        self.ekf.landmark_ids()
    }

    fn landmarks(&self) -> Vec<LandmarkEstimate> {
        self.ekf.landmarks()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use slamlab_core::kalman::FilterNoise;
    use slamlab_core::range_bearing;
    use slamlab_core::{MotionModel, math};

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

    /// A filter that can be offered the true state.
    trait Offered: LandmarkSlam {
        fn offer(&mut self, before: Pose2, truth: Pose2, landmarks: &[(usize, Vector2<f64>)]);
    }

    impl Offered for EkfSlam {
        fn offer(&mut self, before: Pose2, truth: Pose2, landmarks: &[(usize, Vector2<f64>)]) {
            self.supply_linearization_point(before, truth, &mut landmarks.iter().copied());
        }
    }

    impl Offered for IdealEkf {
        fn offer(&mut self, before: Pose2, truth: Pose2, landmarks: &[(usize, Vector2<f64>)]) {
            self.observe_truth(before, truth, &mut landmarks.iter().copied());
        }
    }

    fn landmarks() -> [(usize, Vector2<f64>); 2] {
        [(4, Vector2::new(3.0, 1.0)), (9, Vector2::new(1.0, 3.5))]
    }

    /// Twenty ticks of exact commands and of exact measurements plus `wobble`, the
    /// truth offered before each.
    fn run<F: Offered>(mut filter: F, wobble: f64) -> F {
        let mut truth = Pose2::IDENTITY;
        let control = Control::new(1.0, 0.3);
        for tick in 0..20 {
            let before = truth;
            truth = MotionModel::ExactArc.step(&truth, &control, 0.1).pose;
            filter.offer(before, truth, &landmarks());
            filter
                .predict(&control, 0.1)
                .unwrap_or_else(|e| panic!("{e}"));
            for (id, lm) in landmarks() {
                let exact = range_bearing::predict(&truth, &lm)
                    .unwrap_or_else(|e| panic!("{e}"))
                    .measurement;
                let noise = wobble * math::sin((tick * 5 + id) as f64);
                let z = RangeBearing::new(exact.range + noise, exact.bearing - noise);
                filter.update(id, &z).unwrap_or_else(|e| panic!("{e}"));
            }
        }
        filter
    }

    fn ekf(linearization: Linearization) -> EkfSlam {
        EkfSlam::with_linearization(config(), Pose2::IDENTITY, linearization)
            .unwrap_or_else(|e| panic!("{e}"))
    }

    fn ideal() -> IdealEkf {
        IdealEkf::new(config(), Pose2::IDENTITY).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn the_ideal_ekf_is_the_textbook_ekf_when_the_estimate_is_the_truth() {
        // Exact commands and measurements keep the estimate on the truth (every
        // innovation is zero), so Jacobians at the truth and at the estimate agree.
        let (textbook, ideal) = (
            run(ekf(Linearization::LatestEstimate), 0.0),
            run(ideal(), 0.0),
        );
        assert_eq!(ideal.name(), "ideal-ekf");
        assert!((textbook.covariance() - ideal.covariance()).norm() < 1e-12);
        assert!((textbook.mean() - ideal.mean()).norm() < 1e-12);
        // With noisy measurements the estimate leaves the truth and the two differ.
        let (textbook, ideal) = (
            run(ekf(Linearization::LatestEstimate), 0.05),
            run(self::ideal(), 0.05),
        );
        assert!((textbook.covariance() - ideal.covariance()).norm() > 1e-6);
        // Other linearizations ignore the point they are offered.
        let mut fej = run(ekf(Linearization::FirstEstimates), 0.05);
        let before = fej.clone();
        fej.offer(
            Pose2::new(9.0, 9.0, 1.0),
            Pose2::new(9.0, 9.0, 1.0),
            &landmarks(),
        );
        fej.predict(&Control::new(1.0, 0.3), 0.1)
            .unwrap_or_else(|e| panic!("{e}"));
        let mut reference = before;
        reference
            .predict(&Control::new(1.0, 0.3), 0.1)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(fej.covariance(), reference.covariance());
    }
}
