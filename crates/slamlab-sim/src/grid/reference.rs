//! A laser log's reference trajectory, and how a trajectory scores against it
//! the way the field scores laser SLAM on the corrected logs.
//!
//! The reference ([`LogReference`]) is a corrected log's poses at the raw
//! scans they were matched to ([`crate::io::laser_reference`]: by time,
//! confirmed by identical ranges). A pose source gives one pose per input scan
//! (or none, for a scan it has not placed); [`score`] compares them at the
//! reference scans with the project's trajectory metrics ([`crate::metrics`],
//! the evo equations):
//!
//! - **ATE**: the RMS of `‖p_est − p_ref‖` after the SE(2) alignment that fits
//!   the estimated positions to the reference's best (Umeyama's method; the
//!   reference is in a frame of its own).
//! - **Relative error** (Kümmerle et al. 2009, "On measuring the accuracy of
//!   SLAM algorithms", Eq. 2; the Cartographer paper's Table I, Hess et al.
//!   2016): over every pair of reference scans `δ` apart (1 and 10 here), the
//!   error transform `E = (Q_i⁻¹ Q_j)⁻¹ (P_i⁻¹ P_j)` of the estimated relative
//!   motion against the reference's, its translation `‖t_E‖` (m) and angle
//!   `|θ_E|` (degrees), each as mean and standard deviation, and the same of
//!   their squares (m², deg²), as Table I reports them. No alignment enters:
//!   a relative motion does not see the frame.

use crate::io::laser_log::LaserLog;
use crate::io::laser_reference::{Association, ReferenceError, ReferenceLog, associate};
use crate::metrics::{self, DeltaUnit, RelativeDelta, Trajectory};
use serde::Serialize;
use slamlab_core::Pose2;

/// The reference steps scored: pairs 1 and 10 reference scans apart.
pub const RELATIVE_DELTAS: [usize; 2] = [1, 10];

/// One reference scan at its input scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferencePoint {
    /// The input scan's index.
    pub scan: usize,
    /// The reference pose (in the reference's own frame).
    pub pose: Pose2,
}

/// The reference poses of a log's scans.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LogReference {
    /// The reference's name (its file).
    pub name: String,
    /// The matched reference scans, in reference order.
    pub points: Vec<ReferencePoint>,
    /// Scans in the reference file.
    pub reference_scans: usize,
    /// How the matching went, in a sentence.
    pub description: String,
}

impl LogReference {
    /// The reference of `log` (the raw log; its scan indices are the mapping
    /// input's, as the grid's `log_input` keeps them) from a corrected log's bytes.
    pub fn read(bytes: &[u8], name: &str, log: &LaserLog) -> Result<Self, ReferenceError> {
        let reference = ReferenceLog::from_bytes(bytes)?;
        let association = associate(&reference, log)?;
        Ok(Self::from_association(name, &reference, &association))
    }

    /// The reference from a corrected log and its association with the raw log.
    pub fn from_association(
        name: &str,
        reference: &ReferenceLog,
        association: &Association,
    ) -> Self {
        Self {
            name: name.to_owned(),
            points: association
                .pairs
                .iter()
                .filter_map(|p| {
                    Some(ReferencePoint {
                        scan: p.scan,
                        pose: reference.scans.get(p.reference)?.pose,
                    })
                })
                .collect(),
            reference_scans: reference.scans.len(),
            description: association.describe(),
        }
    }
}

/// A mean and a (population) standard deviation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MeanStd {
    /// The mean.
    pub mean: f64,
    /// The standard deviation.
    pub std: f64,
}

impl MeanStd {
    fn of(values: &[f64]) -> Self {
        match metrics::ErrorStats::of(values) {
            Some(s) => Self {
                mean: s.mean,
                std: s.std,
            },
            None => Self {
                mean: f64::NAN,
                std: f64::NAN,
            },
        }
    }
}

/// Kümmerle's relative error over reference pairs `delta` scans apart.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RelativeScore {
    /// Reference scans between the two of a pair.
    pub delta: usize,
    /// Pairs.
    pub pairs: usize,
    /// `‖t_E‖`, metres.
    pub translation_m: MeanStd,
    /// `‖t_E‖²`, m².
    pub translation_sq_m2: MeanStd,
    /// `|θ_E|`, degrees.
    pub rotation_deg: MeanStd,
    /// `θ_E²`, deg².
    pub rotation_sq_deg2: MeanStd,
}

/// A trajectory's score against the reference.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrajectoryScore {
    /// Reference scans the trajectory has a pose for.
    pub pairs: usize,
    /// RMS position error after the SE(2) alignment, metres.
    pub ate_m: f64,
    /// The largest position error after the alignment, metres.
    pub ate_max_m: f64,
    /// Relative errors over pairs 1 and 10 reference scans apart.
    pub relative: Vec<RelativeScore>,
}

/// The estimate and the reference at the reference scans the estimate has a
/// pose for (`poses[scan]`), as two trajectories paired index by index (the
/// reference's order; stamps are the pair's index).
fn paired(reference: &LogReference, poses: &[Option<Pose2>]) -> (Trajectory, Trajectory) {
    let (mut est, mut refs) = (Vec::new(), Vec::new());
    for p in &reference.points {
        if let Some(Some(pose)) = poses.get(p.scan)
            && pose.is_finite()
        {
            est.push(*pose);
            refs.push(p.pose);
        }
    }
    let stamps: Vec<f64> = (0..est.len()).map(|k| k as f64).collect();
    (
        Trajectory::new(stamps.clone(), est),
        Trajectory::new(stamps, refs),
    )
}

/// The identity pairing of two trajectories of equal length.
fn identity(n: usize) -> metrics::Association {
    metrics::Association {
        estimate: (0..n).collect(),
        reference: (0..n).collect(),
        max_diff: 0.0,
        offset: 0.0,
        estimate_poses: n,
        reference_poses: n,
    }
}

/// The SE(2) transform that moves `poses` (one per input scan) onto the
/// reference at the reference scans they cover (Umeyama's method), with the
/// ATE after it and the scans it rests on; `None` with fewer than two.
pub fn alignment(
    reference: &LogReference,
    poses: &[Option<Pose2>],
) -> Option<(metrics::Similarity, f64, usize)> {
    let (est, refs) = paired(reference, poses);
    let n = est.len();
    if n < 2 {
        return None;
    }
    let xy = |t: &Trajectory| -> Vec<[f64; 2]> { t.poses().iter().map(|p| [p.x, p.y]).collect() };
    let similarity = metrics::umeyama(&xy(&est), &xy(&refs), false).ok()?;
    let errors = metrics::absolute_errors(&refs, &est, &identity(n), &similarity)?;
    Some((similarity, errors.translation.rmse, n))
}

/// The ATE (RMS and largest position error after the SE(2) alignment) of
/// `poses` (one per input scan) at the reference scans they cover; `None`
/// with fewer than two such scans (nothing fixes the alignment).
pub fn ate(reference: &LogReference, poses: &[Option<Pose2>]) -> Option<(f64, f64, usize)> {
    let (est, refs) = paired(reference, poses);
    let n = est.len();
    if n < 2 {
        return None;
    }
    let pairs = identity(n);
    let xy = |t: &Trajectory| -> Vec<[f64; 2]> { t.poses().iter().map(|p| [p.x, p.y]).collect() };
    // SE(2): rotation and translation, no scale (evo's `--align`).
    let alignment = metrics::umeyama(&xy(&est), &xy(&refs), false).ok()?;
    let errors = metrics::absolute_errors(&refs, &est, &pairs, &alignment)?;
    Some((errors.translation.rmse, errors.translation.max, n))
}

/// Scores `poses` (one per input scan, `None` where the source placed none)
/// against the reference; `None` when fewer than two reference scans have a
/// pose.
pub fn score(reference: &LogReference, poses: &[Option<Pose2>]) -> Option<TrajectoryScore> {
    let (ate_m, ate_max_m, n) = ate(reference, poses)?;
    let (est, refs) = paired(reference, poses);
    let pairs = identity(n);
    let relative = RELATIVE_DELTAS
        .iter()
        .filter(|&&d| d < n)
        .filter_map(|&d| {
            let delta = RelativeDelta {
                delta: d as f64,
                unit: DeltaUnit::Frames,
                all_pairs: true,
            };
            let (errors, ids) = metrics::relative_errors(
                &refs,
                &est,
                &pairs,
                &metrics::Similarity::IDENTITY,
                &delta,
            )
            .ok()?;
            let sq = |v: &[f64]| -> Vec<f64> { v.iter().map(|e| e * e).collect() };
            Some(RelativeScore {
                delta: d,
                pairs: ids.len(),
                translation_m: MeanStd::of(&errors.translation_m),
                translation_sq_m2: MeanStd::of(&sq(&errors.translation_m)),
                rotation_deg: MeanStd::of(&errors.rotation_deg),
                rotation_sq_deg2: MeanStd::of(&sq(&errors.rotation_deg)),
            })
        })
        .collect();
    Some(TrajectoryScore {
        pairs: n,
        ate_m,
        ate_max_m,
        relative,
    })
}

/// Poses for every input scan from poses at some of them (`path`: scan index
/// and pose, in scan order), each scan between placed ones moved from the
/// last placed scan by the odometry since (`odometry[k]`); scans before the
/// first placed one have none.
pub fn fill_by_odometry(path: &[(usize, Pose2)], odometry: &[Pose2]) -> Vec<Option<Pose2>> {
    let mut out = vec![None; odometry.len()];
    let mut next = path.iter().peekable();
    let mut last: Option<(usize, Pose2)> = None;
    for (k, slot) in out.iter_mut().enumerate() {
        while let Some(&&(s, p)) = next.peek() {
            if s > k {
                break;
            }
            if s == k {
                last = Some((s, p));
            }
            next.next();
        }
        *slot = last.map(|(s, p)| {
            if s == k {
                p
            } else {
                p.compose(&odometry[s].between(&odometry[k]))
            }
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reference on a square path, scans 0..40 every other one.
    fn square() -> (LogReference, Vec<Pose2>) {
        let mut truth = Vec::new();
        for k in 0..40 {
            let side = k / 10;
            let s = (k % 10) as f64 * 0.5;
            let p = match side {
                0 => Pose2::new(s, 0.0, 0.0),
                1 => Pose2::new(5.0, s, std::f64::consts::FRAC_PI_2),
                2 => Pose2::new(5.0 - s, 5.0, std::f64::consts::PI),
                _ => Pose2::new(0.0, 5.0 - s, -std::f64::consts::FRAC_PI_2),
            };
            truth.push(p);
        }
        let points = (0..40)
            .step_by(2)
            .map(|k| ReferencePoint {
                scan: k,
                pose: truth[k],
            })
            .collect();
        (
            LogReference {
                name: "square".to_owned(),
                points,
                reference_scans: 20,
                description: String::new(),
            },
            truth,
        )
    }

    #[test]
    fn a_trajectory_in_another_frame_scores_zero_and_an_error_is_measured() {
        let (reference, truth) = square();
        // The truth moved by 30° and (3, -2): the alignment takes it back.
        let moved = Pose2::new(3.0, -2.0, std::f64::consts::FRAC_PI_6);
        let poses: Vec<Option<Pose2>> = truth.iter().map(|p| Some(moved.compose(p))).collect();
        let s = score(&reference, &poses).unwrap();
        assert_eq!(s.pairs, 20);
        assert!(s.ate_m < 1e-12, "{s:?}");
        assert_eq!(s.relative.len(), 2);
        assert_eq!((s.relative[0].delta, s.relative[0].pairs), (1, 19));
        assert_eq!((s.relative[1].delta, s.relative[1].pairs), (10, 10));
        assert!(s.relative.iter().all(|r| r.translation_m.mean < 1e-12));
        // One reference scan's estimate 0.3 m off along x: 19 pairs at 0, one
        // at 0.3 m; the relative error of the two pairs with that scan is 0.3 m.
        let mut off = poses.clone();
        off[10] = off[10].map(|p| p.compose(&Pose2::new(0.3, 0.0, 0.0)));
        let s = score(&reference, &off).unwrap();
        let r1 = s.relative[0];
        assert!(
            (r1.translation_m.mean - 2.0 * 0.3 / 19.0).abs() < 1e-9,
            "{r1:?}"
        );
        assert!((r1.translation_sq_m2.mean - 2.0 * 0.09 / 19.0).abs() < 1e-9);
        assert!(r1.rotation_deg.mean.abs() < 1e-9);
        // Unaligned, the RMS would be 0.3 / √20 = 0.067 m; a shift alone
        // takes 1/20 of the error off every pose, leaving 0.3 √(19/20) / √20
        // = 0.0654 m, and the rotation a little more (0.0641 m).
        let shifted = 0.3 * (19.0f64 / 20.0).sqrt() / 20f64.sqrt();
        assert!(s.ate_m <= shifted && s.ate_m > 0.06, "{}", s.ate_m);
    }

    #[test]
    fn scans_without_a_pose_are_left_out_and_too_few_give_no_score() {
        let (reference, truth) = square();
        let mut poses: Vec<Option<Pose2>> = truth.iter().copied().map(Some).collect();
        for p in poses.iter_mut().skip(20) {
            *p = None;
        }
        assert_eq!(score(&reference, &poses).unwrap().pairs, 10);
        assert!(score(&reference, &poses[..1]).is_none());
        assert!(score(&reference, &[]).is_none());
    }

    #[test]
    fn odometry_fills_the_scans_between_placed_ones() {
        let odometry: Vec<Pose2> = (0..6).map(|k| Pose2::new(k as f64, 0.0, 0.0)).collect();
        let path = [
            (1, Pose2::new(10.0, 0.0, std::f64::consts::FRAC_PI_2)),
            (4, Pose2::new(0.0, 0.0, 0.0)),
        ];
        let filled = fill_by_odometry(&path, &odometry);
        assert_eq!(filled[0], None);
        assert_eq!(filled[1], Some(path[0].1));
        // Two metres forward from scan 1, facing +y.
        let p3 = filled[3].unwrap();
        assert!(
            (p3.x - 10.0).abs() < 1e-12 && (p3.y - 2.0).abs() < 1e-12,
            "{p3:?}"
        );
        assert_eq!(filled[4], Some(path[1].1));
        assert_eq!(filled[5], Some(Pose2::new(1.0, 0.0, 0.0)));
    }
}
