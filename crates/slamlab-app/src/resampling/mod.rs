//! The resampling lab (`lesson=resampling`): one row of weighted particles and
//! the four resamplers of a particle filter side by side (thesis `000` Sec. 2.3,
//! Algorithms 6 and 7; slides `001`). Every resampler is unbiased, so each
//! particle gets `M wᵢ` copies on average; the student presses "resample" once
//! or a thousand times and sees how far each method's copy counts scatter around
//! that mean, which is the noise resampling adds to a filter.
//!
//! The centre shows the weights (drag a bar to change one) and each method's
//! latest copies; the plots show one particle's histogram of copy counts against
//! the binomial law and every particle's copy-count variance against the theory.

mod explain;
mod plots;
mod row;

use crate::lesson::{self, Lesson, LessonFrame, LessonStart, LessonView};
use crate::palette;
use crate::time_control::{TimeAction, TimeControl, TimeInfo};
use crate::widgets::params_panel::{self, PendingParams};
use egui::Color32;
use serde::{Deserialize, Serialize};
use slamlab_core::particle::Resampler;
use slamlab_sim::params;
use slamlab_sim::resampling::session::{LabRun, LabScenario, LabWeights};
use std::convert::Infallible;

/// The lesson's id in URLs and the menu.
pub const LESSON_ID: &str = "resampling";

/// The parameters the panel shows, in order.
/// (The weights have their presets and editor above the table.)
const PANEL_PARAMS: &[&str] = &["particles", "presses", "seed"];

/// A method's colour (Okabe-Ito; multinomial, the naive sampler, in the particle
/// filters' purple).
pub fn method_color(method: Resampler) -> Color32 {
    match method {
        Resampler::Multinomial => palette::PURPLE,
        Resampler::LowVariance => palette::BLUE,
        Resampler::Stratified => palette::GREEN,
        Resampler::Residual => palette::ORANGE,
    }
}

/// What the lab shows; saved with the user's settings.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LabView {}

/// The resampling lab.
#[derive(Debug)]
pub struct ResamplingLesson {
    run: LabRun,
    pending: PendingParams<LabScenario>,
    /// The clock, the view, the map view, the notices and the requests.
    pub frame: LessonFrame<LabView>,
    /// The weight editor's text.
    weights_text: String,
}

impl LessonView for LabView {}

/// Opens the lab from the URL's pairs, with what it stored last time.
pub fn open(start: &LessonStart<'_>) -> Box<dyn Lesson> {
    let new = |scenario| Ok::<_, Infallible>(ResamplingLesson::new(scenario));
    let Ok(lesson) = lesson::open_lesson(start, LabScenario::default(), new, |l| &mut l.frame);
    Box::new(lesson)
}

impl ResamplingLesson {
    /// The lab on `scenario`.
    pub fn new(scenario: LabScenario) -> Self {
        let run = LabRun::new(scenario);
        let mut time = TimeControl::default();
        // Ten resamplings a second while running: each one visible.
        time.speed_tps = 10.0;
        let mut lesson = Self {
            pending: PendingParams::new(run.scenario().clone()),
            run,
            frame: LessonFrame::new(LESSON_ID, LabView::default()).with_time(time),
            weights_text: String::new(),
        };
        lesson.sync_editor();
        lesson
    }

    /// The lab and its presses.
    pub fn run(&self) -> &LabRun {
        &self.run
    }

    /// Resamples `times` times with every method.
    pub fn press(&mut self, times: usize) {
        self.run.press(times);
    }

    /// Sets a parameter from text, as the panel does, and applies it.
    pub fn set_param(&mut self, name: &str, value: &str) -> Option<params::ParamIssue> {
        let issue = self.pending.set(name, value);
        self.apply_pending();
        issue
    }

    /// Runs the panel's parameters: the lab starts over unless only what is shown
    /// changed.
    fn apply_pending(&mut self) {
        if self.run.reconfigure(self.pending.scenario.clone()) {
            self.frame.time.apply(TimeAction::Reset);
        }
        self.sync_editor();
    }

    /// The editor shows the lab's weights.
    fn sync_editor(&mut self) {
        self.weights_text = match &self.run.scenario().weights {
            LabWeights::Custom(list) => list
                .iter()
                .map(|w| w.to_string())
                .collect::<Vec<_>>()
                .join(", "),
            LabWeights::Preset(_) => self
                .run
                .lab()
                .weights()
                .iter()
                .map(|w| format!("{w:.4}"))
                .collect::<Vec<_>>()
                .join(", "),
        };
    }

    /// Reads the weight editor's text; a list that cannot be read is refused with
    /// a note and the lab keeps its weights (and the text stays for fixing).
    fn apply_editor(&mut self) {
        let text = self.weights_text.replace(';', ",");
        match self.pending.set("weights", &text) {
            Some(issue) => self.frame.note = Some(format!("Weights not changed: {issue}")),
            None => {
                self.apply_pending();
                self.frame.note = self.run.note().map(|n| format!("Weights checked: {n}"));
            }
        }
    }

    /// Gives particle `i` the normalized weight `weight` (from a drag on its bar);
    /// the others share the rest in their old proportions.
    pub fn set_weight(&mut self, i: usize, weight: f64) {
        let mut weights = self.run.lab().weights().to_vec();
        let m = weights.len();
        let Some(&old) = weights.get(i) else {
            return;
        };
        let weight = if weight.is_finite() {
            weight.clamp(0.0, 1.0)
        } else {
            old
        };
        let rest = 1.0 - old;
        for (j, w) in weights.iter_mut().enumerate() {
            *w = if j == i {
                weight
            } else if rest > 1e-12 {
                *w * (1.0 - weight) / rest
            } else {
                (1.0 - weight) / (m - 1).max(1) as f64
            };
        }
        self.pending.scenario.weights = LabWeights::Custom(weights);
        self.apply_pending();
        self.frame.note = self.run.note().map(|n| format!("Weights checked: {n}"));
    }

    /// Plots particle `i`'s histogram.
    pub fn set_focus(&mut self, i: usize) {
        self.pending.scenario.focus = Some(i);
        self.apply_pending();
    }

    fn lab_parameters_ui(&mut self, ui: &mut egui::Ui) {
        ui.heading("Resampling lab");
        ui.label(
            "Each resampling draws M particles from the row, particle i with probability w_i. \
             Press, watch the copies, compare the methods.",
        );
        ui.horizontal_wrapped(|ui| {
            if ui
                .button("Resample once")
                .on_hover_text("Every method draws M particles once (shortcut: . or N)")
                .clicked()
            {
                self.apply_time_action(TimeAction::StepTick);
            }
            let times = self.run.scenario().presses;
            if ui
                .button(format!("Resample ×{times}"))
                .on_hover_text("Every method resamples this many times; the statistics gather")
                .clicked()
            {
                self.frame.time.apply(TimeAction::StepTick);
                self.press(times);
            }
            if ui
                .add_enabled(self.run.press_count() > 0, egui::Button::new("Clear"))
                .on_hover_text("Forget every resampling (same weights, same seed)")
                .clicked()
            {
                self.apply_time_action(TimeAction::Reset);
            }
        });
        ui.separator();
        ui.label(egui::RichText::new("Weight presets").strong());
        ui.horizontal_wrapped(|ui| {
            for preset in slamlab_core::particle::WeightPreset::ALL {
                let chosen = self.run.scenario().weights == LabWeights::Preset(preset);
                if ui.selectable_label(chosen, preset.name()).clicked() {
                    self.set_param("weights", preset.name());
                    self.frame.note = None;
                }
            }
        });
        let label = ui
            .label(egui::RichText::new("Weights (edit, then Enter)").strong())
            .on_hover_text(
                "Any non-negative numbers, separated by commas; they are normalized. \
                 Negative and NaN entries become 0; all zeros become uniform.",
            );
        let response = ui
            .add(
                egui::TextEdit::multiline(&mut self.weights_text)
                    .desired_rows(3)
                    .desired_width(f32::INFINITY),
            )
            .labelled_by(label.id);
        let enter = response.has_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        if response.lost_focus() || enter {
            let current = self.run.lab().weights().to_vec();
            let typed: Vec<f64> = self
                .weights_text
                .replace(';', ",")
                .split(',')
                .filter_map(|t| t.trim().parse().ok())
                .collect();
            // Only a real edit starts the lab over (focus leaving the box is not one).
            if typed.len() != current.len()
                || typed
                    .iter()
                    .zip(&current)
                    .any(|(a, b)| (a - b).abs() > 5e-5)
                || self
                    .weights_text
                    .split(',')
                    .any(|t| t.trim().parse::<f64>().is_err())
            {
                self.apply_editor();
            }
        }
        ui.separator();
        ui.label(egui::RichText::new("Methods").strong());
        ui.horizontal_wrapped(|ui| {
            for method in Resampler::ALL {
                let mut on = self.run.scenario().methods.contains(&method);
                let text = egui::RichText::new(method.name()).color(method_color(method));
                if ui.checkbox(&mut on, text).changed() {
                    let mut methods: Vec<Resampler> = Resampler::ALL
                        .into_iter()
                        .filter(|m| {
                            if *m == method {
                                on
                            } else {
                                self.run.scenario().methods.contains(m)
                            }
                        })
                        .collect();
                    if methods.is_empty() {
                        methods.push(method);
                        self.frame.note = Some("At least one method stays on".to_owned());
                    }
                    self.pending.scenario.methods = methods;
                    self.apply_pending();
                }
            }
        });
        ui.separator();
        let running = self.run.scenario().clone();
        // A typed list has its own length: no particle count to set.
        let names: Vec<&str> = PANEL_PARAMS
            .iter()
            .copied()
            .filter(|n| *n != "particles" || matches!(running.weights, LabWeights::Preset(_)))
            .collect();
        if params_panel::params_ui(ui, &mut self.pending, &running, &names) {
            self.apply_pending();
        }
        ui.separator();
        crate::widgets::share::share_ui(
            ui,
            |embed| Lesson::share_query(self, embed),
            "index.html?… with these pairs opens this lab; presses are not in it",
            None,
        );
    }
}

impl crate::widgets::layout::LessonPanels for ResamplingLesson {
    fn plots_ui(&mut self, ui: &mut egui::Ui) {
        plots::plots_ui(ui, &self.run);
    }

    fn parameters_ui(&mut self, ui: &mut egui::Ui) {
        self.lab_parameters_ui(ui);
    }

    fn explanation_ui(&mut self, ui: &mut egui::Ui) {
        explain::explanation_ui(ui, &self.run);
    }

    fn map_ui(&mut self, ui: &mut egui::Ui) {
        match row::row_ui(ui, &self.run) {
            Some(row::RowRequest::SetWeight(i, w)) => self.set_weight(i, w),
            Some(row::RowRequest::Focus(i)) => self.set_focus(i),
            None => {}
        }
    }
}

impl Lesson for ResamplingLesson {
    crate::lesson::frame_accessors!();

    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        plots::series(&self.run)
    }

    fn subtitle(&self) -> String {
        let names: Vec<&str> = self
            .run
            .scenario()
            .methods
            .iter()
            .map(|m| m.name())
            .collect();
        format!("{} particles: {}", self.run.particles(), names.join(", "))
    }

    fn time_info(&self) -> TimeInfo {
        TimeInfo {
            tick: self.run.press_count() as u64,
            // A press is not a moment in time.
            time_s: f64::NAN,
            last_phase: self.run.last_press().map(|times| {
                if times == 1 {
                    "resample once".to_owned()
                } else {
                    format!("resample ×{times}")
                }
            }),
            next_phase: "resample once".to_owned(),
            can_step_back: self.run.press_count() > 0,
        }
    }

    fn on_time_action(&mut self, action: TimeAction) {
        match action {
            TimeAction::ToggleRun => {}
            TimeAction::StepPhase | TimeAction::StepTick => self.press(1),
            TimeAction::StepBack => {
                self.run.undo();
            }
            TimeAction::Reset => {
                self.run = LabRun::new(self.run.scenario().clone());
            }
        }
    }

    fn advance(&mut self, dt: f64) {
        let run = &mut self.run;
        lesson::advance_within_budget(&mut self.frame.time, dt, || {
            run.press(1);
            true
        });
    }

    fn changed_params(&self) -> Vec<(String, String)> {
        params::changed_pairs(self.run.scenario(), &LabScenario::default())
    }

    fn share_pairs(&self) -> Vec<(String, String)> {
        lesson::with_seed(self.changed_params(), self.run.scenario().seed)
    }

    fn test_state(&self) -> serde_json::Value {
        let lab = self.run.lab();
        let methods: Vec<serde_json::Value> = self
            .run
            .scenario()
            .methods
            .iter()
            .map(|&m| {
                let stats = lab.stats(m);
                serde_json::json!({
                    "name": m.name(),
                    "last_copies": lab.last_copies(m),
                    "mean_variance": stats.map(|s| s.mean_variance()),
                    "max_bias": stats.map(|s| s.max_bias(lab.weights())),
                })
            })
            .collect();
        serde_json::json!({
            "tick": self.run.press_count(),
            "resamplings": self.run.resamplings(),
            "seed": self.run.scenario().seed,
            "particles": self.run.particles(),
            "weights": lab.weights(),
            "focus": self.run.focus(),
            "note": self.run.note(),
            "methods": methods,
        })
    }
}
