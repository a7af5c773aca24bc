//! Grid FastSLAM over a mapping input (a simulated robot's log or a real
//! one), and the experiment `slamlab experiment grid-fastslam` runs: the
//! odometry and the improved (scan-matching) proposal over particle counts.
//!
//! The filter is [`slamlab_core::particle::GridFastSlam`]; this module feeds
//! it the scans and measures it. The truth of a simulated log reaches only
//! the metrics: the best particle's path at its update scans against the true
//! poses, and its map against the true map.

use super::scenario::{MappingScenario, simulated_input};
use crate::grid::{MappingInput, builtin_map, map_agreement};
use serde::Serialize;
use slamlab_core::Pose2;
use slamlab_core::grid::{InsertParams, OccupancyGrid};
use slamlab_core::particle::{GridFastSlam, GridFastSlamConfig, Proposal};
use std::sync::Arc;
use std::time::Instant;

/// What one run of grid FastSLAM measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GridRunSummary {
    /// Scans read.
    pub scans: usize,
    /// Filter updates (the robot moved `linear_update` or `angular_update`).
    pub updates: usize,
    /// Resamplings.
    pub resamplings: usize,
    /// Particle proposals that fell back to odometry.
    pub fallbacks: usize,
    /// RMS position error of the best particle's path at its update scans,
    /// metres (simulation only).
    pub trajectory_rmse: Option<f64>,
    /// The best particle's map against the true map ([`map_agreement`];
    /// simulation only).
    pub map_agreement: Option<f64>,
    /// Wall-clock time of the run, milliseconds.
    pub time_ms: f64,
    /// The most map memory the particles held at once, bytes (shared tiles
    /// counted once).
    pub peak_memory_bytes: usize,
}

/// Runs `config` over every scan of `input`, inserting with `insert`.
/// Returns the filter at the end and what the run measured.
pub fn run_grid_fastslam(
    input: &MappingInput,
    config: GridFastSlamConfig,
    insert: InsertParams,
    seed: u64,
) -> (GridFastSlam, GridRunSummary) {
    let (mut filter, _) = GridFastSlam::new(config, insert, seed);
    let started = Instant::now();
    for (k, s) in input.scans.iter().enumerate() {
        filter.process(k, s.odometry, &s.scan);
    }
    let time_ms = started.elapsed().as_secs_f64() * 1e3;
    let summary = summarize(&filter, input, time_ms);
    (filter, summary)
}

/// The metrics of a filter that has read `input`.
pub fn summarize(filter: &GridFastSlam, input: &MappingInput, time_ms: f64) -> GridRunSummary {
    let best = filter.best();
    let trajectory_rmse = match (best, &input.truth) {
        (Some(b), Some(truth)) => path_rmse(&b.path.path(), truth),
        _ => None,
    };
    let map_agreement = match (best, &input.true_map) {
        (Some(b), Some(map)) => map_agreement(&b.map, map),
        _ => None,
    };
    GridRunSummary {
        scans: input.scans.len(),
        updates: filter.updates(),
        resamplings: filter.resamplings(),
        fallbacks: filter.fallbacks(),
        trajectory_rmse,
        map_agreement,
        time_ms,
        peak_memory_bytes: filter.peak_memory_bytes(),
    }
}

/// RMS position error of a path of `(scan, pose)` against the true poses.
pub fn path_rmse(path: &[(usize, Pose2)], truth: &[Pose2]) -> Option<f64> {
    let errors: Vec<f64> = path
        .iter()
        .filter_map(|(k, p)| {
            let t = truth.get(*k)?;
            Some((p.x - t.x).powi(2) + (p.y - t.y).powi(2))
        })
        .collect();
    (!errors.is_empty()).then(|| (errors.iter().sum::<f64>() / errors.len() as f64).sqrt())
}

/// A median and a 90th percentile.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Spread {
    /// The median.
    pub median: f64,
    /// The 90th percentile (nearest rank).
    pub p90: f64,
}

/// A median alone.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Median {
    /// The median.
    pub median: f64,
}

/// One row of the experiment: a particle count and a proposal over trials.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GridExperimentRow {
    /// Particles.
    pub particles: usize,
    /// The proposal's name.
    pub proposal: &'static str,
    /// The best particle's trajectory RMSE over trials, metres.
    pub trajectory_rmse: Spread,
    /// Map agreement over trials.
    pub map_agreement: Median,
    /// Resamplings per run, mean.
    pub resamplings: f64,
    /// Updates per run, mean.
    pub updates: f64,
    /// Wall-clock milliseconds per run, mean.
    pub time_ms: f64,
    /// The largest map memory of any run, megabytes.
    pub memory_mb: f64,
    /// Every trial's RMSE, in seed order.
    pub trials: Vec<f64>,
}

/// The experiment's result.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GridExperiment {
    /// `"grid-fastslam"`.
    pub experiment: &'static str,
    /// The map the robot drove in.
    pub map: String,
    /// Scans per trial.
    pub steps: usize,
    /// Trials per row (trial `i` uses seed `seed + i`).
    pub trials: usize,
    /// The first seed.
    pub seed: u64,
    /// The filter's settings (the particle count and proposal vary by row).
    pub config: GridFastSlamConfig,
    /// One row per particle count and proposal.
    pub results: Vec<GridExperimentRow>,
}

/// What the experiment runs: every particle count with every proposal over
/// `trials` simulated drives of `steps` scans (trial `i`: seed `seed + i`,
/// the same drive for every row).
#[derive(Clone, Debug, PartialEq)]
pub struct GridExperimentPlan {
    /// Particle counts.
    pub counts: Vec<usize>,
    /// Proposals.
    pub proposals: Vec<Proposal>,
    /// Drives per row.
    pub trials: usize,
    /// Scans per drive.
    pub steps: usize,
    /// The first drive's seed.
    pub seed: u64,
}

/// Runs `plan` with `config` (its particle count and proposal set by each
/// row) in `map`, reporting progress as `(done, total)`.
pub fn grid_fastslam_experiment(
    map: (Arc<OccupancyGrid>, String),
    config: GridFastSlamConfig,
    plan: &GridExperimentPlan,
    mut progress: impl FnMut(usize, usize),
) -> Result<GridExperiment, String> {
    let GridExperimentPlan {
        counts,
        proposals,
        trials,
        steps,
        seed,
    } = plan.clone();
    let (grid, name) = map;
    let inputs: Vec<MappingInput> = (0..trials)
        .map(|i| {
            let scenario = MappingScenario {
                seed: seed + i as u64,
                steps,
                map: name.clone(),
                ..MappingScenario::default()
            };
            simulated_input(&scenario, Arc::clone(&grid), &name)
        })
        .collect::<Result<_, _>>()?;
    let insert = MappingScenario::default().insert_params();
    let total = counts.len() * proposals.len() * trials;
    let mut done = 0;
    let mut results = Vec::new();
    for &particles in &counts {
        for &proposal in &proposals {
            let config = GridFastSlamConfig {
                particles,
                proposal,
                ..config
            };
            let mut runs = Vec::with_capacity(trials);
            for (i, input) in inputs.iter().enumerate() {
                let (_, summary) = run_grid_fastslam(input, config, insert, seed + i as u64);
                runs.push(summary);
                done += 1;
                progress(done, total);
            }
            let rmse: Vec<f64> = runs.iter().filter_map(|r| r.trajectory_rmse).collect();
            let agreement: Vec<f64> = runs.iter().filter_map(|r| r.map_agreement).collect();
            let mean = |f: &dyn Fn(&GridRunSummary) -> f64| {
                runs.iter().map(f).sum::<f64>() / runs.len().max(1) as f64
            };
            results.push(GridExperimentRow {
                particles,
                proposal: proposal.name(),
                trajectory_rmse: Spread {
                    median: quantile(&rmse, 0.5),
                    p90: quantile(&rmse, 0.9),
                },
                map_agreement: Median {
                    median: quantile(&agreement, 0.5),
                },
                resamplings: mean(&|r| r.resamplings as f64),
                updates: mean(&|r| r.updates as f64),
                time_ms: mean(&|r| r.time_ms),
                memory_mb: runs.iter().map(|r| r.peak_memory_bytes).max().unwrap_or(0) as f64 / 1e6,
                trials: rmse,
            });
        }
    }
    Ok(GridExperiment {
        experiment: "grid-fastslam",
        map: name,
        steps,
        trials,
        seed,
        config,
        results,
    })
}

/// The built-in map `name` with its name, for the experiment.
pub fn builtin(name: &str) -> Result<(Arc<OccupancyGrid>, String), String> {
    Ok((Arc::new(builtin_map(name)?), name.to_owned()))
}

/// The nearest-rank quantile `q` of `values` (NaN for none).
fn quantile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

#[cfg(test)]
mod tests;
