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
    // Two agreeing matches of the new map's nodes in the old submaps merge
    // the maps (scan 157 measured); after it the whole run sits in the
    // first map's frame: 0.071 m against the truth, agreement 0.880.
    let merged = s.recovered_at.unwrap();
    assert!((153..=170).contains(&merged), "{merged}");
    assert_eq!(sim.root(1), 0);
    assert!(
        sim.constraints
            .iter()
            .filter(|c| c.kind == ConstraintKind::InterTrajectory)
            .count()
            >= 2
    );
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
