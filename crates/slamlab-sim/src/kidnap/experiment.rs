//! The kidnapped-robot experiment (thesis `000` Sec. 5.1.4, Tables 5.1 and
//! 5.2): a filter tracks the exploring robot, the robot is kidnapped, and the
//! number of filter updates until the filter has found it again is counted,
//! with the fraction of particles randomized (injected or regenerated) per
//! update on the way.

use super::run::{CONVERGED_HEADING, CONVERGED_POSITION, CONVERGED_UPDATES, MclRun, MclRunError};
use super::scenario::{InitMode, LocalizationEstimator, MclScenario};
use serde::{Deserialize, Serialize};
use slamlab_core::grid::OccupancyGrid;

/// The protocol, printed with every result.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KidnapProtocol {
    /// The filter starts around the true pose (tracking) and tracks for this
    /// many updates before the kidnap.
    pub tracked_updates_before_kidnap: usize,
    /// The kidnap takes the robot at least this far, metres.
    pub kidnap_distance: f64,
    /// Converged: within this distance, metres...
    pub converged_position: f64,
    /// ...and this heading, radians...
    pub converged_heading: f64,
    /// ...for this many consecutive updates.
    pub converged_updates: usize,
    /// A trial that has not converged this many updates after the kidnap is a
    /// failure.
    pub limit_updates: usize,
}

impl Default for KidnapProtocol {
    fn default() -> Self {
        Self {
            tracked_updates_before_kidnap: 50,
            kidnap_distance: 3.0,
            converged_position: CONVERGED_POSITION,
            converged_heading: CONVERGED_HEADING,
            converged_updates: CONVERGED_UPDATES,
            limit_updates: 500,
        }
    }
}

/// One trial.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KidnapTrial {
    /// Estimator name.
    pub estimator: &'static str,
    /// Particle count.
    pub particles: usize,
    /// The trial's seed.
    pub seed: u64,
    /// The tick of the kidnap.
    pub kidnap_tick: Option<u64>,
    /// Updates from the kidnap to the first of the converged run, `None` if the
    /// limit was reached first.
    pub steps_to_converge: Option<usize>,
    /// Mean fraction of particles randomized or regenerated per update from the
    /// kidnap to convergence (to the limit if it never converged).
    pub recovery_ratio: f64,
}

/// Runs one trial of `estimator` with `particles` particles.
pub fn kidnap_trial(
    base: &MclScenario,
    grid: &OccupancyGrid,
    estimator: LocalizationEstimator,
    particles: usize,
    seed: u64,
    protocol: &KidnapProtocol,
) -> Result<KidnapTrial, MclRunError> {
    let scenario = MclScenario {
        estimators: vec![estimator],
        init: InitMode::Tracking,
        max_particles: particles,
        seed,
        kidnap_at: None,
        kidnap_distance: protocol.kidnap_distance,
        ..base.clone()
    };
    let mut run = MclRun::new(scenario, grid.clone())?;
    // A generous tick budget: the robot updates every 0.2 m or 30°.
    let max_ticks =
        40 * (protocol.tracked_updates_before_kidnap + protocol.limit_updates) as u64 + 1000;
    while run.filters()[0].updates.len() < protocol.tracked_updates_before_kidnap
        && run.tick_count() < max_ticks
    {
        run.tick();
    }
    run.kidnap_random();
    let first = run.filters()[0].updates.len();
    let mut converged = None;
    while run.tick_count() < max_ticks {
        run.tick();
        let ups = &run.filters()[0].updates;
        let after = ups.len() - first;
        if after >= protocol.converged_updates {
            let start = ups.len() - protocol.converged_updates;
            if ups[start..].iter().all(|r| {
                r.position_error <= protocol.converged_position
                    && r.heading_error <= protocol.converged_heading
            }) {
                converged = Some(start - first);
                break;
            }
        }
        if after >= protocol.limit_updates {
            break;
        }
    }
    let ups = &run.filters()[0].updates;
    let end = converged
        .map_or(ups.len(), |s| first + s + 1)
        .min(ups.len());
    let span = &ups[first.min(end)..end];
    let recovery_ratio = if span.is_empty() {
        0.0
    } else {
        span.iter().map(|r| r.randomized).sum::<f64>() / span.len() as f64
    };
    Ok(KidnapTrial {
        estimator: estimator.name(),
        particles,
        seed,
        kidnap_tick: run.kidnap_tick(),
        steps_to_converge: converged,
        recovery_ratio,
    })
}

/// Statistics of `steps_to_converge` over the converged trials.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepStats {
    /// Median.
    pub median: Option<f64>,
    /// Mean.
    pub mean: Option<f64>,
    /// 90th percentile (nearest rank).
    pub p90: Option<f64>,
}

/// One (estimator, particle count) row of Tables 5.1 and 5.2.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KidnapResult {
    /// Estimator name.
    pub estimator: String,
    /// Particle count.
    pub particles: usize,
    /// Updates from the kidnap to convergence, over the converged trials.
    pub steps_to_converge: StepStats,
    /// Median over all trials, a failure counted as the limit (the median over
    /// the converged trials alone hides the failures). `None` without trials.
    pub median_all_trials: Option<f64>,
    /// Trials that did not converge within the limit.
    pub failures: usize,
    /// Mean over trials of the per-update randomized fraction (Table 5.2).
    pub recovery_ratio: f64,
}

/// The median of the sorted `values`, `None` if empty.
fn median_of_sorted(values: &[f64]) -> Option<f64> {
    let n = values.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(values[n / 2]),
        _ => Some(0.5 * (values[n / 2 - 1] + values[n / 2])),
    }
}

/// Summarizes trials of one estimator and particle count; a failed trial
/// counts as `limit_updates` in [`KidnapResult::median_all_trials`].
pub fn summarize(
    estimator: &str,
    particles: usize,
    trials: &[KidnapTrial],
    limit_updates: usize,
) -> KidnapResult {
    let mut all: Vec<f64> = trials
        .iter()
        .map(|t| t.steps_to_converge.unwrap_or(limit_updates) as f64)
        .collect();
    all.sort_by(f64::total_cmp);
    let mut steps: Vec<f64> = trials
        .iter()
        .filter_map(|t| t.steps_to_converge.map(|s| s as f64))
        .collect();
    steps.sort_by(f64::total_cmp);
    let n = steps.len();
    let stats = if n == 0 {
        StepStats {
            median: None,
            mean: None,
            p90: None,
        }
    } else {
        let rank = ((0.9 * n as f64).ceil() as usize).clamp(1, n);
        StepStats {
            median: median_of_sorted(&steps),
            mean: Some(steps.iter().sum::<f64>() / n as f64),
            p90: Some(steps[rank - 1]),
        }
    };
    KidnapResult {
        estimator: estimator.to_owned(),
        particles,
        steps_to_converge: stats,
        median_all_trials: median_of_sorted(&all),
        failures: trials.len() - n,
        recovery_ratio: if trials.is_empty() {
            0.0
        } else {
            trials.iter().map(|t| t.recovery_ratio).sum::<f64>() / trials.len() as f64
        },
    }
}
