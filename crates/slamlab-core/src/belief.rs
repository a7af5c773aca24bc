//! What an estimator can show, one trait per kind of belief.
//!
//! Estimators differ in what their belief *is*. EKF- and UKF-SLAM keep one joint
//! Gaussian over the robot and every landmark; FastSLAM keeps particles, each a
//! robot path with a map of its own; Monte Carlo localization keeps particles
//! over the robot's pose alone. A lesson draws what an estimator has, and asks
//! for nothing it has not:
//!
//! | trait | what it shows | drawn as | implemented by |
//! |---|---|---|---|
//! | [`PoseBelief`] | the robot pose and its 3x3 covariance | robot, 95% ellipse, heading wedge; errors and NEES | every estimator |
//! | [`LandmarkBelief`] | each landmark's mean and 2x2 covariance | landmark ellipses | EKF, UKF, FastSLAM (its best particle's map) |
//! | [`JointGaussian`] | the whole mean and covariance | the correlation heatmap; gated association | EKF, UKF |
//! | [`ParticleBelief`] | every particle's pose and normalized weight | the particle cloud; `N_eff` | FastSLAM, MCL, AMCL, ACMCL |
//!
//! A particle filter has no joint covariance: FastSLAM's landmarks are
//! independent given a particle's path (Montemerlo et al. 2002), and an MCL
//! cloud may have several modes. Its [`PoseBelief`] is a summary (the weighted
//! mean and covariance of the particles, or of the heaviest cluster as amcl
//! reports it), and nothing pretends it has more.

use crate::geometry::Pose2;
use nalgebra::{DMatrix, DVector, Matrix2, Matrix3, Vector2};

/// One landmark's estimate, for drawing and metrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LandmarkEstimate {
    /// The landmark's id (the sensor's data association, or the filter's own label).
    pub id: usize,
    /// Estimated position, metres.
    pub mean: Vector2<f64>,
    /// Its 2x2 covariance.
    pub covariance: Matrix2<f64>,
}

/// An estimate of the robot's pose with its uncertainty: every estimator has one.
pub trait PoseBelief {
    /// The estimated robot pose.
    fn robot_pose(&self) -> Pose2;
    /// The covariance of `[x, y, θ]` around [`robot_pose`](Self::robot_pose).
    fn robot_covariance(&self) -> Matrix3<f64>;
}

/// A map of point landmarks, each with its own 2x2 uncertainty.
pub trait LandmarkBelief {
    /// Landmark ids in the filter's order (order of discovery).
    fn landmark_ids(&self) -> &[usize];
    /// Every landmark's estimate, in the same order.
    fn landmarks(&self) -> Vec<LandmarkEstimate>;
}

/// One Gaussian over the whole state `M = [x, y, θ, L¹x, L¹y, …]` (thesis `000`
/// Eq. 3.1), landmarks in the order of [`LandmarkBelief::landmark_ids`]: what a
/// Kalman filter keeps, with every cross covariance.
pub trait JointGaussian {
    /// The full state mean `M`.
    fn mean(&self) -> &DVector<f64>;
    /// The full state covariance `P`.
    fn covariance(&self) -> &DMatrix<f64>;
}

/// A weighted set of pose hypotheses.
pub trait ParticleBelief {
    /// Number of particles.
    fn particle_count(&self) -> usize;
    /// Particle `index`'s pose (`None` out of range).
    fn particle_pose(&self, index: usize) -> Option<Pose2>;
    /// Particle `index`'s normalized weight (0 out of range).
    fn particle_weight(&self, index: usize) -> f64;

    /// The effective sample size `N_eff = 1 / Σ wᵢ²` (slides, "Adaptive
    /// resampling"): the particle count for uniform weights, 1 when one particle
    /// carries all the weight.
    fn n_eff(&self) -> f64 {
        crate::stats::effective_sample_size(
            &(0..self.particle_count())
                .map(|i| self.particle_weight(i))
                .collect::<Vec<_>>(),
        )
    }
}

/// The robot pose of a joint state: its first three entries (the origin for a
/// state too short to hold a pose).
pub fn joint_robot_pose(g: &(impl JointGaussian + ?Sized)) -> Pose2 {
    let m = g.mean();
    if m.len() < 3 {
        return Pose2::IDENTITY;
    }
    Pose2::new(m[0], m[1], m[2])
}

/// The robot's 3x3 block of a joint covariance (zeros for a state too small).
pub fn joint_robot_covariance(g: &(impl JointGaussian + ?Sized)) -> Matrix3<f64> {
    let p = g.covariance();
    if p.nrows() < 3 || p.ncols() < 3 {
        return Matrix3::zeros();
    }
    p.fixed_view::<3, 3>(0, 0).into_owned()
}

/// Every landmark's marginal of a joint Gaussian, `ids` in state order. Slots the
/// state does not hold are left out.
pub fn joint_landmarks(g: &(impl JointGaussian + ?Sized), ids: &[usize]) -> Vec<LandmarkEstimate> {
    let (m, p) = (g.mean(), g.covariance());
    ids.iter()
        .enumerate()
        .map(|(slot, &id)| (3 + 2 * slot, id))
        .take_while(|&(j, _)| j + 2 <= m.len() && j + 2 <= p.nrows() && j + 2 <= p.ncols())
        .map(|(j, id)| LandmarkEstimate {
            id,
            mean: Vector2::new(m[j], m[j + 1]),
            covariance: p.fixed_view::<2, 2>(j, j).into_owned(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Joint(DVector<f64>, DMatrix<f64>);

    impl JointGaussian for Joint {
        fn mean(&self) -> &DVector<f64> {
            &self.0
        }
        fn covariance(&self) -> &DMatrix<f64> {
            &self.1
        }
    }

    struct Cloud(Vec<f64>);

    impl ParticleBelief for Cloud {
        fn particle_count(&self) -> usize {
            self.0.len()
        }
        fn particle_pose(&self, index: usize) -> Option<Pose2> {
            (index < self.0.len()).then_some(Pose2::IDENTITY)
        }
        fn particle_weight(&self, index: usize) -> f64 {
            self.0.get(index).copied().unwrap_or(0.0)
        }
    }

    #[test]
    fn marginals_of_a_joint_state_are_its_blocks() {
        let mean = DVector::from_column_slice(&[1.0, 2.0, 0.5, 4.0, 5.0, 6.0, 7.0]);
        let cov = DMatrix::from_fn(7, 7, |i, j| (10 * i + j) as f64);
        let g = Joint(mean, cov);
        assert_eq!(joint_robot_pose(&g), Pose2::new(1.0, 2.0, 0.5));
        assert_eq!(joint_robot_covariance(&g)[(2, 1)], 21.0);
        let lm = joint_landmarks(&g, &[8, 3]);
        assert_eq!(lm.len(), 2);
        assert_eq!((lm[1].id, lm[1].mean), (3, Vector2::new(6.0, 7.0)));
        assert_eq!(lm[1].covariance, Matrix2::new(55.0, 56.0, 65.0, 66.0));
        // More ids than the state holds: only the slots it has.
        assert_eq!(joint_landmarks(&g, &[8, 3, 9]).len(), 2);
        let empty = Joint(DVector::zeros(0), DMatrix::zeros(0, 0));
        assert_eq!(joint_robot_pose(&empty), Pose2::IDENTITY);
        assert_eq!(joint_robot_covariance(&empty), Matrix3::zeros());
    }

    #[test]
    fn n_eff_counts_the_particles_that_carry_the_weight() {
        assert!((Cloud(vec![0.25; 4]).n_eff() - 4.0).abs() < 1e-12);
        assert!((Cloud(vec![1.0, 0.0, 0.0]).n_eff() - 1.0).abs() < 1e-12);
        assert!((Cloud(vec![0.5, 0.5, 0.0, 0.0]).n_eff() - 2.0).abs() < 1e-12);
    }
}
