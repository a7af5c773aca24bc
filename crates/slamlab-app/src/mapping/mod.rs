//! The mapping lesson (`lesson=mapping`): a lidar's scans build an occupancy
//! grid, scan by scan, with each scan's pose from the truth (simulation only),
//! raw odometry, ICP against the previous scan, matching against the map so
//! far, or grid FastSLAM's particles (each with its own map). The scans come from a simulated robot exploring a built-in map or from
//! a real CARMEN log (dropped on the window, opened, or named by `log=`).
//! Switching the pose source replays the same scans from the start.

mod explain;
mod inspect;
mod map;
mod particles;
mod plots;

pub use particles::ShownMap;

use crate::laser_lesson::{LaserLesson, PendingReference};
use crate::lesson::{self, Lesson, LessonFrame, LessonRequest, LessonStart};
use crate::time_control::{TimeAction, TimeInfo};
use crate::widgets::laser_file::{LaserFileState, loaded_note};
use crate::widgets::laser_inputs::LaserInputs;
use crate::widgets::map_canvas::MapView;
use crate::widgets::params_panel::{self, PendingParams};
use crate::widgets::reference_track::ReferenceTrack;
use serde::{Deserialize, Serialize};
use slamlab_sim::grid::{LaserFile, MappingInput, builtin_map};
use slamlab_sim::mapping::{
    MappingEvent, MappingPhase, MappingScenario, MappingSession, PoseSource, simulated_input,
};
use slamlab_sim::params;
use slamlab_sim::stepper::Simulation;
use std::sync::Arc;

/// The lesson's id in URLs and the menu.
pub const LESSON_ID: &str = "mapping";

/// A cell of the built map is occupied in its ROS map above this probability
/// (map_server's `occupied_thresh`).
const ROS_OCCUPIED_ABOVE: f64 = 0.65;
/// A cell of the built map is free in its ROS map below this probability
/// (map_server's `free_thresh`).
const ROS_FREE_BELOW: f64 = 0.196;

/// The parameters the panel shows, in order (the rest are in the URL and CLI).
const PANEL_PARAMS: &[&str] = &[
    "seed",
    "steps",
    "rule",
    "resolution",
    "max-range-free",
    "l-occ",
    "l-free",
    "l-min",
    "l-max",
    "hit-probability",
    "miss-probability",
    "p-min",
    "p-max",
    "linear-search-window",
    "angular-search-window-deg",
    "translation-weight",
    "rotation-weight",
    "icp-max-distance",
    "icp-trim",
    "beams",
    "lidar-range",
    "range-std",
    "odometry-noise",
];

/// The parameters the panel shows with grid FastSLAM (gmapping's names).
const GRID_FASTSLAM_PARAMS: &[&str] = &[
    "seed",
    "steps",
    "particles",
    "proposal",
    "resample-threshold",
    "srr",
    "srt",
    "str",
    "stt",
    "lstep",
    "astep",
    "iterations",
    "lsigma",
    "ogain",
    "linear-update",
    "angular-update",
    "resolution",
    "rule",
    "max-range-free",
    "beams",
    "lidar-range",
    "range-std",
    "odometry-noise",
];

/// What the map shows; saved with the user's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MappingView {
    /// The legend line above the map.
    pub legend: bool,
    /// The current scan's rays and hit points.
    pub scan: bool,
    /// The estimated path.
    pub path: bool,
    /// The true path (simulation only).
    pub truth: bool,
    /// The true map, faint, under the built one (simulation only).
    pub true_map: bool,
    /// Keep the robot in the middle.
    pub follow_robot: bool,
}

crate::lesson::lesson_view!(MappingView, legend: legend, follow: follow_robot);

impl Default for MappingView {
    fn default() -> Self {
        Self {
            legend: true,
            scan: true,
            path: true,
            truth: true,
            true_map: false,
            follow_robot: false,
        }
    }
}

/// The mapping lesson.
#[derive(Debug)]
pub struct MappingLesson {
    session: MappingSession,
    pending: PendingParams<MappingScenario>,
    /// The input every pose source maps (kept when the source changes).
    input: Arc<MappingInput>,
    /// The log the input came from, if any: its name (or `log=` location).
    log_name: Option<String>,
    /// The location of a log read from `log=` (kept for share links).
    log_location: Option<String>,
    /// Replaying to this many scans after a change of pose source.
    catch_up: Option<usize>,
    /// Milliseconds each scan took (index = scan), as measured here.
    scan_ms: ScanTimes,
    /// The clock, the view, the map view, the notices and the requests.
    pub frame: LessonFrame<MappingView>,
    tiles: map::GridTiles,
    /// The files dropped, picked or named by the link (`log=`, `reference=`).
    inputs: LaserInputs,
    /// A reference (name, bytes, location) waiting for its log.
    pending_reference: Option<PendingReference>,
    /// Where the reference came from (`reference=`), for the share link.
    reference_location: Option<String>,
    /// The trajectory error against the reference as the run goes.
    track: ReferenceTrack,
    /// The log or bag being mapped: a bag's topics and what the reader assumed.
    laser: LaserFileState,
    /// The beam of the current scan whose update is inspected, if any.
    pub beam: Option<usize>,
    /// A ROS map the student loaded for the simulated robot to explore
    /// (instead of the scenario's built-in map): its name and grid.
    loaded_map: Option<(String, Arc<slamlab_core::grid::OccupancyGrid>)>,
    /// A built-in map was chosen in place of a log or a loaded map: the next
    /// reset simulates anew.
    builtin_chosen: bool,
    /// Grid FastSLAM: which particle's map is shown.
    pub shown: ShownMap,
    mean_map: particles::MeanMapCache,
    /// Whether the last advance ran a grid FastSLAM update phase (or a
    /// replay), for the frame timing.
    advanced_an_update: bool,
    /// The built map as a ROS map, with the revisions of the grid's tiles it
    /// was made from.
    ros_map: std::cell::RefCell<Option<(TileRevisions, Arc<slamlab_core::grid::OccupancyGrid>)>>,
}

/// A grid's tiles and their revisions: equal lists, equal grids (a revision
/// names one content of one tile, in any grid).
type TileRevisions = Vec<(i64, i64, u64)>;

/// How long each scan took here: the sum of its phases' times, however they
/// were stepped (phase by phase, a tick at once, or running).
#[derive(Debug, Default)]
struct ScanTimes {
    /// Milliseconds per scan (index = scan; NaN where not measured).
    ms: Vec<f64>,
    /// The phases of the scan under way so far.
    open: f64,
}

impl ScanTimes {
    /// Runs `step` on the session and books its time to the scan under way;
    /// a scan that finishes gets its total.
    fn timed(&mut self, session: &mut MappingSession, step: impl FnOnce(&mut MappingSession)) {
        let before = session.sim().scans_done();
        let started = web_time::Instant::now();
        step(session);
        self.open += started.elapsed().as_secs_f64() * 1e3;
        let after = session.sim().scans_done();
        if after > before {
            self.ms.resize(after, f64::NAN);
            self.ms[after - 1] = self.open;
            self.open = 0.0;
        }
    }
}

/// The lesson's start: the simulator's defaults.
pub fn default_scenario() -> MappingScenario {
    MappingScenario::default()
}

/// Opens the lesson from the URL's pairs, with what it stored last time.
pub fn open(start: &LessonStart<'_>) -> Box<dyn Lesson> {
    crate::laser_lesson::open(
        start,
        default_scenario(),
        MappingLesson::new,
        |l| &mut l.frame,
        "Mapping",
    )
}

impl MappingLesson {
    /// Starts the lesson on `scenario`: a simulated robot in its built-in map.
    pub fn new(scenario: MappingScenario) -> Result<Self, String> {
        let input = Arc::new(Self::simulate(&scenario)?);
        let (session, notices) = MappingSession::new(scenario, input.clone());
        let pending = PendingParams::new(session.scenario().clone());
        Ok(Self {
            session,
            pending,
            input,
            log_name: None,
            log_location: None,
            catch_up: None,
            scan_ms: ScanTimes::default(),
            frame: LessonFrame::new(LESSON_ID, MappingView::default())
                .with_map(MapView::growing())
                .with_notices(notices),
            tiles: map::GridTiles::default(),
            inputs: LaserInputs::default(),
            pending_reference: None,
            reference_location: None,
            track: ReferenceTrack::default(),
            laser: LaserFileState::default(),
            beam: None,
            loaded_map: None,
            builtin_chosen: false,
            shown: ShownMap::Best,
            mean_map: particles::MeanMapCache::default(),
            advanced_an_update: false,
            ros_map: std::cell::RefCell::default(),
        })
    }

    fn simulate(scenario: &MappingScenario) -> Result<MappingInput, String> {
        let name = if scenario.map == "office" {
            "office"
        } else {
            "maze"
        };
        let grid = builtin_map(name)?;
        simulated_input(scenario, Arc::new(grid), name)
    }

    /// The simulated input on the loaded map if there is one, else on the
    /// scenario's built-in map.
    fn simulate_current(&self, scenario: &MappingScenario) -> Result<MappingInput, String> {
        match &self.loaded_map {
            Some((name, grid)) => simulated_input(scenario, grid.clone(), name),
            None => Self::simulate(scenario),
        }
    }

    /// The session (the run, its records, its stepper).
    pub fn session(&self) -> &MappingSession {
        &self.session
    }

    /// The latest note under the map toolbar.
    pub fn note(&self) -> Option<&str> {
        self.frame.note.as_deref()
    }

    /// Sets a parameter of the pending scenario from text, as the panel does.
    pub fn set_param(&mut self, name: &str, value: &str) -> Option<params::ParamIssue> {
        self.pending.set(name, value)
    }

    /// Starts over with the pending parameters: a new simulated log if the
    /// simulation changed, the same scans otherwise (a loaded log stays).
    pub fn reset(&mut self) {
        let scenario = self.pending.scenario.clone();
        let running = self.session.scenario();
        let new_data = self.builtin_chosen
            || self.log_name.is_none()
                && (scenario.map != running.map
                    || scenario.steps != running.steps
                    || scenario.seed != running.seed
                    || scenario.beams != running.beams
                    || scenario.lidar_range != running.lidar_range
                    || scenario.range_std != running.range_std
                    || scenario.odometry_noise != running.odometry_noise);
        if new_data {
            match self.simulate_current(&scenario) {
                Ok(input) => self.input = Arc::new(input),
                Err(why) => {
                    self.frame.note = Some(format!("Could not start over: {why}; the run goes on"));
                    return;
                }
            }
        }
        self.builtin_chosen = false;
        self.restart(scenario, None);
    }

    /// A new session on the current input with `scenario`, replaying to
    /// `catch_up` scans if given.
    fn restart(&mut self, scenario: MappingScenario, catch_up: Option<usize>) {
        let (session, notices) = MappingSession::new(scenario, self.input.clone());
        self.pending = PendingParams::new(session.scenario().clone());
        self.session = session;
        self.frame.notices = notices;
        self.catch_up = catch_up.filter(|&n| n > 0);
        self.scan_ms = ScanTimes::default();
        self.tiles.clear();
        self.track.clear();
        self.mean_map.clear();
        if !matches!(self.shown, ShownMap::Mean) {
            self.shown = ShownMap::Best;
        }
        if catch_up.is_none() {
            self.frame.time.apply(TimeAction::Reset);
            self.frame.map.refit();
        }
    }

    /// Switches the pose source live: the same scans replay from the start
    /// with the new source up to where the run was.
    pub fn set_pose_source(&mut self, source: PoseSource) {
        if source == self.session.sim().source() {
            return;
        }
        if source == PoseSource::Truth && self.input.truth.is_none() {
            self.frame.note =
                Some("A real log has no true poses: choose another pose source".to_owned());
            return;
        }
        let done = self.session.sim().scans_done();
        let mut scenario = self.session.scenario().clone();
        scenario.poses = source;
        self.pending.scenario.poses = source;
        self.restart(scenario, Some(done));
        self.catch_up_note();
    }

    /// Stops mapping the same scans again (a step or step back), and its note.
    fn stop_catch_up(&mut self) {
        if self.catch_up.take().is_some() {
            self.frame.note = None;
        }
    }

    /// The note while the run maps the same scans again up to where it was; none
    /// once it is there (the map and the title then say it).
    fn catch_up_note(&mut self) {
        self.frame.note = self.catch_up.map(|target| {
            format!(
                "Mapping again with {}: scan {} of {target}…",
                self.session.sim().source().label(),
                self.session.sim().scans_done()
            )
        });
    }

    /// Maps a laser file (a CARMEN log, plain or compressed, or a ROS 2 bag)
    /// instead of the simulated robot. On any problem the current run stays,
    /// with a note that names it.
    pub fn load_log(&mut self, name: &str, bytes: &[u8]) {
        match self.laser.open(name, bytes) {
            Ok(file) => self.map_file(name, file),
            Err(why) => self.frame.note = Some(why),
        }
    }

    /// Maps an opened laser file.
    fn map_file(&mut self, name: &str, file: LaserFile) {
        let note = loaded_note(name, &file);
        let has_truth = file.input.truth.is_some();
        self.input = Arc::new(file.input);
        self.log_name = Some(name.to_owned());
        self.reference_location = None;
        let mut scenario = self.pending.scenario.clone();
        if scenario.poses == PoseSource::Truth && !has_truth {
            scenario.poses = PoseSource::ScanToMap;
        }
        self.restart(scenario, None);
        self.frame.note = Some(note);
        if let Some((reference, bytes, location)) = self.pending_reference.take() {
            self.load_reference(&reference, bytes, location);
        }
    }

    /// Brings the trajectory error against the reference up to the run.
    fn refresh_reference(&mut self) {
        let reference = self.input.reference.clone();
        let done = self.session.sim().scans_done();
        let session = &self.session;
        self.track
            .update(reference.as_deref(), done, || session.scan_poses());
    }

    /// Runs one phase (or catches up after a change of pose source).
    pub fn step_phase(&mut self) {
        self.scan_ms.timed(&mut self.session, |s| {
            s.stepper_mut().step_phase();
        });
    }

    /// Finishes the scan, or runs a whole one.
    pub fn step_tick(&mut self) {
        self.scan_ms
            .timed(&mut self.session, |s| s.stepper_mut().step_tick());
    }

    /// The built map as a ROS map: three states, occupied above 0.65 and free
    /// below 0.196 (map_server's thresholds); `None` while it is empty. What
    /// "Export map" writes and what a student's map is scored beside.
    pub fn built_ros_map(&self) -> Option<slamlab_core::grid::OccupancyGrid> {
        self.session
            .sim()
            .grid()
            .to_occupancy_grid(ROS_OCCUPIED_ABOVE, ROS_FREE_BELOW)
    }

    /// [`Self::built_ros_map`], converted again only after the grid changed:
    /// the same `Arc` while it has not (so "Your estimates", scoring the run
    /// every tick, compares the map with the truth once per change).
    pub fn built_ros_map_shared(&self) -> Option<Arc<slamlab_core::grid::OccupancyGrid>> {
        let change: TileRevisions = self.session.sim().grid().tile_revisions().collect();
        let mut cache = self.ros_map.borrow_mut();
        if let Some((seen, map)) = cache.as_ref()
            && *seen == change
        {
            return Some(map.clone());
        }
        let map = Arc::new(self.built_ros_map()?);
        *cache = Some((change, map.clone()));
        Some(map)
    }

    /// The built map as ROS map files (`slamlab-map.yaml` and `slamlab-map.pgm`),
    /// as "Export map" saves them.
    pub fn map_files(&self) -> Result<Vec<crate::export::ExportFile>, String> {
        let grid = self
            .built_ros_map()
            .ok_or("The map is empty: nothing to export yet")?;
        let (yaml, image) = slamlab_sim::io::ros_map::export_map(
            &grid,
            "slamlab-map.pgm",
            slamlab_sim::io::ros_map::ImageFormat::Pgm,
        )
        .map_err(|why| format!("Could not export the map: {why}"))?;
        Ok(vec![
            crate::export::ExportFile {
                name: "slamlab-map.yaml".to_owned(),
                mime: "text/yaml",
                bytes: yaml.into_bytes(),
            },
            crate::export::ExportFile {
                name: "slamlab-map.pgm".to_owned(),
                mime: "image/x-portable-graymap",
                bytes: image,
            },
        ])
    }

    /// The built map as a ROS map (YAML and PGM), for download.
    fn export_map(&mut self) {
        match self.map_files() {
            Ok(files) => self.frame.request = Some(LessonRequest::Save(files)),
            Err(why) => self.frame.note = Some(why),
        }
    }

    /// Opens the Monte Carlo localization lesson on the map built so far.
    fn localize_in_map(&mut self) {
        let Some(grid) = self.built_ros_map() else {
            self.frame.note = Some("The map is empty: map some scans first".to_owned());
            return;
        };
        let name = format!("the map built from {}", self.input.name);
        self.frame.request = Some(LessonRequest::LocalizeInMap { name, grid });
    }

    fn next_phase_label(&self) -> String {
        let sim = self.session.sim();
        if sim.is_done() {
            return "done: every scan is in".to_owned();
        }
        if sim.is_mid_tick() {
            "next phase of this scan".to_owned()
        } else {
            format!("scan {}", sim.scans_done())
        }
    }

    fn source_ui(&mut self, ui: &mut egui::Ui) {
        let current = self.session.sim().source();
        let mut chosen = current;
        ui.label("Pose source (live, same scans):");
        for source in PoseSource::ALL {
            let enabled = source != PoseSource::Truth || self.input.truth.is_some();
            ui.add_enabled_ui(enabled, |ui| {
                ui.radio_value(&mut chosen, source, source.label());
            });
        }
        if chosen != current {
            self.set_pose_source(chosen);
        }
        let icp = matches!(chosen, PoseSource::Icp | PoseSource::Plicp);
        let mut stepping = self.session.sim().steps_iterations();
        ui.add_enabled_ui(icp, |ui| {
            ui.checkbox(&mut stepping, "ICP one iteration per phase")
                .on_hover_text(
                    "Step phase (.) then shows each ICP iteration of a match on its own: the pairs \
                     it used and the pose it reached",
                );
        });
        self.set_iteration_stepping(stepping);
        if let Some(filter) = self.session.sim().grid_fastslam() {
            ui.separator();
            particles::particles_ui(ui, filter, &mut self.shown);
        }
    }

    /// Shows ICP matches one iteration per phase (or whole); switching it on
    /// follows the robot closely enough to see the pairs.
    pub fn set_iteration_stepping(&mut self, on: bool) {
        if on != self.session.sim().steps_iterations() {
            self.session
                .stepper_mut()
                .apply(MappingEvent::StepIterations(on));
            if on {
                self.look_closer(150.0);
            }
        }
    }

    /// Follows the robot at `scale` pixels per metre or closer.
    fn look_closer(&mut self, scale: f32) {
        self.frame.view.follow_robot = true;
        self.frame.map.zoom_to_at_least(scale);
    }

    fn mapping_parameters_ui(&mut self, ui: &mut egui::Ui) {
        ui.heading("Mapping with a lidar");
        self.source_ui(ui);
        ui.separator();
        ui.horizontal_wrapped(|ui| {
            if ui
                .button("Export map")
                .on_hover_text("Download the map built so far as a ROS map (YAML + PGM)")
                .clicked()
            {
                self.export_map();
            }
            if ui
                .button("Localize in this map")
                .on_hover_text("Open the Monte Carlo localization lesson on the map built so far")
                .clicked()
            {
                self.localize_in_map();
            }
        });
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("map");
            let current = self.pending.scenario.map.clone();
            egui::ComboBox::from_id_salt("mapping_map")
                .selected_text(match (&self.log_name, &self.loaded_map) {
                    (Some(name), _) | (None, Some((name, _))) => name.clone(),
                    (None, None) => current.clone(),
                })
                .show_ui(ui, |ui| {
                    for name in ["maze", "office"] {
                        let chosen =
                            current == name && self.log_name.is_none() && self.loaded_map.is_none();
                        if ui.selectable_label(chosen, name).clicked() {
                            self.builtin_chosen |=
                                self.log_name.is_some() || self.loaded_map.is_some();
                            self.log_name = None;
                            self.log_location = None;
                            self.laser.close();
                            self.loaded_map = None;
                            self.pending.set("map", name);
                        }
                    }
                })
                .response
                .on_hover_text(
                    "The built-in maps the simulated robot explores; press \"Apply & reset\"",
                )
                .widget_info(|| egui::WidgetInfo::labeled(egui::Role::ComboBox, true, "map"));
        });
        if let Some(result) = self.laser.topics_ui(ui) {
            match result {
                Ok(file) => {
                    let name = self.log_name.clone().unwrap_or_default();
                    self.map_file(&name, file);
                }
                Err(why) => self.frame.note = Some(why),
            }
        }
        ui.label(
            "Or open a CARMEN laser log (.clf, .log, .gz, .bz2), a ROS 2 bag (.mcap), or a ROS \
             map (its YAML with the image) for the robot to explore; or drop either on the window:",
        );
        self.inputs.picker_ui(ui);
        let running = self.session.scenario().clone();
        let shown_params = if self.pending.scenario.poses == PoseSource::GridFastSlam {
            GRID_FASTSLAM_PARAMS
        } else {
            PANEL_PARAMS
        };
        params_panel::params_ui(ui, &mut self.pending, &running, shown_params);
        ui.separator();
        let changed = self.pending.differs_from(&running)
            || self.builtin_chosen
            || self.log_name.is_some() && self.pending.scenario.map != running.map;
        if params_panel::apply_and_share_ui(
            ui,
            changed,
            "Start over with these parameters (same seed: same scans)",
            |embed| lesson::Lesson::share_query(self, embed),
            "index.html?… with these pairs opens exactly this run",
        ) {
            self.reset();
        }
    }

    /// Grid FastSLAM's numbers for the browser checks: the particles, the
    /// heaviest one's pose (compared bit for bit with the native run), and
    /// the time the update scans took here (`null` with another source).
    fn grid_fastslam_state(&self) -> serde_json::Value {
        let Some(filter) = self.session.sim().grid_fastslam() else {
            return serde_json::Value::Null;
        };
        let records = self.session.stepper().records();
        let mut update_ms: Vec<f64> = self
            .scan_ms
            .ms
            .iter()
            .zip(&records.neff)
            .filter(|(t, n)| t.is_finite() && n.is_finite())
            .map(|(t, _)| *t)
            .collect();
        update_ms.sort_by(f64::total_cmp);
        let best = filter.best().map(|p| [p.pose.x, p.pose.y, p.pose.theta]);
        serde_json::json!({
            "particles": filter.particles().len(),
            "proposal": filter.config().proposal.name(),
            "updates": filter.updates(),
            "resamplings": filter.resamplings(),
            "neff": filter.neff(),
            "memory_mb": filter.memory_bytes() as f64 / 1e6,
            "best": best,
            "shown": match self.shown {
                ShownMap::Best => serde_json::json!("best"),
                ShownMap::Mean => serde_json::json!("mean"),
                ShownMap::Particle(i) => serde_json::json!(i),
            },
            "update_scans_timed": update_ms.len(),
            "update_ms_median": update_ms.get(update_ms.len() / 2),
        })
    }
}

impl LaserLesson for MappingLesson {
    fn open_log(&mut self, name: &str, bytes: &[u8]) {
        self.load_log(name, bytes);
    }
    fn open_linked_log(&mut self, name: &str, bytes: &[u8], location: String) {
        self.load_log(name, bytes);
        if self.log_name.as_deref() == Some(name) {
            self.log_location = Some(location);
            // The link's figure keys (`run=1`, `tick=`) hold for the log.
            self.frame.restarted_from_link = true;
        }
    }
    fn logged_input(&self) -> Option<Arc<MappingInput>> {
        self.log_name.as_ref().map(|_| self.input.clone())
    }
    fn pending_reference(&mut self) -> &mut Option<PendingReference> {
        &mut self.pending_reference
    }
    fn restart_with_reference(&mut self, input: Arc<MappingInput>, location: Option<String>) {
        self.input = input;
        self.reference_location = location;
        let scenario = self.session.scenario().clone();
        self.restart(scenario, None);
    }

    /// Lets the simulated robot explore a ROS map (map_server YAML with its
    /// PGM or PNG image) instead of a built-in one. On any problem the current
    /// run stays, with a note that names it.
    fn load_map_files(&mut self, files: &[(String, Vec<u8>)]) {
        let Some((name, grid, notes)) = self.read_map(files) else {
            return;
        };
        let scenario = self.pending.scenario.clone();
        let scenario = MappingScenario {
            poses: if scenario.poses == PoseSource::Truth || self.log_name.is_none() {
                scenario.poses
            } else {
                PoseSource::ScanToMap
            },
            ..scenario
        };
        match simulated_input(&scenario, grid.clone(), &name) {
            Ok(input) => {
                let (w, h, r) = (grid.width(), grid.height(), grid.resolution());
                self.input = Arc::new(input);
                self.loaded_map = Some((name.clone(), grid));
                self.log_name = None;
                self.log_location = None;
                self.laser.close();
                self.restart(scenario, None);
                self.frame.note = Some(format!(
                    "The robot explores {name}: {w} x {h} cells at {r} m{}",
                    if notes.is_empty() {
                        String::new()
                    } else {
                        format!(" ({})", notes.join("; "))
                    }
                ));
            }
            Err(why) => {
                self.frame.note =
                    Some(format!("Could not drive in {name}: {why}; the run goes on"));
            }
        }
    }

    fn laser_file(&mut self) -> &mut LaserFileState {
        &mut self.laser
    }
    fn laser_inputs(&mut self) -> &mut LaserInputs {
        &mut self.inputs
    }
}

impl crate::widgets::layout::LessonPanels for MappingLesson {
    fn plots_ui(&mut self, ui: &mut egui::Ui) {
        self.refresh_reference();
        plots::plots_ui(ui, &self.session, &self.scan_ms.ms, &self.track);
    }

    fn parameters_ui(&mut self, ui: &mut egui::Ui) {
        self.mapping_parameters_ui(ui);
    }

    fn explanation_ui(&mut self, ui: &mut egui::Ui) {
        explain::explanation_ui(ui, &self.session);
        inspect::iteration_ui(ui, &self.session);
        let inspecting = self.beam.is_some();
        inspect::beam_ui(ui, &self.session, &mut self.beam);
        if self.beam.is_some() && !inspecting {
            // Cells of 5 cm: about 8 pixels each.
            self.look_closer(160.0);
        }
    }

    fn map_ui(&mut self, ui: &mut egui::Ui) {
        self.refresh_reference();
        // While a beam is inspected the run keeps the grid from before each
        // insertion, to explain a scan already in (a new run or a step back
        // starts without it).
        if self.session.sim().keeps_grid_before_insert() != self.beam.is_some() {
            self.session
                .stepper_mut()
                .sim_mut_untracked()
                .keep_grid_before_insert(self.beam.is_some());
        }
        let sim = self.session.sim();
        let mean = match sim.grid_fastslam() {
            Some(filter) if self.shown == ShownMap::Mean => self
                .mean_map
                .get(filter, self.session.stepper().phases_run()),
            _ => None,
        };
        let (grid, highlighted) = match sim.grid_fastslam() {
            Some(filter) if !filter.particles().is_empty() => {
                let highlighted = match self.shown {
                    ShownMap::Best => Some(filter.best_index()),
                    ShownMap::Particle(i) => Some(i.min(filter.particles().len() - 1)),
                    ShownMap::Mean => None,
                };
                let grid = particles::shown_grid(filter, self.shown, mean.as_deref());
                (grid.unwrap_or(sim.grid()), highlighted)
            }
            _ => (sim.grid(), None),
        };
        if let Some(clicked) = map::map_ui(
            ui,
            &self.session,
            &mut self.frame.map,
            &mut self.tiles,
            &mut self.frame.view,
            self.beam,
            grid,
            highlighted,
            &self.track,
        ) {
            self.shown = ShownMap::Particle(clicked);
        }
    }
}

impl Lesson for MappingLesson {
    crate::lesson::frame_accessors!();

    fn trajectories(&self) -> Vec<slamlab_sim::metrics::NamedTrajectory> {
        slamlab_sim::mapping::export::trajectories(&self.session)
    }

    fn scores_maps(&self) -> bool {
        self.input.true_map.is_some()
    }

    fn occupancy_maps(&self) -> Vec<(String, Arc<slamlab_core::grid::OccupancyGrid>)> {
        let Some(truth) = &self.input.true_map else {
            return Vec::new();
        };
        let mut maps = vec![("truth".to_owned(), truth.clone())];
        if let Some(built) = self.built_ros_map_shared() {
            // Beside its path's row, which has the estimator's name.
            maps.push((
                format!("{} (map)", self.session.sim().source().name()),
                built,
            ));
        }
        maps
    }

    fn share_pairs(&self) -> Vec<(String, String)> {
        let scenario = self.session.scenario();
        let mut pairs = lesson::with_seed(
            params::changed_pairs(scenario, &default_scenario()),
            scenario.seed,
        );
        pairs.extend(crate::laser_lesson::share_pairs(
            self.log_location.as_deref(),
            self.reference_location.as_deref(),
            &self.laser,
        ));
        pairs
    }

    fn subtitle(&self) -> String {
        format!(
            "{} with {}",
            self.input.name,
            self.session.sim().source().label()
        )
    }

    fn run_notices(&self) -> Vec<String> {
        let mut all: Vec<String> = self.laser.notices().to_vec();
        all.extend(self.session.sim().note().map(str::to_owned));
        all
    }

    fn changed_params(&self) -> Vec<(String, String)> {
        params::changed_pairs(&self.pending.scenario, &default_scenario())
    }

    fn time_info(&self) -> TimeInfo {
        let sim = self.session.sim();
        let last = sim.scans_done().checked_sub(1);
        TimeInfo {
            tick: sim.scans_done() as u64,
            time_s: last
                .and_then(|k| sim.input().scans.get(k))
                .map_or(0.0, |s| s.time),
            last_phase: self.session.stepper().last_phase().map(MappingPhase::label),
            next_phase: self.next_phase_label(),
            can_step_back: self.session.stepper().phases_run() > 0,
        }
    }

    fn on_time_action(&mut self, action: TimeAction) {
        match action {
            TimeAction::ToggleRun => {}
            TimeAction::StepPhase => self.step_phase(),
            TimeAction::StepTick => self.step_tick(),
            TimeAction::StepBack => {
                self.stop_catch_up();
                self.scan_ms.open = 0.0;
                self.session.stepper_mut().step_back();
            }
            TimeAction::Reset => {
                let scenario = self.session.scenario().clone();
                self.restart(scenario, None);
            }
        }
    }

    fn read_input(&mut self, ctx: &egui::Context) {
        self.read_laser_inputs(ctx);
    }

    fn advance(&mut self, dt: f64) {
        self.advanced_an_update = false;
        if let Some(target) = self.catch_up {
            self.advanced_an_update = true;
            // Replay after a change of pose source, within the frame budget.
            let started = web_time::Instant::now();
            while self.session.sim().scans_done() < target
                && !self.session.sim().is_done()
                && started.elapsed().as_millis() < 12
            {
                self.step_tick();
            }
            if self.session.sim().scans_done() >= target || self.session.sim().is_done() {
                self.catch_up = None;
            }
            self.catch_up_note();
            return;
        }
        if self.session.sim().is_done() {
            self.frame.time.running = false;
            return;
        }
        let session = &mut self.session;
        let scan_ms = &mut self.scan_ms;
        let mut updated = false;
        lesson::advance_within_budget(&mut self.frame.time, dt, || {
            scan_ms.timed(session, |s| {
                updated |= s.stepper_mut().step_phase().is_filter_update();
            });
            !session.sim().is_mid_tick()
        });
        self.advanced_an_update = updated;
    }

    fn last_advance_updated(&self) -> bool {
        self.advanced_an_update
    }

    fn wants_repaint(&self) -> bool {
        self.frame.time.running || self.catch_up.is_some() || self.inputs.is_fetching()
    }

    fn view_menu_ui(&mut self, ui: &mut egui::Ui) {
        ui.checkbox(&mut self.frame.view.legend, "Map legend");
        ui.checkbox(&mut self.frame.view.scan, "Current scan");
        ui.checkbox(&mut self.frame.view.path, "Estimated path");
        ui.checkbox(&mut self.frame.view.truth, "True path");
        ui.checkbox(&mut self.frame.view.true_map, "True map underneath");
    }

    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        plots::series(&self.session, &self.scan_ms.ms, &self.track)
    }

    fn test_state(&self) -> serde_json::Value {
        let summary = self.session.summary();
        let pose = self
            .session
            .sim()
            .current()
            .map(|(_, _, p)| [p.x, p.y, p.theta]);
        serde_json::json!({
            "tick": summary.scans,
            "scans": summary.scans,
            "total_scans": self.input.scans.len(),
            "input_seconds": self.input.duration(),
            "log": self.log_name,
            "reference": self.input.reference.as_deref().map(|r| serde_json::json!({
                "name": r.name,
                "matched": r.points.len(),
                "scans": r.reference_scans,
                "ate_m": self.track.latest().map(|p| p[1]),
                "ate_at_scan": self.track.latest().map(|p| p[0]),
                "ate_points": self.track.ate.len(),
                "path_points": self.track.path.len(),
            })),
            "topics": self.laser.topics().map(|t| [t.scan.clone(), t.odometry.clone()]),
            "note": self.frame.note,
            "seed": self.session.scenario().seed,
            "poses": summary.poses,
            "input": summary.input,
            "pose": pose,
            "trajectory_rmse": summary.trajectory_rmse,
            "map_agreement": summary.map_agreement,
            "known_cells": summary.map.known_cells,
            "catching_up": self.catch_up.is_some(),
            "phase": self.session.stepper().last_phase().map(MappingPhase::label).unwrap_or_default(),
            "grid_fastslam": self.grid_fastslam_state(),
        })
    }
}
