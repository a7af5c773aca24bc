//! `slamlab run kidnap` and `slamlab map`: the JSON keys, the map commands, and
//! refusals of bad input.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

mod common;

use common::{Scratch, json, slamlab_output};

#[test]
fn run_kidnap_prints_the_issue_json() {
    // Tracking from the true start, twice: the same seed must print the same bytes.
    let args = [
        "run",
        "kidnap",
        "--map",
        "maze",
        "--estimator",
        "mcl",
        "--particles",
        "300",
        "--init",
        "tracking",
        "--steps",
        "120",
        "--seed",
        "2",
        "--json",
    ];
    let out = slamlab_output(&args);
    let v = json(&out);
    assert_eq!(v["steps"], 120);
    assert_eq!(v["seed"], 2);
    assert_eq!(v["map"]["name"], "maze");
    assert_eq!(v["map"]["width"], 202);
    assert_eq!(v["map"]["height"], 202);
    assert_eq!(v["map"]["resolution"], 0.05);
    assert_eq!(v["parameters"]["max_particles"], 300);
    assert_eq!(v["parameters"]["laser_model_type"], "likelihood_field");
    assert!(v["parameters"]["lidar"]["beams"].is_u64());
    let f = &v["filters"][0];
    assert_eq!(f["name"], "mcl");
    assert_eq!(f["particles"], 300);
    // Tracking from the true start converges at once.
    assert_eq!(f["converged_tick"], 0);
    assert!(f["position_error_final"].as_f64().unwrap() < 0.5);
    assert!(f["heading_error_final"].as_f64().unwrap() < 0.3);
    assert!(f["position_rmse_converged"].as_f64().unwrap() < 0.3);
    // Same seed, same numbers.
    let again = slamlab_output(&args);
    assert_eq!(out.stdout, again.stdout);
}

#[test]
fn bad_input_is_refused_or_clamped_with_a_message() {
    let out = slamlab_output(&["run", "kidnap", "--particles", "0", "--steps", "3"]);
    assert!(out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("particles = 0 is out of range; using 1")
    );
    let out = slamlab_output(&["run", "kidnap", "--laser-sigma-hit", "nan"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--laser-sigma-hit"));
    let out = slamlab_output(&["run", "kidnap", "--estimator", "ekf"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a comma-separated list of mcl"));
    let dir = Scratch::new("kidnap");
    let yaml = dir.join("m.yaml");
    std::fs::write(
        &yaml,
        "image: missing.png\nresolution: 0.05\norigin: [0, 0, 0]\n",
    )
    .unwrap();
    let out = slamlab_output(&["map", "info", yaml.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("missing.png"),
        "{err}"
    );
    std::fs::write(&yaml, "image: m.pgm\nresolution: -1\norigin: [0, 0, 0]\n").unwrap();
    let out = slamlab_output(&["map", "info", yaml.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("resolution -1"), "{err}");
}

#[test]
fn map_convert_and_info_round_trip() {
    let dir = Scratch::new("map");
    let pgm_yaml = dir.join("maze-pgm.yaml");
    let out = slamlab_output(&[
        "map",
        "convert",
        "maze",
        pgm_yaml.to_str().unwrap(),
        "--format",
        "pgm",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.join("maze-pgm.pgm").is_file());
    let png_yaml = dir.join("back.yaml");
    let out = slamlab_output(&[
        "map",
        "convert",
        pgm_yaml.to_str().unwrap(),
        png_yaml.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let a = slamlab_output(&["map", "info", "maze"]);
    let b = slamlab_output(&["map", "info", png_yaml.to_str().unwrap()]);
    let tail = |o: &std::process::Output| {
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .skip(1)
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(tail(&a), tail(&b));
    assert!(tail(&a).contains("202 x 202 cells"));
}

#[test]
fn experiment_kidnap_prints_its_json_and_csv() {
    let scratch = Scratch::new("kidnap-exp");
    // A folder that is not there yet: `--csv DIR` makes it.
    let dir = scratch.join("csv");
    let out = slamlab_output(&[
        "experiment",
        "kidnap",
        "--map",
        "maze",
        "--particles",
        "200,300",
        "--estimator",
        "amcl,acmcl",
        "--trials",
        "2",
        "--limit",
        "30",
        "--seed",
        "1",
        "--json",
        "--csv",
        dir.to_str().unwrap(),
    ]);
    let v = json(&out);
    assert_eq!(v["experiment"], "kidnap");
    assert_eq!(v["map"]["name"], "maze");
    assert!(v["parameters"]["recovery_alpha_fast"].is_f64());
    assert_eq!(v["protocol"]["limit_updates"], 30);
    let results = v["results"].as_array().unwrap();
    assert_eq!(results.len(), 4);
    for r in results {
        assert!(r["estimator"] == "amcl" || r["estimator"] == "acmcl");
        let failures = r["failures"].as_u64().unwrap();
        assert!(failures <= 2);
        assert!(r["steps_to_converge"]["median"].is_null() == (failures == 2));
        assert!(r["recovery_ratio"].as_f64().unwrap() >= 0.0);
    }
    let csv = std::fs::read_to_string(dir.join("kidnap_trials.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 8);
}
