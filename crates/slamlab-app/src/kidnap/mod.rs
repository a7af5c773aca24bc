//! The Monte Carlo localization lesson (`lesson=kidnap`): a round robot with a
//! lidar explores a grid map (the built-in maze or office, or a ROS map the
//! student drops on the window) and a cloud of particles finds it and follows it,
//! one phase at a time: *move* (the robot, its odometry and a scan), *predict*
//! (the cloud spreads), *weight* (each particle's scan likelihood) and *resample*
//! (copies replace the unlikely). The robot can be kidnapped at any moment.
//!
//! Or the filters localize a recorded robot: a CARMEN log or a ROS 2 bag opened
//! (picker, drop, `log=`) through the laser lessons' shared widget, replayed
//! scan by scan in the map on screen (built-in, loaded, or the mapping lesson's
//! *Localize in this map*), against the bag's truth where it has one.

mod explain;
mod map;
mod plots;

use crate::lesson::{self, Lesson, LessonFrame, LessonStart};
use crate::palette;
use crate::time_control::{TimeAction, TimeInfo};
use crate::widgets::drive::{self, PadDirection};
use crate::widgets::dropped_files::DropInbox;
use crate::widgets::fetch::{self, Fetch, LinkedFile};
use crate::widgets::file_picker::{FilePicker, PickedFile};
use crate::widgets::laser_file::{LASER_FILE_TYPES, LaserFileState, loaded_note};
use crate::widgets::map_canvas::MapView;
use crate::widgets::params_panel::{self, PendingParams};
use egui::Color32;
use serde::{Deserialize, Serialize};
use slamlab_core::grid::OccupancyGrid;
use slamlab_sim::grid::laser_file::MAX_LASER_FILE_BYTES;
use slamlab_sim::grid::{LaserFile, MappingInput};
use slamlab_sim::kidnap::session::{KidnapEvent, KidnapSim};
use slamlab_sim::kidnap::{MclPhase, MclScenario};
use slamlab_sim::params;
use slamlab_sim::stepper::{Simulation, Stepper};

/// The lesson's id in URLs and the menu.
pub const LESSON_ID: &str = "kidnap";

/// The parameters the panel shows, in order (the rest are in the URL and CLI).
const PANEL_PARAMS: &[&str] = &[
    "seed",
    "estimator",
    "particles",
    "init",
    "laser-model-type",
    "laser-max-beams",
    "laser-sigma-hit",
    "laser-z-hit",
    "laser-z-rand",
    "laser-likelihood-exponent",
    "odom-alpha1",
    "odom-alpha2",
    "odom-alpha3",
    "odom-alpha4",
    "update-min-d",
    "update-min-a-deg",
    "resampler",
    "resample-interval",
    "lidar-beams",
    "lidar-max-range",
    "lidar-range-std",
    "robot-radius",
    "kidnap-distance",
];

/// The colour of filter `k` named `name` (LESSONS.md: particle filters purple,
/// costmap-aware ones green; a second plain filter orange).
pub fn filter_color(k: usize, name: &str) -> Color32 {
    match name {
        "cmcl" | "acmcl" => palette::GREEN,
        _ if k == 0 => palette::PURPLE,
        _ => palette::ORANGE,
    }
}

/// What the map shows; saved with the user's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct KidnapView {
    /// The legend box.
    pub legend: bool,
    /// The lidar's rays and hits.
    pub rays: bool,
    /// The particles.
    pub particles: bool,
    /// The true path.
    pub path: bool,
    /// Keep the true robot in the middle.
    pub follow_robot: bool,
    /// The costmap's invalid zone in pink.
    pub costmap: bool,
    /// A click on the map kidnaps the robot (instead of panning).
    #[serde(skip)]
    pub click_kidnap: bool,
}

crate::lesson::lesson_view!(KidnapView, legend: legend, follow: follow_robot);

impl Default for KidnapView {
    fn default() -> Self {
        Self {
            legend: true,
            rays: true,
            particles: true,
            path: true,
            follow_robot: false,
            costmap: false,
            click_kidnap: false,
        }
    }
}

/// The lesson's start: the simulator's defaults.
pub fn default_scenario() -> MclScenario {
    MclScenario::default()
}

/// An image without its YAML: it needs a resolution before it is a map.
#[derive(Debug)]
struct LoneImage {
    name: String,
    bytes: Vec<u8>,
    /// Metres per pixel, as typed.
    resolution: f64,
}

/// The Monte Carlo localization lesson.
#[derive(Debug)]
pub struct KidnapLesson {
    stepper: Stepper<KidnapSim>,
    pending: PendingParams<MclScenario>,
    /// A map the student loaded (name, grid); used instead of the built-in one.
    loaded: Option<(String, OccupancyGrid)>,
    /// The clock, the view, the map view and the notices.
    pub frame: LessonFrame<KidnapView>,
    texture: map::GridTexture,
    drag: map::KidnapDrag,
    /// Maps dropped on the window, while they are read.
    inbox: DropInbox,
    /// A lone image dropped or opened without its YAML, waiting for its resolution.
    lone_image: Option<LoneImage>,
    /// "Open map, log or bag…": a map's YAML with its image, or a CARMEN log or a ROS 2 bag.
    map_picker: FilePicker,
    /// `map=` named a ROS map YAML (a URL beside the site, a path on the
    /// desktop): where it is, and its reading, stage by stage.
    map_location: Option<MapFetch>,
    /// The pad button held this frame (driving by hand).
    pad: Option<PadDirection>,
    /// The latest command sent to the run while driving by hand.
    sent: Option<(f64, f64)>,
    /// A recorded robot the filters localize instead of the simulated one: the
    /// file's name and its scans (kept when the map or the parameters change).
    log: Option<(String, MappingInput)>,
    /// The log or bag open: a bag's topics and what the reader assumed.
    laser: LaserFileState,
    /// `log=` named a log or bag: where it is, read after the first frame.
    log_fetch: Option<LinkedFile>,
    /// The location of a log read from `log=` (kept for share links).
    log_location: Option<String>,
}

/// A ROS map read from a location named in the URL: first its YAML, then the
/// image the YAML names, relative to it.
#[derive(Debug)]
struct MapFetch {
    /// The YAML's location as the URL gave it (kept for share links).
    location: String,
    /// Not started yet (it starts with the first frame, which has the context).
    started: bool,
    /// The YAML, once read.
    yaml: Option<Vec<u8>>,
    /// The read under way.
    fetch: Fetch,
    /// The map was loaded from here.
    loaded: bool,
}

/// Does a `map=` value name a ROS map YAML rather than a built-in map?
pub fn is_map_location(value: &str) -> bool {
    let lower = value.to_ascii_lowercase();
    lower.ends_with(".yaml") || lower.ends_with(".yml")
}

/// Opens the lesson from the URL's pairs, with what it stored last time.
pub fn open(start: &LessonStart<'_>) -> Box<dyn Lesson> {
    // `map=maps/lab.yaml`: a ROS map beside the site, read after the first frame;
    // the lesson opens on the default map meanwhile.
    let location = start
        .pairs
        .iter()
        .rev()
        .find(|(k, v)| k == "map" && is_map_location(v))
        .map(|(_, v)| v.clone());
    let log_location = start.last_value("log");
    let (laser, pairs) = LaserFileState::from_link(start.pairs, |k, v| {
        (k == "map" && is_map_location(v)) || k == "log"
    });
    let start = &LessonStart {
        pairs: &pairs,
        ..*start
    };
    let opened = lesson::open_lesson(start, default_scenario(), KidnapLesson::new, |l| {
        &mut l.frame
    });
    let mut lesson = match opened {
        Ok(lesson) => lesson,
        // Only a broken build could get here (the built-in maze is tested); the
        // landmark lesson opens instead, saying why.
        Err(why) => {
            return lesson::open_instead(
                start,
                format!("Monte Carlo localization could not open: {why}"),
            );
        }
    };
    // An embed keeps the legend on: without it a lecture figure's particle clouds,
    // rays and ellipses are unexplained (`legend=0` hides it).
    if start.embed {
        lesson.frame.view.legend = true;
    }
    lesson.laser = laser;
    if let Some(location) = log_location {
        lesson.frame.note = Some(format!("Loading the log {location}…"));
        lesson.log_fetch = Some(LinkedFile::new(location));
    }
    if let Some(location) = location {
        lesson.frame.note = Some(format!("Loading the map {location}…"));
        lesson.map_location = Some(MapFetch {
            location,
            started: false,
            yaml: None,
            fetch: Fetch::default(),
            loaded: false,
        });
    }
    Box::new(lesson)
}

/// Opens the lesson on `grid` (a map another lesson built), named `name` in
/// the notes; the default scenario otherwise. A map the robot cannot be placed
/// in leaves the maze, with a note that says why.
pub fn open_with_map(name: String, grid: OccupancyGrid) -> Box<dyn Lesson> {
    match KidnapLesson::new(default_scenario()) {
        Ok(mut lesson) => {
            lesson.use_loaded_map(name, grid, &[]);
            Box::new(lesson)
        }
        Err(why) => lesson::open_instead(
            &LessonStart {
                pairs: &[],
                embed: false,
                stored: None,
                many_runs: None,
            },
            format!("Monte Carlo localization could not open: {why}"),
        ),
    }
}

impl KidnapLesson {
    /// Starts the lesson on `scenario` (its map by name; the maze if that map
    /// cannot hold the robot).
    pub fn new(scenario: MclScenario) -> Result<Self, String> {
        let (sim, notices) = KidnapSim::open(scenario, None)?;
        let pending = PendingParams::new(sim.run().scenario().clone());
        Ok(Self {
            stepper: Stepper::new(sim, ()),
            pending,
            loaded: None,
            frame: LessonFrame::new(LESSON_ID, KidnapView::default())
                .with_map(MapView::default())
                .with_notices(notices),
            texture: map::GridTexture::default(),
            drag: map::KidnapDrag::default(),
            inbox: DropInbox::default(),
            map_picker: FilePicker::multiple(),
            lone_image: None,
            map_location: None,
            pad: None,
            sent: None,
            log: None,
            laser: LaserFileState::default(),
            log_fetch: None,
            log_location: None,
        })
    }

    /// The running simulation.
    pub fn sim(&self) -> &KidnapSim {
        self.stepper.sim()
    }

    /// The latest note under the map toolbar (a refusal, what a load did).
    pub fn note(&self) -> Option<&str> {
        self.frame.note.as_deref()
    }

    /// The scenario being edited in the parameter panel (applied on reset).
    pub fn pending(&self) -> &MclScenario {
        &self.pending.scenario
    }

    /// Sets a parameter of the pending scenario from text, as the panel does.
    pub fn set_param(&mut self, name: &str, value: &str) -> Option<params::ParamIssue> {
        self.pending.set(name, value)
    }

    /// Starts over with the pending parameters (and the loaded map, if any).
    pub fn reset(&mut self) {
        let grid = self.loaded.as_ref().map(|(_, g)| g.clone());
        let scenario = self.pending.scenario.clone();
        let opened = match &self.log {
            Some((name, input)) => KidnapSim::open_log(scenario, grid, input.clone())
                .map_err(|why| format!("{name}: {why}")),
            None => KidnapSim::open(scenario, grid),
        };
        let (sim, notices) = match opened {
            Ok(opened) => opened,
            Err(why) => {
                self.frame.note = Some(format!("Could not start over: {why}; the run goes on"));
                return;
            }
        };
        self.pending = PendingParams::new(sim.run().scenario().clone());
        self.stepper = Stepper::new(sim, ());
        self.frame.notices = notices;
        self.frame.note = None;
        self.frame.time.apply(TimeAction::Reset);
        self.texture.clear();
        self.frame.map.refit();
    }

    /// Applies a live event (a kidnap, scattering the particles) to the run; it is
    /// recorded, so stepping back and forth replays it.
    pub fn apply_event(&mut self, event: KidnapEvent) {
        if let KidnapEvent::KidnapTo(pose) = event
            && let Err(why) = self.stepper.sim().check_kidnap(&pose)
        {
            self.frame.note = Some(format!("Kidnap refused: {why}"));
            return;
        }
        self.frame.note = Some(event.describe());
        self.stepper.apply(event);
    }

    /// Runs one phase.
    pub fn step_phase(&mut self) {
        self.stepper.step_phase();
    }

    /// Finishes the tick, or runs a whole one.
    pub fn step_tick(&mut self) {
        self.stepper.step_tick();
    }

    /// Localizes a recorded robot: a laser file (a CARMEN log, plain or
    /// compressed, or a ROS 2 bag) replayed in the map on screen. On any problem
    /// the current run stays, with a note that names it.
    pub fn load_log(&mut self, name: &str, bytes: &[u8]) {
        match self.laser.open(name, bytes) {
            Ok(file) => self.localize_file(name, file),
            Err(why) => self.frame.note = Some(why),
        }
    }

    /// Replays an opened laser file in the map on screen.
    fn localize_file(&mut self, name: &str, file: LaserFile) {
        let note = loaded_note(name, &file);
        let before = self.log.replace((name.to_owned(), file.input));
        self.reset();
        if self.sim().run().log().is_none() {
            // The run could not start on it: the lesson keeps what it had.
            let why = self.frame.note.take().unwrap_or_default();
            self.log = before;
            self.laser.close();
            self.frame.note = Some(format!("Could not localize in {name}: {why}"));
            return;
        }
        self.frame.note = Some(format!("{note}; localizing in {}", self.map_name()));
    }

    /// Back to the simulated robot (the map stays).
    pub fn close_log(&mut self) {
        if self.log.take().is_some() {
            self.laser.close();
            self.log_location = None;
            self.reset();
            self.frame.note = Some("The simulated robot again".to_owned());
        }
    }

    /// The log or bag the filters localize, if any: its name.
    pub fn log_name(&self) -> Option<&str> {
        self.log.as_ref().map(|(name, _)| name.as_str())
    }

    /// Reads the log named by `log=`.
    fn poll_log_fetch(&mut self, ctx: &egui::Context) {
        // The map named by `map=` first, so that the log replays in it.
        if self.map_location.as_ref().is_some_and(|m| !m.loaded) {
            return;
        }
        let Some((location, result)) = LinkedFile::poll(&mut self.log_fetch, ctx) else {
            return;
        };
        match result {
            Ok(bytes) => {
                let name = fetch::file_name(&location).to_owned();
                self.load_log(&name, &bytes);
                if self.log_name() == Some(name.as_str()) {
                    self.log_location = Some(location);
                    self.frame.restarted_from_link = true;
                }
            }
            Err(why) => {
                self.frame.note = Some(format!(
                    "Could not load the log {location}: {why}; the simulated robot runs instead"
                ));
            }
        }
    }

    /// Loads a map the student dropped on the window: a ROS map_server YAML with
    /// its image, or a lone image at the pending `resolution`. On any problem the
    /// current map and run stay, with a note that names it.
    pub fn load_dropped(&mut self, files: &[(String, Vec<u8>)]) {
        // A lone image has no resolution: ask for it before loading.
        let is = |name: &str, exts: &[&str]| {
            let lower = name.to_ascii_lowercase();
            exts.iter().any(|e| lower.ends_with(e))
        };
        if let [(name, bytes)] = files
            && is(name, &[".pgm", ".png"])
        {
            self.lone_image = Some(LoneImage {
                name: name.clone(),
                bytes: bytes.clone(),
                resolution: slamlab_sim::kidnap::session::LONE_IMAGE_RESOLUTION,
            });
            self.frame.note = Some(format!(
                "{name} has no YAML: give its resolution (metres per pixel) above the map and press Load"
            ));
            return;
        }
        match slamlab_sim::kidnap::session::load_dropped_map(files) {
            Ok((name, grid, notes)) => self.use_loaded_map(name, grid, &notes),
            Err(why) => self.frame.note = Some(format!("Could not load the map: {why}")),
        }
    }

    /// The lone image waiting for its resolution, if any: its name and the
    /// resolution typed so far.
    pub fn lone_image(&self) -> Option<(&str, f64)> {
        self.lone_image
            .as_ref()
            .map(|l| (l.name.as_str(), l.resolution))
    }

    /// Loads the waiting lone image at `resolution` metres per pixel (origin at 0).
    pub fn load_lone_image(&mut self, resolution: f64) {
        let Some(image) = self.lone_image.take() else {
            return;
        };
        match slamlab_sim::io::ros_map::load_lone_image(&image.bytes, resolution) {
            Ok(grid) => self.use_loaded_map(
                image.name,
                grid,
                &["its origin at (0, 0), as no YAML gives one".to_owned()],
            ),
            Err(why) => {
                self.frame.note = Some(format!("Could not load {}: {why}", image.name));
                self.lone_image = Some(image);
            }
        }
    }

    /// Restarts the run on a loaded map, with a note that describes it.
    fn use_loaded_map(&mut self, name: String, grid: OccupancyGrid, notes: &[String]) {
        let note = format!(
            "Loaded {name}: {} x {} cells at {} m{}",
            grid.width(),
            grid.height(),
            grid.resolution(),
            if notes.is_empty() {
                String::new()
            } else {
                format!(" ({})", notes.join("; "))
            }
        );
        // The scenario keeps a built-in map's name (a loaded file cannot travel in a
        // link); the run uses the loaded grid.
        self.loaded = Some((name, grid));
        self.map_location = None;
        self.lone_image = None;
        self.reset();
        let note = match self.log_name() {
            Some(log) => format!("{note}; localizing {log} in it"),
            None => note,
        };
        self.frame.note = Some(note);
    }

    /// A picked map YAML with the image it names, read from beside it (natively the
    /// picker gives one file; in the browser the student picks both).
    #[cfg_attr(target_arch = "wasm32", allow(clippy::unused_self))]
    fn with_named_image(&self, batch: Vec<PickedFile>) -> Vec<PickedFile> {
        #[cfg(not(target_arch = "wasm32"))]
        let mut batch = batch;
        #[cfg(not(target_arch = "wasm32"))]
        {
            let yaml_image = batch.iter().find_map(|(name, bytes)| {
                let lower = name.to_ascii_lowercase();
                let text = bytes
                    .as_ref()
                    .ok()
                    .and_then(|b| std::str::from_utf8(b).ok())?;
                (lower.ends_with(".yaml") || lower.ends_with(".yml"))
                    .then(|| slamlab_sim::io::ros_map::parse_map_yaml(text).ok())
                    .flatten()
                    .map(|yaml| yaml.image)
            });
            if let (Some(image), Some(folder)) = (yaml_image, self.map_picker.folder()) {
                let path = folder.join(&image);
                let name = path
                    .file_name()
                    .map_or_else(|| image.clone(), |n| n.to_string_lossy().into_owned());
                let bytes = std::fs::read(&path)
                    .map_err(|e| format!("the image {} beside the YAML: {e}", path.display()));
                batch.push((name, bytes));
            }
        }
        batch
    }

    /// Reads the map named by `map=` stage by stage: the YAML, then its image.
    fn poll_map_location(&mut self, ctx: &egui::Context) {
        let Some(state) = self.map_location.as_mut() else {
            return;
        };
        if state.loaded {
            return;
        }
        if !state.started {
            state.started = true;
            state.fetch = Fetch::start(&state.location, ctx);
            return;
        }
        let Some(result) = state.fetch.poll() else {
            return;
        };
        let location = state.location.clone();
        let fail = |lesson: &mut Self, why: String| {
            lesson.frame.note = Some(format!(
                "Could not load the map {location}: {why}; showing the {}",
                lesson.sim().run().scenario().map
            ));
            lesson.map_location = None;
        };
        let bytes = match result {
            Ok(bytes) => bytes,
            Err(why) => return fail(self, why),
        };
        let yaml_name = fetch::file_name(&location).to_owned();
        match state.yaml.take() {
            None => {
                // The YAML: find the image it names and read that next.
                let image = std::str::from_utf8(&bytes)
                    .map_err(|_| "it is not text".to_owned())
                    .and_then(|text| {
                        slamlab_sim::io::ros_map::parse_map_yaml(text).map_err(|e| e.to_string())
                    });
                match image {
                    Ok(parsed) => {
                        let image = fetch::relative_to(&location, &parsed.image);
                        state.yaml = Some(bytes);
                        state.fetch = Fetch::start(&image, ctx);
                    }
                    Err(why) => fail(self, why),
                }
            }
            Some(yaml) => {
                // The image: load both as if they had been dropped together.
                let image_name = {
                    let text = String::from_utf8_lossy(&yaml);
                    slamlab_sim::io::ros_map::parse_map_yaml(&text)
                        .map(|p| fetch::file_name(&p.image).to_owned())
                        .unwrap_or_default()
                };
                self.load_dropped(&[(yaml_name, yaml), (image_name, bytes)]);
                if self.loaded.is_some() {
                    self.frame.restarted_from_link = true;
                    self.map_location = Some(MapFetch {
                        location,
                        started: true,
                        yaml: None,
                        fetch: Fetch::default(),
                        loaded: true,
                    });
                } else {
                    self.map_location = None;
                }
            }
        }
    }

    /// The map on screen: `maze`, `office`, or a loaded file's name.
    pub fn map_name(&self) -> String {
        match &self.loaded {
            Some((name, _)) => name.clone(),
            None => self.sim().run().scenario().map.clone(),
        }
    }

    fn next_phase_label(&self) -> String {
        match self.sim().run().next_phase() {
            MclPhase::Move => "move (new tick)".to_owned(),
            phase => phase_name(phase).to_owned(),
        }
    }

    /// Is the robot driven by hand (rather than by the explorer)?
    pub fn driving_by_hand(&self) -> bool {
        self.sim().run().manual().is_some()
    }

    /// Takes the wheel (`true`: by hand, the robot stops until told) or gives it
    /// back to the explorer; recorded like any live event.
    pub fn set_driving_by_hand(&mut self, by_hand: bool) {
        if by_hand == self.driving_by_hand() {
            return;
        }
        let event = if by_hand {
            KidnapEvent::Drive(0.0, 0.0)
        } else {
            KidnapEvent::Explore
        };
        self.frame.note = Some(if by_hand {
            "Driving by hand: hold the arrow keys or WASD, or the pad above the map".to_owned()
        } else {
            event.describe()
        });
        self.sent = None;
        self.stepper.apply(event);
    }

    /// Sends the held keys' or pad's command to the run when what is held
    /// changed; a command to move starts the clock.
    fn drive_by_hand(&mut self, keys: Option<slamlab_core::Control>) {
        if !self.driving_by_hand() {
            self.sent = None;
            return;
        }
        let command = keys
            .or(self.pad.map(PadDirection::command))
            .map_or((0.0, 0.0), |c| (c.v, c.w));
        // Only a change of what is held is an event: stepping back replays the
        // recorded commands untouched while nothing is pressed.
        if self.sent == Some(command) {
            return;
        }
        if self.sent.is_some() || self.sim().run().manual() != Some(command) {
            self.stepper.apply(KidnapEvent::Drive(command.0, command.1));
        }
        if command != (0.0, 0.0) {
            self.frame.time.running = true;
        }
        self.sent = Some(command);
    }

    fn driving_ui(&mut self, ui: &mut egui::Ui) {
        let mut by_hand = self.driving_by_hand();
        ui.horizontal(|ui| {
            ui.label("Driving");
            ui.radio_value(&mut by_hand, false, "Explorer")
                .on_hover_text("The robot tours seeded waypoints through the free space");
            ui.radio_value(&mut by_hand, true, "By hand").on_hover_text(
                "Arrow keys or WASD, or the pad above the map: forward/back 1 m/s, turn 45°/s",
            );
        });
        self.set_driving_by_hand(by_hand);
    }

    /// The lesson's main actions, in the row above the map at every window size
    /// (never only in a closed drawer).
    fn actions_ui(&mut self, ui: &mut egui::Ui) {
        let recorded = self.log.is_some();
        let has_truth = self.sim().run().has_truth();
        ui.horizontal_wrapped(|ui| {
            if ui
                .button("Global localization")
                .on_hover_text("Scatter every filter's particles uniformly over the free space")
                .clicked()
            {
                self.apply_event(KidnapEvent::GlobalLocalization);
            }
            if ui
                .add_enabled(has_truth, egui::Button::new("Reset around truth"))
                .on_hover_text("Every filter's particles around the true pose (tracking)")
                .on_disabled_hover_text("This log has no truth: no true pose to reset around")
                .clicked()
            {
                self.apply_event(KidnapEvent::ResetAroundTruth);
            }
            if ui
                .add_enabled(!recorded, egui::Button::new("Kidnap"))
                .on_hover_text("Teleport the robot to a random free pose at least kidnap-distance away; the filters are not told")
                .on_disabled_hover_text("A recorded robot cannot be kidnapped: the log says where it went")
                .clicked()
            {
                self.apply_event(KidnapEvent::KidnapRandom);
            }
            if let Some((name, _)) = &self.log {
                let progress = self
                    .sim()
                    .run()
                    .log_progress()
                    .map_or(String::new(), |(done, all)| format!(": scan {done} of {all}"));
                ui.label(format!("Replaying {name}{progress}"));
                if ui
                    .button("Simulated robot")
                    .on_hover_text("Close the log: the simulated robot explores this map again")
                    .clicked()
                {
                    self.close_log();
                }
            }
        });
    }

    /// Each filter's status ("MCL: tracking (0.12 m off)") in its colour, one line
    /// each, then what a kidnap shows: above the map at every window size, so the
    /// student sees tracking or lost without opening the explanation. After a
    /// kidnap that no filter of the run can recover from, the last line says so
    /// and which filter can, with a button that runs it beside them.
    fn status_ui(&mut self, ui: &mut egui::Ui) {
        let run = self.sim().run();
        let lines: Vec<(String, Color32)> = run
            .filters()
            .iter()
            .enumerate()
            .map(|(k, f)| {
                (
                    format!("{}: {}", f.name.to_uppercase(), run.status_of(k)),
                    filter_color(k, f.name),
                )
            })
            .collect();
        for (text, color) in lines {
            one_line(ui, egui::RichText::new(text).color(color).strong());
        }
        let verdict = recovery_verdict(run);
        let compare = ui
            .horizontal(|ui| {
                let asks = matches!(verdict, Verdict::CannotRecover { .. });
                let room = ui.available_width() - if asks { 150.0 } else { 0.0 };
                ui.allocate_ui_with_layout(
                    egui::vec2(room.max(40.0), ui.spacing().interact_size.y),
                    egui::Layout::left_to_right(egui::Align::Center),
                    |ui| {
                        let text = verdict.text();
                        let text = match verdict {
                            Verdict::CannotRecover { .. } => egui::RichText::new(text)
                                .color(palette::VERMILLION)
                                .strong(),
                            _ => egui::RichText::new(text).weak(),
                        };
                        ui.add(egui::Label::new(text).truncate())
                            .on_hover_text(verdict.reason());
                    },
                );
                asks && ui
                    .button("Compare with ACMCL")
                    .on_hover_text(
                        "Start over with ACMCL beside these filters, the kidnap scheduled at the \
                         same tick, and run back to this tick: one robot, one set of scans and \
                         one kidnap for all the filters",
                    )
                    .clicked()
            })
            .inner;
        if compare && let Verdict::CannotRecover { kidnap_tick, .. } = verdict {
            self.compare_with_acmcl(kidnap_tick);
        }
    }

    /// Starts over with ACMCL beside the run's filters and the kidnap scheduled at
    /// `kidnap_tick`, then runs to where the run was.
    pub fn compare_with_acmcl(&mut self, kidnap_tick: u64) {
        use slamlab_sim::kidnap::LocalizationEstimator;
        let now = self.sim().run().tick_count();
        let mut scenario = self.sim().run().scenario().clone();
        if !scenario.estimators.contains(&LocalizationEstimator::Acmcl) {
            scenario.estimators.push(LocalizationEstimator::Acmcl);
        }
        scenario.kidnap_at = Some(kidnap_tick);
        self.pending = PendingParams::new(scenario);
        self.reset();
        for _ in 0..now {
            self.step_tick();
        }
    }

    fn kidnap_parameters_ui(&mut self, ui: &mut egui::Ui) {
        ui.heading("Monte Carlo localization");
        ui.label("Kidnap, Global localization and Reset around truth are above the map.");
        if self.log.is_none() {
            self.driving_ui(ui);
        }
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("map");
            let current = self.pending.scenario.map.clone();
            egui::ComboBox::from_id_salt("kidnap_map")
                .selected_text(self.map_name())
                .show_ui(ui, |ui| {
                    for name in ["maze", "office"] {
                        if ui.selectable_label(current == name, name).clicked() {
                            self.loaded = None;
                            self.map_location = None;
                            self.pending.set("map", name);
                        }
                    }
                })
                .response
                .on_hover_text("The built-in maps; press \"Apply & reset\" to open one")
                .widget_info(|| egui::WidgetInfo::labeled(egui::Role::ComboBox, true, "map"));
        });
        if let Some(result) = self.laser.topics_ui(ui) {
            match result {
                Ok(file) => {
                    let name = self.log_name().unwrap_or_default().to_owned();
                    self.localize_file(&name, file);
                }
                Err(why) => self.frame.note = Some(why),
            }
        }
        ui.label(
            "Or open a ROS map (its .yaml and .pgm/.png together), or a recorded robot to \
             localize in the map: a CARMEN laser log (.clf, .log, .gz, .bz2) or a ROS 2 bag \
             (.mcap); or drop either on the window:",
        );
        self.map_picker.ui(
            ui,
            "Open map, log or bag…",
            LASER_FILE_TYPES,
            MAX_LASER_FILE_BYTES as usize,
            "path/to/map.yaml",
        );
        let running = self.sim().run().scenario().clone();
        params_panel::params_ui(ui, &mut self.pending, &running, PANEL_PARAMS);
        ui.separator();
        if params_panel::apply_and_share_ui(
            ui,
            self.pending.differs_from(&running),
            "Start over with these parameters (same seed: same run)",
            |embed| lesson::Lesson::share_query(self, embed),
            "index.html?… with these pairs opens exactly this run",
        ) {
            self.reset();
        }
    }
}

/// Each filter's status line ("AMCL: lost: 3.2 m off, …"), as the explanation
/// panel shows it.
pub fn explain_status(lesson: &KidnapLesson) -> Vec<String> {
    let run = lesson.sim().run();
    run.filters()
        .iter()
        .enumerate()
        .map(|(k, f)| format!("{}: {}", f.name.to_uppercase(), run.status_of(k)))
        .collect()
}

/// What the run shows about finding the robot again.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// No kidnap yet.
    NotKidnapped,
    /// Kidnapped at this tick; a filter of the run can find the robot again.
    Kidnapped(u64),
    /// Kidnapped at `kidnap_tick`, and no filter of the run can find the robot
    /// again (`names`: theirs).
    CannotRecover {
        /// The kidnap's tick.
        kidnap_tick: u64,
        /// The run's filters, "MCL" or "MCL and AMCL".
        names: String,
    },
}

impl Verdict {
    /// What the line above the map says.
    pub fn text(&self) -> String {
        match self {
            Verdict::NotKidnapped => {
                "Kidnap (above) carries the robot elsewhere; the filters are not told".to_owned()
            }
            Verdict::Kidnapped(tick) => format!(
                "Kidnapped at tick {tick}: a costmap-aware filter can find the robot again \
                 (its status above says when)"
            ),
            Verdict::CannotRecover { names, .. } if names == "MCL" => "MCL adds no particles: \
                 it finds the robot again only if some lie near its new place. ACMCL \
                 regenerates them:"
                .to_owned(),
            Verdict::CannotRecover { names, .. } => format!(
                "{names} seldom add particles (AMCL only while its mean weight falls): the robot \
                 is found again only if some lie near its new place. ACMCL regenerates them:"
            ),
        }
    }

    /// Why (on hover).
    pub fn reason(&self) -> &'static str {
        match self {
            Verdict::NotKidnapped => {
                "The filters are not told of a kidnap: watch whether they notice."
            }
            Verdict::Kidnapped(_) => {
                "CMCL and ACMCL regenerate, at every update, the particles their costmap rules out \
                 (thesis Algorithms 10-11), so some land near the robot's new place."
            }
            Verdict::CannotRecover { .. } => {
                "MCL never adds a particle: after a kidnap it finds the robot again only if some \
                 of its particles happen to lie near the new place (a cloud not yet collapsed). \
                 AMCL injects random particles only while its short-term mean weight is below \
                 its long-term one, which the lesson's tempered scan likelihood seldom allows \
                 (docs/kidnap.md: in six runs it never injected). ACMCL regenerates the \
                 particles its costmap rules out at every update."
            }
        }
    }
}

/// Whether the run's filters can find the robot again after its kidnap: a
/// costmap-aware filter (CMCL, ACMCL) regenerates the particles its costmap rules
/// out at every update; plain MCL never adds a particle, and AMCL injects only
/// while its short-term mean weight is below the long-term one, which the
/// lesson's tempered scan likelihood seldom allows (docs/kidnap.md).
pub fn recovery_verdict(run: &slamlab_sim::kidnap::MclRun) -> Verdict {
    use slamlab_sim::kidnap::LocalizationEstimator as E;
    let Some(kidnap_tick) = run.kidnap_tick() else {
        return Verdict::NotKidnapped;
    };
    let estimators = &run.scenario().estimators;
    if estimators.iter().any(|e| matches!(e, E::Cmcl | E::Acmcl)) {
        return Verdict::Kidnapped(kidnap_tick);
    }
    let names: Vec<String> = estimators.iter().map(|e| e.name().to_uppercase()).collect();
    Verdict::CannotRecover {
        kidnap_tick,
        names: names.join(" and "),
    }
}

/// `text` on one line cut to the room there is (the whole on hover).
fn one_line(ui: &mut egui::Ui, text: egui::RichText) {
    ui.add(egui::Label::new(text).truncate());
}

/// The run's time now, seconds: ticks of `dt` for the simulated robot, the
/// last scan's time since the log's first for a recorded one.
fn run_time(run: &slamlab_sim::kidnap::MclRun) -> f64 {
    match run.log_progress() {
        Some((0, _)) => 0.0,
        Some((done, _)) => run.tick_time(done - 1),
        None => run.tick_count() as f64 * run.scenario().dt,
    }
}

/// A phase's name on screen.
fn phase_name(phase: MclPhase) -> &'static str {
    match phase {
        MclPhase::Move => "move",
        MclPhase::Predict => "predict",
        MclPhase::Weight => "weight",
        MclPhase::Resample => "resample",
    }
}

impl crate::widgets::layout::LessonPanels for KidnapLesson {
    fn plots_ui(&mut self, ui: &mut egui::Ui) {
        plots::plots_ui(ui, self.stepper.sim().run());
    }

    fn parameters_ui(&mut self, ui: &mut egui::Ui) {
        self.kidnap_parameters_ui(ui);
    }

    fn explanation_ui(&mut self, ui: &mut egui::Ui) {
        explain::explanation_ui(
            ui,
            self.stepper.sim().run(),
            self.stepper.last_phase().copied(),
        );
    }

    fn map_ui(&mut self, ui: &mut egui::Ui) {
        self.actions_ui(ui);
        self.status_ui(ui);
        let mut lone_action = None;
        if let Some(image) = &mut self.lone_image {
            ui.horizontal_wrapped(|ui| {
                let label = ui.label(format!("{}: metres per pixel", image.name));
                ui.add(
                    egui::DragValue::new(&mut image.resolution)
                        .range(0.001..=10.0)
                        .speed(0.001)
                        .fixed_decimals(3),
                )
                .labelled_by(label.id);
                if ui.button("Load").clicked() {
                    lone_action = Some(true);
                }
                if ui.button("Cancel").clicked() {
                    lone_action = Some(false);
                }
            });
        }
        match lone_action {
            Some(true) => {
                let resolution = self.lone_image.as_ref().map_or(0.05, |i| i.resolution);
                self.load_lone_image(resolution);
            }
            Some(false) => {
                self.lone_image = None;
                self.frame.note = None;
            }
            None => {}
        }
        self.pad = None;
        if self.driving_by_hand() {
            let press = drive::pad_ui(ui);
            if press.stop {
                self.stepper.apply(KidnapEvent::Drive(0.0, 0.0));
                self.sent = Some((0.0, 0.0));
            }
            self.pad = press.held;
        }
        let request = map::map_ui(
            ui,
            self.stepper.sim().run(),
            &mut self.frame.map,
            &mut self.texture,
            &mut self.frame.view,
            &mut self.drag,
        );
        if let Some(map::MapRequest::KidnapTo(pose)) = request {
            self.apply_event(KidnapEvent::KidnapTo(pose));
        }
    }
}

impl Lesson for KidnapLesson {
    crate::lesson::frame_accessors!();

    fn trajectories(&self) -> Vec<slamlab_sim::metrics::NamedTrajectory> {
        slamlab_sim::kidnap::export::trajectories(self.sim().run())
    }

    fn share_pairs(&self) -> Vec<(String, String)> {
        let scenario = self.sim().run().scenario();
        let mut pairs = lesson::with_seed(
            params::changed_pairs(scenario, &default_scenario()),
            scenario.seed,
        );
        // A map read from a location travels in the link as that location.
        if let Some(fetch) = self.map_location.as_ref().filter(|f| f.loaded) {
            pairs.retain(|(name, _)| name != "map");
            pairs.push(("map".to_owned(), fetch.location.clone()));
        }
        if let Some(location) = self.log_location.as_ref().filter(|_| self.log.is_some()) {
            pairs.push(("log".to_owned(), location.clone()));
            pairs.extend(self.laser.share_pairs());
        }
        pairs
    }

    fn keys(&self) -> Vec<(&'static str, &'static str)> {
        crate::widgets::drive::DRIVE_KEYS.to_vec()
    }

    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        plots::series(self.stepper.sim().run())
    }

    fn subtitle(&self) -> String {
        let run = self.sim().run();
        let names: Vec<String> = run
            .filters()
            .iter()
            .map(|f| f.name.to_uppercase())
            .collect();
        let map = match &self.loaded {
            Some((name, _)) => name.clone(),
            None => format!("the {}", self.map_name()),
        };
        match self.log_name() {
            Some(log) => format!("{} on {log} in {map}", names.join(" vs ")),
            None => format!("{} on {map}", names.join(" vs ")),
        }
    }

    fn run_notices(&self) -> Vec<String> {
        let mut all: Vec<String> = self.laser.notices().to_vec();
        all.extend(self.sim().run().notes().iter().rev().take(3).cloned());
        all
    }

    fn changed_params(&self) -> Vec<(String, String)> {
        params::changed_pairs(&self.pending.scenario, &default_scenario())
    }

    fn time_info(&self) -> TimeInfo {
        let run = self.sim().run();
        TimeInfo {
            tick: run.tick_count(),
            time_s: run_time(run),
            last_phase: self.stepper.last_phase().map(|p| phase_name(*p).to_owned()),
            next_phase: self.next_phase_label(),
            can_step_back: self.stepper.phases_run() > 0,
        }
    }

    fn on_time_action(&mut self, action: TimeAction) {
        match action {
            TimeAction::ToggleRun => {}
            TimeAction::StepPhase => self.step_phase(),
            TimeAction::StepTick => self.step_tick(),
            TimeAction::StepBack => {
                self.stepper.step_back();
            }
            TimeAction::Reset => self.reset(),
        }
    }

    fn read_input(&mut self, ctx: &egui::Context) {
        self.poll_map_location(ctx);
        self.poll_log_fetch(ctx);
        let keys = if self.driving_by_hand() {
            drive::keyboard_command(ctx)
        } else {
            None
        };
        self.drive_by_hand(keys);
        let picked = self
            .map_picker
            .poll_all()
            .map(|batch| self.with_named_image(batch));
        if let Some(batch) = self.inbox.poll(ctx).or(picked) {
            let (files, refused) = crate::widgets::dropped_files::sort_read(batch);
            if let Some(why) = refused.into_iter().next() {
                self.frame.note = Some(why);
                return;
            }
            // A map (YAML, PGM, PNG) loads as a map; anything else is read as a
            // laser file, a CARMEN log or a bag told apart by its bytes.
            let (maps, logs): (Vec<_>, Vec<_>) = files
                .into_iter()
                .partition(|(name, _)| crate::widgets::laser_inputs::is_map_file(name));
            if !maps.is_empty() {
                self.load_dropped(&maps);
            }
            if let Some((name, bytes)) = logs.first() {
                self.load_log(name, bytes);
            }
        }
    }

    fn advance(&mut self, dt: f64) {
        if self.sim().run().is_finished() {
            // The log has no scan left.
            self.frame.time.running = false;
            return;
        }
        let stepper = &mut self.stepper;
        lesson::advance_within_budget(&mut self.frame.time, dt, || {
            stepper.step_phase();
            !stepper.sim().is_mid_tick()
        });
    }

    fn wants_repaint(&self) -> bool {
        self.frame.time.running || self.log_fetch.is_some()
    }

    fn view_menu_ui(&mut self, ui: &mut egui::Ui) {
        ui.checkbox(&mut self.frame.view.legend, "Map legend");
        ui.checkbox(&mut self.frame.view.rays, "Lidar rays");
        ui.checkbox(&mut self.frame.view.particles, "Particles");
    }

    fn test_state(&self) -> serde_json::Value {
        let run = self.sim().run();
        let truth = run.truth_now();
        let filters: Vec<serde_json::Value> = run
            .filters()
            .iter()
            .enumerate()
            .map(|(k, f)| {
                // `estimate` at the filter's last update; `estimate_now` and the
                // errors as the panels show them: moved by the odometry since, against
                // the truth now.
                let estimate = f.mcl().estimate().map(|e| e.pose);
                let now = f.current_estimate(&run.odometry());
                let error = run.error_now(k);
                serde_json::json!({
                    "name": f.name,
                    "particles": f.mcl().count(),
                    "position_error": error.map(|e| e.position),
                    "heading_error": error.map(|e| e.heading),
                    "estimate": estimate.map(|e| [e.x, e.y, e.theta]),
                    "estimate_now": now.map(|e| [e.x, e.y, e.theta]),
                    "n_eff": f.mcl().n_eff(),
                    "status": run.status_of(k),
                })
            })
            .collect();
        serde_json::json!({
            "tick": run.tick_count(),
            "time": run_time(run),
            "phase": self.stepper.last_phase().map(|p| phase_name(*p)).unwrap_or_default(),
            "seed": run.scenario().seed,
            "map": self.map_name(),
            "truth": truth.map(|t| [t.x, t.y, t.theta]),
            "kidnap_tick": run.kidnap_tick(),
            "log": self.log_name(),
            "log_progress": run.log_progress(),
            "topics": self.laser.topics().map(|t| [t.scan.clone(), t.odometry.clone()]),
            "note": self.frame.note,
            "filters": filters,
        })
    }
}
