use super::input::{KidnapPlace, kidnap_input, kidnap_input_to};
use super::*;
use crate::grid::SimulatedLogConfig;
use crate::grid::builtin_map;

fn run_with(
    map: &str,
    steps: usize,
    seed: u64,
    kidnap_at: Option<usize>,
    params: CartographerParams,
) -> (CartographerSim, CartographerSummary) {
    let kidnap = kidnap_at.map(|k| (k, KidnapPlace::Mapped));
    let (sim, summary, notes) = run_simulated(map, steps, seed, kidnap, params);
    assert!(notes.is_empty(), "{notes:?}");
    (sim, summary)
}

/// Runs `map` for `steps` scans of seed `seed`, kidnapped at `(scan, place)`
/// if given, to the end: the run, its summary and the notes it opened with.
fn run_simulated(
    map: &str,
    steps: usize,
    seed: u64,
    kidnap: Option<(usize, KidnapPlace)>,
    params: CartographerParams,
) -> (CartographerSim, CartographerSummary, Vec<String>) {
    let grid = Arc::new(builtin_map(map).unwrap());
    let config = SimulatedLogConfig::default();
    let input = kidnap_input_to(grid, map, steps, seed, kidnap, &config).unwrap();
    let (mut sim, notes) = CartographerSim::new(Arc::new(input), params);
    sim.run_to_end();
    let summary = sim.summary(kidnap.map(|(k, _)| k), 0.0);
    (sim, summary, notes)
}

#[test]
fn a_kidnap_free_maze_run_closes_loops_without_a_false_alarm() {
    let (sim, s) = run_with("maze", 600, 1, None, CartographerParams::default());
    assert_eq!(s.detections, Vec::<usize>::new());
    assert_eq!(s.false_alarms, 0);
    assert_eq!(s.trajectories, 1);
    // 78 loop closures from 301 searches (a tenth of the node-submap pairs
    // in reach, each in a window of 0.6 m and 5° around the estimate), none
    // refused by the gate (the window is the gate). Measured 0.089 m against
    // the truth, the map agreeing on 0.870 of its cells (2026-11-28; 0.080
    // and 0.881 with a 7 m, 30° window on every third node).
    assert!(s.loop_closures > 50, "{s:?}");
    assert_eq!(s.rejected_closures, 0);
    let rmse = s.trajectory_rmse.unwrap();
    assert!(rmse < 0.12, "{rmse}");
    assert!(s.map_agreement.unwrap() > 0.86, "{s:?}");
    // Branch and bound scored a small share of what exhaustive search would
    // (40x fewer in this small window).
    assert!(
        s.bbs.exhaustive_candidates > 30 * s.bbs.nodes_evaluated,
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
    // the whole run sits in the first map's frame: 0.068 m against the
    // truth, agreement 0.906 (measured 2026-11-26).
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
    assert_eq!(p.linear_search_window, 0.6);
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
        sampling_ratio: 0.0,
        global_search_every_n_nodes: usize::MAX,
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

/// Runs `map` with a kidnap at scan 152 to `place`.
fn run_kidnapped_to(
    map: &str,
    seed: u64,
    place: KidnapPlace,
) -> (CartographerSim, CartographerSummary) {
    let params = CartographerParams::default();
    let (sim, summary, _) = run_simulated(map, 600, seed, Some((152, place)), params);
    (sim, summary)
}

/// The built-in office, seed 2, kidnapped at scan 152 to a place on its
/// path so far: detected on scan 152, the new map merged right at scan 157
/// (measured 2026-11-26: the match 0.04 m from the truth, map agreement
/// 0.973 against 0.970 without the kidnap).
#[test]
fn an_office_kidnap_is_detected_and_merged_right() {
    let (sim, s) = run_kidnapped_to("office", 2, KidnapPlace::Mapped);
    assert_eq!(s.kidnap_detected_at, Some(152));
    assert_eq!(s.false_alarms, 0);
    assert_eq!(s.recovered_at, Some(157));
    assert_eq!(wrong_merges(&sim), 0);
    assert!(s.trajectory_rmse.unwrap() < 0.1, "{s:?}");
    assert!(s.map_agreement.unwrap() > 0.95, "{s:?}");
}

/// The office experiment: seeds 1-10 with a kidnap at 152 to a
/// place on the path so far, and the same seeds without. Measured
/// 2026-11-26: every kidnap detected on scan 152, no false alarm, all ten
/// maps merged (at scan 154 or 157) and none wrongly, median map agreement
/// 0.949 against 0.944 kidnap-free. Release speed: minutes.
#[test]
#[ignore = "slow: twenty office runs with global searches; cargo test --release -- --ignored"]
fn office_kidnaps_merge_in_at_least_8_of_10() {
    let (mut recovered, mut kidnapped, mut free) = (0, Vec::new(), Vec::new());
    for seed in 1..=10 {
        let (sim, s) = run_kidnapped_to("office", seed, KidnapPlace::Mapped);
        assert_eq!(s.kidnap_detected_at, Some(152), "seed {seed}");
        assert_eq!(s.false_alarms, 0, "seed {seed}");
        assert_eq!(wrong_merges(&sim), 0, "seed {seed}");
        recovered += usize::from(s.recovered_at.is_some());
        kidnapped.push(s.map_agreement.unwrap());
        let (_, f) = run_with("office", 600, seed, None, CartographerParams::default());
        assert!(f.detections.is_empty(), "seed {seed}: {f:?}");
        free.push(f.map_agreement.unwrap());
    }
    assert!(recovered >= 8, "{recovered} of 10 merged");
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (v[4] + v[5]) / 2.0
    };
    let (k, f) = (median(&mut kidnapped), median(&mut free));
    assert!(k > f - 0.02, "agreement {k} kidnapped, {f} kidnap-free");
}

/// A kidnap to any free place of the office (`kidnap-place=anywhere`)
/// mostly lands where the robot has not mapped and, in the 448 scans left,
/// does not come back to: nothing right to merge with, and no wrong merge
/// is taken (measured before the scan-to-map fix: 0 of 6 merged, none
/// wrongly). Release speed: minutes.
#[test]
#[ignore = "slow: office runs with global searches; cargo test --release -- --ignored"]
fn office_kidnaps_anywhere_never_merge_wrongly() {
    for seed in 1..=4 {
        let (sim, s) = run_kidnapped_to("office", seed, KidnapPlace::Anywhere);
        assert_eq!(s.kidnap_detected_at, Some(152), "seed {seed}");
        assert_eq!(wrong_merges(&sim), 0, "seed {seed}");
        eprintln!("anywhere, seed {seed}: merged at {:?}", s.recovered_at);
    }
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

/// Everything a run produced, exactly (`{:?}` of an `f64` round-trips, so
/// equal strings mean equal bits, NaN aside).
fn fingerprint(sim: &CartographerSim) -> String {
    let submaps: Vec<_> = sim
        .submaps
        .iter()
        .map(|s| {
            (
                s.trajectory,
                s.local_pose,
                s.global_pose,
                s.num_range_data,
                s.finished,
            )
        })
        .collect();
    let nodes: Vec<_> = sim
        .nodes
        .iter()
        .map(|n| (n.trajectory, n.scan, n.local_pose, n.global_pose))
        .collect();
    let trajectories: Vec<_> = sim
        .trajectories
        .iter()
        .map(|t| (t.first_scan, t.joined_to, t.global_from_local))
        .collect();
    format!(
        "{:?}\n{submaps:?}\n{nodes:?}\n{:?}\n{trajectories:?}\n{:?}\n{:?}\n{:?}\n{} {} {:?}\n{:?}",
        sim.records,
        sim.constraints,
        sim.detections,
        sim.merges,
        sim.bbs,
        sim.optimizations,
        sim.rejected_closures,
        sim.merge_checks,
        sim.last_search,
    )
}

/// The office, seed 1, kidnapped at scan 152 (detected there, merged at
/// scan 157 by a global search): run phase by phase, every scan, node,
/// submap, constraint, count and the last search are exactly what whole
/// scans give; each phase is what it says (one search, one optimization).
#[test]
fn stepping_by_phases_gives_exactly_what_stepping_by_scans_gives() {
    let grid = Arc::new(builtin_map("office").unwrap());
    let input = Arc::new(
        kidnap_input(
            grid,
            "office",
            240,
            1,
            Some(152),
            &SimulatedLogConfig::default(),
        )
        .unwrap(),
    );
    let (mut whole, _) = CartographerSim::new(input.clone(), CartographerParams::default());
    whole.run_to_end();
    let (mut phased, _) = CartographerSim::new(input, CartographerParams::default());
    let (mut scans, mut searches, mut global, mut optimizations) = (0, 0, 0, 0);
    let mut most_searches = 0;
    // Scans whose outlook promised an optimization, and scans that ran one.
    let (mut promised, mut optimized) = (Vec::new(), Vec::new());
    while !phased.is_done() {
        let outlook = phased.outlook();
        if outlook.optimization_pending && promised.last() != Some(&outlook.scan) {
            promised.push(outlook.scan);
        }
        let before = (phased.bbs.searches, phased.optimizations);
        let phase = phased.step_phase();
        match (outlook.next, phase) {
            (NextPhase::LocalSlam, CartographerPhase::LocalSlam { scan }) => {
                assert_eq!(scan, scans);
                scans += 1;
                assert_eq!(before, (phased.bbs.searches, phased.optimizations));
                most_searches = most_searches.max(phased.outlook().searches_planned);
            }
            (NextPhase::Search, CartographerPhase::Search { global: g, .. }) => {
                assert!(outlook.searches_pending > 0);
                searches += 1;
                global += usize::from(g);
                assert_eq!(phased.bbs.searches, before.0 + 1);
                assert_eq!(phased.optimizations, before.1);
            }
            (NextPhase::Optimization, CartographerPhase::Optimization { scan }) => {
                optimizations += 1;
                if optimized.last() != Some(&scan) {
                    optimized.push(scan);
                }
                assert_eq!(phased.optimizations, before.1 + 1);
                assert_eq!(phased.bbs.searches, before.0);
            }
            other => panic!("announced and ran: {other:?}"),
        }
    }
    assert_eq!(phased.step_phase(), CartographerPhase::Done);
    // "then optimization" held every time it was said (and a merge's
    // optimization, which no outlook can promise before the match, is the
    // only one not announced with the scan's searches).
    assert!(
        promised.iter().all(|k| optimized.contains(k)),
        "{promised:?} {optimized:?}"
    );
    assert!(
        optimized
            .iter()
            .all(|k| promised.contains(k) || whole.merges.contains(k))
    );
    assert_eq!(fingerprint(&phased), fingerprint(&whole));
    assert_eq!(scans, 240);
    assert_eq!(searches, whole.bbs.searches);
    assert_eq!(optimizations, whole.optimizations);
    // What the run holds: the detection, the merge by a global search, loop
    // closures and several optimizations (23 searches, 4 of them global,
    // 5 optimizations, at most 4 searches planned for one scan; before the
    // sampling per submap, 63, 5 and 5).
    assert_eq!(whole.detections, vec![152]);
    assert_eq!(whole.merges, vec![157]);
    assert_eq!((searches, global, optimizations), (23, 4, 5));
    assert_eq!(most_searches, 4);
}
