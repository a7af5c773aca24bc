//! Trajectory metrics: `cargo bench -p slamlab-sim --bench metrics`.
//!
//! One evaluation of a 10,000-pose estimate with covariances against a
//! 10,000-pose reference whose times are jittered: association by time, SE(2)
//! alignment, APE, RPE over one frame and NEES, as `slamlab evaluate` and a
//! lesson's dropped estimate run it (target: under 50 ms). Also the reading of
//! the estimate's CSV file.

use nalgebra::Matrix3;
use slamlab_core::{Pose2, math};
use slamlab_sim::io::trajectory::{read_trajectory, write_csv};
use slamlab_sim::metrics::{EvaluationSettings, Trajectory, evaluate};

fn main() {
    divan::main();
}

const POSES: usize = 10_000;

fn pair() -> (Trajectory, Trajectory) {
    let stamps: Vec<f64> = (0..POSES).map(|k| k as f64 * 0.1).collect();
    let truth: Vec<Pose2> = (0..POSES)
        .map(|k| {
            let t = k as f64 * 0.1;
            Pose2::new(
                20.0 * math::sin(0.01 * t),
                15.0 * math::sin(0.013 * t),
                0.02 * t,
            )
        })
        .collect();
    let est: Vec<Pose2> = truth
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let w = 0.05 * math::sin(k as f64);
            Pose2::new(p.x + w + 3.0, p.y - w, p.theta + 0.1 * w)
        })
        .collect();
    let jittered: Vec<f64> = stamps
        .iter()
        .enumerate()
        .map(|(k, t)| t + 0.004 * math::sin(1.3 * k as f64))
        .collect();
    let cov = vec![Matrix3::new(0.04, 0.001, 0.0, 0.001, 0.05, 0.0, 0.0, 0.0, 0.01); POSES];
    (
        Trajectory::new(stamps, truth),
        Trajectory::new(jittered, est).with_covariances(cov),
    )
}

/// Association, SE(2) alignment, APE, RPE and NEES of 10,000 poses.
#[divan::bench(sample_count = 20)]
fn evaluate_10000_poses(bencher: divan::Bencher) {
    let (truth, est) = pair();
    let settings = EvaluationSettings::default();
    bencher.bench_local(|| {
        let e = evaluate(divan::black_box(&truth), divan::black_box(&est), &settings);
        divan::black_box(e.map(|e| e.ape.translation.rmse).unwrap_or(f64::NAN))
    });
}

/// Reading the 10,000-pose CSV file (with covariances) an estimate arrives in.
#[divan::bench(sample_count = 20)]
fn read_10000_pose_csv(bencher: divan::Bencher) {
    let (_, est) = pair();
    let text = write_csv(&est);
    bencher.bench_local(|| {
        let t = read_trajectory("est.csv", divan::black_box(text.as_bytes()));
        divan::black_box(t.map(|t| t.trajectory.len()).unwrap_or(0))
    });
}
