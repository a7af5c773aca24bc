//! `slamlab export-inputs` and `slamlab grade`, run as a student and an
//! instructor would: the folder holds the same bytes as the page's download,
//! the answers grade perfectly, a grade's JSON and Gradescope's results.json say
//! the same as the library, a class is graded from a roster, and the starter
//! code's output (Python with numpy, in a throwaway virtual environment) is
//! graded as the page grades it.
#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

mod common;

use common::{Scratch, python_venv, slamlab};

use slamlab_sim::assignments::{builtin, prepare};
use std::path::{Path, PathBuf};
use std::process::Command;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn exported_inputs_are_the_pages_bytes_and_the_answers_grade_perfectly() {
    let dir = Scratch::new("assign-export");
    let out = dir.join("ada");
    let export = |more: &[&str]| {
        let args: &[&str] = &["export-inputs", "ekf-slam", "--student", "ada@uni.edu"];
        slamlab(&[args, &["--out", s(&out)], more].concat())
    };
    let (ok, stdout, stderr) = export(&["--answers"]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("variant") && stdout.contains("world.dat"),
        "{stdout}"
    );
    let prepared = prepare(&builtin("ekf-slam").unwrap(), "ada@uni.edu").unwrap();
    for (path, bytes) in prepared.input_files(true).files {
        assert_eq!(std::fs::read(out.join(&path)).unwrap(), bytes, "{path}");
    }
    // Writing again over the same folder is refused; nothing is lost.
    let (ok, _, stderr) = export(&[]);
    assert!(
        !ok && stderr.contains("already holds") && stderr.contains("--force"),
        "{stderr}"
    );

    let truth = out.join("answers/truth.tum");
    let gradescope = dir.join("results.json");
    let (ok, stdout, stderr) = slamlab(&[
        "grade",
        "ekf-slam",
        "--student",
        "ada@uni.edu",
        "--estimate",
        s(&truth),
        "--json",
        "--gradescope",
        s(&gradescope),
    ]);
    assert!(ok, "{stderr}");
    let grade: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(grade["score"], 100.0);
    assert_eq!(grade["max_score"], 100.0);
    assert_eq!(grade["pass"], true);
    assert_eq!(grade["criteria"][0]["metric"], "ate_rmse");
    assert!(grade["criteria"][0]["value"].as_f64().unwrap() < 1e-6);
    assert_eq!(grade["criteria"][0]["threshold"], 0.5);
    assert_eq!(grade["criteria"][0]["points"], 70.0);
    assert_eq!(
        grade["estimate_sha256"].as_str().unwrap(),
        slamlab_sim::coursework::sha256_hex(&std::fs::read(&truth).unwrap())
    );
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&gradescope).unwrap()).unwrap();
    assert_eq!(results["score"], 100.0);
    assert_eq!(results["max_score"], 100.0);
    let tests = results["tests"].as_array().unwrap();
    assert_eq!(tests.len(), 2);
    assert_eq!(tests[0]["max_score"], 70.0);
    assert_eq!(tests[0]["status"], "passed");
    assert!(tests[0]["output"].as_str().unwrap().contains("ekf"));

    // Another student's grade of Ada's truth: refused, saying why.
    let (ok, _, stderr) = slamlab(&[
        "grade",
        "ekf-slam",
        "--student",
        "alan@uni.edu",
        "--estimate",
        s(&truth),
    ]);
    assert!(!ok && stderr.contains("variant"), "{stderr}");
}

#[test]
fn bad_assignments_and_students_are_refused_with_a_message() {
    let dir = Scratch::new("assign-bad");
    let (ok, _, stderr) = slamlab(&[
        "export-inputs",
        "ekf_slam",
        "--student",
        "a",
        "--out",
        s(&dir.join("x")),
    ]);
    assert!(
        !ok && stderr.contains("ekf-slam, mcl, pose-graph, grid-mapping"),
        "{stderr}"
    );
    let json = dir.join("hw3.json");
    let text = slamlab_sim::coursework::BUILTIN[0]
        .1
        .replace(r#""threshold": 0.5"#, r#""threshold": -1"#);
    std::fs::write(&json, text).unwrap();
    let (ok, _, stderr) = slamlab(&[
        "export-inputs",
        s(&json),
        "--student",
        "a",
        "--out",
        s(&dir.join("x")),
    ]);
    assert!(
        !ok && stderr.contains("hw3.json") && stderr.contains("threshold -1"),
        "{stderr}"
    );
    let (ok, _, stderr) = slamlab(&[
        "export-inputs",
        "mcl",
        "--student",
        "  ",
        "--out",
        s(&dir.join("x")),
    ]);
    assert!(!ok && stderr.contains("--student is empty"), "{stderr}");
}

#[test]
fn a_class_is_graded_from_a_roster() {
    let dir = Scratch::new("assign-class");
    let estimates = dir.join("estimates");
    std::fs::create_dir_all(estimates.join("grace@uni.edu")).unwrap();
    let a = builtin("ekf-slam").unwrap();
    // Ada hands in the reference EKF, Grace dead reckoning, Alan nothing.
    let tum = |student: &str, which: usize| {
        let p = prepare(&a, student).unwrap();
        slamlab_sim::io::trajectory::write_tum(&p.references().unwrap()[which].1)
    };
    std::fs::write(estimates.join("ada@uni.edu.tum"), tum("ada@uni.edu", 0)).unwrap();
    std::fs::write(
        estimates.join("grace@uni.edu/estimate.tum"),
        tum("grace@uni.edu", 1),
    )
    .unwrap();
    let roster = dir.join("roster.csv");
    std::fs::write(
        &roster,
        "name,student\nAda,ada@uni.edu\nAlan,alan@uni.edu\nGrace,grace@uni.edu\n",
    )
    .unwrap();
    let grades = dir.join("grades.csv");
    let (ok, _, stderr) = slamlab(&[
        "grade",
        "ekf-slam",
        "--students",
        s(&roster),
        "--estimates",
        s(&estimates),
        "--out",
        s(&grades),
    ]);
    assert!(ok, "{stderr}");
    let csv = std::fs::read_to_string(&grades).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(
        rows[0],
        [
            "student",
            "variant",
            "score",
            "max_score",
            "pass",
            "ate_rmse",
            "final_position_error",
            "estimate",
            "estimate_sha256",
            "error"
        ]
    );
    assert_eq!(rows.len(), 4, "{csv}");
    assert_eq!(
        (rows[1][0], rows[1][2], rows[1][4]),
        ("ada@uni.edu", "100", "true")
    );
    assert_eq!(
        (rows[2][0], rows[2][2], rows[2][4]),
        ("alan@uni.edu", "0", "false")
    );
    assert!(rows[2][9].contains("no estimate"), "{csv}");
    assert_eq!((rows[3][0], rows[3][4]), ("grace@uni.edu", "false"));
    assert!(rows[3][5].parse::<f64>().unwrap() > 0.5, "{csv}");
}

/// A Python with numpy: `$SLAMLAB_NUMPY_PYTHON`, the system's, or a new
/// virtual environment with numpy from PyPI.
fn python_with_numpy(dir: &Path) -> Option<PathBuf> {
    let has_numpy = |python: &Path| {
        Command::new(python)
            .args(["-c", "import numpy"])
            .stderr(std::process::Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    };
    if let Some(p) = std::env::var_os("SLAMLAB_NUMPY_PYTHON") {
        return Some(PathBuf::from(p));
    }
    if has_numpy(Path::new("python3")) {
        return Some(PathBuf::from("python3"));
    }
    let python = python_venv(dir, &["numpy"], "(no python3 with numpy)")?.join("python");
    if !has_numpy(&python) {
        eprintln!("skipped: numpy could not be installed from PyPI");
        return None;
    }
    Some(python)
}

/// The starter code of the built-in assignments runs, writes an estimate
/// `slamlab grade` reads, and scores exactly what the library (the page's grader)
/// computes: dead reckoning, raw odometry, a graph's initial guess, a
/// two-view pose without rotation, straight ahead, and the fusion drive's
/// dead reckoning failing.
#[test]
fn the_starter_code_writes_an_estimate_that_grades_as_in_the_page() {
    let dir = Scratch::new("assign-starter");
    let Some(python) = python_with_numpy(&dir) else {
        return;
    };
    for (name, naive, extra, file) in [
        ("ekf-slam", "dead-reckoning", None, "estimate.tum"),
        (
            "ekf-slam",
            "dead-reckoning",
            Some("--odometry"),
            "estimate.tum",
        ),
        ("mcl", "odometry", None, "estimate.tum"),
        ("pose-graph", "initial-guess", None, "estimate.g2o"),
        ("grid-mapping", "all free", None, "map.zip"),
        ("grid-mapping", "all free", None, "map.yaml"),
        ("icp", "odometry", None, "pose.txt"),
        ("two-view", "naive", None, "pose.txt"),
        ("fusion", "dead-reckoning", None, "estimate.tum"),
    ] {
        let out = dir.join(format!("{name}-{}-{file}", extra.is_some()));
        let (ok, _, stderr) = slamlab(&[
            "export-inputs",
            name,
            "--student",
            "ada@uni.edu",
            "--out",
            s(&out),
        ]);
        assert!(ok, "{stderr}");
        let estimate = out.join(file);
        let mut cmd = Command::new(&python);
        cmd.arg(out.join("starter.py"));
        if let Some(flag) = extra {
            cmd.arg(flag);
        }
        // The grid-mapping starter writes map.zip and, beside it, map.yaml and
        // map.pgm: graded as the zip or through the YAML.
        let written = if file == "map.yaml" {
            out.join("map.zip")
        } else {
            estimate.clone()
        };
        let run = cmd.arg(&written).output().unwrap();
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let (ok, stdout, stderr) = slamlab(&[
            "grade",
            name,
            "--student",
            "ada@uni.edu",
            "--estimate",
            s(&estimate),
            "--json",
        ]);
        assert!(ok, "{stderr}");
        let cli: serde_json::Value = serde_json::from_str(&stdout).unwrap();
        let bytes = std::fs::read(&written).unwrap();
        let page = prepare(&builtin(name).unwrap(), "ada@uni.edu")
            .unwrap()
            .grade(s(&estimate), &bytes)
            .unwrap();
        // Compared as text: serde_json's default float parsing may be one ulp
        // off, the printed shortest representations are exact. (A map given
        // by its YAML is zipped by the command line: other bytes, the same
        // values.)
        if file == "map.yaml" {
            for (k, c) in page.criteria.iter().enumerate() {
                assert_eq!(
                    cli["criteria"][k]["value"].to_string(),
                    serde_json::to_string(&c.value).unwrap()
                );
            }
        } else {
            assert_eq!(
                stdout.trim(),
                serde_json::to_string_pretty(&page).unwrap(),
                "{name}"
            );
        }
        assert_eq!(cli["pass"], false, "{name}: {stdout}");
        // The starter is the naive reference, to the printed precision.
        let value = page.criteria[0].value.unwrap();
        let reference = page.criteria[0]
            .references
            .iter()
            .find(|r| r.name == naive)
            .and_then(|r| r.value)
            .unwrap();
        assert!(
            (value - reference).abs() < 1e-6,
            "{name} {extra:?}: {value} vs {reference}"
        );
    }
}
