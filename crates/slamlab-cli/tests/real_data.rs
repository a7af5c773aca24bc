//! `slamlab experiment real-data` on the Freiburg course's files (331 steps):
//! the JSON's `parameters` are the data set's noise and the lists that ran.
//! Skipped with a message where `../shared/data` is absent.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

mod common;

use common::{run_json, shared_data};

#[test]
fn the_json_parameters_are_the_ones_the_freiburg_run_used() {
    let Some(data) = shared_data("landmarks/freiburg/sensor_data.dat") else {
        return;
    };
    let v = run_json(&[
        "experiment",
        "real-data",
        "--data",
        data.to_str().unwrap(),
        "--estimator",
        "dead-reckoning,ekf",
        "--mode",
        "slam",
        "--json",
    ]);
    let p = &v["parameters"];
    // The course's noise (the `freiburg` preset), not the simulated world's.
    assert_eq!(p["odometry-rot-std"], 0.005, "{p}");
    assert_eq!(p["odometry-trans-std"], 0.01, "{p}");
    assert_eq!(p["range-std"], 0.1, "{p}");
    assert_eq!(p["estimator"], "dead-reckoning,ekf", "{p}");
    assert_eq!(p["mode"], "slam", "{p}");
    for absent in [
        "landmarks",
        "controller",
        "v-std",
        "w-std-deg",
        "robot",
        "dt",
    ] {
        assert!(p.get(absent).is_none(), "{absent} in {p}");
    }
    // Two rows: dead reckoning, then EKF-SLAM with the nine landmarks of world.dat.
    let rows = v["results"].as_array().unwrap();
    assert_eq!(rows.len(), 2, "{v}");
    assert_eq!(rows[1]["estimator"], "ekf");
    assert_eq!(rows[1]["landmarks"], 9);
    assert!(rows[1]["gps"].is_null());
}
