use super::input::kidnap_input;
use super::*;
use crate::laser_log::SimulatedLogConfig;
use crate::mapping::builtin_map;

fn run_with(
    map: &str,
    steps: usize,
    seed: u64,
    kidnap_at: Option<usize>,
    params: CartographerParams,
) -> (CartographerSim, CartographerSummary) {
    let grid = Arc::new(builtin_map(map).unwrap());
    let input = kidnap_input(
        grid,
        map,
        steps,
        seed,
        kidnap_at,
        &SimulatedLogConfig::default(),
    )
    .unwrap();
    let (mut sim, notes) = CartographerSim::new(Arc::new(input), params);
    assert!(notes.is_empty(), "{notes:?}");
    sim.run_to_end();
    let summary = sim.summary(kidnap_at, 0.0);
    (sim, summary)
}

#[test]
fn a_kidnap_free_maze_run_closes_loops_without_a_false_alarm() {
    let (sim, s) = run_with("maze", 600, 1, None, CartographerParams::default());
    assert_eq!(s.detections, Vec::<usize>::new());
    assert_eq!(s.false_alarms, 0);
    assert_eq!(s.trajectories, 1);
    assert!(s.loop_closures > 100, "{s:?}");
    // Measured 0.080 m against the truth, the map agreeing on 0.881 of
    // its cells (2026-11-26).
    let rmse = s.trajectory_rmse.unwrap();
    assert!(rmse < 0.12, "{rmse}");
    assert!(s.map_agreement.unwrap() > 0.86, "{s:?}");
    // Branch and bound scored a small share of what exhaustive search would.
    assert!(
        s.bbs.exhaustive_candidates > 100 * s.bbs.nodes_evaluated,
        "{:?}",
        s.bbs
    );
    // Every scan's cost is kept (NaN only for the very first scan).
    assert_eq!(sim.records.len(), 600);
    assert!(sim.records[1..].iter().all(|r| r.cost.is_finite()));
}

#[test]
fn a_kidnap_at_scan_152_is_detected_and_the_new_map_merged() {
    let (sim, s) = run_with("maze", 600, 2, Some(152), CartographerParams::default());
    // Detected on the very scan (the filtered cost jumped 0.069 to 0.180).
    assert_eq!(s.kidnap_detected_at, Some(152));
    assert_eq!(s.false_alarms, 0);
    assert_eq!(s.trajectories, 2);
    assert_eq!(sim.trajectories[1].first_scan, 152);
    // A global match of the new map's third node, checked against the old
    // map (all 450 of its first three scans' points that land on known
    // cells land on or beside walls), merges the maps at scan 154; after it
    // the whole run sits in the first map's frame: 0.074 m against the
    // truth, agreement 0.879 (measured 2026-11-26).
    let merged = s.recovered_at.unwrap();
    assert!((153..=170).contains(&merged), "{merged}");
    assert_eq!(sim.root(1), 0);
    let accepted: Vec<&MergeCheck> = sim.merge_checks.iter().filter(|c| c.accepted).collect();
    assert_eq!(accepted.len(), 1);
    assert!(accepted[0].occupied_share > 0.99, "{:?}", accepted[0]);
    let truth = sim.input().truth.as_ref().unwrap()[accepted[0].scan];
    let err = slamlab_core::math::hypot(
        accepted[0].node_pose.x - truth.x,
        accepted[0].node_pose.y - truth.y,
    );
    assert!(err < 0.15, "{err}");
    let rmse = s.trajectory_rmse.unwrap();
    assert!(rmse < 0.15, "{rmse}");
    let merged_agreement = s.map_agreement.unwrap();
    assert!(merged_agreement > 0.86, "{merged_agreement}");
    // With detection off the same run maps on into one corrupted map
    // (Fig. 5.10).
    let off = CartographerParams {
        detection: false,
        ..CartographerParams::default()
    };
    let (_, s_off) = run_with("maze", 600, 2, Some(152), off);
    assert_eq!(s_off.trajectories, 1);
    assert_eq!(s_off.kidnap_detected_at, None);
    let rmse_off = s_off.trajectory_rmse.unwrap();
    eprintln!("detection off: {s_off:?}");
    assert!(rmse_off > 1.0, "{rmse_off}");
    assert!(s_off.map_agreement.unwrap() < merged_agreement - 0.02);
}

#[test]
fn bad_parameters_are_clamped_with_notes() {
    let bad = CartographerParams {
        num_range_data: 0,
        resolution: f64::NAN,
        hit_probability: 0.3,
        linear_search_window: -1.0,
        ..CartographerParams::default()
    };
    let (p, notes) = bad.sanitized();
    assert_eq!(p.num_range_data, 1);
    assert_eq!(p.resolution, 0.05);
    assert_eq!(p.hit_probability, 0.55);
    assert_eq!(p.linear_search_window, 7.0);
    assert_eq!(notes.len(), 4, "{notes:?}");
    // An empty input runs to its end at once.
    let (mut sim, _) = CartographerSim::new(Arc::new(MappingInput::default()), p);
    assert!(!sim.step());
    assert_eq!(sim.summary(None, 0.0).scans, 0);
}

/// The merge check's verdict on every proposed merge: the node's implied
/// pose in the old map against the truth.
fn wrong_merges(sim: &CartographerSim) -> usize {
    let truth = sim.input().truth.as_ref().unwrap();
    sim.merge_checks
        .iter()
        .filter(|c| c.accepted)
        .filter(|c| {
            let t = truth[c.scan];
            slamlab_core::math::hypot(c.node_pose.x - t.x, c.node_pose.y - t.y) > 0.5
        })
        .count()
}

/// The built-in office with a kidnap at scan 152 (the thesis's case), ten
/// seeds, and the same ten seeds without a kidnap: Algorithm 13 sees only
/// the local matching cost, which loop closures do not change (local SLAM
/// matches against the trajectory's own active submaps), so these runs skip
/// the loop-closure searches. Measured 2026-11-26 with `T` 1.5, `f_size`
/// 4: every kidnap detected on scan 152 itself, no false alarm in the ten
/// kidnap-free runs (with `f_size` 5, 8 of 10 detected).
#[test]
fn office_kidnaps_at_scan_152_are_detected_and_kidnap_free_runs_raise_no_alarm() {
    let local_only = CartographerParams {
        constraint_every_n_nodes: usize::MAX,
        ..CartographerParams::default()
    };
    let (mut detected, mut delays, mut false_alarms) = (0, Vec::new(), 0);
    for seed in 1..=10 {
        let (_, s) = run_with("office", 600, seed, Some(152), local_only);
        if let Some(d) = s.kidnap_detected_at {
            detected += 1;
            delays.push(d - 152);
        }
        false_alarms += s.false_alarms;
        let (_, free) = run_with("office", 600, seed, None, local_only);
        false_alarms += free.detections.len();
    }
    assert!(detected >= 9, "{detected} of 10 detected");
    // The stated delay: within 2 scans (measured: 0 every time).
    assert!(delays.iter().all(|&d| d <= 2), "{delays:?}");
    assert_eq!(false_alarms, 0);
}

/// Maze seeds 1 and 3 (kidnap at 152), which merged the maps one corridor
/// over before the merge check: seed 1 now merges at scan 223, right to
/// 0.03 m, once the new map has seen enough of the old one; seed 3's robot
/// never sees enough of the old map again, and the maps stay apart (its
/// 317 proposed merges were all wrong, the best on-wall share 0.917, below
/// the check's 0.945). Release speed: about 25 s CPU.
#[test]
#[ignore = "slow: two full maze runs with global searches; cargo test --release -- --ignored"]
fn maze_kidnaps_merge_right_or_not_at_all() {
    let (sim1, s1) = run_with("maze", 600, 1, Some(152), CartographerParams::default());
    assert_eq!(s1.kidnap_detected_at, Some(152));
    assert_eq!(s1.recovered_at, Some(223));
    assert_eq!(wrong_merges(&sim1), 0);
    assert!(s1.trajectory_rmse.unwrap() < 0.15, "{s1:?}");
    let (sim3, s3) = run_with("maze", 600, 3, Some(152), CartographerParams::default());
    assert_eq!(s3.kidnap_detected_at, Some(152));
    assert_eq!(s3.recovered_at, None);
    assert_eq!(wrong_merges(&sim3), 0);
    assert!(!sim3.merge_checks.is_empty());
    assert!(s3.trajectory_rmse.unwrap() < 0.15, "{s3:?}");
}

/// The built-in office with a kidnap at scan 152, seeds 1-6, loop closures
/// and global searches on: the kidnap carries the robot away from the one
/// corner mapped by then (the office is 55 m x 55 m), and in the remaining
/// 448 scans it does not come back to it, so no right match exists. Every
/// proposed merge is refused and the first map stays right (measured
/// 2026-11-26: recovered in 0 of 6; the issue asks for 8 of 10, see
/// docs/cartographer.md). Release speed: minutes.
#[test]
#[ignore = "slow: six office runs with global searches; cargo test --release -- --ignored"]
fn office_kidnaps_never_merge_wrongly() {
    let mut recovered = 0;
    for seed in 1..=6 {
        let (sim, s) = run_with(
            "office",
            600,
            seed,
            Some(152),
            CartographerParams::default(),
        );
        assert_eq!(s.kidnap_detected_at, Some(152), "seed {seed}");
        assert_eq!(wrong_merges(&sim), 0, "seed {seed}");
        assert!(s.trajectory_rmse.unwrap() < 0.2, "seed {seed}: {s:?}");
        recovered += usize::from(s.recovered_at.is_some());
    }
    assert_eq!(recovered, 0);
}

/// Bad input: a log with a gap (scans 120-199 cut out, as the thesis cropped
/// its bag to make a kidnap), a scan whose odometry is not a number, and a
/// loop-closure window far larger than the map: the run goes to its end
/// with every pose finite.
#[test]
fn a_log_with_a_gap_bad_odometry_and_a_huge_window_runs_to_its_end() {
    let grid = Arc::new(builtin_map("maze").unwrap());
    let mut input =
        kidnap_input(grid, "maze", 260, 2, None, &SimulatedLogConfig::default()).unwrap();
    input.scans.drain(120..200);
    if let Some(t) = input.truth.as_mut() {
        t.drain(120..200);
    }
    input.scans[50].odometry = Pose2::new(f64::NAN, 0.0, 0.0);
    let params = CartographerParams {
        linear_search_window: 1e4,
        ..CartographerParams::default()
    };
    let (mut sim, notes) = CartographerSim::new(Arc::new(input), params);
    assert!(notes.is_empty(), "{notes:?}");
    sim.run_to_end();
    assert_eq!(sim.records.len(), 180);
    assert!(sim.records.iter().all(|r| r.global_pose.is_finite()));
    assert!(sim.nodes.iter().all(|n| n.global_pose.is_finite()));
    let s = sim.summary(None, 0.0);
    eprintln!(
        "gap: detections {:?}, merges {:?}",
        s.detections, sim.merges
    );
    assert_eq!(s.scans, 180);
}
