//! Occupancy-grid mapping with a lidar (`lesson=mapping`, `slamlab run
//! mapping`): a simulated robot's log or a real CARMEN log, each scan given a
//! pose by the chosen source (the truth, odometry, ICP against the previous
//! scan, matching against the map so far, or grid FastSLAM's particles) and
//! inserted into a growing probability grid.
//!
//! - [`scenario`]: the parameter table.
//! - [`run`]: the run stepped phase by phase, and its metrics.
//! - [`MappingSession`]: the lesson's face on a [`Stepper`], opened from a
//!   scenario and an input.

pub mod assignment;
pub mod export;
pub mod grid_fastslam;
pub mod icp_assignment;
pub mod run;
pub mod scenario;
#[cfg(test)]
mod tests;

pub use run::{
    IcpScanRecord, MappingEvent, MappingPhase, MappingRecords, MappingSim, MatcherSettings,
};
pub use scenario::{MappingScenario, PoseSource, RuleKind, simulated_input};

use crate::grid::{MappingInput, map_agreement, trajectory_rmse};
use crate::params;
use crate::stepper::{CheckpointPolicy, Stepper};
use serde::Serialize;
use slamlab_core::Pose2;
use slamlab_core::scan::icp::IcpConfig;
use std::sync::Arc;

/// What a finished (or paused) run says about itself: `slamlab run mapping
/// --json` prints it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MappingSummary {
    /// Scans inserted.
    pub scans: usize,
    /// The pose source.
    pub poses: &'static str,
    /// The input's name.
    pub input: String,
    /// Seconds of data mapped.
    pub duration_s: f64,
    /// RMS position error against the truth, metres (simulation only).
    pub trajectory_rmse: Option<f64>,
    /// Share of the true map's known cells the built map classifies the same
    /// (simulation only).
    pub map_agreement: Option<f64>,
    /// The built map.
    pub map: MapSummary,
    /// Mean matcher iterations per scan (0 without a matcher).
    pub mean_iterations: f64,
    /// Grid FastSLAM's particles (that source only).
    pub particles: Option<ParticleSummary>,
}

/// What grid FastSLAM's particles did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ParticleSummary {
    /// Particles.
    pub particles: usize,
    /// `"odometry"` or `"scan-match"`.
    pub proposal: &'static str,
    /// Filter updates (scans processed; the rest were skipped).
    pub updates: usize,
    /// Resamplings.
    pub resamplings: usize,
    /// Particle proposals that fell back to odometry.
    pub fallbacks: usize,
    /// `N_eff` after the last weighting.
    pub neff: f64,
    /// Map memory the particles hold now, bytes (shared tiles once).
    pub memory_bytes: usize,
    /// The most they held after any update, bytes.
    pub peak_memory_bytes: usize,
}

/// The built map's size.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MapSummary {
    /// Cells across its observed bounds.
    pub width: usize,
    /// Cells up its observed bounds.
    pub height: usize,
    /// Metres per cell.
    pub resolution: f64,
    /// Cells observed at least once.
    pub known_cells: usize,
    /// Bytes of cell storage.
    pub memory_bytes: usize,
}

/// A mapping run with step and step back: the lesson's face on a
/// [`Stepper<MappingSim>`].
#[derive(Debug)]
pub struct MappingSession {
    scenario: MappingScenario,
    stepper: Stepper<MappingSim>,
}

impl MappingSession {
    /// A run of `scenario` over `input` (its pose source, rule and matcher
    /// settings); parameters out of range are clamped, and the notices say so.
    pub fn new(mut scenario: MappingScenario, input: Arc<MappingInput>) -> (Self, Vec<String>) {
        let mut notices = params::sanitize_notices(&mut scenario);
        if scenario.poses == PoseSource::Truth && input.truth.is_none() {
            notices.push("a log has no true poses: mapping with raw odometry instead".to_owned());
        }
        if let Err(why) = scenario.update_rule().log_odds_steps() {
            notices.push(format!(
                "the update rule cannot be used ({why}); the defaults apply"
            ));
            let defaults = MappingScenario::default();
            scenario.l_occ = defaults.l_occ;
            scenario.l_free = defaults.l_free;
            scenario.l_min = defaults.l_min;
            scenario.l_max = defaults.l_max;
            scenario.hit_probability = defaults.hit_probability;
            scenario.miss_probability = defaults.miss_probability;
            scenario.p_min = defaults.p_min;
            scenario.p_max = defaults.p_max;
        }
        let matchers = MatcherSettings {
            scan_to_map: scenario.scan_to_map_params(),
            icp: IcpConfig {
                max_correspondence_distance: scenario.icp_max_distance,
                trim_fraction: scenario.icp_trim,
                ..IcpConfig::default()
            },
            grid_fastslam: scenario.grid_fastslam_config(),
            seed: scenario.seed,
        };
        let sim = MappingSim::new(
            input,
            scenario.poses,
            scenario.resolution,
            scenario.insert_params(),
            matchers,
        );
        let policy = CheckpointPolicy {
            every_ticks: 100,
            max_checkpoints: 30,
            budget_bytes: 64 << 20,
        };
        let stepper = Stepper::with_policy(sim, MappingRecords::default(), policy);
        (Self { scenario, stepper }, notices)
    }

    /// The scenario (as clamped).
    pub fn scenario(&self) -> &MappingScenario {
        &self.scenario
    }

    /// The stepper (step, step back, records).
    pub fn stepper(&self) -> &Stepper<MappingSim> {
        &self.stepper
    }

    /// The stepper, to step.
    pub fn stepper_mut(&mut self) -> &mut Stepper<MappingSim> {
        &mut self.stepper
    }

    /// The run now.
    pub fn sim(&self) -> &MappingSim {
        self.stepper.sim()
    }

    /// Runs every remaining scan.
    pub fn run_to_end(&mut self) {
        while !self.sim().is_done() {
            self.stepper.step_tick();
        }
    }

    /// Every input scan's pose as the run has it now: the pose it was
    /// inserted at, or with grid FastSLAM the heaviest particle's path (its
    /// past corrected by later scans) with the scans the filter skipped moved
    /// by odometry from the last one it processed; `None` for scans not yet
    /// processed. What [`crate::grid::reference::score`] scores.
    pub fn scan_poses(&self) -> Vec<Option<Pose2>> {
        let sim = self.sim();
        let input = sim.input();
        let done = self.stepper.records().poses.len();
        let mut out: Vec<Option<Pose2>> = match sim.grid_fastslam().and_then(|f| f.best()) {
            Some(best) => {
                let odometry: Vec<Pose2> = input.scans.iter().map(|s| s.odometry).collect();
                crate::grid::reference::fill_by_odometry(&best.path.path(), &odometry)
            }
            None => self
                .stepper
                .records()
                .poses
                .iter()
                .copied()
                .map(Some)
                .collect(),
        };
        out.resize(input.scans.len(), None);
        for slot in out.iter_mut().skip(done) {
            *slot = None;
        }
        out
    }

    /// The metrics so far.
    pub fn summary(&self) -> MappingSummary {
        let mut summary = self.summary_without_agreement();
        let sim = self.sim();
        summary.map_agreement = sim
            .input()
            .true_map
            .as_ref()
            .and_then(|m| map_agreement(sim.grid(), m));
        summary
    }

    /// The metrics so far but the map agreement (which reads every cell of
    /// the true map): cheap enough for every frame.
    pub fn summary_without_agreement(&self) -> MappingSummary {
        let sim = self.sim();
        let input = sim.input();
        let records = self.stepper.records();
        let grid = sim.grid();
        let (width, height) = grid.known_bounds().map_or((0, 0), |(i0, j0, i1, j1)| {
            ((i1 - i0 + 1) as usize, (j1 - j0 + 1) as usize)
        });
        let matched: Vec<usize> = records
            .iterations
            .iter()
            .copied()
            .filter(|&n| n > 0)
            .collect();
        let duration = input
            .scans
            .get(records.poses.len().saturating_sub(1))
            .map_or(0.0, |s| s.time);
        let filter = sim.grid_fastslam();
        // Grid FastSLAM: the heaviest particle's path as it stands now (its
        // past corrected by later scans), at the scans it processed.
        let rmse = match (filter.and_then(|f| f.best()), input.truth.as_deref()) {
            (Some(best), Some(truth)) => {
                crate::mapping::grid_fastslam::path_rmse(&best.path.path(), truth)
            }
            (None, truth) if filter.is_none() => trajectory_rmse(&records.poses, truth),
            _ => None,
        };
        MappingSummary {
            scans: records.poses.len(),
            poses: sim.source().name(),
            input: input.name.clone(),
            duration_s: duration,
            trajectory_rmse: rmse,
            map_agreement: None,
            map: MapSummary {
                width,
                height,
                resolution: grid.resolution(),
                known_cells: grid.known_cells(),
                memory_bytes: grid.memory_bytes(),
            },
            mean_iterations: if matched.is_empty() {
                0.0
            } else {
                matched.iter().sum::<usize>() as f64 / matched.len() as f64
            },
            particles: filter.map(|f| ParticleSummary {
                particles: f.config().particles,
                proposal: f.config().proposal.name(),
                updates: f.updates(),
                resamplings: f.resamplings(),
                fallbacks: f.fallbacks(),
                neff: f.neff(),
                memory_bytes: f.memory_bytes(),
                peak_memory_bytes: f.peak_memory_bytes(),
            }),
        }
    }
}
