use super::*;
use slamlab_core::kalman::fusion::{FusionError, Outcome};
use slamlab_core::stats::chi2_band_95;

/// A drive whose velocities are random walks with exactly the filter's process
/// noise, and sensors with exactly the noise they report (no scale error, slip
/// or gyro bias): the filter's models match the simulator.
fn matched(seed: u64, q: f64) -> FusionScenario {
    FusionScenario {
        seed,
        drive: DriveParams {
            kind: DriveKind::RandomWalk {
                speed_density: q,
                turn_density: q,
            },
            duration: 60.0,
            ..Default::default()
        },
        odometry: OdometryParams {
            scale_error_std: 0.0,
            turn_slip: 0.0,
            ..Default::default()
        },
        imu: ImuParams {
            gyro_bias_std: 0.0,
            gyro_bias_walk: 0.0,
            ..Default::default()
        },
        slam: SlamParams {
            enabled: false,
            ..Default::default()
        },
        process_noise: [0.0, 0.0, 0.0, q, 0.0, q, 0.0, 0.0],
        // The start is known exactly; robot_localization's default 1e-9 (σ = 3e-5 m)
        // would be larger than the cross-track error of a slow drive.
        initial_variance: 1e-16,
        ..Default::default()
    }
}

/// The pose NEES averaged over `runs` seeded runs at each output time, then
/// over the times after 5 s; and the fraction of those times inside the band.
fn average_nees(runs: u64, q: f64) -> (f64, f64, (f64, f64)) {
    let mut sums: Vec<f64> = Vec::new();
    for seed in 0..runs {
        let s = matched(100 + seed, q);
        let log = simulate(&s).unwrap();
        let run = &run_modes(&s, &log, &[FusionMode::Odometry]).unwrap()[0];
        if sums.is_empty() {
            sums = vec![0.0; run.samples().len()];
        }
        for (k, sample) in run.samples().iter().enumerate() {
            sums[k] += sample.nees.unwrap();
        }
    }
    let band = chi2_band_95(3.0, runs as usize);
    let late: Vec<f64> = sums[150..].iter().map(|s| s / runs as f64).collect();
    let mean = late.iter().sum::<f64>() / late.len() as f64;
    let inside = late
        .iter()
        .filter(|v| (band.0..=band.1).contains(*v))
        .count();
    (mean, inside as f64 / late.len() as f64, band)
}

#[test]
fn odometry_and_imu_alone_are_consistent_where_the_models_match() {
    // Measured with 200 runs (seeds 100..300, release): average NEES 3.20 in the
    // band [2.67, 3.35]; each of x, y and yaw alone 1.05..1.12 times its variance.
    // With 40 runs the band widens.
    let (mean, inside, (lo, hi)) = average_nees(40, 1e-5);
    assert!(
        (lo..=hi).contains(&mean),
        "NEES {mean} outside [{lo}, {hi}]"
    );
    assert!((mean - 3.536).abs() < 0.01, "pinned value moved: {mean}");
    assert!(inside > 0.9, "only {inside} of the times inside the band");
}

#[test]
fn a_fast_random_walk_shows_the_filters_q_dt_approximation() {
    // With a hundred times the acceleration noise, the yaw-rate error decorrelates
    // in about one IMU interval and the prediction's `Q Δt` (robot_localization's
    // discretization) misses the `q Δt³/3` the random yaw rate adds to the heading
    // within each 10 ms step: the filter is overconfident. Measured with 200 runs:
    // average NEES 4.73 against the band [2.67, 3.35].
    let (mean, _, (_, hi)) = average_nees(40, 1e-3);
    assert!(mean > hi, "{mean} not above {hi}");
    assert!((mean - 4.538).abs() < 0.01, "pinned value moved: {mean}");
}

fn short(seed: u64, duration: f64) -> FusionScenario {
    FusionScenario {
        seed,
        drive: DriveParams {
            duration,
            ..Default::default()
        },
        ..Default::default()
    }
}

#[test]
fn differential_is_smooth_at_the_slam_updates_and_relative_jumps() {
    let s = short(1, 120.0);
    let log = simulate(&s).unwrap();
    let runs = run_modes(&s, &log, &[FusionMode::Differential, FusionMode::Relative]).unwrap();
    let (diff, rel) = (&runs[0], &runs[1]);
    assert_eq!(
        diff.slam_jumps().len(),
        120,
        "one jump per fused pose after the first"
    );
    assert_eq!(rel.slam_jumps().len(), 121);
    // A differential update corrects a velocity: the position moves by at most
    // a few millimetres at the update itself.
    assert!(diff.max_slam_jump() < 0.005, "{}", diff.max_slam_jump());
    // A relative update corrects the position directly.
    assert!(rel.max_slam_jump() > 0.1, "{}", rel.max_slam_jump());
    let mean_jump = |r: &ModeRun| {
        r.slam_jumps().iter().map(|j| j.jump).sum::<f64>() / r.slam_jumps().len() as f64
    };
    assert!(mean_jump(rel) > 20.0 * mean_jump(diff));
}

#[test]
fn relative_stays_bounded_while_odometry_drifts() {
    // Ten minutes; seed 3's wheels and gyro drift noticeably.
    let s = short(3, 600.0);
    let log = simulate(&s).unwrap();
    let runs = run_modes(&s, &log, &[FusionMode::Relative, FusionMode::Odometry]).unwrap();
    let last_minute_error = |r: &ModeRun| {
        let tail: Vec<&Sample> = r.samples().iter().filter(|x| x.t >= 540.0).collect();
        tail.iter()
            .map(|x| slamlab_core::math::hypot(x.error[0], x.error[1]))
            .fold(0.0, f64::max)
    };
    let (rel, odo) = (last_minute_error(&runs[0]), last_minute_error(&runs[1]));
    assert!(rel < 0.35, "relative: {rel}");
    assert!(odo > 3.0 * rel, "odometry {odo} vs relative {rel}");
}

/// Every reading but the SLAM poses.
fn not_slam(log: &SensorLog) -> Vec<Arrival> {
    log.measurements
        .iter()
        .filter(|m| m.measurement.sensor != SLAM)
        .copied()
        .collect()
}

#[test]
fn every_mode_sees_the_same_data_and_sensors_have_their_own_streams() {
    let a = simulate(&short(4, 20.0)).unwrap();
    let b = simulate(&short(4, 20.0)).unwrap();
    assert_eq!(a, b);
    // Changing the SLAM noise leaves the odometry and IMU readings alone.
    let mut noisy = short(4, 20.0);
    noisy.slam.position_noise_std = 0.5;
    let c = simulate(&noisy).unwrap();
    assert_eq!(not_slam(&a), not_slam(&c));
    assert_ne!(a.slam_poses, c.slam_poses);
    // Rates: 50, 100 and 1 Hz over 20 s (both ends included).
    let count = |sensor| {
        a.measurements
            .iter()
            .filter(|m| m.measurement.sensor == sensor)
            .count()
    };
    assert_eq!((count(ODOMETRY), count(IMU), count(SLAM)), (1001, 2001, 21));
    // The drive keeps to the thesis's speeds: at most 0.1 m/s.
    assert!(a.truth.iter().all(|s| s.v <= 0.1 + 1e-12));
}

#[test]
fn late_poses_are_skipped_unless_the_filter_waits_for_them() {
    let mut s = short(5, 30.0);
    s.slam.latency = 0.2;
    let log = simulate(&s).unwrap();
    let mut run = ModeRun::new(&s, FusionMode::Relative).unwrap();
    let mut skipped = Vec::new();
    run.advance_to(&log, log.duration(), |step| {
        if let Outcome::Skipped(e) = &step.outcome {
            skipped.push(e.clone());
        }
    });
    // Each pose arrives 0.2 s after its stamp, when the odometry and IMU of those
    // 0.2 s have been applied: every pose is late. (The pose of 30 s would arrive
    // after the drive: 30 of the 31 arrive.)
    assert_eq!(run.filter().stats().out_of_order, 30);
    assert!(matches!(skipped[0], FusionError::TimeWentBackwards { .. }));
    s.filter_delay = 0.25;
    let mut waiting = ModeRun::new(&s, FusionMode::Relative).unwrap();
    waiting.run_to_end(&log);
    assert_eq!(waiting.filter().stats().out_of_order, 0);
    // The last 0.25 s still wait in the queue at the end of the drive.
    let waiting_stats = waiting.filter().stats();
    assert_eq!(
        waiting_stats.fused + waiting.filter().pending_len(),
        run.filter().stats().fused + 30
    );
    assert!(waiting.filter().pending().all(|m| m.stamp > 29.75));
}

#[test]
fn bad_parameters_are_refused_by_name() {
    let mut s = FusionScenario::default();
    s.odometry.rate = 0.0;
    let e = simulate(&s).unwrap_err();
    assert!(e.to_string().contains("odometry.rate"), "{e}");
    let mut s = FusionScenario::default();
    s.imu.gyro_noise_std = f64::NAN;
    assert!(
        ModeRun::new(&s, FusionMode::Odometry)
            .unwrap_err()
            .to_string()
            .contains("imu.gyro_noise_std")
    );
    let mut s = FusionScenario::default();
    s.slam.position_noise_std = -0.1;
    assert!(matches!(
        s.validate(),
        Err(ScenarioError::Invalid {
            name: "slam.position_noise_std",
            ..
        })
    ));
    let mut s = FusionScenario::default();
    s.drive.duration = 1e9;
    assert!(matches!(s.validate(), Err(ScenarioError::TooLong { .. })));
    let mut s = FusionScenario::default();
    s.process_noise[4] = -1.0;
    assert!(s.validate().unwrap_err().to_string().contains("v_y"));
}

#[test]
fn the_experiment_reports_table_5_3s_layout() {
    let template = short(0, 30.0);
    let result = fusion_experiment(&template, 2, 7, |_, _| {}).unwrap();
    let json = serde_json::to_value(&result).unwrap();
    assert_eq!(json["experiment"], "fusion");
    assert_eq!(json["trials"][1]["seed"], 8);
    for mode in ["differential", "relative", "odometry"] {
        for key in ["x", "y", "yaw"] {
            assert!(json["trials"][0][mode][key].as_f64().unwrap() > 0.0);
            let avg = json["average"][mode][key].as_f64().unwrap();
            let by_hand = (json["trials"][0][mode][key].as_f64().unwrap()
                + json["trials"][1][mode][key].as_f64().unwrap())
                / 2.0;
            assert!((avg - by_hand).abs() < 1e-15);
        }
    }
    assert_eq!(json["parameters"]["slam.rate"], 1.0);
    assert_eq!(json["parameters"]["odometry.rate"], 50.0);
    assert_eq!(json["parameters"]["trials"], 2);
    // Every trial's seed replays: the first trial alone gives the same numbers.
    let again = fusion_experiment(&template, 1, 7, |_, _| {}).unwrap();
    assert_eq!(again.trials[0], result.trials[0]);
}

#[test]
fn the_slam_pose_can_come_from_the_landmark_lessons_ekf_slam() {
    let mut s = short(1, 120.0);
    s.slam.source = SlamSource::LandmarkEkf;
    let log = simulate(&s).unwrap();
    assert_eq!(log.slam_poses.len(), 121);
    // The odometry and IMU are the same as with the simulated SLAM pose.
    let plain = simulate(&short(1, 120.0)).unwrap();
    assert_eq!(not_slam(&log), not_slam(&plain));
    let slam_error = log
        .slam_poses
        .iter()
        .map(|(t, p)| {
            let truth = log.truth_at(*t);
            slamlab_core::math::hypot(p.x - truth.x, p.y - truth.y)
        })
        .fold(0.0, f64::max);
    let runs = run_modes(&s, &log, &[FusionMode::Relative, FusionMode::Differential]).unwrap();
    for r in &runs {
        assert_eq!(r.filter().stats().skipped(), 0, "{:?}", r.filter().stats());
    }
    // Measured: EKF-SLAM's pose is off by at most 0.215 m over these two minutes.
    assert!((slam_error - 0.2148).abs() < 1e-3, "{slam_error}");
    // EKF-SLAM's pose moves smoothly from tick to tick (its errors are correlated
    // in time), so even `_relative` jumps little: at most 1.6 cm here, and
    // `_differential` at most 0.3 mm.
    let (rel, diff) = (runs[0].max_slam_jump(), runs[1].max_slam_jump());
    assert!((0.01..0.03).contains(&rel) && diff < 5e-4, "{rel} {diff}");
}

#[test]
fn stepping_one_measurement_at_a_time_gives_the_same_run() {
    for (latency, delay) in [(0.0, 0.0), (0.3, 0.35)] {
        let mut s = short(6, 12.0);
        s.slam.latency = latency;
        s.filter_delay = delay;
        let log = simulate(&s).unwrap();
        let mut whole = ModeRun::new(&s, FusionMode::Relative).unwrap();
        let mut whole_steps = Vec::new();
        whole.advance_to(&log, f64::INFINITY, |r| {
            whole_steps.push((r.sensor, r.stamp))
        });
        let mut stepped = ModeRun::new(&s, FusionMode::Relative).unwrap();
        let mut steps = Vec::new();
        while let Some(r) = stepped.step_one(&log) {
            steps.push((r.sensor, r.stamp));
        }
        assert_eq!(steps, whole_steps);
        assert_eq!(steps.len(), 601 + 1201 + 13);
        assert_eq!(stepped.filter().mean(), whole.filter().mean());
        let (a, b) = (stepped.samples(), whole.samples());
        assert_eq!((a.len(), b.len()), (361, 361));
        for (x, y) in a.iter().zip(b) {
            assert_eq!(x.t, y.t);
            assert!(
                (x.estimate.x - y.estimate.x).abs() < 1e-12,
                "{} {}",
                x.t,
                latency
            );
        }
        assert_eq!(stepped.filter().stats().out_of_order, 0);
    }
}

#[test]
fn mahalanobis_rejection_removes_most_of_the_outliers_harm() {
    // One pose in ten is a wrong relocalization, 1 m off (standard deviation).
    let run = |threshold: Option<f64>| {
        let mut s = short(2, 300.0);
        s.slam.outlier_probability = 0.1;
        s.slam.outlier_std = 1.0;
        s.slam.rejection_threshold = threshold;
        let log = simulate(&s).unwrap();
        let r = run_modes(&s, &log, &[FusionMode::Relative]).unwrap();
        (r[0].rmse(), r[0].filter().stats().rejected)
    };
    let (open, none) = run(None);
    let (gated, rejected) = run(Some(3.0));
    // Measured: x 0.248 → 0.106 m, y 0.348 → 0.112 m, 16 poses rejected.
    assert_eq!(none, 0);
    assert_eq!(rejected, 16);
    assert!(open.x > 0.2 && open.y > 0.3, "{open:?}");
    assert!(gated.x < 0.12 && gated.y < 0.12, "{gated:?}");
}

#[test]
fn the_imu_acceleration_can_be_fused_with_the_constant_acceleration_model() {
    let mut s = short(2, 60.0);
    s.imu.fuse_acceleration = true;
    let log = simulate(&s).unwrap();
    let with = &run_modes(&s, &log, &[FusionMode::Relative]).unwrap()[0];
    s.imu.fuse_acceleration = false;
    let without = &run_modes(&s, &log, &[FusionMode::Relative]).unwrap()[0];
    assert_eq!(with.filter().stats().skipped(), 0);
    // The accelerations are estimated (their variance is no longer zero) ...
    assert!(with.filter().covariance()[(6, 6)] > 0.0);
    assert_eq!(without.filter().covariance()[(6, 6)], 0.0);
    // ... and change the position estimate little at these speeds.
    let (a, b) = (with.rmse(), without.rmse());
    assert!(
        (a.x - b.x).abs() < 0.01 && (a.y - b.y).abs() < 0.01,
        "{a:?} {b:?}"
    );
}
