//! FastSLAM beside the Kalman filters, wrong associations and unknown ids.

use super::tests::shown;
use super::*;
use crate::world::landmark_scenario::Association;
use crate::world::landmark_session::particle_estimator::OWN_LABELS;

fn ekf_and_fastslam(seed: u64) -> LandmarkScenario {
    LandmarkScenario {
        seed,
        estimators: vec![EstimatorKind::Ekf, EstimatorKind::FastSlam2],
        ..Default::default()
    }
}

/// Mean robot position error of every filter over ticks `from..to`.
fn mean_errors(s: &LandmarkSession, from: usize, to: usize) -> Vec<f64> {
    s.filters()
        .iter()
        .map(|r| {
            let e = &r.history[from..to];
            e.iter().map(|m| m.position_error).sum::<f64>() / e.len() as f64
        })
        .collect()
}

fn close(a: f64, b: f64, what: &str) {
    assert!((a - b).abs() < 1e-9, "{what}: {a} against {b}");
}

#[test]
fn ekf_beside_fastslam2_golden_and_the_ekf_is_unchanged() {
    let mut s = LandmarkSession::new(ekf_and_fastslam(1));
    // Phases: sample (predict), weight per observation, resample.
    assert_eq!(s.step_phase(), Phase::Predict);
    let n = s.observations().len();
    for _ in 0..n {
        assert!(matches!(s.step_phase(), Phase::Update { .. }));
    }
    assert_eq!(s.step_phase(), Phase::Resample);
    assert!(!s.is_mid_tick());
    assert_eq!(Phase::Resample.label(), "resample");
    s.run_ticks(99);
    let ekf = s.filters()[0].latest().copied().unwrap();
    let fast = s.filters()[1].latest().copied().unwrap();
    close(ekf.position_error, 0.2112864142132007, "EKF position error");
    close(
        fast.position_error,
        0.2792836264881384,
        "FastSLAM 2.0 position error",
    );
    close(
        fast.landmark_rmse.unwrap(),
        0.43476188949744654,
        "FastSLAM landmark RMSE",
    );
    assert_eq!(
        (ekf.landmarks_initialized, fast.landmarks_initialized),
        (15, 15)
    );
    let n_eff = &s.filters()[1].n_eff;
    assert_eq!(n_eff.len(), 100);
    assert_eq!(n_eff.iter().filter(|n| n.resampled).count(), 11);
    close(n_eff[99].n_eff, 49.47614842063085, "N_eff at tick 100");
    assert!(s.filters()[0].n_eff.is_empty(), "the EKF has no particles");
    let particles = s.filters()[1].filter().particle_set().unwrap();
    assert_eq!(particles.particle_count(), 100);
    // The EKF beside FastSLAM is bit for bit the EKF alone.
    let mut alone = LandmarkSession::new(LandmarkScenario {
        seed: 1,
        ..Default::default()
    });
    alone.run_ticks(100);
    assert_eq!(
        shown(alone.filters()[0].filter()),
        shown(s.filters()[0].filter())
    );
    assert_eq!(alone.filters()[0].history, s.filters()[0].history);
}

#[test]
fn a_wrong_association_is_measured_and_replays_exactly() {
    // Over ten seeds: the sensor mislabels one observation at tick 61; the rise
    // of the mean robot position error over ticks 61-101 against the clean run.
    // With known ids every particle takes the same wrong id, so FastSLAM is
    // hurt as much as the EKF (2.0 even more: its proposal uses the measurement).
    for (kind, ekf_rise, fast_rise) in [
        (EstimatorKind::FastSlam1, 0.994, 0.963),
        (EstimatorKind::FastSlam2, 0.994, 1.378),
    ] {
        let (mut de, mut df) = (0.0, 0.0);
        for seed in 1..=10 {
            let sc = LandmarkScenario {
                estimators: vec![EstimatorKind::Ekf, kind],
                ..ekf_and_fastslam(seed)
            };
            let mut clean = LandmarkSession::new(sc.clone());
            clean.run_ticks(101);
            let mut wrong = LandmarkSession::new(sc);
            wrong.run_ticks(60);
            wrong.mislabel_next_observation();
            wrong.run_ticks(1);
            let m = wrong.mislabel().unwrap();
            assert_ne!(m.true_id, m.reported_id);
            assert_eq!(wrong.observations()[m.index].id, m.reported_id);
            wrong.run_ticks(40);
            let c = mean_errors(&clean, 60, 101);
            let w = mean_errors(&wrong, 60, 101);
            de += w[0] - c[0];
            df += w[1] - c[1];
        }
        assert!((de - ekf_rise).abs() < 5e-4, "{kind:?}: EKF {de}");
        assert!((df - fast_rise).abs() < 5e-4, "{kind:?}: FastSLAM {df}");
    }
    // Seed 1: landmark 1 is reported as its neighbour 19; stepping back over
    // the tick and forward again replays the mislabel.
    let mut s = LandmarkSession::new(ekf_and_fastslam(1));
    s.run_ticks(60);
    s.mislabel_next_observation();
    s.run_ticks(5);
    let at_65 = shown(s.filters()[1].filter());
    while s.tick() > 59 {
        assert!(s.step_back());
    }
    assert_eq!(s.mislabel_ticks(), &[61]);
    s.run_ticks(2);
    assert_eq!(
        s.mislabel(),
        Some(Mislabel {
            index: 0,
            true_id: 1,
            reported_id: 19
        })
    );
    s.run_ticks(4);
    assert_eq!(shown(s.filters()[1].filter()), at_65);
}

#[test]
fn unknown_association_runs_nearest_neighbour_and_maximum_likelihood() {
    let mut s = LandmarkSession::new(LandmarkScenario {
        association: Association::Unknown,
        ..ekf_and_fastslam(1)
    });
    s.run_ticks(100);
    let ekf = s.filters()[0].latest().copied().unwrap();
    let fast = s.filters()[1].latest().copied().unwrap();
    // Both found the 15 landmarks the robot saw, under labels of their own.
    assert_eq!(
        (ekf.landmarks_initialized, fast.landmarks_initialized),
        (15, 15)
    );
    assert!(
        s.filters()[0]
            .filter()
            .landmark_ids()
            .iter()
            .all(|&id| id >= OWN_LABELS)
    );
    close(
        ekf.position_error,
        0.3192219318542592,
        "EKF (nearest neighbour)",
    );
    // argmax{π_j, p₀} (Montemerlo 2003): 0.4766 m; gating on d² alone gave
    // 0.4964 m.
    close(
        fast.position_error,
        0.4765839264904337,
        "FastSLAM 2.0 (maximum likelihood)",
    );
    close(
        ekf.landmark_rmse.unwrap(),
        0.5783381344141212,
        "EKF landmark RMSE",
    );
}

#[test]
fn zero_particles_and_a_threshold_outside_0_1_are_repaired_with_a_notice() {
    let mut s = LandmarkSession::new(LandmarkScenario {
        fastslam: crate::world::landmark_scenario::FastSlamSettings {
            particles: 0,
            resample_threshold: 3.0,
            ..Default::default()
        },
        ..ekf_and_fastslam(1)
    });
    assert_eq!(
        s.notices(),
        &[
            "particles = 0 is out of range; using 1".to_owned(),
            "resample-threshold = 3 is out of range; using 1".to_owned()
        ]
    );
    assert_eq!(s.filters().len(), 2);
    s.run_ticks(3);
    assert_eq!(
        s.filters()[1]
            .filter()
            .particle_set()
            .map(|p| p.particle_count()),
        Some(1)
    );
}
