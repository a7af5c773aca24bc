//! Submaps, branch-and-bound loop closure and the kidnapped robot during
//! mapping (thesis `000` Sec. 5.2, Cartographer's 2-D SLAM; `slamlab run
//! cartographer`).
//!
//! - **Local SLAM** ([`CartographerSim::step`]): each scan's pose in its
//!   trajectory's local frame from the odometry prediction and scan-to-submap
//!   matching against the older of the two active submaps (correlative
//!   search, then thesis Eq. 5.5); every scan's matching cost is kept. A
//!   motion filter skips scans that barely moved; the others become nodes and
//!   go into both active submaps (Eq. 5.3-5.4). A submap is finished after
//!   `2 · num_range_data` scans, a new one started every `num_range_data`, as
//!   Cartographer's `ActiveSubmaps2D` does.
//! - **Global SLAM**: a pose graph of submap and node poses; an
//!   intra-submap constraint for every node and submap it went into, and loop
//!   closures from branch-and-bound against finished submaps (Algorithm 12)
//!   in a window around the current estimate (Eq. 5.6-5.7: the constraint is
//!   the node's pose in the submap's frame, `ξ_ij = ξ_mᵢ⁻¹ ξ_sⱼ`, whose
//!   translation is `R_mᵀ (t_s − t_m)`), solved with the Huber kernel
//!   (Eq. 5.8-5.9) every `optimize_every_n_nodes` nodes by the project's
//!   sparse Levenberg-Marquardt solver.
//! - **The kidnapped robot** (Algorithm 13, Figs. 5.8-5.12): the average
//!   filter over the local matching cost declares a kidnap; the trajectory
//!   ends and a new one starts at the origin with its own submaps and its own
//!   unanchored graph; branch and bound searches the new trajectory's nodes
//!   against the old trajectory's finished submaps, each submap whole and at
//!   every heading; the first match above `global_min_score` adds the
//!   inter-trajectory constraint, the new trajectory is moved onto the first
//!   and the optimization merges the maps. With detection off the run maps on
//!   in one corrupted map (Fig. 5.10).
//!
//! The input is [`MappingInput`] (a simulated log from [`input::kidnap_input`]
//! or a CARMEN log); the truth reaches only [`CartographerSim::summary`].

pub mod export;
pub mod input;
pub mod session;
#[cfg(test)]
mod tests;
mod view;

use crate::grid::{MappingInput, map_agreement};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use slamlab_core::Pose2;
use slamlab_core::graph::{
    EdgeKind, Optimizer, OptimizerSettings, PoseGraph, RobustKernel, SolverKind,
};
use slamlab_core::grid::{InsertParams, ProbabilityGrid, UpdateRule};
use slamlab_core::scan::branch_and_bound::{
    BranchAndBoundParams, NoMatch, PrecomputedGrids, SearchRecord, SearchWindow, branch_and_bound,
};
use slamlab_core::scan::kidnap_detector::{KidnapDetector, KidnapDetectorParams};
use slamlab_core::scan::scan_to_map::{
    ProbabilityLookup, ScanToMapParams, match_scan_to_map, spread_points,
};
use slamlab_core::scan::{Point2, Scan};
use slamlab_core::wrap_angle;
use std::collections::{HashMap, HashSet, VecDeque};
use std::sync::Arc;

/// The parameters, with Cartographer's names where it has them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CartographerParams {
    /// Metres per submap cell (`resolution`).
    pub resolution: f64,
    /// Scans per submap before the next one starts (`num_range_data`); each
    /// submap takes twice as many before it is finished.
    pub num_range_data: usize,
    /// Probability of a hit cell (`hit_probability`).
    pub hit_probability: f64,
    /// Probability of a missed cell (`miss_probability`).
    pub miss_probability: f64,
    /// Free space marked along a beam that returned nothing, metres
    /// (`missing_data_ray_length`).
    pub missing_data_ray_length: f64,
    /// The motion filter: a scan becomes a node when the robot moved this far
    /// since the last node (`max_distance_meters`)...
    pub motion_filter_distance: f64,
    /// ... or turned this far, radians (`max_angle_radians`) ...
    pub motion_filter_angle: f64,
    /// ... or this much time passed, seconds (`max_time_seconds`).
    pub motion_filter_time: f64,
    /// Local scan matching (correlative search and Eq. 5.5).
    pub local: ScanToMapParams,
    /// Half-width of the loop-closure search in x and y, metres
    /// (`linear_search_window`; Cartographer's 7 m finds matches well away
    /// from the estimate that `loop_closure_gate` then refuses, so the
    /// default is the gate and a cell: 0.6 m).
    pub linear_search_window: f64,
    /// Half-width of the loop-closure search in heading, radians
    /// (`angular_search_window`; Cartographer 30°, here 5°: of the 2,826 loop
    /// closures a 10° window found on the Intel log, 99 % turned their node
    /// by less than 3°, one by more than 5°).
    pub angular_search_window: f64,
    /// A node is searched only against submaps whose origin lies within this
    /// distance of it in the same map, metres (`max_constraint_distance`).
    pub max_constraint_distance: f64,
    /// A loop closure must score above this (`min_score`).
    pub min_score: f64,
    /// A global match between trajectories must score above this
    /// (`global_localization_min_score`).
    pub global_min_score: f64,
    /// A loop closure within one map is kept only if it moves the node at
    /// most this far from its current estimate, metres (a gate SLAM Lab adds:
    /// in the maze's repeating corridors a 7 m window finds matches one
    /// corridor over that score above `min_score`; 0 or less: no gate).
    pub loop_closure_gate: f64,
    /// A merge of two maps is taken only when the new map's scans, moved by
    /// the proposed correction, put at least this share of their points
    /// that land on cells the old map knows on cells it holds occupied (a
    /// check SLAM Lab adds: a single scan's match over a whole submap at
    /// every heading is often one corridor or one room over).
    pub merge_min_occupied_share: f64,
    /// ... and at least this many of their points land on cells the old map
    /// knows.
    pub merge_min_known_points: usize,
    /// Refine each branch-and-bound match with Eq. 5.5 (Cartographer's Ceres
    /// refinement after the fast correlative search).
    pub refine_matches: bool,
    /// Height of the tallest precomputed grid (`branch_and_bound_depth − 1`).
    pub max_height: u32,
    /// The share of node-submap pairs within a map (and within
    /// `max_constraint_distance`) searched for a loop closure, sampled per
    /// submap as Cartographer's `sampling_ratio` samples them
    /// ([`FixedRatioSampler`]); 0: no loop closures within a map.
    /// Cartographer's 0.3 goes with its 90 nodes per submap; with this
    /// lesson's 30 a node has three times as many submaps in reach, and 0.1
    /// searches as many pairs per node.
    pub sampling_ratio: f64,
    /// A node-submap pair is not searched once this many loop closures tie
    /// the submap to the submap the node was matched against (its map's
    /// oldest active submap, to which every one of its nodes is tied): the
    /// pair is constrained already, through its own submap. 0: no limit.
    pub max_closures_per_submap_pair: usize,
    /// The nodes of a map not yet joined to another are searched against
    /// the other map's finished submaps (whole, at every heading) every
    /// n-th node (Cartographer samples these global searches with
    /// `global_sampling_ratio`).
    pub global_search_every_n_nodes: usize,
    /// At most this many scan points go into a branch-and-bound search.
    pub bbs_max_points: usize,
    /// Optimize the pose graph every n nodes (`optimize_every_n_nodes`).
    pub optimize_every_n_nodes: usize,
    /// Huber scale on the constraints' weighted error (`huber_scale`).
    pub huber_scale: f64,
    /// Weight of an intra-submap constraint's translation
    /// (`matcher_translation_weight`): information `w²`.
    pub matcher_translation_weight: f64,
    /// ... and rotation (`matcher_rotation_weight`).
    pub matcher_rotation_weight: f64,
    /// Weight of a loop closure's translation
    /// (`loop_closure_translation_weight`).
    pub loop_closure_translation_weight: f64,
    /// ... and rotation (`loop_closure_rotation_weight`).
    pub loop_closure_rotation_weight: f64,
    /// Kidnap detection (Algorithm 13) on or off.
    pub detection: bool,
    /// The thesis's `T` and `f_size`.
    pub kidnap: KidnapDetectorParams,
}

impl Default for CartographerParams {
    fn default() -> Self {
        Self {
            resolution: 0.05,
            num_range_data: 30,
            hit_probability: 0.55,
            miss_probability: 0.49,
            missing_data_ray_length: 5.0,
            motion_filter_distance: 0.2,
            motion_filter_angle: 1f64.to_radians(),
            motion_filter_time: 5.0,
            // Cartographer pulls the position towards the odometry
            // prediction (see `scan_to_map`: without it, corridors swallow
            // the motion).
            local: ScanToMapParams {
                pull_to_prediction: true,
                ..ScanToMapParams::default()
            },
            linear_search_window: 0.6,
            angular_search_window: 5f64.to_radians(),
            max_constraint_distance: 15.0,
            min_score: 0.55,
            global_min_score: 0.6,
            loop_closure_gate: 0.5,
            merge_min_occupied_share: 0.945,
            merge_min_known_points: 450,
            refine_matches: true,
            max_height: 6,
            sampling_ratio: 0.1,
            max_closures_per_submap_pair: 0,
            global_search_every_n_nodes: 3,
            bbs_max_points: 150,
            optimize_every_n_nodes: 30,
            huber_scale: 10.0,
            matcher_translation_weight: 500.0,
            matcher_rotation_weight: 1600.0,
            loop_closure_translation_weight: 1.1e4,
            loop_closure_rotation_weight: 1e5,
            detection: true,
            kidnap: KidnapDetectorParams::default(),
        }
    }
}

impl CartographerParams {
    /// The same parameters with loop closures off: no node-submap pair is
    /// sampled for a search (`sampling_ratio` 0) and no global search runs
    /// after a kidnap detection, so no branch and bound at all; local SLAM
    /// alone (the lesson's switch, `--loop-closures off`).
    #[must_use]
    pub fn without_loop_closures(self) -> Self {
        Self {
            sampling_ratio: 0.0,
            global_search_every_n_nodes: usize::MAX,
            ..self
        }
    }

    /// The parameters made usable (a clamp or a default for each bad value),
    /// with a note for each change.
    pub fn sanitized(mut self) -> (Self, Vec<String>) {
        let d = Self::default();
        let mut notes = Vec::new();
        let fix = |ok: bool, name: &str, shown: String, notes: &mut Vec<String>| {
            if !ok {
                notes.push(format!(
                    "{name} = {shown} cannot be used; the default applies"
                ));
            }
            ok
        };
        if !fix(
            self.resolution.is_finite() && (0.01..=1.0).contains(&self.resolution),
            "resolution",
            self.resolution.to_string(),
            &mut notes,
        ) {
            self.resolution = d.resolution;
        }
        if self.num_range_data == 0 || self.num_range_data > 10_000 {
            notes.push(format!(
                "num_range_data = {} must be 1 to 10000; {} is used",
                self.num_range_data,
                self.num_range_data.clamp(1, 10_000)
            ));
            self.num_range_data = self.num_range_data.clamp(1, 10_000);
        }
        let rule = UpdateRule::Odds {
            p_hit: self.hit_probability,
            p_miss: self.miss_probability,
            p_min: 0.1,
            p_max: 0.9,
        };
        if let Err(why) = rule.log_odds_steps() {
            notes.push(format!(
                "the hit and miss probabilities cannot be used ({why}); the defaults apply"
            ));
            self.hit_probability = d.hit_probability;
            self.miss_probability = d.miss_probability;
        }
        for (value, default, name, max) in [
            (
                &mut self.linear_search_window,
                d.linear_search_window,
                "linear_search_window",
                1e4,
            ),
            (
                &mut self.angular_search_window,
                d.angular_search_window,
                "angular_search_window",
                std::f64::consts::PI,
            ),
            (
                &mut self.max_constraint_distance,
                d.max_constraint_distance,
                "max_constraint_distance",
                1e4,
            ),
            (&mut self.min_score, d.min_score, "min_score", 1.0),
            (
                &mut self.global_min_score,
                d.global_min_score,
                "global_min_score",
                1.0,
            ),
            (&mut self.huber_scale, d.huber_scale, "huber_scale", 1e9),
            (
                &mut self.motion_filter_distance,
                d.motion_filter_distance,
                "max_distance_meters",
                1e3,
            ),
            (
                &mut self.motion_filter_angle,
                d.motion_filter_angle,
                "max_angle_radians",
                10.0,
            ),
            (
                &mut self.motion_filter_time,
                d.motion_filter_time,
                "max_time_seconds",
                1e6,
            ),
            (
                &mut self.missing_data_ray_length,
                d.missing_data_ray_length,
                "missing_data_ray_length",
                1e3,
            ),
        ] {
            if !(value.is_finite() && *value >= 0.0 && *value <= max) {
                notes.push(format!(
                    "{name} = {value} must be 0 to {max}; {default} is used"
                ));
                *value = default;
            }
        }
        if !(self.huber_scale > 0.0) {
            self.huber_scale = d.huber_scale;
        }
        for (value, default, name) in [
            (
                &mut self.matcher_translation_weight,
                d.matcher_translation_weight,
                "matcher_translation_weight",
            ),
            (
                &mut self.matcher_rotation_weight,
                d.matcher_rotation_weight,
                "matcher_rotation_weight",
            ),
            (
                &mut self.loop_closure_translation_weight,
                d.loop_closure_translation_weight,
                "loop_closure_translation_weight",
            ),
            (
                &mut self.loop_closure_rotation_weight,
                d.loop_closure_rotation_weight,
                "loop_closure_rotation_weight",
            ),
        ] {
            if !(value.is_finite() && *value > 0.0 && *value < 1e7) {
                notes.push(format!(
                    "{name} = {value} must be a positive number below 1e7; {default} is used"
                ));
                *value = default;
            }
        }
        if !(self.merge_min_occupied_share.is_finite()
            && (0.0..=1.0).contains(&self.merge_min_occupied_share))
        {
            notes.push(format!(
                "merge_min_occupied_share = {} must be 0 to 1; {} is used",
                self.merge_min_occupied_share, d.merge_min_occupied_share
            ));
            self.merge_min_occupied_share = d.merge_min_occupied_share;
        }
        self.max_height = self.max_height.min(10);
        if !(self.sampling_ratio.is_finite() && (0.0..=1.0).contains(&self.sampling_ratio)) {
            notes.push(format!(
                "sampling_ratio = {} must be 0 to 1; {} is used",
                self.sampling_ratio, d.sampling_ratio
            ));
            self.sampling_ratio = d.sampling_ratio;
        }
        self.global_search_every_n_nodes = self.global_search_every_n_nodes.max(1);
        self.optimize_every_n_nodes = self.optimize_every_n_nodes.max(1);
        self.bbs_max_points = self.bbs_max_points.max(1);
        let (kidnap, kidnap_notes) = self.kidnap.sanitized();
        self.kidnap = kidnap;
        notes.extend(kidnap_notes);
        (self, notes)
    }

    fn insert_params(&self) -> InsertParams {
        InsertParams {
            rule: UpdateRule::Odds {
                p_hit: self.hit_probability,
                p_miss: self.miss_probability,
                p_min: 0.1,
                p_max: 0.9,
            },
            max_range_free: self.missing_data_ray_length,
        }
    }
}

/// A submap: a probability grid in its trajectory's local frame.
#[derive(Clone, Debug)]
pub struct Submap {
    /// The trajectory it belongs to.
    pub trajectory: usize,
    /// Its origin in the trajectory's local frame (the position of its first
    /// scan, heading 0, as Cartographer places it).
    pub local_pose: Pose2,
    /// Its origin in the global frame (the pose graph's estimate).
    pub global_pose: Pose2,
    /// The grid, cells in the local frame.
    pub grid: ProbabilityGrid,
    /// Scans inserted.
    pub num_range_data: usize,
    /// Whether it takes no more scans.
    pub finished: bool,
    /// Its precomputed grids, once finished.
    pub precomputed: Option<Arc<PrecomputedGrids>>,
    /// Which node-submap pairs with it are searched (`sampling_ratio`).
    pub sampler: FixedRatioSampler,
}

/// Cartographer's `FixedRatioSampler`: of the pulses so far, a pulse is
/// sampled when the share sampled is below `ratio`, so that exactly
/// `⌈ratio · n⌉` of the first `n` pulses are (the first always is, for a
/// positive ratio). Deterministic: the same pulses give the same samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FixedRatioSampler {
    /// Pulses so far.
    pub pulses: u64,
    /// Pulses sampled.
    pub samples: u64,
}

impl FixedRatioSampler {
    /// One pulse: whether it is sampled.
    pub fn pulse(&mut self, ratio: f64) -> bool {
        self.pulses += 1;
        if (self.samples as f64) / (self.pulses as f64) < ratio {
            self.samples += 1;
            true
        } else {
            false
        }
    }
}

/// A node: a scan that went into the submaps.
#[derive(Clone, Debug)]
pub struct Node {
    /// The trajectory it belongs to.
    pub trajectory: usize,
    /// The scan's index in the input.
    pub scan: usize,
    /// Its pose in the trajectory's local frame (local SLAM).
    pub local_pose: Pose2,
    /// Its pose in the global frame (the pose graph's estimate).
    pub global_pose: Pose2,
    /// The points branch and bound matches (sensor frame, at most
    /// `bbs_max_points`).
    pub points: Arc<Vec<Point2>>,
    /// The submaps it went into, the one it was matched against first (its
    /// trajectory's oldest active submap).
    pub submaps: Vec<usize>,
}

/// What a constraint is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ConstraintKind {
    /// The node went into the submap (local SLAM).
    IntraSubmap,
    /// Branch and bound matched the node in a finished submap of its own
    /// trajectory, or of one already joined to it.
    LoopClosure,
    /// Branch and bound matched a node of a trajectory not yet joined to the
    /// submap's: the match that merges the maps.
    InterTrajectory,
}

/// A constraint: node `node` seen from submap `submap`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Constraint {
    /// Submap index.
    pub submap: usize,
    /// Node index.
    pub node: usize,
    /// `submap_from_node` (Eq. 5.7's `ξ_ij`).
    pub relative: Pose2,
    /// What made it.
    pub kind: ConstraintKind,
    /// Branch and bound's score (1 for an intra-submap constraint).
    pub score: f64,
}

/// A trajectory: one continuous stretch of local SLAM.
#[derive(Clone, Debug)]
pub struct Trajectory {
    /// The first scan.
    pub first_scan: usize,
    /// The kidnap detection that started it (`None` for the first).
    pub started_by_detection: bool,
    /// The trajectory whose frame it has been joined to (itself until a
    /// match joins it; the first trajectory's frame is the global frame).
    pub joined_to: usize,
    /// `global_from_local`: where its local frame sits in the global frame.
    pub global_from_local: Pose2,
    /// Its active submaps (indices), oldest first.
    active: Vec<usize>,
    /// The last scan matched: `(scan, local pose)`.
    last_scan: Option<(usize, Pose2)>,
    /// The last node: `(local pose, time)`.
    last_node: Option<(Pose2, f64)>,
    /// Nodes made.
    nodes: usize,
}

/// What happened to one scan.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScanRecord {
    /// The scan's index in the input.
    pub scan: usize,
    /// The trajectory it belongs to.
    pub trajectory: usize,
    /// The local matching cost (Eq. 5.5 with the pulls; NaN where nothing
    /// was matched: a trajectory's first scan).
    pub cost: f64,
    /// The average filter's value `y_t` (NaN until `f_size` costs are in).
    pub filtered: f64,
    /// The level it had to exceed, `T · y_{t−1}` (NaN without one).
    pub trigger_level: f64,
    /// Whether the detector declared a kidnap here.
    pub detected: bool,
    /// Whether the scan became a node.
    pub node: bool,
    /// Its pose in the global frame (the estimate when it was taken).
    pub global_pose: Pose2,
    /// Its pose in its trajectory's local frame (local SLAM).
    pub local_pose: Pose2,
}

/// One branch-and-bound search and what came of it.
#[derive(Clone, Debug, PartialEq)]
pub struct SearchEvent {
    /// Scan of the node searched.
    pub scan: usize,
    /// Node index.
    pub node: usize,
    /// Submap index.
    pub submap: usize,
    /// Whether it searched the whole submap at every heading.
    pub global: bool,
    /// The score found (None: below the minimum).
    pub score: Option<f64>,
    /// The minimum a match had to score (`min_score`, or
    /// `global_min_score` for a search between maps).
    pub min_score: f64,
    /// With no match: the highest bound at the top of the tree (Eq. 5.14),
    /// which no candidate in the window can score above.
    pub best_bound: Option<f64>,
    /// What the search did.
    pub record: SearchRecord,
}

/// What one optimization of the pose graph did (Eq. 5.8 with the Huber
/// kernel, Eq. 5.9).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OptimizationReport {
    /// The scan after which it ran.
    pub scan: usize,
    /// Levenberg-Marquardt iterations.
    pub iterations: usize,
    /// The cost `Σ ρ(eᵀΩe)` before the first iteration (NaN: none ran).
    pub cost_before: f64,
    /// ... and after the last.
    pub cost_after: f64,
    /// How far it moved the nodes on average, metres.
    pub mean_node_move: f64,
    /// ... and the node it moved farthest.
    pub max_node_move: f64,
}

/// Totals of the branch-and-bound searches.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BbsTotals {
    /// Searches run.
    pub searches: usize,
    /// Candidates scored at every height.
    pub nodes_evaluated: usize,
    /// Candidates an exhaustive search would have scored.
    pub exhaustive_candidates: usize,
}

/// The check of one proposed merge of two maps: the new map's scans moved
/// by the correction a global match proposes, looked up in the old map.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MergeCheck {
    /// Scan of the node whose global match proposed it.
    pub scan: usize,
    /// The old map's submap it matched.
    pub submap: usize,
    /// Branch and bound's score of the match.
    pub score: f64,
    /// The node's pose in the old map's frame the match implies.
    pub node_pose: Pose2,
    /// Nodes of the new map checked.
    pub nodes: usize,
    /// Their points that land on cells the old map knows.
    pub known_points: usize,
    /// The share of those on cells the old map holds occupied (1 when none
    /// land on known cells).
    pub occupied_share: f64,
    /// Whether the maps were merged on it.
    pub accepted: bool,
}

/// One run of Cartographer-style SLAM over an input.
#[derive(Clone, Debug)]
pub struct CartographerSim {
    input: Arc<MappingInput>,
    params: CartographerParams,
    insert: InsertParams,
    lookup: Arc<ProbabilityLookup>,
    /// Every submap of every trajectory.
    pub submaps: Vec<Submap>,
    /// Every node.
    pub nodes: Vec<Node>,
    /// Every constraint.
    pub constraints: Vec<Constraint>,
    /// Every trajectory.
    pub trajectories: Vec<Trajectory>,
    /// One record per scan processed.
    pub records: Vec<ScanRecord>,
    /// Scans where the detector declared a kidnap.
    pub detections: Vec<usize>,
    /// Scans whose node's match merged a trajectory into the first.
    pub merges: Vec<usize>,
    /// The last branch-and-bound search (for drawing).
    pub last_search: Option<Arc<SearchEvent>>,
    /// The totals of every search.
    pub bbs: BbsTotals,
    /// The last optimization: its cost before and after, how far it moved
    /// the nodes.
    pub last_optimization: Option<OptimizationReport>,
    /// Optimizations run.
    pub optimizations: usize,
    /// Loop closures found but refused by the gate.
    pub rejected_closures: usize,
    /// Notes for the user (an optimization that failed, ...).
    pub notes: Vec<String>,
    /// Every proposed merge of two maps and its check.
    pub merge_checks: Vec<MergeCheck>,
    detector: KidnapDetector,
    /// `(submap, node)` pairs with a constraint.
    constrained: HashSet<(usize, usize)>,
    /// Loop closures per `(node's matching submap, submap)` pair.
    pair_closures: HashMap<(usize, usize), usize>,
    nodes_since_optimization: usize,
    next: usize,
    /// The scan part way through its phases.
    pending: Option<PendingScan>,
}

/// What one [`CartographerSim::step_phase`] ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CartographerPhase {
    /// Local SLAM of scan `scan`: matched into its submap, the kidnap
    /// detector fed and, past the motion filter, inserted as a node.
    LocalSlam {
        /// The scan.
        scan: usize,
    },
    /// One branch-and-bound search of scan `scan`'s node against `submap`.
    Search {
        /// The scan whose node was searched.
        scan: usize,
        /// The submap searched.
        submap: usize,
        /// Whole submap at every heading (against another map), not a
        /// window around the estimate.
        global: bool,
    },
    /// One optimization of the pose graph, after scan `scan`.
    Optimization {
        /// The scan it followed.
        scan: usize,
    },
    /// Scan `scan` had nothing left to run.
    Settled {
        /// The scan.
        scan: usize,
    },
    /// Every scan is in.
    Done,
}

/// What [`CartographerSim::step_phase`] runs next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NextPhase {
    /// Local SLAM of the next scan.
    LocalSlam,
    /// A branch-and-bound search of the current scan's node.
    Search,
    /// An optimization of the pose graph.
    Optimization,
    /// Nothing: every scan is in.
    Done,
}

/// Where the current scan stands among its phases.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PhaseOutlook {
    /// The current scan (part way through), or the next one.
    pub scan: usize,
    /// What runs next.
    pub next: NextPhase,
    /// Searches of the current scan still to run.
    pub searches_pending: usize,
    /// Searches planned for it when its node was made (a merge drops the
    /// rest).
    pub searches_planned: usize,
    /// Whether an optimization is due after its searches.
    pub optimization_pending: bool,
}

/// Where a scan is among its phases.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// Its node's branch-and-bound searches.
    Searches,
    /// The optimization after a merge of two maps.
    MergeOptimization,
    /// The node to count towards `optimize_every_n_nodes` (no phase).
    CountNode,
    /// The optimization every `optimize_every_n_nodes` nodes.
    DueOptimization,
    /// Nothing left.
    Finished,
}

/// A scan part way through its phases.
#[derive(Clone, Debug)]
struct PendingScan {
    scan: usize,
    /// Its node, if it became one.
    node: Option<usize>,
    /// The root trajectory of the node's map when its searches were planned.
    root: usize,
    /// Searches still to run, in order: the submap, and whether the search
    /// is global (the whole submap of a map not joined to the node's).
    planned: VecDeque<(usize, bool)>,
    searches_planned: usize,
    /// A search merged the node's map into another.
    merged: bool,
    stage: Stage,
}

impl CartographerSim {
    /// A run of `input` with `params` (sanitized; the notes say what changed).
    pub fn new(input: Arc<MappingInput>, params: CartographerParams) -> (Self, Vec<String>) {
        let (params, notes) = params.sanitized();
        let sim = Self {
            input,
            insert: params.insert_params(),
            lookup: Arc::new(ProbabilityLookup::default()),
            submaps: Vec::new(),
            nodes: Vec::new(),
            constraints: Vec::new(),
            trajectories: Vec::new(),
            records: Vec::new(),
            detections: Vec::new(),
            merges: Vec::new(),
            last_search: None,
            bbs: BbsTotals::default(),
            last_optimization: None,
            optimizations: 0,
            rejected_closures: 0,
            notes: Vec::new(),
            merge_checks: Vec::new(),
            detector: KidnapDetector::new(params.kidnap),
            constrained: HashSet::new(),
            pair_closures: HashMap::new(),
            nodes_since_optimization: 0,
            next: 0,
            pending: None,
            params,
        };
        (sim, notes)
    }

    /// The parameters in use.
    pub fn params(&self) -> &CartographerParams {
        &self.params
    }

    /// The input.
    pub fn input(&self) -> &Arc<MappingInput> {
        &self.input
    }

    /// Scans begun: local SLAM has run for each (the last may still have
    /// searches or an optimization to run, see [`is_mid_scan`](Self::is_mid_scan)).
    pub fn scans_done(&self) -> usize {
        self.next
    }

    /// Whether every scan is in, with every phase of the last one.
    pub fn is_done(&self) -> bool {
        self.next >= self.input.scans.len() && self.pending.is_none()
    }

    /// Runs every remaining scan.
    pub fn run_to_end(&mut self) {
        while self.step() {}
    }

    /// The root trajectory of `t` (the one whose frame it is in).
    pub fn root(&self, mut t: usize) -> usize {
        while self.trajectories[t].joined_to != t {
            t = self.trajectories[t].joined_to;
        }
        t
    }

    fn start_trajectory(&mut self, scan: usize, by_detection: bool) -> usize {
        let id = self.trajectories.len();
        self.trajectories.push(Trajectory {
            first_scan: scan,
            started_by_detection: by_detection,
            joined_to: id,
            global_from_local: Pose2::IDENTITY,
            active: Vec::new(),
            last_scan: None,
            last_node: None,
            nodes: 0,
        });
        self.detector.reset();
        id
    }

    /// Finishes the active submaps of trajectory `t` (the trajectory ends).
    fn finish_trajectory(&mut self, t: usize) {
        let active = std::mem::take(&mut self.trajectories[t].active);
        for s in active {
            self.finish_submap(s);
        }
    }

    fn finish_submap(&mut self, s: usize) {
        let submap = &mut self.submaps[s];
        if submap.finished {
            return;
        }
        submap.finished = true;
        submap.precomputed =
            PrecomputedGrids::new(&submap.grid, self.params.max_height).map(Arc::new);
    }

    /// Processes the next scan whole: local SLAM, then every
    /// branch-and-bound search and optimization it leads to (or, in the
    /// middle of a scan stepped by [`step_phase`](Self::step_phase), the
    /// rest of that scan). Returns false when every scan is in.
    pub fn step(&mut self) -> bool {
        if self.is_done() {
            return false;
        }
        loop {
            self.step_phase();
            if self.pending.is_none() {
                return true;
            }
        }
    }

    /// Runs the next phase of the current scan, or local SLAM of the next
    /// scan when the current one is finished, and says which phase ran. A
    /// scan's phases run in the order [`step`](Self::step) runs them, so
    /// stepping by phases gives exactly what stepping by scans gives.
    pub fn step_phase(&mut self) -> CartographerPhase {
        let Some(pending) = self.pending.as_ref() else {
            return self.local_slam();
        };
        let scan = pending.scan;
        let phase = match pending.stage {
            Stage::Searches => self.run_next_search(),
            Stage::MergeOptimization => {
                self.optimize();
                if let Some(p) = self.pending.as_mut() {
                    p.stage = Stage::CountNode;
                }
                CartographerPhase::Optimization { scan }
            }
            Stage::DueOptimization => {
                self.optimize();
                if let Some(p) = self.pending.as_mut() {
                    p.stage = Stage::Finished;
                }
                CartographerPhase::Optimization { scan }
            }
            // Not left pending by `settle`; finished here all the same.
            Stage::CountNode | Stage::Finished => CartographerPhase::Settled { scan },
        };
        self.settle();
        phase
    }

    /// Whether a scan is part way through its phases (its searches or
    /// optimization still to run).
    pub fn is_mid_scan(&self) -> bool {
        self.pending.is_some()
    }

    /// What the next [`step_phase`](Self::step_phase) runs and what the
    /// current scan has left.
    pub fn outlook(&self) -> PhaseOutlook {
        let Some(p) = self.pending.as_ref() else {
            let next = if self.is_done() {
                NextPhase::Done
            } else {
                NextPhase::LocalSlam
            };
            return PhaseOutlook {
                scan: self.next,
                next,
                searches_pending: 0,
                searches_planned: 0,
                optimization_pending: false,
            };
        };
        let searches_pending = if p.stage == Stage::Searches {
            self.searches_left(p)
        } else {
            0
        };
        let next = match p.stage {
            Stage::Searches => NextPhase::Search,
            Stage::MergeOptimization | Stage::DueOptimization => NextPhase::Optimization,
            Stage::CountNode | Stage::Finished => NextPhase::LocalSlam,
        };
        let due = p.node.is_some()
            && self.nodes_since_optimization + 1 >= self.params.optimize_every_n_nodes;
        let optimization_pending = match p.stage {
            Stage::Searches => p.merged || due,
            Stage::MergeOptimization | Stage::DueOptimization => true,
            Stage::CountNode => due,
            Stage::Finished => false,
        };
        PhaseOutlook {
            scan: p.scan,
            next,
            searches_pending,
            searches_planned: p.searches_planned,
            optimization_pending,
        }
    }

    /// Local SLAM of the next scan: the prediction, scan-to-submap matching,
    /// the kidnap detector and, past the motion filter, the insertion into
    /// the submaps; its searches and optimization are left pending.
    fn local_slam(&mut self) -> CartographerPhase {
        let Some(input_scan) = self.input.scans.get(self.next) else {
            return CartographerPhase::Done;
        };
        let k = self.next;
        self.next += 1;
        let scan = input_scan.scan.clone();
        let odometry = input_scan.odometry;
        let time = input_scan.time;
        if self.trajectories.is_empty() {
            self.start_trajectory(k, false);
        }
        let mut t = self.trajectories.len() - 1;
        // Predict: the last pose moved by the odometry since then; the first
        // trajectory starts at the first odometry pose, a later one at the
        // origin of its own frame.
        let predicted = match self.trajectories[t].last_scan {
            Some((j, last)) => {
                let increment = self.input.scans[j].odometry.between(&odometry);
                let p = last.compose(&increment);
                Pose2::new(p.x, p.y, p.theta)
            }
            None if t == 0 && odometry.is_finite() => odometry,
            None => Pose2::IDENTITY,
        };
        let predicted = if predicted.is_finite() {
            predicted
        } else {
            self.trajectories[t]
                .last_scan
                .map_or(Pose2::IDENTITY, |(_, p)| p)
        };
        // Match against the oldest active submap.
        let points = scan.points();
        let matched = self.trajectories[t]
            .active
            .first()
            .and_then(|&s| {
                match_scan_to_map(
                    &self.submaps[s].grid,
                    &self.lookup,
                    &points,
                    predicted,
                    &self.params.local,
                )
            })
            .map(|(m, _)| m);
        let (mut local, cost) = matched.map_or((predicted, f64::NAN), |m| (m.pose, m.cost));
        let mut record = ScanRecord {
            scan: k,
            trajectory: t,
            cost,
            filtered: f64::NAN,
            trigger_level: f64::NAN,
            detected: false,
            node: false,
            global_pose: Pose2::IDENTITY,
            local_pose: Pose2::IDENTITY,
        };
        if self.params.detection && cost.is_finite() {
            let step = self.detector.push(cost);
            record.filtered = step.filtered.unwrap_or(f64::NAN);
            record.trigger_level = step.trigger_level.unwrap_or(f64::NAN);
            if step.triggered {
                // Kidnapped: this trajectory ends before the scan goes in;
                // a new one starts with it at its origin.
                record.detected = true;
                self.detections.push(k);
                self.finish_trajectory(t);
                t = self.start_trajectory(k, true);
                record.trajectory = t;
                local = Pose2::IDENTITY;
            }
        }
        record.local_pose = local;
        let traj = &mut self.trajectories[t];
        traj.last_scan = Some((k, local));
        let global = traj.global_from_local.compose(&local);
        record.global_pose = Pose2::new(global.x, global.y, global.theta);
        // The motion filter.
        let moves = match traj.last_node {
            None => true,
            Some((p, t0)) => {
                let d = p.between(&local);
                slamlab_core::math::hypot(d.x, d.y) > self.params.motion_filter_distance
                    || wrap_angle(d.theta).abs() > self.params.motion_filter_angle
                    || time - t0 > self.params.motion_filter_time
            }
        };
        let mut pending = PendingScan {
            scan: k,
            node: None,
            root: 0,
            planned: VecDeque::new(),
            searches_planned: 0,
            merged: false,
            stage: Stage::Finished,
        };
        if moves && !points.is_empty() {
            record.node = true;
            let node = self.add_node(t, k, local, &scan, &points);
            pending.node = Some(node);
            self.plan_searches(node, &mut pending);
            pending.stage = if pending.planned.is_empty() {
                Stage::CountNode
            } else {
                Stage::Searches
            };
        }
        self.records.push(record);
        self.pending = Some(pending);
        self.settle();
        CartographerPhase::LocalSlam { scan: k }
    }

    /// Moves the current scan past the stages that need no phase of their
    /// own: searches none of which is left to run, the count of nodes
    /// towards the next optimization, the end of the scan.
    fn settle(&mut self) {
        loop {
            let Some(p) = self.pending.as_ref() else {
                return;
            };
            match p.stage {
                Stage::Searches => {
                    if self.searches_left(p) > 0 {
                        return;
                    }
                    let merged = p.merged;
                    if let Some(p) = self.pending.as_mut() {
                        p.planned.clear();
                        p.stage = if merged {
                            Stage::MergeOptimization
                        } else {
                            Stage::CountNode
                        };
                    }
                }
                Stage::MergeOptimization | Stage::DueOptimization => return,
                Stage::CountNode => {
                    self.nodes_since_optimization += 1;
                    let due = self.nodes_since_optimization >= self.params.optimize_every_n_nodes;
                    if let Some(p) = self.pending.as_mut() {
                        p.stage = if due {
                            Stage::DueOptimization
                        } else {
                            Stage::Finished
                        };
                    }
                }
                Stage::Finished => {
                    self.pending = None;
                    return;
                }
            }
        }
    }

    /// Inserts scan `k` at `local` into trajectory `t`'s active submaps and
    /// makes it a node with its constraints; returns the node.
    fn add_node(
        &mut self,
        t: usize,
        k: usize,
        local: Pose2,
        scan: &Scan,
        points: &[Point2],
    ) -> usize {
        let time = self.input.scans[k].time;
        let n = self.params.num_range_data;
        // A new submap when there is none or the newest has num_range_data.
        let needs_new = match self.trajectories[t].active.last() {
            None => true,
            Some(&s) => self.submaps[s].num_range_data >= n,
        };
        if needs_new {
            let origin = Pose2::new(local.x, local.y, 0.0);
            let g = self.trajectories[t].global_from_local.compose(&origin);
            self.submaps.push(Submap {
                trajectory: t,
                local_pose: origin,
                global_pose: g,
                grid: ProbabilityGrid::new(self.params.resolution),
                num_range_data: 0,
                finished: false,
                precomputed: None,
                sampler: FixedRatioSampler::default(),
            });
            self.trajectories[t].active.push(self.submaps.len() - 1);
        }
        let node = self.nodes.len();
        let global = self.trajectories[t].global_from_local.compose(&local);
        let active = self.trajectories[t].active.clone();
        self.nodes.push(Node {
            trajectory: t,
            scan: k,
            local_pose: local,
            global_pose: global,
            points: Arc::new(spread_points(points, self.params.bbs_max_points)),
            submaps: active.clone(),
        });
        // Into both active submaps, the beams traced once.
        let mut grids: Vec<&mut ProbabilityGrid> = self
            .submaps
            .iter_mut()
            .enumerate()
            .filter(|(s, _)| active.contains(s))
            .map(|(_, submap)| &mut submap.grid)
            .collect();
        if let Err(why) =
            ProbabilityGrid::insert_scan_into_all(&mut grids, &local, scan, &self.insert)
        {
            self.notes.push(format!("scan {k}: {why}"));
        }
        for &s in &active {
            let submap = &mut self.submaps[s];
            submap.num_range_data += 1;
            let relative = submap.local_pose.between(&local);
            self.constraints.push(Constraint {
                submap: s,
                node,
                relative,
                kind: ConstraintKind::IntraSubmap,
                score: 1.0,
            });
            self.constrained.insert((s, node));
        }
        // The oldest is finished at 2 · num_range_data.
        if let Some(&front) = active.first()
            && self.submaps[front].num_range_data >= 2 * n
        {
            self.finish_submap(front);
            self.trajectories[t].active.remove(0);
        }
        let traj = &mut self.trajectories[t];
        traj.last_node = Some((local, time));
        traj.nodes += 1;
        node
    }

    /// Plans node `node`'s searches, in submap order: against each finished
    /// submap it has no constraint with yet,
    ///
    /// - of its own map: a search in a window around its estimate when the
    ///   submap's origin is within `max_constraint_distance`, the pair is not
    ///   tied already (`max_closures_per_submap_pair`) and the submap's
    ///   sampler takes it (`sampling_ratio`, Cartographer's
    ///   `ConstraintBuilder2D::MaybeAddConstraint`);
    /// - of another map (after a kidnap detection, before the maps are
    ///   merged): the whole submap at every heading, on every
    ///   `global_search_every_n_nodes`-th node of the trajectory
    ///   (Cartographer's `MaybeAddGlobalConstraint`). These come first, the
    ///   submaps nearest where the robot was last seen (the last node of the
    ///   trajectory the detection ended) first: the first match that passes
    ///   the merge check ends the node's searches, and after a false alarm
    ///   (the Intel log has one) the robot is still there.
    fn plan_searches(&mut self, node: usize, pending: &mut PendingScan) {
        let t = self.nodes[node].trajectory;
        pending.root = self.root(t);
        let global_due = self.trajectories[t]
            .nodes
            .is_multiple_of(self.params.global_search_every_n_nodes);
        let matching = self.nodes[node].submaps.first().copied();
        let node_global = self.nodes[node].global_pose;
        let limit = self.params.max_closures_per_submap_pair;
        let last_seen = if global_due && pending.root != 0 {
            self.last_seen_before(t)
        } else {
            None
        };
        let mut global: Vec<(f64, usize)> = Vec::new();
        let mut planned = VecDeque::new();
        for s in 0..self.submaps.len() {
            if !self.submaps[s].finished
                || self.submaps[s].precomputed.is_none()
                || self.constrained.contains(&(s, node))
            {
                continue;
            }
            if self.root(self.submaps[s].trajectory) != pending.root {
                if global_due {
                    let g = self.submaps[s].global_pose;
                    let d =
                        last_seen.map_or(0.0, |p| slamlab_core::math::hypot(g.x - p.x, g.y - p.y));
                    global.push((d, s));
                }
                continue;
            }
            let in_submap = self.submaps[s].global_pose.between(&node_global);
            if slamlab_core::math::hypot(in_submap.x, in_submap.y)
                > self.params.max_constraint_distance
            {
                continue;
            }
            if limit > 0
                && matching
                    .is_some_and(|m| self.pair_closures.get(&(m, s)).copied().unwrap_or(0) >= limit)
            {
                continue;
            }
            if self.submaps[s].sampler.pulse(self.params.sampling_ratio) {
                planned.push_back((s, false));
            }
        }
        global.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for (_, s) in global.into_iter().rev() {
            planned.push_front((s, true));
        }
        pending.searches_planned = planned.len();
        pending.planned = planned;
    }

    /// Where the robot was last seen before trajectory `t` began: the last
    /// node of the trajectory before it, in that trajectory's map.
    fn last_seen_before(&self, t: usize) -> Option<Pose2> {
        let previous = t.checked_sub(1)?;
        self.nodes
            .iter()
            .rev()
            .find(|n| n.trajectory == previous)
            .map(|n| n.global_pose)
    }

    /// The searches still to run for the current scan (none once a match
    /// merged its map into another).
    fn searches_left(&self, p: &PendingScan) -> usize {
        if p.merged || p.node.is_none() {
            0
        } else {
            p.planned.len()
        }
    }

    /// The window of a planned search of the current scan's node against
    /// submap `s`: around its estimate in its own map (with `min_score`), or
    /// the whole submap at every heading against a map not yet joined to
    /// its own (with `global_min_score`).
    fn search_window(&self, node: usize, s: usize, global: bool) -> (SearchWindow, f64) {
        if global {
            return (SearchWindow::WholeSubmap, self.params.global_min_score);
        }
        let submap = &self.submaps[s];
        // The node's estimate in the submap's grid frame.
        let in_submap = submap.global_pose.between(&self.nodes[node].global_pose);
        let initial = submap.local_pose.compose(&in_submap);
        (
            SearchWindow::Around {
                initial,
                linear: self.params.linear_search_window,
                angular: self.params.angular_search_window,
            },
            self.params.min_score,
        )
    }

    /// Runs the current scan's next branch-and-bound search and what comes
    /// of it: a loop closure, or a merge of two maps.
    fn run_next_search(&mut self) -> CartographerPhase {
        let Some(mut p) = self.pending.take() else {
            return CartographerPhase::Done;
        };
        let scan = p.scan;
        let mut phase = CartographerPhase::Settled { scan };
        if let (Some(node), false, Some((s, global))) = (p.node, p.merged, p.planned.pop_front()) {
            let (window, min_score) = self.search_window(node, s, global);
            let mut too_young = false;
            self.search(
                node,
                s,
                p.root,
                window,
                min_score,
                !global,
                &mut p.merged,
                &mut too_young,
            );
            if too_young {
                p.planned.retain(|&(_, g)| !g);
            }
            phase = CartographerPhase::Search {
                scan,
                submap: s,
                global,
            };
        }
        self.pending = Some(p);
        phase
    }

    /// One branch-and-bound search of node `node` against submap `s` in
    /// `window`; a match above `min_score` becomes a loop closure within
    /// the node's map (`same_map`), or merges the node's map (rooted at
    /// `root`) into the submap's when the check agrees (`merged` is set;
    /// `too_young` when the check refused it for too few known points).
    #[allow(clippy::too_many_arguments)]
    fn search(
        &mut self,
        node: usize,
        s: usize,
        root: usize,
        window: SearchWindow,
        min_score: f64,
        same_map: bool,
        merged: &mut bool,
        too_young: &mut bool,
    ) {
        let Some(grids) = self.submaps[s].precomputed.clone() else {
            return;
        };
        let submap_root = self.root(self.submaps[s].trajectory);
        let submap_local = self.submaps[s].local_pose;
        let submap_global = self.submaps[s].global_pose;
        let node_global = self.nodes[node].global_pose;
        let node_scan = self.nodes[node].scan;
        let points = Arc::clone(&self.nodes[node].points);
        let params = BranchAndBoundParams {
            min_score,
            recorded_nodes: RECORDED_TREE_NODES,
        };
        let (result, record) = branch_and_bound(&grids, &points, &window, &params);
        self.bbs.searches += 1;
        self.bbs.nodes_evaluated += record.evaluated();
        self.bbs.exhaustive_candidates += record.exhaustive_candidates;
        let score = result.as_ref().ok().map(|m| m.score);
        let best_bound = match &result {
            Err(NoMatch::BelowMinScore { best_bound, .. }) if best_bound.is_finite() => {
                Some(*best_bound)
            }
            _ => None,
        };
        self.last_search = Some(Arc::new(SearchEvent {
            scan: node_scan,
            node,
            submap: s,
            global: !same_map,
            score,
            min_score,
            best_bound,
            record,
        }));
        let m = match result {
            Ok(m) => m,
            Err(NoMatch::BelowMinScore { .. } | NoMatch::NoPoints | NoMatch::BadWindow) => {
                return;
            }
        };
        // Cartographer refines the fast correlative match with its Ceres
        // scan matcher (Eq. 5.5) before the constraint is made.
        let pose = if self.params.refine_matches {
            self.refine(s, &points, m.pose)
        } else {
            m.pose
        };
        // The constraint: the node in the submap's frame (Eq. 5.7).
        let relative = submap_local.between(&pose);
        let relative = Pose2::new(relative.x, relative.y, relative.theta);
        if same_map && self.params.loop_closure_gate > 0.0 {
            let moved = submap_global.compose(&relative);
            let shift = slamlab_core::math::hypot(moved.x - node_global.x, moved.y - node_global.y);
            if shift > self.params.loop_closure_gate {
                self.rejected_closures += 1;
                return;
            }
        }
        let kind = if same_map {
            ConstraintKind::LoopClosure
        } else {
            ConstraintKind::InterTrajectory
        };
        let constraint = Constraint {
            submap: s,
            node,
            relative,
            kind,
            score: m.score,
        };
        if same_map {
            self.constraints.push(constraint);
            self.constrained.insert((s, node));
            if let Some(&m) = self.nodes[node].submaps.first() {
                *self.pair_closures.entry((m, s)).or_insert(0) += 1;
            }
            return;
        }
        // A match between maps: the correction that would move the node's
        // map onto the submap's. It is taken only when the new map's scans,
        // moved by it, agree with the old map (their points on its occupied
        // cells, not in its free space), so that one aliased match in a
        // repeating corridor cannot merge the maps wrongly.
        let target = submap_global.compose(&relative);
        let correction = target.compose(&node_global.inverse());
        let correction = Pose2::new(correction.x, correction.y, correction.theta);
        let mut check = self.check_merge(root, submap_root, &correction);
        check.scan = node_scan;
        check.submap = s;
        check.score = m.score;
        check.node_pose = Pose2::new(target.x, target.y, target.theta);
        check.accepted = check.occupied_share >= self.params.merge_min_occupied_share
            && check.known_points >= self.params.merge_min_known_points;
        self.merge_checks.push(check);
        if !check.accepted {
            self.rejected_closures += 1;
            // Too few of the new map's points on the old map's known cells
            // to judge, though those that are agree: the new map is too young
            // for any match to pass, so this node searches no further (the
            // next node due searches again, nearest first).
            if check.known_points < self.params.merge_min_known_points
                && check.occupied_share >= self.params.merge_min_occupied_share
            {
                *too_young = true;
            }
            return;
        }
        self.constraints.push(constraint);
        self.constrained.insert((s, node));
        self.move_map(root, &correction, submap_root);
        self.merges.push(node_scan);
        *merged = true;
    }

    /// Refines a branch-and-bound match of `points` in submap `s` (grid
    /// frame) with Eq. 5.5, pulled towards the match as Cartographer's
    /// loop-closure Ceres matcher is (translation weight 10, rotation 1, ten
    /// iterations); the match itself when the refinement fails or wanders
    /// off by more than a cell.
    fn refine(&self, s: usize, points: &[Point2], pose: Pose2) -> Pose2 {
        let params = ScanToMapParams {
            correlative: false,
            translation_weight: 10.0,
            rotation_weight: 1.0,
            occupied_space_weight: 20.0,
            max_iterations: 10,
            ..self.params.local
        };
        let r = self.params.resolution;
        match match_scan_to_map(&self.submaps[s].grid, &self.lookup, points, pose, &params) {
            Some((m, _))
                if m.pose.is_finite()
                    && slamlab_core::math::hypot(m.pose.x - pose.x, m.pose.y - pose.y) <= r
                    && wrap_angle(m.pose.theta - pose.theta).abs() <= 0.05 =>
            {
                m.pose
            }
            _ => pose,
        }
    }

    /// Looks the scans of the map rooted at `new_root`, moved by
    /// `correction`, up in the submaps of the map rooted at `old_root`: how
    /// many of their points land on cells the old map knows, and the share
    /// of those on or next to cells it holds occupied (a point counts as
    /// on a wall when any old submap holds its cell or one of the eight
    /// around it occupied). At most 100 nodes, evenly
    /// spread over the new map.
    fn check_merge(&self, new_root: usize, old_root: usize, correction: &Pose2) -> MergeCheck {
        let new_nodes: Vec<usize> = (0..self.nodes.len())
            .filter(|&n| self.root(self.nodes[n].trajectory) == new_root)
            .collect();
        let old_submaps: Vec<usize> = (0..self.submaps.len())
            .filter(|&s| self.root(self.submaps[s].trajectory) == old_root)
            .collect();
        // Each old submap's grid frame from the global frame.
        let frames: Vec<Pose2> = old_submaps
            .iter()
            .map(|&s| {
                let sm = &self.submaps[s];
                sm.local_pose.compose(&sm.global_pose.inverse())
            })
            .collect();
        let take = new_nodes.len().min(100);
        let (mut known, mut occupied) = (0usize, 0usize);
        for k in 0..take {
            let n = new_nodes[k * new_nodes.len() / take];
            let pose = correction.compose(&self.nodes[n].global_pose);
            for p in self.nodes[n].points.iter() {
                let q = slamlab_core::scan::transform_point(&pose, *p);
                let mut seen = false;
                let mut hit = false;
                for (&s, frame) in old_submaps.iter().zip(&frames) {
                    let g = slamlab_core::scan::transform_point(frame, q);
                    let grid = &self.submaps[s].grid;
                    let (i, j) = grid.cell_of(g[0], g[1]);
                    if grid.probability_at(i, j).is_none() {
                        continue;
                    }
                    seen = true;
                    // A wall one cell over still counts (a scan's points
                    // straddle the cells of the wall it hits).
                    if (-1..=1).any(|di| {
                        (-1..=1)
                            .any(|dj| grid.probability_at(i + di, j + dj).is_some_and(|p| p > 0.5))
                    }) {
                        hit = true;
                        break;
                    }
                }
                known += usize::from(seen);
                occupied += usize::from(hit);
            }
        }
        MergeCheck {
            scan: 0,
            submap: 0,
            score: 0.0,
            node_pose: Pose2::IDENTITY,
            nodes: take,
            known_points: known,
            occupied_share: if known == 0 {
                1.0
            } else {
                occupied as f64 / known as f64
            },
            accepted: false,
        }
    }

    /// Moves every submap and node of the map rooted at `root` by
    /// `correction` (applied on the left) and joins it to `onto`.
    fn move_map(&mut self, root: usize, correction: &Pose2, onto: usize) {
        let members: Vec<usize> = (0..self.trajectories.len())
            .filter(|&t| self.root(t) == root)
            .collect();
        for s in &mut self.submaps {
            if members.contains(&s.trajectory) {
                s.global_pose = correction.compose(&s.global_pose);
            }
        }
        for n in &mut self.nodes {
            if members.contains(&n.trajectory) {
                n.global_pose = correction.compose(&n.global_pose);
            }
        }
        for &t in &members {
            let g = correction.compose(&self.trajectories[t].global_from_local);
            self.trajectories[t].global_from_local = Pose2::new(g.x, g.y, g.theta);
        }
        self.trajectories[root].joined_to = onto;
    }

    /// Solves the pose graph (Eq. 5.8 with the Huber kernel) and writes the
    /// estimates back. The first submap of each map that nothing joins is
    /// held fixed (each map's own gauge).
    pub fn optimize(&mut self) {
        self.nodes_since_optimization = 0;
        if self.nodes.is_empty() {
            return;
        }
        let mut graph = PoseGraph::new();
        let node_base = self.submaps.len() as u64;
        for (s, submap) in self.submaps.iter().enumerate() {
            if graph.add_pose(s as u64, submap.global_pose).is_err() {
                self.notes.push(format!("submap {s}'s pose is not finite"));
                return;
            }
        }
        for (n, node) in self.nodes.iter().enumerate() {
            if graph
                .add_pose(node_base + n as u64, node.global_pose)
                .is_err()
            {
                self.notes.push(format!("node {n}'s pose is not finite"));
                return;
            }
        }
        let p = &self.params;
        for c in &self.constraints {
            let (wt, wr) = match c.kind {
                ConstraintKind::IntraSubmap => {
                    (p.matcher_translation_weight, p.matcher_rotation_weight)
                }
                _ => (
                    p.loop_closure_translation_weight,
                    p.loop_closure_rotation_weight,
                ),
            };
            let information =
                Matrix3::from_diagonal(&nalgebra::Vector3::new(wt * wt, wt * wt, wr * wr));
            let edge = EdgeKind::PosePose {
                from: c.submap,
                to: self.submaps.len() + c.node,
                measurement: c.relative,
                information,
            };
            if let Err(e) = graph.add_edge(edge) {
                self.notes.push(format!("a constraint was refused: {e}"));
            }
        }
        // Each map's anchor: the first submap of its root trajectory.
        for t in 0..self.trajectories.len() {
            if self.root(t) != t {
                continue;
            }
            if let Some(s) = self.submaps.iter().position(|s| s.trajectory == t) {
                let _ = graph.set_fixed(s as u64, true);
            }
        }
        // Nodes in no constraint (none, by construction) would be free; a
        // submap with no node cannot exist. Optimize.
        let settings = OptimizerSettings {
            solver: SolverKind::LevenbergMarquardt,
            kernel: RobustKernel::Huber {
                delta: p.huber_scale,
            },
            relative_tolerance: OPTIMIZER_RELATIVE_TOLERANCE,
            ..OptimizerSettings::default()
        };
        let mut optimizer = match Optimizer::new(graph, settings) {
            Ok(o) => o,
            Err(e) => {
                self.notes
                    .push(format!("the pose graph cannot be optimized: {e}"));
                return;
            }
        };
        let before: Vec<Pose2> = self.nodes.iter().map(|n| n.global_pose).collect();
        let mut report = OptimizationReport {
            scan: self.next.saturating_sub(1),
            iterations: 0,
            cost_before: f64::NAN,
            cost_after: f64::NAN,
            mean_node_move: 0.0,
            max_node_move: 0.0,
        };
        match optimizer.optimize(50, |_| true) {
            Ok(reports) => {
                report.iterations = reports.len();
                if let (Some(first), Some(last)) = (reports.first(), reports.last()) {
                    report.cost_before = first.cost_before;
                    report.cost_after = last.cost;
                }
            }
            Err(e) => self.notes.push(format!("the optimization stopped: {e}")),
        }
        self.optimizations += 1;
        let graph = optimizer.into_graph();
        for (i, v) in graph.vertices().iter().enumerate() {
            let slamlab_core::graph::VertexState::Pose(pose) = v.state else {
                continue;
            };
            if i < self.submaps.len() {
                self.submaps[i].global_pose = pose;
            } else if let Some(node) = self.nodes.get_mut(i - self.submaps.len()) {
                node.global_pose = pose;
            }
        }
        // Each trajectory's frame follows its newest node.
        for t in 0..self.trajectories.len() {
            if let Some(node) = self.nodes.iter().rev().find(|n| n.trajectory == t) {
                let g = node.global_pose.compose(&node.local_pose.inverse());
                self.trajectories[t].global_from_local = Pose2::new(g.x, g.y, g.theta);
            }
        }
        let moves: Vec<f64> = self
            .nodes
            .iter()
            .zip(&before)
            .map(|(n, b)| slamlab_core::math::hypot(n.global_pose.x - b.x, n.global_pose.y - b.y))
            .collect();
        if !moves.is_empty() {
            report.mean_node_move = moves.iter().sum::<f64>() / moves.len() as f64;
            report.max_node_move = moves.iter().copied().fold(0.0, f64::max);
        }
        self.last_optimization = Some(report);
    }

    /// Every processed scan's pose in the first map's frame as the pose graph
    /// has it now: a node's optimized pose; a scan that did not become a
    /// node, the last node of its trajectory before it moved by local SLAM's
    /// motion since. `None` for the scans of a map not joined to the first
    /// (and for scans not yet processed: the vector has one entry per input
    /// scan).
    pub fn scan_poses(&self) -> Vec<Option<Pose2>> {
        let mut out = vec![None; self.input.scans.len()];
        // Per trajectory: the last node's (global, local) pose.
        let mut last: Vec<Option<(Pose2, Pose2)>> = vec![None; self.trajectories.len()];
        let mut nodes = self.nodes.iter().peekable();
        for r in &self.records {
            let t = r.trajectory;
            if r.node
                && let Some(n) = nodes.next_if(|n| n.scan == r.scan)
                && let Some(slot) = last.get_mut(t)
            {
                *slot = Some((n.global_pose, n.local_pose));
            }
            if self.root(t) != 0 {
                continue;
            }
            let pose = match last.get(t).copied().flatten() {
                Some((global, local)) => global.compose(&local.between(&r.local_pose)),
                None => self.trajectories[t]
                    .global_from_local
                    .compose(&r.local_pose),
            };
            if let Some(slot) = out.get_mut(r.scan) {
                *slot = Some(Pose2::new(pose.x, pose.y, pose.theta));
            }
        }
        out
    }

    /// The map of every node in the first trajectory's frame (the first
    /// trajectory and every one joined to it), each node's scan inserted at
    /// its global pose into one grid.
    pub fn global_map(&self) -> ProbabilityGrid {
        let mut grid = ProbabilityGrid::new(self.params.resolution);
        for n in &self.nodes {
            if self.root(n.trajectory) != 0 {
                continue;
            }
            let _ = grid.insert_scan(&n.global_pose, &self.input.scans[n.scan].scan, &self.insert);
        }
        grid
    }

    /// The metrics of the run so far (`kidnap_at`: the scan of the
    /// simulated kidnap, if any).
    pub fn summary(&self, kidnap_at: Option<usize>, time_ms: f64) -> CartographerSummary {
        let detected = kidnap_at.and_then(|k| {
            self.detections
                .iter()
                .copied()
                .find(|&d| d >= k && d <= k + DETECTION_WINDOW)
        });
        let false_alarms = self
            .detections
            .iter()
            .filter(|&&d| kidnap_at.is_none_or(|k| d < k || d > k + DETECTION_WINDOW))
            .count();
        let loop_closures = self
            .constraints
            .iter()
            .filter(|c| c.kind != ConstraintKind::IntraSubmap)
            .count();
        let truth = self.input.truth.as_deref();
        let trajectory_rmse = truth.and_then(|truth| {
            let (mut sum, mut n) = (0.0, 0usize);
            for node in &self.nodes {
                if self.root(node.trajectory) != 0 {
                    continue;
                }
                if let Some(t) = truth.get(node.scan) {
                    let (dx, dy) = (node.global_pose.x - t.x, node.global_pose.y - t.y);
                    sum += dx * dx + dy * dy;
                    n += 1;
                }
            }
            (n > 0).then(|| (sum / n as f64).sqrt())
        });
        let map_agreement = self
            .input
            .true_map
            .as_ref()
            .and_then(|m| map_agreement(&self.global_map(), m));
        CartographerSummary {
            scans: self.records.len(),
            nodes: self.nodes.len(),
            submaps: self.submaps.len(),
            trajectories: self.trajectories.len(),
            kidnap_at,
            kidnap_detected_at: detected,
            detections: self.detections.clone(),
            false_alarms,
            recovered_at: self.merges.first().copied(),
            loop_closures,
            optimizations: self.optimizations,
            rejected_closures: self.rejected_closures,
            trajectory_rmse,
            map_agreement,
            bbs: self.bbs,
            time_ms,
            notes: self.notes.clone(),
        }
    }
}

/// An optimization stops when a Levenberg-Marquardt step lowers the cost
/// `Σ ρ(eᵀΩe)` by less than this share of it (or after 50 iterations). The
/// solver's default, 1e-5, took 2,140 iterations over the Intel log's 228
/// optimizations (9.5 s of CPU); 1e-3 took 864 (4.2 s), the last steps moving
/// the nodes by less than a millimetre (measured 2026-11-28).
pub const OPTIMIZER_RELATIVE_TOLERANCE: f64 = 1e-3;

/// Tree nodes each branch-and-bound search keeps for the lesson to draw
/// (the first ones in the order the depth-first search visits them).
pub const RECORDED_TREE_NODES: usize = 400;

/// A detection counts for a kidnap when it comes within this many scans
/// after it; any other is a false alarm.
pub const DETECTION_WINDOW: usize = 10;

/// What `slamlab run cartographer --json` prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CartographerSummary {
    /// Scans processed.
    pub scans: usize,
    /// Nodes (scans past the motion filter).
    pub nodes: usize,
    /// Submaps of every trajectory.
    pub submaps: usize,
    /// Trajectories (one more for each detection).
    pub trajectories: usize,
    /// The simulated kidnap's scan.
    pub kidnap_at: Option<usize>,
    /// The first detection within [`DETECTION_WINDOW`] scans after it.
    pub kidnap_detected_at: Option<usize>,
    /// Every detection.
    pub detections: Vec<usize>,
    /// Detections not within [`DETECTION_WINDOW`] scans after a kidnap.
    pub false_alarms: usize,
    /// The scan whose match merged a later map into the first.
    pub recovered_at: Option<usize>,
    /// Loop-closure constraints (inter-trajectory ones included).
    pub loop_closures: usize,
    /// Pose-graph optimizations.
    pub optimizations: usize,
    /// Loop closures refused by the gate.
    pub rejected_closures: usize,
    /// RMS position error of the nodes in the first map's frame against
    /// the truth, metres (simulation only).
    pub trajectory_rmse: Option<f64>,
    /// Agreement of the first map (with what was merged into it) with the
    /// true map, as the mapping lesson measures it (simulation only).
    pub map_agreement: Option<f64>,
    /// Branch-and-bound totals.
    pub bbs: BbsTotals,
    /// Wall time, milliseconds (measured by the caller).
    pub time_ms: f64,
    /// What went wrong along the way.
    pub notes: Vec<String>,
}
