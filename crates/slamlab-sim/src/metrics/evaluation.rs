//! One estimate against one reference, as `slamlab evaluate` and the lessons
//! report it: association, alignment, APE, RPE and NEES in one place.

use super::errors::{Nees, PoseErrors, RelativeDelta, absolute_errors, nees, relative_errors};
use super::{Alignment, Association, MetricsError, Similarity, Trajectory, associate, umeyama};
use serde::Serialize;

/// How an estimate is compared with its reference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct EvaluationSettings {
    /// The most two paired times may differ, seconds (evo's `--t_max_diff`).
    pub max_diff: f64,
    /// Added to the estimate's times before pairing, seconds (evo's `--t_offset`).
    pub offset: f64,
    /// The alignment before the errors.
    #[serde(serialize_with = "alignment_name")]
    pub alignment: Alignment,
    /// The relative error's step.
    pub delta: RelativeDelta,
}

fn alignment_name<S: serde::Serializer>(a: &Alignment, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(a.name())
}

impl Default for EvaluationSettings {
    /// evo's defaults, with the SE(2) alignment an estimate in its own frame needs.
    fn default() -> Self {
        EvaluationSettings {
            max_diff: super::DEFAULT_MAX_DIFF,
            offset: 0.0,
            alignment: Alignment::Se2,
            delta: RelativeDelta::default(),
        }
    }
}

/// The pairing of the two trajectories, as reported.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PairingReport {
    /// Pairs found.
    pub pairs: usize,
    /// The estimate's poses.
    pub estimate_poses: usize,
    /// The reference's poses.
    pub reference_poses: usize,
    /// The time tolerance, seconds.
    pub max_diff_s: f64,
    /// The offset added to the estimate's times, seconds.
    pub offset_s: f64,
    /// The first and last paired reference time, seconds.
    pub overlap_s: (f64, f64),
    /// The share of the reference's time span the pairs cover.
    pub coverage: f64,
}

/// The alignment found, as reported.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AlignmentReport {
    /// `none`, `se2` or `sim2`.
    pub kind: &'static str,
    /// The rotation, degrees.
    pub rotation_deg: f64,
    /// The translation, metres.
    pub translation_m: [f64; 2],
    /// The scale.
    pub scale: f64,
}

/// An estimate against a reference.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Evaluation {
    /// How they were compared.
    pub settings: EvaluationSettings,
    /// The pairing.
    pub pairing: PairingReport,
    /// The alignment.
    pub alignment: AlignmentReport,
    /// The absolute errors at each pair (the estimate aligned).
    pub ape: PoseErrors,
    /// The relative errors, when the step leaves pairs.
    pub rpe: Option<PoseErrors>,
    /// Why there is no relative error.
    pub rpe_refused: Option<String>,
    /// NEES, when the estimate has covariances.
    pub nees: Option<Nees>,
    /// What a reader should know: a partial overlap, dropped poses.
    pub notices: Vec<String>,
    /// The pairs (for plots over time): estimate and reference index.
    #[serde(skip)]
    pub association: Association,
    /// The transform applied to the estimate.
    #[serde(skip)]
    pub similarity: Similarity,
}

impl Evaluation {
    /// The reference times of the pairs, seconds (the x axis of an error plot).
    pub fn pair_times(&self, reference: &Trajectory) -> Vec<f64> {
        self.association
            .reference
            .iter()
            .filter_map(|&r| reference.stamps().get(r).copied())
            .collect()
    }
}

/// Compares `estimate` with `reference`: pairs them by time, aligns, and
/// computes the absolute and relative errors and, with covariances, NEES.
pub fn evaluate(
    reference: &Trajectory,
    estimate: &Trajectory,
    settings: &EvaluationSettings,
) -> Result<Evaluation, MetricsError> {
    let pairs = associate(reference, estimate, settings.max_diff, settings.offset)?;
    let point = |t: &Trajectory, k: usize| t.poses().get(k).map(|p| [p.x, p.y]);
    let x: Vec<[f64; 2]> = pairs
        .estimate
        .iter()
        .filter_map(|&e| point(estimate, e))
        .collect();
    let y: Vec<[f64; 2]> = pairs
        .reference
        .iter()
        .filter_map(|&r| point(reference, r))
        .collect();
    let similarity = match settings.alignment {
        Alignment::None => Similarity::IDENTITY,
        Alignment::Se2 => umeyama(&x, &y, false)?,
        Alignment::Sim2 => umeyama(&x, &y, true)?,
    };
    let ape = absolute_errors(reference, estimate, &pairs, &similarity)
        .ok_or_else(|| MetricsError::NoOverlap("no pairs".to_owned()))?;
    let (rpe, rpe_refused) =
        match relative_errors(reference, estimate, &pairs, &similarity, &settings.delta) {
            Ok((errors, _)) => (Some(errors), None),
            Err(e) => (None, Some(e.to_string())),
        };
    let nees = nees(reference, estimate, &pairs, &similarity);
    let stamp = |k: &usize| reference.stamps().get(*k).copied().unwrap_or(f64::NAN);
    let first = pairs.reference.first().map_or(f64::NAN, stamp);
    let last = pairs.reference.last().map_or(f64::NAN, stamp);
    let coverage = match reference.span() {
        Some((a, b)) if b > a => ((last - first) / (b - a)).clamp(0.0, 1.0),
        _ => 1.0,
    };
    let mut notices = Vec::new();
    if coverage < 0.95 {
        notices.push(format!(
            "the estimate covers {:.1} % of the reference's time ({first:.3} to {last:.3} s of {}): evaluated over that overlap",
            100.0 * coverage,
            reference
                .span()
                .map_or(String::new(), |(a, b)| format!("{a:.3} to {b:.3} s")),
        ));
    }
    let unpaired = pairs.estimate_poses.saturating_sub(pairs.len());
    if unpaired > 0 && pairs.estimate_poses <= pairs.reference_poses {
        notices.push(format!(
            "{unpaired} of the estimate's {} poses have no reference pose within {} s and are left out",
            pairs.estimate_poses, settings.max_diff
        ));
    }
    Ok(Evaluation {
        settings: *settings,
        pairing: PairingReport {
            pairs: pairs.len(),
            estimate_poses: pairs.estimate_poses,
            reference_poses: pairs.reference_poses,
            max_diff_s: settings.max_diff,
            offset_s: settings.offset,
            overlap_s: (first, last),
            coverage,
        },
        alignment: AlignmentReport {
            kind: settings.alignment.name(),
            rotation_deg: similarity.rotation.to_degrees(),
            translation_m: similarity.translation,
            scale: similarity.scale,
        },
        ape,
        rpe,
        rpe_refused,
        nees,
        notices,
        association: pairs,
        similarity,
    })
}
