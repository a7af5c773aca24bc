//! The graph-based SLAM simulation of thesis 000 Sec. 4.2 (Fig. 4.4-4.6).
//!
//! EKF-SLAM runs on the thesis's circle scenario; its estimated path becomes a pose
//! graph with one odometry edge between consecutive poses, plus loop closures from
//! the first pose to randomly chosen poses measured from the truth with noise; the
//! graph is then optimized. The result compares the position RMSE of dead
//! reckoning, EKF-SLAM and the optimized graph against the truth.

use crate::grid;
use crate::world::landmark_scenario::ekf_vs_ukf_scenario;
use crate::world::landmark_scenario::{EstimatorKind, LandmarkScenario};
use crate::world::landmark_session::LandmarkSession;
use nalgebra::{Matrix3, Vector3};
use rand::SeedableRng;
use rand::seq::index::sample;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use slamlab_core::Pose2;
use slamlab_core::graph::{
    EdgeKind, OptimizeError, Optimizer, OptimizerSettings, PoseGraph, SolverKind, VertexState,
};
use std::f64::consts::PI;

/// Ticks of the thesis's run (200 iterations, one lap of the circle at dt = 0.1 s).
pub const STEPS: u64 = 200;

/// Loop-closure noise at `noise_scale = 1`: standard deviations of x, y (m) and θ (rad).
/// The thesis measures its loop closures exactly; SLAM Lab adds this noise.
pub const LOOP_CLOSURE_STD: [f64; 3] = [0.05, 0.05, PI / 180.0];

/// Stream offset of the loop-closure RNG (kept apart from the world's streams).
const LOOP_CLOSURE_STREAM: u64 = 0x9e37_79b9_7f4a_7c15;

/// Settings of one run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PoseGraphExperimentConfig {
    /// Loop-closure edges from the first pose to distinct random poses.
    pub loop_closures: usize,
    /// Multiplies the control, measurement and loop-closure noise (2 is Experiment 2).
    pub noise_scale: f64,
    /// Seed of the world and of the loop-closure choice.
    pub seed: u64,
    /// The solver.
    pub solver: SolverKind,
    /// At most this many solver steps.
    pub max_iterations: usize,
}

impl Default for PoseGraphExperimentConfig {
    fn default() -> Self {
        Self {
            loop_closures: 10,
            noise_scale: 1.0,
            seed: 1,
            solver: SolverKind::GaussNewton,
            max_iterations: 20,
        }
    }
}

/// The outcome, with every choice spelled out.
#[derive(Clone, Debug, Serialize)]
pub struct PoseGraphExperimentResult {
    /// The settings.
    pub config: PoseGraphExperimentConfig,
    /// The scenario EKF-SLAM ran (thesis Experiment 1 with the noise scaled).
    pub scenario: LandmarkScenario,
    /// Ticks simulated.
    pub steps: u64,
    /// Poses in the graph (one per tick and the start).
    pub poses: usize,
    /// Edges in the graph.
    pub edges: usize,
    /// The poses the loop closures reach from pose 0.
    pub loop_closure_nodes: Vec<usize>,
    /// Odometry information `diag(1/σ_x², 1/σ_y², 1/σ_θ²)` with σ_x = σ_y = σ_v·dt, σ_θ = σ_w·dt.
    pub odometry_information: [f64; 3],
    /// Loop-closure information `diag(1/σ²)` from [`LOOP_CLOSURE_STD`] × noise scale.
    pub loop_closure_information: [f64; 3],
    /// How the gauge is fixed.
    pub gauge: String,
    /// Cost Σ eᵀΩe before optimizing.
    pub initial_cost: f64,
    /// Cost after each solver step.
    pub costs: Vec<f64>,
    /// Cost at the end.
    pub final_cost: f64,
    /// Solver steps taken.
    pub iterations: usize,
    /// Position RMSE (m) of dead reckoning against the truth.
    pub rmse_dead_reckoning: f64,
    /// Position RMSE (m) of EKF-SLAM.
    pub rmse_ekf: f64,
    /// Position RMSE (m) of the optimized graph.
    pub rmse_optimized: f64,
    /// Notes on the choices made.
    pub notes: Vec<String>,
    /// Paths `[x, y, θ]` per tick: truth, dead reckoning, EKF-SLAM, optimized.
    #[serde(skip)]
    pub paths: [Vec<Pose2>; 4],
}

/// The scenario: thesis Experiment 1 (`v = 1 m/s`, `w = π/10 rad/s`, 20 landmarks,
/// `q = [0.1, π/18]`, `v = [2, π/18]`) with control *and* measurement noise
/// multiplied by `noise_scale` (the thesis doubles both for its second run), EKF only.
pub fn scenario(noise_scale: f64, seed: u64) -> LandmarkScenario {
    let mut s = ekf_vs_ukf_scenario(noise_scale, seed);
    s.range_std *= noise_scale;
    s.bearing_std *= noise_scale;
    s.estimators = vec![EstimatorKind::Ekf];
    s
}

/// Runs EKF-SLAM and returns the truth, dead-reckoning and EKF paths, one pose per
/// tick including the start. (All use of the landmark session is here.)
fn run_ekf(scenario: &LandmarkScenario, steps: u64) -> [Vec<Pose2>; 3] {
    let mut session = LandmarkSession::new(scenario.clone());
    let ekf_pose = |s: &LandmarkSession| s.filters().first().map(|f| f.filter().robot_pose());
    let mut ekf = Vec::with_capacity(steps as usize + 1);
    ekf.push(ekf_pose(&session).unwrap_or_else(|| scenario.start_pose()));
    for _ in 0..steps {
        session.step_tick();
        if let Some(p) = ekf_pose(&session) {
            ekf.push(p);
        }
    }
    [
        session.truth_path().to_vec(),
        session.dead_reckoning_path().to_vec(),
        ekf,
    ]
}

/// The RMS position error of `a` against `b` over the poses both have, metres
/// (NaN when either is empty).
fn position_rmse(a: &[Pose2], b: &[Pose2]) -> f64 {
    grid::trajectory_rmse(a, Some(b)).unwrap_or(f64::NAN)
}

/// The experiment's graph before optimizing, with what it was built from.
#[derive(Clone, Debug)]
pub struct ThesisGraph {
    /// The scenario EKF-SLAM ran.
    pub scenario: LandmarkScenario,
    /// The graph: poses at the EKF-SLAM estimate, odometry edges, loop closures; pose 0 fixed.
    pub graph: PoseGraph,
    /// Poses in the graph.
    pub poses: usize,
    /// The poses the loop closures reach from pose 0.
    pub loop_closure_nodes: Vec<usize>,
    /// Odometry information diagonal.
    pub odometry_information: [f64; 3],
    /// Loop-closure information diagonal.
    pub loop_closure_information: [f64; 3],
    /// Loop-closure standard deviations (x, y, θ).
    pub loop_closure_std: [f64; 3],
    /// Paths per tick: truth, dead reckoning, EKF-SLAM.
    pub paths: [Vec<Pose2>; 3],
}

/// Runs EKF-SLAM and builds the experiment's graph (the part of [`run`] before the solver).
pub fn thesis_graph(config: &PoseGraphExperimentConfig) -> Result<ThesisGraph, OptimizeError> {
    let scenario = scenario(config.noise_scale, config.seed);
    let [truth, dead_reckoning, ekf] = run_ekf(&scenario, STEPS);
    let n = ekf.len().min(truth.len());
    let dt = scenario.dt;
    let (sx, st) = (scenario.v_std * dt, scenario.w_std * dt);
    let odometry_information = [1.0 / (sx * sx), 1.0 / (sx * sx), 1.0 / (st * st)];
    let lc_std = LOOP_CLOSURE_STD.map(|s| s * config.noise_scale);
    let loop_closure_information = lc_std.map(|s| 1.0 / (s * s));

    let mut graph = PoseGraph::new();
    for (k, p) in ekf.iter().take(n).enumerate() {
        graph.add_pose(k as u64, *p)?;
    }
    graph.set_fixed(0, true)?;
    let odo = Matrix3::from_diagonal(&Vector3::from(odometry_information));
    for k in 0..n.saturating_sub(1) {
        graph.add_edge(EdgeKind::PosePose {
            from: k,
            to: k + 1,
            measurement: ekf[k].between(&ekf[k + 1]),
            information: odo,
        })?;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed ^ LOOP_CLOSURE_STREAM);
    let candidates = n.saturating_sub(2);
    let count = config.loop_closures.min(candidates);
    let mut nodes: Vec<usize> = sample(&mut rng, candidates.max(1), count)
        .into_iter()
        .map(|k| k + 2)
        .collect();
    nodes.sort_unstable();
    let lc = Matrix3::from_diagonal(&Vector3::from(loop_closure_information));
    for &j in &nodes {
        let t = truth[0].between(&truth[j]);
        let mut noise = [0.0; 3];
        for (k, v) in noise.iter_mut().enumerate() {
            let z: f64 = slamlab_core::random::standard_normal(&mut rng);
            *v = z * lc_std[k];
        }
        graph.add_edge(EdgeKind::PosePose {
            from: 0,
            to: j,
            measurement: Pose2::new(t.x + noise[0], t.y + noise[1], t.theta + noise[2]),
            information: lc,
        })?;
    }
    Ok(ThesisGraph {
        scenario,
        graph,
        poses: n,
        loop_closure_nodes: nodes,
        odometry_information,
        loop_closure_information,
        loop_closure_std: lc_std,
        paths: [truth, dead_reckoning, ekf],
    })
}

/// Runs the experiment.
pub fn run(config: PoseGraphExperimentConfig) -> Result<PoseGraphExperimentResult, OptimizeError> {
    let ThesisGraph {
        scenario,
        graph,
        poses: n,
        loop_closure_nodes: nodes,
        odometry_information,
        loop_closure_information,
        loop_closure_std: lc_std,
        paths: [truth, dead_reckoning, ekf],
    } = thesis_graph(&config)?;
    let dt = scenario.dt;
    let count = nodes.len();
    let edges = graph.edges().len();
    let mut optimizer = Optimizer::new(
        graph,
        OptimizerSettings {
            solver: config.solver,
            ..OptimizerSettings::default()
        },
    )?;
    let initial_cost = optimizer.cost();
    let reports = optimizer.optimize(config.max_iterations, |_| true)?;
    let optimized: Vec<Pose2> = optimizer
        .graph()
        .vertices()
        .iter()
        .map(|v| match v.state {
            VertexState::Pose(p) => p,
            VertexState::Point(p) => Pose2::new(p[0], p[1], 0.0),
        })
        .collect();
    let notes = vec![
        format!(
            "EKF-SLAM on the circle of Experiment 1 in Xiang's thesis (§3.4.3) (v = 1 m/s, w = π/10 rad/s, dt = {dt} s, {STEPS} ticks, 20 random landmarks); control and measurement noise × {}",
            config.noise_scale
        ),
        "graph: one pose per tick at the EKF-SLAM estimate; odometry edges measure the EKF's relative pose between consecutive ticks".to_owned(),
        format!(
            "odometry information diag(1/(σ_v dt)², 1/(σ_v dt)², 1/(σ_w dt)²) with σ_v = {:.3} m/s, σ_w = {:.4} rad/s",
            scenario.v_std, scenario.w_std
        ),
        format!(
            "{count} loop closures from pose 0 to distinct random poses (seeded), measured as the true relative pose plus Gaussian noise σ = ({:.3} m, {:.3} m, {:.4} rad); Xiang's thesis (§4.2) uses the exact true relative pose",
            lc_std[0], lc_std[1], lc_std[2]
        ),
        "gauge: pose 0 held fixed at the EKF's (and the truth's) start pose".to_owned(),
        "RMSE: root mean square of the position error over every tick including the start".to_owned(),
    ];
    Ok(PoseGraphExperimentResult {
        config,
        scenario,
        steps: STEPS,
        poses: n,
        edges,
        loop_closure_nodes: nodes,
        odometry_information,
        loop_closure_information,
        gauge: "pose 0 fixed".to_owned(),
        initial_cost,
        costs: reports.iter().map(|r| r.cost).collect(),
        final_cost: optimizer.cost(),
        iterations: reports.len(),
        rmse_dead_reckoning: position_rmse(&dead_reckoning, &truth),
        rmse_ekf: position_rmse(&ekf[..n], &truth[..n]),
        rmse_optimized: position_rmse(&optimized, &truth[..n]),
        notes,
        paths: [truth, dead_reckoning, ekf, optimized],
    })
}

/// A synthetic Manhattan-world pose graph (after Olson et al.'s M3500): a robot
/// walks a grid of 1 m cells inside a square of `side` cells, going straight with
/// probability 0.7 and turning left or right by 90° otherwise; odometry edges carry
/// Gaussian noise σ = (0.05 m, 0.05 m, 1°); whenever it stands on a cell it visited
/// more than 10 poses ago, a loop closure to the latest such visit is measured with
/// the same noise. The initial estimate chains the noisy odometry; pose 0 is fixed.
/// Returns the graph and the true poses.
pub fn manhattan_graph(poses: usize, side: i64, seed: u64) -> (PoseGraph, Vec<Pose2>) {
    use rand::Rng;
    let sigma = [0.05, 0.05, PI / 180.0];
    let info = Matrix3::from_diagonal(&Vector3::from(sigma.map(|s| 1.0 / (s * s))));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noisy = |rng: &mut ChaCha8Rng, z: Pose2| {
        let n: [f64; 3] = [0, 1, 2].map(|k| {
            let g: f64 = slamlab_core::random::standard_normal(rng);
            g * sigma[k]
        });
        Pose2::new(z.x + n[0], z.y + n[1], z.theta + n[2])
    };
    let side = side.max(2);
    let (mut cx, mut cy, mut heading) = (0i64, 0i64, 0i64); // heading in quarter turns
    let mut truth = vec![Pose2::IDENTITY];
    let mut cells: Vec<(i64, i64)> = vec![(0, 0)];
    while truth.len() < poses.max(2) {
        let r: f64 = rng.random();
        let mut turn = if r < 0.7 {
            0
        } else if r < 0.85 {
            1
        } else {
            3
        };
        // Turn until the next cell is inside the square.
        for _ in 0..4 {
            let h = (heading + turn) % 4;
            let (dx, dy) = [(1, 0), (0, 1), (-1, 0), (0, -1)][h as usize];
            if (0..side).contains(&(cx + dx)) && (0..side).contains(&(cy + dy)) {
                break;
            }
            turn = (turn + 1) % 4;
        }
        heading = (heading + turn) % 4;
        let (dx, dy) = [(1, 0), (0, 1), (-1, 0), (0, -1)][heading as usize];
        cx += dx;
        cy += dy;
        truth.push(Pose2::new(cx as f64, cy as f64, heading as f64 * PI / 2.0));
        cells.push((cx, cy));
    }
    let mut graph = PoseGraph::new();
    let mut estimate = Pose2::IDENTITY;
    let mut measurements = Vec::with_capacity(truth.len());
    for k in 0..truth.len() {
        if k > 0 {
            let z = noisy(&mut rng, truth[k - 1].between(&truth[k]));
            estimate = estimate.compose(&z);
            measurements.push(z);
        }
        // Ids and states are valid by construction; a failure here cannot happen.
        let _ = graph.add_pose(k as u64, estimate);
    }
    let _ = graph.set_fixed(0, true);
    for (k, z) in measurements.iter().enumerate() {
        let _ = graph.add_edge(EdgeKind::PosePose {
            from: k,
            to: k + 1,
            measurement: *z,
            information: info,
        });
    }
    for k in 0..truth.len() {
        if let Some(j) = (0..k.saturating_sub(10))
            .rev()
            .find(|&j| cells[j] == cells[k])
        {
            let z = noisy(&mut rng, truth[j].between(&truth[k]));
            let _ = graph.add_edge(EdgeKind::PosePose {
                from: j,
                to: k,
                measurement: z,
                information: info,
            });
        }
    }
    (graph, truth)
}
