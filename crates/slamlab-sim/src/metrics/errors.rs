//! The absolute and relative pose errors, their statistics, and the normalized
//! estimation error squared, each as evo (and Bar-Shalom) define them.

use super::{Association, MetricsError, Similarity, Trajectory};
use nalgebra::{DMatrix, DVector, Matrix3};
use serde::Serialize;
use slamlab_core::stats::{chi2_band_95, normalized_squared_error};
use slamlab_core::{Pose2, wrap_angle};

/// The statistics evo prints for an error series (`evo_ape`'s `rmse`, `mean`,
/// `median`, `std`, `min`, `max`, `sse`): `std` is the population standard
/// deviation (numpy's `std`), `median` the middle value or the mean of the two
/// middle ones.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ErrorStats {
    /// `√(Σ e²/n)`.
    pub rmse: f64,
    /// `Σ e/n`.
    pub mean: f64,
    /// The middle value.
    pub median: f64,
    /// `√(Σ (e − mean)²/n)`.
    pub std: f64,
    /// The smallest.
    pub min: f64,
    /// The largest.
    pub max: f64,
    /// `Σ e²`.
    pub sse: f64,
    /// How many errors.
    pub count: usize,
}

impl ErrorStats {
    /// The statistics of `errors`; `None` for none.
    pub fn of(errors: &[f64]) -> Option<Self> {
        if errors.is_empty() {
            return None;
        }
        let n = errors.len() as f64;
        let sse: f64 = errors.iter().map(|e| e * e).sum();
        let mean = errors.iter().sum::<f64>() / n;
        let var = errors.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / n;
        let mut sorted = errors.to_vec();
        sorted.sort_by(f64::total_cmp);
        let mid = sorted.len() / 2;
        let median = if sorted.len() % 2 == 1 {
            sorted[mid]
        } else {
            0.5 * (sorted[mid - 1] + sorted[mid])
        };
        Some(ErrorStats {
            rmse: (sse / n).sqrt(),
            mean,
            median,
            std: var.sqrt(),
            min: sorted[0],
            max: sorted[sorted.len() - 1],
            sse,
            count: errors.len(),
        })
    }
}

/// The error at each pair and its statistics: translation in metres, rotation in
/// degrees.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseErrors {
    /// The distances between the paired positions (APE) or the translation of
    /// each relative error pose (RPE), metres.
    pub translation_m: Vec<f64>,
    /// The absolute angle of each error's rotation, degrees.
    pub rotation_deg: Vec<f64>,
    /// The statistics of `translation_m`.
    pub translation: ErrorStats,
    /// The statistics of `rotation_deg`.
    pub rotation: ErrorStats,
}

impl PoseErrors {
    fn new(translation_m: Vec<f64>, rotation_deg: Vec<f64>) -> Option<Self> {
        Some(PoseErrors {
            translation: ErrorStats::of(&translation_m)?,
            rotation: ErrorStats::of(&rotation_deg)?,
            translation_m,
            rotation_deg,
        })
    }
}

/// The absolute pose error (evo's APE; the ATE of Sturm et al. 2012 for the
/// translation) of the aligned estimate at each pair: `‖p_est − p_ref‖` and
/// `|wrap(θ_ref − θ_est)|`.
pub fn absolute_errors(
    reference: &Trajectory,
    estimate: &Trajectory,
    pairs: &Association,
    alignment: &Similarity,
) -> Option<PoseErrors> {
    let mut translation = Vec::with_capacity(pairs.len());
    let mut rotation = Vec::with_capacity(pairs.len());
    for (&e, &r) in pairs.estimate.iter().zip(&pairs.reference) {
        let (Some(est), Some(truth)) = (estimate.poses().get(e), reference.poses().get(r)) else {
            continue;
        };
        let est = alignment.apply(est);
        translation.push(slamlab_core::math::hypot(est.x - truth.x, est.y - truth.y));
        rotation.push(wrap_angle(truth.theta - est.theta).abs().to_degrees());
    }
    PoseErrors::new(translation, rotation)
}

/// What the relative error's step is counted in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DeltaUnit {
    /// Poses (evo's `--delta_unit f`).
    Frames,
    /// Metres travelled by the estimate (evo's `--delta_unit m`).
    Meters,
}

impl DeltaUnit {
    /// The name on the command line: `frames` or `m`.
    pub fn name(self) -> &'static str {
        match self {
            DeltaUnit::Frames => "frames",
            DeltaUnit::Meters => "m",
        }
    }

    /// Reads `frames`/`f` or `m`/`meters`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "frames" | "frame" | "f" => Some(DeltaUnit::Frames),
            "m" | "meters" | "metres" => Some(DeltaUnit::Meters),
            _ => None,
        }
    }
}

/// How the relative error's pairs are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RelativeDelta {
    /// The step, in `unit`.
    pub delta: f64,
    /// Poses or metres.
    pub unit: DeltaUnit,
    /// Every pair `delta` apart (evo's `--all_pairs`) instead of consecutive ones.
    pub all_pairs: bool,
}

impl Default for RelativeDelta {
    /// evo's default: consecutive poses.
    fn default() -> Self {
        RelativeDelta {
            delta: 1.0,
            unit: DeltaUnit::Frames,
            all_pairs: false,
        }
    }
}

/// The index pairs of evo's `id_pairs_from_delta` on `poses` (the estimate's,
/// aligned): every `delta`-th pose in a chain, or with `all_pairs` every pose
/// with the one `delta` later; in metres (evo 1.38's `filter_pairs_by_path`), a
/// chain from the first pose whose every link is the first pose whose path from
/// the link before reaches `delta`, or, with `all_pairs`, each pose with the one
/// whose path distance from it is nearest `delta`, within 10 %.
pub fn delta_pairs(
    poses: &[Pose2],
    delta: &RelativeDelta,
) -> Result<Vec<(usize, usize)>, MetricsError> {
    let n = poses.len();
    let pairs = match delta.unit {
        DeltaUnit::Frames => {
            if !(delta.delta >= 1.0) || delta.delta.fract() != 0.0 || delta.delta > n as f64 {
                return Err(MetricsError::BadSetting(format!(
                    "a step in frames must be a whole number from 1 to the {n} paired poses (was {})",
                    delta.delta
                )));
            }
            let d = delta.delta as usize;
            if delta.all_pairs {
                (0..n.saturating_sub(d)).map(|i| (i, i + d)).collect()
            } else {
                let ids: Vec<usize> = (0..n).step_by(d).collect();
                ids.windows(2).map(|w| (w[0], w[1])).collect()
            }
        }
        DeltaUnit::Meters => {
            if !(delta.delta > 0.0) || !delta.delta.is_finite() {
                return Err(MetricsError::BadSetting(format!(
                    "a step in metres must be a positive number (was {})",
                    delta.delta
                )));
            }
            if delta.all_pairs {
                let mut travelled = vec![0.0; n];
                for k in 1..n {
                    travelled[k] =
                        travelled[k - 1] + super::trajectory::distance(&poses[k - 1], &poses[k]);
                }
                let tolerance = 0.1 * delta.delta;
                let mut pairs = Vec::new();
                for i in 0..n.saturating_sub(1) {
                    // The later pose whose distance from i is nearest delta (the first of equals).
                    let mut best = (i + 1, f64::INFINITY);
                    for (j, t) in travelled.iter().enumerate().skip(i + 1) {
                        let off = ((t - travelled[i]) - delta.delta).abs();
                        if off < best.1 {
                            best = (j, off);
                        }
                    }
                    if best.1 <= tolerance {
                        pairs.push((i, best.0));
                    }
                }
                pairs
            } else {
                let mut ids = vec![0];
                let mut path = 0.0;
                for k in 1..n {
                    path += super::trajectory::distance(&poses[k - 1], &poses[k]);
                    if path >= delta.delta {
                        ids.push(k);
                        path = 0.0;
                    }
                }
                ids.windows(2).map(|w| (w[0], w[1])).collect()
            }
        }
    };
    if pairs.is_empty() {
        return Err(MetricsError::BadSetting(format!(
            "a step of {} {} leaves no pair of poses among the {n} paired ones: try a smaller step",
            delta.delta,
            delta.unit.name()
        )));
    }
    Ok(pairs)
}

/// The relative pose error (evo's RPE, Sturm et al. 2012 Eq. 1) over the pairs
/// `delta` apart: `E = (Q_i⁻¹ Q_j)⁻¹ (P_i⁻¹ P_j)` for reference poses `Q` and
/// aligned estimated poses `P`, its translation's length and its angle. Returns
/// the errors and the pairs (indices into the association).
pub fn relative_errors(
    reference: &Trajectory,
    estimate: &Trajectory,
    pairs: &Association,
    alignment: &Similarity,
    delta: &RelativeDelta,
) -> Result<(PoseErrors, Vec<(usize, usize)>), MetricsError> {
    let est: Vec<Pose2> = pairs
        .estimate
        .iter()
        .filter_map(|&e| estimate.poses().get(e).map(|p| alignment.apply(p)))
        .collect();
    let truth: Vec<Pose2> = pairs
        .reference
        .iter()
        .filter_map(|&r| reference.poses().get(r).copied())
        .collect();
    let ids = delta_pairs(&est, delta)?;
    let mut translation = Vec::with_capacity(ids.len());
    let mut rotation = Vec::with_capacity(ids.len());
    for &(i, j) in &ids {
        let q = truth[i].between(&truth[j]);
        let p = est[i].between(&est[j]);
        let e = q.between(&p);
        translation.push(slamlab_core::math::hypot(e.x, e.y));
        rotation.push(wrap_angle(e.theta).abs().to_degrees());
    }
    let errors = PoseErrors::new(translation, rotation)
        .ok_or_else(|| MetricsError::BadSetting("no relative pose pairs".to_owned()))?;
    Ok((errors, ids))
}

/// The normalized estimation error squared of the estimate's covariances.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Nees {
    /// `eᵀ P⁻¹ e` at each pair whose covariance is usable (`None` where it is
    /// not positive definite, as at a filter's start), with
    /// `e = (x_est − x_ref, y_est − y_ref, wrap(θ_est − θ_ref))`.
    pub values: Vec<Option<f64>>,
    /// The average over the usable values (ANEES).
    pub anees: Option<f64>,
    /// How many values are usable.
    pub count: usize,
    /// The 95 % band of one value: χ²₃ quantiles 0.025 and 0.975.
    pub band95: (f64, f64),
    /// The 95 % band of the average of `count` values.
    pub anees_band95: (f64, f64),
    /// The share of usable values inside `band95`.
    pub share_in_band: Option<f64>,
}

/// NEES at each pair, for an estimate with covariances; the covariance is turned
/// (and scaled) with the estimate by the alignment. The value at each pair is
/// exactly what the lessons plot for their estimators (the same
/// [`normalized_squared_error`] on the same numbers).
pub fn nees(
    reference: &Trajectory,
    estimate: &Trajectory,
    pairs: &Association,
    alignment: &Similarity,
) -> Option<Nees> {
    let covariances = estimate.covariances()?;
    let (s, c) = slamlab_core::math::sin_cos(alignment.rotation);
    let k = alignment.scale;
    let jacobian = Matrix3::new(k * c, -k * s, 0.0, k * s, k * c, 0.0, 0.0, 0.0, 1.0);
    let rigid = *alignment == Similarity::IDENTITY;
    let values: Vec<Option<f64>> = pairs
        .estimate
        .iter()
        .zip(&pairs.reference)
        .map(|(&e, &r)| {
            let (est, truth, p) = (
                estimate.poses().get(e)?,
                reference.poses().get(r)?,
                covariances.get(e)?,
            );
            let est = alignment.apply(est);
            let p = if rigid {
                *p
            } else {
                jacobian * p * jacobian.transpose()
            };
            let error = [
                truth.x - est.x,
                truth.y - est.y,
                wrap_angle(truth.theta - est.theta),
            ];
            normalized_squared_error(
                &DVector::from_column_slice(&error),
                &DMatrix::from_iterator(3, 3, p.iter().copied()),
            )
        })
        .collect();
    let usable: Vec<f64> = values.iter().flatten().copied().collect();
    let count = usable.len();
    let band95 = chi2_band_95(3.0, 1);
    Some(Nees {
        anees: (count > 0).then(|| usable.iter().sum::<f64>() / count as f64),
        share_in_band: (count > 0).then(|| {
            usable
                .iter()
                .filter(|v| (band95.0..=band95.1).contains(*v))
                .count() as f64
                / count as f64
        }),
        anees_band95: chi2_band_95(3.0, count.max(1)),
        band95,
        count,
        values,
    })
}
