//! One mapping run: scans in order, each given a pose by the chosen source and
//! inserted into a probability grid. Stepped phase by phase by the generic
//! [`Stepper`](crate::stepper::Stepper): *predict* (odometry), *match* (the
//! scan matcher's correction), *insert* (the grid update). With
//! [`MappingEvent::StepIterations`] on, an ICP match is shown one iteration
//! per phase (the alignment is computed at once; each phase reveals the next
//! iteration's correspondences and pose).
//!
//! With grid FastSLAM as the pose source a scan takes gmapping's phases
//! instead: *propose* (every particle's odometry sample in one phase, or each
//! particle's scan match and the Gaussian around it in a phase of its own),
//! *weight* (`N_eff`), *resample* (only when `N_eff`
//! is low) and *update maps*; a scan taken before the robot has moved
//! `linear_update` or `angular_update` is skipped in one phase, as gmapping
//! skips it.
//!
//! The input is the same for every pose source (a simulated log or a real
//! one), so switching the source replays the same scans. The truth of a
//! simulated log travels beside the input and reaches only the metrics.

use super::scenario::PoseSource;
use crate::grid::{InputScan, MappingInput};
use crate::stepper::{Records, Simulation};
use slamlab_core::Pose2;
use slamlab_core::grid::{BeamUpdate, InsertParams, InsertReport, ProbabilityGrid};
use slamlab_core::particle::grid_fastslam::LikelihoodPoints;
use slamlab_core::particle::{GridFastSlam, GridFastSlamConfig, Proposal};
use slamlab_core::scan::Point2;
use slamlab_core::scan::icp::{IcpConfig, IcpIteration, IcpVariant, align};
use slamlab_core::scan::scan_to_map::{
    ProbabilityLookup, ScanToMapParams, ScanToMapRecord, match_scan_to_map,
};
use slamlab_core::wrap_angle;
use std::sync::Arc;

/// The phase a run is at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Predict,
    Match,
    /// Showing ICP iteration `i` (0-based) of the current scan's match.
    Iteration(usize),
    /// Grid FastSLAM: the particles are being moved by the improved
    /// proposal, one per phase.
    Proposing,
    /// Grid FastSLAM: the particles are proposed; next their weights.
    Weight,
    /// Grid FastSLAM: `N_eff` is low; next the resampling.
    Resample,
    /// Insert the scan (grid FastSLAM: into every particle's map).
    Insert,
}

/// A change a student makes during a run (recorded, so that stepping back
/// replays it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MappingEvent {
    /// Show ICP matches one iteration per phase (or the whole match in one).
    StepIterations(bool),
}

/// The ICP alignment of one scan against the previous one, every iteration.
#[derive(Clone, Debug, PartialEq)]
pub struct IcpScanRecord {
    /// The scan matched.
    pub scan: usize,
    /// The scan it was matched against (the previous one).
    pub reference_scan: usize,
    /// The reference scan's pose in the world: the frame of the iterations'
    /// poses and correspondences.
    pub reference_pose: Pose2,
    /// Every iteration, in order.
    pub iterations: Vec<IcpIteration>,
}

/// What one phase did.
#[derive(Clone, Debug, PartialEq)]
pub enum MappingPhase {
    /// The pose predicted for scan `scan` (odometry or truth).
    Predict {
        /// Scan index.
        scan: usize,
        /// The predicted pose.
        pose: Pose2,
    },
    /// The matcher's correction.
    Match {
        /// Scan index.
        scan: usize,
        /// The matched pose.
        pose: Pose2,
        /// The matcher's final cost.
        cost: f64,
        /// Its iterations.
        iterations: usize,
    },
    /// One ICP iteration of the current scan's match, shown on its own.
    Iteration {
        /// Scan index.
        scan: usize,
        /// 1 for the first iteration.
        iteration: usize,
        /// Iterations of the whole match.
        of: usize,
        /// The pose after this iteration (world frame).
        pose: Pose2,
        /// Mean squared error of the kept pairs at the iteration's start, m².
        mean_squared_error: f64,
        /// Pairs kept.
        kept: usize,
    },
    /// Grid FastSLAM's first scan: one map from it, shared by every particle.
    GridStart {
        /// Scan index.
        scan: usize,
        /// Particles.
        particles: usize,
    },
    /// Grid FastSLAM skipped a scan: the robot has not moved far enough since
    /// the last update.
    GridSkip {
        /// Scan index.
        scan: usize,
        /// Metres moved since the last update (by odometry).
        moved: f64,
        /// Radians turned since the last update.
        turned: f64,
    },
    /// Grid FastSLAM moved every particle by its proposal.
    GridPropose {
        /// Scan index.
        scan: usize,
        /// `"odometry"` or `"scan-match"`.
        proposal: &'static str,
        /// Particles whose scan match failed and took the odometry proposal.
        fallbacks: usize,
    },
    /// Grid FastSLAM moved one particle by the improved proposal.
    GridParticle {
        /// Scan index.
        scan: usize,
        /// The particle (0-based).
        particle: usize,
        /// Particles.
        of: usize,
        /// Its scan could not be matched: it took the odometry proposal.
        fell_back: bool,
    },
    /// Grid FastSLAM weighted the particles.
    GridWeight {
        /// Scan index.
        scan: usize,
        /// The effective sample size after weighting.
        neff: f64,
        /// Resampling happens below this `N_eff`.
        threshold: f64,
    },
    /// Grid FastSLAM resampled.
    GridResample {
        /// Scan index.
        scan: usize,
        /// Distinct particles that survived.
        survivors: usize,
        /// Particles.
        of: usize,
    },
    /// Grid FastSLAM inserted the scan into every particle's map.
    GridUpdate {
        /// Scan index.
        scan: usize,
        /// Cells the scan updated in the heaviest particle's map.
        cells: usize,
        /// Map memory all particles hold, bytes (shared tiles once).
        memory_bytes: usize,
    },
    /// The scan went into the map.
    Insert {
        /// Scan index.
        scan: usize,
        /// What it changed.
        report: InsertReport,
    },
    /// Every scan is in.
    Done,
}

impl MappingPhase {
    /// Whether the phase is part of a grid FastSLAM update (every particle's
    /// proposal, the weights, resampling, the maps): the steps that cost
    /// more than drawing a frame.
    pub fn is_filter_update(&self) -> bool {
        matches!(
            self,
            MappingPhase::GridStart { .. }
                | MappingPhase::GridPropose { .. }
                | MappingPhase::GridParticle { .. }
                | MappingPhase::GridWeight { .. }
                | MappingPhase::GridResample { .. }
                | MappingPhase::GridUpdate { .. }
        )
    }

    /// A short name for the time bar.
    pub fn label(&self) -> String {
        match self {
            MappingPhase::Predict { scan, .. } => format!("predict scan {scan}"),
            MappingPhase::Match {
                scan, iterations, ..
            } => {
                format!("match scan {scan} ({iterations} iterations)")
            }
            MappingPhase::Iteration {
                scan,
                iteration,
                of,
                ..
            } => format!("scan {scan}: ICP iteration {iteration} of {of}"),
            MappingPhase::Insert { scan, report } => format!(
                "insert scan {scan}: {} hit, {} crossed cells",
                report.hits, report.misses
            ),
            MappingPhase::GridStart { scan, particles } => {
                format!("scan {scan}: {particles} particles share its map")
            }
            MappingPhase::GridSkip {
                scan,
                moved,
                turned,
            } => format!(
                "scan {scan} skipped: {moved:.2} m, {:.0}° since the last update",
                turned.to_degrees()
            ),
            MappingPhase::GridPropose {
                scan,
                proposal,
                fallbacks,
            } => {
                if *fallbacks > 0 {
                    format!("scan {scan}: {proposal} proposal ({fallbacks} fell back to odometry)")
                } else {
                    format!("scan {scan}: {proposal} proposal")
                }
            }
            MappingPhase::GridParticle {
                scan,
                particle,
                of,
                fell_back,
            } => {
                let n = particle + 1;
                if *fell_back {
                    format!("scan {scan}: particle {n} of {of} could not match: odometry proposal")
                } else {
                    format!("scan {scan}: particle {n} of {of} scan-matched, pose drawn")
                }
            }
            MappingPhase::GridWeight {
                scan,
                neff,
                threshold,
            } => {
                let verdict = if *neff < *threshold {
                    "resample next"
                } else {
                    "no resampling"
                };
                format!(
                    "scan {scan}: weights, N_eff {neff:.1} (threshold {threshold:.1}): {verdict}"
                )
            }
            MappingPhase::GridResample {
                scan,
                survivors,
                of,
            } => {
                format!("scan {scan}: resampled, {survivors} of {of} particles survive")
            }
            MappingPhase::GridUpdate {
                scan,
                cells,
                memory_bytes,
            } => format!(
                "scan {scan}: every particle's map updated ({cells} cells; maps {:.1} MB)",
                *memory_bytes as f64 / 1e6
            ),
            MappingPhase::Done => "every scan is in the map".to_owned(),
        }
    }
}

/// What a run records scan by scan (outside the checkpoints).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MappingRecords {
    /// The pose each scan was inserted at.
    pub poses: Vec<Pose2>,
    /// The matcher's cost per scan (NaN where nothing was matched).
    pub costs: Vec<f64>,
    /// The matcher's iterations per scan.
    pub iterations: Vec<usize>,
    /// Grid FastSLAM: `N_eff` after weighting, per scan (NaN where the scan
    /// was skipped or another source runs).
    pub neff: Vec<f64>,
    /// Grid FastSLAM: whether the particles were resampled at each scan.
    pub resampled: Vec<bool>,
}

impl Records for MappingRecords {
    type Mark = usize;
    fn mark(&self) -> usize {
        self.poses.len()
    }
    fn truncate(&mut self, mark: &usize) {
        self.poses.truncate(*mark);
        self.costs.truncate(*mark);
        self.iterations.truncate(*mark);
        self.neff.truncate(*mark);
        self.resampled.truncate(*mark);
    }
}

/// The matcher settings of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatcherSettings {
    /// Scan-to-map.
    pub scan_to_map: ScanToMapParams,
    /// ICP (the variant is set by the pose source).
    pub icp: IcpConfig,
    /// Grid FastSLAM.
    pub grid_fastslam: GridFastSlamConfig,
    /// Grid FastSLAM's seed.
    pub seed: u64,
}

/// One mapping run. Cloning it is a checkpoint (the grid's tiles are shared
/// until written).
#[derive(Clone, Debug)]
pub struct MappingSim {
    input: Arc<MappingInput>,
    source: PoseSource,
    insert: InsertParams,
    matchers: MatcherSettings,
    lookup: Arc<ProbabilityLookup>,
    grid: ProbabilityGrid,
    /// The scan the next tick works on.
    next: usize,
    stage: Stage,
    /// The current scan's pose (predicted, then matched).
    pose: Pose2,
    /// The last inserted scan's pose and index.
    last: Option<(usize, Pose2)>,
    /// The last scan-to-map match, for the explanation panel.
    last_record: Option<Arc<ScanToMapRecord>>,
    /// The last ICP match, every iteration (for drawing its correspondences).
    icp_record: Option<Arc<IcpScanRecord>>,
    /// The ICP iteration shown now (while stepping through a match).
    shown_iteration: Option<usize>,
    /// Whether ICP matches are shown one iteration per phase.
    step_iterations: bool,
    /// The grid before the last insertion (tiles shared), so that a beam's
    /// update can still be explained after it happened; kept only while
    /// [`MappingSim::keep_grid_before_insert`] is on, as holding it makes every
    /// insertion copy the tiles it writes.
    grid_before_insert: Option<ProbabilityGrid>,
    /// Whether to keep [`Self::grid_before_insert`].
    keep_before: bool,
    /// The matched pose while its iterations are being shown.
    matched: Pose2,
    /// The last message about something that went wrong (a bad rule).
    note: Option<String>,
    /// The particle filter, when grid FastSLAM is the pose source.
    fastslam: Option<Box<GridFastSlam>>,
}

impl MappingSim {
    /// A run over `input` with poses from `source`.
    pub fn new(
        input: Arc<MappingInput>,
        source: PoseSource,
        resolution: f64,
        insert: InsertParams,
        matchers: MatcherSettings,
    ) -> Self {
        // Without truth there are no true poses to map with.
        let source = if source == PoseSource::Truth && input.truth.is_none() {
            PoseSource::Odometry
        } else {
            source
        };
        Self {
            input,
            source,
            insert,
            matchers,
            lookup: Arc::new(ProbabilityLookup::default()),
            grid: ProbabilityGrid::new(resolution),
            next: 0,
            stage: Stage::Predict,
            pose: Pose2::IDENTITY,
            last: None,
            last_record: None,
            icp_record: None,
            shown_iteration: None,
            step_iterations: false,
            grid_before_insert: None,
            keep_before: false,
            matched: Pose2::IDENTITY,
            note: None,
            fastslam: (source == PoseSource::GridFastSlam).then(|| {
                let config = GridFastSlamConfig {
                    delta: resolution,
                    ..matchers.grid_fastslam
                };
                Box::new(GridFastSlam::new(config, insert, matchers.seed).0)
            }),
        }
    }

    /// The particle filter, when grid FastSLAM is the pose source.
    pub fn grid_fastslam(&self) -> Option<&GridFastSlam> {
        self.fastslam.as_deref()
    }

    /// The input.
    pub fn input(&self) -> &Arc<MappingInput> {
        &self.input
    }

    /// The pose source (odometry if truth was asked for a log without it).
    pub fn source(&self) -> PoseSource {
        self.source
    }

    /// The map so far (grid FastSLAM: the heaviest particle's).
    pub fn grid(&self) -> &ProbabilityGrid {
        self.fastslam
            .as_ref()
            .and_then(|f| f.best())
            .map_or(&self.grid, |p| &p.map)
    }

    /// Scans inserted so far.
    pub fn scans_done(&self) -> usize {
        self.last.map_or(0, |(k, _)| k + 1)
    }

    /// Whether every scan is in the map.
    pub fn is_done(&self) -> bool {
        self.next >= self.input.scans.len()
    }

    /// The scan being worked on (or the last one), its index and its pose now.
    pub fn current(&self) -> Option<(usize, &InputScan, Pose2)> {
        if self.stage != Stage::Predict && self.next < self.input.scans.len() {
            return Some((self.next, &self.input.scans[self.next], self.pose));
        }
        let (k, pose) = self.last?;
        Some((k, &self.input.scans[k], pose))
    }

    /// The last scan-to-map match.
    pub fn last_scan_to_map(&self) -> Option<&ScanToMapRecord> {
        self.last_record.as_deref()
    }

    /// The last ICP match and the iteration shown now (`None`: the whole
    /// match is done).
    pub fn icp_record(&self) -> Option<(&IcpScanRecord, Option<usize>)> {
        self.icp_record
            .as_deref()
            .map(|record| (record, self.shown_iteration))
    }

    /// Whether ICP matches are shown one iteration per phase.
    pub fn steps_iterations(&self) -> bool {
        self.step_iterations
    }

    /// Keeps the grid as it was before each insertion (shared tiles), so that
    /// [`explain_beam`](Self::explain_beam) can explain a scan already inserted.
    /// A display setting: it changes no result.
    pub fn keep_grid_before_insert(&mut self, on: bool) {
        self.keep_before = on;
        if !on {
            self.grid_before_insert = None;
        }
    }

    /// Whether the grid before each insertion is kept.
    pub fn keeps_grid_before_insert(&self) -> bool {
        self.keep_before
    }

    /// Whether the next phase inserts the current scan.
    pub fn next_is_insert(&self) -> bool {
        self.stage == Stage::Insert && !self.is_done()
    }

    /// What beam `beam` of the current scan does to the map: before the
    /// insertion (the next phase inserts it) or, once it is in, what it did.
    /// `None` before the first scan, or after an insertion made while
    /// [`keep_grid_before_insert`](Self::keep_grid_before_insert) was off.
    pub fn explain_beam(&self, beam: usize) -> Option<Result<BeamUpdate, String>> {
        if self.fastslam.is_some() {
            // Every particle inserts into its own map.
            return None;
        }
        let (grid, k, pose) = if self.next_is_insert() {
            (&self.grid, self.next, self.pose)
        } else {
            let (k, pose) = self.last?;
            (self.grid_before_insert.as_ref()?, k, pose)
        };
        Some(grid.explain_beam(&pose, &self.input.scans[k].scan, beam, &self.insert))
    }

    /// A problem the run met (an update rule it could not use).
    pub fn note(&self) -> Option<&str> {
        self.note.as_deref()
    }

    /// The phases one scan takes with this source.
    fn has_match_phase(&self) -> bool {
        matches!(
            self.source,
            PoseSource::Icp | PoseSource::Plicp | PoseSource::ScanToMap
        )
    }

    /// The odometry prediction of scan `k`: the last pose moved by the
    /// odometry increment between the two scans.
    fn predict(&self, k: usize) -> Pose2 {
        let scans = &self.input.scans;
        match self.last {
            None => scans[k].odometry,
            Some((j, pose)) => {
                let increment = scans[j].odometry.between(&scans[k].odometry);
                let p = pose.compose(&increment);
                Pose2::new(p.x, p.y, wrap_angle(p.theta))
            }
        }
    }

    /// The matcher's correction of scan `k` from `predicted`; `None` when
    /// there is nothing to match against (the first scan) or nothing to match.
    fn correct(&mut self, k: usize, predicted: Pose2) -> Option<(Pose2, f64, usize)> {
        let scan = &self.input.scans[k].scan;
        let points = scan.points();
        match self.source {
            PoseSource::ScanToMap => {
                // (known_cells reads every cell: only before the first scan.)
                if self.last.is_none() && self.grid.known_cells() == 0 {
                    return None;
                }
                let (m, record) = match_scan_to_map(
                    &self.grid,
                    &self.lookup,
                    &points,
                    predicted,
                    &self.matchers.scan_to_map,
                )?;
                self.last_record = Some(Arc::new(record));
                Some((m.pose, m.cost, m.iterations))
            }
            PoseSource::Icp | PoseSource::Plicp => {
                let (j, last_pose) = self.last?;
                let reference: Vec<Point2> = self.input.scans[j].scan.points();
                // The scan's pose in the previous scan's frame, from odometry.
                let initial = last_pose.between(&predicted);
                let params = IcpConfig {
                    variant: if self.source == PoseSource::Icp {
                        IcpVariant::PointToPoint
                    } else {
                        IcpVariant::PointToLine
                    },
                    ..self.matchers.icp
                };
                let (m, iterations) = align(&reference, &points, initial, &params).ok()?;
                self.icp_record = Some(Arc::new(IcpScanRecord {
                    scan: k,
                    reference_scan: j,
                    reference_pose: last_pose,
                    iterations,
                }));
                let p = last_pose.compose(&m.pose);
                Some((
                    Pose2::new(p.x, p.y, wrap_angle(p.theta)),
                    m.cost,
                    m.iterations,
                ))
            }
            PoseSource::Truth | PoseSource::Odometry | PoseSource::GridFastSlam => None,
        }
    }

    /// The estimate at scan `k` between grid FastSLAM's updates: the
    /// heaviest particle's pose moved by the odometry since the last update.
    fn grid_estimate(filter: &GridFastSlam, odometry: Pose2) -> Pose2 {
        let Some(best) = filter.best() else {
            return odometry;
        };
        let Some(last) = filter.last_odometry() else {
            return best.pose;
        };
        let p = best.pose.compose(&last.between(&odometry));
        Pose2::new(p.x, p.y, wrap_angle(p.theta))
    }

    /// One grid FastSLAM phase of scan `k`.
    fn step_grid(&mut self, k: usize, records: &mut MappingRecords) -> MappingPhase {
        let Some(filter) = self.fastslam.as_deref_mut() else {
            return MappingPhase::Done;
        };
        let input = &self.input.scans[k];
        let odometry = input.odometry;
        let scan = &input.scan;
        let finish = |sim: &mut Self, records: &mut MappingRecords, pose: Pose2| {
            records.poses.push(pose);
            sim.pose = pose;
            sim.last = Some((k, pose));
            sim.next += 1;
            sim.stage = Stage::Predict;
        };
        match self.stage {
            Stage::Predict => {
                records.costs.push(f64::NAN);
                records.iterations.push(0);
                records.neff.push(f64::NAN);
                records.resampled.push(false);
                if filter.particles().is_empty() || !odometry.is_finite() {
                    if !odometry.is_finite() {
                        // A scan without odometry is skipped.
                        let pose = self.pose;
                        finish(self, records, pose);
                        return MappingPhase::GridSkip {
                            scan: k,
                            moved: f64::NAN,
                            turned: f64::NAN,
                        };
                    }
                    let particles = filter.config().particles;
                    filter.initialize(k, odometry, scan);
                    finish(self, records, odometry);
                    return MappingPhase::GridStart { scan: k, particles };
                }
                if !filter.update_due(&odometry) {
                    let d = filter
                        .last_odometry()
                        .map_or(Pose2::IDENTITY, |last| last.between(&odometry));
                    let pose = Self::grid_estimate(filter, odometry);
                    finish(self, records, pose);
                    return MappingPhase::GridSkip {
                        scan: k,
                        moved: slamlab_core::math::hypot(d.x, d.y),
                        turned: wrap_angle(d.theta).abs(),
                    };
                }
                if filter.config().proposal == Proposal::ScanMatch {
                    // One particle per phase: each scan match can be seen.
                    filter.begin_proposals(odometry);
                    self.stage = Stage::Proposing;
                    return self.step_grid(k, records);
                }
                let fallbacks = filter.propose(odometry, scan);
                self.pose = filter.best().map_or(odometry, |p| p.pose);
                self.stage = Stage::Weight;
                MappingPhase::GridPropose {
                    scan: k,
                    proposal: filter.config().proposal.name(),
                    fallbacks,
                }
            }
            Stage::Proposing => {
                let of = filter.particles().len();
                let points = LikelihoodPoints::new(scan);
                let Some(p) = filter.propose_next(&points) else {
                    self.stage = Stage::Weight;
                    return self.step_grid(k, records);
                };
                let (pose, fell_back) = (p.pose, p.fell_back);
                let particle = filter.proposals().len() - 1;
                if !filter.proposing() {
                    self.stage = Stage::Weight;
                }
                self.pose = pose;
                MappingPhase::GridParticle {
                    scan: k,
                    particle,
                    of,
                    fell_back,
                }
            }
            Stage::Weight => {
                let neff = filter.normalize();
                if let Some(n) = records.neff.last_mut() {
                    *n = neff;
                }
                self.pose = filter.best().map_or(odometry, |p| p.pose);
                self.stage = if filter.resample_due() {
                    Stage::Resample
                } else {
                    Stage::Insert
                };
                MappingPhase::GridWeight {
                    scan: k,
                    neff,
                    threshold: filter.config().resample_threshold * filter.particles().len() as f64,
                }
            }
            Stage::Resample => {
                let (resampled, survivors) = filter.resample_if_needed();
                if let Some(r) = records.resampled.last_mut() {
                    *r = resampled;
                }
                self.pose = filter.best().map_or(odometry, |p| p.pose);
                self.stage = Stage::Insert;
                MappingPhase::GridResample {
                    scan: k,
                    survivors,
                    of: filter.particles().len(),
                }
            }
            Stage::Match | Stage::Iteration(_) | Stage::Insert => {
                let cells = filter.update_maps(k, scan);
                let memory_bytes = filter.memory_bytes();
                let pose = filter.best().map_or(odometry, |p| p.pose);
                finish(self, records, pose);
                MappingPhase::GridUpdate {
                    scan: k,
                    cells,
                    memory_bytes,
                }
            }
        }
    }
}

impl MappingSim {
    /// Shows ICP iteration `i` of scan `k`'s match: the pose moves to where
    /// that iteration left it; after the last one, to the match.
    fn show_iteration(&mut self, k: usize, i: usize) -> MappingPhase {
        let Some(record) = self.icp_record.clone() else {
            self.stage = Stage::Insert;
            self.pose = self.matched;
            return MappingPhase::Match {
                scan: k,
                pose: self.pose,
                cost: f64::NAN,
                iterations: 0,
            };
        };
        let of = record.iterations.len();
        let Some(step) = record.iterations.get(i) else {
            self.stage = Stage::Insert;
            self.shown_iteration = None;
            self.pose = self.matched;
            return MappingPhase::Match {
                scan: k,
                pose: self.pose,
                cost: f64::NAN,
                iterations: of,
            };
        };
        let last = i + 1 >= of;
        let p = record.reference_pose.compose(&step.pose);
        self.pose = if last {
            self.matched
        } else {
            Pose2::new(p.x, p.y, wrap_angle(p.theta))
        };
        self.shown_iteration = Some(i);
        self.stage = if last {
            Stage::Insert
        } else {
            Stage::Iteration(i + 1)
        };
        MappingPhase::Iteration {
            scan: k,
            iteration: step.iteration,
            of,
            pose: self.pose,
            mean_squared_error: step.mean_squared_error,
            kept: step.kept,
        }
    }
}

impl Simulation for MappingSim {
    type Phase = MappingPhase;
    type Event = MappingEvent;
    type Records = MappingRecords;

    fn step_phase(&mut self, records: &mut MappingRecords) -> MappingPhase {
        let k = self.next;
        if k >= self.input.scans.len() {
            return MappingPhase::Done;
        }
        if self.fastslam.is_some() {
            return self.step_grid(k, records);
        }
        match self.stage {
            Stage::Predict => {
                self.pose = match (&self.input.truth, self.source) {
                    (Some(truth), PoseSource::Truth) if k < truth.len() => truth[k],
                    _ => self.predict(k),
                };
                self.stage = if self.has_match_phase() {
                    Stage::Match
                } else {
                    Stage::Insert
                };
                records.costs.push(f64::NAN);
                records.iterations.push(0);
                records.neff.push(f64::NAN);
                records.resampled.push(false);
                MappingPhase::Predict {
                    scan: k,
                    pose: self.pose,
                }
            }
            Stage::Match => {
                self.stage = Stage::Insert;
                let predicted = self.pose;
                self.icp_record = None;
                self.shown_iteration = None;
                match self.correct(k, predicted) {
                    Some((pose, cost, iterations)) if pose.is_finite() => {
                        if let Some(c) = records.costs.last_mut() {
                            *c = cost;
                        }
                        if let Some(n) = records.iterations.last_mut() {
                            *n = iterations;
                        }
                        if self.step_iterations && self.icp_record.is_some() {
                            // The match is known; reveal it one iteration per phase.
                            self.matched = pose;
                            return self.show_iteration(k, 0);
                        }
                        self.pose = pose;
                        MappingPhase::Match {
                            scan: k,
                            pose,
                            cost,
                            iterations,
                        }
                    }
                    _ => MappingPhase::Match {
                        scan: k,
                        pose: predicted,
                        cost: f64::NAN,
                        iterations: 0,
                    },
                }
            }
            Stage::Iteration(i) => self.show_iteration(k, i),
            Stage::Insert | Stage::Proposing | Stage::Weight | Stage::Resample => {
                self.shown_iteration = None;
                self.grid_before_insert = self.keep_before.then(|| self.grid.clone());
                let scan = &self.input.scans[k].scan;
                let report = match self.grid.insert_scan(&self.pose, scan, &self.insert) {
                    Ok(report) => report,
                    Err(message) => {
                        self.note = Some(message);
                        InsertReport::default()
                    }
                };
                records.poses.push(self.pose);
                self.last = Some((k, self.pose));
                self.next += 1;
                self.stage = Stage::Predict;
                MappingPhase::Insert { scan: k, report }
            }
        }
    }

    fn is_mid_tick(&self) -> bool {
        self.stage != Stage::Predict
    }

    fn tick(&self) -> u64 {
        self.next as u64 + u64::from(self.is_mid_tick())
    }

    fn apply_event(&mut self, event: &MappingEvent) {
        match *event {
            MappingEvent::StepIterations(on) => self.step_iterations = on,
        }
    }

    fn checkpoint_bytes(&self) -> usize {
        // Tiles are shared with the live run until it writes them; count the
        // tile table and a share of the tiles.
        let particles = self
            .fastslam
            .as_ref()
            .map_or(0, |f| f.memory_bytes() / 8 + f.particles().len() * 256);
        self.grid.memory_bytes() / 8 + particles + 1024
    }
}
