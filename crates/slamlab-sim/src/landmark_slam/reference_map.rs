//! The reference map of Victoria Park: the same drive as a pose graph with its
//! trees already associated (`../shared/data/posegraphs/victoria_park.txt`, the
//! iSAM file gtsam ships: 6,969 poses, 151 trees, 6,968 odometry and 3,640
//! range-bearing edges), solved in batch by the project's own Levenberg-Marquardt
//! ([`slamlab_core::graph::Optimizer`]), then carried into a filter's frame.
//!
//! The graph's frame starts at its first pose and its poses carry no time, so the
//! pairing with the lesson's steps goes by distance driven. The graph's odometry is
//! the ACFR car model at the rear axle's centre, integrated from the same encoder
//! and steering (chained, it lies on the model's dead reckoning to centimetres);
//! the lesson estimates the laser's pose, 3.78 m ahead of the rear axle and 0.5 m
//! to its left ([`CarGeometry::VICTORIA_PARK`]). So each graph pose is moved to
//! its laser, `x_i ∘ (a, b, 0)`, before anything is compared: the laser of pose
//! `i` has driven `s_i` (the sum of the distances between the lasers of
//! consecutive chained poses), and the lesson's step whose dead-reckoning path
//! has driven the same distance is its partner (the estimate's pose there,
//! interpolated between the two steps around it). Umeyama's method
//! ([`crate::metrics::umeyama`], rigid) then gives the transform that moves the
//! solved path onto the estimate, and the RMS distance that remains is the
//! **alignment RMSE** (`sqrt(1/N Σ |p_k − (R r_k + t)|²)` over the `N` pairs).
//!
//! The filter's trees are scored against the reference trees seen so far: each
//! reference tree, carried into the filter's frame, is matched to the filter's
//! nearest tree within [`LANDMARK_GATE_M`]; the **landmark RMSE** is over the
//! matched ones, and how many matched is part of the score (a filter that
//! merged or never started a tree misses it).

use crate::io::graph::{GraphFileError, read_isam};
use crate::metrics::{Similarity, umeyama};
use nalgebra::Vector2;
use serde::Serialize;
use slamlab_core::Pose2;
use slamlab_core::graph::{
    EdgeKind, OptimizeError, Optimizer, OptimizerSettings, PoseGraph, SolverKind, StepReport,
    Vertex, VertexState,
};
use slamlab_core::math;
use slamlab_core::motion::CarGeometry;

/// The most Levenberg-Marquardt steps (rejected ones included) the reference
/// solve takes; Victoria Park converges in 147 (75 of them rejected).
pub const MAX_STEPS: usize = 400;

/// How far a filter's tree may lie from a reference tree (in the filter's frame,
/// after the alignment) and still count as the same tree, metres. Trunks in the
/// park stand a few metres apart; a filter's tree further off than this is
/// another tree, or a duplicate the filter started.
pub const LANDMARK_GATE_M: f64 = 3.0;

/// Why the reference graph cannot be solved.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// The file is no iSAM pose graph the reader accepts.
    #[error(transparent)]
    File(#[from] GraphFileError),
    /// The solver refused the graph.
    #[error("the reference graph cannot be solved: {0}")]
    Solve(#[from] OptimizeError),
    /// The graph has no poses or no landmarks.
    #[error("the reference graph has {poses} poses and {trees} landmarks; it needs both")]
    Empty {
        /// Poses in the graph.
        poses: usize,
        /// Landmarks in the graph.
        trees: usize,
    },
}

/// The pose graph being solved, one Levenberg-Marquardt step at a time, so the
/// lesson can spread the solve over frames.
#[derive(Debug)]
pub struct ReferenceSolver {
    optimizer: Optimizer,
    /// The cost `Σ eᵀΩe` of the odometry-chained start (twice gtsam's `error`).
    pub initial_cost: f64,
    /// Steps taken (rejected ones included).
    pub steps: usize,
    /// Steps LM rejected (the cost would have risen; λ grew).
    pub rejected: usize,
    done: bool,
    /// Vertex indices of the poses, in the odometry's order.
    pose_index: Vec<usize>,
    /// Distance the laser of each pose has driven along the chained odometry, metres.
    arc_length: Vec<f64>,
    /// Vertex indices of the landmarks and the position (in `pose_index`) of the
    /// first pose that sees each.
    trees: Vec<(usize, usize)>,
}

impl ReferenceSolver {
    /// Reads an iSAM pose graph (`ODOMETRY`/`LANDMARK` lines) and prepares its
    /// solve from the odometry-chained start, the first pose held fixed (gtsam's
    /// reference puts a tight prior there; the optimum is the same).
    pub fn new(text: &str) -> Result<Self, ReferenceError> {
        let mut graph = read_isam(text)?;
        let pose_index: Vec<usize> = (0..graph.vertices().len())
            .filter(|&i| matches!(graph.vertices()[i].state, VertexState::Pose(_)))
            .collect();
        let arc_length = distance_driven(&lasers(graph.vertices(), &pose_index));
        let trees = first_sightings(&graph, &pose_index);
        if pose_index.is_empty() || trees.is_empty() {
            return Err(ReferenceError::Empty {
                poses: pose_index.len(),
                trees: trees.len(),
            });
        }
        let first = graph.vertices()[pose_index[0]].id;
        graph
            .set_fixed(first, true)
            .map_err(|e| ReferenceError::Solve(e.into()))?;
        let optimizer = Optimizer::new(
            graph,
            OptimizerSettings {
                solver: SolverKind::LevenbergMarquardt,
                ..OptimizerSettings::default()
            },
        )?;
        let initial_cost = optimizer.cost();
        Ok(Self {
            optimizer,
            initial_cost,
            steps: 0,
            rejected: 0,
            done: false,
            pose_index,
            arc_length,
            trees,
        })
    }

    /// One Levenberg-Marquardt step (a factorization of the 7,120-vertex system);
    /// `None` once the solve is done. After an error the solve stops where it is.
    pub fn step(&mut self) -> Option<Result<StepReport, OptimizeError>> {
        if self.done {
            return None;
        }
        let report = self.optimizer.step();
        self.steps += 1;
        match &report {
            Ok(r) => {
                self.rejected += usize::from(!r.accepted);
                self.done = r.converged || self.steps >= MAX_STEPS;
            }
            Err(_) => self.done = true,
        }
        Some(report)
    }

    /// Steps until converged (or [`MAX_STEPS`]).
    pub fn solve(&mut self) -> Result<(), OptimizeError> {
        while let Some(r) = self.step() {
            r?;
        }
        Ok(())
    }

    /// Has the solve finished (converged, out of steps, or failed)?
    pub fn is_done(&self) -> bool {
        self.done
    }

    /// Has the solver converged (a step lowered the cost by less than 1e-5 of it)?
    pub fn is_converged(&self) -> bool {
        self.optimizer.is_converged()
    }

    /// The cost `Σ eᵀΩe` now (twice gtsam's `error`).
    pub fn cost(&self) -> f64 {
        self.optimizer.cost()
    }

    /// The map as solved so far.
    pub fn map(&self) -> ReferenceMap {
        let vertices = self.optimizer.graph().vertices();
        ReferenceMap {
            path: lasers(vertices, &self.pose_index),
            arc_length: self.arc_length.clone(),
            trees: self
                .trees
                .iter()
                .map(|&(i, first)| ReferenceTree {
                    id: vertices[i].id,
                    position: vertices[i].state.position(),
                    first_seen: first,
                })
                .collect(),
            cost: self.cost(),
            steps: self.steps,
            converged: self.is_converged(),
        }
    }
}

/// The laser's pose on the car at `pose` (the rear axle's centre):
/// `pose ∘ (a, b, 0)` with Victoria Park's `a = 3.78 m`, `b = 0.5 m`.
pub fn laser(pose: &Pose2) -> Pose2 {
    let car = CarGeometry::VICTORIA_PARK;
    pose.compose(&Pose2::new(car.laser_ahead, car.laser_left, 0.0))
}

/// The lasers ([`laser`]) of the pose vertices at `pose_index`, in that order.
fn lasers(vertices: &[Vertex], pose_index: &[usize]) -> Vec<Pose2> {
    pose_index
        .iter()
        .filter_map(|&i| match vertices[i].state {
            VertexState::Pose(p) => Some(laser(&p)),
            VertexState::Point(_) => None,
        })
        .collect()
}

/// For every landmark vertex: its index and the position (in `pose_index`) of the
/// first pose whose range-bearing or point edge sees it, in vertex order.
fn first_sightings(graph: &PoseGraph, pose_index: &[usize]) -> Vec<(usize, usize)> {
    let mut order = vec![usize::MAX; graph.vertices().len()];
    for (k, &i) in pose_index.iter().enumerate() {
        order[i] = k;
    }
    let mut first = vec![usize::MAX; graph.vertices().len()];
    for edge in graph.edges() {
        if let EdgeKind::RangeBearing { pose, point, .. }
        | EdgeKind::PosePoint { pose, point, .. } = *edge
        {
            first[point] = first[point].min(order[pose]);
        }
    }
    (0..graph.vertices().len())
        .filter(|&i| matches!(graph.vertices()[i].state, VertexState::Point(_)))
        .map(|i| (i, first[i]))
        .collect()
}

/// A landmark of the reference map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceTree {
    /// Its vertex id (10000 + the file's landmark number).
    pub id: u64,
    /// Its solved position, in the graph's frame.
    pub position: Vector2<f64>,
    /// The first pose that sees it (an index into [`ReferenceMap::path`]).
    pub first_seen: usize,
}

/// The solved pose graph: the path, the distance driven to each pose, the trees.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceMap {
    /// The solved poses' lasers ([`laser`]), in the odometry's order, in the
    /// graph's frame (its first pose, the rear axle, is the identity).
    pub path: Vec<Pose2>,
    /// Distance the laser of each pose has driven along the chained odometry, metres.
    pub arc_length: Vec<f64>,
    /// The solved trees.
    pub trees: Vec<ReferenceTree>,
    /// The cost `Σ eᵀΩe` (twice gtsam's `error`).
    pub cost: f64,
    /// Solver steps taken (rejected ones included).
    pub steps: usize,
    /// Did the solver converge?
    pub converged: bool,
}

/// The reference map carried into a filter's frame ([`align`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReferenceFit {
    /// The RMS distance between the filter's path and the aligned reference
    /// path over the pairs, metres.
    pub rmse: f64,
    /// Reference poses paired with a step of the lesson.
    pub pairs: usize,
    /// The rotation that carries the reference into the filter's frame, degrees.
    pub rotation_deg: f64,
    /// The translation that carries the reference into the filter's frame, metres.
    pub translation_m: [f64; 2],
    /// The last reference pose paired (an index into [`ReferenceMap::path`]):
    /// the trees first seen up to it are the ones the lesson has driven past.
    pub last_paired: usize,
    /// The transform (reference to filter).
    #[serde(skip)]
    pub similarity: Similarity,
}

impl ReferenceFit {
    /// A reference position in the filter's frame.
    pub fn apply(&self, p: &Vector2<f64>) -> Vector2<f64> {
        carry(&self.similarity, p)
    }
}

/// The position `p` moved by `similarity` (`R p + t`).
fn carry(similarity: &Similarity, p: &Vector2<f64>) -> Vector2<f64> {
    let q = similarity.apply(&Pose2::new(p[0], p[1], 0.0));
    Vector2::new(q.x, q.y)
}

/// The positions along `path` at each distance of `at` (ascending), where
/// `driven[k]` is the distance driven to `path[k]` (ascending); interpolated
/// between the two poses around it. Distances past the end give none.
fn at_distances(path: &[Pose2], driven: &[f64], at: &[f64]) -> Vec<[f64; 2]> {
    let mut out = Vec::with_capacity(at.len());
    let mut k = 0;
    let (Some(&end), true) = (driven.last(), path.len() == driven.len()) else {
        return out;
    };
    for &s in at {
        if s > end {
            break;
        }
        while k + 1 < driven.len() && driven[k + 1] < s {
            k += 1;
        }
        let (a, b) = (path[k], path[(k + 1).min(path.len() - 1)]);
        let span = driven[(k + 1).min(driven.len() - 1)] - driven[k];
        let f = if span > 0.0 {
            ((s - driven[k]) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push([a.x + f * (b.x - a.x), a.y + f * (b.y - a.y)]);
    }
    out
}

/// The distance driven to each pose of `path`, metres (0 at the first).
pub fn distance_driven(path: &[Pose2]) -> Vec<f64> {
    let mut driven = 0.0;
    let mut out = Vec::with_capacity(path.len());
    for (k, p) in path.iter().enumerate() {
        if k > 0 {
            driven += math::hypot(p.x - path[k - 1].x, p.y - path[k - 1].y);
        }
        out.push(driven);
    }
    out
}

/// Carries `map` into the frame of a filter whose path is `estimate` (one pose
/// per step, with `dead_reckoning` the lesson's dead-reckoning path of the same
/// steps): each reference pose is paired with the estimate where the dead
/// reckoning has driven as far as the reference's odometry, and Umeyama's rigid
/// fit moves the reference onto those poses. `None` before two distinct
/// positions pair (the car has not moved yet) or when the paths differ in length.
pub fn align(
    map: &ReferenceMap,
    dead_reckoning: &[Pose2],
    estimate: &[Pose2],
) -> Option<ReferenceFit> {
    if dead_reckoning.len() != estimate.len() || map.path.len() != map.arc_length.len() {
        return None;
    }
    let driven = distance_driven(dead_reckoning);
    let partners = at_distances(estimate, &driven, &map.arc_length);
    let n = partners.len();
    // The car stands still at the start: pairs only once it has moved.
    if n < 2 || map.arc_length[n - 1] <= 0.0 {
        return None;
    }
    let reference: Vec<[f64; 2]> = map.path[..n].iter().map(|p| [p.x, p.y]).collect();
    let similarity = umeyama(&reference, &partners, false).ok()?;
    let sum: f64 = reference
        .iter()
        .zip(&partners)
        .map(|(r, p)| {
            (carry(&similarity, &Vector2::new(r[0], r[1])) - Vector2::new(p[0], p[1]))
                .norm_squared()
        })
        .sum();
    Some(ReferenceFit {
        rmse: (sum / n as f64).sqrt(),
        pairs: n,
        rotation_deg: similarity.rotation.to_degrees(),
        translation_m: similarity.translation,
        last_paired: n - 1,
        similarity,
    })
}

/// A filter's trees against the reference trees it has driven past.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LandmarkScore {
    /// RMS distance from each matched reference tree (aligned) to the filter's
    /// nearest tree, metres; `None` when none matched.
    pub rmse: Option<f64>,
    /// Reference trees with a filter tree within the gate.
    pub matched: usize,
    /// Reference trees first seen by a pose paired so far.
    pub reference: usize,
    /// Trees in the filter's map.
    pub estimated: usize,
    /// The gate, metres ([`LANDMARK_GATE_M`]).
    pub gate_m: f64,
}

/// Scores `estimated` (a filter's tree positions, its frame) against the
/// reference trees first seen up to `fit.last_paired`, carried by `fit`: each
/// is matched to the nearest estimated tree within `gate_m` metres.
pub fn landmark_score(
    map: &ReferenceMap,
    fit: &ReferenceFit,
    estimated: &[Vector2<f64>],
    gate_m: f64,
) -> LandmarkScore {
    let mut sum = 0.0;
    let mut matched = 0;
    let mut reference = 0;
    for tree in map.trees.iter().filter(|t| t.first_seen <= fit.last_paired) {
        reference += 1;
        let p = fit.apply(&tree.position);
        let nearest = estimated
            .iter()
            .map(|e| (e - p).norm())
            .fold(f64::INFINITY, f64::min);
        if nearest <= gate_m {
            matched += 1;
            sum += nearest * nearest;
        }
    }
    LandmarkScore {
        rmse: (matched > 0).then(|| (sum / matched as f64).sqrt()),
        matched,
        reference,
        estimated: estimated.len(),
        gate_m,
    }
}

#[cfg(test)]
mod tests;
