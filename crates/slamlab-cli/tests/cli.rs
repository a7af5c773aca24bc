//! The `slamlab` binary as a user runs it.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

mod common;

use common::{Scratch, record_maze, run_json, slamlab};

const RUN: &[&str] = &[
    "run",
    "landmark-slam",
    "--estimator",
    "ekf",
    "--steps",
    "200",
    "--seed",
    "1",
    "--json",
];

#[test]
fn run_prints_the_documented_fields_all_finite() {
    let v = run_json(RUN);
    assert_eq!(v["steps"], 200);
    assert_eq!(v["seed"], 1);
    assert_eq!(v["estimator"], "ekf");
    for key in ["robot_rmse", "landmark_rmse", "nees_mean"] {
        let x = v[key].as_f64().unwrap_or(f64::NAN);
        assert!(x.is_finite() && x >= 0.0, "{key} = {}", v[key]);
    }
    // A lap of the teaching world keeps EKF-SLAM's errors at decimetres.
    assert!(v["robot_rmse"].as_f64().unwrap_or(f64::NAN) < 1.0);
    assert!(v["landmark_rmse"].as_f64().unwrap_or(f64::NAN) < 1.0);
    let p = &v["parameters"];
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
        "seed",
    ] {
        assert!(!p[key].is_null(), "parameter {key} missing from {p}");
    }
    assert_eq!(p["dt"], 0.1);
    assert_eq!(p["world-size"], 16.0);
    assert_eq!(v["filters"][0]["name"], "ekf");
}

#[test]
fn same_seed_same_numbers_other_seed_other_numbers() {
    let a = run_json(RUN);
    let b = run_json(RUN);
    assert_eq!(a, b);
    let c = run_json(&[
        "run",
        "landmark-slam",
        "--steps",
        "200",
        "--seed",
        "2",
        "--json",
    ]);
    assert_ne!(a["robot_rmse"], c["robot_rmse"]);
}

#[test]
fn scenario_flags_change_the_run() {
    let v = run_json(&[
        "run",
        "landmark-slam",
        "--steps",
        "50",
        "--landmarks",
        "5",
        "--fov-deg",
        "360",
        "--json",
    ]);
    assert_eq!(v["parameters"]["landmarks"], 5);
    assert!(
        v["filters"][0]["landmarks_initialized"]
            .as_u64()
            .unwrap_or(99)
            <= 5
    );
    let none = run_json(&[
        "run",
        "landmark-slam",
        "--steps",
        "50",
        "--landmarks",
        "0",
        "--json",
    ]);
    assert!(
        none["landmark_rmse"].is_null(),
        "no landmarks, no landmark error"
    );
    assert!(none["robot_rmse"].as_f64().unwrap_or(f64::NAN).is_finite());
}

#[test]
fn bad_values_are_refused_or_clamped_with_a_message() {
    let (ok, _, stderr) = slamlab(&["run", "landmark-slam", "--range-std", "NaN", "--json"]);
    assert!(!ok);
    assert!(stderr.contains("range-std"), "{stderr}");
    // A refused value says what was expected, in one line, and nothing about a
    // default that is not used.
    let (ok, _, stderr) = slamlab(&["run", "landmark-slam", "--seed", "abc"]);
    assert!(!ok);
    assert_eq!(
        stderr.trim(),
        "error: --seed 'abc' is not a whole number (0 or more)"
    );
    let (ok, stdout, stderr) = slamlab(&[
        "run",
        "landmark-slam",
        "--range-std",
        "0",
        "--steps",
        "20",
        "--json",
    ]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("out of range"), "{stderr}");
    assert!(stdout.contains("\"range-std\":0.001"), "{stdout}");
    let (ok, _, stderr) = slamlab(&["run", "no-such-lesson"]);
    assert!(!ok && stderr.contains("no-such-lesson"), "{stderr}");
}

#[test]
fn readable_summary_names_every_parameter() {
    let (ok, stdout, _) = slamlab(&["run", "landmark-slam", "--steps", "20"]);
    assert!(ok);
    for word in [
        "parameters:",
        "dt",
        "0.1 s",
        "world-size",
        "robot RMSE",
        "NEES",
    ] {
        assert!(stdout.contains(word), "missing {word} in\n{stdout}");
    }
}

#[test]
fn experiment_prints_the_documented_json_and_csv() {
    let scratch = Scratch::new("cli-test");
    // A folder that is not there yet: `--csv DIR` makes it.
    let dir = scratch.join("csv");
    let dir_arg = dir.to_string_lossy().into_owned();
    let v = run_json(&[
        "experiment",
        "ekf-vs-ukf",
        "--noise-scale",
        "2",
        "--trials",
        "4",
        "--seed",
        "1",
        "--json",
        "--csv",
        &dir_arg,
    ]);
    assert_eq!(v["experiment"], "ekf-vs-ukf");
    assert_eq!(v["parameters"]["noise-scale"], 2.0);
    assert_eq!(v["parameters"]["range-std"], 2.0);
    let filters = v["filters"].as_array().cloned().unwrap_or_default();
    assert_eq!(
        filters
            .iter()
            .map(|f| f["name"].as_str().unwrap_or(""))
            .collect::<Vec<_>>(),
        ["ekf", "ukf"]
    );
    for f in &filters {
        for key in [
            "robot_mse",
            "landmark_mse",
            "robot_mse_final",
            "landmark_mse_final",
            "robot_mse_std",
            "landmark_mse_std",
            "nees_mean",
        ] {
            assert!(
                f[key].as_f64().is_some_and(f64::is_finite),
                "{key} = {}",
                f[key]
            );
        }
        assert!(f["diverged"].as_u64().is_some());
    }
    let csv = std::fs::read_to_string(dir.join("ekf-vs-ukf-noise2-seed1-trials4.csv"))
        .unwrap_or_default();
    assert_eq!(csv.lines().count(), 201, "header + 200 steps");
    let (ok, _, stderr) = slamlab(&["experiment", "ekf-vs-ukf", "--noise-scale", "NaN"]);
    assert!(!ok && stderr.contains("noise-scale"), "{stderr}");
}

#[test]
fn both_estimators_run_side_by_side_from_the_command_line() {
    let v = run_json(&[
        "run",
        "landmark-slam",
        "--estimator",
        "ekf,ukf",
        "--steps",
        "100",
        "--ukf-alpha",
        "0.8",
        "--json",
    ]);
    let names: Vec<&str> = v["filters"]
        .as_array()
        .map(|a| a.iter().filter_map(|f| f["name"].as_str()).collect())
        .unwrap_or_default();
    assert_eq!(names, ["ekf", "ukf"]);
    assert_eq!(v["parameters"]["ukf-alpha"], 0.8);
    for f in v["filters"].as_array().into_iter().flatten() {
        assert!(
            f["robot_rmse"]
                .as_f64()
                .is_some_and(|x| x.is_finite() && x < 1.0),
            "{f}"
        );
    }
    let (ok, _, stderr) = slamlab(&[
        "run",
        "landmark-slam",
        "--estimator",
        "ukf",
        "--ukf-alpha",
        "0.1",
        "--ukf-kappa",
        "-9",
        "--json",
    ]);
    assert!(!ok && stderr.contains("ukf could not start"), "{stderr}");
}

#[test]
fn a_preset_sets_the_scenario_and_flags_apply_on_top() {
    let v = run_json(&[
        "run",
        "landmark-slam",
        "--landmarks",
        "10",
        "--preset",
        "thesis-exp2",
        "--seed",
        "3",
        "--steps",
        "20",
        "--json",
    ]);
    let p = &v["parameters"];
    assert_eq!(p["v-std"], 0.2, "{p}");
    assert_eq!(p["range-std"], 2.0, "{p}");
    assert_eq!(p["fov-deg"], 360.0, "{p}");
    assert_eq!(p["landmarks"], 10, "a flag beside the preset wins: {p}");
    assert_eq!(v["seed"], 3);
    let names: Vec<&str> = v["filters"]
        .as_array()
        .map(|a| a.iter().filter_map(|f| f["name"].as_str()).collect())
        .unwrap_or_default();
    assert_eq!(names, ["ekf", "ukf"]);
    let (ok, _, stderr) = slamlab(&["run", "landmark-slam", "--preset", "exp9"]);
    assert!(!ok);
    assert!(
        stderr.contains("--preset") && stderr.contains("thesis-exp1"),
        "{stderr}"
    );
}

#[test]
fn consistency_experiment_averages_nees_over_seeded_trials() {
    let scratch = Scratch::new("cli-consistency");
    let dir = scratch.join("csv");
    let dir_arg = dir.to_string_lossy().into_owned();
    let args = [
        "experiment",
        "consistency",
        "--estimator",
        "ekf,fej-ekf",
        "--trials",
        "6",
        "--steps",
        "80",
        "--seed",
        "3",
        "--json",
        "--csv",
        &dir_arg,
    ];
    let v = run_json(&args);
    assert_eq!(v["experiment"], "consistency");
    assert_eq!(v["trials_done"], 6);
    assert_eq!(v["parameters"]["trials"], 6);
    assert_eq!(v["parameters"]["steps"], 80);
    assert_eq!(v["parameters"]["seed"], 3);
    // The band of the average of 6 runs of a 3-dof statistic: chi2(18) quantiles / 6.
    let band = v["nees_band"].as_array().cloned().unwrap_or_default();
    let lo = band[0].as_f64().unwrap_or(f64::NAN);
    let hi = band[1].as_f64().unwrap_or(f64::NAN);
    assert!((lo - 8.230_746 / 6.0).abs() < 1e-5, "{lo}");
    assert!((hi - 31.526_38 / 6.0).abs() < 1e-5, "{hi}");
    let filters = v["filters"].as_array().cloned().unwrap_or_default();
    assert_eq!(filters.len(), 2);
    assert_eq!(filters[0]["name"], "ekf");
    assert_eq!(filters[1]["name"], "fej-ekf");
    // The whole-run average NEES is the mean of the trials' per-tick NEES: the
    // `run` command's own nees_mean, averaged over seeds 3..8 (every trial has
    // NEES on ticks 2..80).
    let mut expected = 0.0;
    for seed in 3..9 {
        let run = run_json(&[
            "run",
            "landmark-slam",
            "--estimator",
            "ekf",
            "--steps",
            "80",
            "--seed",
            &seed.to_string(),
            "--json",
        ]);
        expected += run["nees_mean"].as_f64().unwrap_or(f64::NAN) / 6.0;
    }
    let got = filters[0]["nees_mean"].as_f64().unwrap_or(f64::NAN);
    assert!((got - expected).abs() < 1e-9, "{got} vs {expected}");
    for f in &filters {
        let in_band = f["ticks_in_band"].as_f64().unwrap_or(f64::NAN);
        assert!((0.0..=1.0).contains(&in_band), "{in_band}");
        assert!(f["nis_mean"].as_f64().is_some_and(|n| n > 0.0 && n < 10.0));
        assert_eq!(f["diverged"], 0);
    }
    let csv =
        std::fs::read_to_string(dir.join("consistency-ekf-fej-ekf-seed3-trials6-steps80.csv"))
            .unwrap_or_default();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 81, "header + 80 ticks");
    assert_eq!(
        lines[0],
        "step,time_s,band_lo,band_hi,ekf_nees,fej-ekf_nees"
    );
    // Same seed, same numbers.
    assert_eq!(run_json(&args[..args.len() - 2]), v);

    // Flags that do not belong to the experiment are refused with the reason.
    let (ok, _, stderr) = slamlab(&["experiment", "ekf-vs-ukf", "--landmarks", "5"]);
    assert!(
        !ok && stderr.contains("--landmarks") && stderr.contains("consistency"),
        "{stderr}"
    );
    let (ok, _, stderr) = slamlab(&["experiment", "consistency", "--noise-scale", "2"]);
    assert!(!ok && stderr.contains("--noise-scale"), "{stderr}");
    let (ok, _, stderr) = slamlab(&["experiment", "consistency", "--controller", "manual"]);
    assert!(!ok && stderr.contains("manual"), "{stderr}");
    let (ok, _, stderr) = slamlab(&["experiment", "consistency", "--range-std", "NaN"]);
    assert!(!ok && stderr.contains("range-std"), "{stderr}");
}

#[test]
fn a_run_that_cannot_go_as_asked_is_refused_with_the_reason() {
    // λ + n ≤ 0: the UKF cannot start, and no result pretends it ran.
    for command in [
        &["run", "landmark-slam", "--json"][..],
        &["experiment", "consistency", "--trials", "2", "--json"][..],
    ] {
        let args: Vec<&str> = command
            .iter()
            .copied()
            .chain(["--estimator", "ekf,ukf", "--ukf-kappa", "-10"])
            .collect();
        let (ok, stdout, stderr) = slamlab(&args);
        assert!(!ok, "{args:?} succeeded: {stdout}");
        assert!(stdout.is_empty(), "{args:?}: {stdout}");
        assert!(
            stderr.contains("ukf could not start") && stderr.contains("kappa"),
            "{args:?}: {stderr}"
        );
    }
    // Nobody drives a hand-driven robot headless, and its circle speed means nothing.
    let (ok, _, stderr) = slamlab(&["run", "landmark-slam", "--controller", "manual"]);
    assert!(!ok && stderr.contains("nobody to drive"), "{stderr}");
    let (ok, _, stderr) = slamlab(&["run", "landmark-slam", "--controller", "manual", "--v", "2"]);
    assert!(!ok && stderr.contains("v was ignored"), "{stderr}");
}

/// A scenario file the app exported runs the same as its flags; flags on the command
/// line win; a file of another lesson, a bad file and a missing file are refused.
#[test]
fn a_scenario_file_runs_like_its_flags() {
    let dir = Scratch::new("scenario");
    let file = dir.join("lesson.json");
    std::fs::write(
        &file,
        r#"{
  "format": "slamlab-scenario",
  "version": 1,
  "lesson": "landmark-slam",
  "params": {
    "seed": "3",
    "estimator": "ekf",
    "landmarks": "30",
    "range-std": "0.25"
  },
  "view": {
    "tick": "120"
  }
}
"#,
    )
    .unwrap();
    let path = file.to_string_lossy().into_owned();
    let flags = run_json(&[
        "run",
        "landmark-slam",
        "--seed",
        "3",
        "--estimator",
        "ekf",
        "--landmarks",
        "30",
        "--range-std",
        "0.25",
        "--steps",
        "50",
        "--json",
    ]);
    let from_file = run_json(&["run", "--scenario", &path, "--steps", "50", "--json"]);
    assert_eq!(from_file["robot_rmse"], flags["robot_rmse"]);
    assert_eq!(from_file["parameters"], flags["parameters"]);
    // A flag on the command line wins over the file's value.
    let seed_5 = run_json(&[
        "run",
        "landmark-slam",
        &format!("--scenario={path}"),
        "--seed",
        "5",
        "--steps",
        "50",
        "--json",
    ]);
    assert_eq!(seed_5["seed"], 5);
    assert_eq!(
        seed_5["parameters"]["landmarks"],
        flags["parameters"]["landmarks"]
    );

    let fusion = dir.join("fusion.json");
    std::fs::write(
        &fusion,
        r#"{"format":"slamlab-scenario","version":1,"lesson":"fusion","params":{}}"#,
    )
    .unwrap();
    let fusion = fusion.to_string_lossy().into_owned();
    let (ok, _, stderr) = slamlab(&["run", "--scenario", &fusion]);
    assert!(
        !ok && stderr.contains("scenario of the fusion lesson"),
        "{stderr}"
    );
    let (ok, _, stderr) = slamlab(&["run", "kidnap", "--scenario", &path]);
    assert!(!ok && stderr.contains("not kidnap"), "{stderr}");
    let bad = dir.join("bad.json");
    std::fs::write(&bad, "{ not json").unwrap();
    let (ok, _, stderr) = slamlab(&["run", "--scenario", &bad.to_string_lossy()]);
    assert!(!ok && stderr.contains("does not parse"), "{stderr}");
    let (ok, _, stderr) = slamlab(&["run", "--scenario", "/nonexistent/x.json"]);
    assert!(!ok && stderr.contains("reading the scenario"), "{stderr}");
    let (ok, _, stderr) = slamlab(&["run", "--scenario"]);
    assert!(!ok && stderr.contains("needs a file"), "{stderr}");
    // The kidnap lesson's file: an app-only key is skipped with a warning.
    let kidnap = dir.join("kidnap.json");
    std::fs::write(
        &kidnap,
        r#"{"format":"slamlab-scenario","version":1,"lesson":"kidnap",
            "params":{"seed":"2","particles":"300","estimator":"mcl","init":"tracking","nope":"1"}}"#,
    )
    .unwrap();
    let (ok, stdout, stderr) = slamlab(&[
        "run",
        "--scenario",
        &kidnap.to_string_lossy(),
        "--steps",
        "20",
        "--json",
    ]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("`nope` is not a flag"), "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["seed"], 2, "{v}");
}

#[test]
fn log_record_writes_a_carmen_log_and_its_truth_that_log_info_reads() {
    let dir = Scratch::new("cli-log");
    let log = dir.join("maze.clf");
    let log_s = log.to_str().unwrap();
    let stdout = record_maze(&log, 40, 2);
    assert!(stdout.contains("40 scans of 360 beams"), "{stdout}");
    let truth = std::fs::read_to_string(dir.join("maze.clf.truth")).unwrap();
    let lines: Vec<&str> = truth.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(lines.len(), 40);
    assert!(lines[0].starts_with("0.100000 "), "{}", lines[0]);
    assert!(lines[39].starts_with("4.000000 "), "{}", lines[39]);

    let v = run_json(&["log", "info", log_s, "--json"]);
    assert_eq!(v["compression"], "plain");
    assert_eq!(v["scans"], 40);
    assert_eq!(v["scan_records"]["FLASER"], 40);
    assert_eq!(v["odometry"], 40);
    assert_eq!(v["beams"], 360);
    assert_eq!(v["max_range"], 12.0);
    assert!((v["fov_deg"].as_f64().unwrap() - 360.0).abs() < 1e-6, "{v}");
    assert_eq!(v["first_timestamp"], 0.1);
    assert_eq!(v["last_timestamp"], 4.0);
    assert_eq!(v["params"]["slamlab_map"], "maze");
    assert_eq!(v["params"]["slamlab_seed"], "2");
    assert_eq!(v["unusable_readings"], 0);
    let (ok, stdout, _) = slamlab(&["log", "info", log_s]);
    assert!(
        ok && stdout.contains("scans:       40 (40 FLASER)"),
        "{stdout}"
    );

    // Bad input: a message naming the line, no panic.
    let bad = dir.join("bad.clf");
    std::fs::write(&bad, "FLASER 3 1 2\n").unwrap();
    let (ok, _, stderr) = slamlab(&["log", "info", bad.to_str().unwrap()]);
    assert!(
        !ok && stderr.contains("line 1: malformed FLASER record"),
        "{stderr}"
    );
    let (ok, _, stderr) = slamlab(&["log", "info", dir.join("missing.clf").to_str().unwrap()]);
    assert!(!ok && stderr.contains("cannot read"), "{stderr}");
    let (ok, _, stderr) = slamlab(&["log", "record", "--map", "nowhere.yaml", "--out", log_s]);
    assert!(!ok && stderr.contains("nowhere.yaml"), "{stderr}");
}

/// `slamlab run kidnap --log`: a simulated run recorded as a bag (with its truth)
/// and converted to CARMEN (without), localized globally in the maze it was
/// recorded in.
#[test]
fn run_kidnap_localizes_a_recorded_bag_and_its_carmen_copy() {
    let dir = Scratch::new("cli-kidnap-log");
    let bag = dir.join("run.mcap");
    let bag_s = bag.to_str().unwrap();
    record_maze(&bag, 400, 3);
    let args = [
        "--map",
        "maze",
        "--seed",
        "1",
        "--estimator",
        "mcl,acmcl",
        "--json",
    ];
    let mut with_bag = vec!["run", "kidnap", "--log", bag_s];
    with_bag.extend(args);
    let v = run_json(&with_bag);
    assert_eq!(v["log"]["scans"], 400);
    assert_eq!(v["log"]["replayed"], 400);
    assert_eq!(v["log"]["truth"], true);
    assert_eq!(v["log"]["name"], "run.mcap (/scan, odometry /odom)");
    // The numbers of the sim's replay test: the same bag, seed and filters.
    assert_eq!(v["filters"][0]["converged_tick"], 86);
    assert_eq!(v["filters"][1]["converged_tick"], 71);
    for f in v["filters"].as_array().unwrap() {
        assert!(f["position_rmse_converged"].as_f64().unwrap() < 0.12, "{f}");
    }

    let clf = dir.join("run.clf");
    let clf_s = clf.to_str().unwrap();
    let (ok, _, stderr) = slamlab(&["log", "convert", bag_s, "--out", clf_s]);
    assert!(ok, "{stderr}");
    let mut with_log = vec!["run", "kidnap", "--log", clf_s];
    with_log.extend(args);
    let v = run_json(&with_log);
    assert_eq!(v["log"]["truth"], false);
    assert!(v["filters"][0]["position_error_final"].is_null());
    // Against the truth file beside the log, the last line: the robot was found.
    let truth = std::fs::read_to_string(dir.join("run.clf.truth")).unwrap();
    let last: Vec<f64> = truth
        .lines()
        .rfind(|l| !l.starts_with('#'))
        .unwrap()
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    for e in v["final_estimates"].as_array().unwrap() {
        let (x, y) = (e["x"].as_f64().unwrap(), e["y"].as_f64().unwrap());
        let d = ((x - last[1]).powi(2) + (y - last[2]).powi(2)).sqrt();
        assert!(d < 0.15, "{e}: {d} m from the truth");
    }
    let (ok, stdout, _) = slamlab(&[
        "run", "kidnap", "--map", "maze", "--log", clf_s, "--steps", "50",
    ]);
    assert!(ok, "{stdout}");
    assert!(stdout.contains("50 of 400 scans"), "{stdout}");
    assert!(stdout.contains("no truth: errors unknown"), "{stdout}");
    // A topic that is not in the bag: the message names it.
    let (ok, _, stderr) = slamlab(&["run", "kidnap", "--log", bag_s, "--scan-topic", "/front"]);
    assert!(!ok && stderr.contains("\"/front\""), "{stderr}");
}

/// A square of four poses with a loop closure that disagrees a little.
const SQUARE_G2O: &str = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1.1 0 1.6\nVERTEX_SE2 2 1.0 1.1 3.1\nVERTEX_SE2 3 0 0.9 -1.5\n\
     EDGE_SE2 0 1 1 0 1.5708 100 0 0 100 0 1000\nEDGE_SE2 1 2 1 0 1.5708 100 0 0 100 0 1000\n\
     EDGE_SE2 2 3 1 0 1.5708 100 0 0 100 0 1000\nEDGE_SE2 3 0 1.02 0 1.5708 100 0 0 100 0 1000\n";

#[test]
fn graph_evaluate_scores_an_optimized_graph_against_the_reference_solver() {
    let dir = Scratch::new("graph-evaluate");
    let problem = dir.join("square.g2o");
    let optimized = dir.join("optimized.g2o");
    let truth = dir.join("truth.tum");
    std::fs::write(&problem, SQUARE_G2O).unwrap();
    std::fs::write(
        &truth,
        "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0.7071067811865476 0.7071067811865476\n\
         2 1 1 0 0 0 1 0\n3 0 1 0 0 0 -0.7071067811865476 0.7071067811865476\n",
    )
    .unwrap();
    let (p, o, t) = (
        problem.to_str().unwrap(),
        optimized.to_str().unwrap(),
        truth.to_str().unwrap(),
    );
    let (ok, _, stderr) = slamlab(&["graph", "optimize", p, "--solver", "gn", "--out", o]);
    assert!(ok, "{stderr}");
    // The lesson's solver's own output scores its own final cost.
    let (ok, stdout, stderr) = slamlab(&["graph", "evaluate", p, o, "--truth", t, "--json"]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let (cost, reference) = (
        v["cost"].as_f64().unwrap(),
        v["reference_cost"].as_f64().unwrap(),
    );
    assert!(reference > 0.0 && reference < v["initial_cost"].as_f64().unwrap());
    assert!((cost - reference).abs() <= 1e-9 * reference, "{v}");
    assert!((v["cost_ratio"].as_f64().unwrap() - 1.0).abs() <= 1e-9);
    let ate = v["ate"]["ape"]["translation"]["rmse"].as_f64().unwrap();
    let reference_ate = v["reference_ate"]["ape"]["translation"]["rmse"]
        .as_f64()
        .unwrap();
    assert!((ate - reference_ate).abs() < 1e-9 && ate < 0.05, "{ate}");
    // The problem as its own answer scores its initial cost.
    let (ok, stdout, stderr) = slamlab(&["graph", "evaluate", p, p, "--json"]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["cost"], v["initial_cost"]);
    assert!(v["cost_ratio"].as_f64().unwrap() > 1.0);
    // A vertex missing: refused, naming it.
    let missing = dir.join("missing.g2o");
    let without_2: String = SQUARE_G2O
        .lines()
        .filter(|l| !l.starts_with("VERTEX_SE2 2 ") && !l.contains(" 2 ") || l.contains(" 0 1 "))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&missing, without_2).unwrap();
    let (ok, _, stderr) = slamlab(&["graph", "evaluate", p, missing.to_str().unwrap()]);
    assert!(!ok);
    assert!(stderr.contains("missing.g2o"), "{stderr}");
    assert!(
        stderr.contains("vertex 2 of the problem is missing"),
        "{stderr}"
    );
}
