//! How good an estimate is, computed once for every lesson, the command line and
//! the graders, the way the field computes it.
//!
//! A trajectory ([`Trajectory`]: timed planar poses, with covariances when the
//! estimator has them) is compared with a reference in three steps, as evo does
//! (Grupp, "evo: Python package for the evaluation of odometry and SLAM", 2017;
//! `evo_ape`, `evo_rpe`):
//!
//! 1. [`associate`]: each pose finds its partner by time, the nearest within a
//!    tolerance (evo's `--t_max_diff`, default 0.01 s), after an optional offset.
//! 2. [`umeyama`]: the estimate is moved into the reference's frame by the rigid
//!    (SE(2)) or similarity (Sim(2)) transform that fits the paired positions best
//!    (evo's `--align`, `--correct_scale`), or left as it is.
//! 3. The errors: the absolute pose error at each pair ([`absolute_errors`], the
//!    ATE of Sturm et al. 2012 for its translation), the relative pose error over
//!    steps of poses or metres ([`relative_errors`], evo's RPE), and, with
//!    covariances, the normalized estimation error squared ([`nees`]) with its
//!    chi-square bands (Bar-Shalom et al. 2001, Sec. 5.4).
//!
//! [`evaluate`] does all three and reports them as `slamlab evaluate --json`
//! prints them. `docs/metrics.md` has the equations and the evo options they
//! correspond to; a test runs evo itself on the same files. Beside trajectories:
//! landmark errors after the same alignment ([`landmark_errors`]), the error of
//! a relative pose ([`relative_pose_error`]), the final cost of an optimized
//! pose graph against the reference solver's ([`graph::score_graph`]), and map
//! agreement ([`crate::grid::map_agreement`], the mapping lesson's metric).

pub mod alignment;
pub mod association;
pub mod errors;
pub mod evaluation;
pub mod graph;
pub mod trajectory;

pub use alignment::{Alignment, Similarity, umeyama};
pub use association::{Association, DEFAULT_MAX_DIFF, associate};
pub use errors::{
    DeltaUnit, ErrorStats, Nees, PoseErrors, RelativeDelta, absolute_errors, delta_pairs, nees,
    relative_errors,
};
pub use evaluation::{Evaluation, EvaluationSettings, evaluate};
pub use trajectory::{NamedTrajectory, Trajectory, TrajectoryRole};

use nalgebra::{Matrix3, Vector3};
use serde::Serialize;
use slamlab_core::math;
use thiserror::Error;

/// Why an estimate could not be evaluated.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum MetricsError {
    /// No pose of the estimate is near a pose of the reference in time.
    #[error("{0}")]
    NoOverlap(String),
    /// The alignment has nothing to fix it.
    #[error("cannot align: {0}")]
    CannotAlign(String),
    /// A setting out of its range.
    #[error("{0}")]
    BadSetting(String),
}

/// One landmark's error after the alignment.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LandmarkError {
    /// The landmark's id.
    pub id: u64,
    /// The distance between the aligned estimate and the true position, metres.
    pub error_m: f64,
}

/// The estimated landmarks (`id`, position) moved by `alignment` and compared with
/// the true ones of the same id; ids without a true landmark are left out.
pub fn landmark_errors(
    estimated: &[(u64, [f64; 2])],
    truth: &[(u64, [f64; 2])],
    alignment: &Similarity,
) -> Vec<LandmarkError> {
    estimated
        .iter()
        .filter_map(|(id, p)| {
            let t = truth.iter().find(|(tid, _)| tid == id)?.1;
            let q = alignment.apply(&slamlab_core::Pose2::new(p[0], p[1], 0.0));
            Some(LandmarkError {
                id: *id,
                error_m: math::hypot(q.x - t[0], q.y - t[1]),
            })
        })
        .collect()
}

/// How far an estimated relative pose `(R, t)` of two views is from the true one:
/// the angle of `R_trueᵀ R` and the angle between the translation directions
/// (a monocular `t` has no length).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RelativePoseError {
    /// The rotation error, degrees.
    pub rotation_deg: f64,
    /// The angle between the estimated and the true direction of translation, degrees.
    pub translation_direction_deg: f64,
}

/// The error of an estimated relative pose against the true one (the two-view
/// lesson's and the `two-view` experiment's measure).
pub fn relative_pose_error(
    rotation: &Matrix3<f64>,
    translation: &Vector3<f64>,
    true_rotation: &Matrix3<f64>,
    true_translation: &Vector3<f64>,
) -> Option<RelativePoseError> {
    let r = true_rotation.transpose() * rotation;
    let cos = ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
    let (a, b) = (translation.norm(), true_translation.norm());
    if !(a > 0.0 && b > 0.0) {
        return None;
    }
    let cos_t = (translation.dot(true_translation) / (a * b)).clamp(-1.0, 1.0);
    Some(RelativePoseError {
        rotation_deg: math::acos(cos).to_degrees(),
        translation_direction_deg: math::acos(cos_t).to_degrees(),
    })
}

#[cfg(test)]
mod tests;
