//! The fusion EKF over a 10-minute drive at the lesson's rates (wheel odometry
//! 50 Hz, IMU 100 Hz, SLAM pose 1 Hz: 90,601 measurements):
//! `cargo bench -p slamlab-sim --bench fusion`.
//!
//! Target (docs/fusion.md, "Sensor fusion (headless)"): under 0.5 s per drive natively.

use slamlab_sim::fusion::{DriveParams, FusionMode, FusionScenario, ModeRun, SensorLog, simulate};

fn main() {
    divan::main();
}

/// The drive; `None` only if the default scenario were invalid.
fn ten_minutes() -> Option<(FusionScenario, SensorLog)> {
    let scenario = FusionScenario {
        drive: DriveParams {
            duration: 600.0,
            ..Default::default()
        },
        ..Default::default()
    };
    let log = simulate(&scenario).ok()?;
    Some((scenario, log))
}

/// Every measurement of the drive applied in stamp order, the estimate sampled
/// at 30 Hz against the truth (what the experiment does per mode).
#[divan::bench(args = ["differential", "relative", "odometry"], sample_count = 10)]
fn fuse_ten_minute_drive(bencher: divan::Bencher, mode: &str) {
    let Some((scenario, log)) = ten_minutes() else {
        return;
    };
    let mode = match mode {
        "differential" => FusionMode::Differential,
        "relative" => FusionMode::Relative,
        _ => FusionMode::Odometry,
    };
    bencher.bench_local(|| {
        let mut run = ModeRun::new(&scenario, mode).ok()?;
        run.run_to_end(&log);
        Some(divan::black_box(run.rmse()))
    });
}

/// Simulating the drive and its sensors (the truth at 200 Hz).
#[divan::bench(sample_count = 10)]
fn simulate_ten_minute_drive() -> Option<SensorLog> {
    ten_minutes().map(|(_, log)| log)
}
