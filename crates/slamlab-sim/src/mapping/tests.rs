use super::*;
use crate::grid::builtin_map;
use crate::stepper::Simulation;

fn session(map: &str, steps: usize, seed: u64, poses: PoseSource) -> MappingSession {
    let scenario = MappingScenario {
        map: map.to_owned(),
        steps,
        seed,
        poses,
        ..MappingScenario::default()
    };
    let input = Arc::new(simulated_in(map, &scenario));
    let (session, notices) = MappingSession::new(scenario, input);
    assert!(notices.is_empty(), "{notices:?}");
    session
}

/// The scenario's simulated robot driven in the built-in map `map`.
fn simulated_in(map: &str, scenario: &MappingScenario) -> MappingInput {
    let grid = Arc::new(builtin_map(map).unwrap());
    simulated_input(scenario, grid, map).unwrap()
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
    let mut input = simulated_in("maze", &scenario);
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
/// odometry. Measured (2026-11-25): scan-to-map agrees with the true map on
/// 0.894-0.951 of the cells it knows (odometry 0.885-0.897); its position RMSE
/// is below half of odometry's in 3 of 5 seeds, and its median (0.53 m) is far
/// below half of odometry's (4.54 m). Seeds 3 and 4 lose track in long
/// corridors (6.7 m and 3.8 m), which local matching without loop closure does
/// not recover from. The 95% agreement a first reading of the metric suggests
/// is out of reach even with true poses (see the maze test above);
/// docs/mapping.md has the table.
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
    assert!(halved >= 3, "{text}");
    let median = |f: fn(&(u64, f64, f64, f64, f64)) -> f64| {
        let mut v: Vec<f64> = rows.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    assert!(median(|r| r.2) < 0.5 * median(|r| r.4), "{text}");
}

#[test]
fn icp_iterations_step_one_per_phase_and_land_where_the_whole_match_does() {
    let mut whole = session("maze", 30, 2, PoseSource::Plicp);
    whole.run_to_end();
    let mut stepped = session("maze", 30, 2, PoseSource::Plicp);
    stepped
        .stepper_mut()
        .apply(MappingEvent::StepIterations(true));
    // Scan 0 has nothing to match; scan 1's match is shown iteration by iteration.
    stepped.stepper_mut().step_tick();
    stepped.stepper_mut().step_phase(); // predict scan 1
    let mut shown = Vec::new();
    loop {
        match stepped.stepper_mut().step_phase() {
            MappingPhase::Iteration {
                scan,
                iteration,
                of,
                mean_squared_error,
                ..
            } => {
                assert_eq!(scan, 1);
                let (record, now) = stepped.sim().icp_record().unwrap();
                assert_eq!(record.iterations.len(), of);
                assert_eq!(now, Some(iteration - 1));
                assert_eq!(
                    record.iterations[iteration - 1].mean_squared_error,
                    mean_squared_error
                );
                shown.push(mean_squared_error);
            }
            MappingPhase::Insert { scan, .. } => {
                assert_eq!(scan, 1);
                break;
            }
            other => panic!("unexpected phase {other:?}"),
        }
    }
    assert!(shown.len() >= 2, "{shown:?}");
    assert!(
        shown.last() <= shown.first(),
        "the error falls over the iterations: {shown:?}"
    );
    // Stepping back through the iterations and on again changes nothing.
    for _ in 0..3 {
        assert!(stepped.stepper_mut().step_back());
    }
    while !stepped.sim().is_done() {
        stepped.stepper_mut().step_phase();
    }
    assert_eq!(
        stepped.stepper().records().poses,
        whole.stepper().records().poses,
        "iteration stepping shows the match; it does not change it"
    );
}

#[test]
fn a_beam_is_explained_before_and_after_its_scan_goes_in() {
    let mut s = session("maze", 10, 1, PoseSource::Odometry);
    assert!(s.sim().explain_beam(0).is_none(), "no scan yet");
    s.stepper_mut()
        .sim_mut_untracked()
        .keep_grid_before_insert(true);
    s.stepper_mut().run_ticks(3);
    s.stepper_mut().step_phase(); // predict scan 3: the next phase inserts it
    assert!(s.sim().next_is_insert());
    let beam = 90;
    let before = s.sim().explain_beam(beam).unwrap().unwrap();
    assert!(!before.cells.is_empty());
    s.stepper_mut().step_phase(); // insert
    assert!(!s.sim().next_is_insert());
    let after = s.sim().explain_beam(beam).unwrap().unwrap();
    assert_eq!(before, after, "the same update, explained before and after");
    for c in &after.cells {
        let now = s.sim().grid().log_odds_at(c.cell.0, c.cell.1).unwrap();
        assert!((now - c.after).abs() < 1e-6, "{c:?} now {now}");
    }
    assert!(s.sim().explain_beam(100_000).unwrap().is_err());
}

/// Grid FastSLAM in the lesson, phase by phase, is the filter the experiment
/// runs scan by scan: the same seed gives the same heaviest particle to the
/// bit, and every update takes each particle's proposal, weight,
/// (resample,) update maps.
#[test]
fn grid_fastslam_phase_by_phase_is_the_experiments_filter_to_the_bit() {
    let scenario = MappingScenario {
        map: "maze".to_owned(),
        steps: 160,
        seed: 4,
        poses: PoseSource::GridFastSlam,
        particles: 8,
        ..MappingScenario::default()
    };
    let input = Arc::new(simulated_in("maze", &scenario));
    let (mut s, notices) = MappingSession::new(scenario.clone(), input.clone());
    assert!(notices.is_empty(), "{notices:?}");
    let mut labels = Vec::new();
    while !s.sim().is_done() {
        let phase = s.stepper_mut().step_phase();
        labels.push(phase.label());
    }
    let (filter, _) = crate::mapping::grid_fastslam::run_grid_fastslam(
        &input,
        scenario.grid_fastslam_config(),
        scenario.insert_params(),
        scenario.seed,
    );
    let lesson = s.sim().grid_fastslam().unwrap();
    assert!(filter.updates() > 5, "{} updates", filter.updates());
    assert_eq!(lesson.updates(), filter.updates());
    assert_eq!(lesson.resamplings(), filter.resamplings());
    let bits = |f: &slamlab_core::particle::GridFastSlam| {
        f.particles()
            .iter()
            .map(|p| {
                [
                    p.pose.x.to_bits(),
                    p.pose.y.to_bits(),
                    p.pose.theta.to_bits(),
                ]
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(lesson), bits(&filter));
    // The phases: one per skipped scan; per update one per particle's scan
    // match, then weight, (resample,) update maps.
    let count = |what: &str| labels.iter().filter(|l| l.contains(what)).count();
    let updates = filter.updates() - 1;
    assert_eq!(count(": particle "), 8 * updates);
    assert_eq!(count("particle 8 of 8"), updates);
    assert_eq!(count("N_eff"), updates);
    assert_eq!(count("resampled"), filter.resamplings());
    assert_eq!(count("every particle's map updated"), updates);
    assert_eq!(count("skipped"), 160 - updates - 1);
    let records = s.stepper().records();
    assert_eq!(records.poses.len(), 160);
    assert_eq!(
        records.neff.iter().filter(|n| n.is_finite()).count(),
        updates
    );
    assert_eq!(
        records.resampled.iter().filter(|r| **r).count(),
        filter.resamplings()
    );
    let summary = s.summary();
    let particles = summary.particles.unwrap();
    assert_eq!(particles.particles, 8);
    assert_eq!(particles.updates, filter.updates());
    // The map shown is the heaviest particle's; its error is its path's.
    assert_eq!(
        s.sim().grid().known_cells(),
        filter.best().unwrap().map.known_cells()
    );
    let rmse = summary.trajectory_rmse.unwrap();
    assert!(rmse.is_finite() && rmse < 0.5, "{rmse}");
}

/// Stepping back through grid FastSLAM's phases and forward again lands on
/// the same particles (the checkpoints hold the filter and its random
/// stream).
#[test]
fn grid_fastslam_steps_back_and_replays_the_same_particles() {
    let scenario = MappingScenario {
        steps: 90,
        seed: 6,
        poses: PoseSource::GridFastSlam,
        particles: 6,
        ..MappingScenario::default()
    };
    let input = Arc::new(simulated_in("maze", &scenario));
    let (mut s, _) = MappingSession::new(scenario, input);
    for _ in 0..80 {
        s.stepper_mut().step_tick();
    }
    let pose = |s: &MappingSession| {
        let f = s.sim().grid_fastslam().unwrap();
        f.particles()
            .iter()
            .map(|p| (p.pose.x.to_bits(), p.pose.y.to_bits()))
            .collect::<Vec<_>>()
    };
    let before = pose(&s);
    let neff = s.stepper().records().neff.clone();
    for _ in 0..30 {
        assert!(s.stepper_mut().step_back());
    }
    while s.stepper().records().poses.len() < 80 {
        s.stepper_mut().step_phase();
    }
    assert_eq!(pose(&s), before);
    assert_eq!(
        format!("{:?}", s.stepper().records().neff),
        format!("{neff:?}")
    );
}
