//! EKF-SLAM consistency over seeded Monte Carlo runs (thesis `000` Sec. 3.2).

use nalgebra::SymmetricEigen;
use slamlab_core::kalman::LandmarkSlam;
use slamlab_core::stats::chi2_band_95;
use slamlab_sim::metrics::run_headless;
use slamlab_sim::{LandmarkScenario, LandmarkSession};

const RUNS: u64 = 50;
const STEPS: u64 = 200;

/// The robot-pose NEES averaged over `RUNS` seeded runs, tick by tick, and the
/// mean of those averages over the run.
fn average_nees(scenario: &LandmarkScenario) -> (Vec<f64>, f64) {
    let mut sums = vec![0.0; STEPS as usize];
    for seed in 1..=RUNS {
        let (session, _) = run_headless(
            LandmarkScenario {
                seed,
                ..scenario.clone()
            },
            STEPS,
        );
        for (k, m) in session.filters()[0].history.iter().enumerate() {
            // P_RR is singular only at the very start, before the first prediction.
            sums[k] += m.nees.unwrap_or(f64::NAN);
        }
    }
    let per_tick: Vec<f64> = sums.iter().map(|s| s / RUNS as f64).collect();
    let defined: Vec<f64> = per_tick.iter().copied().filter(|v| v.is_finite()).collect();
    assert!(
        defined.len() as u64 >= STEPS - 2,
        "NEES defined on {} of {STEPS} ticks",
        defined.len()
    );
    let mean = defined.iter().sum::<f64>() / defined.len() as f64;
    (per_tick, mean)
}

#[test]
fn average_robot_nees_at_nominal_noise_lies_in_the_95_percent_band() {
    let (per_tick, mean) = average_nees(&LandmarkScenario::default());
    let (lo, hi) = chi2_band_95(3.0, RUNS as usize);
    let inside = per_tick.iter().filter(|a| (lo..=hi).contains(*a)).count();
    println!("average NEES {mean:.3}, band [{lo:.3}, {hi:.3}], ticks in band {inside} of {STEPS}");
    assert!(
        (lo..=hi).contains(&mean),
        "average NEES {mean} outside [{lo}, {hi}]"
    );
    // Tick by tick most of the run stays in the band too (a consistent filter has ~95%).
    assert!(
        inside as f64 >= 0.6 * STEPS as f64,
        "only {inside} of {STEPS} ticks in the band"
    );
}

#[test]
fn a_precise_range_sensor_with_coarse_bearing_makes_ekf_slam_overconfident() {
    // 0.1 m range and 10° bearing: the true measurement likelihood is a thin
    // crescent that the linearization cannot follow. This is the inconsistency the
    // lesson lets students find; the test pins that it is real and large.
    let (_, mean) = average_nees(&LandmarkScenario {
        range_std: 0.1,
        ..Default::default()
    });
    let (_, hi) = chi2_band_95(3.0, RUNS as usize);
    println!("average NEES with range std 0.1 m: {mean:.2}");
    assert!(
        mean > 2.0 * hi,
        "expected a clearly inconsistent filter, got NEES {mean}"
    );
}

#[test]
fn landmark_uncertainty_shrinks_on_re_observation() {
    let mut session = LandmarkSession::new(LandmarkScenario {
        seed: 3,
        ..Default::default()
    });
    session.step_tick();
    let first: Vec<(usize, f64)> = session.filters()[0]
        .filter()
        .landmarks()
        .iter()
        .map(|l| (l.id, l.covariance.determinant()))
        .collect();
    assert!(!first.is_empty(), "landmarks are seen on the first tick");
    // The robot barely moves in one tick; the same landmarks are seen again.
    session.step_tick();
    let again = session.filters()[0].filter().landmarks();
    let mut compared = 0;
    for (id, det_before) in first {
        if session.observations().iter().any(|o| o.id == id) {
            let det_after = again
                .iter()
                .find(|l| l.id == id)
                .map(|l| l.covariance.determinant())
                .unwrap_or(f64::NAN);
            assert!(
                det_after < det_before,
                "landmark {id}: det {det_before} -> {det_after}"
            );
            compared += 1;
        }
    }
    assert!(compared > 0, "no landmark was re-observed");
    // And over a lap every initialized landmark ends far more certain than it started.
    session.run_ticks(200);
    for l in session.filters()[0].filter().landmarks() {
        assert!(
            l.covariance.trace() < 0.5,
            "landmark {} trace {}",
            l.id,
            l.covariance.trace()
        );
    }
}

#[test]
fn covariance_stays_symmetric_positive_semidefinite_over_ten_thousand_steps() {
    let mut session = LandmarkSession::new(LandmarkScenario {
        seed: 11,
        landmarks: 30,
        ..Default::default()
    });
    for block in 0..100 {
        session.run_ticks(100);
        let filter = session.filters()[0].filter();
        let p = filter.covariance().clone();
        assert_eq!(
            p,
            p.transpose(),
            "asymmetric after {} ticks",
            (block + 1) * 100
        );
        let eig = SymmetricEigen::new(p.clone());
        let min = eig.eigenvalues.min();
        let scale = p.trace().max(1.0);
        assert!(
            min >= -1e-12 * scale,
            "min eigenvalue {min} after {} ticks",
            (block + 1) * 100
        );
        assert!(filter.mean().iter().all(|v| v.is_finite()));
    }
    assert_eq!(session.tick(), 10_000);
}
