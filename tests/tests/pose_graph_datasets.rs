//! The standard 2D pose-graph data sets against gtsam 4.3.0's final errors
//! (`../shared/data/posegraphs/README.md`, doubled: SLAM Lab's cost Σ eᵀΩe is twice
//! gtsam's `graph.error`). Skipped with a message when `../shared` is absent;
//! city10000 and Victoria Park run only in the release profile.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

use slamlab_core::graph::{EdgeKind, Optimizer, OptimizerSettings, SolverKind};
use slamlab_sim::io::graph::read_graph;
use slamlab_tests::shared_data;

fn load(file: &str) -> Option<slamlab_core::graph::PoseGraph> {
    let path = shared_data(&format!("posegraphs/{file}"))?;
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
    let mut g = read_graph(&text).unwrap_or_else(|e| panic!("{file}: {e}"));
    // The gauge as in the CLI: the first vertex held fixed (gtsam's reference
    // puts a tight prior there; the optimum is the same).
    assert!(!g.edges().iter().any(EdgeKind::is_prior));
    let first = g.vertices()[0].id;
    g.set_fixed(first, true).unwrap();
    Some(g)
}

/// Optimizes and returns (final cost, steps).
fn optimize(file: &str, solver: SolverKind, max_iterations: usize) -> Option<(f64, usize)> {
    let g = load(file)?;
    let mut opt = Optimizer::new(
        g,
        OptimizerSettings {
            solver,
            ..OptimizerSettings::default()
        },
    )
    .unwrap_or_else(|e| panic!("{file}: {e}"));
    let steps = opt
        .optimize(max_iterations, |_| true)
        .unwrap_or_else(|e| panic!("{file}: {e}"));
    Some((opt.cost(), steps.len()))
}

/// gtsam's final error × 2, relative tolerance 0.1 %.
fn assert_matches_gtsam(file: &str, solver: SolverKind, gtsam_error: f64) {
    let Some((cost, steps)) = optimize(file, solver, 100) else {
        return;
    };
    let reference = 2.0 * gtsam_error;
    let rel = (cost - reference) / reference;
    println!(
        "{file} {solver:?}: {cost} after {steps} steps, gtsam × 2 = {reference}, {:+.4} %",
        100.0 * rel
    );
    assert!(
        rel.abs() < 1e-3,
        "{file}: {cost} vs gtsam × 2 = {reference}"
    );
}

#[test]
fn intel_fr079_frh_m3500_match_gtsam_with_lm_and_gn() {
    for solver in [SolverKind::LevenbergMarquardt, SolverKind::GaussNewton] {
        assert_matches_gtsam("intel.g2o", solver, 22.5021);
        assert_matches_gtsam("FR079.g2o", solver, 18.7856);
        assert_matches_gtsam("FRH.g2o", solver, 9.65685e-5);
    }
    assert_matches_gtsam("M3500.g2o", SolverKind::LevenbergMarquardt, 68.9574);
}

#[test]
fn mitb_from_its_poor_start_reaches_gtsam_cost() {
    // gtsam's LM reaches 385.122 (GN fails). The minimum of SLAM Lab's cost, whose
    // pose-pose error is thesis Eq. 4.5 (g2o's) rather than gtsam's SE(2)
    // logarithm, lies 0.06 % above gtsam's: the two costs differ at MITb's large
    // residuals. Bound: within 0.1 %.
    let Some((cost, steps)) = optimize("MITb.g2o", SolverKind::LevenbergMarquardt, 100) else {
        return;
    };
    println!("MITb: {cost} after {steps} steps (gtsam × 2 = 770.244)");
    assert!(cost < 770.244 * 1.001, "{cost}");
    assert!(steps < 40);
}

#[test]
fn city10000_and_victoria_park_match_gtsam_in_release() {
    if cfg!(debug_assertions) {
        println!(
            "skipped in the debug profile (city10000 and Victoria Park take a few seconds in release): run `cargo test -p slamlab-tests --release --test pose_graph_datasets`"
        );
        return;
    }
    assert_matches_gtsam("city10000.g2o", SolverKind::LevenbergMarquardt, 255.994);
    // Victoria Park: gtsam's LM stops at 105330 after 64 iterations; SLAM Lab's LM
    // goes on to a slightly lower cost. Bound: no worse than gtsam's + 0.1 %.
    if let Some((cost, steps)) = optimize("victoria_park.txt", SolverKind::LevenbergMarquardt, 400)
    {
        println!("victoria: {cost} after {steps} steps (gtsam × 2 = 210660)");
        assert!(cost < 210_660.0 * 1.001, "{cost}");
    }
}
