use super::model::pose_delta;
use super::*;
use crate::geometry::wrap_angle;
use nalgebra::Vector3;

const ODOM: usize = 0;
const IMU: usize = 1;
const SLAM: usize = 2;

fn sensors(mode: PoseMode, threshold: Option<f64>) -> Vec<SensorConfig> {
    vec![
        SensorConfig::new(
            "wheel odometry",
            &[StateIndex::VX, StateIndex::VY, StateIndex::YawRate],
        ),
        SensorConfig::new("IMU", &[StateIndex::YawRate, StateIndex::AX]),
        SensorConfig::new(
            "SLAM pose",
            &[StateIndex::X, StateIndex::Y, StateIndex::Yaw],
        )
        .with_pose_mode(mode, threshold),
    ]
}

fn filter(mode: PoseMode, threshold: Option<f64>, use_acceleration: bool) -> FusionEkf {
    let config = FusionConfig {
        use_acceleration,
        ..FusionConfig::default()
    };
    let mean = StateVector::from_column_slice(&[0.5, -0.2, 0.4, 0.3, 0.0, 0.1, 0.05, 0.0]);
    let cov = StateMatrix::from_diagonal(&StateVector::from_element(0.01));
    FusionEkf::new(config, sensors(mode, threshold), 0.0, mean, cov).unwrap()
}

fn pose(t: f64, p: Pose2, std: f64) -> Measurement {
    Measurement {
        sensor: SLAM,
        stamp: t,
        reading: Reading::Pose {
            pose: p,
            covariance: Matrix3::from_diagonal(&Vector3::new(std * std, std * std, 0.01)),
        },
    }
}

fn twist(t: f64, v: f64, w: f64) -> Measurement {
    Measurement {
        sensor: ODOM,
        stamp: t,
        reading: Reading::Twist {
            twist: Vector3::new(v, 0.0, w),
            covariance: Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 1e-4)),
        },
    }
}

fn imu(t: f64, w: f64) -> Measurement {
    Measurement {
        sensor: IMU,
        stamp: t,
        reading: Reading::Imu {
            values: Vector3::new(w, 0.02, 0.0),
            covariance: Matrix3::from_diagonal(&Vector3::new(1e-5, 1e-3, 1e-3)),
        },
    }
}

fn is_psd(m: &StateMatrix) -> bool {
    m.symmetric_eigenvalues().iter().all(|&e| e > -1e-12)
}

#[test]
fn a_measurement_equal_to_the_prediction_leaves_the_mean_and_shrinks_the_covariance() {
    for use_acceleration in [false, true] {
        let base = filter(PoseMode::Absolute, None, use_acceleration);
        let t = 0.3;
        let (predicted, p_bar) = base.predicted_at(t).unwrap();
        let at_prediction = [
            pose(t, Pose2::new(predicted[0], predicted[1], predicted[2]), 0.1),
            Measurement {
                sensor: ODOM,
                stamp: t,
                reading: Reading::Twist {
                    twist: Vector3::new(predicted[3], predicted[4], predicted[5]),
                    covariance: Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 1e-4)),
                },
            },
            Measurement {
                sensor: IMU,
                stamp: t,
                reading: Reading::Imu {
                    values: Vector3::new(predicted[5], predicted[6], predicted[7]),
                    covariance: Matrix3::from_diagonal(&Vector3::new(1e-5, 1e-3, 1e-3)),
                },
            },
        ];
        for m in at_prediction {
            let mut f = base.clone();
            let report = f.apply(&m);
            let u = report.update().unwrap();
            assert!(u.innovation.iter().all(|v| v.abs() < 1e-12), "{u:?}");
            assert!((f.mean() - predicted).abs().max() < 1e-12);
            let shrink = p_bar - f.covariance();
            assert!(is_psd(&shrink), "P̄ − P not PSD for {}", m.reading.kind());
            assert!(f.covariance().trace() < p_bar.trace() - 1e-6);
            // Each fused variable's variance shrinks by the scalar Kalman factor
            // at least (the others only through correlations).
            for (a, v) in u.variables.iter().enumerate() {
                let i = *v as usize;
                let r = m.reading.covariance()[(a, a)];
                let scalar = p_bar[(i, i)] * r / (p_bar[(i, i)] + r);
                assert!(f.covariance()[(i, i)] <= scalar + 1e-12, "{}", v.label());
            }
        }
    }
}

#[test]
fn the_prediction_adds_process_noise_times_dt_through_the_jacobian() {
    let f = filter(PoseMode::Absolute, None, false);
    let dt = 0.25;
    let (mean, p) = f.predicted_at(dt).unwrap();
    let jac = model::predict_jacobian(f.mean(), dt);
    let mut q = StateMatrix::zeros();
    for i in 0..6 {
        q[(i, i)] = f.config().process_noise[i] * dt;
    }
    let expected = jac * f.covariance() * jac.transpose() + q;
    assert!((p - expected).abs().max() < 1e-15);
    assert_eq!(mean, model::predict_state(f.mean(), dt));
    // The constant-velocity model keeps the accelerations at zero with no variance.
    assert_eq!(mean[6], 0.0);
    assert_eq!(p[(6, 6)], 0.0);
    assert_eq!(p[(7, 7)], 0.0);
}

#[test]
fn relative_mode_rotates_into_the_first_readings_frame() {
    let mut f = filter(PoseMode::Relative, None, false);
    let origin = Pose2::new(2.0, 1.0, 0.7);
    let first = f.apply(&pose(0.1, origin, 0.2));
    let u = first.update().unwrap();
    // The first reading fuses as the identity pose.
    assert!(
        u.measured.iter().all(|v| v.abs() < 1e-12),
        "{:?}",
        u.measured
    );
    // A later reading 1 m ahead of the origin along its heading reads [1, 0, 0].
    let ahead = origin.compose(&Pose2::new(1.0, 0.0, 0.0));
    let second = f.apply(&pose(0.2, ahead, 0.2));
    let u = second.update().unwrap();
    assert!((u.measured[0] - 1.0).abs() < 1e-12 && u.measured[1].abs() < 1e-12);
    // An anisotropic covariance (0.04 along world x, 0.01 along world y) is seen in
    // the origin's frame: S − P̄ (= R) equals the rotated matrix, which is the
    // first-order propagation J Σ Jᵀ with J = ∂(P₀⁻¹∘P)/∂P from `pose_delta`.
    let mut g = filter(PoseMode::Relative, None, false);
    g.apply(&pose(0.1, origin, 0.2));
    let cov = Matrix3::from_diagonal(&Vector3::new(0.04, 0.01, 0.02));
    let (_, _, j) = pose_delta(&origin, &ahead);
    let expected = j * cov * j.transpose();
    let p_bar = g.predicted_at(0.2).unwrap().1;
    let report = g.apply(&Measurement {
        sensor: SLAM,
        stamp: 0.2,
        reading: Reading::Pose {
            pose: ahead,
            covariance: cov,
        },
    });
    let s = &report.update().unwrap().innovation_covariance;
    for a in 0..3 {
        for b in 0..3 {
            let r = s[(a, b)] - p_bar[(a, b)];
            assert!((r - expected[(a, b)]).abs() < 1e-12, "({a},{b}) {r}");
        }
    }
}

#[test]
fn differential_mode_turns_consecutive_poses_into_a_velocity() {
    let mut f = filter(PoseMode::Differential, None, false);
    let p0 = Pose2::new(1.0, 1.0, 0.5);
    let first = f.apply(&pose(1.0, p0, 0.05));
    assert_eq!(first.outcome, Outcome::Stored);
    assert_eq!(f.stats().stored, 1);
    // The filter's time did not move for a stored pose.
    assert_eq!(f.time(), 0.0);
    // 2 s later: 0.2 m forward, 0.04 m to the left, turned by 0.1 rad.
    let p1 = p0.compose(&Pose2::new(0.2, 0.04, 0.1));
    let second = f.apply(&pose(3.0, p1, 0.05));
    let u = second.update().unwrap();
    assert_eq!(
        u.variables,
        vec![StateIndex::VX, StateIndex::VY, StateIndex::YawRate]
    );
    let expected = [0.1, 0.02, 0.05];
    for k in 0..3 {
        assert!(
            (u.measured[k] - expected[k]).abs() < 1e-12,
            "{:?}",
            u.measured
        );
    }
    // Combined covariance: (J₀ Σ₀ J₀ᵀ + J₁ Σ₁ J₁ᵀ) / Δt²; the forward velocity's
    // variance is (0.05² + 0.05² + 0.01·0.04²) / 4 (the heading noise of the first
    // pose moves the lateral offset 0.04 m into the forward direction).
    let expected_r = (2.0 * 0.05_f64.powi(2) + 0.01 * 0.04_f64.powi(2)) / 4.0;
    // P̄ at the second stamp, from a twin that saw the same first pose.
    let mut twin = filter(PoseMode::Differential, None, false);
    twin.apply(&pose(1.0, p0, 0.05));
    let p_bar_twin = twin.predicted_at(3.0).unwrap().1;
    let r_vx_twin = u.innovation_covariance[(0, 0)] - p_bar_twin[(3, 3)];
    assert!(
        (r_vx_twin - expected_r).abs() < 1e-12,
        "{r_vx_twin} vs {expected_r}"
    );
}

#[test]
fn mahalanobis_rejection_leaves_the_state_unchanged() {
    let mut gated = filter(PoseMode::Absolute, Some(3.0), false);
    let mut open = filter(PoseMode::Absolute, None, false);
    let far = pose(0.1, Pose2::new(5.0, 5.0, 0.0), 0.05);
    let before = *gated.mean();
    let report = gated.apply(&far);
    let u = report.update().unwrap();
    assert!(u.rejected && u.nis > 9.0, "{u:?}");
    assert!(report.label().ends_with("(rejected)"), "{}", report.label());
    // Only the prediction to the stamp happened.
    assert_eq!(*gated.mean(), model::predict_state(&before, 0.1));
    assert_eq!(gated.stats().rejected, 1);
    let u = open.apply(&far).update().unwrap().clone();
    assert!(!u.rejected);
    assert_eq!(open.stats().fused, 1);
    assert!((open.mean()[0] - before[0]).abs() > 1.0);
}

#[test]
fn out_of_order_arrivals_are_applied_in_stamp_order() {
    let mut ms = Vec::new();
    for k in 1..=60 {
        let t = k as f64 * 0.01;
        ms.push(imu(t, 0.1 + 0.01 * k as f64));
        if k % 2 == 0 {
            ms.push(twist(t, 0.3, 0.1));
        }
        if k % 20 == 0 {
            ms.push(pose(t, Pose2::new(0.5 + 0.3 * t, -0.2, 0.4 + 0.1 * t), 0.1));
        }
    }
    let mut in_order = filter(PoseMode::Relative, None, true);
    for m in &ms {
        in_order.enqueue(*m);
    }
    // The same measurements arriving in a scrambled order (a fixed permutation).
    let mut shuffled = ms.clone();
    let n = shuffled.len();
    for i in 0..n {
        let j = (i * 37 + 11) % n;
        shuffled.swap(i, j);
    }
    assert_ne!(shuffled, ms);
    let mut scrambled = filter(PoseMode::Relative, None, true);
    for m in &shuffled {
        scrambled.enqueue(*m);
    }
    let mut stamps = Vec::new();
    while let Some(r) = scrambled.step() {
        assert!(r.update().is_some(), "{}", r.label());
        stamps.push(r.stamp);
    }
    assert!(stamps.windows(2).all(|w| w[0] <= w[1]), "{stamps:?}");
    assert_eq!(in_order.process_until(f64::INFINITY), ms.len());
    // Equal stamps from different sensors commute only approximately; the states
    // agree to rounding.
    assert!((in_order.mean() - scrambled.mean()).abs().max() < 1e-9);
    assert!((in_order.covariance() - scrambled.covariance()).abs().max() < 1e-12);
    assert_eq!(scrambled.stats().fused, ms.len());
    // process_until stops at its stamp.
    let mut partial = filter(PoseMode::Relative, None, true);
    for m in &shuffled {
        partial.enqueue(*m);
    }
    let taken = partial.process_until(0.3);
    assert_eq!(taken, ms.iter().filter(|m| m.stamp <= 0.3).count());
    assert_eq!(partial.time(), 0.3);
}

#[test]
fn bad_input_is_skipped_counted_and_leaves_the_state() {
    let mut f = filter(PoseMode::Differential, None, false);
    f.apply(&twist(0.5, 0.3, 0.1));
    let (mean, cov, time) = (*f.mean(), *f.covariance(), f.time());
    let mut zero_noise = twist(0.6, 0.3, 0.1);
    if let Reading::Twist { covariance, .. } = &mut zero_noise.reading {
        covariance[(2, 2)] = 0.0;
    }
    let mut negative_noise = imu(0.6, 0.1);
    if let Reading::Imu { covariance, .. } = &mut negative_noise.reading {
        covariance[(0, 0)] = -1e-4;
    }
    let mut nan_reading = twist(0.6, f64::NAN, 0.1);
    nan_reading.stamp = 0.6;
    let nan_stamp = twist(f64::NAN, 0.3, 0.1);
    let before_start = pose(-1.0, Pose2::new(0.0, 0.0, 0.0), 0.1);
    let backwards = imu(0.2, 0.1);
    let unknown = Measurement {
        sensor: 9,
        ..twist(0.6, 0.3, 0.1)
    };
    type Check = fn(&FusionError) -> bool;
    let cases: [(Measurement, Check); 7] = [
        (zero_noise, |e| {
            matches!(
                e,
                FusionError::NonPositiveNoise {
                    variable: "yaw rate",
                    ..
                }
            )
        }),
        (negative_noise, |e| {
            matches!(e, FusionError::NonPositiveNoise { .. })
        }),
        (nan_reading, |e| {
            matches!(e, FusionError::NonFiniteReading { .. })
        }),
        (nan_stamp, |e| {
            matches!(e, FusionError::NonFiniteStamp { .. })
        }),
        (before_start, |e| {
            matches!(e, FusionError::BeforeStart { .. })
        }),
        (backwards, |e| {
            matches!(e, FusionError::TimeWentBackwards { .. })
        }),
        (unknown, |e| matches!(e, FusionError::UnknownSensor { .. })),
    ];
    for (m, expected) in cases {
        let report = f.apply(&m);
        let Outcome::Skipped(e) = &report.outcome else {
            panic!("not skipped: {report:?}")
        };
        assert!(expected(e), "{e}");
        assert!(!e.to_string().is_empty());
        assert_eq!((*f.mean(), *f.covariance(), f.time()), (mean, cov, time));
    }
    let s = *f.stats();
    assert_eq!(
        (
            s.bad_noise,
            s.non_finite,
            s.before_start,
            s.out_of_order,
            s.unusable
        ),
        (2, 2, 1, 1, 1)
    );
    assert_eq!(s.skipped(), 7);
    assert_eq!(s.fused, 1);
    // A NaN stamp queued goes first and is skipped, not stuck.
    f.enqueue(twist(0.7, 0.3, 0.1));
    f.enqueue(twist(f64::NAN, 0.3, 0.1));
    assert_eq!(f.process_until(1.0), 2);
    assert_eq!(f.stats().non_finite, 3);
    assert_eq!(f.stats().fused, 2);
    // A differential pose repeated at the same stamp cannot make a velocity.
    f.apply(&pose(0.8, Pose2::new(0.0, 0.0, 0.0), 0.1));
    let r = f.apply(&pose(0.8, Pose2::new(0.0, 0.0, 0.0), 0.1));
    assert!(matches!(
        r.outcome,
        Outcome::Skipped(FusionError::ZeroInterval { .. })
    ));
    // A sensor whose selection misses the reading's variables.
    let mut g = filter(PoseMode::Absolute, None, false);
    let r = g.apply(&Measurement {
        sensor: IMU,
        ..twist(0.1, 0.3, 0.1)
    });
    // The IMU sensor fuses ψ̇ and a_x; a twist carries ψ̇, so this one is fused.
    assert!(r.update().is_some());
    let mut only_pose = sensors(PoseMode::Absolute, None);
    only_pose[0].fuse = StateMask::of(&[StateIndex::X]);
    let mut h = FusionEkf::new(
        FusionConfig::default(),
        only_pose,
        0.0,
        StateVector::zeros(),
        StateMatrix::identity(),
    )
    .unwrap();
    let r = h.apply(&twist(0.1, 0.3, 0.1));
    assert!(matches!(
        r.outcome,
        Outcome::Skipped(FusionError::NothingToFuse { .. })
    ));
    // Bad configurations are refused up front.
    let bad_q = FusionConfig {
        process_noise: [0.05, -1.0, 0.06, 0.025, 0.025, 0.02, 0.01, 0.01],
        ..FusionConfig::default()
    };
    let e = FusionEkf::new(
        bad_q,
        sensors(PoseMode::Absolute, None),
        0.0,
        StateVector::zeros(),
        StateMatrix::identity(),
    )
    .unwrap_err();
    assert!(matches!(
        e,
        FusionError::InvalidProcessNoise { variable: "y", .. }
    ));
    let e = FusionEkf::new(
        FusionConfig::default(),
        sensors(PoseMode::Absolute, Some(f64::NAN)),
        0.0,
        StateVector::zeros(),
        StateMatrix::identity(),
    )
    .unwrap_err();
    assert!(matches!(e, FusionError::InvalidThreshold { .. }));
    let e = FusionEkf::new(
        FusionConfig::default(),
        sensors(PoseMode::Absolute, None),
        0.0,
        StateVector::from_element(f64::NAN),
        StateMatrix::identity(),
    )
    .unwrap_err();
    assert_eq!(e, FusionError::InvalidInitialState);
}

#[test]
fn step_labels_name_the_sensor_the_variables_and_the_time() {
    let mut f = filter(PoseMode::Differential, None, false);
    let r = f.apply(&imu(12.34, 0.1));
    assert_eq!(r.label(), "IMU: yaw rate, a_x at 12.34 s");
    let r = f.apply(&pose(13.0, Pose2::new(0.0, 0.0, 0.0), 0.1));
    assert_eq!(
        r.label(),
        "SLAM pose: first pose stored for differencing at 13.00 s"
    );
    let r = f.apply(&pose(14.0, Pose2::new(0.1, 0.0, 0.0), 0.1));
    assert_eq!(
        r.label(),
        "SLAM pose (differential): v_x, v_y, yaw rate at 14.00 s"
    );
    assert!(r.update().unwrap().gain_norm > 0.0);
    assert!(wrap_angle(f.pose().theta - f.mean()[2]).abs() < 1e-15);
}
