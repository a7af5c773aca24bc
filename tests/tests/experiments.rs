//! Thesis `000` Sec. 3.4.3 reproduced: EKF-SLAM vs UKF-SLAM, Experiments 1 and 2.
//!
//! Seeded (trials use seeds 1..=50), so the numbers below are exact for this
//! code; the assertions state what the reproduction shows, with margins.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

use slamlab_sim::landmark_slam::experiment::{
    ExperimentResult, FilterResult, ekf_vs_ukf, series_csv,
};

fn run(noise_scale: f64) -> ExperimentResult {
    ekf_vs_ukf(noise_scale, 50, 1, |_, _| {})
}

fn filter<'a>(r: &'a ExperimentResult, name: &str) -> &'a FilterResult {
    r.filters
        .iter()
        .find(|f| f.name == name)
        .unwrap_or_else(|| panic!("no {name} in {:?}", r.filters))
}

#[test]
fn experiment_1_both_filters_map_the_landmarks() {
    let r = run(1.0);
    for name in ["ekf", "ukf"] {
        let f = filter(&r, name);
        println!("{name}: {f:?}");
        // With 2 m range noise, landmark RMSE below 1.5 m (MSE < 2.25 m²) and robot
        // RMSE below 1 m over the lap. Measured: EKF 1.34 / 0.46 m², UKF 0.58 / 0.12 m².
        assert!(
            f.landmark_mse < 2.25,
            "{name} landmark MSE {}",
            f.landmark_mse
        );
        assert!(f.robot_mse < 1.0, "{name} robot MSE {}", f.robot_mse);
        assert_eq!(f.diverged, 0, "{name}");
    }
    // The thesis calls the two "similar" here; this reproduction finds the UKF
    // clearly better already, because the EKF has a heavy tail of bad trials.
    assert!(filter(&r, "ukf").robot_mse < 0.5 * filter(&r, "ekf").robot_mse);
}

#[test]
fn experiment_2_ukf_is_better_and_no_filter_diverges_past_5_m() {
    let r = run(2.0);
    let (ekf, ukf) = (filter(&r, "ekf"), filter(&r, "ukf"));
    println!("ekf: {ekf:?}\nukf: {ukf:?}");
    // Measured: robot MSE EKF 1.09, UKF 0.25 m²; landmark MSE EKF 2.59, UKF 0.87 m².
    assert!(ukf.robot_mse < 0.5 * ekf.robot_mse);
    assert!(ukf.landmark_mse < 0.5 * ekf.landmark_mse);
    // The EKF grows worse with the doubled noise, as the thesis says...
    let e1 = run(1.0);
    assert!(ekf.robot_mse > 1.5 * filter(&e1, "ekf").robot_mse);
    // ...but by the 5 m criterion no trial of either filter diverges.
    assert_eq!((ekf.diverged, ukf.diverged), (0, 0));
    // The EKF is far more overconfident (NEES; 3 is consistent).
    assert!(
        ekf.nees_mean > 3.0 * ukf.nees_mean,
        "NEES EKF {} UKF {}",
        ekf.nees_mean,
        ukf.nees_mean
    );
}

#[test]
fn experiments_are_reproducible_and_print_every_parameter() {
    let a = ekf_vs_ukf(1.0, 5, 9, |_, _| {});
    let b = ekf_vs_ukf(1.0, 5, 9, |_, _| {});
    assert_eq!(a, b);
    for key in [
        "dt",
        "world-size",
        "landmarks",
        "v-std",
        "w-std-deg",
        "range-std",
        "bearing-std-deg",
        "fov-deg",
        "max-range",
        "trials",
        "steps",
        "noise-scale",
        "seed",
    ] {
        assert!(a.parameters.contains_key(key), "missing {key}");
    }
    let csv = series_csv(&a, 0.1);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "step,time_s,ekf_robot_mse,ekf_landmark_mse,ukf_robot_mse,ukf_landmark_mse"
    );
    assert_eq!(lines.len(), 201);
    assert!(lines[200].starts_with("200,20.000,"));
    let mut progress = Vec::new();
    ekf_vs_ukf(2.0, 3, 1, |done, total| progress.push((done, total)));
    assert_eq!(progress, vec![(1, 3), (2, 3), (3, 3)]);
}
