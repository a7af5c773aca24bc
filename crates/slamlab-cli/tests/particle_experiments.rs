//! `slamlab experiment fastslam` and `slamlab experiment resampling` as a user
//! runs them.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

mod common;

use common::{run_json, slamlab};

#[test]
fn fastslam_reports_one_entry_per_particle_count() {
    let v = run_json(&[
        "experiment",
        "fastslam",
        "--version",
        "1",
        "--particles",
        "3,6",
        "--trials",
        "2",
        "--steps",
        "50",
        "--seed",
        "1",
        "--json",
    ]);
    assert_eq!(v["experiment"], "fastslam");
    assert_eq!(v["version"], 1);
    let results = v["results"].as_array().unwrap();
    assert_eq!(results.len(), 2);
    for (r, m) in results.iter().zip([3, 6]) {
        assert_eq!(r["particles"], m);
        for key in ["robot_rmse", "landmark_rmse"] {
            for stat in ["mean", "std"] {
                let x = r[key][stat].as_f64().unwrap_or(f64::NAN);
                assert!(x.is_finite() && x >= 0.0, "{key}.{stat} = {}", r[key][stat]);
            }
            // Half a lap of the teaching world: decimetres, not metres.
            assert!(r[key]["mean"].as_f64().unwrap() < 1.5, "{key}: {}", r[key]);
        }
        let n_eff = r["mean_n_eff"].as_f64().unwrap();
        assert!(n_eff >= 1.0 && n_eff <= m as f64, "{n_eff}");
    }
    assert!(
        v["settings"]["world"]
            .as_str()
            .unwrap()
            .contains("range_std")
    );
}

#[test]
fn resampling_reports_every_method_on_every_preset() {
    let v = run_json(&[
        "experiment",
        "resampling",
        "--method",
        "all",
        "--trials",
        "2000",
        "--json",
    ]);
    let results = v["results"].as_array().unwrap();
    let names: Vec<&str> = results
        .iter()
        .map(|r| r["method"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        ["multinomial", "low-variance", "stratified", "residual"]
    );
    for r in results {
        let presets: Vec<&str> = r["presets"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["preset"].as_str().unwrap())
            .collect();
        assert_eq!(
            presets,
            ["one-dominant", "uniform", "two-modes", "many-tiny"]
        );
    }
    let var = |m: usize, p: usize| {
        results[m]["presets"][p]["copy_count_variance"]
            .as_f64()
            .unwrap()
    };
    for p in 0..4 {
        assert!(
            var(1, p) < var(0, p),
            "low-variance below multinomial on preset {p}"
        );
    }
}

#[test]
fn grid_fastslam_reports_one_row_per_particle_count_and_proposal() {
    let v = run_json(&[
        "experiment",
        "grid-fastslam",
        "--map",
        "maze",
        "--particles",
        "2",
        "--proposal",
        "odometry,scan-match",
        "--trials",
        "1",
        "--steps",
        "150",
        "--json",
    ]);
    assert_eq!(v["experiment"], "grid-fastslam");
    let results = v["results"].as_array().unwrap();
    assert_eq!(results.len(), 2);
    for (r, proposal) in results.iter().zip(["odometry", "scan-match"]) {
        assert_eq!(r["particles"], 2);
        assert_eq!(r["proposal"], proposal);
        let rmse = r["trajectory_rmse"]["median"].as_f64().unwrap();
        assert!(
            rmse.is_finite()
                && rmse >= 0.0
                && rmse <= r["trajectory_rmse"]["p90"].as_f64().unwrap()
        );
        let agreement = r["map_agreement"]["median"].as_f64().unwrap();
        assert!(agreement > 0.5 && agreement <= 1.0, "{agreement}");
        for key in ["resamplings", "time_ms", "memory_mb"] {
            assert!(r[key].as_f64().unwrap() >= 0.0, "{key}");
        }
    }
}

#[test]
fn run_mapping_with_grid_fastslam_reports_its_particles() {
    let v = run_json(&[
        "run",
        "mapping",
        "--map",
        "maze",
        "--steps",
        "120",
        "--poses",
        "grid-fastslam",
        "--particles",
        "4",
        "--proposal",
        "scan-match",
        "--linear-update",
        "0.5",
        "--seed",
        "2",
        "--json",
    ]);
    assert_eq!(v["poses"], "grid-fastslam");
    assert_eq!(v["scans"], 120);
    let p = &v["particles"];
    assert_eq!(p["particles"], 4);
    assert_eq!(p["proposal"], "scan-match");
    let updates = p["updates"].as_u64().unwrap();
    assert!(updates > 3 && updates < 120, "{updates} updates");
    assert!(p["peak_memory_bytes"].as_u64().unwrap() > 0);
    assert_eq!(v["parameters"]["linear_update"], 0.5);
    assert_eq!(v["parameters"]["poses"], "grid-fastslam");
    let rmse = v["trajectory_rmse"].as_f64().unwrap();
    assert!(rmse.is_finite() && rmse < 1.0, "{rmse}");
    // A particle count out of range is clamped with a message.
    let (ok, _, stderr) = slamlab(&[
        "run",
        "mapping",
        "--steps",
        "5",
        "--poses",
        "grid-fastslam",
        "--particles",
        "100000",
        "--json",
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("particles = 100000 is out of range; using 1000"),
        "{stderr}"
    );
}

#[test]
fn bad_input_is_refused_with_a_message() {
    for (args, expected) in [
        (
            vec!["experiment", "fastslam", "--particles", "0"],
            "at least one particle",
        ),
        (
            vec!["experiment", "fastslam", "--particles", "5,x"],
            "not a whole number",
        ),
        (
            vec!["experiment", "fastslam", "--method", "all"],
            "does not belong",
        ),
        (
            vec!["experiment", "grid-fastslam", "--particles", "5000"],
            "each particle carries a map",
        ),
        (
            vec!["experiment", "grid-fastslam", "--proposal", "fastslam2"],
            "not a proposal",
        ),
        (
            vec!["experiment", "resampling", "--method", "systematic"],
            "not a resampler",
        ),
        (
            vec!["experiment", "resampling", "--landmarks", "5"],
            "landmark-world parameter",
        ),
        (
            vec!["experiment", "consistency", "--particles", "5"],
            "belongs to the fastslam",
        ),
    ] {
        let (ok, _, stderr) = slamlab(&args);
        assert!(!ok, "{args:?} should fail");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
    let (ok, stdout, _) = slamlab(&["--version"]);
    assert!(
        ok && stdout.contains("slamlab"),
        "the program's own --version still works"
    );
}
