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
