//! The kidnapped robot: AMCL, CMCL and ACMCL on the built-in maze.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

use slamlab_core::particle::ParticleFlag;
use slamlab_sim::grid::BuiltinMap;
use slamlab_sim::kidnap::experiment::{KidnapProtocol, KidnapTrial, kidnap_trial, summarize};
use slamlab_sim::kidnap::{InitMode, LocalizationEstimator, MclPhase, MclRun, MclScenario};

fn scenario(est: Vec<LocalizationEstimator>, particles: usize, seed: u64) -> MclScenario {
    MclScenario {
        estimators: est,
        init: InitMode::Tracking,
        max_particles: particles,
        seed,
        ..Default::default()
    }
}

/// CMCL and ACMCL never keep a particle inside the inflated costmap after
/// their motion step; AMCL and MCL do not regenerate.
#[test]
fn costmap_filters_keep_no_particle_in_invalid_cells_after_motion() {
    use LocalizationEstimator::*;
    let mut run = MclRun::new(
        MclScenario {
            init: InitMode::Global,
            ..scenario(vec![Mcl, Amcl, Cmcl, Acmcl], 400, 4)
        },
        BuiltinMap::Maze.load().unwrap(),
    )
    .unwrap();
    let mut predictions = 0;
    let mut regenerated = 0;
    while run.tick_count() < 150 {
        if run.step_phase() == MclPhase::Predict {
            predictions += 1;
            let costmap = run.collision_map();
            for f in run.filters() {
                let flags = f
                    .mcl()
                    .particles()
                    .iter()
                    .filter(|p| p.flag == ParticleFlag::Regenerated)
                    .count();
                if f.name == "cmcl" || f.name == "acmcl" {
                    regenerated += flags;
                    for p in f.mcl().particles() {
                        assert!(costmap.is_valid_at(p.pose.x, p.pose.y), "{}: {p:?}", f.name);
                    }
                } else {
                    assert_eq!(flags, 0, "{}", f.name);
                }
            }
        }
    }
    assert!(predictions > 20, "{predictions}");
    // Global localization starts with particles everywhere: many regenerate.
    assert!(regenerated > 100, "{regenerated}");
}

/// AMCL injects almost nothing while tracking (under 1% per update over 500
/// updates) and injects after a kidnap.
#[test]
fn amcl_injects_after_a_kidnap_and_hardly_while_tracking() {
    let mut run = MclRun::new(
        scenario(vec![LocalizationEstimator::Amcl], 300, 2),
        BuiltinMap::Maze.load().unwrap(),
    )
    .unwrap();
    while run.filters()[0].updates.len() < 500 {
        run.tick();
    }
    let ups = &run.filters()[0].updates;
    let mean: f64 = ups.iter().map(|u| u.randomized).sum::<f64>() / ups.len() as f64;
    let worst = ups.iter().map(|u| u.randomized).fold(0.0, f64::max);
    assert!(mean < 0.01 && worst < 0.05, "mean {mean}, worst {worst}");
    run.kidnap_random();
    let first = run.filters()[0].updates.len();
    for _ in 0..100 {
        run.tick();
    }
    let after = &run.filters()[0].updates[first..];
    let injected: f64 = after.iter().map(|u| u.randomized).sum();
    assert!(injected > 0.0, "no injection after the kidnap");
    assert!(after.iter().any(|u| u.injection_probability > 0.0));
}

/// A seeded kidnap on the maze, 6 trials of 1000 particles: both filters
/// recover in most trials, and the comparison is pinned as measured:
/// ACMCL median 33 updates (0 failures), AMCL median 325 (1 failure), ACMCL
/// regenerating about a quarter of its particles per update, AMCL injecting
/// almost none (the tempered likelihood keeps w_avg from falling far).
#[test]
#[cfg_attr(debug_assertions, ignore = "5 s in release")]
fn seeded_kidnap_acmcl_recovers_faster_than_amcl() {
    let grid = BuiltinMap::Maze.load().unwrap();
    let protocol = KidnapProtocol::default();
    let mut results = Vec::new();
    for est in [LocalizationEstimator::Amcl, LocalizationEstimator::Acmcl] {
        let trials: Vec<_> = (1..=6)
            .map(|s| kidnap_trial(&MclScenario::default(), &grid, est, 1000, s, &protocol).unwrap())
            .collect();
        results.push(summarize(est.name(), 1000, &trials, protocol.limit_updates));
    }
    let (amcl, acmcl) = (&results[0], &results[1]);
    assert!(amcl.failures <= 2 && acmcl.failures <= 1, "{results:?}");
    assert_eq!(acmcl.steps_to_converge.median, Some(33.0), "{results:?}");
    assert_eq!(amcl.steps_to_converge.median, Some(325.0), "{results:?}");
    assert!(
        acmcl.recovery_ratio > 0.15 && amcl.recovery_ratio < 0.01,
        "{results:?}"
    );
}

/// One kidnap trial is cheap enough to run always (300 particles, a short limit).
#[test]
fn one_kidnap_trial_runs_and_reports() {
    let grid = BuiltinMap::Maze.load().unwrap();
    let protocol = KidnapProtocol {
        limit_updates: 60,
        ..Default::default()
    };
    let t = kidnap_trial(
        &MclScenario::default(),
        &grid,
        LocalizationEstimator::Acmcl,
        300,
        3,
        &protocol,
    )
    .unwrap();
    assert!(t.kidnap_tick.is_some());
    assert!(t.recovery_ratio > 0.0 && t.recovery_ratio < 1.0, "{t:?}");
    let s = summarize("acmcl", 300, &[t], 60);
    assert_eq!(
        s.failures + usize::from(s.steps_to_converge.median.is_some()),
        1
    );
    // One trial: the median over all trials is its steps, or the limit.
    assert_eq!(
        s.median_all_trials,
        Some(t.steps_to_converge.unwrap_or(60) as f64)
    );
    // Failures count as the limit: steps 10, 20 and two failures (limit 60)
    // give 40 over all trials, 15 over the converged ones.
    let trial = |steps| KidnapTrial {
        steps_to_converge: steps,
        ..t
    };
    let s = summarize(
        "acmcl",
        300,
        &[trial(Some(10)), trial(None), trial(Some(20)), trial(None)],
        60,
    );
    assert_eq!(s.steps_to_converge.median, Some(15.0));
    assert_eq!(s.median_all_trials, Some(40.0));
    assert_eq!(s.failures, 2);
}

/// KLD-sampling: the particle count falls while tracking and rises after a
/// kidnap (ACMCL regenerates lost particles all over the maze), within its
/// limits. With the plain product likelihood (exponent 1): the tempered
/// default keeps the tracking cloud so wide that KLD keeps about the maximum.
#[test]
fn kld_count_falls_while_tracking_and_rises_after_a_kidnap() {
    let mut run = MclRun::new(
        MclScenario {
            kld_sampling: true,
            laser_likelihood_exponent: 1.0,
            min_particles: 100,
            max_particles: 3000,
            ..scenario(vec![LocalizationEstimator::Acmcl], 3000, 6)
        },
        BuiltinMap::Maze.load().unwrap(),
    )
    .unwrap();
    while run.filters()[0].updates.len() < 40 {
        run.tick();
    }
    let ups = &run.filters()[0].updates;
    let tracking = ups[20..].iter().map(|u| u.particles).sum::<usize>() / (ups.len() - 20);
    assert!(tracking < 800, "{tracking}");
    run.kidnap_random();
    let first = run.filters()[0].updates.len();
    for _ in 0..60 {
        run.tick();
    }
    let ups = &run.filters()[0].updates[first..];
    let peak = ups.iter().map(|u| u.particles).max().unwrap();
    assert!(peak > 2 * tracking && peak >= 1000, "{tracking} -> {peak}");
    assert!(
        run.filters()[0]
            .updates
            .iter()
            .all(|u| (100..=3000).contains(&u.particles))
    );
}

/// Right after a kidnap the scan is still the one taken before it (drawn from where
/// it was taken), the true path breaks at the teleport, and the status reads the
/// estimate's error against the truth now.
#[test]
fn a_kidnap_breaks_the_path_keeps_the_scan_pose_and_the_status_reads_the_error_now() {
    use LocalizationEstimator::*;
    let mut run = MclRun::new(
        scenario(vec![Amcl], 300, 3),
        BuiltinMap::Maze.load().unwrap(),
    )
    .unwrap();
    run.run_ticks(30);
    let before = run.robot().pose;
    assert_eq!(run.scan_pose(), Some(before), "the scan of the last move");
    assert_eq!(run.path_stretches().len(), 1);
    let path_len = run.path().len();
    run.kidnap_random();
    let after = run.robot().pose;
    assert!(slamlab_core::math::hypot(after.x - before.x, after.y - before.y) > 1.0);
    assert_eq!(run.scan_pose(), Some(before), "a kidnap takes no scan");
    let stretches = run.path_stretches();
    assert_eq!(stretches.len(), 2);
    assert_eq!(stretches[0].len(), path_len);
    assert_eq!(stretches[1], &[after][..]);
    // The status's error is the estimate's against the truth now, several metres.
    let now = run.error_now(0).unwrap();
    let estimate = run.filters()[0].current_estimate(&run.odometry()).unwrap();
    let by_hand = slamlab_core::math::hypot(estimate.x - after.x, estimate.y - after.y);
    assert_eq!(now.position, by_hand);
    assert!(now.position > 1.0, "{now:?}");
    let status = run.status_of(0);
    assert!(
        status.starts_with(&format!("lost: {:.2} m off", now.position)),
        "{status}"
    );
    // The records still hold the error from before the kidnap.
    let recorded = run.filters()[0].ticks.last().unwrap().position;
    assert!(recorded < 0.5, "{recorded}");
    // After the next move the scan is taken at the new place.
    run.run_ticks(1);
    assert_eq!(run.scan_pose(), Some(run.robot().pose));
    assert_eq!(run.path_stretches().len(), 2);
}
