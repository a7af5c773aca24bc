//! `slamlab experiment two-view`: RANSAC with the eight-point and five-point
//! solvers on seeded random two-view scenes, by outlier share.

use nalgebra::{Rotation3, Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use slamlab_core::random::standard_normal;
use slamlab_core::vision::{
    Correspondence, EarlyRejection, Intrinsics, Method, RansacConfig, RelativePose, angle_between,
    estimate_two_view, rotation_angle,
};

/// What the experiment varies and fixes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TwoViewSettings {
    /// Solvers compared.
    pub methods: Vec<Method>,
    /// Outlier shares, 0 .. 1.
    pub outliers: Vec<f64>,
    /// Pixel noise, standard deviation, pixels.
    pub noise_px: f64,
    /// Matches per trial.
    pub points: usize,
    /// Trials per method and share; trial i uses seed + i.
    pub trials: usize,
    /// First seed.
    pub seed: u64,
    /// Hartley normalization in the eight-point solver.
    pub normalize: bool,
    /// Early rejection of hypotheses (none, or Matas and Chum's SPRT).
    #[serde(default)]
    pub early_rejection: EarlyRejection,
    /// Levenberg-Marquardt refinement of `(R, t)` after RANSAC.
    #[serde(default = "super::odometry::refine_by_default")]
    pub refine: bool,
}

/// Median and 90th percentile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Median.
    pub median: f64,
    /// 90th percentile.
    pub p90: f64,
}

/// A median alone.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Median {
    /// Median.
    pub median: f64,
}

/// One method at one outlier share.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TwoViewResult {
    /// "eight-point" or "five-point".
    pub method: String,
    /// Outlier share.
    pub outliers: f64,
    /// Rotation error, degrees.
    pub rotation_error_deg: Spread,
    /// Angle between estimated and true translation directions, degrees.
    pub translation_angle_error_deg: Spread,
    /// RANSAC samples drawn.
    pub ransac_iterations: Median,
    /// True inliers among the matches kept, summed over trials.
    pub inlier_precision: f64,
    /// Matches kept among the true inliers, summed over trials.
    pub inlier_recall: f64,
    /// Trials without an estimate (counted with 180 degree errors).
    pub failures: usize,
    /// With the SPRT: how early it rejected, over every trial.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sprt: Option<SprtSummary>,
}

/// The SPRT's counts summed over the trials of one method and share.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SprtSummary {
    /// Hypotheses tested.
    pub hypotheses: usize,
    /// Share of them rejected before the last match.
    pub rejected_share: f64,
    /// Mean matches checked by a rejected hypothesis.
    pub matches_checked_when_rejected: f64,
    /// Mean matches checked by a hypothesis (rejected or accepted).
    pub matches_checked_per_hypothesis: f64,
}

/// The experiment's output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TwoViewReport {
    /// The settings.
    pub settings: TwoViewSettings,
    /// The scene every trial draws from (documented with the results).
    pub scene: String,
    /// Per method and outlier share.
    pub results: Vec<TwoViewResult>,
}

/// The scene description printed with the results.
pub const SCENE: &str = "640x480 pinhole, 60 deg horizontal field of view; points at depths 4-12 m inside the left view; rotation up to 10 deg about a random axis; 2 m baseline in a random direction; wrong matches have a uniformly random right pixel; Sampson threshold 2 px, p = 0.99, at most 5000 samples";

fn percentile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let i = ((values.len() - 1) as f64 * q).round() as usize;
    values[i.min(values.len() - 1)]
}

/// One seeded scene: the motion, the matches and which are wrong.
pub fn random_two_view_scene(
    rng: &mut ChaCha8Rng,
    camera: &Intrinsics,
    points: usize,
    noise_px: f64,
    outliers: f64,
) -> (RelativePose, Vec<Correspondence>, Vec<bool>) {
    let axis = Vector3::new(
        standard_normal(rng),
        standard_normal(rng),
        standard_normal(rng),
    );
    let angle = 10f64.to_radians() * rng.random_range(0.3..1.0);
    let rotation = *Rotation3::from_scaled_axis(axis.normalize() * angle).matrix();
    let direction = Vector3::new(
        standard_normal(rng),
        0.3 * standard_normal(rng),
        standard_normal(rng),
    );
    let pose = RelativePose {
        rotation,
        translation: direction.normalize() * 2.0,
    };
    let mut matches = Vec::with_capacity(points);
    let mut wrong = Vec::with_capacity(points);
    let mut attempts = 0;
    while matches.len() < points && attempts < 100 * points {
        attempts += 1;
        let z = rng.random_range(4.0..12.0);
        let p = Vector3::new(
            rng.random_range(-0.6..0.6) * z,
            rng.random_range(-0.45..0.45) * z,
            z,
        );
        let q = rotation * p + pose.translation;
        let (Some(a), Some(b)) = (camera.project(&p), camera.project(&q)) else {
            continue;
        };
        if !camera.contains(&a) || !camera.contains(&b) {
            continue;
        }
        let mut noisy = |v: Vector2<f64>| {
            v + Vector2::new(standard_normal(rng), standard_normal(rng)) * noise_px
        };
        let left = noisy(a);
        let right_true = noisy(b);
        let is_wrong = rng.random::<f64>() < outliers;
        let right = if is_wrong {
            Vector2::new(
                rng.random_range(0.0..camera.width),
                rng.random_range(0.0..camera.height),
            )
        } else {
            right_true
        };
        matches.push(Correspondence::new(left, right));
        wrong.push(is_wrong);
    }
    (pose, matches, wrong)
}

/// Runs the experiment; `progress(done, total)` after each trial.
pub fn two_view_experiment(
    settings: &TwoViewSettings,
    mut progress: impl FnMut(usize, usize),
) -> TwoViewReport {
    let camera = Intrinsics::from_fov(640.0, 480.0, 60.0);
    let total = settings.methods.len() * settings.outliers.len() * settings.trials;
    let mut done = 0;
    let mut results = Vec::new();
    for &method in &settings.methods {
        for &share in &settings.outliers {
            let (mut rot, mut trans, mut iters) = (Vec::new(), Vec::new(), Vec::new());
            let (mut kept, mut kept_true, mut true_total, mut failures) =
                (0usize, 0usize, 0usize, 0usize);
            let (mut tested, mut rejected, mut checked, mut checked_rejected) =
                (0usize, 0usize, 0usize, 0usize);
            for trial in 0..settings.trials {
                let mut rng = ChaCha8Rng::seed_from_u64(settings.seed.wrapping_add(trial as u64));
                // The same scene for every method at this share.
                let (pose, matches, wrong) = random_two_view_scene(
                    &mut rng,
                    &camera,
                    settings.points,
                    settings.noise_px,
                    share,
                );
                true_total += wrong.iter().filter(|w| !**w).count();
                let config = RansacConfig {
                    method,
                    normalize: settings.normalize,
                    max_iterations: 5000,
                    early_rejection: settings.early_rejection,
                    refine: settings.refine,
                    ..RansacConfig::default()
                };
                match estimate_two_view(&matches, &camera, config, &mut rng) {
                    Ok(e) => {
                        if let Some(stats) = e.sprt {
                            tested += stats.tested;
                            rejected += stats.rejected;
                            checked += stats.evaluated;
                            checked_rejected += stats.evaluated_in_rejected;
                        }
                        rot.push(
                            rotation_angle(&(e.rotation.transpose() * pose.rotation)).to_degrees(),
                        );
                        let t = e.translation.unwrap_or_else(Vector3::zeros);
                        trans.push(angle_between(&t, &pose.translation).to_degrees());
                        iters.push(e.iterations as f64);
                        kept += e.inlier_count;
                        kept_true += e
                            .inliers
                            .iter()
                            .zip(&wrong)
                            .filter(|(i, w)| **i && !**w)
                            .count();
                    }
                    Err(_) => {
                        failures += 1;
                        rot.push(180.0);
                        trans.push(180.0);
                        iters.push(5000.0);
                    }
                }
                done += 1;
                progress(done, total);
            }
            results.push(TwoViewResult {
                method: method.name().to_owned(),
                outliers: share,
                rotation_error_deg: Spread {
                    median: percentile(&mut rot, 0.5),
                    p90: percentile(&mut rot, 0.9),
                },
                translation_angle_error_deg: Spread {
                    median: percentile(&mut trans, 0.5),
                    p90: percentile(&mut trans, 0.9),
                },
                ransac_iterations: Median {
                    median: percentile(&mut iters, 0.5),
                },
                inlier_precision: if kept > 0 {
                    kept_true as f64 / kept as f64
                } else {
                    0.0
                },
                inlier_recall: if true_total > 0 {
                    kept_true as f64 / true_total as f64
                } else {
                    0.0
                },
                failures,
                sprt: (settings.early_rejection == EarlyRejection::Sprt).then(|| SprtSummary {
                    hypotheses: tested,
                    rejected_share: rejected as f64 / tested.max(1) as f64,
                    matches_checked_when_rejected: checked_rejected as f64 / rejected.max(1) as f64,
                    matches_checked_per_hypothesis: checked as f64 / tested.max(1) as f64,
                }),
            });
        }
    }
    TwoViewReport {
        settings: settings.clone(),
        scene: SCENE.to_owned(),
        results,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn more_outliers_cost_more_iterations_and_five_point_needs_fewer() {
        let settings = TwoViewSettings {
            methods: vec![Method::EightPoint, Method::FivePoint],
            outliers: vec![0.0, 0.5],
            noise_px: 1.0,
            points: 200,
            trials: 10,
            seed: 1,
            normalize: true,
            early_rejection: EarlyRejection::None,
            refine: true,
        };
        let report = two_view_experiment(&settings, |_, _| {});
        let get = |m: &str, o: f64| {
            report
                .results
                .iter()
                .find(|r| r.method == m && r.outliers == o)
                .cloned()
                .unwrap()
        };
        for m in ["eight-point", "five-point"] {
            assert!(get(m, 0.5).ransac_iterations.median > get(m, 0.0).ransac_iterations.median);
            assert!(get(m, 0.5).inlier_precision > 0.95, "{:?}", get(m, 0.5));
            assert!(
                get(m, 0.0).rotation_error_deg.median < 1.0,
                "{:?}",
                get(m, 0.0)
            );
            assert_eq!(get(m, 0.5).failures, 0);
        }
        assert!(
            get("five-point", 0.5).ransac_iterations.median
                < get("eight-point", 0.5).ransac_iterations.median
        );
    }

    /// With the SPRT the same scenes give the same accuracy while a rejected
    /// hypothesis is checked against a few dozen of the 200 matches.
    #[test]
    fn the_sprt_reports_how_early_it_rejects() {
        let settings = TwoViewSettings {
            methods: vec![Method::EightPoint, Method::FivePoint],
            outliers: vec![0.5],
            noise_px: 1.0,
            points: 200,
            trials: 10,
            seed: 1,
            normalize: true,
            early_rejection: EarlyRejection::Sprt,
            refine: true,
        };
        let report = two_view_experiment(&settings, |_, _| {});
        for r in &report.results {
            let sprt = r.sprt.unwrap();
            eprintln!(
                "{}: {sprt:?}, rotation {:?}",
                r.method, r.rotation_error_deg
            );
            assert_eq!(r.failures, 0);
            assert!(r.rotation_error_deg.median < 1.0, "{r:?}");
            assert!(sprt.rejected_share > 0.9, "{sprt:?}");
            assert!(sprt.matches_checked_when_rejected < 30.0, "{sprt:?}");
        }
        let plain = two_view_experiment(
            &TwoViewSettings {
                early_rejection: EarlyRejection::None,
                ..settings
            },
            |_, _| {},
        );
        assert!(plain.results.iter().all(|r| r.sprt.is_none()));
    }
}
