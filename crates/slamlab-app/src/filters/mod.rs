//! The filters lesson (`lesson=filters`): the estimators before any SLAM
//! (Xiang's thesis ch. 2; Wu's thesis ch. 2).
//!
//! Two views share the lesson:
//! - **One step**: a prior Gaussian the student drags, pushed through a nonlinear
//!   function by the EKF (linearization), the UKF (sigma points) and particles,
//!   against 100,000 samples drawn as a density image, with a table of how far
//!   each Gaussian is from the samples' moments;
//! - **Corridor**: a histogram Bayes filter and a Kalman filter on the same
//!   robot, motions and door sightings, stepped with the time bar (predict,
//!   update, step back), with the Kalman gain's plot.
//!
//! Only the corridor has time. The time bar acts on what is shown: Run, a step
//! or a step key pressed while the One step view is on screen opens the Corridor
//! view and acts there, and leaving the Corridor view pauses the run, so the
//! corridor never moves unseen. A link's `tick=` and `run=` are applied before
//! the first frame: `tick=` steps the corridor and keeps the view the link names
//! (so that a shared link reopens as shared), `run=1` shows the corridor it runs.

mod corridor;
mod explain;
mod marginal;
mod one_step;

use crate::lesson::{self, Lesson, LessonFrame, LessonStart, LessonView, StoredSettings};
use crate::palette;
use crate::time_control::{TimeAction, TimeControl, TimeInfo};
use crate::widgets::map_canvas::MapView;
use crate::widgets::params_panel::{self, PendingParams};
use serde::{Deserialize, Serialize};
use slamlab_sim::filters::session::{
    CorridorSim, Draws, FUNCTION_NAMES, FiltersScenario, FunctionKind, OneStep, one_step_with,
};
use slamlab_sim::params;
use slamlab_sim::stepper::Stepper;

/// The lesson's id in URLs and the menu.
pub const LESSON_ID: &str = "filters";

/// Which view the centre shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Tab {
    /// The one-step comparison.
    #[default]
    OneStep,
    /// The corridor.
    Corridor,
}

/// What the lesson shows; saved with the user's settings.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FiltersView {
    /// The view in the centre.
    pub tab: Tab,
    /// A narrow window's bottom panel: the error table instead of the marginal plot.
    pub table: bool,
}

impl LessonView for FiltersView {}

/// The parameters of the one-step view's panel.
const ONE_STEP_PARAMS: &[&str] = &[
    "coefficient",
    "dt",
    "mean-1",
    "mean-2",
    "std-1",
    "std-2",
    "rho",
    "alpha",
    "beta",
    "kappa",
    "samples",
    "particles",
    "seed",
];

/// The parameters of the corridor view's panel.
const CORRIDOR_PARAMS: &[&str] = &[
    "step",
    "motion-std",
    "measurement-std",
    "p-hit",
    "p-false",
    "start",
    "cell",
    "seed",
];

/// The filters lesson.
#[derive(Debug)]
pub struct FiltersLesson {
    scenario: FiltersScenario,
    pending: PendingParams<FiltersScenario>,
    /// The last valid one-step comparison.
    result: Option<OneStep>,
    /// The samples' and particles' standard normal draws, kept while the prior moves.
    draws: Draws,
    /// The clock, the view, the map view, the notices and the requests.
    pub frame: LessonFrame<FiltersView>,
    corridor: Stepper<CorridorSim>,
    input_view: MapView,
    output_view: MapView,
    density: one_step::Density,
    density_stale: bool,
    /// The prior's handles: which is held, where they were drawn.
    drag: one_step::DragState,
    /// The samples' histogram of the first output and its range.
    marginal: (Vec<[f64; 2]>, [f64; 2]),
    /// How long the last one-step computation took, milliseconds.
    last_compute_ms: f64,
    /// One-step computations so far (a frame whose prior did not change runs none).
    computations: u64,
    /// Was the One step view drawn in the last frame (the student sees it)?
    one_step_on_screen: bool,
    /// Did the prior move during the drag under way? Its release refits the output.
    moved_by_drag: bool,
}

/// Opens the lesson from the URL's pairs, with what it stored last time.
pub fn open(start: &LessonStart<'_>) -> Box<dyn Lesson> {
    let stored = StoredSettings::<FiltersView>::from_start(start);
    // `view=` chooses the tab; it is not a scenario parameter.
    let pairs: Vec<(String, String)> = start
        .pairs
        .iter()
        .filter(|(k, _)| k != "view")
        .cloned()
        .collect();
    let scenario_start = LessonStart {
        pairs: &pairs,
        ..*start
    };
    let (scenario, notices) = lesson::scenario_from_start(
        &scenario_start,
        FiltersScenario::default(),
        stored.as_ref().map(|s| s.params.as_slice()),
    );
    let mut lesson = FiltersLesson::new(scenario);
    lesson.frame.notices.extend(notices);
    lesson.frame = lesson.frame.restored(stored.as_ref());
    if let Some((_, v)) = start.pairs.iter().find(|(k, _)| k == "view") {
        match v.as_str() {
            "corridor" => lesson.frame.view.tab = Tab::Corridor,
            "one-step" => lesson.frame.view.tab = Tab::OneStep,
            other => lesson.frame.notices.push(format!(
                "link: view={other} is not a view (one-step or corridor); showing one-step"
            )),
        }
    }
    Box::new(lesson)
}

impl FiltersLesson {
    /// The lesson on `scenario`.
    pub fn new(scenario: FiltersScenario) -> Self {
        let mut time = TimeControl::default();
        time.speed_tps = 2.0;
        let mut lesson = Self {
            pending: PendingParams::new(scenario.clone()),
            corridor: Stepper::new(CorridorSim::new(scenario.clone()), ()),
            scenario,
            result: None,
            draws: Draws::default(),
            frame: LessonFrame::new(LESSON_ID, FiltersView::default()).with_time(time),
            input_view: MapView::default(),
            output_view: MapView::default(),
            density: one_step::Density::default(),
            density_stale: true,
            drag: one_step::DragState::default(),
            marginal: (Vec::new(), [0.0, 1.0]),
            last_compute_ms: 0.0,
            computations: 0,
            one_step_on_screen: false,
            moved_by_drag: false,
        };
        lesson.recompute();
        if lesson.result.is_none() {
            // A link with a bad belief: say why, and show the function's own prior.
            let mut fallback = lesson.scenario.clone();
            (fallback.mean, fallback.std, fallback.rho) = fallback.function.default_prior();
            fallback.particles = fallback.particles.max(2);
            fallback.alpha = 1.0;
            fallback.kappa = 0.0;
            let why = lesson.frame.note.clone();
            lesson.scenario = fallback;
            lesson.pending = PendingParams::new(lesson.scenario.clone());
            lesson.recompute();
            if let Some(why) = why {
                lesson
                    .frame
                    .notices
                    .push(format!("{why}; showing the function's default prior"));
            }
        }
        lesson
    }

    /// The last valid one-step comparison.
    pub fn result(&self) -> Option<&OneStep> {
        self.result.as_ref()
    }

    /// The running scenario.
    pub fn scenario(&self) -> &FiltersScenario {
        &self.scenario
    }

    /// Why the latest change was refused.
    pub fn note(&self) -> Option<&str> {
        self.frame.note.as_deref()
    }

    /// Where the prior's handles were drawn in the last frame (mean, first and
    /// second covariance handle), screen points; `None` off the one-step view.
    pub fn handles_on_screen(&self) -> Option<[egui::Pos2; 3]> {
        self.drag.on_screen
    }

    /// The output canvas's zoom, pixels per unit (for the tests of its Reset view).
    pub fn output_scale(&self) -> f32 {
        self.output_view.scale()
    }

    /// Where the output canvas looks (for the tests of its refit after a drag).
    pub fn output_view(&self) -> &MapView {
        &self.output_view
    }

    /// The view in the centre.
    pub fn tab(&self) -> Tab {
        self.frame.view.tab
    }

    /// The corridor run.
    pub fn corridor(&self) -> &CorridorSim {
        self.corridor.sim()
    }

    /// Shows a view (leaving the Corridor view pauses its run).
    pub fn set_tab(&mut self, tab: Tab) {
        self.frame.view.tab = tab;
        self.pause_unless_corridor();
    }

    /// The corridor runs only where it is seen: any other view pauses it.
    fn pause_unless_corridor(&mut self) {
        if self.frame.view.tab != Tab::Corridor {
            self.frame.time.running = false;
        }
    }

    /// Sets a parameter from text, as the panel does, and applies it.
    pub fn set_param(&mut self, name: &str, value: &str) -> Option<params::ParamIssue> {
        let issue = self.pending.set(name, value);
        self.apply_pending();
        issue
    }

    /// Runs the one-step comparison on the running scenario; on failure keeps the
    /// last valid result and says why.
    fn recompute(&mut self) {
        let start = web_time::Instant::now();
        match one_step_with(&self.scenario, &mut self.draws) {
            Ok(r) => {
                self.marginal = marginal::histogram(&r);
                self.result = Some(r);
                self.frame.note = None;
                self.density_stale = true;
            }
            Err(e) => self.frame.note = Some(format!("{e}. The last valid belief is kept.")),
        }
        self.last_compute_ms = start.elapsed().as_secs_f64() * 1e3;
        self.computations += 1;
    }

    /// Applies the panel's parameters: a new function refits the views, a changed
    /// corridor parameter replays the corridor to the same step.
    fn apply_pending(&mut self) {
        let new = self.pending.scenario.clone();
        if new == self.scenario && self.frame.note.is_none() && self.result.is_some() {
            // Nothing changed (a held handle that did not move): the result stands.
            return;
        }
        let function_changed = new.function != self.scenario.function;
        let corridor_changed = corridor_part(&new) != corridor_part(&self.scenario);
        let last_valid = std::mem::replace(&mut self.scenario, new);
        self.recompute();
        if self.frame.note.is_some() && self.result.is_some() {
            // Refused: the last valid setting stays (the note says why).
            self.scenario = last_valid;
            self.pending.scenario = self.scenario.clone();
        }
        if function_changed {
            self.input_view.refit();
            self.output_view.refit();
        }
        if corridor_changed {
            let phases = self.corridor.phases_run();
            self.corridor = Stepper::new(CorridorSim::new(self.scenario.clone()), ());
            for _ in 0..phases {
                self.corridor.step_phase();
            }
        }
    }

    /// Moves the prior (from a drag).
    pub fn set_prior(&mut self, mean: [f64; 2], std: [f64; 2], rho: f64) {
        self.pending.scenario.mean = mean;
        self.pending.scenario.std = std;
        self.pending.scenario.rho = rho;
        self.apply_pending();
    }

    fn one_step_map_ui(&mut self, ui: &mut egui::Ui) {
        let f = self.scenario.step_function();
        if self.density_stale
            && let Some(r) = &self.result
        {
            let bounds = if self.output_view_needs_bounds() {
                one_step::output_bounds(r)
            } else {
                self.density.bounds
            };
            let color = palette::truth_color(ui.visuals().dark_mode);
            self.density
                .update(ui.ctx(), &r.truth.points, bounds, color);
            self.density_stale = false;
        }
        let prior = self
            .result
            .as_ref()
            .map_or(self.scenario.prior(), |r| r.prior);
        // Two halves of exactly the room there is (side by side when the area is
        // wide): nothing spills out of a small window. A short half drops the keys
        // to a hover, so that the canvas keeps its room.
        let full = ui.available_rect_before_wrap();
        let horizontal = full.width() > 1.2 * full.height();
        let gap = 8.0;
        let (first, second) = if horizontal {
            let w = 0.5 * (full.width() - gap);
            (
                egui::Rect::from_min_size(full.min, egui::vec2(w, full.height())),
                egui::Rect::from_min_size(
                    full.min + egui::vec2(w + gap, 0.0),
                    egui::vec2(w, full.height()),
                ),
            )
        } else {
            let h = 0.5 * (full.height() - gap);
            (
                egui::Rect::from_min_size(full.min, egui::vec2(full.width(), h)),
                egui::Rect::from_min_size(
                    full.min + egui::vec2(0.0, h + gap),
                    egui::vec2(full.width(), h),
                ),
            )
        };
        let compact = first.height() < 280.0 || first.width() < 330.0;
        let mut change = None;
        let grabbing = self.drag.grab.is_some();
        ui.scope_builder(egui::UiBuilder::new().max_rect(first), |ui| {
            ui.set_clip_rect(first.intersect(ui.clip_rect()));
            change = one_step::input_ui(
                ui,
                &mut self.input_view,
                &prior,
                self.result.as_ref(),
                f.input_axes(),
                &mut self.drag,
                compact,
            );
        });
        ui.scope_builder(egui::UiBuilder::new().max_rect(second), |ui| {
            ui.set_clip_rect(second.intersect(ui.clip_rect()));
            if let Some(r) = &self.result {
                one_step::output_ui(
                    ui,
                    &mut self.output_view,
                    &self.density,
                    r,
                    f.output_axes(),
                    compact,
                );
            }
        });
        if let Some((mean, std, rho)) = change {
            self.moved_by_drag = true;
            self.set_prior(mean, std, rho);
        }
        // The output keeps its view while the prior is dragged (the picture does
        // not jump under the hand); on release it fits what the function made of
        // the new prior, so that no ellipse is left cut at the canvas's edge.
        if grabbing && self.drag.grab.is_none() && std::mem::take(&mut self.moved_by_drag) {
            self.output_view.refit();
            self.density_stale = true;
            ui.ctx().request_repaint();
        }
    }

    /// The density image keeps its bounds while the student drags, so the
    /// picture does not jump; it takes new ones when nothing is grabbed.
    fn output_view_needs_bounds(&self) -> bool {
        self.drag.grab.is_none() || self.density.bounds == [0.0; 4]
    }

    fn parameters_panel_ui(&mut self, ui: &mut egui::Ui) {
        ui.heading("Filters: from Bayes to particles");
        ui.horizontal(|ui| {
            ui.selectable_value(&mut self.frame.view.tab, Tab::OneStep, "One step")
                .on_hover_text("Leaving the Corridor view pauses its run");
            ui.selectable_value(&mut self.frame.view.tab, Tab::Corridor, "Corridor");
        });
        self.pause_unless_corridor();
        ui.separator();
        let names = match self.frame.view.tab {
            Tab::OneStep => {
                let mut chosen = self.scenario.function.name();
                ui.horizontal(|ui| {
                    ui.label("Function");
                    egui::ComboBox::from_id_salt("filters_function")
                        .selected_text(chosen)
                        .show_ui(ui, |ui| {
                            for name in FUNCTION_NAMES {
                                ui.selectable_value(&mut chosen, name, *name);
                            }
                        })
                        .response
                        .on_hover_text(
                            "The nonlinear function; choosing one resets the prior to its own",
                        )
                        .widget_info(|| {
                            egui::WidgetInfo::labeled(egui::Role::ComboBox, true, "function")
                        });
                });
                if chosen != self.scenario.function.name() {
                    self.set_param("function", chosen);
                }
                ui.label(egui::RichText::new(self.scenario.step_function().formula()).monospace());
                let used: Vec<&str> = ONE_STEP_PARAMS
                    .iter()
                    .copied()
                    .filter(|n| match *n {
                        "coefficient" => matches!(
                            self.scenario.function,
                            FunctionKind::Linear | FunctionKind::Quadratic | FunctionKind::Exp
                        ),
                        "dt" => self.scenario.function == FunctionKind::Motion,
                        _ => true,
                    })
                    .collect();
                used
            }
            Tab::Corridor => CORRIDOR_PARAMS.to_vec(),
        };
        let running = self.scenario.clone();
        if params_panel::params_ui(ui, &mut self.pending, &running, &names) {
            self.apply_pending();
        }
        ui.separator();
        crate::widgets::share::share_ui(
            ui,
            |embed| Lesson::share_query(self, embed),
            "index.html?… with these pairs opens this setup",
            None,
        );
    }
}

/// The corridor's parameters (a change replays the corridor).
fn corridor_part(s: &FiltersScenario) -> [f64; 8] {
    [
        s.seed as f64,
        s.step,
        s.motion_std,
        s.start,
        s.p_hit,
        s.p_false,
        s.measurement_std,
        s.cell,
    ]
}

impl crate::widgets::layout::LessonPanels for FiltersLesson {
    fn plots_ui(&mut self, ui: &mut egui::Ui) {
        match self.frame.view.tab {
            Tab::OneStep => {
                let height = ui.available_height();
                let Some(r) = &self.result else {
                    ui.label("No valid belief yet.");
                    return;
                };
                let (histogram, range) = (&self.marginal.0, self.marginal.1);
                let compute_ms = self.last_compute_ms;
                if ui.available_width() >= 900.0 {
                    crate::widgets::plots::columns_ui(ui, 2, |k, ui| {
                        if k == 0 {
                            explain::table_ui(ui, Some(r), compute_ms);
                        } else {
                            marginal::marginal_ui(ui, r, histogram, range, height);
                        }
                    });
                } else {
                    // A narrow window: the plot or the table, one at a time.
                    let top = ui.cursor().top();
                    ui.horizontal(|ui| {
                        ui.selectable_value(&mut self.frame.view.table, false, "Marginal plot");
                        ui.selectable_value(&mut self.frame.view.table, true, "Error table");
                    });
                    let height = height - (ui.cursor().top() - top);
                    if self.frame.view.table {
                        egui::ScrollArea::vertical()
                            .id_salt("filters_table_scroll")
                            .show(ui, |ui| explain::table_ui(ui, Some(r), compute_ms));
                    } else {
                        marginal::marginal_ui(ui, r, histogram, range, height);
                    }
                }
            }
            Tab::Corridor => {
                let h = ui.available_height();
                corridor::gain_ui(ui, self.corridor.sim(), h);
            }
        }
    }

    fn parameters_ui(&mut self, ui: &mut egui::Ui) {
        self.parameters_panel_ui(ui);
    }

    fn explanation_ui(&mut self, ui: &mut egui::Ui) {
        match self.frame.view.tab {
            Tab::OneStep => explain::one_step_ui(ui, self.result.as_ref(), &self.scenario),
            Tab::Corridor => explain::corridor_ui(ui, &self.corridor),
        }
    }

    fn map_ui(&mut self, ui: &mut egui::Ui) {
        self.one_step_on_screen = self.frame.view.tab == Tab::OneStep;
        match self.frame.view.tab {
            Tab::OneStep => self.one_step_map_ui(ui),
            Tab::Corridor => {
                self.drag.on_screen = None;
                corridor::belief_ui(ui, self.corridor.sim());
            }
        }
    }
}

impl Lesson for FiltersLesson {
    crate::lesson::frame_accessors!();

    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        let mut all = corridor::series(self.corridor.sim());
        if let Some(r) = &self.result {
            all.extend(marginal::series(r, &self.marginal.0, self.marginal.1));
        }
        all
    }

    fn subtitle(&self) -> String {
        match self.frame.view.tab {
            Tab::OneStep => format!("one step through {}", self.scenario.function.name()),
            Tab::Corridor => "corridor: histogram vs Kalman".to_owned(),
        }
    }

    fn time_info(&self) -> TimeInfo {
        let sim = self.corridor.sim();
        TimeInfo {
            tick: slamlab_sim::stepper::Simulation::tick(sim),
            time_s: f64::NAN,
            last_phase: self
                .corridor
                .last_phase()
                .map(|p| format!("corridor {}", p.name())),
            // The One step view has no time: the bar says where its steps act.
            next_phase: match self.frame.view.tab {
                Tab::Corridor => format!("corridor {}", sim.next_phase().name()),
                Tab::OneStep => format!(
                    "corridor {} (Run and the steps open the Corridor view)",
                    sim.next_phase().name()
                ),
            },
            can_step_back: self.corridor.phases_run() > 0,
        }
    }

    fn on_time_action(&mut self, action: TimeAction) {
        // What the student asks while looking at the One step view acts on the
        // corridor, so the corridor is shown. A link's `tick=` comes before the
        // first frame and keeps the link's view.
        if self.one_step_on_screen && self.frame.view.tab == Tab::OneStep {
            self.frame.view.tab = Tab::Corridor;
        }
        match action {
            TimeAction::ToggleRun => {}
            TimeAction::StepPhase => {
                self.corridor.step_phase();
            }
            TimeAction::StepTick => self.corridor.step_tick(),
            TimeAction::StepBack => {
                self.corridor.step_back();
            }
            TimeAction::Reset => {
                self.corridor = Stepper::new(CorridorSim::new(self.scenario.clone()), ());
            }
        }
    }

    fn advance(&mut self, dt: f64) {
        // A running clock shows what it runs (a link's `run=1` on the One step
        // view): the student leaving the Corridor view has paused it.
        if self.frame.time.running {
            self.frame.view.tab = Tab::Corridor;
        }
        let corridor = &mut self.corridor;
        lesson::advance_within_budget(&mut self.frame.time, dt, || {
            corridor.step_phase();
            !slamlab_sim::stepper::Simulation::is_mid_tick(corridor.sim())
        });
    }

    fn changed_params(&self) -> Vec<(String, String)> {
        params::changed_pairs(&self.scenario, &FiltersScenario::default())
    }

    fn share_pairs(&self) -> Vec<(String, String)> {
        let mut pairs = lesson::with_seed(self.changed_params(), self.scenario.seed);
        if self.frame.view.tab == Tab::Corridor {
            pairs.push(("view".to_owned(), "corridor".to_owned()));
        }
        pairs
    }

    fn test_state(&self) -> serde_json::Value {
        let sim = self.corridor.sim();
        let rows: Vec<serde_json::Value> = self
            .result
            .iter()
            .flat_map(|r| r.rows.iter())
            .map(|row| {
                serde_json::json!({
                    "method": row.method,
                    "mean": [row.gaussian.mean[0], row.gaussian.mean[1]],
                    "mean_error": row.comparison.mean_error,
                    "covariance_error": row.comparison.covariance_error,
                    "kl_divergence": row.comparison.kl_divergence,
                })
            })
            .collect();
        serde_json::json!({
            "tick": slamlab_sim::stepper::Simulation::tick(sim),
            "seed": self.scenario.seed,
            "view": match self.frame.view.tab { Tab::OneStep => "one-step", Tab::Corridor => "corridor" },
            "function": self.scenario.function.name(),
            "note": self.frame.note,
            "samples_mean": self.result.as_ref().map(|r| [r.truth.moments.mean[0], r.truth.moments.mean[1]]),
            "samples": self.result.as_ref().map(|r| r.truth.points.len()),
            "prior": {
                "mean": self.scenario.mean,
                "std": self.scenario.std,
                "rho": self.scenario.rho,
            },
            "handles_px": self.drag.on_screen.map(|h| h.map(|p| [p.x, p.y])),
            "jacobian": self.result.as_ref().map(|r| {
                let j = r.ekf.jacobian;
                [[j[(0, 0)], j[(0, 1)]], [j[(1, 0)], j[(1, 1)]]]
            }),
            "ukf_weights": self.result.as_ref().map(|r| {
                let w = r.ukf.weights;
                serde_json::json!({ "lambda": w.lambda, "mean0": w.mean0, "cov0": w.cov0, "other": w.other })
            }),
            "density_inside": self.density.inside,
            "compute_ms": self.last_compute_ms,
            "computations": self.computations,
            "results": rows,
            "corridor": {
                "histogram_mean": sim.histogram().mean(),
                "histogram_mode": sim.histogram().mode(),
                "kalman_mean": sim.kalman().mean,
                "kalman_variance": sim.kalman().variance,
                "gain": sim.last_update().map(|(u, _)| u.gain),
                "gain_tick": sim.last_update().map(|_| sim.last_update_tick()),
            },
        })
    }
}
