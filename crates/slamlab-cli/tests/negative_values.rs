//! Negative numbers as a student types them: `--offset -0.5`, with a space, works
//! as `--offset=-0.5` does, a flag after the value stays a flag, and a value out
//! of range is refused with the command's own message, whichever form it came in.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

mod common;

use common::{Scratch, run_json, slamlab, slamlab_stdout};

/// A reference TUM file (ten poses 1 s apart on a line) and an estimate of the
/// same poses stamped `lag` seconds late; their paths, the estimate's first.
fn lagging_pair(dir: &Scratch, lag: f64) -> (String, String) {
    let write = |name: &str, shift: f64| {
        let text: String = (0..10)
            .map(|k| {
                format!(
                    "{} {} 0 0 0 0 0 1\n",
                    f64::from(k) + shift,
                    0.5 * f64::from(k)
                )
            })
            .collect();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path.to_str().unwrap().to_owned()
    };
    (write("estimate.tum", lag), write("reference.tum", 0.0))
}

/// `slamlab evaluate` of the pair with `args`, as JSON.
fn evaluate(estimate: &str, reference: &str, args: &[&str]) -> serde_json::Value {
    let all = [
        &["evaluate", "--estimate", estimate, "--reference", reference][..],
        args,
    ]
    .concat();
    serde_json::from_str(&slamlab_stdout(&all)).unwrap()
}

#[test]
fn evaluate_takes_a_negative_offset_with_a_space() {
    let dir = Scratch::new("negative-offset");
    let (estimate, reference) = lagging_pair(&dir, 0.5);
    // The estimate runs 0.5 s late: -0.5 s pairs every pose, and the flag after
    // the value (`--json`) is read as a flag, or the output would not be JSON.
    let spaced = evaluate(&estimate, &reference, &["--offset", "-0.5", "--json"]);
    assert_eq!(spaced["pairing"]["offset_s"], -0.5);
    assert_eq!(spaced["pairing"]["pairs"], 10, "{}", spaced["pairing"]);
    assert_eq!(spaced["ape"]["translation"]["rmse"], 0.0, "{spaced}");
    // The same as the `=` form and as any other spelling of the number.
    let joined = evaluate(&estimate, &reference, &["--offset=-0.5", "--json"]);
    assert_eq!(spaced, joined);
    let dotted = evaluate(&estimate, &reference, &["--offset", "-.5", "--json"]);
    assert_eq!(dotted["pairing"]["pairs"], 10);
    let exponent = evaluate(&estimate, &reference, &["--offset", "-5e-1", "--json"]);
    assert_eq!(exponent["pairing"]["offset_s"], -0.5);
    // Without it, 0.5 s is beyond the 0.01 s tolerance: no pose pairs.
    let (ok, _, stderr) = slamlab(&[
        "evaluate",
        "--estimate",
        &estimate,
        "--reference",
        &reference,
    ]);
    assert!(!ok, "paired without the offset");
    assert!(stderr.contains("estimate.tum"), "{stderr}");
}

#[test]
fn a_missing_value_or_one_out_of_range_is_refused_as_before() {
    let dir = Scratch::new("negative-refusals");
    let (estimate, reference) = lagging_pair(&dir, 0.5);
    let evaluate = |args: &[&str]| {
        let all = [
            &[
                "evaluate",
                "--estimate",
                &estimate,
                "--reference",
                &reference,
            ][..],
            args,
        ]
        .concat();
        slamlab(&all)
    };
    // A flag where the value belongs is not taken for it in silence.
    let (ok, stdout, stderr) = evaluate(&["--offset", "--json"]);
    assert!(!ok && stdout.is_empty(), "{stdout}");
    assert!(
        stderr.contains("'--json'") && stderr.contains("a flag, not a number"),
        "{stderr}"
    );
    // Out of range: the same refusal with a space as with `=`.
    for form in [&["--max-diff", "-1"][..], &["--max-diff=-1"][..]] {
        let (ok, _, stderr) = evaluate(form);
        assert!(
            !ok && stderr
                .contains("the time tolerance must be a number of seconds, at least 0 (was -1)"),
            "{form:?}: {stderr}"
        );
    }
    // An experiment's number flags and a lesson's table flags alike.
    let (ok, _, stderr) = slamlab(&["experiment", "two-view", "--noise-px", "-1", "--json"]);
    assert!(
        !ok && stderr.contains("--noise-px: -1 is outside 0 .. 20"),
        "{stderr}"
    );
    let (ok, _, stderr) = slamlab(&["experiment", "ekf-vs-ukf", "--noise-scale", "-2"]);
    assert!(
        !ok && stderr.contains("--noise-scale -2: expected a number between 0 and 20"),
        "{stderr}"
    );
    let (ok, _, stderr) = slamlab(&[
        "graph",
        "optimize",
        "x.g2o",
        "--kernel",
        "huber",
        "--kernel-width",
        "-1",
    ]);
    assert!(
        !ok && stderr.contains("--kernel-width -1 must be a finite number above 0"),
        "{stderr}"
    );
    let (ok, _, stderr) = slamlab(&["run", "landmark-slam", "--seed", "-3"]);
    assert!(!ok && stderr.contains("--seed '-3'"), "{stderr}");
    // Whole numbers: refused by their parser, not taken for an unknown flag.
    for args in [
        &["experiment", "fastslam", "--trials", "-3"][..],
        &["experiment", "fastslam", "--trials=-3"][..],
        &["log", "record", "--out", "never.log", "--seed", "-1"][..],
        &["run", "cartographer", "--seed", "-1"][..],
    ] {
        let (ok, _, stderr) = slamlab(args);
        let value = args
            .last()
            .map_or("", |a| a.trim_start_matches("--trials="));
        assert!(
            !ok && stderr.contains(&format!("invalid value '{value}'")),
            "{args:?}: {stderr}"
        );
    }
}

#[test]
fn a_lesson_takes_a_negative_turn_rate_with_a_space() {
    // A clockwise circle: the turn rate the run reports is the one given, and the
    // flags after it are read as flags.
    let v = run_json(&[
        "run",
        "landmark-slam",
        "--w-deg",
        "-10",
        "--steps",
        "20",
        "--json",
    ]);
    assert_eq!(v["parameters"]["w-deg"], -10.0, "{}", v["parameters"]);
    assert_eq!(v["steps"], 20);
    // Any spelling of the number, as in the app's URL.
    let v = run_json(&[
        "run",
        "landmark-slam",
        "--w-deg",
        "-.5e1",
        "--steps",
        "3",
        "--json",
    ]);
    assert_eq!(v["parameters"]["w-deg"], -5.0, "{}", v["parameters"]);
    // The value left out: the flag after it is not taken for it.
    let (ok, stdout, stderr) = slamlab(&["run", "landmark-slam", "--w-deg", "--json"]);
    assert!(!ok && stdout.is_empty(), "{stdout}");
    assert!(
        stderr.contains("'--json'") && stderr.contains("a flag, not a value"),
        "{stderr}"
    );
}
