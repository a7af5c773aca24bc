//! Pose-graph optimization: `cargo bench -p slamlab-sim --bench posegraph`.
//!
//! Levenberg-Marquardt to convergence on synthetic Manhattan graphs (structure
//! analysis included), and one LM step. The comparison with gtsam on the standard
//! data sets is `scripts/bench-posegraph.sh` (docs/pose-graph.md, "Pose-graph SLAM").

use slamlab_core::graph::{Optimizer, OptimizerSettings};
use slamlab_sim::pose_graph::experiment::manhattan_graph;

fn main() {
    divan::main();
}

#[divan::bench(args = [500, 3500])]
fn lm_to_convergence_manhattan(bencher: divan::Bencher, poses: usize) {
    let (graph, _) = manhattan_graph(poses, 30, 1);
    bencher.bench_local(|| {
        let mut opt = Optimizer::new(graph.clone(), OptimizerSettings::default())
            .unwrap_or_else(|e| unreachable!("{e}"));
        let steps = opt.optimize(100, |_| true).map(|r| r.len()).unwrap_or(0);
        divan::black_box((opt.cost(), steps))
    });
}

#[divan::bench(args = [500, 3500])]
fn one_lm_step_manhattan(bencher: divan::Bencher, poses: usize) {
    let (graph, _) = manhattan_graph(poses, 30, 1);
    let mut opt =
        Optimizer::new(graph, OptimizerSettings::default()).unwrap_or_else(|e| unreachable!("{e}"));
    bencher.bench_local(|| divan::black_box(opt.step().map(|r| r.cost).unwrap_or(f64::NAN)));
}
