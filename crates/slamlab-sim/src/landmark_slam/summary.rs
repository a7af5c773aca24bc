//! Whole-run metrics and the headless runner behind the CLI and the tests.

use crate::params;
use crate::world::landmark_scenario::Association;
use crate::world::landmark_scenario::LandmarkScenario;
use crate::world::landmark_session::{
    FilterRun, LandmarkSession, nearest_landmark_rmse, tick_metrics,
};
use crate::world::recorded::RecordedWorld;
use serde::Serialize;
use std::sync::Arc;

/// The summary of one estimator over one run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FilterSummary {
    /// The estimator ("ekf").
    pub name: String,
    /// Root mean square robot position error over all ticks, metres.
    pub robot_rmse: f64,
    /// Robot position error after the last tick, metres.
    pub robot_error_final: f64,
    /// RMS landmark position error after the last tick, over initialized landmarks, metres.
    pub landmark_rmse: Option<f64>,
    /// Mean robot-pose NEES over the ticks where it is defined (3 degrees of freedom).
    pub nees_mean: Option<f64>,
    /// Mean NIS over all correcting updates (2 degrees of freedom).
    pub nis_mean: Option<f64>,
    /// Landmarks in the state at the end.
    pub landmarks_initialized: usize,
}

impl FilterSummary {
    /// Summarizes one estimator's history.
    pub fn of(run: &FilterRun) -> Self {
        let h = &run.history;
        let robot_rmse = if h.is_empty() {
            0.0
        } else {
            (h.iter().map(|m| m.position_error.powi(2)).sum::<f64>() / h.len() as f64).sqrt()
        };
        let nees: Vec<f64> = h.iter().filter_map(|m| m.nees).collect();
        let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        let nis: Vec<f64> = run.nis.iter().map(|s| s.nis).collect();
        Self {
            name: run.kind.name().to_owned(),
            robot_rmse,
            robot_error_final: h.last().map_or(0.0, |m| m.position_error),
            landmark_rmse: h.last().and_then(|m| m.landmark_rmse),
            nees_mean: mean(&nees),
            nis_mean: mean(&nis),
            landmarks_initialized: h.last().map_or(0, |m| m.landmarks_initialized),
        }
    }
}

/// The summary of a whole run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunSummary {
    /// The lesson ("landmark-slam").
    pub lesson: String,
    /// Ticks run.
    pub steps: u64,
    /// The seed.
    pub seed: u64,
    /// Simulated time, seconds.
    pub duration_s: f64,
    /// Every parameter used, by its URL/CLI name, in its URL/CLI unit.
    pub parameters: serde_json::Map<String, serde_json::Value>,
    /// What had to be changed in the parameters.
    pub notices: Vec<String>,
    /// One entry per estimator.
    pub filters: Vec<FilterSummary>,
    /// The recorded world the run replayed (absent for the simulated world).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub data: Option<DataSummary>,
}

/// The recorded world of a run: what it is and where it comes from.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DataSummary {
    /// "MRCLAM_Dataset6, robot 1".
    pub name: String,
    /// The data set's title.
    pub title: String,
    /// Where its files come from.
    pub source: String,
    /// How to cite it.
    pub citation: String,
    /// The steps played and the world's step count.
    pub steps_played: usize,
    /// The world's step count.
    pub steps_total: usize,
    /// Whether the data has the robot's true path (the robot errors and NEES
    /// are over the ticks where it does).
    pub has_truth: bool,
}

/// Every parameter of a scenario as JSON, numbers as numbers.
pub fn parameters_json(scenario: &LandmarkScenario) -> serde_json::Map<String, serde_json::Value> {
    params::to_pairs(scenario)
        .into_iter()
        .map(|(k, v)| {
            let value = match (k, v.parse::<f64>()) {
                ("seed", _) => scenario.seed.into(),
                ("landmarks", _) => scenario.landmarks.into(),
                (_, Ok(n)) if n.is_finite() => {
                    serde_json::Number::from_f64(n).map_or(serde_json::Value::String(v), Into::into)
                }
                _ => serde_json::Value::String(v),
            };
            (k.to_owned(), value)
        })
        .collect()
}

/// Runs a scenario for `steps` ticks without a user interface.
pub fn run_headless(scenario: LandmarkScenario, steps: u64) -> (LandmarkSession, RunSummary) {
    let mut session = LandmarkSession::new(scenario);
    session.run_ticks(steps);
    let summary = RunSummary {
        lesson: "landmark-slam".to_owned(),
        steps,
        seed: session.scenario().seed,
        duration_s: session.time(),
        parameters: parameters_json(session.scenario()),
        notices: session.notices().to_vec(),
        filters: session.filters().iter().map(FilterSummary::of).collect(),
        data: None,
    };
    (session, summary)
}

/// Replays a recorded world for `steps` ticks, or to its end, without a user
/// interface. The errors are over the ticks where the data has a truth.
pub fn run_recorded(
    scenario: LandmarkScenario,
    world: Arc<RecordedWorld>,
    steps: Option<u64>,
) -> (LandmarkSession, RunSummary) {
    let mut session = LandmarkSession::recorded(scenario, world.clone());
    session.run_ticks(steps.unwrap_or(u64::MAX));
    let source = world.source();
    let (played, total) = session.recorded_progress().unwrap_or_default();
    let unknown = session.scenario().association == Association::Unknown;
    let mut filters: Vec<FilterSummary> = session.filters().iter().map(FilterSummary::of).collect();
    // The map is compared with the true landmarks after the last tick, whether
    // or not the data knows the robot's path then.
    for (summary, run) in filters.iter_mut().zip(session.filters()) {
        summary.landmark_rmse = if unknown {
            nearest_landmark_rmse(session.world(), run.filter())
        } else {
            tick_metrics(0, 0.0, &world.start, session.world(), run.filter()).landmark_rmse
        };
        summary.landmarks_initialized = run.filter().landmark_ids().len();
    }
    let summary = RunSummary {
        lesson: "landmark-slam".to_owned(),
        steps: session.tick(),
        seed: session.scenario().seed,
        duration_s: session.time(),
        parameters: parameters_json(session.scenario()),
        notices: session.notices().to_vec(),
        filters,
        data: Some(DataSummary {
            name: world.name.clone(),
            title: source.title.to_owned(),
            source: source.source.to_owned(),
            citation: source.citation.to_owned(),
            steps_played: played,
            steps_total: total,
            has_truth: world.truth.is_some(),
        }),
    };
    (session, summary)
}
