//! The pose-graph lesson (`lesson=pose-graph`): a graph of robot poses (and
//! landmarks) joined by odometry edges, loop closures and landmark edges, optimized
//! one solver iteration at a time (Gauss-Newton, Levenberg-Marquardt or a
//! first-order method) while the path snaps into place. The student drags vertices,
//! adds a deliberately wrong loop closure and compares robust kernels, and opens
//! g2o or TORO files (M3500, intel) by the picker or by dropping them on the window.

mod explain;
mod map;
mod plots;
pub mod solutions;

use crate::lesson::{self, Lesson, LessonFrame, LessonStart};
use crate::time_control::{FRAME_BUDGET_MS, StepControls, TimeAction, TimeControl, TimeInfo};
use crate::widgets::dropped_files::DropInbox;
use crate::widgets::file_picker::FilePicker;
use crate::widgets::map_canvas::MapView;
use crate::widgets::params_panel::{self, PendingParams};
use serde::{Deserialize, Serialize};
use slamlab_core::graph::SolverKind;
use slamlab_sim::params;
use slamlab_sim::pose_graph::session::{
    EdgeRole, KernelRun, MAX_FILE_BYTES, PoseGraphScenario, PoseGraphSession, kernel_name,
    solver_label,
};

/// The lesson's id in URLs and the menu.
pub const LESSON_ID: &str = "pose-graph";

/// The parameters the panel shows, in order.
const PANEL_PARAMS: &[&str] = &[
    "example",
    "seed",
    "solver",
    "kernel",
    "kernel-width",
    "loop-closures",
    "noise-scale",
    "manhattan-poses",
    "manhattan-side",
    "max-iterations",
];

/// Parameters that apply at once to the running graph (the rest on "Apply & reset").
const LIVE_PARAMS: &[&str] = &["solver", "kernel", "kernel-width", "max-iterations"];

/// Vertices whose marginal covariance is drawn at most: every k-th vertex of a
/// large graph, few enough that the ellipses far from the fixed vertex (which
/// grow to tens of metres on M3500) do not hide the graph.
pub(crate) const MAX_ELLIPSES: usize = 60;

/// What the map shows; saved with the user's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PoseGraphView {
    /// The legend box.
    pub legend: bool,
    /// The true path (built-in examples).
    pub truth: bool,
    /// 95% ellipses from the marginals once converged.
    pub ellipses: bool,
    /// Optimize at once after a vertex is dropped.
    pub reoptimize_after_drag: bool,
}

crate::lesson::lesson_view!(PoseGraphView, legend: legend);

impl Default for PoseGraphView {
    fn default() -> Self {
        Self {
            legend: true,
            truth: true,
            ellipses: true,
            reoptimize_after_drag: true,
        }
    }
}

/// How long the latest "Optimize" took (to convergence or the iteration limit).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct OptimizeTiming {
    /// From the press (or from the file's bytes, reading and analysing included) to
    /// the last iteration, milliseconds, including the frames drawn in between.
    pub wall_ms: f64,
    /// Time spent in the solver's iterations alone, milliseconds.
    pub compute_ms: f64,
    /// Iterations run.
    pub iterations: usize,
    /// Did it converge (rather than stop at the limit or on an error)?
    pub converged: bool,
}

#[derive(Clone, Copy, Debug)]
struct OptimizeRun {
    started: web_time::Instant,
    compute_ms: f64,
    iterations: usize,
}

/// The sparsity images and their counts, rebuilt when the graph's structure changes.
#[derive(Default)]
pub(crate) struct Patterns {
    pub(crate) h: Option<egui::TextureHandle>,
    pub(crate) l: Option<egui::TextureHandle>,
    pub(crate) unknowns: usize,
    /// Vertices of the graph (blocks of H per side).
    pub(crate) vertices: usize,
    pub(crate) h_blocks: usize,
    pub(crate) l_blocks: usize,
    pub(crate) fill_blocks: usize,
    pub(crate) l_nonzeros: usize,
    pub(crate) error: Option<String>,
    pub(crate) dirty: bool,
    pub(crate) dark: bool,
}

impl std::fmt::Debug for Patterns {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Patterns")
            .field("unknowns", &self.unknowns)
            .field("fill_blocks", &self.fill_blocks)
            .finish_non_exhaustive()
    }
}

/// The lesson's start: the simulator's defaults.
pub fn default_scenario() -> PoseGraphScenario {
    PoseGraphScenario::default()
}

/// The pose-graph lesson.
#[derive(Debug)]
pub struct PoseGraphLesson {
    session: PoseGraphSession,
    pending: PendingParams<PoseGraphScenario>,
    /// A file the student opened (name, bytes); "Apply & reset" reopens it.
    loaded: Option<(String, Vec<u8>)>,
    /// The clock, the view, the map view, the notices and the requests.
    pub frame: LessonFrame<PoseGraphView>,
    drag: Option<usize>,
    last_transform: Option<crate::widgets::map_canvas::MapTransform>,
    optimizing: Option<OptimizeRun>,
    last_optimize: Option<OptimizeTiming>,
    pub(crate) patterns: Patterns,
    marginals: Option<Vec<(usize, nalgebra::Matrix2<f64>)>>,
    comparison: Option<[KernelRun; 2]>,
    inbox: DropInbox,
    picker: FilePicker,
    /// Students' optimized graphs of the problem on screen.
    solutions: solutions::Solutions,
}

/// Opens the lesson from the URL's pairs, with what it stored last time.
pub fn open(start: &LessonStart<'_>) -> Box<dyn Lesson> {
    // The defaults are tested; a scenario they refuse falls back to them.
    let new = |scenario| -> Result<PoseGraphLesson, String> {
        PoseGraphLesson::new(scenario).or_else(|why| {
            let mut lesson = PoseGraphLesson::new(default_scenario())?;
            lesson.frame.notices.push(format!(
                "the link's graph could not be built ({why}); showing the default"
            ));
            Ok(lesson)
        })
    };
    let opened = lesson::open_lesson(start, default_scenario(), new, |l| &mut l.frame);
    let mut lesson = match opened {
        Ok(lesson) => lesson,
        Err(again) => {
            return lesson::open_instead(
                start,
                format!("The pose-graph lesson could not open: {again}"),
            );
        }
    };
    if start.embed {
        lesson.frame.view.legend = false;
    }
    Box::new(lesson)
}

impl PoseGraphLesson {
    /// Starts the lesson on the scenario's built-in graph.
    pub fn new(scenario: PoseGraphScenario) -> Result<Self, String> {
        let session = PoseGraphSession::from_scenario(scenario)?;
        let pending = PendingParams::new(session.scenario().clone());
        let mut time = TimeControl::default();
        time.speed_tps = 2.0;
        Ok(Self {
            session,
            pending,
            loaded: None,
            frame: LessonFrame::new(LESSON_ID, PoseGraphView::default())
                .with_map(MapView::default())
                .with_time(time),
            drag: None,
            last_transform: None,
            optimizing: None,
            last_optimize: None,
            patterns: Patterns {
                dirty: true,
                ..Patterns::default()
            },
            marginals: None,
            comparison: None,
            inbox: DropInbox::default(),
            picker: FilePicker::default(),
            solutions: solutions::Solutions::default(),
        })
    }

    /// The running session.
    pub fn session(&self) -> &PoseGraphSession {
        &self.session
    }

    /// The scenario being edited in the parameter panel.
    pub fn pending(&self) -> &PoseGraphScenario {
        &self.pending.scenario
    }

    /// The latest refusal or load result.
    pub fn note(&self) -> Option<&str> {
        self.frame.note.as_deref()
    }

    /// How long the latest "Optimize" took.
    pub fn last_optimize(&self) -> Option<OptimizeTiming> {
        self.last_optimize
    }

    /// Is an "Optimize" under way?
    pub fn is_optimizing(&self) -> bool {
        self.optimizing.is_some()
    }

    /// The kernel comparison, once run.
    pub fn comparison(&self) -> Option<&[KernelRun; 2]> {
        self.comparison.as_ref()
    }

    /// Sets a parameter of the pending scenario from text, as the panel does; the
    /// solver and the kernel apply to the running graph at once.
    pub fn set_param(&mut self, name: &str, value: &str) -> Option<params::ParamIssue> {
        let issue = self.pending.set(name, value);
        self.apply_live_params();
        issue
    }

    fn apply_live_params(&mut self) {
        let p = self.pending.scenario.clone();
        if p.solver != self.session.scenario().solver {
            self.session.set_solver(p.solver);
            self.after_edit();
        }
        let s = self.session.scenario();
        if p.kernel != s.kernel || p.kernel_width != s.kernel_width {
            match self.session.set_kernel(p.kernel, p.kernel_width) {
                Ok(()) => self.after_edit(),
                Err(why) => self.frame.note = Some(why),
            }
        }
    }

    fn after_edit(&mut self) {
        self.marginals = None;
        self.frame.time.running = false;
    }

    fn install(&mut self, session: PoseGraphSession) {
        self.session = session;
        self.pending = PendingParams::new(self.session.scenario().clone());
        self.frame.time.apply(TimeAction::Reset);
        self.optimizing = None;
        self.last_optimize = None;
        self.patterns.dirty = true;
        self.marginals = None;
        self.comparison = None;
        self.drag = None;
        self.solutions.rescore();
        self.frame.map.refit();
    }

    /// Starts over with the pending parameters (and the opened file, if any). On a
    /// problem the current graph stays, with a note.
    pub fn reset(&mut self) {
        let scenario = self.pending.scenario.clone();
        let opened = match &self.loaded {
            Some((name, bytes)) => PoseGraphSession::from_file(scenario, name, bytes),
            None => PoseGraphSession::from_scenario(scenario),
        };
        match opened {
            Ok(session) => {
                self.install(session);
                self.frame.note = None;
            }
            Err(why) => {
                self.frame.note = Some(format!("Could not start over: {why}; the graph stays"))
            }
        }
    }

    /// Opens a built-in example (forgetting an opened file).
    pub fn open_example(&mut self) {
        self.loaded = None;
        self.reset();
    }

    /// Students' optimized graphs of the problem on screen.
    pub fn solutions(&self) -> &solutions::Solutions {
        &self.solutions
    }

    /// Students' optimized graphs, to show, hide or remove them.
    pub fn solutions_mut(&mut self) -> &mut solutions::Solutions {
        &mut self.solutions
    }

    /// A graph file dropped or opened: a student's solution when its vertices
    /// and edges are the graph on screen's (scored in "Your solutions"),
    /// otherwise a new problem (opened and optimized, as before). The note says
    /// which it did and why.
    pub fn open_graph_file(&mut self, name: &str, bytes: Vec<u8>) {
        let parsed = std::str::from_utf8(&bytes)
            .ok()
            .filter(|_| bytes.len() <= MAX_FILE_BYTES)
            .and_then(|text| slamlab_sim::io::graph::read_graph(text).ok());
        let why_not = match parsed {
            Some(file) => match self.solutions.try_add(&self.session, name, &file) {
                Ok(said) => {
                    self.frame.note = Some(said);
                    return;
                }
                Err(why) => why,
            },
            // Unreadable: opening it says why, with its line.
            None => String::new(),
        };
        let was = self.session.source().to_owned();
        self.load_file(name, bytes);
        if self.session.source() == name && !why_not.is_empty() {
            let dropped = self.solutions.clear();
            let note = self.frame.note.take().unwrap_or_default();
            self.frame.note = Some(format!(
                "{note}. Opened as a new problem, not scored as a solution of {was}: {why_not}{}",
                if dropped > 0 {
                    format!(" ({dropped} solution(s) of {was} set aside)")
                } else {
                    String::new()
                }
            ));
        }
    }

    /// Opens a pose-graph file's bytes and starts optimizing it. On any problem the
    /// graph on screen stays and the note names the problem (and its line).
    pub fn load_file(&mut self, name: &str, bytes: Vec<u8>) {
        let started = web_time::Instant::now();
        match PoseGraphSession::from_file(self.pending.scenario.clone(), name, &bytes) {
            Ok(session) => {
                let text = format!(
                    "Opened {name}: {} vertices, {} edges{}",
                    session.graph().vertices().len(),
                    session.graph().edges().len(),
                    if session.notes().is_empty() {
                        String::new()
                    } else {
                        format!(" ({})", session.notes().join("; "))
                    }
                );
                self.install(session);
                self.loaded = Some((name.to_owned(), bytes));
                self.frame.note = Some(text);
                self.start_optimize();
                // The time to convergence counts the reading and the structure analysis.
                if let Some(run) = self.optimizing.as_mut() {
                    run.started = started;
                }
            }
            Err(why) => {
                self.frame.note = Some(format!("Could not open {why}; the graph on screen stays"));
            }
        }
    }

    /// Goes back one iteration or edit: the graph, the cost plot, the sparsity
    /// images and the panel's solver and kernel are as they were before it.
    pub fn step_back(&mut self) {
        self.optimizing = None;
        self.drag = None;
        let edges = self.session.graph().edges().len();
        match self.session.step_back() {
            Ok(_) => {
                self.frame.note = None;
                if self.session.graph().edges().len() != edges {
                    self.comparison = None;
                }
                let s = self.session.scenario();
                let (solver, kernel, width) = (s.solver, s.kernel, s.kernel_width);
                let pending = &mut self.pending.scenario;
                pending.solver = solver;
                pending.kernel = kernel;
                pending.kernel_width = width;
            }
            Err(why) => self.frame.note = Some(why),
        }
        self.patterns.dirty = true;
        self.marginals = None;
    }

    /// One solver iteration.
    pub fn step_iteration(&mut self) {
        self.optimizing = None;
        if let Err(why) = self.session.step() {
            self.frame.note = Some(format!("The solver stopped: {why}"));
            self.frame.time.running = false;
        }
        self.marginals = None;
    }

    /// Runs iterations to convergence (or the limit) within the frame budget,
    /// drawing the progress between frames.
    pub fn start_optimize(&mut self) {
        self.frame.time.running = false;
        self.marginals = None;
        self.optimizing = Some(OptimizeRun {
            started: web_time::Instant::now(),
            compute_ms: 0.0,
            iterations: 0,
        });
    }

    /// Runs what an "Optimize" owes this frame (up to the frame budget, or to the
    /// end when `budget_ms` is `None`).
    pub fn advance_optimize(&mut self, budget_ms: Option<u128>) {
        let Some(mut run) = self.optimizing else {
            return;
        };
        let frame = web_time::Instant::now();
        let limit = self.session.scenario().max_iterations as usize;
        let mut finished = None;
        loop {
            if run.iterations >= limit {
                finished = Some(false);
                break;
            }
            if budget_ms.is_some_and(|b| frame.elapsed().as_millis() >= b) {
                break;
            }
            let t0 = web_time::Instant::now();
            let result = self.session.step();
            run.compute_ms += t0.elapsed().as_secs_f64() * 1000.0;
            run.iterations += 1;
            match result {
                Ok(report) if report.converged => {
                    finished = Some(true);
                    break;
                }
                Ok(_) => {}
                Err(why) => {
                    self.frame.note = Some(format!("The solver stopped: {why}"));
                    finished = Some(false);
                    break;
                }
            }
        }
        match finished {
            Some(converged) => {
                self.optimizing = None;
                self.last_optimize = Some(OptimizeTiming {
                    wall_ms: run.started.elapsed().as_secs_f64() * 1000.0,
                    compute_ms: run.compute_ms,
                    iterations: run.iterations,
                    converged,
                });
            }
            None => self.optimizing = Some(run),
        }
    }

    /// Adds a deliberately wrong loop closure.
    pub fn add_wrong_loop_closure(&mut self) {
        match self.session.add_wrong_loop_closure() {
            Ok(text) => {
                self.frame.note = Some(format!("Added a {text}"));
                self.patterns.dirty = true;
                self.comparison = None;
                self.after_edit();
            }
            Err(why) => self.frame.note = Some(format!("No wrong loop closure added: {why}")),
        }
    }

    /// Optimizes the graph from its start without and with a robust kernel.
    pub fn compare_kernels(&mut self) {
        self.comparison = Some(self.session.compare_kernels());
    }

    /// Moves vertex `index` (a drag on the map).
    pub fn drag_vertex(&mut self, index: usize, x: f64, y: f64) -> Result<(), String> {
        self.optimizing = None;
        self.marginals = None;
        self.session.move_vertex(index, x, y)
    }

    /// Ends a drag: records it, and re-optimizes when the view asks for it.
    pub fn finish_drag(&mut self, index: usize) {
        self.session.finish_drag(index);
        if self.frame.view.reoptimize_after_drag {
            self.start_optimize();
        }
    }

    fn solver_name(solver: SolverKind) -> &'static str {
        solver_label(solver)
    }

    fn ensure_marginals(&mut self) {
        if self.marginals.is_none()
            && self.frame.view.ellipses
            && self.session.is_converged()
            && self.optimizing.is_none()
        {
            self.marginals = Some(self.session.marginals(MAX_ELLIPSES).unwrap_or_default());
        }
    }

    fn read_files(&mut self, ctx: &egui::Context) {
        let mut picked = self.picker.poll();
        if picked.is_none()
            && let Some(batch) = self.inbox.poll(ctx)
        {
            if batch.len() > 1 {
                self.frame.note = Some(format!(
                    "{} files were dropped; drop one pose-graph file at a time. The graph on screen stays",
                    batch.len()
                ));
                return;
            }
            picked = batch.into_iter().next();
        }
        if let Some((name, bytes)) = picked {
            match bytes {
                Ok(bytes) => self.open_graph_file(&name, bytes),
                Err(why) => {
                    self.frame.note = Some(format!(
                        "Could not read {name}: {why}; the graph on screen stays"
                    ))
                }
            }
        }
    }

    fn parameters_panel_ui(&mut self, ui: &mut egui::Ui) {
        ui.heading("Pose-graph optimization");
        ui.horizontal_wrapped(|ui| {
            let optimize = if self.optimizing.is_some() {
                "Optimizing…"
            } else {
                "Optimize"
            };
            if ui
                .add_enabled(self.optimizing.is_none(), egui::Button::new(optimize))
                .on_hover_text("Iterate until converged (or max-iterations), showing the progress")
                .clicked()
            {
                self.start_optimize();
            }
        });
        ui.horizontal_wrapped(|ui| {
            if ui
                .button("Add wrong loop closure")
                .on_hover_text(
                    "Claim that two poses far apart are at the same place, with the information of a real loop closure",
                )
                .clicked()
            {
                self.add_wrong_loop_closure();
            }
            if ui
                .button("Compare kernels")
                .on_hover_text(
                    "Optimize the graph from its start with no kernel and with the robust kernel (Huber if none is chosen); both results are drawn on the map, with their errors on the legend",
                )
                .clicked()
            {
                self.compare_kernels();
            }
        });
        ui.separator();
        ui.label(egui::RichText::new("Open a graph").strong());
        self.picker.ui(
            ui,
            "Open file…",
            ".g2o,.graph,.toro,.txt",
            MAX_FILE_BYTES,
            "path/to/graph.g2o",
        );
        ui.horizontal_wrapped(|ui| {
            ui.label("Or drop a .g2o or TORO file (M3500, intel, …) on the window.");
            crate::widgets::sources::source_link(ui, "datasets", "Sources: the datasets");
        });
        if self.loaded.is_some()
            && ui
                .button("Back to the built-in example")
                .on_hover_text("Forget the opened file and build the example below")
                .clicked()
        {
            self.open_example();
        }
        ui.separator();
        let running = self.session.scenario().clone();
        if params_panel::params_ui(ui, &mut self.pending, &running, PANEL_PARAMS) {
            self.apply_live_params();
        }
        ui.label(format!(
            "{} apply at once; the others on \"Apply & reset\".",
            LIVE_PARAMS.join(", ")
        ));
        let hover = if self.loaded.is_some() {
            "An opened file cannot travel in a link: the link opens the built-in example with these settings"
        } else {
            "index.html?… with these pairs opens exactly this graph"
        };
        if params_panel::apply_and_share_ui(
            ui,
            self.pending.differs_from(&running),
            "Build the graph again with these parameters (same seed: same graph)",
            |embed| Lesson::share_query(self, embed),
            hover,
        ) {
            self.reset();
        }
    }
}

impl crate::widgets::layout::LessonPanels for PoseGraphLesson {
    fn plots_ui(&mut self, ui: &mut egui::Ui) {
        plots::plots_ui(ui, &mut self.session, &mut self.patterns);
    }

    fn parameters_ui(&mut self, ui: &mut egui::Ui) {
        self.parameters_panel_ui(ui);
    }

    fn explanation_ui(&mut self, ui: &mut egui::Ui) {
        explain::explanation_ui(
            ui,
            &self.session,
            self.optimizing.map(|r| r.iterations),
            self.last_optimize,
            self.comparison.as_ref(),
        );
    }

    fn map_ui(&mut self, ui: &mut egui::Ui) {
        self.ensure_marginals();
        let request = map::map_ui(
            ui,
            &self.session,
            &mut self.frame.map,
            &mut self.frame.view,
            &mut self.drag,
            &mut self.last_transform,
            self.marginals.as_deref(),
            self.comparison.as_ref(),
        );
        match request {
            Some(map::MapRequest::Move(i, x, y)) => {
                if let Err(why) = self.drag_vertex(i, x, y) {
                    self.frame.note = Some(why);
                    self.drag = None;
                }
            }
            Some(map::MapRequest::Drop(i)) => self.finish_drag(i),
            None => {}
        }
        self.solutions.draw(ui.ctx());
        self.solutions.window_ui(ui.ctx(), &self.session);
    }
}

impl Lesson for PoseGraphLesson {
    crate::lesson::frame_accessors!();

    fn trajectories(&self) -> Vec<slamlab_sim::metrics::NamedTrajectory> {
        use slamlab_sim::metrics::TrajectoryRole;
        use slamlab_sim::pose_graph::export::pose_trajectory;
        vec![pose_trajectory(
            self.session.graph(),
            "graph",
            TrajectoryRole::Estimate,
        )]
    }

    fn estimate_clock(&self) -> Option<f64> {
        None
    }

    fn share_pairs(&self) -> Vec<(String, String)> {
        let scenario = self.session.scenario();
        lesson::with_seed(
            params::changed_pairs(scenario, &default_scenario()),
            scenario.seed,
        )
    }

    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        plots::series(&self.session)
    }

    fn subtitle(&self) -> String {
        let s = self.session.scenario();
        format!(
            "{} on {}, kernel {}",
            Self::solver_name(s.solver),
            self.session.source(),
            kernel_name(s.kernel)
        )
    }

    fn changed_params(&self) -> Vec<(String, String)> {
        params::changed_pairs(&self.pending.scenario, &default_scenario())
    }

    fn time_info(&self) -> TimeInfo {
        let solver = Self::solver_name(self.session.scenario().solver);
        let k = self.session.iterations();
        TimeInfo {
            tick: k as u64,
            // Iterations are not moments in time.
            time_s: f64::NAN,
            last_phase: (k > 0).then(|| format!("{solver} iteration {k}")),
            next_phase: format!("{solver} iteration {}", k + 1),
            can_step_back: self.session.can_step_back() && self.optimizing.is_none(),
        }
    }

    fn step_controls(&self) -> StepControls {
        StepControls::One {
            label: "Step iteration",
            hover: "Run one iteration of the solver",
            unit: "iteration",
            back_unit: "iteration",
        }
    }

    fn on_time_action(&mut self, action: TimeAction) {
        match action {
            TimeAction::ToggleRun => self.optimizing = None,
            TimeAction::StepPhase | TimeAction::StepTick => self.step_iteration(),
            TimeAction::StepBack => self.step_back(),
            TimeAction::Reset => self.reset(),
        }
    }

    fn read_input(&mut self, ctx: &egui::Context) {
        self.read_files(ctx);
        self.solutions.refresh(&self.session);
    }

    fn advance(&mut self, dt: f64) {
        if self.optimizing.is_some() {
            self.advance_optimize(Some(FRAME_BUDGET_MS));
            return;
        }
        let session = &mut self.session;
        let mut error = None;
        lesson::advance_within_budget(&mut self.frame.time, dt, || {
            if error.is_none()
                && !session.is_converged()
                && let Err(why) = session.step()
            {
                error = Some(why);
            }
            true
        });
        if self.frame.time.running && (self.session.is_converged() || error.is_some()) {
            self.frame.time.running = false;
        }
        if let Some(why) = error {
            self.frame.note = Some(format!("The solver stopped: {why}"));
        }
        if self.frame.time.running {
            self.marginals = None;
        }
    }

    fn wants_repaint(&self) -> bool {
        self.frame.time.running || self.optimizing.is_some()
    }

    fn view_menu_ui(&mut self, ui: &mut egui::Ui) {
        ui.checkbox(&mut self.frame.view.legend, "Map legend");
        ui.checkbox(&mut self.frame.view.truth, "True path");
        ui.checkbox(&mut self.frame.view.ellipses, "Covariance ellipses");
        ui.checkbox(
            &mut self.frame.view.reoptimize_after_drag,
            "Re-optimize after a drag",
        );
    }

    fn test_state(&self) -> serde_json::Value {
        let s = self.session.scenario();
        let count = |role: EdgeRole| self.session.roles().iter().filter(|r| **r == role).count();
        let report = self.session.last_report();
        serde_json::json!({
            "tick": self.session.iterations(),
            "iterations": self.session.iterations(),
            "phase": self.time_info().last_phase.unwrap_or_default(),
            "seed": s.seed,
            "source": self.session.source(),
            "solver": s.solver.short_name(),
            "kernel": kernel_name(s.kernel),
            "vertices": self.session.graph().vertices().len(),
            "edges": self.session.graph().edges().len(),
            "loop_closures": count(EdgeRole::LoopClosure),
            "wrong_loop_closures": count(EdgeRole::WrongLoopClosure),
            "initial_cost": self.session.history().first().map(|h| h[1]),
            "cost": self.session.cost(),
            "last_cost_before": report.map(|r| r.cost_before),
            "converged": self.session.is_converged(),
            "rmse": self.session.rmse(),
            "optimizing": self.optimizing.is_some(),
            "optimize": self.last_optimize,
            "note": self.frame.note,
            "can_step_back": self.session.can_step_back(),
            "h_blocks": self.patterns.h_blocks,
            "step_back_undoes": self.session.step_back_undoes(),
            "solutions": self.solutions.state(),
        })
    }
}
