//! The Cartographer lesson (`lesson=cartographer`, thesis `000` Sec. 5.2):
//! submaps built by local SLAM, a pose graph with branch-and-bound loop
//! closures, and the kidnapped robot during mapping. The kidnap detector's
//! cost, filtered value and threshold are plotted live (Figs. 5.8-5.9); after
//! a detection the new trajectory maps on in its own colour until an
//! inter-trajectory loop closure merges it into the first map (Figs.
//! 5.10-5.12). The last branch-and-bound search and the precomputed max grids
//! of a finished submap (Fig. 5.7) are shown beside the map.
//!
//! One tick is one scan, run in phases (`CartographerSim::step_phase`): local
//! SLAM, then each branch-and-bound search the scan's node is due, then the
//! optimization when one is due. "Step scan" finishes a scan, "Step search"
//! and "Step optimization" run up to and including the next search or
//! optimization, and a running lesson spends at most [`PHASE_BUDGET_MS`] a
//! frame on phases, so a scan with many searches spreads over frames. Step
//! back goes back one phase: it restores the latest checkpoint and replays
//! (the run is deterministic from its seed).

mod explain;
mod map;
mod plots;

use crate::laser_lesson::{LaserLesson, PendingReference};
use crate::lesson::{self, Lesson, LessonFrame, LessonStart};
use crate::time_control::{StepControls, TimeAction, TimeInfo};
use crate::widgets::laser_file::{LaserFileState, loaded_note};
use crate::widgets::laser_inputs::LaserInputs;
use crate::widgets::map_canvas::MapView;
use crate::widgets::params_panel::{self, PendingParams};
use crate::widgets::reference_track::ReferenceTrack;
use serde::{Deserialize, Serialize};
use slamlab_core::Pose2;
use slamlab_core::grid::OccupancyGrid;
use slamlab_sim::cartographer::session::{
    CartographerEvent, CartographerRun, CartographerScenario,
};
use slamlab_sim::cartographer::{CartographerPhase, CartographerSim, NextPhase};
use slamlab_sim::grid::{LaserFile, MappingInput, builtin_map};
use slamlab_sim::params;
use slamlab_sim::stepper::{CheckpointPolicy, Stepper};
use std::sync::Arc;

/// The lesson's id in URLs and the menu.
pub const LESSON_ID: &str = "cartographer";

/// Milliseconds a frame may spend on the run's phases while it runs or
/// catches up (the rest of a 16 ms frame draws the submaps and plots).
pub const PHASE_BUDGET_MS: u128 = 12;

/// The parameters the panel shows (all of the table but the map).
const PANEL_PARAMS: &[&str] = &[
    "seed",
    "steps",
    "kidnap-at",
    "kidnap-place",
    "detection",
    "num_range_data",
    "resolution",
    "hit_probability",
    "miss_probability",
    "linear_search_window",
    "angular_search_window",
    "max_constraint_distance",
    "sampling_ratio",
    "min_score",
    "global_min_score",
    "optimize_every_n_nodes",
    "huber_scale",
    "T",
    "f_size",
];

/// What the map shows; saved with the user's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CartographerView {
    /// The legend line above the map.
    pub legend: bool,
    /// The current scan's rays and hit points.
    pub scan: bool,
    /// Intra-submap constraints (node to submap origin).
    pub intra: bool,
    /// The true robot (simulation only).
    pub truth: bool,
    /// Keep the robot in the middle.
    pub follow_robot: bool,
    /// The precomputed grids window (Fig. 5.7).
    pub grids_window: bool,
    /// The reference path of a log with a corrected version.
    pub reference: bool,
}

crate::lesson::lesson_view!(CartographerView, legend: legend, follow: follow_robot);

impl Default for CartographerView {
    fn default() -> Self {
        Self {
            legend: true,
            scan: true,
            intra: true,
            truth: true,
            follow_robot: false,
            grids_window: false,
            reference: true,
        }
    }
}

/// Where the scans come from.
#[derive(Clone, Debug)]
enum Source {
    /// The simulated robot in a map (built-in or loaded): its name and grid.
    Simulated(String, Arc<OccupancyGrid>),
    /// A CARMEN log or a ROS 2 bag: its name and, from `log=`, its location.
    Log(String, Option<String>),
}

/// The Cartographer lesson.
#[derive(Debug)]
pub struct CartographerLesson {
    stepper: Stepper<CartographerRun>,
    /// The scenario of the run (the kidnap scan follows the Kidnap button).
    scenario: CartographerScenario,
    pending: PendingParams<CartographerScenario>,
    source: Source,
    /// Replaying to this many scans (after a change of the detection switch).
    catch_up: Option<usize>,
    /// Milliseconds each scan took here, its phases summed (index = scan;
    /// NaN: not measured).
    scan_ms: Vec<f64>,
    /// The longest single phase here, milliseconds.
    phase_ms_max: f64,
    /// The most time one frame spent on phases, milliseconds.
    frame_ms_max: f64,
    /// The clock, the view, the map view, the notices and the requests.
    pub frame: LessonFrame<CartographerView>,
    tiles: map::SubmapTiles,
    grids: map::MaxGridTextures,
    /// The files dropped, picked or named by the link (`log=`, `reference=`).
    inputs: LaserInputs,
    /// A reference (name, bytes, location) waiting for its log.
    pending_reference: Option<PendingReference>,
    /// Where the reference came from (`reference=`), for the share link.
    reference_location: Option<String>,
    /// The trajectory error against the reference as the run goes.
    track: ReferenceTrack,
    /// The latest ATE against the reference `[scan, m]` with loop closures
    /// off (0) and on (1), kept across the switch.
    scores: [Option<[f64; 2]>; 2],
    /// The log or bag being mapped: a bag's topics and what the reader assumed.
    laser: LaserFileState,
    /// A click on the map kidnaps the robot there.
    pub click_kidnap: bool,
    /// A built-in map was chosen in place of a log or a loaded map: the
    /// next reset simulates in it.
    builtin_chosen: bool,
    advanced: bool,
}

/// The lesson's start: the simulator's defaults.
pub fn default_scenario() -> CartographerScenario {
    CartographerScenario::default()
}

/// Opens the lesson from the URL's pairs, with what it stored last time.
pub fn open(start: &LessonStart<'_>) -> Box<dyn Lesson> {
    crate::laser_lesson::open(
        start,
        default_scenario(),
        CartographerLesson::new,
        |l| &mut l.frame,
        "Cartographer",
    )
}

fn policy() -> CheckpointPolicy {
    CheckpointPolicy {
        every_ticks: 20,
        max_checkpoints: 40,
        budget_bytes: 96 << 20,
    }
}

impl CartographerLesson {
    /// Starts the lesson on `scenario`: a simulated robot in its built-in map.
    pub fn new(scenario: CartographerScenario) -> Result<Self, String> {
        let name = if scenario.map == "office" {
            "office"
        } else {
            "maze"
        };
        let grid = Arc::new(builtin_map(name)?);
        let input = Arc::new(scenario.simulate(grid.clone(), name)?);
        let (run, notices) = CartographerRun::new(&scenario, input);
        Ok(Self {
            stepper: Stepper::with_policy(run, (), policy()),
            pending: PendingParams::new(scenario.clone()),
            scenario,
            source: Source::Simulated(name.to_owned(), grid),
            catch_up: None,
            scan_ms: Vec::new(),
            phase_ms_max: 0.0,
            frame_ms_max: 0.0,
            frame: LessonFrame::new(LESSON_ID, CartographerView::default())
                .with_map(MapView::default())
                .with_notices(notices),
            tiles: map::SubmapTiles::default(),
            grids: map::MaxGridTextures::default(),
            inputs: LaserInputs::default(),
            pending_reference: None,
            reference_location: None,
            track: ReferenceTrack::default(),
            scores: [None, None],
            laser: LaserFileState::default(),
            click_kidnap: false,
            builtin_chosen: false,
            advanced: false,
        })
    }

    /// The mapper.
    pub fn sim(&self) -> &CartographerSim {
        self.stepper.sim().sim()
    }

    /// The scenario of the run.
    pub fn scenario(&self) -> &CartographerScenario {
        &self.scenario
    }

    /// The latest note under the map toolbar.
    pub fn note(&self) -> Option<&str> {
        self.frame.note.as_deref()
    }

    /// Sets a parameter of the pending scenario from text, as the panel does.
    pub fn set_param(&mut self, name: &str, value: &str) -> Option<params::ParamIssue> {
        self.pending.set(name, value)
    }

    /// Whether the scans come from a simulated robot (which can be kidnapped).
    pub fn is_simulated(&self) -> bool {
        matches!(self.source, Source::Simulated(..))
    }

    /// A new run of `scenario` on `input`, replaying to `catch_up` scans.
    fn restart_on(
        &mut self,
        scenario: CartographerScenario,
        input: Arc<MappingInput>,
        catch_up: Option<usize>,
    ) {
        let (run, notices) = CartographerRun::new(&scenario, input);
        self.stepper = Stepper::with_policy(run, (), policy());
        self.pending = PendingParams::new(scenario.clone());
        self.scenario = scenario;
        self.frame.notices = notices;
        self.scan_ms.clear();
        self.phase_ms_max = 0.0;
        self.frame_ms_max = 0.0;
        self.tiles.clear();
        self.grids.clear();
        self.track.clear();
        self.catch_up = catch_up.filter(|&n| n > 0);
        if catch_up.is_none() {
            self.frame.time.apply(TimeAction::Reset);
            self.frame.map.refit();
        }
    }

    /// The input of `scenario` from the current source.
    fn input_of(&self, scenario: &CartographerScenario) -> Result<Arc<MappingInput>, String> {
        match &self.source {
            Source::Simulated(name, grid) => scenario.simulate(grid.clone(), name).map(Arc::new),
            Source::Log(..) => Ok(self.sim().input().clone()),
        }
    }

    /// Starts over with the pending parameters (same seed: same scans).
    pub fn reset(&mut self) {
        let mut scenario = self.pending.scenario.clone();
        if self.builtin_chosen || scenario.map != self.scenario.map {
            self.builtin_chosen = false;
            let name = if scenario.map == "office" {
                "office"
            } else {
                "maze"
            };
            match builtin_map(name) {
                Ok(grid) => {
                    self.source = Source::Simulated(name.to_owned(), Arc::new(grid));
                    self.laser.close();
                }
                Err(why) => {
                    self.frame.note = Some(format!("Could not open the map {name}: {why}"));
                    scenario.map = self.scenario.map.clone();
                }
            }
        }
        match self.input_of(&scenario) {
            Ok(input) => self.restart_on(scenario, input, None),
            Err(why) => {
                self.frame.note = Some(format!("Could not start over: {why}; the run goes on"))
            }
        }
    }

    /// Switches kidnap detection on or off: the same scans replay from the
    /// start up to where the run was.
    pub fn set_detection(&mut self, on: bool) {
        if on == self.scenario.detection {
            return;
        }
        let done = self.sim().scans_done();
        let scenario = CartographerScenario {
            detection: on,
            ..self.scenario.clone()
        };
        let input = self.sim().input().clone();
        self.restart_on(scenario, input, Some(done));
        self.catch_up_note();
    }

    /// Stops mapping the same scans again (a step or step back), and its note.
    fn stop_catch_up(&mut self) {
        if self.catch_up.take().is_some() {
            self.frame.note = None;
        }
    }

    /// The note while the run maps the same scans again up to where it was; none
    /// once it is there.
    fn catch_up_note(&mut self) {
        self.frame.note = self.catch_up.map(|target| {
            format!(
                "Kidnap detection {}: mapping the same scans again, scan {} of {target}…",
                if self.scenario.detection { "on" } else { "off" },
                self.sim().scans_done()
            )
        });
    }

    /// Switches loop closures on or off: the same scans replay from the start
    /// up to where the run was, and the score against a reference reached so
    /// far is kept beside the other's.
    pub fn set_loop_closures(&mut self, on: bool) {
        if on == self.scenario.loop_closures {
            return;
        }
        self.refresh_reference();
        self.scores[usize::from(self.scenario.loop_closures)] = self.track.latest();
        let done = self.sim().scans_done();
        let scenario = CartographerScenario {
            loop_closures: on,
            ..self.scenario.clone()
        };
        self.pending.scenario.loop_closures = on;
        let input = self.sim().input().clone();
        self.restart_on(scenario, input, Some(done));
        self.frame.note = Some(format!(
            "Loop closures {}: mapping the same scans again up to scan {done}",
            if on { "on" } else { "off" }
        ));
    }

    /// Brings the trajectory error against the reference up to the run.
    fn refresh_reference(&mut self) {
        let sim = self.stepper.sim().sim();
        let reference = sim.input().reference.clone();
        let done = sim.scans_done();
        self.track
            .update(reference.as_deref(), done, || sim.scan_poses());
        if reference.is_some() {
            self.scores[usize::from(self.scenario.loop_closures)] = self.track.latest();
        }
    }

    /// Carries the simulated robot elsewhere before the next scan: to `to`
    /// (a click), or to a random free place at least 2 m away.
    pub fn kidnap(&mut self, to: Option<Pose2>) {
        let Source::Simulated(name, grid) = &self.source else {
            self.frame.note = Some(
                "A log is replayed as recorded: only a simulated robot can be kidnapped".to_owned(),
            );
            return;
        };
        let k = self.sim().scans_done();
        if self.sim().is_done() {
            self.frame.note = Some("Every scan is in: reset to kidnap the robot".to_owned());
            return;
        }
        if let Some(at) = self.scenario.kidnap_at.filter(|&at| at < k) {
            self.frame.note = Some(format!(
                "The robot was kidnapped at scan {at} already: one kidnap per run (reset to kidnap it elsewhere)"
            ));
            return;
        }
        let scenario = CartographerScenario {
            kidnap_at: Some(k),
            kidnap_to: to.map(|p| [p.x, p.y]),
            ..self.scenario.clone()
        };
        let input = scenario.simulate(grid.clone(), name);
        match input {
            Ok(input) => {
                self.stepper
                    .apply(CartographerEvent::Kidnap(Arc::new(input)));
                self.pending.scenario.kidnap_at = Some(k);
                self.pending.scenario.kidnap_to = scenario.kidnap_to;
                self.scenario = scenario;
                self.frame.note = Some(format!(
                    "Kidnapped before scan {k}: the odometry does not see it; watch the matching cost"
                ));
            }
            Err(why) => self.frame.note = Some(format!("Could not kidnap the robot: {why}")),
        }
    }

    /// Maps a laser file (a CARMEN log, plain or compressed, or a ROS 2 bag).
    /// On any problem the current run stays, with a note that names it.
    pub fn load_log(&mut self, name: &str, bytes: &[u8], location: Option<String>) {
        match self.laser.open(name, bytes) {
            Ok(file) => self.map_file(name, file, location),
            Err(why) => self.frame.note = Some(why),
        }
    }

    /// Maps an opened laser file.
    fn map_file(&mut self, name: &str, file: LaserFile, location: Option<String>) {
        let note = loaded_note(name, &file);
        self.source = Source::Log(name.to_owned(), location);
        self.reference_location = None;
        self.scores = [None, None];
        let scenario = CartographerScenario {
            kidnap_at: None,
            kidnap_to: None,
            ..self.pending.scenario.clone()
        };
        self.restart_on(scenario, Arc::new(file.input), None);
        self.frame.note = Some(format!("{note}; no kidnap button"));
        if let Some((reference, bytes, location)) = self.pending_reference.take() {
            self.load_reference(&reference, bytes, location);
        }
    }

    /// Runs the next phase, timed (its time goes to its scan's).
    fn run_phase(&mut self) -> CartographerPhase {
        let started = web_time::Instant::now();
        let phase = self.stepper.step_phase();
        let ms = started.elapsed().as_secs_f64() * 1e3;
        self.phase_ms_max = self.phase_ms_max.max(ms);
        let (scan, first) = match phase {
            CartographerPhase::LocalSlam { scan } => (scan, true),
            CartographerPhase::Search { scan, .. }
            | CartographerPhase::Optimization { scan }
            | CartographerPhase::Settled { scan } => (scan, false),
            CartographerPhase::Done => return phase,
        };
        if self.scan_ms.len() <= scan {
            self.scan_ms.resize(scan + 1, f64::NAN);
        }
        let slot = &mut self.scan_ms[scan];
        *slot = if first || !slot.is_finite() {
            ms
        } else {
            *slot + ms
        };
        phase
    }

    /// Finishes the current scan, or runs a whole new one, timed.
    pub fn step_scan(&mut self) {
        if self.sim().is_done() {
            return;
        }
        loop {
            self.run_phase();
            if !self.sim().is_mid_scan() {
                break;
            }
        }
    }

    /// Runs phases up to and including the next one `wanted` picks (through
    /// as many scans as it takes); false when every scan went in first.
    fn step_until(&mut self, wanted: impl Fn(&CartographerPhase) -> bool) -> bool {
        while !self.sim().is_done() {
            let phase = self.run_phase();
            if wanted(&phase) {
                return true;
            }
        }
        false
    }

    /// "Step search": runs up to and including the next branch-and-bound
    /// search (its tree is the one drawn).
    pub fn step_search(&mut self) {
        self.stop_catch_up();
        self.frame.time.apply(TimeAction::StepPhase);
        if self.step_until(|p| matches!(p, CartographerPhase::Search { .. })) {
            if let Some(search) = &self.sim().last_search {
                let result = search.score.map_or_else(
                    || "no match above min_score".to_owned(),
                    |s| format!("best score {s:.3}"),
                );
                self.frame.note = Some(format!(
                    "Searched scan {}'s node in submap {}{}: {result}",
                    search.scan,
                    search.submap,
                    if search.global { " (whole submap)" } else { "" },
                ));
            }
        } else {
            self.frame.note = Some("No search left: every scan is in".to_owned());
        }
    }

    /// "Step optimization": runs up to and including the next optimization
    /// of the pose graph.
    pub fn step_optimization(&mut self) {
        self.stop_catch_up();
        self.frame.time.apply(TimeAction::StepPhase);
        let before = self.sim().scans_done();
        if self.step_until(|p| matches!(p, CartographerPhase::Optimization { .. })) {
            let every = self.sim().params().optimize_every_n_nodes;
            self.frame.note = self.sim().last_optimization.map(|o| {
                // A jump of many scans is explained: the graph is solved only every
                // n nodes (and after a merge).
                let ran = match o.scan.saturating_sub(before) {
                    0 | 1 => String::new(),
                    n => format!(
                        " (ran {n} scans to reach it: the pose graph is solved every {every} \
                         nodes and after a merge)"
                    ),
                };
                format!(
                    "Optimized after scan {}{ran}: cost {} → {} in {} iterations; nodes moved \
                     {:.3} m on average, {:.3} m at most",
                    o.scan,
                    explain::cost_text(o.cost_before),
                    explain::cost_text(o.cost_after),
                    o.iterations,
                    o.mean_node_move,
                    o.max_node_move
                )
            });
        } else {
            self.frame.note = Some("No optimization left: every scan is in".to_owned());
        }
    }

    /// What runs next: "scan 153: 4 of 12 searches pending, then
    /// optimization".
    pub fn next_phase_text(&self) -> String {
        let o = self.sim().outlook();
        let then = if o.optimization_pending {
            ", then optimization"
        } else {
            ""
        };
        match o.next {
            NextPhase::Done => "done: every scan is in".to_owned(),
            NextPhase::LocalSlam => format!("scan {}", o.scan),
            NextPhase::Search => format!(
                "scan {}: {} of {} searches pending{then}",
                o.scan, o.searches_pending, o.searches_planned
            ),
            NextPhase::Optimization => format!("scan {}: optimization", o.scan),
        }
    }

    /// Where the map draws the robot: the last scan's pose moved with its
    /// trajectory since (a merge, an optimization).
    pub fn robot_pose(&self) -> Option<slamlab_core::geometry::Pose2> {
        map::robot_pose_now(self.sim())
    }

    /// The kidnap's key moments so far, for the time bar: the detection and the
    /// merge (which moves the second map onto the first at once), and whether the
    /// optimization after it has run yet.
    pub fn moment_text(&self) -> Option<String> {
        let sim = self.sim();
        let detected = sim.detections.last().copied();
        let merged = sim.merges.last().copied();
        let optimized_since = |m: usize| sim.last_optimization.is_some_and(|o| o.scan >= m);
        match (detected, merged) {
            (None, None) => None,
            (Some(d), None) => Some(format!("Kidnap detected at scan {d}: a new map started")),
            (d, Some(m)) => {
                let detected =
                    d.map_or(String::new(), |d| format!("Kidnap detected at scan {d}; "));
                let then = if optimized_since(m) {
                    ", then the optimization refined both"
                } else {
                    "; the optimization that refines both is next"
                };
                Some(format!(
                    "{detected}maps merged at scan {m}: the second moved onto the first{then}"
                ))
            }
        }
    }

    /// Runs scans until `n` are in (or every scan), however long it takes.
    pub fn run_to(&mut self, n: usize) {
        while (self.sim().scans_done() < n || self.sim().is_mid_scan()) && !self.sim().is_done() {
            self.step_scan();
        }
    }

    /// Keeps the most time one frame spent on phases.
    fn note_frame(&mut self, started: web_time::Instant) {
        let ms = started.elapsed().as_secs_f64() * 1e3;
        self.frame_ms_max = self.frame_ms_max.max(ms);
    }

    fn subtitle_text(&self) -> String {
        let name = match &self.source {
            Source::Simulated(name, _) => format!("simulated {name}"),
            Source::Log(name, _) => name.clone(),
        };
        let kidnap = self
            .scenario
            .kidnap_at
            .map_or(String::new(), |k| format!(", kidnap at scan {k}"));
        format!("{name}, seed {}{kidnap}", self.scenario.seed)
    }

    /// The lesson's main actions, in the row above the map at every size.
    fn actions_ui(&mut self, ui: &mut egui::Ui) {
        ui.horizontal_wrapped(|ui| {
            let more = !self.sim().is_done();
            if ui
                .add_enabled(more, egui::Button::new("Step search"))
                .on_hover_text(
                    "Run up to and including the next branch-and-bound search (through as \
                     many scans as it takes); its tree is drawn in the explanation panel",
                )
                .clicked()
            {
                self.step_search();
            }
            if ui
                .add_enabled(more, egui::Button::new("Step optimization"))
                .on_hover_text(
                    "Run up to and including the next optimization of the pose graph; the note \
                     says its cost before and after and how far it moved the nodes",
                )
                .clicked()
            {
                self.step_optimization();
            }
            ui.separator();
            let simulated = self.is_simulated();
            if ui
                .add_enabled(simulated, egui::Button::new("Kidnap"))
                .on_hover_text(
                    "Carry the robot to a random free place at least 2 m away before the next \
                     scan; the odometry does not see it",
                )
                .clicked()
            {
                self.kidnap(None);
            }
            // A button of its own (not a child ui), so that it wraps as one piece.
            if ui
                .add_enabled(
                    simulated,
                    egui::Button::selectable(self.click_kidnap, "Kidnap by click"),
                )
                .on_hover_text("Then click on the map: the robot is carried there (heading 0)")
                .clicked()
            {
                self.click_kidnap = !self.click_kidnap;
            }
            let mut detection = self.scenario.detection;
            ui.checkbox(&mut detection, "Detection").on_hover_text(
                "Kidnap detection (Xiang's thesis, Algorithm 13): off, the same scans map on into one \
                 corrupted map (Fig. 5.10). Switching replays the run to this scan",
            );
            self.set_detection(detection);
            let mut closures = self.scenario.loop_closures;
            ui.checkbox(&mut closures, "Loop closures").on_hover_text(
                "Off: local SLAM alone, no branch-and-bound search (on a long log, the open, \
                 doubled corridors). Switching replays the same scans to this scan; with a \
                 reference, both scores stay in the error plot's title",
            );
            self.set_loop_closures(closures);
            ui.toggle_value(&mut self.frame.view.grids_window, "Max grids")
                .on_hover_text("The precomputed grids of a finished submap (thesis Fig. 5.7)");
        });
    }

    fn parameters_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("Cartographer: submaps and loop closure");
        ui.label("Kidnap, detection and the max grids are above the map.");
        ui.horizontal(|ui| {
            ui.label("map");
            let current = self.pending.scenario.map.clone();
            let shown = match &self.source {
                Source::Simulated(name, _) | Source::Log(name, _) => name.clone(),
            };
            egui::ComboBox::from_id_salt("cartographer_map")
                .selected_text(shown)
                .show_ui(ui, |ui| {
                    for name in ["maze", "office"] {
                        if ui.selectable_label(current == name, name).clicked() {
                            self.pending.set("map", name);
                            // A log or a loaded map gives way on the next reset.
                            self.builtin_chosen = true;
                        }
                    }
                })
                .response
                .on_hover_text("The built-in maps; press \"Apply & reset\"")
                .widget_info(|| egui::WidgetInfo::labeled(egui::Role::ComboBox, true, "map"));
        });
        if let Some(result) = self.laser.topics_ui(ui) {
            match result {
                Ok(file) => {
                    let (name, location) = match &self.source {
                        Source::Log(name, location) => (name.clone(), location.clone()),
                        Source::Simulated(name, _) => (name.clone(), None),
                    };
                    self.map_file(&name, file, location);
                }
                Err(why) => self.frame.note = Some(why),
            }
        }
        ui.label(
            "Or open a CARMEN laser log (.clf, .gz, .bz2), a ROS 2 bag (.mcap) or a ROS map (its \
             YAML with the image); or drop either on the window:",
        );
        self.inputs.picker_ui(ui);
        let running = self.scenario.clone();
        params_panel::params_ui(ui, &mut self.pending, &running, PANEL_PARAMS);
        ui.separator();
        if params_panel::apply_and_share_ui(
            ui,
            self.pending.differs_from(&running) || self.builtin_chosen,
            "Start over with these parameters (same seed: same scans)",
            |embed| lesson::Lesson::share_query(self, embed),
            "index.html?… with these pairs opens exactly this run",
        ) {
            self.reset();
        }
    }
}

impl LaserLesson for CartographerLesson {
    fn open_log(&mut self, name: &str, bytes: &[u8]) {
        self.load_log(name, bytes, None);
    }
    fn open_linked_log(&mut self, name: &str, bytes: &[u8], location: String) {
        self.load_log(name, bytes, Some(location));
        if matches!(&self.source, Source::Log(n, _) if n == name) {
            // The link's figure keys (`run=1`, `tick=`) hold for the log.
            self.frame.restarted_from_link = true;
        }
    }
    fn logged_input(&self) -> Option<Arc<MappingInput>> {
        matches!(self.source, Source::Log(..)).then(|| self.sim().input().clone())
    }
    fn pending_reference(&mut self) -> &mut Option<PendingReference> {
        &mut self.pending_reference
    }
    fn restart_with_reference(&mut self, input: Arc<MappingInput>, location: Option<String>) {
        self.reference_location = location;
        self.scores = [None, None];
        let scenario = self.scenario.clone();
        self.restart_on(scenario, input, None);
    }

    /// Lets the simulated robot explore a ROS map instead of a built-in one.
    fn load_map_files(&mut self, files: &[(String, Vec<u8>)]) {
        let Some((name, grid, notes)) = self.read_map(files) else {
            return;
        };
        let scenario = self.pending.scenario.clone();
        match scenario.simulate(grid.clone(), &name) {
            Ok(input) => {
                self.source = Source::Simulated(name.clone(), grid);
                self.laser.close();
                self.restart_on(scenario, Arc::new(input), None);
                self.frame.note = Some(format!(
                    "The robot explores {name}{}",
                    if notes.is_empty() {
                        String::new()
                    } else {
                        format!(" ({})", notes.join("; "))
                    }
                ));
            }
            Err(why) => self.frame.note = Some(format!("Could not drive in {name}: {why}")),
        }
    }

    fn laser_file(&mut self) -> &mut LaserFileState {
        &mut self.laser
    }
    fn laser_inputs(&mut self) -> &mut LaserInputs {
        &mut self.inputs
    }
}

impl crate::widgets::layout::LessonPanels for CartographerLesson {
    fn plots_ui(&mut self, ui: &mut egui::Ui) {
        self.refresh_reference();
        let on = self.scenario.loop_closures;
        plots::plots_ui(ui, self.sim(), &self.scan_ms, &self.track, self.scores, on);
    }

    fn parameters_ui(&mut self, ui: &mut egui::Ui) {
        self.parameters_panel(ui);
    }

    fn explanation_ui(&mut self, ui: &mut egui::Ui) {
        explain::explanation_ui(ui, self.sim(), &self.scenario);
    }

    fn map_ui(&mut self, ui: &mut egui::Ui) {
        self.refresh_reference();
        self.actions_ui(ui);
        if self.frame.view.grids_window {
            let mut open = true;
            map::max_grids_window(
                ui.ctx(),
                // Under the lesson's actions: the Max grids button stays in view.
                ui.available_rect_before_wrap(),
                self.stepper.sim().sim(),
                &mut self.grids,
                &mut open,
            );
            self.frame.view.grids_window = open;
        }
        let clicked = map::map_ui(
            ui,
            self.stepper.sim().sim(),
            &mut self.frame.map,
            &mut self.tiles,
            &mut self.frame.view,
            self.click_kidnap,
            &self.track,
        );
        if let Some(pose) = clicked {
            self.click_kidnap = false;
            self.kidnap(Some(pose));
        }
    }
}

impl Lesson for CartographerLesson {
    crate::lesson::frame_accessors!();

    fn moment(&self) -> Option<String> {
        self.moment_text()
    }

    fn trajectories(&self) -> Vec<slamlab_sim::metrics::NamedTrajectory> {
        slamlab_sim::cartographer::export::trajectories(self.sim())
    }

    fn share_pairs(&self) -> Vec<(String, String)> {
        let mut pairs = lesson::with_seed(
            params::changed_pairs(&self.scenario, &default_scenario()),
            self.scenario.seed,
        );
        let log = match &self.source {
            Source::Log(_, location) => location.as_deref(),
            Source::Simulated(..) => None,
        };
        pairs.extend(crate::laser_lesson::share_pairs(
            log,
            self.reference_location.as_deref(),
            &self.laser,
        ));
        pairs
    }

    fn subtitle(&self) -> String {
        self.subtitle_text()
    }

    fn run_notices(&self) -> Vec<String> {
        let mut all: Vec<String> = self.laser.notices().to_vec();
        all.extend(self.sim().notes.iter().take(3).cloned());
        all
    }

    fn changed_params(&self) -> Vec<(String, String)> {
        params::changed_pairs(&self.pending.scenario, &default_scenario())
    }

    fn time_info(&self) -> TimeInfo {
        let sim = self.sim();
        let done = sim.scans_done();
        TimeInfo {
            tick: done as u64,
            time_s: done
                .checked_sub(1)
                .and_then(|k| sim.input().scans.get(k))
                .map_or(0.0, |s| s.time),
            last_phase: self.stepper.last_phase().map(phase_text),
            next_phase: self.next_phase_text(),
            can_step_back: self.stepper.phases_run() > 0,
        }
    }

    fn step_controls(&self) -> StepControls {
        StepControls::One {
            label: "Step scan",
            hover: "Finish the current scan, or run a whole new one: local matching, insertion \
                    into the submaps, the loop-closure searches and, when due, the optimization. \
                    \"Step search\" and \"Step optimization\" above the map run one search or one \
                    optimization; Step back goes back one of these phases",
            unit: "scan",
            back_unit: "phase",
        }
    }

    fn on_time_action(&mut self, action: TimeAction) {
        match action {
            TimeAction::ToggleRun => {}
            TimeAction::StepPhase | TimeAction::StepTick => {
                self.stop_catch_up();
                self.step_scan();
            }
            TimeAction::StepBack => {
                // One phase back: the last search, optimization or local SLAM.
                self.stop_catch_up();
                self.stepper.step_back();
                let done = self.sim().scans_done();
                self.scan_ms.truncate(done);
            }
            TimeAction::Reset => {
                let scenario = self.scenario.clone();
                let input = self.input_of(&scenario);
                match input {
                    Ok(input) => self.restart_on(scenario, input, None),
                    Err(why) => self.frame.note = Some(format!("Could not start over: {why}")),
                }
            }
        }
    }

    fn read_input(&mut self, ctx: &egui::Context) {
        self.read_laser_inputs(ctx);
    }

    fn advance(&mut self, dt: f64) {
        self.advanced = false;
        let started = web_time::Instant::now();
        if let Some(target) = self.catch_up {
            self.advanced = true;
            let reached = |sim: &CartographerSim| sim.scans_done() >= target && !sim.is_mid_scan();
            while !reached(self.sim())
                && !self.sim().is_done()
                && started.elapsed().as_millis() < PHASE_BUDGET_MS
            {
                self.run_phase();
            }
            if reached(self.sim()) || self.sim().is_done() {
                self.catch_up = None;
            }
            self.catch_up_note();
            self.note_frame(started);
            return;
        }
        if self.sim().is_done() {
            self.frame.time.running = false;
            return;
        }
        let mut stepped = false;
        let lesson = &mut *self;
        let mut time = lesson.frame.time.clone();
        // Phase by phase within the budget: a scan with many searches
        // spreads over frames; a tick is counted when its scan is finished.
        lesson::advance_within_ms(&mut time, dt, PHASE_BUDGET_MS, || {
            if lesson.sim().is_done() {
                return true;
            }
            lesson.run_phase();
            stepped = true;
            !lesson.sim().is_mid_scan()
        });
        self.frame.time = time;
        self.advanced = stepped;
        if stepped {
            self.note_frame(started);
        }
    }

    fn last_advance_updated(&self) -> bool {
        self.advanced
    }

    fn wants_repaint(&self) -> bool {
        self.frame.time.running || self.catch_up.is_some() || self.inputs.is_fetching()
    }

    fn view_menu_ui(&mut self, ui: &mut egui::Ui) {
        ui.checkbox(&mut self.frame.view.legend, "Map legend");
        ui.checkbox(&mut self.frame.view.scan, "Current scan");
        ui.checkbox(&mut self.frame.view.intra, "Intra-submap constraints");
        ui.checkbox(&mut self.frame.view.truth, "True robot");
        ui.checkbox(
            &mut self.frame.view.grids_window,
            "Precomputed max grids (Fig. 5.7)",
        );
        ui.checkbox(
            &mut self.frame.view.reference,
            "Reference path (a corrected log)",
        );
    }

    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        plots::series(
            self.sim(),
            &self.scan_ms,
            &self.track,
            self.scenario.loop_closures,
        )
    }

    fn test_state(&self) -> serde_json::Value {
        let sim = self.sim();
        // Counted here, not by `summary` (which builds the global map for its
        // agreement metric: too slow for a state read every frame).
        let kidnap_at = self.scenario.kidnap_at;
        let detected = kidnap_at.and_then(|k| {
            sim.detections
                .iter()
                .copied()
                .find(|&d| d >= k && d <= k + slamlab_sim::cartographer::DETECTION_WINDOW)
        });
        let loop_closures = sim
            .constraints
            .iter()
            .filter(|c| c.kind != slamlab_sim::cartographer::ConstraintKind::IntraSubmap)
            .count();
        let pose = sim
            .records
            .last()
            .map(|r| [r.global_pose.x, r.global_pose.y, r.global_pose.theta]);
        let mut timed: Vec<f64> = self
            .scan_ms
            .iter()
            .copied()
            .filter(|t| t.is_finite())
            .collect();
        timed.sort_by(f64::total_cmp);
        let search = sim.last_search.as_ref().map(|s| {
            serde_json::json!({
                "scan": s.scan,
                "submap": s.submap,
                "global": s.global,
                "score": s.score,
                "evaluated": s.record.evaluated(),
                "exhaustive": s.record.exhaustive_candidates,
            })
        });
        serde_json::json!({
            "tick": sim.scans_done(),
            "scans": sim.scans_done(),
            "total_scans": sim.input().scans.len(),
            "input": sim.input().name,
            "input_seconds": sim.input().duration(),
            "seed": self.scenario.seed,
            "kidnap_at": kidnap_at,
            "detection": self.scenario.detection,
            "detections": sim.detections,
            "kidnap_detected_at": detected,
            "recovered_at": sim.merges.first(),
            "merges": sim.merges,
            "submaps": sim.submaps.len(),
            "nodes": sim.nodes.len(),
            "trajectories": sim.trajectories.len(),
            "loop_closures": loop_closures,
            "optimizations": sim.optimizations,
            "bbs": sim.bbs,
            "pose": pose,
            "catching_up": self.catch_up.is_some(),
            "last_search": search,
            "scan_ms_median": timed.get(timed.len() / 2),
            "scan_ms_max": timed.last(),
            "phase_ms_max": self.phase_ms_max,
            "frame_ms_max": self.frame_ms_max,
            "mid_scan": sim.is_mid_scan(),
            "next_phase": self.next_phase_text(),
            "phases_run": self.stepper.phases_run(),
            "loop_closures_on": self.scenario.loop_closures,
            "reference": sim.input().reference.as_deref().map(|r| serde_json::json!({
                "name": r.name,
                "matched": r.points.len(),
                "scans": r.reference_scans,
                "ate_m": self.track.latest().map(|p| p[1]),
                "ate_at_scan": self.track.latest().map(|p| p[0]),
                "ate_points": self.track.ate.len(),
                "path_points": self.track.path.len(),
                "ate_loop_closures_on": self.scores[1].map(|p| p[1]),
                "ate_loop_closures_off": self.scores[0].map(|p| p[1]),
            })),
        })
    }
}

/// A phase as the time bar names it ("scan 153: search in submap 4").
fn phase_text(phase: &CartographerPhase) -> String {
    match *phase {
        CartographerPhase::LocalSlam { scan } => format!("scan {scan}: local SLAM"),
        CartographerPhase::Search {
            scan,
            submap,
            global,
        } => format!(
            "scan {scan}: {}search in submap {submap}",
            if global { "global " } else { "" }
        ),
        CartographerPhase::Optimization { scan } => format!("scan {scan}: optimization"),
        CartographerPhase::Settled { scan } => format!("scan {scan}"),
        CartographerPhase::Done => "every scan is in".to_owned(),
    }
}
