//! Two-view geometry against hand-made scenes with known motion.

use nalgebra::{Matrix3, Rotation3, Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::decompose::choose_by_cheirality;
use super::ransac::adaptive_bound;
use super::*;
use crate::random::standard_normal;

fn camera() -> Intrinsics {
    Intrinsics::from_fov(640.0, 480.0, 60.0)
}

/// A scene: points in front of the left camera, a motion and the matches.
struct Scene {
    points: Vec<Vector3<f64>>,
    matches: Vec<Correspondence>,
    outlier: Vec<bool>,
}

fn essential_of(pose: &RelativePose) -> Matrix3<f64> {
    let e = skew(&pose.translation) * pose.rotation;
    e / e.norm()
}

fn random_pose(rng: &mut ChaCha8Rng, rotation_deg: f64, baseline: f64) -> RelativePose {
    let axis = Vector3::new(
        standard_normal(rng),
        standard_normal(rng),
        standard_normal(rng),
    );
    let angle = rotation_deg.to_radians() * rng.random_range(0.3..1.0);
    let rotation = *Rotation3::from_scaled_axis(axis.normalize() * angle).matrix();
    let direction = Vector3::new(
        standard_normal(rng),
        standard_normal(rng) * 0.3,
        standard_normal(rng),
    );
    RelativePose {
        rotation,
        translation: direction.normalize() * baseline,
    }
}

/// Points seen by both cameras, with pixel noise (std `noise_px`) and a share
/// of matches replaced by random pixels.
fn scene(
    rng: &mut ChaCha8Rng,
    pose: RelativePose,
    count: usize,
    noise_px: f64,
    outlier_share: f64,
    planar: bool,
) -> Scene {
    let k = camera();
    let mut points = Vec::new();
    let mut matches = Vec::new();
    let mut outlier = Vec::new();
    let mut attempts = 0;
    while matches.len() < count && attempts < 100 * count {
        attempts += 1;
        let z = rng.random_range(4.0..12.0);
        let p = if planar {
            Vector3::new(
                rng.random_range(-4.0..4.0),
                rng.random_range(-3.0..3.0),
                8.0,
            )
        } else {
            Vector3::new(
                rng.random_range(-0.6..0.6) * z,
                rng.random_range(-0.45..0.45) * z,
                z,
            )
        };
        let q = pose.rotation * p + pose.translation;
        let (Some(a), Some(b)) = (k.project(&p), k.project(&q)) else {
            continue;
        };
        if !k.contains(&a) || !k.contains(&b) {
            continue;
        }
        let noisy = |v: Vector2<f64>, rng: &mut ChaCha8Rng| {
            v + Vector2::new(standard_normal(rng), standard_normal(rng)) * noise_px
        };
        let left = noisy(a, rng);
        let is_outlier = rng.random::<f64>() < outlier_share;
        let right = if is_outlier {
            Vector2::new(rng.random_range(0.0..640.0), rng.random_range(0.0..480.0))
        } else {
            noisy(b, rng)
        };
        points.push(p);
        matches.push(Correspondence::new(left, right));
        outlier.push(is_outlier);
    }
    Scene {
        points,
        matches,
        outlier,
    }
}

fn sign_free_distance(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    let a = a / a.norm();
    let b = b / b.norm();
    (a - b).norm().min((a + b).norm())
}

fn cubic_residual(e: &Matrix3<f64>) -> f64 {
    let eet = e * e.transpose();
    (eet * e - e * (0.5 * eet.trace())).norm()
}

fn rotation_error_deg(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    rotation_angle(&(a.transpose() * b)).to_degrees()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn eight_point_is_exact_on_noise_free_matches() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let k = camera();
    for _ in 0..10 {
        let pose = random_pose(&mut rng, 15.0, 1.0);
        let s = scene(&mut rng, pose, 30, 0.0, 0.0, false);
        for normalize in [true, false] {
            let e = essential_eight_point(&s.matches, &k, normalize).unwrap();
            // Unnormalized, A mixes pixels² with 1 and the residual is ~1e-9.
            let tolerance = if normalize { 1e-10 } else { 1e-8 };
            for m in &s.matches {
                let (l, r) = (k.normalize(&m.left), k.normalize(&m.right));
                let residual = r.dot(&(e * l)).abs();
                assert!(residual < tolerance, "normalize {normalize}: {residual}");
            }
            assert!(
                cubic_residual(&e) < 1e-9,
                "cubic constraint {}",
                cubic_residual(&e)
            );
            assert!(sign_free_distance(&e, &essential_of(&pose)) < 1e-7);
        }
    }
}

#[test]
fn five_point_returns_the_true_essential_matrix_among_its_candidates() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let k = camera();
    let mut counts = Vec::new();
    for _ in 0..50 {
        let pose = random_pose(&mut rng, 20.0, 1.0);
        let s = scene(&mut rng, pose, 5, 0.0, 0.0, false);
        let left: [Vector3<f64>; 5] = std::array::from_fn(|i| k.normalize(&s.matches[i].left));
        let right: [Vector3<f64>; 5] = std::array::from_fn(|i| k.normalize(&s.matches[i].right));
        let candidates = essential_five_point(&left, &right);
        assert!(!candidates.is_empty() && candidates.len() <= 10);
        counts.push(candidates.len());
        let truth = essential_of(&pose);
        let nearest = candidates
            .iter()
            .map(|e| sign_free_distance(e, &truth))
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest < 1e-6,
            "nearest candidate is {nearest} from the truth"
        );
        for e in &candidates {
            // Every candidate is an essential matrix through the five matches.
            assert!(cubic_residual(e) < 1e-8, "cubic {}", cubic_residual(e));
            assert!(e.determinant().abs() < 1e-8);
            for i in 0..5 {
                assert!(right[i].dot(&(e * left[i])).abs() < 1e-8);
            }
        }
    }
    // Real solutions come in even numbers minus complex pairs: 10 − 2k is even.
    assert!(counts.iter().all(|c| c % 2 == 0), "{counts:?}");
}

#[test]
fn five_point_works_on_a_planar_scene_where_eight_point_is_degenerate() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let k = camera();
    let pose = random_pose(&mut rng, 10.0, 1.0);
    let s = scene(&mut rng, pose, 20, 0.0, 0.0, true);
    let err = essential_eight_point(&s.matches, &k, true).unwrap_err();
    assert!(matches!(err, VisionError::Degenerate(_)), "{err}");
    let left: [Vector3<f64>; 5] = std::array::from_fn(|i| k.normalize(&s.matches[i].left));
    let right: [Vector3<f64>; 5] = std::array::from_fn(|i| k.normalize(&s.matches[i].right));
    let nearest = essential_five_point(&left, &right)
        .iter()
        .map(|e| sign_free_distance(e, &essential_of(&pose)))
        .fold(f64::INFINITY, f64::min);
    assert!(nearest < 1e-6, "{nearest}");
}

#[test]
fn decomposition_recovers_rotation_and_translation_direction() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let k = camera();
    for _ in 0..20 {
        let pose = random_pose(&mut rng, 30.0, 2.0);
        let s = scene(&mut rng, pose, 40, 0.0, 0.0, false);
        let left: Vec<_> = s.matches.iter().map(|m| k.normalize(&m.left)).collect();
        let right: Vec<_> = s.matches.iter().map(|m| k.normalize(&m.right)).collect();
        let d = choose_by_cheirality(&essential_of(&pose), &left, &right).unwrap();
        let chosen = d.pose();
        assert!((chosen.rotation - pose.rotation).amax() < 1e-9);
        assert!((chosen.translation - pose.translation.normalize()).amax() < 1e-9);
        // All points in front for the right candidate, fewer for the others.
        assert_eq!(d.in_front[d.best], s.points.len());
        assert!(
            d.in_front.iter().filter(|&&c| c == s.points.len()).count() == 1,
            "{:?}",
            d.in_front
        );
        // Singular values (s, s, 0).
        let sv = d.singular_values;
        assert!((sv[0] - sv[1]).abs() < 1e-12 && sv[2].abs() < 1e-12);
        // The triangulated point is the scene point.
        let (p, _, _) = triangulate_midpoint(&chosen, &left[0], &right[0]).unwrap();
        let scale = pose.translation.norm();
        assert!((p * scale - s.points[0]).norm() < 1e-9 * s.points[0].norm());
    }
}

#[test]
fn normalization_lowers_the_eight_point_error_with_one_pixel_noise() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let k = camera();
    let (mut normalized, mut raw) = (Vec::new(), Vec::new());
    for _ in 0..40 {
        let pose = random_pose(&mut rng, 10.0, 1.0);
        let s = scene(&mut rng, pose, 100, 1.0, 0.0, false);
        let left: Vec<_> = s.matches.iter().map(|m| k.normalize(&m.left)).collect();
        let right: Vec<_> = s.matches.iter().map(|m| k.normalize(&m.right)).collect();
        for (normalize, errors) in [(true, &mut normalized), (false, &mut raw)] {
            let e = essential_eight_point(&s.matches, &k, normalize).unwrap();
            let r = choose_by_cheirality(&e, &left, &right)
                .unwrap()
                .pose()
                .rotation;
            errors.push(rotation_error_deg(&r, &pose.rotation));
        }
    }
    let (n, r) = (median(normalized), median(raw));
    eprintln!("median rotation error: normalized {n:.4} deg, unnormalized {r:.4} deg");
    assert!(n < r, "normalized {n} deg, unnormalized {r} deg");
    assert!(n < 0.5, "{n}");
}

#[test]
fn adaptive_bound_matches_the_formula() {
    // w = 0.5, s = 5, p = 0.99: log(0.01) / log(1 − 1/32) = 145.05 → 146.
    assert_eq!(adaptive_bound(0.5, 5, 0.99, 10_000), 146);
    // s = 8: log(0.01) / log(1 − 1/256) = 1176.6 → 1177.
    assert_eq!(adaptive_bound(0.5, 8, 0.99, 10_000), 1177);
    assert_eq!(adaptive_bound(0.0, 5, 0.99, 500), 500);
    assert_eq!(adaptive_bound(1.0, 5, 0.99, 500), 1);
    assert_eq!(adaptive_bound(f64::NAN, 5, 0.99, 500), 500);
}

/// Seeded trials of RANSAC on 200 matches, half of them wrong, 1 px noise:
/// `(rotation errors in degrees, translation-direction errors in degrees,
/// runs that ended at their adaptive bound, true outliers kept, inliers kept)`.
fn ransac_trials(
    method: Method,
    trials: usize,
    seed: u64,
) -> (Vec<f64>, Vec<f64>, usize, usize, usize) {
    let (rotation, translation, within_bound, kept_outliers, kept, _) =
        ransac_trials_with(method, EarlyRejection::None, true, trials, seed);
    (rotation, translation, within_bound, kept_outliers, kept)
}

/// [`ransac_trials`] with a choice of early rejection and of the nonlinear
/// refinement; also the SPRT's counts summed over the trials and the samples
/// drawn.
fn ransac_trials_with(
    method: Method,
    early_rejection: EarlyRejection,
    refine: bool,
    trials: usize,
    seed: u64,
) -> (Vec<f64>, Vec<f64>, usize, usize, usize, (SprtStats, usize)) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let k = camera();
    let (mut rotation_errors, mut translation_errors) = (Vec::new(), Vec::new());
    let (mut within_bound, mut kept_outliers, mut kept) = (0, 0, 0);
    let (mut sprt, mut samples) = (SprtStats::default(), 0);
    for _ in 0..trials {
        let pose = random_pose(&mut rng, 10.0, 2.0);
        let s = scene(&mut rng, pose, 200, 1.0, 0.5, false);
        let config = RansacConfig {
            method,
            max_iterations: 5000,
            early_rejection,
            refine,
            ..RansacConfig::default()
        };
        let mut ransac = Ransac::new(&s.matches, &k, config).unwrap();
        ransac.run(&mut rng);
        let estimate = ransac.finish().unwrap();
        // Stopped by the adaptive bound, not by the cap.
        if estimate.iterations < config.max_iterations {
            within_bound += 1;
        }
        let t = estimate.translation.unwrap_or_else(Vector3::zeros);
        rotation_errors.push(rotation_error_deg(&estimate.rotation, &pose.rotation));
        translation_errors.push(angle_between(&t, &pose.translation).to_degrees());
        kept_outliers += estimate
            .inliers
            .iter()
            .zip(&s.outlier)
            .filter(|(i, o)| **i && **o)
            .count();
        kept += estimate.inlier_count;
        samples += estimate.iterations;
        if let Some(stats) = estimate.sprt {
            sprt.tested += stats.tested;
            sprt.rejected += stats.rejected;
            sprt.evaluated += stats.evaluated;
            sprt.evaluated_in_rejected += stats.evaluated_in_rejected;
            sprt.designs += stats.designs;
        }
    }
    (
        rotation_errors,
        translation_errors,
        within_bound,
        kept_outliers,
        kept,
        (sprt, samples),
    )
}

fn share_below(values: &[f64], limit: f64) -> usize {
    values.iter().filter(|v| **v < limit).count()
}

/// Prints what [`ransac_trials`] measured, in the words the docs quote.
fn print_trials(
    name: &str,
    rotation: &[f64],
    translation: &[f64],
    within_bound: usize,
    (kept_outliers, kept): (usize, usize),
) {
    eprintln!(
        "{name}: rotation median {:.3} deg, {} of 100 below 1 deg; translation median {:.3} deg; {} within bound; {kept_outliers} outliers in {kept} inliers",
        median(rotation.to_vec()),
        share_below(rotation, 1.0),
        median(translation.to_vec()),
        within_bound
    );
}

/// The specification's bound: 99 % of the trials end within 1° of the true
/// rotation.
fn assert_99_of_100_within_one_degree(rotation: &[f64]) {
    let within = share_below(rotation, 1.0);
    assert!(within >= 99, "{within}");
}

/// The specification's accuracy test: RANSAC with half the matches wrong
/// ends within 1° of the true rotation in at least 99 % of seeded trials,
/// within its adaptive bound. Five-point with the nonlinear refinement (the
/// default): 100 of 100 on seed 21, all stopped by the bound.
#[test]
fn five_point_ransac_survives_half_outliers() {
    let (rotation, translation, within_bound, kept_outliers, kept) =
        ransac_trials(Method::FivePoint, 100, 21);
    print_trials(
        "five-point",
        &rotation,
        &translation,
        within_bound,
        (kept_outliers, kept),
    );
    // Measured (seed 21): rotation median 0.186 deg, 100 of 100 below 1 deg,
    // translation median 0.459 deg, every run stopped by its adaptive bound,
    // 199 wrong matches among 9798 inliers. Over 1,000 trials (seeds
    // 100-109) 996 (docs/visual-odometry.md).
    assert_99_of_100_within_one_degree(&rotation);
    assert_eq!(share_below(&rotation, 3.0), 100);
    assert!(median(rotation) < 0.3);
    assert!(median(translation) < 0.7);
    assert_eq!(within_bound, 100);
    assert!(kept_outliers * 33 < kept, "{kept_outliers} of {kept}");
}

/// The same for the eight-point method: 100 of 100 on seed 22, 996 of 1,000
/// over seeds 100-109 ([`thousand_trials_within_one_degree`],
/// docs/visual-odometry.md). Before its local optimization ended on the
/// essential constraint, and was triggered by the best sample hypothesis
/// rather than the best model, 99 of 100 and 985 of 1,000: the misses were
/// mostly runs that reached the 5,000-sample cap with half the right matches
/// as their consensus.
#[test]
fn eight_point_ransac_survives_half_outliers() {
    let (rotation, translation, within_bound, kept_outliers, kept) =
        ransac_trials(Method::EightPoint, 100, 22);
    print_trials(
        "eight-point",
        &rotation,
        &translation,
        within_bound,
        (kept_outliers, kept),
    );
    // Measured (seed 22): rotation median 0.236 deg, 100 of 100 below 1 deg,
    // translation median 0.542 deg, 97 of 100 runs stopped by the bound (with
    // s = 8 and w ≈ 0.45 the bound log(0.01)/log(1 − w⁸) is in the thousands:
    // a run with few right matches reaches the 5000 cap), 206 wrong matches
    // among 9720 inliers. Before the local optimization on the essential
    // constraint: 0.244 deg, 99 of 100, 0.559 deg, 90 by the bound.
    assert_99_of_100_within_one_degree(&rotation);
    assert!(median(rotation) < 0.3);
    assert!(median(translation) < 0.7);
    // 85 of 100 when local optimization stopped after three refits, 90 with
    // the eight-point refits alone.
    assert!(within_bound >= 95, "{within_bound}");
    assert!(kept_outliers * 33 < kept, "{kept_outliers} of {kept}");
}

/// The nonlinear refinement is what lifts the share within 1°: the same
/// seeded trials without it (the linear refits alone) end within 1° in 84
/// (five-point) and 99 (eight-point) of 100, with it in 100 and 100; the
/// medians of the rotation and translation errors fall as well. (The
/// eight-point method also refines inside its local optimization when the
/// refinement is on; over 1,000 trials 973 without, 996 with.)
#[test]
fn refinement_lifts_the_share_within_one_degree() {
    for (method, seed, without, with) in [
        (Method::FivePoint, 21, 84, 100),
        (Method::EightPoint, 22, 99, 100),
    ] {
        let (linear, linear_t, ..) =
            ransac_trials_with(method, EarlyRejection::None, false, 100, seed);
        let (refined, refined_t, ..) =
            ransac_trials_with(method, EarlyRejection::None, true, 100, seed);
        eprintln!(
            "{}: without refinement {} of 100 below 1 deg (medians {:.3} deg, t {:.3} deg); with {} ({:.3} deg, t {:.3} deg)",
            method.name(),
            share_below(&linear, 1.0),
            median(linear.clone()),
            median(linear_t.clone()),
            share_below(&refined, 1.0),
            median(refined.clone()),
            median(refined_t.clone()),
        );
        assert_eq!(share_below(&linear, 1.0), without);
        assert_eq!(share_below(&refined, 1.0), with);
        assert!(median(refined) < median(linear));
        assert!(median(refined_t) < median(linear_t));
    }
}

#[test]
fn pure_rotation_is_reported_without_a_translation() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let k = camera();
    for method in [Method::FivePoint, Method::EightPoint] {
        let config = RansacConfig {
            method,
            ..RansacConfig::default()
        };
        let estimate = |s: &Scene, rng: &mut ChaCha8Rng| {
            estimate_two_view(&s.matches, &k, config, rng).unwrap()
        };
        for _ in 0..10 {
            let mut pose = random_pose(&mut rng, 10.0, 1.0);
            pose.translation = Vector3::zeros();
            let s = scene(&mut rng, pose, 150, 1.0, 0.2, false);
            let estimate = estimate(&s, &mut rng);
            assert_eq!(
                estimate.motion,
                Motion::PureRotation,
                "parallax {}",
                estimate.parallax_px
            );
            assert!(estimate.translation.is_none());
            assert!(rotation_error_deg(&estimate.rotation, &pose.rotation) < 0.2);
        }
        // The same scene with a 1 m baseline is general motion.
        let pose = random_pose(&mut rng, 10.0, 1.0);
        let s = scene(&mut rng, pose, 150, 1.0, 0.2, false);
        let estimate = estimate(&s, &mut rng);
        assert_eq!(
            estimate.motion,
            Motion::General,
            "parallax {}",
            estimate.parallax_px
        );
    }
}

#[test]
fn bad_input_gets_a_typed_error() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let k = camera();
    let pose = random_pose(&mut rng, 10.0, 1.0);
    let s = scene(&mut rng, pose, 40, 0.0, 0.0, false);
    let config = RansacConfig {
        method: Method::EightPoint,
        ..RansacConfig::default()
    };
    assert!(matches!(
        Ransac::new(&s.matches[..7], &k, config).unwrap_err(),
        VisionError::TooFewMatches {
            needed: 8,
            got: 7,
            ..
        }
    ));
    let five = RansacConfig {
        method: Method::FivePoint,
        ..config
    };
    assert!(matches!(
        Ransac::new(&s.matches[..4], &k, five).unwrap_err(),
        VisionError::TooFewMatches {
            needed: 5,
            got: 4,
            ..
        }
    ));
    let mut bad = s.matches.clone();
    bad[3].right.x = f64::NAN;
    assert_eq!(
        Ransac::new(&bad, &k, config).unwrap_err(),
        VisionError::NonFinite { index: 3 }
    );
    assert!(fundamental_eight_point(&bad, true).is_err());
    let zero_focal = Intrinsics { fx: 0.0, ..k };
    assert!(matches!(
        Ransac::new(&s.matches, &zero_focal, config).unwrap_err(),
        VisionError::BadIntrinsics(_)
    ));
    // Every match wrong: no consensus, not a confident answer.
    let random: Vec<Correspondence> = (0..200)
        .map(|_| {
            Correspondence::new(
                Vector2::new(rng.random_range(0.0..640.0), rng.random_range(0.0..480.0)),
                Vector2::new(rng.random_range(0.0..640.0), rng.random_range(0.0..480.0)),
            )
        })
        .collect();
    for method in [Method::EightPoint, Method::FivePoint] {
        let config = RansacConfig {
            method,
            max_iterations: 300,
            ..RansacConfig::default()
        };
        let err = estimate_two_view(&random, &k, config, &mut rng).unwrap_err();
        assert!(matches!(err, VisionError::NoConsensus { .. }), "{err}");
    }
}

#[test]
fn sampson_distance_is_the_pixel_distance_for_a_horizontal_epipolar_geometry() {
    // Pure sideways translation with K = I-like pixels: epipolar lines are the
    // rows, F ∝ [t]x with t = x, and the Sampson distance of a match off by d
    // pixels vertically is d / √2 (the error is split between both images).
    let f = skew(&Vector3::new(1.0, 0.0, 0.0));
    let m = Correspondence::new(Vector2::new(10.0, 20.0), Vector2::new(40.0, 23.0));
    assert!((sampson_squared(&f, &m) - 4.5).abs() < 1e-12);
    let line = epipolar_line(&f, &m.left).unwrap();
    // Line v = 20 in the right image: distance of (40, 23) is 3 pixels.
    assert!((line.dot(&Vector3::new(40.0, 23.0, 1.0)).abs() - 3.0).abs() < 1e-12);
}

/// A seeded scene (300 matches, half wrong) stepped to the end and run to the
/// end with the same seed, for each method: the same number of samples, bound
/// and best F, stopped by the bound. With the SPRT, every stepped report
/// carries the SPRT's verdict for each hypothesis, and the rejections the
/// reports show add up to the run's count.
fn assert_running_gives_what_stepping_gives(early_rejection: EarlyRejection) {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let k = camera();
    let pose = random_pose(&mut rng, 10.0, 2.0);
    let s = scene(&mut rng, pose, 300, 1.0, 0.5, false);
    for method in [Method::EightPoint, Method::FivePoint] {
        let config = RansacConfig {
            method,
            max_iterations: 5000,
            early_rejection,
            ..RansacConfig::default()
        };
        let mut stepped = Ransac::new(&s.matches, &k, config).unwrap();
        let mut rng_a = ChaCha8Rng::seed_from_u64(9);
        let mut rejected_in_reports = 0;
        while let Some(report) = stepped.step(&mut rng_a) {
            if early_rejection == EarlyRejection::Sprt {
                let sample = report.sprt.unwrap();
                assert_eq!(sample.checks.len(), report.hypotheses);
                rejected_in_reports += sample.checks.iter().filter(|c| c.rejected).count();
            }
        }
        let mut run = Ransac::new(&s.matches, &k, config).unwrap();
        let mut rng_b = ChaCha8Rng::seed_from_u64(9);
        run.run(&mut rng_b);
        assert_eq!(run.iteration(), stepped.iteration(), "{method:?}");
        assert_eq!(run.bound(), stepped.bound(), "{method:?}");
        assert_eq!(
            run.best_fundamental(),
            stepped.best_fundamental(),
            "{method:?}"
        );
        if early_rejection == EarlyRejection::Sprt {
            assert_eq!(rejected_in_reports, run.sprt().unwrap().stats().rejected);
        }
        assert!(run.iteration() < 5000, "{method:?} stopped by the cap");
    }
}

/// `run` stops counting a hypothesis's inliers once it cannot beat the best;
/// the best hypothesis, its inliers and the bound are those of stepping.
#[test]
fn running_gives_what_stepping_gives() {
    assert_running_gives_what_stepping_gives(EarlyRejection::None);
}

/// The SPRT keeps RANSAC's accuracy at half outliers: on the same seeded
/// trials as [`five_point_ransac_survives_half_outliers`] and
/// [`eight_point_ransac_survives_half_outliers`] as many runs end within 1°
/// (give or take a few), while a rejected hypothesis is checked against a
/// handful of the 200 matches.
#[test]
fn sprt_keeps_the_accuracy_and_checks_few_matches() {
    for (method, seed) in [(Method::FivePoint, 21), (Method::EightPoint, 22)] {
        let (plain, _, _, _, _, (_, plain_samples)) =
            ransac_trials_with(method, EarlyRejection::None, true, 100, seed);
        let (rotation, translation, within_bound, kept_outliers, kept, (stats, samples)) =
            ransac_trials_with(method, EarlyRejection::Sprt, true, 100, seed);
        eprintln!(
            "{} with SPRT: rotation median {:.3} deg, {} of 100 below 1 deg (without: {}); translation median {:.3} deg; {within_bound} within bound; {kept_outliers} outliers in {kept} inliers; {samples} samples (without: {plain_samples}); {} hypotheses, {} rejected after {:.2} matches on average, {:.2} matches per hypothesis, {} designs",
            method.name(),
            median(rotation.clone()),
            share_below(&rotation, 1.0),
            share_below(&plain, 1.0),
            median(translation.clone()),
            stats.tested,
            stats.rejected,
            stats.mean_evaluated_when_rejected(),
            stats.evaluated as f64 / stats.tested as f64,
            stats.designs,
        );
        assert!(
            share_below(&rotation, 1.0) + 3 >= share_below(&plain, 1.0),
            "{} against {}",
            share_below(&rotation, 1.0),
            share_below(&plain, 1.0)
        );
        assert!(median(rotation) < 0.5);
        assert!(median(translation) < 1.5);
        assert!(kept_outliers * 33 < kept, "{kept_outliers} of {kept}");
        assert!(stats.mean_evaluated_when_rejected() < 30.0);
        assert!(stats.rejected * 100 >= stats.tested * 90);
    }
}

/// A good hypothesis is rarely rejected: the final model of a seeded SPRT run
/// (219 of 500 matches agree) checked from every starting point of the
/// shuffled order with the run's last test, and the hypotheses of samples
/// drawn from the true inliers alone that agree with at least 80 % of them.
/// Matas and Chum's test rejects a good model with probability about `1/A`.
#[test]
fn sprt_rarely_rejects_a_good_model() {
    let k = camera();
    for (method, seed) in [(Method::EightPoint, 31), (Method::FivePoint, 32)] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let pose = random_pose(&mut rng, 10.0, 2.0);
        let s = scene(&mut rng, pose, 500, 1.0, 0.5, false);
        let config = RansacConfig {
            method,
            max_iterations: 5000,
            early_rejection: EarlyRejection::Sprt,
            ..RansacConfig::default()
        };
        let mut ransac = Ransac::new(&s.matches, &k, config).unwrap();
        ransac.run(&mut rng);
        let best = ransac.best_fundamental().unwrap();
        let sprt = ransac.sprt().unwrap().clone();
        let n = s.matches.len();
        let final_rejected = (0..n)
            .filter(|&start| ransac.sprt_check(&best, start).rejected)
            .count();
        // Hypotheses from samples of true inliers only.
        let inliers: Vec<usize> = (0..n).filter(|&i| !s.outlier[i]).collect();
        let (mut good, mut good_rejected) = (0, 0);
        let (mut any, mut any_rejected) = (0, 0);
        for _ in 0..1000 {
            let mut sample = Vec::new();
            while sample.len() < method.sample_size() {
                let i = inliers[rng.random_range(0..inliers.len())];
                if !sample.contains(&i) {
                    sample.push(i);
                }
            }
            for f in ransac.hypotheses(&sample) {
                let rejected = ransac.sprt_check(&f, rng.random_range(0..n)).rejected;
                any += 1;
                any_rejected += usize::from(rejected);
                if ransac.classify(&f).1 * 5 >= inliers.len() * 4 {
                    good += 1;
                    good_rejected += usize::from(rejected);
                }
            }
        }
        eprintln!(
            "{}: {} inliers of the best, eps {:.3}, delta {:.4}, A {:.1}; the best rejected from {final_rejected} of {n} starts; hypotheses of all-inlier samples rejected {any_rejected} of {any}, of those with 80 % of the inliers {good_rejected} of {good}",
            method.name(),
            ransac.best_inliers(),
            sprt.epsilon(),
            sprt.delta(),
            sprt.threshold()
        );
        assert!(final_rejected * 100 <= n, "{final_rejected} of {n}");
        assert!(good >= 50, "{good}");
        assert!(good_rejected * 20 <= good, "{good_rejected} of {good}");
    }
}

/// The threshold A solves `A = t_M C / m_S + 1 + ln A`; no test when ε ≤ δ.
#[test]
fn sprt_threshold_solves_its_equation() {
    let (epsilon, delta) = (0.44, 0.02);
    let a = sprt_threshold(epsilon, delta, 330.0, 1.0);
    let ln = crate::math::ln;
    let c = (1.0 - delta) * ln((1.0 - delta) / (1.0 - epsilon)) + delta * ln(delta / epsilon);
    assert!((a - (330.0 * c + 1.0 + ln(a))).abs() < 1e-6, "{a}");
    assert!(a > 150.0 && a < 250.0, "{a}");
    assert_eq!(sprt_threshold(0.05, 0.05, 330.0, 1.0), f64::INFINITY);
    assert_eq!(sprt_threshold(f64::NAN, 0.05, 330.0, 1.0), f64::INFINITY);
}

/// With the SPRT, stepping and running give the same run (the SPRT alone
/// decides when a hypothesis's check stops, in both).
#[test]
fn running_gives_what_stepping_gives_with_sprt() {
    assert_running_gives_what_stepping_gives(EarlyRejection::Sprt);
}

/// The 1,000-trial measurement of `docs/visual-odometry.md` ("The 99 %
/// accuracy criterion"): seeds 100-109, ten runs of 100 trials each of
/// [`ransac_trials_with`], for both methods, with and without the SPRT and
/// the refinement. Prints how many of the 1,000 runs end within 1° of the
/// true rotation, how many stopped by their bound, and the samples drawn.
/// Slow in a debug build: `cargo test --release -p slamlab-core --lib
/// thousand_trials -- --ignored --nocapture`.
#[test]
#[ignore = "the 1,000-trial measurement of docs/visual-odometry.md; minutes in a debug build"]
fn thousand_trials_within_one_degree() {
    for method in [Method::EightPoint, Method::FivePoint] {
        for early_rejection in [EarlyRejection::None, EarlyRejection::Sprt] {
            for refine in [false, true] {
                let (mut within, mut translation_within, mut bound, mut samples) = (0, 0, 0, 0);
                let mut misses = Vec::new();
                for seed in 100..110 {
                    let (rotation, translation, within_bound, _, _, (_, drawn)) =
                        ransac_trials_with(method, early_rejection, refine, 100, seed);
                    within += share_below(&rotation, 1.0);
                    translation_within += share_below(&translation, 1.0);
                    bound += within_bound;
                    samples += drawn;
                    misses.extend(rotation.iter().filter(|e| **e >= 1.0).copied());
                }
                misses.sort_by(f64::total_cmp);
                eprintln!(
                    "{} {} refine {refine}: {within} of 1000 within 1 deg (translation {translation_within}), {bound} stopped by the bound, {samples} samples; misses {:.2?}",
                    method.name(),
                    early_rejection.name(),
                    misses
                );
            }
        }
    }
}
