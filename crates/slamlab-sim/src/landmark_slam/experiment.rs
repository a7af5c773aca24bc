//! The thesis's simulation experiments (thesis `000` Sec. 3.4.3), reproduced.
//!
//! Experiment 1: 200 iterations of the circle `u_v = 1 m/s`, `u_w = π/10 rad/s`,
//! 20 landmarks, control noise `q = [0.1 m/s, π/18 rad/s]`, measurement noise
//! `v = [2 m, π/18 rad]`. Experiment 2 doubles `q`. The thesis leaves out the
//! time step, the map size and the sensor; SLAM Lab uses `dt = 0.1 s` (one lap in
//! 200 iterations), a 20 m square with uniformly random landmarks, and a sensor
//! that sees all around to 8 m. Every parameter is printed with the results.

use crate::world::landmark_session::{FilterRun, LandmarkSession};
use serde::Serialize;

pub use crate::world::landmark_scenario::ekf_vs_ukf_scenario;

/// Iterations per trial, as in the thesis.
pub const STEPS: u64 = 200;

/// A final robot error above this (metres) counts a trial as diverged.
pub const DIVERGED_ERROR: f64 = 5.0;

/// Has this run diverged: is its final robot error above [`DIVERGED_ERROR`] (or not
/// a number)?
pub(crate) fn has_diverged(run: &FilterRun) -> bool {
    run.latest()
        .is_some_and(|m| !(m.position_error <= DIVERGED_ERROR))
}

/// Mean and sample standard deviation.
fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    if values.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mean = values.iter().sum::<f64>() / n;
    let var = if values.len() > 1 {
        values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    (mean, var.sqrt())
}

/// One filter's results over all trials.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FilterResult {
    /// "ekf" or "ukf".
    pub name: String,
    /// Mean over trials of the time-averaged squared robot position error, m².
    pub robot_mse: f64,
    /// Its standard deviation across trials.
    pub robot_mse_std: f64,
    /// Mean over trials of the time-averaged squared landmark position error
    /// (mean over initialized landmarks at each step), m².
    pub landmark_mse: f64,
    /// Its standard deviation across trials.
    pub landmark_mse_std: f64,
    /// Mean over trials of the squared robot position error after the last step, m².
    pub robot_mse_final: f64,
    /// Its standard deviation across trials.
    pub robot_mse_final_std: f64,
    /// Mean over trials of the squared landmark error after the last step, m².
    pub landmark_mse_final: f64,
    /// Its standard deviation across trials.
    pub landmark_mse_final_std: f64,
    /// Mean robot-pose NEES over all trials and steps (3 degrees of freedom).
    pub nees_mean: f64,
    /// Trials whose final robot error exceeds 5 m.
    pub diverged: usize,
    /// The largest final robot position error of any trial, metres.
    pub robot_error_final_max: f64,
}

/// Per-step errors averaged over trials (thesis Fig. 3.4 and 3.6).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepSeries {
    /// The filter.
    pub name: String,
    /// Mean squared robot position error at each step, m².
    pub robot_mse: Vec<f64>,
    /// Mean squared landmark error at each step, m² (NaN before any landmark).
    pub landmark_mse: Vec<f64>,
}

/// The outcome of an experiment.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExperimentResult {
    /// "ekf-vs-ukf".
    pub experiment: String,
    /// Every parameter used, including the ones the thesis leaves out.
    pub parameters: serde_json::Map<String, serde_json::Value>,
    /// One entry per filter.
    pub filters: Vec<FilterResult>,
    /// The per-step series, for plotting.
    #[serde(skip)]
    pub series: Vec<StepSeries>,
}

/// Runs `trials` trials of thesis Experiment 1 (noise scale 1) or 2 (scale 2);
/// trial `i` uses seed `seed + i`. `progress(done, total)` is called after each trial.
pub fn ekf_vs_ukf(
    noise_scale: f64,
    trials: usize,
    seed: u64,
    mut progress: impl FnMut(usize, usize),
) -> ExperimentResult {
    let template = ekf_vs_ukf_scenario(noise_scale, seed);
    let names: Vec<&str> = template.estimators.iter().map(|e| e.name()).collect();
    let n_filters = names.len();
    let steps = STEPS as usize;
    // Per filter: per-trial summaries and per-step sums.
    let mut robot_avg = vec![Vec::new(); n_filters];
    let mut landmark_avg = vec![Vec::new(); n_filters];
    let mut robot_final = vec![Vec::new(); n_filters];
    let mut landmark_final = vec![Vec::new(); n_filters];
    let mut nees = vec![Vec::new(); n_filters];
    let mut diverged = vec![0; n_filters];
    let mut robot_steps = vec![vec![0.0; steps]; n_filters];
    let mut landmark_steps = vec![vec![(0.0, 0usize); steps]; n_filters];
    for trial in 0..trials {
        let mut session = LandmarkSession::new(ekf_vs_ukf_scenario(
            noise_scale,
            seed.wrapping_add(trial as u64),
        ));
        session.run_ticks(STEPS);
        for (f, run) in session.filters().iter().enumerate() {
            let h = &run.history;
            let robot_sq: Vec<f64> = h.iter().map(|m| m.position_error.powi(2)).collect();
            let landmark_sq: Vec<f64> = h
                .iter()
                .filter_map(|m| m.landmark_rmse.map(|r| r * r))
                .collect();
            robot_avg[f].push(mean_std(&robot_sq).0);
            if !landmark_sq.is_empty() {
                landmark_avg[f].push(mean_std(&landmark_sq).0);
            }
            let last = h.last();
            robot_final[f].push(last.map_or(f64::NAN, |m| m.position_error.powi(2)));
            if let Some(r) = last.and_then(|m| m.landmark_rmse) {
                landmark_final[f].push(r * r);
            }
            nees[f].extend(h.iter().filter_map(|m| m.nees));
            if has_diverged(run) {
                diverged[f] += 1;
            }
            for (k, m) in h.iter().enumerate().take(steps) {
                robot_steps[f][k] += m.position_error.powi(2) / trials as f64;
                if let Some(r) = m.landmark_rmse {
                    landmark_steps[f][k].0 += r * r;
                    landmark_steps[f][k].1 += 1;
                }
            }
        }
        progress(trial + 1, trials);
    }
    let filters = (0..n_filters)
        .map(|f| {
            let (robot_mse, robot_mse_std) = mean_std(&robot_avg[f]);
            let (landmark_mse, landmark_mse_std) = mean_std(&landmark_avg[f]);
            let (robot_mse_final, robot_mse_final_std) = mean_std(&robot_final[f]);
            let (landmark_mse_final, landmark_mse_final_std) = mean_std(&landmark_final[f]);
            FilterResult {
                name: names[f].to_owned(),
                robot_mse,
                robot_mse_std,
                landmark_mse,
                landmark_mse_std,
                robot_mse_final,
                robot_mse_final_std,
                landmark_mse_final,
                landmark_mse_final_std,
                nees_mean: mean_std(&nees[f]).0,
                diverged: diverged[f],
                robot_error_final_max: robot_final[f].iter().fold(0.0_f64, |m, v| m.max(v.sqrt())),
            }
        })
        .collect();
    let series = (0..n_filters)
        .map(|f| StepSeries {
            name: names[f].to_owned(),
            robot_mse: robot_steps[f].clone(),
            landmark_mse: landmark_steps[f]
                .iter()
                .map(|(s, c)| if *c > 0 { s / *c as f64 } else { f64::NAN })
                .collect(),
        })
        .collect();
    let mut parameters = crate::landmark_slam::summary::parameters_json(&template);
    parameters.remove("seed");
    parameters.insert("seed".into(), seed.into());
    parameters.insert("trials".into(), trials.into());
    parameters.insert("steps".into(), STEPS.into());
    parameters.insert(
        "noise-scale".into(),
        serde_json::Number::from_f64(noise_scale).map_or(serde_json::Value::Null, Into::into),
    );
    parameters.insert(
        "trial-seeds".into(),
        format!("seed + trial index (0..{trials})").into(),
    );
    parameters.insert(
        "diverged-if-final-error-above-m".into(),
        DIVERGED_ERROR.into(),
    );
    ExperimentResult {
        experiment: "ekf-vs-ukf".to_owned(),
        parameters,
        filters,
        series,
    }
}

/// The per-step series as CSV: `step,time_s,<filter>_robot_mse,<filter>_landmark_mse,…`.
pub fn series_csv(result: &ExperimentResult, dt: f64) -> String {
    let mut out = String::from("step,time_s");
    for s in &result.series {
        out.push_str(&format!(",{0}_robot_mse,{0}_landmark_mse", s.name));
    }
    out.push('\n');
    let steps = result
        .series
        .iter()
        .map(|s| s.robot_mse.len())
        .max()
        .unwrap_or(0);
    for k in 0..steps {
        out.push_str(&format!("{},{:.3}", k + 1, (k + 1) as f64 * dt));
        for s in &result.series {
            let fmt = |v: Option<&f64>| {
                v.filter(|v| v.is_finite())
                    .map_or(String::new(), |v| format!("{v:.6}"))
            };
            out.push_str(&format!(
                ",{},{}",
                fmt(s.robot_mse.get(k)),
                fmt(s.landmark_mse.get(k))
            ));
        }
        out.push('\n');
    }
    out
}
