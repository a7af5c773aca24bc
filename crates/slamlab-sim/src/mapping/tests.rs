use super::*;
use crate::stepper::Simulation;

fn session(map: &str, steps: usize, seed: u64, poses: PoseSource) -> MappingSession {
    let scenario = MappingScenario {
        map: map.to_owned(),
        steps,
        seed,
        poses,
        ..MappingScenario::default()
    };
    let grid = Arc::new(builtin_map(map).unwrap());
    let input = Arc::new(simulated_input(&scenario, grid, map).unwrap());
    let (session, notices) = MappingSession::new(scenario, input);
    assert!(notices.is_empty(), "{notices:?}");
    session
}

#[test]
fn mapping_with_true_poses_reproduces_the_maze() {
    let mut s = session("maze", 300, 3, PoseSource::Truth);
    s.run_to_end();
    let summary = s.summary();
    assert_eq!(summary.scans, 300);
    assert_eq!(summary.trajectory_rmse, Some(0.0));
    // Even with true poses the agreement stays near 0.92 on the maze: its
    // walls are one or two cells thick, and a wall cell that range noise
    // leaves on the free side of the beams reads free. That is the metric's
    // ceiling here, not a mapping error (docs/mapping.md).
    let agreement = summary.map_agreement.unwrap();
    assert!(agreement > 0.90, "{agreement}");
}

#[test]
fn stepping_back_replays_the_same_poses_to_the_bit() {
    let mut s = session("maze", 60, 5, PoseSource::ScanToMap);
    for _ in 0..40 {
        s.stepper_mut().step_tick();
    }
    let before: Vec<_> = s.stepper().records().poses.clone();
    let known = s.sim().grid().known_cells();
    for _ in 0..25 {
        assert!(s.stepper_mut().step_back());
    }
    assert!(s.stepper().records().poses.len() < 40);
    while s.stepper().records().poses.len() < 40 {
        s.stepper_mut().step_phase();
    }
    assert_eq!(s.stepper().records().poses, before);
    assert_eq!(s.sim().grid().known_cells(), known);
    assert!(!s.sim().is_mid_tick());
}

#[test]
fn a_log_without_truth_maps_with_odometry_when_truth_is_asked() {
    let scenario = MappingScenario {
        steps: 20,
        poses: PoseSource::Truth,
        ..MappingScenario::default()
    };
    let grid = Arc::new(builtin_map("maze").unwrap());
    let mut input = simulated_input(&scenario, grid, "maze").unwrap();
    input.truth = None;
    input.true_map = None;
    let (mut s, notices) = MappingSession::new(scenario, Arc::new(input));
    assert!(
        notices.iter().any(|n| n.contains("no true poses")),
        "{notices:?}"
    );
    s.run_to_end();
    let summary = s.summary();
    assert_eq!(summary.poses, "odometry");
    assert_eq!(summary.trajectory_rmse, None);
    assert_eq!(summary.map_agreement, None);
    assert!(summary.map.known_cells > 1000);
}

/// The built-in office, 3000 scans, seeds 1-5, scan-to-map against raw
/// odometry. Measured (2026-11-24): scan-to-map agrees with the true map on
/// 0.889-0.948 of the cells it knows (odometry 0.874-0.895) and its position
/// RMSE is below half of odometry's in 4 of 5 seeds (seed 3 loses track in a
/// long corridor: 4.7 m against 1.9 m). The 95% agreement a first reading of
/// the metric suggests is out of reach even with true poses (see the maze
/// test above); docs/mapping.md has the table.
#[test]
fn scan_to_map_builds_the_office_and_beats_odometry() {
    let grid = Arc::new(builtin_map("office").unwrap());
    let mut rows = Vec::new();
    for seed in 1..=5 {
        let scenario = MappingScenario {
            map: "office".to_owned(),
            steps: 3000,
            seed,
            ..MappingScenario::default()
        };
        let input = Arc::new(simulated_input(&scenario, grid.clone(), "office").unwrap());
        let run = |poses| {
            let (mut s, _) = MappingSession::new(
                MappingScenario {
                    poses,
                    ..scenario.clone()
                },
                input.clone(),
            );
            s.run_to_end();
            s.summary()
        };
        let matched = run(PoseSource::ScanToMap);
        let odometry = run(PoseSource::Odometry);
        rows.push((
            seed,
            matched.map_agreement.unwrap(),
            matched.trajectory_rmse.unwrap(),
            odometry.map_agreement.unwrap(),
            odometry.trajectory_rmse.unwrap(),
        ));
    }
    let text = rows
        .iter()
        .map(|r| {
            format!(
                "seed {}: scan-to-map {:.4} agree, {:.3} m; odometry {:.4} agree, {:.3} m",
                r.0, r.1, r.2, r.3, r.4
            )
        })
        .collect::<Vec<_>>()
        .join("\n");
    eprintln!("{text}");
    for r in &rows {
        assert!(r.1 >= 0.88 && r.1 > r.3, "{text}");
    }
    let halved = rows.iter().filter(|r| r.2 < 0.5 * r.4).count();
    assert!(halved >= 4, "{text}");
    let mean = |f: fn(&(u64, f64, f64, f64, f64)) -> f64| {
        rows.iter().map(f).sum::<f64>() / rows.len() as f64
    };
    assert!(mean(|r| r.2) < 0.5 * mean(|r| r.4), "{text}");
}
