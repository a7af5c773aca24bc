use super::*;
use slamlab_core::Pose2;

/// A curvy reference path and a copy of it moved, turned and distorted.
fn pair(n: usize) -> (Trajectory, Trajectory) {
    let stamps: Vec<f64> = (0..n).map(|k| k as f64 * 0.1).collect();
    let truth: Vec<Pose2> = (0..n)
        .map(|k| {
            let t = k as f64 * 0.1;
            Pose2::new(3.0 * math::cos(0.2 * t), 2.0 * math::sin(0.3 * t), 0.25 * t)
        })
        .collect();
    let frame = Similarity {
        rotation: -0.8,
        translation: [10.0, -4.0],
        scale: 1.0,
    };
    let est: Vec<Pose2> = truth
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let wobble = 0.05 * math::sin(k as f64);
            frame.apply(&Pose2::new(
                p.x + wobble,
                p.y - 0.5 * wobble,
                p.theta + 0.1 * wobble,
            ))
        })
        .collect();
    (
        Trajectory::new(stamps.clone(), truth),
        Trajectory::new(stamps, est),
    )
}

#[test]
fn statistics_are_evos() {
    let s = ErrorStats::of(&[3.0, 1.0, 4.0, 1.0, 5.0, 9.0]).unwrap();
    assert_eq!(s.count, 6);
    assert_eq!(s.sse, 133.0);
    assert_eq!(s.rmse, (133.0_f64 / 6.0).sqrt());
    assert_eq!(s.mean, 23.0 / 6.0);
    assert_eq!(s.median, 3.5);
    assert_eq!((s.min, s.max), (1.0, 9.0));
    // numpy.std (population): sqrt(mean((e - mean)^2)).
    let var = [3.0, 1.0, 4.0, 1.0, 5.0, 9.0]
        .iter()
        .map(|e: &f64| (e - 23.0 / 6.0).powi(2))
        .sum::<f64>()
        / 6.0;
    assert!((s.std - var.sqrt()).abs() < 1e-15);
    assert_eq!(ErrorStats::of(&[2.0, 7.0, 1.0]).unwrap().median, 2.0);
    assert!(ErrorStats::of(&[]).is_none());
}

#[test]
fn alignment_removes_the_frame_and_leaves_the_wobble() {
    let (truth, est) = pair(300);
    let settings = EvaluationSettings::default();
    let aligned = evaluate(&truth, &est, &settings).unwrap();
    assert_eq!(aligned.pairing.pairs, 300);
    assert!((aligned.alignment.rotation_deg - 0.8_f64.to_degrees()).abs() < 0.5);
    // The wobble is at most 0.056 m: after alignment the error is of that size.
    assert!(
        aligned.ape.translation.max < 0.07,
        "{:?}",
        aligned.ape.translation
    );
    assert!(aligned.ape.translation.rmse > 0.02);
    let raw = evaluate(
        &truth,
        &est,
        &EvaluationSettings {
            alignment: Alignment::None,
            ..settings
        },
    )
    .unwrap();
    assert!(raw.ape.translation.rmse > 5.0);
    // Relative errors do not see a rigid frame change: the same with and without.
    let (a, b) = (aligned.rpe.unwrap(), raw.rpe.unwrap());
    for (x, y) in a.translation_m.iter().zip(&b.translation_m) {
        assert!((x - y).abs() < 1e-12);
    }
    for (x, y) in a.rotation_deg.iter().zip(&b.rotation_deg) {
        assert!((x - y).abs() < 1e-9);
    }
}

#[test]
fn relative_errors_of_a_known_drift() {
    // The reference drives straight at 1 m a step; the estimate's steps are
    // 1.1 m and each turns 0.01 rad too much: every relative error of one step
    // is the same pose, (0.1 m, 0.01 rad) in the step's frame.
    let n = 50;
    let stamps: Vec<f64> = (0..n).map(f64::from).collect();
    let truth: Vec<Pose2> = (0..n).map(|k| Pose2::new(f64::from(k), 0.0, 0.0)).collect();
    let mut est = vec![Pose2::IDENTITY];
    for _ in 1..n {
        let last = *est.last().unwrap();
        est.push(last.compose(&Pose2::new(1.1, 0.0, 0.01)));
    }
    let (truth, est) = (
        Trajectory::new(stamps.clone(), truth),
        Trajectory::new(stamps, est),
    );
    let pairs = associate(&truth, &est, 0.01, 0.0).unwrap();
    let (errors, ids) = relative_errors(
        &truth,
        &est,
        &pairs,
        &Similarity::IDENTITY,
        &RelativeDelta::default(),
    )
    .unwrap();
    assert_eq!(ids.len(), 49);
    assert!(errors.translation_m.iter().all(|e| (e - 0.1).abs() < 1e-12));
    assert!(
        errors
            .rotation_deg
            .iter()
            .all(|e| (e - 0.01_f64.to_degrees()).abs() < 1e-9)
    );
    // Ten frames apart, consecutive pairs: (0,10), (10,20), ... (30,40).
    let ten = RelativeDelta {
        delta: 10.0,
        ..RelativeDelta::default()
    };
    let (_, ids) = relative_errors(&truth, &est, &pairs, &Similarity::IDENTITY, &ten).unwrap();
    assert_eq!(ids, vec![(0, 10), (10, 20), (20, 30), (30, 40)]);
    let all = RelativeDelta {
        all_pairs: true,
        ..ten
    };
    let (_, ids) = relative_errors(&truth, &est, &pairs, &Similarity::IDENTITY, &all).unwrap();
    assert_eq!(ids.len(), 40);
    // Metres along the estimate (1.1 m steps): 5 m are reached after 5 steps.
    let metres = RelativeDelta {
        delta: 5.0,
        unit: DeltaUnit::Meters,
        all_pairs: false,
    };
    let ids = delta_pairs(est.poses(), &metres).unwrap();
    assert_eq!(&ids[..3], &[(0, 5), (5, 10), (10, 15)]);
    assert!(
        delta_pairs(
            est.poses(),
            &RelativeDelta {
                delta: 500.0,
                ..metres
            }
        )
        .is_err()
    );
    assert!(
        delta_pairs(
            est.poses(),
            &RelativeDelta {
                delta: 1.5,
                ..RelativeDelta::default()
            }
        )
        .is_err()
    );
}

#[test]
fn a_partial_estimate_is_evaluated_over_the_overlap_and_says_so() {
    let (truth, est) = pair(300);
    let tenth = Trajectory::new(
        est.stamps()[100..130].to_vec(),
        est.poses()[100..130].to_vec(),
    );
    let e = evaluate(&truth, &tenth, &EvaluationSettings::default()).unwrap();
    assert_eq!(e.pairing.pairs, 30);
    assert!(
        (e.pairing.coverage - 2.9 / 29.9).abs() < 1e-9,
        "{}",
        e.pairing.coverage
    );
    assert_eq!(e.pairing.overlap_s, (10.0, 12.9));
    assert!(
        e.notices[0].starts_with("the estimate covers 9.7 % of the reference's time"),
        "{:?}",
        e.notices
    );
    let elsewhere = Trajectory::new(vec![100.0, 101.0], vec![Pose2::IDENTITY; 2]);
    let err = evaluate(&truth, &elsewhere, &EvaluationSettings::default()).unwrap_err();
    assert!(
        err.to_string()
            .contains("no pose of the estimate (100 to 101 s)"),
        "{err}"
    );
}

#[test]
fn scale_is_recovered_with_sim2_only() {
    let (truth, est) = pair(200);
    let small = Trajectory::new(
        est.stamps().to_vec(),
        est.poses()
            .iter()
            .map(|p| Pose2::new(0.5 * p.x, 0.5 * p.y, p.theta))
            .collect(),
    );
    let sim = evaluate(
        &truth,
        &small,
        &EvaluationSettings {
            alignment: Alignment::Sim2,
            ..EvaluationSettings::default()
        },
    )
    .unwrap();
    assert!(
        (sim.alignment.scale - 2.0).abs() < 0.01,
        "{}",
        sim.alignment.scale
    );
    assert!(sim.ape.translation.rmse < 0.05);
    let rigid = evaluate(&truth, &small, &EvaluationSettings::default()).unwrap();
    assert!(rigid.ape.translation.rmse > 0.5);
}

#[test]
fn landmark_and_relative_pose_errors() {
    let align = Similarity {
        rotation: std::f64::consts::FRAC_PI_2,
        translation: [1.0, 0.0],
        scale: 1.0,
    };
    let est = [(1, [1.0, 0.0]), (2, [0.0, 2.0]), (9, [5.0, 5.0])];
    let truth = [(1, [1.0, 1.0]), (2, [-1.0, 0.5])];
    let errors = landmark_errors(&est, &truth, &align);
    assert_eq!(errors.len(), 2);
    assert!(errors[0].error_m < 1e-12);
    assert!((errors[1].error_m - 0.5).abs() < 1e-12);
    let r = nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::z_axis(), 0.1).into_inner();
    let e = relative_pose_error(
        &r,
        &nalgebra::Vector3::new(1.0, 1.0, 0.0),
        &Matrix3::identity(),
        &nalgebra::Vector3::new(2.0, 0.0, 0.0),
    )
    .unwrap();
    assert!((e.rotation_deg - 0.1_f64.to_degrees()).abs() < 1e-9);
    assert!((e.translation_direction_deg - 45.0).abs() < 1e-9);
}
