//! `slamlab experiment fusion` as a user runs it (thesis `002` Table 5.3).

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

mod common;

use common::slamlab;

#[test]
fn the_issues_command_prints_table_5_3s_json() {
    let args = [
        "experiment",
        "fusion",
        "--trials",
        "6",
        "--seed",
        "1",
        "--json",
    ];
    let (ok, stdout, stderr) = slamlab(&args);
    assert!(ok, "{stderr}");
    assert_eq!(stdout.lines().count(), 1);
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    // (serde_json's map lists keys sorted.)
    let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
    assert_eq!(keys, ["average", "experiment", "parameters", "trials"]);
    assert_eq!(v["experiment"], "fusion");
    let trials = v["trials"].as_array().unwrap();
    assert_eq!(trials.len(), 6);
    for (i, t) in trials.iter().enumerate() {
        assert_eq!(t["seed"], 1 + i as u64);
        let modes: Vec<&String> = t.as_object().unwrap().keys().collect();
        assert_eq!(modes, ["differential", "odometry", "relative", "seed"]);
    }
    for mode in ["differential", "relative", "odometry"] {
        for axis in ["x", "y", "yaw"] {
            let mean = trials
                .iter()
                .map(|t| t[mode][axis].as_f64().unwrap())
                .sum::<f64>()
                / 6.0;
            assert!((v["average"][mode][axis].as_f64().unwrap() - mean).abs() < 1e-12);
        }
    }
    // The README's table (seeded; libm makes it the same on every machine).
    let avg = |mode: &str, axis: &str| v["average"][mode][axis].as_f64().unwrap();
    assert!((avg("differential", "x") - 0.0887).abs() < 5e-5);
    assert!((avg("relative", "x") - 0.0709).abs() < 5e-5);
    assert!((avg("relative", "y") - 0.0813).abs() < 5e-5);
    assert!((avg("odometry", "yaw") - 0.1623).abs() < 5e-5);
    assert_eq!(v["parameters"]["imu.rate"], 100.0);
    assert_eq!(v["parameters"]["drive.duration"], 300.0);
}

#[test]
fn the_readable_table_lists_every_trial_and_the_thesis_average() {
    let (ok, stdout, stderr) = slamlab(&["experiment", "fusion", "--trials", "1", "--seed", "2"]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("Trial1"), "{stdout}");
    assert!(stdout.contains("Average"));
    assert!(stdout.contains("relative"));
    assert!(stdout.contains("Thesis Table 5.3 average"));
    let (ok, _, stderr) = slamlab(&["experiment", "fusion", "--range-std", "0.2"]);
    assert!(!ok && stderr.contains("--range-std"), "{stderr}");
}
