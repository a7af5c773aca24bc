//! The "Many runs" window: the lesson's scenario run again with many seeds, and
//! each filter's robot-pose NEES averaged tick by tick against the narrow band of
//! a consistent filter's average (slamlab-sim's [`ConsistencyStudy`]).
//!
//! One run's NEES plot cannot show whether a filter is honest: a consistent
//! filter's NEES scatters over [0.22, 9.35]. Averaged over 50 runs with other
//! noise, it lies in [2.36, 3.72] at about 95% of the ticks; the window shows where
//! each filter leaves it.

use super::plots::{band_ui, thin, time_plot};
use crate::palette;
use crate::query::MANY_RUNS_RANGE;
use crate::widgets::plots::{KeyEntry, Mark, key_ui};
use egui_plot::{Line, PlotPoints};
use slamlab_sim::landmark_slam::consistency::{ConsistencyResult, ConsistencyStudy};
use slamlab_sim::params;
use slamlab_sim::{ControllerKind, LandmarkScenario, LandmarkSession};
use std::f64::consts::PI;

/// The most time one frame spends on the runs, milliseconds.
const FRAME_BUDGET_MS: u128 = 12;
/// Ticks run between two looks at the clock (one: a tick of a huge map is slow).
const TICKS_PER_SLICE: u64 = 1;
/// Longest run offered, ticks (500 s at the default time step).
const MAX_STEPS: u64 = 5_000;

/// How long each run is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunLength {
    /// One lap of the scripted circle.
    OneLap,
    /// As long as the run on the map, replaying its commands (a manual drive too).
    ThisRun,
}

/// The window's settings and the study in progress.
#[derive(Debug)]
pub struct ManyRunsState {
    /// How many runs the next study has.
    pub trials: usize,
    /// How long each run is.
    pub length: RunLength,
    study: Option<ConsistencyStudy>,
    /// Is the study being advanced (not stopped)?
    running: bool,
    /// Why the last start did not happen, for the user.
    message: Option<String>,
}

impl Default for ManyRunsState {
    fn default() -> Self {
        Self {
            trials: 50,
            length: RunLength::OneLap,
            study: None,
            running: false,
            message: None,
        }
    }
}

/// Ticks in one lap of the scenario's circle, if it drives one.
fn lap_ticks(scenario: &LandmarkScenario) -> Option<u64> {
    match scenario.controller {
        ControllerKind::Circle { w, .. } if w.abs() > 1e-9 => {
            let ticks = (2.0 * PI / w.abs() / scenario.dt).round();
            (ticks.is_finite() && ticks >= 1.0).then(|| (ticks as u64).min(MAX_STEPS))
        }
        _ => None,
    }
}

impl ManyRunsState {
    /// Starts a study of the session's scenario as it stands now (the controller that
    /// drives and the sensor's reach now): `trials` runs from the session's seed on,
    /// each one lap of the circle or a replay of the session's commands.
    pub fn start(&mut self, session: &LandmarkSession) {
        self.message = None;
        let scenario = session.scenario_now();
        let trials = self
            .trials
            .clamp(*MANY_RUNS_RANGE.start(), *MANY_RUNS_RANGE.end());
        let study = match (self.length, lap_ticks(&scenario)) {
            (RunLength::OneLap, Some(steps)) => ConsistencyStudy::new(scenario, trials, steps),
            (RunLength::OneLap, _) => {
                self.message = Some(
                    "One lap needs the scripted circle; choose \"this run\" to replay your drive."
                        .to_owned(),
                );
                return;
            }
            (RunLength::ThisRun, _) => {
                let commands = session.commands();
                if commands.is_empty() {
                    self.message =
                        Some("This run has no ticks yet: run or drive first.".to_owned());
                    return;
                }
                let steps = commands.len().min(MAX_STEPS as usize);
                ConsistencyStudy::replaying(scenario, trials, commands[..steps].to_vec())
            }
        };
        self.study = Some(study);
        self.running = true;
    }

    /// Stops advancing the study (its results so far stay).
    pub fn stop(&mut self) {
        self.running = false;
    }

    /// Is a study being advanced?
    pub fn is_running(&self) -> bool {
        self.running && self.study.as_ref().is_some_and(|s| !s.is_done())
    }

    /// The study's results so far.
    pub fn result(&self) -> Option<ConsistencyResult> {
        self.study.as_ref().map(ConsistencyStudy::result)
    }

    /// Advances the study for at most `budget_ms` milliseconds.
    pub fn advance(&mut self, budget_ms: u128) {
        if !self.is_running() {
            return;
        }
        let Some(study) = self.study.as_mut() else {
            return;
        };
        let start = web_time::Instant::now();
        while !study.advance(TICKS_PER_SLICE) && start.elapsed().as_millis() < budget_ms {}
        if study.is_done() {
            self.running = false;
        }
    }
}

/// The window's contents.
pub fn many_runs_ui(ui: &mut egui::Ui, state: &mut ManyRunsState, session: &LandmarkSession) {
    state.advance(FRAME_BUDGET_MS);
    if state.is_running() {
        ui.ctx().request_repaint();
    }
    ui.label(
        "One run's NEES jumps about: a consistent filter's lies anywhere in [0.22, 9.35] \
         95% of the time. Run the same world and drive again with other noise, average \
         the NEES tick by tick, and the average of a consistent filter stays in a \
         narrow band around 3 (for 50 runs, [2.36, 3.72]) at about 95% of the ticks. \
         Above it, the filter is overconfident; below it, too cautious.",
    );
    ui.add_space(4.0);
    let lap = lap_ticks(&session.scenario_now());
    let dt = session.scenario().dt;
    ui.horizontal_wrapped(|ui| {
        ui.label("runs");
        ui.add(
            egui::DragValue::new(&mut state.trials)
                .range(MANY_RUNS_RANGE)
                .speed(1.0),
        )
        .on_hover_text("Run i uses the seed of the run on the map plus i");
        ui.separator();
        ui.label("each");
        let lap_label = match lap {
            Some(ticks) => format!("one lap ({:.1} s)", ticks as f64 * dt),
            None => "one lap (circle only)".to_owned(),
        };
        ui.add_enabled_ui(lap.is_some(), |ui| {
            ui.radio_value(&mut state.length, RunLength::OneLap, lap_label);
        });
        ui.radio_value(
            &mut state.length,
            RunLength::ThisRun,
            format!(
                "as long as this run ({:.1} s)",
                session.commands().len().min(MAX_STEPS as usize) as f64 * dt
            ),
        )
        .on_hover_text("Replays this run's commands (a drive by hand too) with each run's noise");
    });
    if lap.is_none() && state.length == RunLength::OneLap {
        state.length = RunLength::ThisRun;
    }
    ui.horizontal(|ui| {
        let label = format!("Run {} runs", state.trials);
        if ui
            .button(label)
            .on_hover_text("The parameters and estimators of the run on the map")
            .clicked()
        {
            state.start(session);
        }
        if state.is_running() && ui.button("Stop").clicked() {
            state.stop();
        }
        if let Some(study) = &state.study {
            let done = study.trials_done();
            let total = study.trials().max(1);
            ui.add(
                egui::ProgressBar::new(done as f32 / total as f32)
                    .desired_width(180.0)
                    .text(format!("{done} of {total} runs")),
            );
        }
    });
    if let Some(message) = &state.message {
        ui.colored_label(palette::VERMILLION, message);
    }
    let Some(study) = &state.study else {
        ui.weak("Press Run: the runs take a few seconds.");
        return;
    };
    // The study keeps the scenario it was started from.
    if params::to_pairs(study.scenario()) != params::to_pairs(&session.scenario_now()) {
        ui.colored_label(
            palette::VERMILLION,
            "These runs used other parameters than the run on the map now; run again for the current ones.",
        );
    }
    if study.trials_done() == 0 {
        ui.weak("The first run is on its way.");
        return;
    }
    let result = study.result();
    average_nees_plot_ui(ui, study, &result);
    summary_ui(ui, &result);
}

fn average_nees_plot_ui(ui: &mut egui::Ui, study: &ConsistencyStudy, result: &ConsistencyResult) {
    let [lo, hi] = result.nees_band;
    let dt = study.scenario().dt;
    let average = study.average_nees();
    let mut key: Vec<KeyEntry> = average
        .iter()
        .map(|(name, _)| {
            KeyEntry::new(
                format!("{} average NEES", name.to_uppercase()),
                palette::estimator_color(name),
                Mark::Solid,
            )
        })
        .collect();
    key.push(KeyEntry::new(
        format!("95% band of a consistent filter's average {lo:.2}..{hi:.2}"),
        palette::GREEN,
        Mark::Dashed,
    ));
    key_ui(ui, &key);
    time_plot("many_runs_nees", "average NEES", 220.0)
        // Fitted to the data and the band every frame: the average settles as runs come in.
        .include_y(0.0)
        .include_y(hi * 1.3)
        .auto_bounds(egui::Vec2b::new(true, true))
        .show(ui, |plot_ui| {
            band_ui(plot_ui, lo, hi);
            for (name, series) in &average {
                let points = thin(
                    series
                        .iter()
                        .enumerate()
                        .filter_map(|(k, v)| v.map(|v| [(k + 1) as f64 * dt, v]))
                        .collect(),
                );
                plot_ui.line(
                    Line::new(
                        format!("{} average NEES", name.to_uppercase()),
                        PlotPoints::new(points),
                    )
                    .color(palette::estimator_color(name))
                    .width(1.8),
                );
            }
        });
}

/// What a filter's numbers say, in words.
pub fn verdict(in_band: f64, above: f64) -> &'static str {
    let below = (1.0 - in_band - above).max(0.0);
    if in_band >= 0.9 {
        "consistent"
    } else if above >= 0.5 {
        "overconfident most of the time"
    } else if above >= 0.15 {
        "overconfident at times"
    } else if below >= 0.15 {
        "too cautious at times"
    } else {
        "about consistent"
    }
}

/// Runs needed before the window gives a verdict: with fewer, the band a
/// consistent filter's average stays in is so wide that an overconfident filter
/// passes (over 6 runs a 3-dof average may lie anywhere in [1.37, 5.25]).
pub const VERDICT_RUNS: usize = 20;

/// The 95% band of the average of `runs` robot-pose NEES values of a consistent
/// filter (3 dof): `runs` times the average is chi-square with 3 `runs` dof.
pub fn average_nees_band(runs: usize) -> [f64; 2] {
    let n = runs.max(1) as f64;
    [
        slamlab_core::stats::chi2_quantile(0.025, 3.0 * n) / n,
        slamlab_core::stats::chi2_quantile(0.975, 3.0 * n) / n,
    ]
}

/// The verdict column: a verdict from [`VERDICT_RUNS`] runs on, before that how many
/// runs are still missing.
pub fn verdict_after(runs: usize, in_band: f64, above: f64) -> String {
    if runs < VERDICT_RUNS {
        format!("too few runs for a verdict ({runs} of {VERDICT_RUNS})")
    } else {
        verdict(in_band, above).to_owned()
    }
}

fn summary_ui(ui: &mut egui::Ui, result: &ConsistencyResult) {
    let [lo, hi] = result.nees_band;
    ui.label(format!(
        "Over {} runs the band is [{lo:.2}, {hi:.2}]; a consistent filter's average stays in it at about 95% of the ticks.",
        result.trials_done
    ));
    if result.trials_done < VERDICT_RUNS {
        let [lo_v, hi_v] = average_nees_band(VERDICT_RUNS);
        ui.label(
            egui::RichText::new(format!(
                "Too few runs for a verdict: the band is still wide. Over {VERDICT_RUNS} runs \
                 it narrows to [{lo_v:.2}, {hi_v:.2}]; the average must stay in that to count \
                 as consistent."
            ))
            .color(ui.visuals().warn_fg_color),
        );
    }
    let fmt = |v: Option<f64>| v.map_or_else(|| "–".to_owned(), |v| format!("{v:.2}"));
    egui::Grid::new("many_runs_summary")
        .num_columns(7)
        .striped(true)
        .show(ui, |ui| {
            for heading in [
                "filter",
                "average NEES",
                "first quarter",
                "last quarter",
                "ticks in band",
                "mean NIS",
                "",
            ] {
                ui.label(egui::RichText::new(heading).strong());
            }
            ui.end_row();
            for f in &result.filters {
                ui.colored_label(palette::estimator_color(&f.name), f.name.to_uppercase());
                ui.label(fmt(f.nees_mean));
                ui.label(fmt(f.nees_first_quarter));
                ui.label(fmt(f.nees_last_quarter));
                ui.label(format!("{:.0}%", 100.0 * f.ticks_in_band));
                ui.label(fmt(f.nis_mean))
                    .on_hover_text("Mean NIS of every landmark update (2 dof: expected 2)");
                let mut text =
                    verdict_after(result.trials_done, f.ticks_in_band, f.ticks_above_band);
                if f.diverged > 0 {
                    text.push_str(&format!(", {} diverged", f.diverged));
                }
                ui.label(text);
                ui.end_row();
            }
        });
    let honest_innovations_overconfident_pose = result.filters.iter().any(|f| {
        f.ticks_above_band >= 0.15 && f.nis_mean.is_some_and(|nis| (nis - 2.0).abs() < 0.1)
    });
    if honest_innovations_overconfident_pose {
        ui.add_space(4.0);
        ui.label(
            "Mean NIS near 2 with the NEES above the band: the innovations look honest, yet \
             the pose is overconfident. The spurious confidence lies where range and bearing \
             cannot look: where the whole map sits and how it is turned.",
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use slamlab_sim::EstimatorKind;

    #[test]
    fn one_lap_of_the_default_circle_is_200_ticks() {
        assert_eq!(lap_ticks(&LandmarkScenario::default()), Some(200));
        let manual = LandmarkScenario {
            controller: ControllerKind::Manual,
            ..Default::default()
        };
        assert_eq!(lap_ticks(&manual), None);
        let slow = LandmarkScenario {
            controller: ControllerKind::Circle { v: 1.0, w: 1e-6 },
            ..Default::default()
        };
        assert_eq!(lap_ticks(&slow), Some(MAX_STEPS));
    }

    #[test]
    fn the_window_runs_the_study_of_the_session_in_slices() {
        let scenario = LandmarkScenario {
            seed: 9,
            estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
            ..Default::default()
        };
        let mut session = LandmarkSession::new(scenario.clone());
        session.run_ticks(30);
        let mut state = ManyRunsState {
            trials: 5,
            length: RunLength::ThisRun,
            ..Default::default()
        };
        state.start(&session);
        assert!(state.is_running());
        let mut frames = 0;
        while state.is_running() {
            state.advance(0);
            frames += 1;
        }
        assert!(
            frames >= 30,
            "a zero budget still runs one tick a frame: {frames} frames"
        );
        // Replaying the circle's commands is the circle: only the label differs.
        let mut direct = ConsistencyStudy::new(scenario, 5, 30);
        direct.run_to_end(|_, _| {});
        let mut expected = direct.result();
        expected
            .parameters
            .insert("controller".into(), "replay of recorded commands".into());
        assert_eq!(state.result(), Some(expected));
    }

    #[test]
    fn one_lap_needs_the_circle_and_a_replay_needs_ticks() {
        let mut state = ManyRunsState::default();
        let manual = LandmarkSession::new(LandmarkScenario {
            controller: ControllerKind::Manual,
            ..Default::default()
        });
        state.start(&manual);
        assert!(state.message.is_some() && state.result().is_none());
        state.length = RunLength::ThisRun;
        state.start(&manual);
        assert!(
            state
                .message
                .as_deref()
                .is_some_and(|m| m.contains("no ticks"))
        );
        let circle = LandmarkSession::new(LandmarkScenario::default());
        state.length = RunLength::OneLap;
        state.start(&circle);
        assert!(state.message.is_none() && state.is_running());
        state.stop();
        assert!(!state.is_running());
    }

    #[test]
    fn no_verdict_before_enough_runs_and_the_band_they_would_need() {
        assert_eq!(
            verdict_after(6, 0.95, 0.0),
            "too few runs for a verdict (6 of 20)"
        );
        assert_eq!(verdict_after(20, 0.95, 0.0), "consistent");
        // The band of a consistent average: chi-square(3n)/n, narrowing with n.
        let [lo6, hi6] = average_nees_band(6);
        assert!(
            (lo6 - 1.372).abs() < 0.01 && (hi6 - 5.254).abs() < 0.01,
            "{lo6} {hi6}"
        );
        let [lo50, hi50] = average_nees_band(50);
        assert!(
            (lo50 - 2.360).abs() < 0.01 && (hi50 - 3.716).abs() < 0.01,
            "{lo50} {hi50}"
        );
    }

    #[test]
    fn verdicts() {
        assert_eq!(verdict(0.97, 0.02), "consistent");
        assert_eq!(verdict(0.34, 0.66), "overconfident most of the time");
        assert_eq!(verdict(0.77, 0.23), "overconfident at times");
        assert_eq!(verdict(0.7, 0.0), "too cautious at times");
        assert_eq!(verdict(0.88, 0.06), "about consistent");
    }
}
