//! The `landmark-slam` lesson: EKF-SLAM (and UKF-SLAM once it exists) on the same
//! landmark world, stepped phase by phase.
//!
//! The lesson owns a [`LandmarkSession`] (the truth, the sensor and the filters) and
//! paints it; every number it shows comes from the session. Parameters are edited
//! on a copy of the scenario and take effect on reset, except the sensor's field of
//! view and range, which change the running session from the next tick.
//!
//! The world is the simulated one or a recorded data set ([`data`]): MRCLAM (a
//! robot of five, with Vicon truth), the Freiburg course's files or Victoria
//! Park, opened by the file picker, a drop or `data=`. A data set opens with its
//! preset (the noise measured from the data); the robot and the mode (SLAM or
//! localization with the map given) are parameters like the others. Victoria
//! Park takes gtsam's pose graph of the same drive as its reference map
//! ([`reference`]), solved one step per frame and drawn over the filters.

pub mod data;
pub mod drive;
mod explain;
mod heatmap;
pub mod many_runs;
mod map;
mod params_panel;
mod plots;
pub mod reference;

use crate::lesson::{self, Lesson, LessonFrame, LessonStart, PanelVisibility};
use crate::time_control::{TimeAction, TimeInfo};
use serde::{Deserialize, Serialize};
use slamlab_core::Pose2;
use slamlab_core::kalman::LandmarkSlam;
use slamlab_sim::io::landmark_data::DataSetKind;
use slamlab_sim::landmark_slam::presets;
use slamlab_sim::params::{self, ParamIssue};
use slamlab_sim::world::landmark_scenario::ControllerKind;
use slamlab_sim::world::recorded::RecordedWorld;
use slamlab_sim::{LandmarkScenario, LandmarkSession};
use std::collections::BTreeMap;
use std::convert::Infallible;
use std::sync::Arc;

/// The lesson's id in URLs and the menu.
pub const LESSON_ID: &str = "landmark-slam";

/// Parameters that change the running session at once (from the next tick): the
/// sensor's reach. The filters never see it, only the measurements it lets through.
pub const LIVE_PARAMS: [&str; 2] = ["fov-deg", "max-range"];

/// What the map and the panels show; saved with the user's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ViewOptions {
    /// The legend box on the map.
    pub legend: bool,
    /// A magnified inset around the robot while its ellipses are small on the map.
    pub magnifier: bool,
    /// The sensor's field of view as a faint wedge.
    pub fov: bool,
    /// This tick's observations as rays from the true robot.
    pub rays: bool,
    /// A thin line from each estimated landmark to its true position.
    pub error_lines: bool,
    /// Landmark ids beside the true landmarks.
    pub ids: bool,
    /// UKF sigma points of the robot (when a filter has them).
    pub sigma_points: bool,
    /// Keep the true robot in the middle of the map.
    pub follow_robot: bool,
    /// The covariance heatmap window.
    pub heatmap: bool,
    /// The "Many runs" window: average NEES over seeded runs.
    pub many_runs: bool,
}

crate::lesson::lesson_view!(ViewOptions, legend: legend, follow: follow_robot);

impl Default for ViewOptions {
    fn default() -> Self {
        Self {
            legend: true,
            magnifier: true,
            fov: true,
            rays: true,
            error_lines: false,
            ids: true,
            sigma_points: true,
            follow_robot: false,
            heatmap: false,
            many_runs: false,
        }
    }
}

/// The first filter's path so far carried onto the data's GPS (Victoria Park):
/// the rigid transform between the GPS's frame and the estimate's, and the RMS
/// distance that remains ([`slamlab_sim::landmark_slam::real_data::gps_fit`], as
/// `slamlab experiment real-data` reports it for the whole run). `None` without
/// a GPS or before two fixes pair with the path.
pub fn gps_fit_now(
    session: &LandmarkSession,
) -> Option<slamlab_sim::landmark_slam::real_data::GpsFit> {
    let world = session.recorded_world()?;
    if world.reference.is_empty() {
        return None;
    }
    let filters = session.filters();
    let run = filters.first()?;
    let path = slamlab_sim::metrics::Trajectory::new(
        session.tick_times().to_vec(),
        run.records().path.clone(),
    );
    slamlab_sim::landmark_slam::real_data::gps_fit(world, &path)
}

/// The robot's sigma points if the filter is sigma-point based (UKF), else none.
pub fn robot_sigma_points(filter: &dyn LandmarkSlam) -> Vec<Pose2> {
    filter.robot_sigma_points()
}

/// The lesson's starting scenario, the `lesson` preset: the simulator's defaults
/// with EKF-SLAM and UKF-SLAM side by side (the FEJ-EKF is one checkbox away).
pub fn default_scenario() -> LandmarkScenario {
    let seed = LandmarkScenario::default().seed;
    slamlab_sim::landmark_slam::presets::scenario("lesson", seed).unwrap_or_default()
}

/// The parameters of `scenario` that differ from the lesson's start, in table order.
fn changed_pairs(scenario: &LandmarkScenario) -> Vec<(String, String)> {
    params::changed_pairs(scenario, &default_scenario())
}

/// The landmark-SLAM lesson.
#[derive(Debug)]
pub struct LandmarkSlamLesson {
    session: LandmarkSession,
    pending: LandmarkScenario,
    pending_issues: BTreeMap<String, String>,
    /// The clock, the view, the map view, the notices and the requests.
    pub frame: LessonFrame<ViewOptions>,
    /// Manual driving.
    pub drive: drive::DriveState,
    heatmap: heatmap::HeatmapState,
    /// The "Many runs" window's study.
    pub many_runs: many_runs::ManyRunsState,
    /// Bumped whenever the session changes, so caches know when to refresh.
    version: u64,
    /// The recorded data set the run replays; `None` in the simulated world.
    data: Option<data::LoadedData>,
    /// The picker, the drops and `data=`.
    data_input: data::DataInput,
    /// The URL's parameter pairs, applied again over a data set's preset when
    /// `data=` arrives (so `robot=3&mode=localization` hold).
    link_pairs: Vec<(String, String)>,
    /// Victoria Park's reference map (gtsam's pose graph, solved here).
    reference: reference::ReferenceState,
}

/// Opens the lesson from the URL's pairs, with what it stored last time (the
/// stored parameters only when the URL gives none).
pub fn open(start: &LessonStart<'_>) -> Box<dyn Lesson> {
    let location = data::location(start.pairs);
    let reference_location = start
        .pairs
        .iter()
        .rev()
        .find(|(k, v)| k == reference::REFERENCE_KEY && !v.trim().is_empty())
        .map(|(_, v)| v.clone());
    let pairs: Vec<(String, String)> = start
        .pairs
        .iter()
        .filter(|(k, _)| k != data::DATA_KEY && k != reference::REFERENCE_KEY)
        .cloned()
        .collect();
    let start = &LessonStart {
        pairs: &pairs,
        ..*start
    };
    // A lecture figure looks the same for every student: the view a student left
    // in the full app (an open heatmap, say) stays there.
    let new = |scenario| Ok::<_, Infallible>(LandmarkSlamLesson::new(scenario));
    let Ok(mut lesson) = lesson::open_lesson(start, default_scenario(), new, |l| &mut l.frame);
    if let Some(location) = location {
        lesson.frame.note = Some(format!("Loading the data set {location}…"));
        lesson.link_pairs = pairs.clone();
        lesson.data_input.fetch(location);
    }
    if let Some(location) = reference_location {
        lesson.reference.fetch(location);
    }
    if let Some(trials) = start.many_runs {
        lesson.start_many_runs(trials);
    }
    if start.embed {
        // A lecture figure is small: the map gets the room, and the legend is one
        // click away (every element also has a tooltip).
        lesson.frame.view.legend = false;
    }
    Box::new(lesson)
}

impl LandmarkSlamLesson {
    /// Starts the lesson on `scenario` (already checked by [`params`]).
    pub fn new(scenario: LandmarkScenario) -> Self {
        let session = LandmarkSession::new(scenario);
        let pending = session.scenario().clone();
        Self {
            session,
            pending,
            pending_issues: BTreeMap::new(),
            frame: LessonFrame::new(LESSON_ID, ViewOptions::default())
                .with_map(crate::widgets::map_canvas::MapView::default()),
            drive: drive::DriveState::default(),
            heatmap: heatmap::HeatmapState::default(),
            many_runs: many_runs::ManyRunsState::default(),
            version: 0,
            data: None,
            data_input: data::DataInput::default(),
            link_pairs: Vec::new(),
            reference: reference::ReferenceState::default(),
        }
    }

    /// The data set the run replays, if any.
    pub fn data(&self) -> Option<&data::LoadedData> {
        self.data.as_ref()
    }

    /// The recorded world being replayed, if any.
    pub fn recorded_world(&self) -> Option<&Arc<RecordedWorld>> {
        self.session.recorded_world()
    }

    /// A session of `scenario` in the current world: the data set's (its robot
    /// `scenario.robot` for MRCLAM) or the simulated one.
    fn start_session(&self, scenario: LandmarkScenario) -> Result<LandmarkSession, String> {
        match &self.data {
            None => Ok(LandmarkSession::new(scenario)),
            Some(loaded) => {
                let world = RecordedWorld::from_data(&loaded.data, scenario.robot)?;
                Ok(LandmarkSession::recorded(scenario, Arc::new(world)))
            }
        }
    }

    /// Opens a data set in place of the current world, with the data set's preset
    /// (its measured noise) and the panel's seed, then the link's own parameters
    /// when it came from `data=`. A world the data cannot give (a robot not in
    /// the files) leaves the current run as it was, with a note that says why.
    pub fn open_data(&mut self, loaded: data::LoadedData) {
        let kind = loaded.data.kind();
        let seed = self.pending.seed;
        let mut scenario = presets::scenario(presets::for_data(kind), seed).unwrap_or_default();
        if loaded.location.is_some() {
            let pairs = self
                .link_pairs
                .iter()
                .filter(|(k, _)| k != "preset")
                .map(|(k, v)| (k.as_str(), v.as_str()));
            let issues = params::apply_pairs(&mut scenario, pairs, &crate::query::APP_KEYS);
            self.frame
                .notices
                .extend(issues.iter().map(ToString::to_string));
        }
        let given = loaded.reference.clone();
        let previous = self.data.replace(loaded);
        match self.start_session(scenario) {
            Ok(session) => {
                let name = session
                    .recorded_world()
                    .map(|w| w.name.clone())
                    .unwrap_or_default();
                self.install(session);
                // MRCLAM's odometry comes at 67 Hz and Victoria Park's inputs at 40 Hz:
                // the fastest speed plays them at about real time or faster.
                self.frame.time.speed_tps = match kind {
                    DataSetKind::Freiburg => 10.0,
                    DataSetKind::Mrclam | DataSetKind::VictoriaPark => {
                        *crate::time_control::SPEED_RANGE.end()
                    }
                };
                self.frame.note = Some(format!("Opened {name} ({})", kind.name()));
                match given {
                    Some((file, text)) if kind == DataSetKind::VictoriaPark => {
                        self.reference.open(file, None, &text);
                    }
                    // A reference named by the link stays for Victoria Park.
                    _ if kind == DataSetKind::VictoriaPark && self.reference.location.is_some() => {
                    }
                    _ => self.reference = reference::ReferenceState::default(),
                }
            }
            Err(why) => {
                let name = self.data.as_ref().map(|d| d.name.clone());
                self.data = previous;
                self.frame.note = Some(format!(
                    "Could not open {}: {why}; the current world stays",
                    name.unwrap_or_default()
                ));
            }
        }
    }

    /// Opens the files of a data set as a drop or the picker hands them over; a
    /// refusal goes to the note and the current world stays.
    pub fn open_files(&mut self, files: Vec<crate::widgets::file_picker::PickedFile>) {
        self.arrived(data::read(files, None));
    }

    /// Leaves the data set for the simulated world, with the lesson's parameters.
    pub fn open_simulated_world(&mut self) {
        self.data = None;
        self.reference = reference::ReferenceState::default();
        let seed = self.pending.seed;
        self.pending = default_scenario();
        self.pending.seed = seed;
        self.pending_issues.clear();
        self.reset();
        self.frame.time.speed_tps = crate::time_control::TimeControl::default().speed_tps;
        self.frame.note = Some("Back in the simulated world".to_owned());
    }

    /// Runs `session` from its start in place of the current one.
    fn install(&mut self, session: LandmarkSession) {
        self.session = session;
        self.pending = self.session.scenario().clone();
        self.pending_issues.clear();
        self.frame.time.apply(TimeAction::Reset);
        self.drive.stop();
        self.frame.map.refit();
        self.version += 1;
    }

    /// Reads a data set that arrived (picked, dropped or from `data=`).
    fn poll_data(&mut self, ctx: &egui::Context) {
        if let Some(arrival) = self.data_input.poll(ctx) {
            self.arrived(arrival);
        }
        // One solver step a frame: Victoria Park's graph solves in about 150.
        self.reference.poll(ctx);
    }

    /// Victoria Park's reference map, read, being solved, or refused.
    pub fn reference(&self) -> &reference::ReferenceState {
        &self.reference
    }

    /// Solves the reference graph to the end at once (tests).
    pub fn finish_reference(&mut self) {
        self.reference.finish();
    }

    /// Opens what arrived, or says why it cannot be opened.
    fn arrived(&mut self, arrival: data::Arrival) {
        match arrival {
            data::Arrival::Data(loaded) => self.open_data(loaded),
            data::Arrival::Reference(name, text) => {
                if self.data_kind() == Some(DataSetKind::VictoriaPark) {
                    self.reference.open(name.clone(), None, &text);
                    self.frame.note = Some(format!("Solving {name} as the reference map"));
                } else {
                    self.frame.note = Some(format!(
                        "{name} is a pose graph of Victoria Park: open Victoria Park's inputs.dat, \
                         measurements.dat and gps.dat first (or drop the four files together)"
                    ));
                }
            }
            data::Arrival::Refused(why) => {
                let world = if self.data.is_some() {
                    "the data set stays open"
                } else {
                    "the simulated world stays open"
                };
                self.frame.note = Some(format!("{why}; {world}"));
            }
        }
    }

    /// The data set's kind, if a recorded world is open.
    pub fn data_kind(&self) -> Option<DataSetKind> {
        self.data.as_ref().map(|d| d.data.kind())
    }

    /// The running session (truth, sensor, filters).
    pub fn session(&self) -> &LandmarkSession {
        &self.session
    }

    /// The filters running, for the top bar: "EKF", "EKF vs UKF", "EKF, UKF and FEJ-EKF".
    pub fn filters_title(&self) -> String {
        let names: Vec<String> = self
            .session
            .filters()
            .iter()
            .map(|run| run.kind.name().to_uppercase())
            .collect();
        match names.as_slice() {
            [] => String::new(),
            [one] => one.clone(),
            [a, b] => format!("{a} vs {b}"),
            [init @ .., last] => format!("{} and {last}", init.join(", ")),
        }
    }

    /// The scenario being edited in the parameter panel (applied on reset).
    pub fn pending(&self) -> &LandmarkScenario {
        &self.pending
    }

    /// Sets one parameter of the pending scenario from text, exactly as the
    /// parameter panel's widgets do. The issue, if any, is shown beside the parameter.
    pub fn set_param(&mut self, name: &str, value: &str) -> Option<ParamIssue> {
        let issue = params::set(&mut self.pending, name, value);
        match &issue {
            Some(issue) => {
                self.pending_issues
                    .insert(name.to_owned(), issue.to_string());
            }
            None => {
                self.pending_issues.remove(name);
            }
        }
        issue
    }

    /// The message about the last value typed for `name`, if it had a problem.
    pub fn param_issue(&self, name: &str) -> Option<&str> {
        self.pending_issues.get(name).map(String::as_str)
    }

    /// Do the panel's parameters differ from the running ones? Who drives and the
    /// sensor's reach change live, the rest on reset.
    pub fn params_changed(&self) -> bool {
        params::to_pairs(&self.pending) != params::to_pairs(&self.session.scenario_now())
    }

    /// Sets a parameter from the panel and, if it is one that changes live (the
    /// sensor's field of view and range), hands it to the running session at once.
    pub fn set_param_live(&mut self, name: &str, value: &str) -> Option<ParamIssue> {
        let issue = self.set_param(name, value);
        if LIVE_PARAMS.contains(&name) {
            self.session
                .set_sensor_reach(self.pending.fov, self.pending.max_range);
            self.version += 1;
        }
        issue
    }

    /// Starts over with the pending parameters (same seed: same world and noise).
    pub fn reset(&mut self) {
        match self.start_session(self.pending.clone()) {
            Ok(session) => self.install(session),
            Err(why) => {
                self.frame.note = Some(format!("{why}; the run goes on as it was"));
            }
        }
    }

    /// Opens preset `id` with the panel's seed and restarts the run with it.
    pub fn open_preset(&mut self, id: &str) {
        if self.set_param("preset", id).is_none() {
            self.reset();
        }
    }

    /// Switches between the scripted circle and manual driving from the next tick
    /// on. The run goes on (map, filters, plots); a reset keeps the choice. Taking
    /// the wheel starts with the robot stopped; giving it back resumes the circle's
    /// speeds.
    pub fn set_manual_driving(&mut self, manual: bool) {
        let value = if manual { "manual" } else { "circle" };
        let _issue = params::set(&mut self.pending, "controller", value);
        let controller = if manual {
            ControllerKind::Manual
        } else {
            match (self.session.scenario().controller, self.pending.controller) {
                (circle @ ControllerKind::Circle { .. }, _) => circle,
                (_, pending) => pending,
            }
        };
        self.drive.stop();
        self.session.set_teleop(self.drive.command());
        self.session.set_controller(controller);
        self.version += 1;
    }

    /// Opens the "Many runs" window and starts `trials` runs of the current scenario.
    pub fn start_many_runs(&mut self, trials: usize) {
        self.frame.view.many_runs = true;
        self.many_runs.trials = trials;
        self.many_runs.start(&self.session);
    }

    /// Is the robot driven by hand?
    pub fn is_manual(&self) -> bool {
        matches!(self.session.controller(), ControllerKind::Manual)
    }

    /// Runs one phase.
    pub fn step_phase(&mut self) {
        self.apply_drive_command();
        self.session.step_phase();
        self.version += 1;
    }

    /// Finishes the tick, or runs a whole one.
    pub fn step_tick(&mut self) {
        self.apply_drive_command();
        self.session.step_tick();
        self.version += 1;
    }

    /// Can the run go back one phase quickly? Going back replays the run from the
    /// session's latest checkpoint before it (usually at most 50 ticks); a replay
    /// that would freeze the page (huge maps, or far behind the oldest checkpoint)
    /// is not offered.
    pub fn can_step_back(&self) -> bool {
        let state = 3 + 2 * self.session.world().landmarks.len() as u64;
        let cost = self
            .session
            .step_back_replay_length()
            .saturating_mul(state.saturating_mul(state));
        self.session.phases_run() > 0 && cost <= 2_000_000_000
    }

    /// Runs the ticks the clock owes after `dt` seconds of real time, phase by phase,
    /// within the frame budget (so that even 500 landmarks keep the page responsive).
    pub fn advance(&mut self, dt: f64) {
        if self.frame.time.running {
            self.apply_drive_command();
        }
        let session = &mut self.session;
        let mut phases = 0_u64;
        lesson::advance_within_budget(&mut self.frame.time, dt, || {
            session.step_phase();
            phases += 1;
            !session.is_mid_tick()
        });
        if phases > 0 {
            self.version += 1;
        }
    }

    /// Gives the session the manual-driving command.
    fn apply_drive_command(&mut self) {
        self.session.set_teleop(self.drive.command());
    }

    /// The time bar's view of the clock.
    pub fn time_info(&self) -> TimeInfo {
        TimeInfo {
            tick: self.session.tick(),
            time_s: self.session.time(),
            last_phase: self.session.last_phase().map(|p| p.label()),
            next_phase: self.next_phase_label(),
            can_step_back: self.can_step_back(),
        }
    }

    /// The phase a "Step phase" runs next: the pending one, or the next tick's predict.
    pub fn next_phase_label(&self) -> String {
        match self.session.next_phase() {
            Some(phase) => phase.label(),
            None => "predict (new tick)".to_owned(),
        }
    }

    /// Pairs of the pending scenario that differ from the lesson's defaults, for saving.
    pub fn pending_pairs(&self) -> Vec<(String, String)> {
        changed_pairs(&self.pending)
    }

    /// Does anything need another frame soon (running, a drive key held, the
    /// "Many runs" window at work)?
    pub fn wants_repaint(&self) -> bool {
        self.frame.time.running
            || self.drive.is_active()
            || (self.frame.view.many_runs && self.many_runs.is_running())
            || self.reference.is_busy()
    }

    /// Reads the drive keys (arrows, WASD) while driving by hand. Starting to drive
    /// starts the clock.
    pub fn read_drive_keys(&mut self, ctx: &egui::Context) {
        if !self.is_manual() {
            self.drive.keys = None;
            return;
        }
        self.drive.keys = drive::keyboard_command(ctx);
        let active = self.drive.is_active();
        if active && !self.drive.was_active && !self.frame.time.running {
            self.frame.time.apply(TimeAction::ToggleRun);
        }
        self.drive.was_active = active;
    }

    /// The lesson's panels: parameters (left), explanation (right), plots (bottom)
    /// and the map (centre), plus the heatmap window.
    pub fn panels_ui(&mut self, ui: &mut egui::Ui, panels: &mut PanelVisibility, compact: bool) {
        crate::widgets::layout::lesson_panels_ui(self, ui, panels, compact, "landmark");
        if self.frame.view.heatmap {
            let mut open = true;
            // Beside the map where there is room (the right of the window), inside the
            // frame always: a lecture iframe of 800 x 500 included.
            let screen = ui.ctx().content_rect();
            let size = egui::vec2(
                440.0_f32.min(screen.width() - 16.0),
                560.0_f32.min(screen.height() - 40.0),
            );
            egui::Window::new("Covariance as correlations")
                .open(&mut open)
                .default_size(size)
                .default_pos(screen.right_top() + egui::vec2(-size.x - 8.0, 32.0))
                .constrain(true)
                .resizable(true)
                .show(ui.ctx(), |ui| {
                    heatmap::heatmap_ui(ui, &self.session, &mut self.heatmap, self.version);
                });
            self.frame.view.heatmap = open;
        }
        // Esc closes the windows over the map, the one on top (Many runs) first.
        if (self.frame.view.many_runs || self.frame.view.heatmap)
            && ui.input(|i| i.key_pressed(egui::Key::Escape))
        {
            if self.frame.view.many_runs {
                self.frame.view.many_runs = false;
            } else {
                self.frame.view.heatmap = false;
            }
        }
        if self.frame.view.many_runs {
            let mut open = true;
            // As large as it needs, as small as a lecture page's iframe.
            let screen = ui.ctx().content_rect();
            let size = egui::vec2(
                640.0_f32.min(screen.width() - 16.0),
                560.0_f32.min(screen.height() - 40.0),
            );
            egui::Window::new("Consistency over many runs")
                .open(&mut open)
                .default_size(size)
                .default_pos(screen.center() - 0.5 * size)
                .constrain(true)
                .resizable(true)
                .show(ui.ctx(), |ui| {
                    egui::ScrollArea::vertical()
                        .id_salt("many_runs_scroll")
                        .show(ui, |ui| {
                            many_runs::many_runs_ui(ui, &mut self.many_runs, &self.session);
                        });
                });
            self.frame.view.many_runs = open;
        }
    }

    fn landmark_parameters_ui(&mut self, ui: &mut egui::Ui) {
        data::world_ui(ui, self);
        ui.separator();
        if self.data.is_some() {
            // A recorded robot drives itself.
            if params_panel::parameters_ui(ui, self) {
                self.reset();
            }
            return;
        }
        let manual_before = self.is_manual();
        let mut manual = manual_before;
        drive::drive_panel_ui(
            ui,
            &mut self.drive,
            &mut manual,
            self.session.scenario().wheel_base,
        );
        if manual != manual_before {
            self.set_manual_driving(manual);
        }
        ui.separator();
        if params_panel::parameters_ui(ui, self) {
            self.reset();
        }
    }
}

impl crate::widgets::layout::LessonPanels for LandmarkSlamLesson {
    fn plots_ui(&mut self, ui: &mut egui::Ui) {
        plots::plots_ui(ui, &self.session);
    }

    fn parameters_ui(&mut self, ui: &mut egui::Ui) {
        self.landmark_parameters_ui(ui);
    }

    fn explanation_ui(&mut self, ui: &mut egui::Ui) {
        explain::explanation_ui(ui, &self.session);
    }

    fn map_ui(&mut self, ui: &mut egui::Ui) {
        let overlay = if self.data_kind() == Some(DataSetKind::VictoriaPark) {
            self.reference.overlay(&self.session, self.version).cloned()
        } else {
            None
        };
        map::map_ui(
            ui,
            &self.session,
            overlay.as_ref(),
            &mut self.frame.map,
            &mut self.frame.view,
            &mut self.drive,
        );
    }
}

impl Lesson for LandmarkSlamLesson {
    crate::lesson::frame_accessors!();

    fn trajectories(&self) -> Vec<slamlab_sim::metrics::NamedTrajectory> {
        slamlab_sim::landmark_slam::export::trajectories(&self.session)
    }

    fn landmark_maps(&self) -> Vec<(String, Vec<slamlab_sim::io::trajectory::LandmarkRow>)> {
        slamlab_sim::landmark_slam::export::landmarks(&self.session)
    }

    fn changed_params(&self) -> Vec<(String, String)> {
        self.pending_pairs()
    }

    /// The query string (without `?`) that opens this setup: the lesson, the share
    /// pairs, `many-runs=N` while the "Many runs" window is open, and `embed=1` if asked.
    fn share_query(&self, embed: bool) -> String {
        let mut pairs = self.share_pairs();
        if self.frame.view.many_runs {
            pairs.push(("many-runs".to_owned(), self.many_runs.trials.to_string()));
        }
        crate::query::build(LESSON_ID, &pairs, embed)
    }

    /// `key=value` pairs that reproduce the running setup: the seed and every
    /// parameter that differs from the lesson's start (which a link opens on).
    /// A data set read from `data=` is named again by its location; one dropped
    /// or picked cannot be (the link opens the simulated world then).
    fn share_pairs(&self) -> Vec<(String, String)> {
        let mut pairs = lesson::with_seed(
            changed_pairs(&self.session.scenario_now()),
            self.session.scenario().seed,
        );
        if let Some(location) = self.data.as_ref().and_then(|d| d.location.clone()) {
            if let Some(reference) = self.reference.location.clone() {
                pairs.insert(0, (reference::REFERENCE_KEY.to_owned(), reference));
            }
            pairs.insert(0, (data::DATA_KEY.to_owned(), location));
        }
        pairs
    }

    /// What the session had to change, and the errors of the latest phase.
    fn run_notices(&self) -> Vec<String> {
        let mut notices = Vec::new();
        notices.extend(self.session.notices().iter().cloned());
        notices.extend(
            self.session
                .filters()
                .iter()
                .filter_map(|run| run.last_error.clone()),
        );
        notices
    }

    /// Does what a time-bar button or shortcut asks.
    fn on_time_action(&mut self, action: TimeAction) {
        match action {
            TimeAction::ToggleRun => {}
            TimeAction::StepPhase => self.step_phase(),
            TimeAction::StepTick => self.step_tick(),
            TimeAction::StepBack => {
                if self.can_step_back() && self.session.step_back() {
                    self.version += 1;
                }
            }
            TimeAction::Reset => self.reset(),
        }
    }

    fn keys(&self) -> Vec<(&'static str, &'static str)> {
        crate::widgets::drive::DRIVE_KEYS.to_vec()
    }

    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        plots::series(&self.session)
    }

    fn subtitle(&self) -> String {
        self.filters_title()
    }

    fn time_info(&self) -> TimeInfo {
        LandmarkSlamLesson::time_info(self)
    }

    fn read_input(&mut self, ctx: &egui::Context) {
        self.poll_data(ctx);
        self.read_drive_keys(ctx);
    }

    fn advance(&mut self, dt: f64) {
        LandmarkSlamLesson::advance(self, dt);
    }

    fn wants_repaint(&self) -> bool {
        LandmarkSlamLesson::wants_repaint(self)
    }

    fn panels_ui(&mut self, ui: &mut egui::Ui, panels: &mut PanelVisibility, compact: bool) {
        LandmarkSlamLesson::panels_ui(self, ui, panels, compact);
    }

    fn view_menu_ui(&mut self, ui: &mut egui::Ui) {
        ui.checkbox(&mut self.frame.view.legend, "Map legend");
        ui.checkbox(&mut self.frame.view.heatmap, "Covariance heatmap");
        ui.checkbox(&mut self.frame.view.many_runs, "Many runs (average NEES)");
    }

    fn test_state(&self) -> serde_json::Value {
        let many_runs = self.many_runs.result().map(|r| {
            serde_json::json!({
                "done": r.trials_done,
                "running": self.many_runs.is_running(),
                "nees": r.filters.iter().map(|f| (f.name.clone(), f.nees_mean)).collect::<BTreeMap<_, _>>(),
            })
        });
        let session = self.session();
        let data = session.recorded_world().map(|world| {
            let (played, steps) = session.recorded_progress().unwrap_or_default();
            serde_json::json!({
                "name": world.name,
                "kind": world.kind.name(),
                "robot": world.robot,
                "mode": session.scenario().mode.name(),
                "played": played,
                "steps": steps,
                "finished": session.is_finished(),
                "truth_known": session.true_pose().is_some(),
                "gps": gps_fit_now(session),
            })
        });
        // The latest robot position error (m) against the truth, per filter, and
        // the RMSE over the ticks with a known truth; `null` without a truth.
        let errors: BTreeMap<&str, serde_json::Value> = session
            .filters()
            .iter()
            .map(|run| {
                let errors: Vec<f64> = run.history.iter().map(|m| m.position_error).collect();
                let rmse = (!errors.is_empty()).then(|| {
                    (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt()
                });
                (
                    run.kind.name(),
                    serde_json::json!({
                        "latest": run.latest().map(|m| m.position_error),
                        "rmse": rmse,
                        "samples": errors.len(),
                    }),
                )
            })
            .collect();
        serde_json::json!({
            "tick": session.tick(),
            "time": session.time(),
            "phase": session.last_phase().map(|p| p.label()).unwrap_or_default(),
            "seed": session.scenario().seed,
            "filters": session.filters().iter().map(|run| run.kind.name()).collect::<Vec<_>>(),
            "many_runs": many_runs,
            "data": data,
            "loading_data": self.data_input.is_fetching(),
            "reference": self.reference.is_given().then(|| self.reference.test_state(session)),
            "position_error": errors,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn share_pairs_hold_the_seed_and_the_changes() {
        let mut scenario = default_scenario();
        let _ = params::set(&mut scenario, "seed", "7");
        let _ = params::set(&mut scenario, "landmarks", "30");
        let lesson = LandmarkSlamLesson::new(scenario);
        assert_eq!(
            lesson.share_pairs(),
            vec![
                ("seed".to_owned(), "7".to_owned()),
                ("landmarks".to_owned(), "30".to_owned())
            ]
        );
    }

    /// The lesson a share link opens, read as the shell reads it (the shell's own
    /// path through the registry is tested in `tests/lessons/shell_ui.rs`).
    fn reopen(link: &str) -> Box<dyn Lesson> {
        let q = crate::query::Query::parse(link);
        assert_eq!(q.lesson.as_deref(), Some(LESSON_ID), "{link}");
        open(&LessonStart {
            pairs: &q.pairs,
            embed: q.embed,
            stored: None,
            many_runs: q.many_runs,
        })
    }

    #[test]
    fn a_shared_link_reopens_the_same_setup() {
        let setups: [&[(&str, &str)]; 4] = [
            &[],
            &[("estimator", "ekf")],
            &[
                ("estimator", "ekf,fej-ekf"),
                ("seed", "3"),
                ("range-std", "0.1"),
            ],
            &[("preset", "thesis-exp2"), ("landmarks", "35")],
        ];
        for setup in setups {
            let mut scenario = default_scenario();
            let issues = params::apply_pairs(&mut scenario, setup.iter().copied(), &[]);
            assert!(issues.is_empty(), "{setup:?}: {issues:?}");
            let mut lesson = LandmarkSlamLesson::new(scenario);
            lesson.step_tick();
            // A live change of the sensor's reach is part of the setup too.
            assert!(lesson.set_param_live("fov-deg", "200").is_none());
            let link = lesson.share_query(true);
            let reopened = reopen(&link);
            let pairs = reopened
                .as_any()
                .downcast_ref::<LandmarkSlamLesson>()
                .map(|l| params::to_pairs(&l.session().scenario_now()));
            assert_eq!(
                pairs,
                Some(params::to_pairs(&lesson.session().scenario_now())),
                "{setup:?} shared as {link}"
            );
        }
    }

    #[test]
    fn the_share_link_opens_many_runs_when_its_window_is_open() {
        let mut lesson = LandmarkSlamLesson::new(default_scenario());
        assert_eq!(lesson.share_query(false), "lesson=landmark-slam&seed=1");
        lesson.frame.view.many_runs = true;
        lesson.many_runs.trials = 80;
        let link = lesson.share_query(true);
        assert_eq!(link, "lesson=landmark-slam&seed=1&many-runs=80&embed=1");
        let opened = reopen(&link);
        let reopened = opened.as_any().downcast_ref::<LandmarkSlamLesson>();
        assert!(reopened.is_some_and(|l| l.frame.view.many_runs && l.many_runs.trials == 80));
    }

    #[test]
    fn edits_wait_for_reset() {
        let mut lesson = LandmarkSlamLesson::new(LandmarkScenario::default());
        assert!(!lesson.params_changed());
        assert!(lesson.set_param("landmarks", "5").is_none());
        assert!(lesson.params_changed());
        assert_eq!(lesson.session().world().landmarks.len(), 20);
        assert!(lesson.set_param("landmarks", "9999").is_some());
        assert!(lesson.param_issue("landmarks").is_some());
        lesson.reset();
        assert!(!lesson.params_changed());
        assert_eq!(lesson.session().world().landmarks.len(), 500);
    }

    #[test]
    fn advancing_runs_whole_ticks() {
        let mut lesson = LandmarkSlamLesson::new(LandmarkScenario::default());
        lesson.frame.time.speed_tps = 10.0;
        lesson.apply_time_action(TimeAction::ToggleRun);
        lesson.advance(0.2);
        assert_eq!(lesson.session().tick(), 2);
        assert!(!lesson.session().is_mid_tick());
    }
}
