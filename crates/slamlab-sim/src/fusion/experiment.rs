//! `slamlab experiment fusion`: thesis `002` Table 5.3 reproduced on seeded drives.

use super::runner::{FusionMode, Rmse, run_modes};
use super::scenario::{FusionScenario, ScenarioError};
use super::sensors::simulate;
use serde::Serialize;

/// One trial's RMSEs (one block of Table 5.3, plus the odometry-only baseline).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FusionTrial {
    /// The trial's seed.
    pub seed: u64,
    /// `_differential`.
    pub differential: Rmse,
    /// `_relative`.
    pub relative: Rmse,
    /// Wheel odometry and IMU only.
    pub odometry: Rmse,
}

/// The mean of the trials' RMSEs, per mode (Table 5.3's "Average").
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FusionAverage {
    /// `_differential`.
    pub differential: Rmse,
    /// `_relative`.
    pub relative: Rmse,
    /// Wheel odometry and IMU only.
    pub odometry: Rmse,
}

/// The experiment's result, as `--json` prints it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FusionExperiment {
    /// Always "fusion".
    pub experiment: &'static str,
    /// Every parameter, with dotted names (`slam.rate`, `odometry.turn_slip`, ...).
    pub parameters: serde_json::Map<String, serde_json::Value>,
    /// One entry per trial.
    pub trials: Vec<FusionTrial>,
    /// The means over the trials.
    pub average: FusionAverage,
}

/// Flattens a JSON object into dotted keys (`drive.duration`).
fn flatten(
    prefix: &str,
    value: &serde_json::Value,
    out: &mut serde_json::Map<String, serde_json::Value>,
) {
    match value {
        serde_json::Value::Object(map) => {
            for (k, v) in map {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&key, v, out);
            }
        }
        other => {
            out.insert(prefix.to_owned(), other.clone());
        }
    }
}

/// Every parameter of `scenario` (all but the seed, which each trial lists) and
/// of the experiment, with dotted names.
pub fn parameters_json(
    scenario: &FusionScenario,
    trials: usize,
    seed: u64,
) -> serde_json::Map<String, serde_json::Value> {
    let mut out = serde_json::Map::new();
    out.insert("trials".into(), trials.into());
    out.insert("first_seed".into(), seed.into());
    if let Ok(value) = serde_json::to_value(scenario) {
        flatten("", &value, &mut out);
    }
    out.remove("seed");
    out
}

/// Runs `trials` drives of `template` with seeds `seed, seed + 1, …`, each fused
/// as `_differential`, `_relative` and odometry only, and reports each trial's
/// RMSE of x, y and yaw and their means (thesis `002` Table 5.3).
pub fn fusion_experiment(
    template: &FusionScenario,
    trials: usize,
    seed: u64,
    mut progress: impl FnMut(usize, usize),
) -> Result<FusionExperiment, ScenarioError> {
    template.validate()?;
    let mut results = Vec::with_capacity(trials);
    for i in 0..trials {
        let scenario = FusionScenario {
            seed: seed.wrapping_add(i as u64),
            ..template.clone()
        };
        let log = simulate(&scenario)?;
        let runs = run_modes(&scenario, &log, &FusionMode::TABLE)?;
        let rmse = |mode: FusionMode| {
            runs.iter()
                .find(|r| r.mode() == mode)
                .map(|r| r.rmse())
                .unwrap_or_default()
        };
        results.push(FusionTrial {
            seed: scenario.seed,
            differential: rmse(FusionMode::Differential),
            relative: rmse(FusionMode::Relative),
            odometry: rmse(FusionMode::Odometry),
        });
        progress(i + 1, trials);
    }
    let n = results.len().max(1) as f64;
    let mean = |pick: fn(&FusionTrial) -> Rmse| {
        let sum = results.iter().map(pick).fold(Rmse::default(), |a, b| Rmse {
            x: a.x + b.x,
            y: a.y + b.y,
            yaw: a.yaw + b.yaw,
        });
        Rmse {
            x: sum.x / n,
            y: sum.y / n,
            yaw: sum.yaw / n,
        }
    };
    let average = FusionAverage {
        differential: mean(|t| t.differential),
        relative: mean(|t| t.relative),
        odometry: mean(|t| t.odometry),
    };
    Ok(FusionExperiment {
        experiment: "fusion",
        parameters: parameters_json(template, trials, seed),
        trials: results,
        average,
    })
}

/// Thesis `002` Table 5.3 as printed: per trial `[differential x, y, yaw,
/// relative x, y, yaw]` (metres, metres, radians), then the average row.
pub const THESIS_TABLE_5_3: [[f64; 6]; 7] = [
    [0.1396, 0.1335, 0.01460, 0.2740, 0.1276, 0.01461],
    [0.1781, 0.1541, 0.01439, 0.3172, 0.1671, 0.01448],
    [0.1854, 0.2071, 0.01612, 0.2796, 0.1974, 0.01614],
    [0.1765, 0.1819, 0.01886, 0.2102, 0.1497, 0.01889],
    [0.1798, 0.1940, 0.01760, 0.3083, 0.1504, 0.01762],
    [0.1518, 0.1808, 0.01475, 0.3442, 0.1642, 0.01478],
    [0.1685, 0.1752, 0.01605, 0.2890, 0.1594, 0.01609],
];
