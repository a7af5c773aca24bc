//! `slamlab evaluate` against evo itself: the same TUM files through `evo_ape` and
//! `evo_rpe` (PyPI's evo, installed in a throwaway virtual environment) and
//! through SLAM Lab give the same statistics to 1e-6 relative, with and without
//! alignment, with a scale error, with missing and jittered times, and with an
//! estimate at another rate than its reference.
//!
//! Skipped with a message when the virtual environment cannot be made (no
//! network, no `python3 -m venv`). `SLAMLAB_EVO_PYTHON=/path/to/python` uses a
//! Python that already has evo.
#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

mod common;

use common::{Scratch, json, python_venv, slamlab_output};

use slamlab_core::{Pose2, math};
use slamlab_sim::io::trajectory::write_tum;
use slamlab_sim::metrics::{Similarity, Trajectory};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The evo release the numbers were checked against.
const EVO: &str = "evo==1.38.1";

/// Runs one `evo_ape`/`evo_rpe` command line and prints its statistics as JSON.
const EVO_STATS: &str = r#"
import json, subprocess, sys, tempfile, zipfile, os
out = os.path.join(tempfile.mkdtemp(), "r.zip")
cmd = sys.argv[1:] + ["--save_results", out, "--no_warnings"]
subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
with zipfile.ZipFile(out) as z:
    print(json.dumps(json.loads(z.read("stats.json"))))
"#;

struct Evo {
    python: PathBuf,
    bin: PathBuf,
    script: PathBuf,
}

/// A Python with evo: `$SLAMLAB_EVO_PYTHON`, or a new virtual environment.
fn evo(dir: &Path) -> Option<Evo> {
    let script = dir.join("evo_stats.py");
    std::fs::write(&script, EVO_STATS).ok()?;
    if let Some(python) = std::env::var_os("SLAMLAB_EVO_PYTHON") {
        let python = PathBuf::from(python);
        let bin = python.parent()?.to_path_buf();
        return Some(Evo {
            python,
            bin,
            script,
        });
    }
    let bin = python_venv(dir, &[EVO], "(no evo to compare with)")?;
    Some(Evo {
        python: bin.join("python"),
        bin,
        script,
    })
}

impl Evo {
    /// `evo_ape`/`evo_rpe` with `args`, its statistics.
    fn stats(&self, tool: &str, args: &[&str]) -> serde_json::Value {
        let output = Command::new(&self.python)
            .arg(&self.script)
            .arg(self.bin.join(tool))
            .args(args)
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "{tool} {args:?}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        serde_json::from_slice(&output.stdout).unwrap()
    }
}

/// `slamlab evaluate --json` with `args`.
fn slamlab(args: &[&str]) -> serde_json::Value {
    json(&slamlab_output(
        &[&["evaluate"], args, &["--json"]].concat(),
    ))
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()) + 1e-12
}

/// The statistics evo and SLAM Lab share agree to 1e-6 relative.
fn assert_same(what: &str, evo: &serde_json::Value, ours: &serde_json::Value) {
    for key in ["rmse", "mean", "median", "std", "min", "max", "sse"] {
        let (a, b) = (evo[key].as_f64().unwrap(), ours[key].as_f64().unwrap());
        assert!(
            close(a, b),
            "{what}: {key} is {b} in SLAM Lab and {a} in evo"
        );
    }
}

/// A reference drive (curves, a loop) sampled at `rate` Hz for `seconds`.
fn reference(rate: f64, seconds: f64) -> Trajectory {
    let n = (rate * seconds) as usize;
    let stamps: Vec<f64> = (0..n).map(|k| 1_000.0 + k as f64 / rate).collect();
    let poses = (0..n)
        .map(|k| {
            let t = k as f64 / rate;
            let (x, y) = (
                6.0 * math::sin(0.11 * t),
                4.0 * math::sin(0.17 * t) + 0.02 * t,
            );
            let (dx, dy) = (
                0.66 * math::cos(0.11 * t),
                0.68 * math::cos(0.17 * t) + 0.02,
            );
            Pose2::new(x, y, math::atan2(dy, dx))
        })
        .collect();
    Trajectory::new(stamps, poses)
}

/// `truth` seen by an estimator in its own frame: moved by `frame`, with a slow
/// drift and a wobble, at the truth's times.
fn estimate_of(truth: &Trajectory, frame: Similarity, seed: f64) -> Trajectory {
    let poses = truth
        .poses()
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let t = k as f64;
            let wobble = 0.04 * math::sin(seed * t) + 0.01 * math::cos(3.1 * t);
            let drift = 0.0004 * t;
            frame.apply(&Pose2::new(
                p.x + wobble + drift,
                p.y - 0.7 * wobble,
                p.theta + 0.02 * math::sin(0.7 * t + seed) + 0.0002 * t,
            ))
        })
        .collect();
    Trajectory::new(truth.stamps().to_vec(), poses)
}

fn write(dir: &Path, name: &str, t: &Trajectory) -> String {
    let path = dir.join(name);
    std::fs::write(&path, write_tum(t)).unwrap();
    path.display().to_string()
}

#[test]
fn slamlab_evaluate_equals_evo() {
    let dir = Scratch::new("evo");
    let Some(evo) = evo(&dir) else {
        return;
    };
    let frame = Similarity {
        rotation: 0.9,
        translation: [3.0, -2.0],
        scale: 1.0,
    };
    let truth = reference(10.0, 120.0);
    let reference_file = write(&dir, "reference.txt", &truth);

    // 1. An estimate in its own frame, at the reference's times.
    let plain = write(&dir, "plain.txt", &estimate_of(&truth, frame, 0.3));

    // 2. The same with its own scale (a monocular estimate).
    let scaled_frame = Similarity {
        scale: 0.55,
        ..frame
    };
    let scaled = write(&dir, "scaled.txt", &estimate_of(&truth, scaled_frame, 0.5));

    // 3. Missing and jittered times: every 7th pose dropped, the rest up to ±6 ms off.
    let base = estimate_of(&truth, frame, 0.7);
    let (mut stamps, mut poses) = (Vec::new(), Vec::new());
    for (k, (t, p)) in base.stamps().iter().zip(base.poses()).enumerate() {
        if k % 7 == 3 {
            continue;
        }
        stamps.push(t + 0.006 * math::sin(1.7 * k as f64));
        poses.push(*p);
    }
    let jittered = write(&dir, "jittered.txt", &Trajectory::new(stamps, poses));

    // 4. An estimate at 30 Hz against the 10 Hz reference (evo then pairs the
    //    reference's poses with the estimate's), offset by 20 ms.
    let fast_truth = reference(30.0, 120.0);
    let fast = estimate_of(&fast_truth, frame, 0.9);
    let fast = Trajectory::new(
        fast.stamps().iter().map(|t| t - 0.02).collect(),
        fast.poses().to_vec(),
    );
    let fast = write(&dir, "fast.txt", &fast);

    // Each case: what | the estimate's file | evo's command | SLAM Lab's flags | the key
    // of SLAM Lab's JSON.
    const CASES: &str = "
        APE, SE(2) | plain | evo_ape -a | --align se2 | ape translation
        APE, not aligned | plain | evo_ape | --align none | ape translation
        APE rotation, SE(2) | plain | evo_ape -a -r angle_deg | --align se2 | ape rotation
        RPE, 1 frame | plain | evo_rpe -a | --align se2 | rpe translation
        RPE rotation, 10 frames | plain | evo_rpe -a -r angle_deg --delta 10 | --delta 10 | rpe rotation
        RPE, 2 m | plain | evo_rpe -a --delta 2 --delta_unit m | --delta 2 --delta-unit m | rpe translation
        RPE, all pairs 5 frames | plain | evo_rpe -a --delta 5 --all_pairs | --delta 5 --all-pairs | rpe translation
        APE, Sim(2) | scaled | evo_ape -a -s | --align sim2 | ape translation
        APE, SE(2) with a scale error | scaled | evo_ape -a | --align se2 | ape translation
        RPE, Sim(2), 3 m | scaled | evo_rpe -a -s --delta 3 --delta_unit m | --align sim2 --delta 3 --delta-unit m | rpe translation
        APE, jittered times | jittered | evo_ape -a --t_max_diff 0.01 | --max-diff 0.01 | ape translation
        APE, jittered times, 5 ms | jittered | evo_ape -a --t_max_diff 0.005 | --max-diff 0.005 | ape translation
        RPE, jittered times | jittered | evo_rpe -a -r angle_deg |  | rpe rotation
        APE, 30 Hz against 10 Hz, offset | fast | evo_ape -a --t_offset 0.02 --t_max_diff 0.004 | --offset 0.02 --max-diff 0.004 | ape translation";
    let files = [
        ("plain", &plain),
        ("scaled", &scaled),
        ("jittered", &jittered),
        ("fast", &fast),
    ];
    for line in CASES.lines().map(str::trim).filter(|l| !l.is_empty()) {
        let [what, file, evo_line, ours_line, key] =
            line.split('|').map(str::trim).collect::<Vec<_>>()[..]
        else {
            panic!("a case needs five fields: {line}");
        };
        let estimate = files
            .iter()
            .find(|(name, _)| *name == file)
            .map(|(_, path)| path.as_str())
            .unwrap();
        let evo_words: Vec<&str> = evo_line.split_whitespace().collect();
        let mut evo_args: Vec<&str> = vec!["tum", &reference_file, estimate];
        evo_args.extend(&evo_words[1..]);
        let theirs = evo.stats(evo_words[0], &evo_args);
        let mut ours_args = vec!["--estimate", estimate, "--reference", &reference_file];
        ours_args.extend(ours_line.split_whitespace());
        let ours = slamlab(&ours_args);
        let (metric, part) = key.split_once(' ').unwrap();
        assert_same(what, &theirs, &ours[metric][part]);
        eprintln!(
            "{what}: rmse {} (evo) and {} (SLAM Lab), {} pairs",
            theirs["rmse"], ours[metric][part]["rmse"], ours["pairing"]["pairs"]
        );
    }
}
