//! Particle filters: importance weights kept in log space, and the resamplers
//! that turn a weighted particle set into an unweighted one (thesis `000` Sec. 2.3,
//! Algorithms 6 and 7; Probabilistic Robotics Table 4.4).
//!
//! Weights travel as logarithms because a likelihood over 60 lidar beams is
//! easily `e^-800`, which is zero in `f64`. Normalizing with log-sum-exp keeps
//! every particle's relative weight however small the absolute numbers are.

pub mod fastslam;
pub mod lab;
pub mod resample;
pub mod weights;

pub use fastslam::{
    FastSlam, FastSlamConfig, FastSlamError, FastSlamNoise, FastSlamVersion, LandmarkEkf,
    LandmarkObservation, ParticleUpdateReport, ParticleView, ResamplePolicy, ResampleReport,
};
pub use lab::{CopyCountStats, ResamplingLab, WeightPreset, copy_counts, sanitize_weights};
pub use resample::{Resampler, resample_indices};
pub use weights::{WeightError, effective_sample_size, normalize_log_weights};
