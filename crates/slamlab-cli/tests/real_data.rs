//! `slamlab experiment real-data` on the Freiburg course's files (331 steps):
//! the JSON's `parameters` are the data set's noise and the lists that ran.
//! Skipped with a message where `../shared/data` is absent.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

use std::path::PathBuf;
use std::process::Command;

/// `../shared/data/landmarks/<rel>` beside the repository (or under
/// `SLAMLAB_SHARED_DATA`), if it is there.
fn shared(rel: &str) -> Option<PathBuf> {
    let root = std::env::var_os("SLAMLAB_SHARED_DATA").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"),
        PathBuf::from,
    );
    let path = root.join("landmarks").join(rel);
    if path.exists() {
        Some(path)
    } else {
        eprintln!(
            "skipped: {} is absent (or set SLAMLAB_SHARED_DATA)",
            path.display()
        );
        None
    }
}

#[test]
fn the_json_parameters_are_the_ones_the_freiburg_run_used() {
    let Some(data) = shared("freiburg/sensor_data.dat") else {
        return;
    };
    let out = Command::new(env!("CARGO_BIN_EXE_slamlab"))
        .args(["experiment", "real-data", "--data"])
        .arg(&data)
        .args([
            "--estimator",
            "dead-reckoning,ekf",
            "--mode",
            "slam",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
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
