//! `slamlab run cartographer` and `slamlab experiment krp`: the JSON keys
//! the issue names, a real log, and refusals of bad input.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

mod common;

use common::{json, shared_data, slamlab_output};

#[test]
fn experiment_krp_prints_detection_recovery_and_agreement_with_detection_on_and_off() {
    let out = slamlab_output(&[
        "experiment",
        "krp",
        "--map",
        "maze",
        "--trials",
        "2",
        "--steps",
        "220",
        "--kidnap-at",
        "152",
        "--seed",
        "2",
        "--json",
    ]);
    let v = json(&out);
    assert_eq!(v["experiment"], "krp");
    assert_eq!(v["runs"].as_array().unwrap().len(), 8);
    for key in ["detection_on", "detection_off"] {
        let r = &v[key];
        for field in [
            "detection_delay",
            "detected",
            "false_alarms",
            "recovered",
            "map_agreement",
        ] {
            assert!(!r[field].is_null(), "{key}.{field}: {r}");
        }
        assert!(r["detection_delay"].get("median").is_some());
        assert!(r["detection_delay"].get("p90").is_some());
        assert!(r["map_agreement"].get("median").is_some());
        assert!(r["false_alarms"]["kidnap_free"].is_u64());
    }
    // Seeds 2 and 3 (maze, kidnap at 152): both detected on the very scan,
    // no false alarm; seed 2's maps merge by scan 154. With detection off,
    // nothing is detected and nothing merged.
    let on = &v["detection_on"];
    assert_eq!(on["detected"], 2);
    assert_eq!(on["detection_delay"]["median"], 0.0);
    assert_eq!(on["false_alarms"]["total"], 0);
    assert!(on["recovered"].as_u64().unwrap() >= 1, "{on}");
    let off = &v["detection_off"];
    assert_eq!(off["detected"], 0);
    assert_eq!(off["recovered"], 0);
    assert!(off["detection_delay"]["median"].is_null());
    // Bad input: a kidnap past the last scan is refused with a message.
    let out = slamlab_output(&["experiment", "krp", "--steps", "100", "--kidnap-at", "152"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--kidnap-at 152"));
}

#[test]
fn run_cartographer_prints_the_issue_json_and_counts_scans() {
    let out = slamlab_output(&[
        "run",
        "cartographer",
        "--map",
        "maze",
        "--steps",
        "200",
        "--kidnap-at",
        "152",
        "--seed",
        "2",
        "--json",
    ]);
    let v = json(&out);
    for key in [
        "scans",
        "kidnap_at",
        "kidnap_detected_at",
        "false_alarms",
        "recovered_at",
        "loop_closures",
        "trajectory_rmse",
        "map_agreement",
        "bbs",
        "time_ms",
    ] {
        assert!(v.get(key).is_some(), "{key} missing: {v}");
    }
    assert_eq!(v["scans"], 200);
    assert_eq!(v["kidnap_detected_at"], 152);
    // The progress (a line every tenth of the way in a log) counts scans.
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cartographer: 200/200 scans"), "{err}");
    assert!(!err.contains("trials"), "{err}");
}

/// `--loop-closures off`: the same scans mapped by local SLAM alone, no
/// branch-and-bound search and no loop closure (the lesson's switch); on, the
/// maze's first 200 scans close loops.
#[test]
fn run_cartographer_with_loop_closures_off_searches_nothing() {
    let run = |closures: &str| {
        json(&slamlab_output(&[
            "run",
            "cartographer",
            "--map",
            "maze",
            "--steps",
            "200",
            "--loop-closures",
            closures,
            "--json",
        ]))
    };
    let off = run("off");
    assert_eq!(off["scans"], 200);
    assert_eq!(off["loop_closures"], 0, "{off}");
    assert_eq!(off["bbs"]["searches"], 0, "{off}");
    assert_eq!(off["parameters"]["sampling_ratio"], 0.0);
    let on = run("on");
    assert!(on["loop_closures"].as_u64().unwrap() > 0, "{on}");
    assert!(on["bbs"]["searches"].as_u64().unwrap() > 0, "{on}");
    // The same local SLAM: as many nodes and submaps either way.
    assert_eq!(off["nodes"], on["nodes"]);
    assert_eq!(off["submaps"], on["submaps"]);
}

/// The Intel log (`../shared/data/laser/intel.clf.bz2`, or under
/// `$SLAMLAB_SHARED_DATA` or `$SLAMLAB_SHARED/data`); skipped with a message
/// when it is absent. Slow in a debug build (over two minutes):
/// `cargo test --release -- --ignored`.
#[test]
#[ignore = "slow: the whole Intel log with loop closures"]
fn run_cartographer_maps_the_intel_log() {
    let Some(path) = shared_data("laser/intel.clf.bz2") else {
        return;
    };
    let path = path.to_str().unwrap();
    let out = slamlab_output(&["run", "cartographer", "--log", path, "--json"]);
    let v = json(&out);
    assert!(v["scans"].as_u64().unwrap() > 10_000, "{v}");
    assert!(v["trajectory_rmse"].is_null());
    eprintln!("Intel log: {v}");
}
