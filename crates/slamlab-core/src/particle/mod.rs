//! Particle filters: importance weights kept in log space, and the resamplers
//! that turn a weighted particle set into an unweighted one (thesis `000` Sec. 2.3,
//! Algorithms 6 and 7; Probabilistic Robotics Table 4.4).
//!
//! Weights travel as logarithms because a likelihood over 60 lidar beams is
//! easily `e^-800`, which is zero in `f64`. Normalizing with log-sum-exp keeps
//! every particle's relative weight however small the absolute numbers are.

pub mod cluster;
pub mod fastslam;
pub mod grid_fastslam;
pub mod lab;
pub mod mcl;
pub mod recovery;
pub mod resample;
pub mod sensor;
pub mod weights;

pub use cluster::{ClusterBins, PoseEstimate, heaviest_cluster};
pub use fastslam::{
    FastSlam, FastSlamConfig, FastSlamError, FastSlamNoise, FastSlamVersion, LandmarkEkf,
    LandmarkObservation, ParticleUpdateReport, ParticleView, ResamplePolicy,
};
pub use grid_fastslam::{
    GridFastSlam, GridFastSlamConfig, GridParticle, GridUpdateReport, MAX_GRID_PARTICLES, PathNode,
    Proposal,
};
pub use lab::{CopyCountStats, ResamplingLab, WeightPreset, copy_counts, sanitize_weights};
pub use mcl::{
    KldSampling, LocalizationMap, MAX_PARTICLES, Mcl, MclConfig, MclError, Particle, ParticleFlag,
    PredictReport, ResampleReport, WeightReport,
};
pub use recovery::{RecoveringMcl, Recovery, RecoveryAlphas, RecoveryReport};
pub use resample::{Resampler, resample_indices};
pub use sensor::{
    BeamLikelihood, BeamModel, LikelihoodFieldModel, MeasurementModel, PreparedModel, Scan,
    ScanAggregation,
};
pub use weights::{WeightError, effective_sample_size, log_sum_exp, normalize_log_weights};

/// The particle filters seen through the belief traits the lessons draw with.
#[cfg(test)]
mod belief_tests {
    use crate::belief::ParticleBelief as _;
    use crate::geometry::Pose2;

    /// The particle filters' beliefs agree with their own accessors: the pose is
    /// the estimate they report, the weights are normalized, `N_eff` is theirs.
    #[test]
    fn particle_filters_show_their_own_estimates() {
        use crate::grid::{Cell, OccupancyGrid};
        use crate::particle::{FastSlam, FastSlamConfig, LocalizationMap, Mcl, MclConfig};
        use nalgebra::Vector3;
        use std::sync::Arc;

        let mut grid = OccupancyGrid::filled(40, 40, 0.1, Pose2::IDENTITY, Cell::Free).unwrap();
        for k in 0..40 {
            grid.set(k, 0, Cell::Occupied);
            grid.set(0, k, Cell::Occupied);
        }
        let map = Arc::new(LocalizationMap::new(grid, 1.0).unwrap());
        let mut mcl = Mcl::new(
            MclConfig {
                particles: 300,
                ..Default::default()
            },
            map,
            4,
        );
        mcl.init_tracking(Pose2::new(2.0, 2.0, 0.3), [0.2, 0.2, 0.1]);
        let Some(estimate) = mcl.estimate().copied() else {
            panic!("a tracking cloud has an estimate");
        };
        assert_eq!(crate::belief::PoseBelief::robot_pose(&mcl), estimate.pose);
        assert_eq!(
            crate::belief::PoseBelief::robot_covariance(&mcl),
            estimate.covariance
        );
        assert_eq!(crate::belief::ParticleBelief::particle_count(&mcl), 300);
        let total: f64 = (0..300).map(|i| mcl.particle_weight(i)).sum();
        assert!((total - 1.0).abs() < 1e-12);
        assert_eq!(crate::belief::ParticleBelief::n_eff(&mcl), mcl.n_eff());
        assert_eq!(mcl.particle_pose(300), None);
        assert_eq!(mcl.particle_weight(300), 0.0);

        let fast = FastSlam::new(
            FastSlamConfig {
                particles: 50,
                ..Default::default()
            },
            Pose2::new(1.0, -1.0, 0.5),
        )
        .unwrap();
        // Every particle starts at the pose: the mean is it, with no spread.
        let mean = crate::belief::PoseBelief::robot_pose(&fast);
        assert!((mean.to_vector() - Vector3::new(1.0, -1.0, 0.5)).norm() < 1e-12);
        assert!(crate::belief::PoseBelief::robot_covariance(&fast).norm() < 1e-24);
        assert!((crate::belief::ParticleBelief::n_eff(&fast) - 50.0).abs() < 1e-9);
        assert_eq!(fast.particle_pose(0), Some(Pose2::new(1.0, -1.0, 0.5)));
    }
}
