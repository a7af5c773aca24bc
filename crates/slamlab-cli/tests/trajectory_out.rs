//! `--trajectory-out DIR` on every lesson run that has trajectories, and on
//! `slamlab graph optimize`: the files are there, read back, and score as the
//! run scored itself.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

mod common;

use common::{Scratch, slamlab_stdout};

use slamlab_sim::io::trajectory::{read_landmarks, read_trajectory};
use std::path::{Path, PathBuf};

/// A scratch folder for one test and the `--trajectory-out` folder inside it,
/// not there yet (the flag makes it). Keep the scratch folder while the test
/// runs: dropped, it goes.
fn out_dir(name: &str) -> (Scratch, PathBuf) {
    let scratch = Scratch::new(&format!("trajout-{name}"));
    let dir = scratch.join("out");
    (scratch, dir)
}

fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn trajectory(dir: &Path, name: &str) -> slamlab_sim::metrics::Trajectory {
    let bytes = std::fs::read(dir.join(name)).unwrap();
    read_trajectory(name, &bytes).unwrap().trajectory
}

#[test]
fn landmark_runs_write_their_paths_and_maps() {
    let (_scratch, dir) = out_dir("landmark");
    let d = dir.to_str().unwrap();
    let summary: serde_json::Value = serde_json::from_str(&slamlab_stdout(&[
        "run",
        "landmark-slam",
        "--estimator",
        "ekf,ukf",
        "--steps",
        "150",
        "--seed",
        "3",
        "--json",
        "--trajectory-out",
        d,
    ]))
    .unwrap();
    assert_eq!(
        names(&dir),
        [
            "README.txt",
            "dead-reckoning.csv",
            "dead-reckoning.tum",
            "ekf-landmarks.csv",
            "ekf.csv",
            "ekf.tum",
            "truth-landmarks.csv",
            "truth.csv",
            "truth.tum",
            "ukf-landmarks.csv",
            "ukf.csv",
            "ukf.tum",
        ]
    );
    assert_eq!(trajectory(&dir, "truth.tum").len(), 151);
    assert_eq!(
        trajectory(&dir, "ekf.csv").covariances().map(<[_]>::len),
        Some(151)
    );
    assert!(
        !read_landmarks(&std::fs::read(dir.join("ekf-landmarks.csv")).unwrap())
            .unwrap()
            .is_empty()
    );
    // The run's mean NEES is the evaluation's ANEES of the exported file (the start,
    // with its zero covariance, has none in either).
    let evaluation: serde_json::Value = serde_json::from_str(&slamlab_stdout(&[
        "evaluate",
        "--estimate",
        &format!("{d}/ekf.csv"),
        "--reference",
        &format!("{d}/truth.tum"),
        "--align",
        "none",
        "--json",
    ]))
    .unwrap();
    let run_nees = summary["filters"][0]["nees_mean"].as_f64().unwrap();
    let anees = evaluation["nees"]["anees"].as_f64().unwrap();
    assert!(
        (run_nees - anees).abs() < 1e-9 * run_nees,
        "{run_nees} against {anees}"
    );
}

#[test]
fn laser_and_camera_runs_write_their_paths() {
    let cases: [(&[&str], &[&str]); 4] = [
        (
            &[
                "run",
                "kidnap",
                "--steps",
                "40",
                "--estimator",
                "amcl,acmcl",
            ],
            &["acmcl.tum", "amcl.tum", "truth.tum"],
        ),
        (
            &["run", "mapping", "--steps", "60", "--poses", "scan-to-map"],
            &["odometry.tum", "scan-to-map.tum", "truth.tum"],
        ),
        (
            &["run", "cartographer", "--steps", "60"],
            &["cartographer.tum", "odometry.tum", "truth.tum"],
        ),
        (
            &["run", "visual-odometry"],
            &[
                "truth.tum",
                "visual-odometry-unit-scale.tum",
                "visual-odometry.tum",
                "wheel-odometry.tum",
            ],
        ),
    ];
    for (args, expected) in cases {
        let (_scratch, dir) = out_dir(args[1]);
        let mut all = args.to_vec();
        all.extend(["--trajectory-out", dir.to_str().unwrap()]);
        slamlab_stdout(&all);
        let files = names(&dir);
        for name in expected {
            assert!(
                files.contains(&(*name).to_owned()),
                "{}: {name} missing from {files:?}",
                args[1]
            );
            let t = trajectory(&dir, name);
            assert!(t.len() > 10, "{}: {name} has {} poses", args[1], t.len());
            let csv = trajectory(&dir, &name.replace(".tum", ".csv"));
            assert_eq!(csv.len(), t.len());
        }
    }
}

#[test]
fn graph_optimize_writes_the_optimized_poses() {
    let (scratch, dir) = out_dir("graph");
    let graph = scratch.join("square.g2o");
    // A square of four poses with a loop closure that disagrees a little.
    std::fs::write(
        &graph,
        "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1.1 0 1.6\nVERTEX_SE2 2 1.0 1.1 3.1\nVERTEX_SE2 3 0 0.9 -1.5\n\
         EDGE_SE2 0 1 1 0 1.5708 100 0 0 100 0 1000\nEDGE_SE2 1 2 1 0 1.5708 100 0 0 100 0 1000\n\
         EDGE_SE2 2 3 1 0 1.5708 100 0 0 100 0 1000\nEDGE_SE2 3 0 1 0 1.5708 100 0 0 100 0 1000\n",
    )
    .unwrap();
    slamlab_stdout(&[
        "graph",
        "optimize",
        graph.to_str().unwrap(),
        "--trajectory-out",
        dir.to_str().unwrap(),
    ]);
    let t = trajectory(&dir, "optimized.tum");
    assert_eq!(t.stamps(), &[0.0, 1.0, 2.0, 3.0]);
    let p = t.poses()[2];
    assert!(
        (p.x - 1.0).abs() < 1e-3 && (p.y - 1.0).abs() < 1e-3,
        "{p:?}"
    );
}
