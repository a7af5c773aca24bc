//! SLAM Lab's egui front end, for the browser (wasm32) and the desktop.
//!
//! The app paints and wires; it owns no estimation logic. A lesson (today:
//! [`landmark_slam`]) owns a simulation session from `slamlab-sim` and draws it. The
//! shell around the lessons is the same everywhere: the lesson menu, the time bar
//! (run, pause, speed, step phase, step tick, reset), the notice bar, the theme, and
//! the URL: `?lesson=landmark-slam&seed=7&embed=1&landmarks=30`, with the figure keys
//! a lecture page uses (`tick=120&run=1&legend=1&panels=plots&zoom=2&follow=1`).
//! An embedded figure has no menu bar: a one-line header (title, panel toggles, a
//! link that opens the same setup in the full app) above the time bar.

pub mod cartographer;
pub mod export;
pub mod filters;
pub mod fonts;
pub mod frame_stats;
pub mod fusion;
pub mod kidnap;
pub mod landmark_slam;
pub mod laser_lesson;
pub mod lesson;
pub mod mapping;
pub mod palette;
pub mod panels;
pub mod pose_graph;
pub mod query;
pub mod registry;
pub mod resampling;
pub mod time_control;
pub mod visual_odometry;
pub mod widgets;

#[cfg(target_arch = "wasm32")]
mod web;

use landmark_slam::LandmarkSlamLesson;
use lesson::{Lesson, LessonStart};
pub use panels::PanelVisibility;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use time_control::TimeAction;

/// The eframe storage key of [`Settings`].
const SETTINGS_KEY: &str = "slamlab_settings";

/// Reads the stored [`Settings`]: JSON (what SLAM Lab writes). The desktop also reads
/// the RON an earlier version wrote. A value that neither reads is ignored (defaults).
fn load_settings(storage: &dyn eframe::Storage) -> Option<Settings> {
    let text = storage.get_string(SETTINGS_KEY)?;
    match serde_json::from_str(&text) {
        Ok(settings) => Some(settings),
        #[cfg(not(target_arch = "wasm32"))]
        Err(_) => eframe::get_value(storage, SETTINGS_KEY),
        #[cfg(target_arch = "wasm32")]
        Err(err) => {
            log::warn!("ignoring the stored settings: {err}");
            None
        }
    }
}

/// Stores the [`Settings`] as JSON (the browser build links no RON: docs/web-build.md).
fn store_settings(storage: &mut dyn eframe::Storage, settings: &Settings) {
    match serde_json::to_string(settings) {
        Ok(text) => storage.set_string(SETTINGS_KEY, text),
        Err(err) => log::warn!("could not store the settings: {err}"),
    }
}

/// What SLAM Lab remembers between visits (eframe storage: a file natively, local
/// storage in the browser). Parameters given in the URL always win over these.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// `Some(true)` dark, `Some(false)` light, `None` follow the system.
    pub dark_mode: Option<bool>,
    /// Which panels are open (full layout only).
    pub panels: PanelVisibility,
    /// Each lesson's own settings ([`Lesson::stored_settings`]), by lesson id.
    pub lessons: BTreeMap<String, serde_json::Value>,
    /// The lesson open last.
    pub last_lesson: Option<String>,
}

/// Does the URL set anything up (a lesson parameter, a figure key, many runs)? Such
/// a link opens exactly as shared, whatever an earlier visit stored.
pub fn link_sets_up(parsed: &query::Query) -> bool {
    !parsed.pairs.is_empty()
        || parsed.many_runs.is_some()
        || parsed.figure != query::FigureOptions::default()
}

/// A file named by `estimate=`, while it is read; a map's image carries the
/// YAML that named it (name, bytes), to be delivered together.
#[derive(Debug)]
struct LinkedEstimate {
    location: String,
    fetch: Option<widgets::fetch::Fetch>,
    yaml: Option<(String, Vec<u8>)>,
}

/// The largest file named `name` that lesson `lesson_id` reads, bytes: the
/// mapping and Cartographer lessons read laser logs and ROS 2 bags (by their
/// extension) up to `grid::laser_file::MAX_LASER_FILE_BYTES` (1 GiB); every
/// other file and lesson stops at 64 MiB ([`widgets::fetch::MAX_FETCH_BYTES`]).
/// In the browser a drop holding a larger file is refused from its size before
/// any of it is read (`web.rs`).
pub fn file_cap(name: &str, lesson_id: &str) -> u64 {
    let lower = name.to_ascii_lowercase();
    let laser = [".clf", ".log", ".gz", ".bz2", ".mcap", ".bag", ".db3"]
        .iter()
        .any(|e| lower.ends_with(e));
    if laser && matches!(lesson_id, "mapping" | "cartographer") {
        slamlab_sim::grid::laser_file::MAX_LASER_FILE_BYTES
    } else {
        widgets::fetch::MAX_FETCH_BYTES as u64
    }
}

/// The SLAM Lab application.
#[derive(Debug)]
pub struct SlamLabApp {
    /// The page's query string, e.g. `lesson=landmark-slam&seed=7`.
    pub query: String,
    /// Frames drawn so far.
    pub frames: u64,
    frame_stats: frame_stats::FrameStats,
    /// eframe's CPU time of the previous frame, milliseconds (none in tests).
    last_cpu_ms: Option<f32>,
    /// What the last frame spent simulating, milliseconds (with `last_cpu_ms`, how
    /// much of the frame's interval the thread sat idle: the clock's budget at
    /// maximum speed).
    last_sim_ms: f32,
    /// The grade report's picture is being taken: the student's estimate is drawn
    /// whole until it arrives.
    report_picture: bool,
    show_frame_timing: bool,
    lesson: Box<dyn Lesson>,
    embed: bool,
    panels: PanelVisibility,
    /// The panels of a narrow window (side panels as drawers, closed at first).
    narrow_panels: PanelVisibility,
    /// Was the window narrow in the last frame?
    narrow: bool,
    /// The header's title and the time bar's next phase in the last frame (a
    /// change asks for one more frame, see `update`).
    last_bar_text: String,
    /// How the figure opened (the URL's figure keys), for links.
    figure: query::FigureOptions,
    /// The map's (central panel's) rectangle and the window's size, last frame.
    map_rect: Option<egui::Rect>,
    /// The time bar's rectangle in the last frame.
    time_bar_rect: Option<egui::Rect>,
    /// The lesson's note and the tick it was first shown at: stepping back before
    /// that tick clears it (what it said no longer holds).
    note_since: Option<(String, u64)>,
    /// The query string the page's address shows (without `?`): the one the app
    /// opened with, then the lesson's after a switch of lessons, so that a reload
    /// opens the lesson on screen.
    address: String,
    /// Has the address changed since the browser last took it?
    address_changed: bool,
    screen: egui::Vec2,
    app_notices: Vec<String>,
    dismissed: BTreeSet<String>,
    dark_mode: Option<bool>,
    theme_applied: bool,
    /// Exports in progress (PNG, CSV, JSON) and what the last one did.
    pub exporter: export::Exporter,
    /// An export asked for from outside a frame (the browser test hook), and the
    /// context to wake for it.
    pending_export: Option<export::ExportKind>,
    ctx: Option<egui::Context>,
    /// "Open scenario…": the picker, and scenario files dropped on the window.
    scenario_picker: widgets::file_picker::FilePicker,
    scenario_drops: widgets::dropped_files::DropInbox,
    /// "Open your estimate…": the picker, and estimates dropped on the window.
    estimate_picker: widgets::file_picker::FilePicker,
    estimate_drops: widgets::dropped_files::DropInbox,
    /// `estimate=` files named in the URL, while they are read.
    estimate_fetches: Vec<LinkedEstimate>,
    /// Homework (`assignment=`, `student=`): the Assignment window.
    assignment: Option<widgets::assignment::AssignmentDesk>,
    /// The link's lesson pairs, for opening an assignment's lesson once its
    /// variant is ready (the file arrived, the student typed their id).
    link_pairs: Vec<(String, String)>,
    /// The settings loaded at start, with each lesson's entry updated when the user
    /// leaves it. An embedded page saves these back unchanged (except the theme), so
    /// a lecture figure never rewrites the student's own setup.
    stored: Settings,
}

impl SlamLabApp {
    /// Creates the app from the page's query string (without the leading `?`), with
    /// the settings eframe stored last time.
    pub fn new(cc: &eframe::CreationContext<'_>, query: &str) -> Self {
        let settings = cc.storage.and_then(load_settings);
        let app = Self::with_settings(query, settings);
        fonts::install(&cc.egui_ctx);
        app.apply_theme(&cc.egui_ctx);
        app
    }

    /// Creates the app without an eframe context or stored settings (tests).
    pub fn from_query(query: &str) -> Self {
        Self::with_settings(query, None)
    }

    /// Creates the app from a query string and optional stored settings. The URL's
    /// parameters win: a lesson uses its stored parameters only when the URL gives
    /// none (and never in embed mode, so that a lecture page always shows the same run).
    pub fn with_settings(query: &str, settings: Option<Settings>) -> Self {
        let parsed = query::Query::parse(query);
        let mut notices: Vec<String> = parsed.issues.clone();
        let assignment = parsed.figure.assignment.as_deref().map(|source| {
            widgets::assignment::AssignmentDesk::new(source, parsed.figure.student.as_deref())
        });
        if parsed.figure.assignment.is_none() && parsed.figure.student.is_some() {
            notices.push(
                "student = … is for homework: give the assignment too (assignment=ekf-slam); it is ignored"
                    .to_owned(),
            );
        }
        if let Some(why) = assignment.as_ref().and_then(|d| d.problem()) {
            notices.push(why.to_owned());
        }
        // A variant ready now (a built-in assignment) opens its lesson with its
        // seed and parameters; an assignment file opens it when it arrives.
        let (lesson_id, lesson_pairs) = match assignment.as_ref().and_then(|d| d.prepared()) {
            Some(prepared) => {
                let (pairs, refused) =
                    widgets::assignment::variant_pairs(&prepared.lesson_pairs(), &parsed.pairs);
                notices.extend(refused);
                if let Some(asked) = parsed.lesson.as_deref()
                    && asked != prepared.assignment.lesson
                {
                    notices.push(format!(
                        "lesson = {asked}: the assignment {} is done in the {} lesson, which opens",
                        prepared.assignment.id, prepared.assignment.lesson
                    ));
                }
                (Some(prepared.assignment.lesson.clone()), pairs)
            }
            None => (parsed.lesson.clone(), parsed.pairs.clone()),
        };
        let entry = match lesson_id.as_deref() {
            None => registry::default_lesson(),
            Some(id) => registry::find(id).unwrap_or_else(|| {
                let default = registry::default_lesson();
                notices.push(format!(
                    "unknown lesson '{id}'; opening \"{}\" instead",
                    default.title
                ));
                default
            }),
        };
        let settings = settings.unwrap_or_default();
        // A link that sets anything up (a parameter, a figure key, many runs) opens
        // exactly as shared: the lesson's defaults and the link, never the windows,
        // view or panels of an earlier visit. Preferences such as the theme stay.
        let link_sets_up = link_sets_up(&parsed);
        let stored = (!parsed.embed && !link_sets_up)
            .then(|| settings.lessons.get(entry.id))
            .flatten();
        let mut lesson = registry::open(
            entry,
            &LessonStart {
                pairs: &lesson_pairs,
                embed: parsed.embed,
                stored,
                many_runs: parsed.many_runs,
            },
        );
        let panels = match parsed.figure.panels {
            Some(panels) => panels,
            None if parsed.embed => PanelVisibility::embedded(),
            None if link_sets_up => PanelVisibility::default(),
            None => settings.panels,
        };
        let narrow_panels = parsed.figure.panels.unwrap_or(PanelVisibility {
            parameters: false,
            explanation: false,
            plots: panels.plots,
        });
        apply_figure(&mut *lesson, &parsed.figure, &mut notices);
        let estimate_fetches = parsed
            .figure
            .estimates
            .iter()
            .map(|location| LinkedEstimate {
                location: location.clone(),
                fetch: None,
                yaml: None,
            })
            .collect();
        Self {
            query: query.trim_start_matches('?').to_owned(),
            frames: 0,
            frame_stats: frame_stats::FrameStats::default(),
            last_cpu_ms: None,
            last_sim_ms: 0.0,
            report_picture: false,
            show_frame_timing: false,
            lesson,
            embed: parsed.embed,
            panels,
            narrow_panels,
            narrow: false,
            last_bar_text: String::new(),
            figure: parsed.figure,
            map_rect: None,
            time_bar_rect: None,
            note_since: None,
            address: query.trim_start_matches('?').to_owned(),
            address_changed: false,
            screen: egui::Vec2::ZERO,
            app_notices: notices,
            dismissed: BTreeSet::new(),
            dark_mode: settings.dark_mode,
            theme_applied: false,
            exporter: export::Exporter::default(),
            pending_export: None,
            ctx: None,
            scenario_picker: widgets::file_picker::FilePicker::default(),
            scenario_drops: widgets::dropped_files::DropInbox::default(),
            estimate_picker: widgets::file_picker::FilePicker::multiple(),
            estimate_drops: widgets::dropped_files::DropInbox::default(),
            estimate_fetches,
            assignment,
            link_pairs: parsed.pairs,
            stored: settings,
        }
    }

    /// The homework of the page (`assignment=`), if there is any.
    pub fn assignment(&self) -> Option<&widgets::assignment::AssignmentDesk> {
        self.assignment.as_ref()
    }

    /// The homework of the page, to hand files in (tests).
    pub fn assignment_mut(&mut self) -> Option<&mut widgets::assignment::AssignmentDesk> {
        self.assignment.as_mut()
    }

    /// Opens the assignment's lesson on the student's variant (its seed and
    /// parameters, then the link's other pairs and figure keys), keeping the
    /// student's estimates: when the assignment file arrived or the student
    /// typed their id.
    fn open_assignment_lesson(&mut self) {
        let Some(prepared) = self.assignment.as_ref().and_then(|d| d.prepared()) else {
            return;
        };
        let Some(entry) = registry::find(&prepared.assignment.lesson) else {
            self.app_notices.push(format!(
                "the assignment {} is done in the lesson '{}', which this SLAM Lab does not have",
                prepared.assignment.id, prepared.assignment.lesson
            ));
            return;
        };
        let (pairs, refused) =
            widgets::assignment::variant_pairs(&prepared.lesson_pairs(), &self.link_pairs);
        self.figure.student = Some(prepared.variant.student.clone());
        if !self.embed {
            self.stored
                .lessons
                .insert(self.lesson.id().to_owned(), self.lesson.stored_settings());
        }
        let estimates = std::mem::take(self.lesson.frame_mut().estimates_mut());
        self.lesson = registry::open(
            entry,
            &LessonStart {
                pairs: &pairs,
                embed: self.embed,
                stored: None,
                many_runs: None,
            },
        );
        *self.lesson.frame_mut().estimates_mut() = estimates;
        self.app_notices.extend(refused);
        let figure = self.figure.clone();
        apply_figure(&mut *self.lesson, &figure, &mut self.app_notices);
    }

    /// The Assignment panel (beside the lesson, before its panels are laid
    /// out), and what it asks for.
    fn assignment_ui(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        let ctx = &ctx;
        let Some(desk) = self.assignment.as_mut() else {
            return;
        };
        if desk.poll(ctx) {
            self.open_assignment_lesson();
        } else if let Some(why) = desk.problem()
            && !self.app_notices.iter().any(|n| n == why)
        {
            self.app_notices.push(why.to_owned());
        }
        let Some(desk) = self.assignment.as_mut() else {
            return;
        };
        for action in desk.panel_ui(ui) {
            use widgets::assignment::DeskAction;
            match action {
                DeskAction::Save(file) => self.exporter.save(file),
                DeskAction::Report => self.export(ctx, export::ExportKind::GradeJson),
                DeskAction::Picture => self.export(ctx, export::ExportKind::GradePng),
                DeskAction::OpenVariant => self.open_assignment_lesson(),
                DeskAction::HandIn(files) => self.take_estimates(files),
            }
        }
    }

    /// The lesson on screen.
    pub fn lesson(&self) -> &dyn Lesson {
        &*self.lesson
    }

    /// The lesson on screen, mutably.
    pub fn lesson_mut(&mut self) -> &mut dyn Lesson {
        &mut *self.lesson
    }

    /// The lesson on screen as its concrete type, if it is one of those.
    pub fn lesson_as<L: 'static>(&self) -> Option<&L> {
        self.lesson.as_any().downcast_ref::<L>()
    }

    /// The lesson on screen as its concrete type, mutably.
    pub fn lesson_as_mut<L: 'static>(&mut self) -> Option<&mut L> {
        self.lesson.as_any_mut().downcast_mut::<L>()
    }

    /// The landmark-SLAM lesson, if it is the one open.
    pub fn landmark_lesson(&self) -> Option<&LandmarkSlamLesson> {
        self.lesson_as()
    }

    /// The landmark-SLAM lesson, mutably (tests drive it through the same methods
    /// as the widgets).
    pub fn landmark_lesson_mut(&mut self) -> Option<&mut LandmarkSlamLesson> {
        self.lesson_as_mut()
    }

    /// The running landmark-SLAM session, read only.
    pub fn session(&self) -> Option<&slamlab_sim::LandmarkSession> {
        self.landmark_lesson().map(LandmarkSlamLesson::session)
    }

    /// The open lesson's id.
    pub fn lesson_id(&self) -> &'static str {
        self.lesson.id()
    }

    /// Is the compact embed layout on?
    pub fn is_embedded(&self) -> bool {
        self.embed
    }

    /// Which panels are open (in a narrow window: which drawers).
    pub fn panels(&self) -> PanelVisibility {
        if self.narrow {
            self.narrow_panels
        } else {
            self.panels
        }
    }

    fn panels_mut(&mut self) -> &mut PanelVisibility {
        if self.narrow {
            &mut self.narrow_panels
        } else {
            &mut self.panels
        }
    }

    /// The map's (central panel's) rectangle in the last frame, points.
    pub fn map_rect(&self) -> Option<egui::Rect> {
        self.map_rect
    }

    /// The time bar's rectangle in the last frame, points.
    pub fn time_bar_rect(&self) -> Option<egui::Rect> {
        self.time_bar_rect
    }

    /// The query string (without `?`) the page's address shows: how the app
    /// opened, or after a switch of lessons (the menu, "Localize in this map", a
    /// scenario file) the lesson on screen, so that a reload opens it.
    pub fn address(&self) -> &str {
        &self.address
    }

    /// The address, when it changed since the last call (the browser then
    /// replaces the page's address with it, without reloading).
    pub fn take_address_change(&mut self) -> Option<String> {
        std::mem::take(&mut self.address_changed).then(|| self.address.clone())
    }

    /// Points the address at the lesson now on screen (`lesson=ID`, with
    /// `embed=1` in a figure).
    fn address_follows_lesson(&mut self) {
        self.address = query::build(self.lesson.id(), &[], self.embed);
        self.address_changed = true;
    }

    /// Was the window narrow (side panels as drawers) in the last frame?
    pub fn is_narrow(&self) -> bool {
        self.narrow
    }

    /// The query string (without `?`) that reopens this setup at the current tick:
    /// the lesson's link and the figure keys (`panels=` only for an embed).
    pub fn share_query(&self, embed: bool) -> String {
        self.lesson.share_query(embed) + &self.figure_suffix(embed)
    }

    /// The figure keys of a share link (`&tick=42&legend=1`): how the figure opened,
    /// at the current tick, never running; `panels=` only for an embed.
    fn figure_suffix(&self, embed: bool) -> String {
        let mut figure = self.figure.clone();
        figure.run = false;
        // A link that set the speed shares the speed the clock has now.
        if figure.speed.is_some() {
            let time = self.lesson.time();
            figure.speed = Some(if time.max_speed {
                query::Speed::Max
            } else {
                query::Speed::TicksPerSecond(time.speed_tps)
            });
        }
        if !embed {
            figure.panels = None;
        }
        figure
            .pairs(self.lesson.time_info().tick)
            .iter()
            .map(|(key, value)| {
                format!(
                    "&{}={}",
                    query::percent_encode(key),
                    query::percent_encode(value)
                )
            })
            .collect()
    }

    /// Every notice not dismissed: problems with the link, what the simulation had to
    /// change, and the latest errors.
    pub fn notices(&self) -> Vec<String> {
        let mut all = self.app_notices.clone();
        all.extend(self.lesson.notices());
        all.retain(|n| !self.dismissed.contains(n));
        all.dedup();
        all
    }

    /// Is the clock running?
    pub fn is_running(&self) -> bool {
        self.lesson.time().running
    }

    /// The settings to store.
    pub fn settings(&self) -> Settings {
        if self.embed {
            return Settings {
                dark_mode: self.dark_mode,
                ..self.stored.clone()
            };
        }
        let mut lessons = self.stored.lessons.clone();
        lessons.insert(self.lesson.id().to_owned(), self.lesson.stored_settings());
        Settings {
            dark_mode: self.dark_mode,
            panels: self.panels,
            lessons,
            last_lesson: Some(self.lesson.id().to_owned()),
        }
    }

    /// A one-line JSON summary of the app's state for browser tests: the shell's
    /// fields and the lesson's own (`tick`, `phase`, `seed`, ...).
    pub fn test_state_json(&self) -> String {
        let mut state = serde_json::json!({
            "frames": self.frames,
            "running": self.is_running(),
            "lesson": self.lesson.id(),
            "embed": self.embed,
            "notices": self.notices().len(),
            "notice_list": self.notices(),
            "frame_timing": self.frame_stats.summary(),
            "narrow": self.narrow,
            "export_status": self.exporter.status,
            "export_last": self.exporter.last.as_ref().map(|f| serde_json::json!({
                "name": f.name,
                "bytes": f.bytes.len(),
            })),
            "screen": [self.screen.x, self.screen.y],
            "map_rect": self.map_rect.map(|r| [r.left(), r.top(), r.width(), r.height()]),
            "estimates": self.lesson.frame().estimates().last_scores(),
            "assignment": self.assignment.as_ref().map(widgets::assignment::AssignmentDesk::test_state),
            "panels": {
                "parameters": self.panels().parameters,
                "explanation": self.panels().explanation,
                "plots": self.panels().plots,
            },
        });
        if let (Some(state), serde_json::Value::Object(lesson)) =
            (state.as_object_mut(), self.lesson.test_state())
        {
            state.extend(lesson);
        }
        state.to_string()
    }

    /// Opens `query` without a window, runs its lesson `ticks` whole ticks and
    /// returns [`test_state_json`](Self::test_state_json). The browser test calls this
    /// in wasm and compares it with the native result: the same seed gives the same
    /// bits in both.
    pub fn headless_state(query: &str, ticks: u64) -> String {
        let mut app = Self::from_query(query);
        for _ in 0..ticks.min(100_000) {
            app.apply_time_action(TimeAction::StepTick);
        }
        app.test_state_json()
    }

    /// Like [`headless_state`](Self::headless_state), with a CARMEN log (`bytes`, plain
    /// or compressed, named `name`) opened in the mapping or Cartographer lesson first,
    /// or a landmark data set (the MRCLAM zip) in the landmark lesson, as if it had
    /// been dropped on the window. The browser test maps the Intel log
    /// this way and times it. A query for another lesson gives an error; a log that
    /// cannot be read gives the state with the lesson's note saying why.
    pub fn headless_log_state(query: &str, name: &str, bytes: &[u8], ticks: u64) -> String {
        let mut app = Self::from_query(query);
        if let Some(lesson) = app.lesson_as_mut::<mapping::MappingLesson>() {
            lesson.load_log(name, bytes);
        } else if let Some(lesson) = app.lesson_as_mut::<cartographer::CartographerLesson>() {
            lesson.load_log(name, bytes, None);
        } else if let Some(lesson) = app.lesson_as_mut::<LandmarkSlamLesson>() {
            lesson.open_files(vec![(name.to_owned(), Ok(bytes.to_vec()))]);
        } else {
            return r#"{"error":"the query opens none of the mapping, Cartographer and landmark lessons"}"#
                .to_owned();
        }
        for _ in 0..ticks.min(100_000) {
            app.apply_time_action(TimeAction::StepTick);
        }
        app.test_state_json()
    }

    /// Opens a landmark data set of several files (the Freiburg course's `world.dat`
    /// and `sensor_data.dat`, Victoria Park's three files) in the landmark lesson of
    /// `query`, as if they had been dropped together, runs up to `ticks` whole ticks
    /// (stopping at the end of the data) with the filters `estimator=` in the query
    /// names (else the data set's preset's) and returns
    /// [`test_state_json`](Self::test_state_json) with `estimates` added: per filter,
    /// the final robot pose `[x, y, θ]` and the landmarks `[id, x, y]`. The browser
    /// test replays the data this way in wasm and compares the bits with the native
    /// run. Another lesson gives an error; files that are no data set give the state
    /// with the lesson's note saying why.
    pub fn headless_files_state(query: &str, files: Vec<(String, Vec<u8>)>, ticks: u64) -> String {
        let mut app = Self::from_query(query);
        let Some(lesson) = app.lesson_as_mut::<LandmarkSlamLesson>() else {
            return r#"{"error":"the query does not open the landmark lesson"}"#.to_owned();
        };
        lesson.open_files(files.into_iter().map(|(n, b)| (n, Ok(b))).collect());
        // A drop opens the data set's preset (EKF beside UKF or FastSLAM); the
        // query's `estimator=` then chooses the filters, as it does for `data=`.
        if let Some((_, estimators)) = query
            .split('&')
            .filter_map(|pair| pair.split_once('='))
            .find(|(key, _)| *key == "estimator")
            && lesson.set_param("estimator", estimators).is_none()
        {
            lesson.reset();
        }
        for _ in 0..ticks.min(200_000) {
            if lesson.session().is_finished() {
                break;
            }
            lesson.step_tick();
        }
        let estimates: BTreeMap<&str, serde_json::Value> = lesson
            .session()
            .filters()
            .iter()
            .map(|run| {
                let filter = run.filter();
                let pose = filter.robot_pose();
                let landmarks: Vec<(usize, f64, f64)> = filter
                    .landmarks()
                    .iter()
                    .map(|l| (l.id, l.mean[0], l.mean[1]))
                    .collect();
                (
                    run.kind.name(),
                    serde_json::json!({ "pose": [pose.x, pose.y, pose.theta], "landmarks": landmarks }),
                )
            })
            .collect();
        let mut state: serde_json::Value =
            serde_json::from_str(&app.test_state_json()).unwrap_or_default();
        if let Some(object) = state.as_object_mut() {
            object.insert("estimates".to_owned(), serde_json::json!(estimates));
        }
        state.to_string()
    }

    fn apply_theme(&self, ctx: &egui::Context) {
        match self.dark_mode {
            Some(true) => ctx.set_theme(egui::Theme::Dark),
            Some(false) => ctx.set_theme(egui::Theme::Light),
            None => {}
        }
    }

    /// Runs one of the time bar's actions.
    pub fn apply_time_action(&mut self, action: TimeAction) {
        if action == TimeAction::Reset {
            self.dismissed.clear();
        }
        self.lesson.apply_time_action(action);
    }

    /// Draws the whole app.
    pub fn app_ui(&mut self, ui: &mut egui::Ui) {
        self.frames += 1;
        if !self.theme_applied {
            self.apply_theme(ui.ctx());
            self.theme_applied = true;
        }
        let ctx = ui.ctx().clone();

        // Input first: shortcuts, the lesson's own keys, then the clock.
        for action in time_control::shortcut_actions(&ctx) {
            self.apply_time_action(action);
        }
        let dt = f64::from(ctx.input(|i| i.stable_dt));
        // Scenario files and estimates dropped on the window are the shell's, not
        // the lesson's (which reads maps, logs and graphs).
        self.refuse_oversized_drops(&ctx);
        self.poll_scenario_files(&ctx);
        self.poll_estimates(&ctx);
        let sim_start = web_time::Instant::now();
        self.lesson.read_input(&ctx);
        if self.lesson.take_restarted_from_link() {
            // A map named in the URL arrived and the run started over on it: the
            // link's figure keys hold for the run on that map.
            let figure = self.figure.clone();
            apply_figure(&mut *self.lesson, &figure, &mut self.app_notices);
        }
        let interval_ms = ctx.input(|i| i.unstable_dt) * 1000.0;
        self.lesson.time_mut().note_frame(
            f64::from(self.last_sim_ms),
            self.last_cpu_ms.map(f64::from),
            f64::from(interval_ms),
        );
        self.lesson.advance(dt);
        let sim_ms = sim_start.elapsed().as_secs_f32() * 1000.0;
        self.last_sim_ms = sim_ms;
        let update = self.lesson.last_advance_updated();
        self.frame_stats
            .record_frame(self.last_cpu_ms, sim_ms, interval_ms, update);

        self.narrow = widgets::layout::is_narrow(&ctx);
        self.screen = ctx.content_rect().size();
        if self.embed {
            egui::Panel::top("slamlab_embed_header").show(ui, |ui| self.embed_header_ui(ui));
        } else {
            egui::Panel::top("slamlab_menu").show(ui, |ui| self.menu_bar_ui(ui));
        }
        // The header's and the time bar's heights depend on the window's width
        // only (their changing texts are cut to one line), so a new title or phase
        // moves nothing. A new title still asks for one more frame, so that an idle
        // lesson shows it.
        let bar_text = format!("{}\n{}", self.title(), self.lesson.time_info().next_phase);
        if bar_text != self.last_bar_text {
            self.last_bar_text = bar_text;
            ctx.request_repaint();
        }
        let bar = egui::Panel::top("slamlab_time_bar").show(ui, |ui| {
            let info = self.lesson.time_info();
            let steps = self.lesson.step_controls();
            let moment = self.lesson.moment();
            let actions = time_control::time_bar_ui(
                ui,
                self.lesson.time_mut(),
                &info,
                steps,
                self.embed,
                moment.as_deref(),
            );
            for action in actions {
                self.apply_time_action(action);
            }
        });
        self.time_bar_rect = Some(bar.response.rect);
        self.expire_note();
        widgets::share::set_figure_suffix(
            &ctx,
            self.figure_suffix(false),
            self.figure_suffix(true),
        );
        if let Some(kind) = self.pending_export.take() {
            self.export(&ctx, kind);
        }
        if self.ctx.is_none() {
            self.ctx = Some(ctx.clone());
        }
        self.assignment_ui(ui);
        let panels = if self.narrow {
            &mut self.narrow_panels
        } else {
            &mut self.panels
        };
        widgets::map_canvas::clear_placement(&ctx);
        self.lesson.panels_ui(ui, panels, self.embed);
        // The notices lie over the foot of the map: they come and go without
        // moving the map or anything on it.
        let notices = self.notices();
        if !notices.is_empty()
            && let Some(map) = widgets::layout::map_rect(&ctx)
        {
            self.notices_ui(&ctx, map, &notices);
        }
        self.estimates_ui(&ctx);
        match self.lesson.take_request() {
            Some(lesson::LessonRequest::Save(files)) => self.exporter.save_all(files),
            Some(request) => {
                if let Some(next) = registry::requested(request) {
                    if !self.embed {
                        self.stored
                            .lessons
                            .insert(self.lesson.id().to_owned(), self.lesson.stored_settings());
                    }
                    self.lesson = next;
                    self.app_notices.clear();
                    self.dismissed.clear();
                    self.address_follows_lesson();
                }
            }
            None => {}
        }
        self.map_rect = widgets::layout::map_rect(&ctx);
        self.exporter.ui(&ctx);
        if self.lesson.wants_repaint() {
            ctx.request_repaint();
        }
        widgets::sources::sources_window(&ctx);
    }

    fn title(&self) -> String {
        let lesson_title = registry::find(self.lesson.id()).map_or("", |l| l.title);
        match self.lesson.subtitle() {
            subtitle if subtitle.is_empty() => lesson_title.to_owned(),
            subtitle => format!("{lesson_title}: {subtitle}"),
        }
    }

    /// The panel toggles of the embed header and of a narrow window's menu bar.
    fn panel_toggles_ui(&mut self, ui: &mut egui::Ui) {
        self.assignment_toggle_ui(ui);
        let panels = self.panels_mut();
        ui.toggle_value(&mut panels.plots, "Plots")
            .on_hover_text("Show or hide the plots");
        ui.toggle_value(&mut panels.explanation, "Explain")
            .on_hover_text("Show or hide the explanation");
        ui.toggle_value(&mut panels.parameters, "Parameters")
            .on_hover_text("Show or hide the parameters");
    }

    /// The switch of the Assignment panel, when the page has homework.
    fn assignment_toggle_ui(&mut self, ui: &mut egui::Ui) {
        if let Some(desk) = self.assignment.as_mut() {
            ui.toggle_value(&mut desk.open, "Assignment")
                .on_hover_text("Show or hide the homework: the task, your inputs, your grade");
        }
    }

    /// The header of an embedded figure: the title, the panel toggles, how to
    /// interact, and a link to the same setup in the full app.
    fn embed_header_ui(&mut self, ui: &mut egui::Ui) {
        let title = self.title();
        // The controls first, then the title in the room left, cut to one line:
        // a new title (a pose source chosen) moves nothing.
        ui.horizontal_wrapped(|ui| {
            self.panel_toggles_ui(ui);
            ui.separator();
            let url = format!("index.html?{}", self.share_query(false));
            ui.add(egui::Hyperlink::from_label_and_url("Open full app", url).open_in_new_tab(true))
                .on_hover_text("This setup, at this tick, in the full SLAM Lab (new tab)");
            ui.label(
                egui::RichText::new("Click to interact, or Ctrl+wheel to zoom")
                    .small()
                    .weak(),
            );
            ui.separator();
            if title_bar::room_left(ui) < 160.0 {
                ui.end_row();
            }
            let room = title_bar::room_left(ui);
            title_bar::title_ui(ui, &title, None, room);
        });
    }

    fn menu_bar_ui(&mut self, ui: &mut egui::Ui) {
        let title = self.title();
        ui.horizontal_wrapped(|ui| {
            ui.label(egui::RichText::new("SLAM Lab").strong());
            ui.menu_button("File", |ui| self.file_menu_ui(ui));
            ui.menu_button("Lessons", |ui| {
                // Each lesson's title and what it shows, in body-size text that
                // wraps; in a short window the list scrolls.
                ui.set_max_width(420.0);
                let height = (ui.ctx().content_rect().height() - 80.0).max(120.0);
                egui::ScrollArea::vertical()
                    .max_height(height)
                    .show(ui, |ui| {
                        for info in registry::LESSONS {
                            let selected = info.id == self.lesson.id();
                            let title = egui::RichText::new(info.title).strong();
                            let response = ui
                                .selectable_label(selected, title)
                                .on_hover_text(info.summary);
                            if response.clicked() {
                                if !selected {
                                    self.switch_lesson(info.id);
                                }
                                ui.close();
                            }
                            ui.label(info.summary);
                            ui.add_space(6.0);
                        }
                    });
            });
            ui.menu_button("View", |ui| {
                let panels = self.panels_mut();
                ui.checkbox(&mut panels.parameters, "Parameters panel");
                ui.checkbox(&mut panels.explanation, "Explanation panel");
                ui.checkbox(&mut panels.plots, "Plots");
                ui.checkbox(&mut self.show_frame_timing, "Frame timing")
                    .on_hover_text(
                        "How long each frame takes: the app's CPU time and the frame rate",
                    );
                self.lesson.view_menu_ui(ui);
            });
            if ui
                .button("Sources")
                .on_hover_text("The documents the lessons cite: titles, authors, sections")
                .clicked()
            {
                widgets::sources::open_sources(ui.ctx(), None);
            }
            ui.menu_button("Keys", |ui| self.keys_ui(ui));
            if !self.narrow {
                self.assignment_toggle_ui(ui);
            }
            // The title and the export status change (a pose source chosen, a file
            // saved): they take the room the row has left, cut to one line, so the
            // bar never changes height under the cursor.
            let theme_width = title_bar::text_width(ui, "Light theme")
                + 2.0 * ui.spacing().button_padding.x
                + 2.0 * ui.spacing().item_spacing.x;
            if self.narrow {
                // A narrow window: the drawer buttons first, then the title; no
                // right-aligned group for wrapped text to run into.
                ui.separator();
                self.panel_toggles_ui(ui);
                ui.separator();
                if title_bar::room_left(ui) < theme_width + 120.0 {
                    ui.end_row();
                }
                let room = title_bar::room_left(ui) - theme_width;
                title_bar::title_ui(ui, &title, self.exporter.status.as_deref(), room);
                let dark = ui.visuals().dark_mode;
                if ui
                    .small_button(if dark { "Light theme" } else { "Dark theme" })
                    .clicked()
                {
                    self.dark_mode = Some(!dark);
                    self.apply_theme(ui.ctx());
                }
                return;
            }
            ui.separator();
            let timing = if self.show_frame_timing { 260.0 } else { 0.0 };
            let room = title_bar::room_left(ui) - theme_width - timing;
            title_bar::title_ui(ui, &title, self.exporter.status.as_deref(), room);
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                let dark = ui.visuals().dark_mode;
                let label = if dark { "Light theme" } else { "Dark theme" };
                if ui
                    .button(label)
                    .on_hover_text("Switch between the light and the dark theme")
                    .clicked()
                {
                    self.dark_mode = Some(!dark);
                    self.apply_theme(ui.ctx());
                }
                if self.show_frame_timing {
                    ui.label(
                        egui::RichText::new(self.frame_stats.label())
                            .small()
                            .monospace(),
                    );
                }
            });
        });
    }

    /// Every keyboard shortcut: the time bar's, then the lesson's own (drive keys).
    fn keys_ui(&mut self, ui: &mut egui::Ui) {
        ui.label("With the mouse over the app and no text field active:");
        egui::Grid::new("slamlab_keys")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                for (key, what) in time_control::shortcuts(self.lesson.step_controls())
                    .into_iter()
                    .chain(
                        self.lesson
                            .keys()
                            .into_iter()
                            .map(|(k, w)| (k, w.to_owned())),
                    )
                {
                    ui.label(egui::RichText::new(key).monospace().strong());
                    ui.label(what);
                    ui.end_row();
                }
            });
    }

    /// The File menu: open a scenario, and the exports.
    fn file_menu_ui(&mut self, ui: &mut egui::Ui) {
        ui.label(
            "Your own estimate (TUM or CSV trajectory, landmark CSV), or drop it on the window:",
        );
        self.estimate_picker.ui(
            ui,
            "Open your estimate…",
            ".tum,.txt,.csv,text/plain,text/csv",
            slamlab_sim::io::trajectory::MAX_TRAJECTORY_BYTES as usize,
            "path/to/my_estimate.tum",
        );
        ui.separator();
        ui.label("Open a scenario file (.json) or drop one on the window:");
        self.scenario_picker.ui(
            ui,
            "Open scenario…",
            ".json,application/json",
            1 << 20,
            "path/to/scenario.json",
        );
        ui.separator();
        let ctx = ui.ctx().clone();
        let exports = [
            (
                "Export map as PNG",
                Some("The map panel as it is on screen"),
                export::ExportKind::MapPng,
            ),
            (
                "Export trajectories (zip)",
                Some(
                    "The truth and every estimator's trajectory so far as TUM and CSV files \
                     (with covariances where the estimator has them), and the landmarks: score \
                     them with `slamlab evaluate` or evo",
                ),
                export::ExportKind::TrajectoriesZip,
            ),
            ("Export window as PNG", None, export::ExportKind::WindowPng),
            (
                "Export plot data as CSV",
                Some("Every plot's series, every point: plot, axes, series, x, y"),
                export::ExportKind::PlotsCsv,
            ),
            (
                "Export scenario as JSON",
                Some(
                    "The lesson, its parameters and the view at this tick: open it again here \
                     (File → Open scenario, or drop it on the window) or run it with \
                     `slamlab run --scenario FILE`",
                ),
                export::ExportKind::ScenarioJson,
            ),
        ];
        for (label, hover, kind) in exports {
            let mut button = ui.button(label);
            if let Some(hover) = hover {
                button = button.on_hover_text(hover);
            }
            if button.clicked() {
                self.export(&ctx, kind);
                ui.close();
            }
        }
    }

    /// Asks for an export in the next frame (for callers outside a frame: the browser
    /// test hook).
    pub fn request_export(&mut self, kind: export::ExportKind) {
        self.pending_export = Some(kind);
        if let Some(ctx) = &self.ctx {
            ctx.request_repaint();
        }
    }

    /// Starts an export of the current lesson: a file name with the lesson and tick.
    pub fn export(&mut self, ctx: &egui::Context, kind: export::ExportKind) {
        use export::{ExportFile, ExportKind};
        let stem = format!(
            "slamlab-{}-t{}",
            self.lesson.id(),
            self.lesson.time_info().tick
        );
        match kind {
            ExportKind::MapPng => match self.map_rect {
                Some(rect) => {
                    self.exporter
                        .request_png(ctx, Some(rect), format!("{stem}-map.png"));
                }
                None => self.exporter.status = Some("No map on screen to export".to_owned()),
            },
            ExportKind::WindowPng => {
                self.exporter
                    .request_png(ctx, None, format!("{stem}-window.png"));
            }
            ExportKind::PlotsCsv => {
                let series = self.lesson.plot_series();
                if series.iter().all(|s| s.points.is_empty()) {
                    self.exporter.status =
                        Some("The plots have no data yet: run or step first".to_owned());
                } else {
                    self.exporter.save(ExportFile {
                        name: format!("{stem}-plots.csv"),
                        mime: "text/csv",
                        bytes: export::series_csv(&series).into_bytes(),
                    });
                }
            }
            ExportKind::TrajectoriesZip => {
                let trajectories = self.lesson.trajectories();
                if trajectories.is_empty() {
                    self.exporter.status =
                        Some("This lesson has no trajectories to export".to_owned());
                } else {
                    let folder = format!("{stem}-trajectories");
                    let files = slamlab_sim::io::trajectory::export_files(
                        self.lesson.id(),
                        &trajectories,
                        &self.lesson.landmark_maps(),
                    );
                    match slamlab_sim::io::archive::write_zip(&folder, &files) {
                        Ok(bytes) => self.exporter.save(ExportFile {
                            name: format!("{folder}.zip"),
                            mime: "application/zip",
                            bytes,
                        }),
                        Err(e) => self.exporter.status = Some(e.to_string()),
                    }
                }
            }
            ExportKind::GradeJson | ExportKind::GradePng => {
                let link = self.share_query(false);
                let grade = self.assignment.as_ref().and_then(|d| d.selected_grade());
                match (kind, grade) {
                    (_, None) => {
                        self.exporter.status =
                            Some("No grade yet: hand in your estimate first".to_owned());
                    }
                    (ExportKind::GradeJson, Some(_)) => {
                        if let Some(file) =
                            self.assignment.as_ref().and_then(|d| d.report_json(&link))
                        {
                            self.exporter.save(file);
                        }
                    }
                    (_, Some(grade)) => {
                        let name = format!(
                            "{}.png",
                            widgets::assignment::AssignmentDesk::report_stem(grade)
                        );
                        self.exporter.request_png(ctx, None, name);
                        self.report_picture = true;
                    }
                }
            }
            ExportKind::ScenarioJson => {
                let file = export::scenario_of_query(&self.share_query(false));
                self.exporter.save(ExportFile {
                    name: format!("slamlab-{}-scenario.json", self.lesson.id()),
                    mime: "application/json",
                    bytes: file.to_json().into_bytes(),
                });
            }
        }
    }

    /// Reads the estimates dropped on the window, picked with "Open your
    /// estimate…" or named by `estimate=`, into the lesson's estimates. A file the
    /// lesson reads itself (in the pose-graph lesson a `.txt` is an iSAM graph)
    /// stays the lesson's.
    fn poll_estimates(&mut self, ctx: &egui::Context) {
        let text_is_theirs = self.lesson.id() == "pose-graph";
        // Homework whose output is no trajectory (a graph, a map, a relative
        // pose) takes every dropped file but a scenario: it is handed in.
        let hands_in_anything = self
            .assignment
            .as_ref()
            .and_then(|d| d.prepared())
            .is_some_and(|p| {
                p.assignment.output.format != slamlab_sim::coursework::OutputFormat::Trajectory
            });
        // A ROS map is the student's map where the run has a true one to score
        // it against (else it stays the lesson's: a world to explore).
        let maps_are_estimates = self.lesson.scores_maps();
        // In the landmark lesson a `.txt` dropped with a data set's `.dat` files, or
        // named as gtsam names Victoria Park's pose graph, is the lesson's: the
        // reference map's graph, not a trajectory.
        let landmark = self.lesson.id() == "landmark-slam";
        let with_data_set = ctx.input(|i| {
            i.raw.dropped_files.iter().any(|f| {
                f.path()
                    .to_string_lossy()
                    .to_ascii_lowercase()
                    .ends_with(".dat")
            })
        });
        let is_estimate = |file: &egui::DroppedFileHandle| {
            let name = file.path().to_string_lossy().to_ascii_lowercase();
            let text_is_lessons = text_is_theirs
                || (landmark && (with_data_set || name.ends_with("victoria_park.txt")));
            hands_in_anything
                || name.ends_with(".tum")
                || name.ends_with(".csv")
                || (!text_is_lessons && name.ends_with(".txt"))
                || (maps_are_estimates && widgets::estimates::is_map_file(&name))
        };
        let taken = widgets::dropped_files::take_dropped(ctx, is_estimate);
        let mut files = self.estimate_drops.read(ctx, taken).unwrap_or_default();
        files.extend(self.estimate_picker.poll_all().unwrap_or_default());
        let mut images = Vec::new();
        for linked in &mut self.estimate_fetches {
            match &mut linked.fetch {
                None => linked.fetch = Some(widgets::fetch::Fetch::start(&linked.location, ctx)),
                Some(f) => {
                    if let Some(result) = f.poll() {
                        let location = &linked.location;
                        let name = location.rsplit('/').next().unwrap_or(location).to_owned();
                        match (linked.yaml.take(), result) {
                            // A map's image: delivered with its YAML.
                            (Some(yaml), Ok(bytes)) => {
                                files.push((yaml.0, Ok(yaml.1)));
                                files.push((name, Ok(bytes)));
                            }
                            (Some(yaml), Err(why)) => files.push((
                                yaml.0.clone(),
                                Err(format!("the image it names, {location}: {why}")),
                            )),
                            // A map's YAML: read its image beside it first.
                            (None, Ok(bytes))
                                if widgets::estimates::is_map_file(&name) && {
                                    let lower = name.to_ascii_lowercase();
                                    lower.ends_with(".yaml") || lower.ends_with(".yml")
                                } =>
                            {
                                match std::str::from_utf8(&bytes)
                                    .ok()
                                    .and_then(|t| slamlab_sim::io::ros_map::parse_map_yaml(t).ok())
                                {
                                    Some(parsed) => images.push(LinkedEstimate {
                                        location: widgets::fetch::relative_to(
                                            location,
                                            &parsed.image,
                                        ),
                                        fetch: None,
                                        yaml: Some((name, bytes)),
                                    }),
                                    // Read as it is: the refusal says why.
                                    None => files.push((name, Ok(bytes))),
                                }
                            }
                            (None, result) => files.push((name, result)),
                        }
                    }
                }
            }
        }
        self.estimate_fetches.retain(|l| {
            l.fetch
                .as_ref()
                .is_none_or(widgets::fetch::Fetch::is_pending)
        });
        self.estimate_fetches.extend(images);
        self.take_estimates(files);
    }

    /// The lesson's own result as the files a student would hand in, for the
    /// browser check that drops them back: the mapping lesson's map as *Export
    /// map* writes it (YAML and PGM), the pose-graph lesson's graph as g2o.
    /// Empty for the other lessons (their trajectories come from File →
    /// Export trajectories).
    pub fn own_result_files(&self) -> Vec<(String, Vec<u8>)> {
        if let Some(lesson) = self.lesson_as::<mapping::MappingLesson>() {
            return lesson
                .map_files()
                .map(|files| files.into_iter().map(|f| (f.name, f.bytes)).collect())
                .unwrap_or_default();
        }
        if let Some(lesson) = self.lesson_as::<pose_graph::PoseGraphLesson>() {
            return slamlab_sim::io::graph::write_g2o(lesson.session().graph())
                .map(|text| vec![("optimized.g2o".to_owned(), text.into_bytes())])
                .unwrap_or_default();
        }
        Vec::new()
    }

    /// The largest file named `name` a drop on this lesson may hold, bytes
    /// ([`file_cap`]).
    pub fn drop_cap_for(&self, name: &str) -> u64 {
        file_cap(name, self.lesson.id())
    }

    /// A file of a drop refused from its size before it was read (the browser's
    /// drop guard): a notice naming it and its size. Nothing of the drop is
    /// taken; the lesson and what was dropped before stay.
    pub fn refuse_dropped(&mut self, name: &str, size: u64) {
        self.app_notices.push(format!(
            "{}: nothing of that drop was read, and the lesson goes on",
            widgets::fetch::too_large(name, size, self.drop_cap_for(name))
        ));
    }

    /// On the desktop, a drop with a file over its cap is refused from the file's
    /// size before anything is read, as the browser's drop guard does: the whole
    /// drop is taken out of the frame's input and a notice names the file.
    fn refuse_oversized_drops(&mut self, ctx: &egui::Context) {
        let oversized = ctx.input(|i| {
            i.raw.dropped_files.iter().find_map(|file| {
                let path = file.path();
                let name = path.file_name()?.to_string_lossy().into_owned();
                let size = path
                    .is_absolute()
                    .then(|| std::fs::metadata(path).ok())??
                    .len();
                (size > self.drop_cap_for(&name)).then_some((name, size))
            })
        });
        if let Some((name, size)) = oversized {
            ctx.input_mut(|i| i.raw.dropped_files.clear());
            self.refuse_dropped(&name, size);
        }
    }

    /// Takes files as if the student had dropped them on the window together
    /// (a ROS map's YAML with its image): into the lesson's estimates, or handed
    /// in with homework open. Tests and the browser hook use it.
    pub fn open_estimate_files(&mut self, files: Vec<(String, Vec<u8>)>) {
        self.take_estimates(files.into_iter().map(|(n, b)| (n, Ok(b))).collect());
    }

    /// Takes a student's estimate files into the lesson (drawn and scored in
    /// *Your estimates*). With homework open, each file is first handed in:
    /// graded in the Assignment panel by the assignment's own kind (a
    /// trajectory, a graph, a map, a relative pose), then drawn on the map where
    /// the lesson's estimates can draw it. A file the grader refuses (made for
    /// another student's variant, another assignment) is said with the grader's
    /// reason and not drawn; what was handed in before stays.
    fn take_estimates(&mut self, files: Vec<(String, Result<Vec<u8>, String>)>) {
        // Outside homework, a ROS map's files come together: the YAML and its image.
        let homework = self
            .assignment
            .as_ref()
            .is_some_and(|d| d.prepared().is_some());
        let (map_files, files): (Vec<_>, Vec<_>) = files
            .into_iter()
            .partition(|(name, _)| !homework && widgets::estimates::is_map_file(name));
        if !map_files.is_empty() {
            self.take_map(map_files);
        }
        for (name, bytes) in files {
            let bytes = match bytes {
                Ok(b) => b,
                Err(why) => {
                    self.app_notices
                        .push(format!("Could not read {name}: {why}"));
                    continue;
                }
            };
            let homework = self.assignment.as_mut().filter(|d| d.prepared().is_some());
            let Some(desk) = homework else {
                // A graph named by `estimate=` in the pose-graph lesson is what a
                // dropped one is there: a solution of the graph on screen, or a new
                // problem.
                if name.to_ascii_lowercase().ends_with(".g2o")
                    && let Some(lesson) = self.lesson_as_mut::<pose_graph::PoseGraphLesson>()
                {
                    lesson.open_graph_file(&name, bytes);
                    continue;
                }
                match self.lesson.frame_mut().estimates_mut().add(&name, &bytes) {
                    // Added: said beside the title (the estimates window shows it too);
                    // the notices are for what went wrong or changed the run.
                    Ok(said) => self.exporter.status = Some(said),
                    Err(why) => self.app_notices.push(why),
                }
                continue;
            };
            match desk.hand_in(&name, &bytes) {
                Ok(grade) => {
                    let said = format!(
                        "{name}: {} of {} points, {}",
                        widgets::assignment::points(grade.score),
                        widgets::assignment::points(grade.max_score),
                        if grade.pass { "pass" } else { "fail" }
                    );
                    // Drawn where the lesson's estimates can draw it; the grade
                    // is in the Assignment panel, so the scores window opens
                    // only if the student had it open.
                    let estimates = self.lesson.frame_mut().estimates_mut();
                    let was_open = estimates.open;
                    let drawn = if widgets::estimates::is_estimate_file(&name, &bytes) {
                        estimates.add(&name, &bytes).err()
                    } else {
                        None
                    };
                    estimates.open = was_open;
                    // Said beside the title, as an estimate added is.
                    self.exporter.status = Some(match drawn {
                        None => said,
                        Some(why) => format!("{said} (not drawn: {why})"),
                    });
                }
                Err(why) => self.app_notices.push(why),
            }
        }
    }

    /// Takes a student's ROS map (its YAML and image) into the lesson's
    /// estimates, scored against the true map; says which it did, or why not.
    fn take_map(&mut self, files: Vec<(String, Result<Vec<u8>, String>)>) {
        let (read, refused) = widgets::dropped_files::sort_read(files);
        if let Some(why) = refused.into_iter().next() {
            self.app_notices.push(why);
            return;
        }
        if !self.lesson.scores_maps() {
            let names: Vec<&str> = read.iter().map(|(n, _)| n.as_str()).collect();
            self.app_notices.push(format!(
                "{}: this run has no true occupancy map to score a map against (the mapping lesson on a simulated robot has one)",
                names.join(", ")
            ));
            return;
        }
        match self.lesson.frame_mut().estimates_mut().add_map(&read) {
            Ok(said) => self.exporter.status = Some(said),
            Err(why) => self.app_notices.push(why),
        }
    }

    /// The student's estimates on the map and in their window.
    fn estimates_ui(&mut self, ctx: &egui::Context) {
        if self.lesson.frame().estimates().is_empty() && !self.lesson.frame().estimates().open {
            return;
        }
        // The report's picture shows the student's whole estimate, not the part
        // up to the time bar's time, until the picture has arrived.
        if !self.exporter.is_taking_picture() {
            self.report_picture = false;
        }
        let now = if self.report_picture {
            f64::INFINITY
        } else {
            self.lesson.estimate_clock().unwrap_or(f64::INFINITY)
        };
        widgets::estimates::map_overlay(ctx, self.lesson.frame_mut().estimates_mut(), now);
        if self.lesson.frame().estimates().open {
            self.score_estimates();
            let has_truth = self
                .lesson
                .trajectories()
                .iter()
                .any(|t| t.role == slamlab_sim::metrics::TrajectoryRole::Truth);
            widgets::estimates::window_ui(ctx, self.lesson.frame_mut().estimates_mut(), has_truth);
        }
    }

    /// Scores the estimates against the lesson's run as it is now.
    fn score_estimates(&mut self) {
        let tick = self.lesson.time_info().tick;
        // Stepping back and starting over change the run at the same tick: score
        // again at least twice a second.
        let version = tick.wrapping_mul(1_000_003).wrapping_add(self.frames / 30);
        if !self.lesson.frame().estimates().is_stale(version) {
            return;
        }
        let output = widgets::estimates::LessonOutput {
            trajectories: self.lesson.trajectories(),
            landmarks: self.lesson.landmark_maps(),
            relative_poses: self.lesson.relative_poses(),
            maps: self.lesson.occupancy_maps(),
        };
        self.lesson
            .frame_mut()
            .estimates_mut()
            .score(version, &output);
    }

    /// Opens a scenario file picked or dropped this frame. A dropped `.json` is taken
    /// out of the frame's input, so that a lesson that reads dropped maps or graphs
    /// does not also try it.
    fn poll_scenario_files(&mut self, ctx: &egui::Context) {
        let is_json = |file: &egui::DroppedFileHandle| {
            file.path()
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("json"))
        };
        let taken = widgets::dropped_files::take_dropped(ctx, is_json);
        let mut files = self.scenario_drops.read(ctx, taken).unwrap_or_default();
        files.extend(self.scenario_picker.poll());
        for (name, bytes) in files {
            let opened = bytes
                .and_then(|b| String::from_utf8(b).map_err(|_| "it is not text".to_owned()))
                .and_then(|text| slamlab_sim::io::scenario_file::ScenarioFile::parse(&text));
            match opened {
                Ok(file) => self.open_scenario(&file, &name),
                Err(e) => self.app_notices.push(format!("{name}: {e}")),
            }
        }
    }

    /// Opens a scenario file's lesson with its parameters and view, as a link with
    /// the same pairs would (its problems become notices).
    pub fn open_scenario(
        &mut self,
        file: &slamlab_sim::io::scenario_file::ScenarioFile,
        name: &str,
    ) {
        if registry::find(&file.lesson).is_none() {
            self.app_notices.push(format!(
                "{name}: no lesson '{}' in this SLAM Lab; the current lesson stays",
                file.lesson
            ));
            return;
        }
        let query = export::query_of_scenario(file, self.embed);
        // The lesson being left keeps its settings, as when switching lessons.
        let fresh = Self::with_settings(&query, Some(self.settings()));
        if !self.embed {
            self.stored.lessons = fresh.stored.lessons.clone();
        }
        self.lesson = fresh.lesson;
        self.figure = fresh.figure;
        self.app_notices = fresh.app_notices;
        self.dismissed.clear();
        self.address = query;
        self.address_changed = true;
        self.exporter.status = Some(format!("Opened {name}"));
    }

    /// Opens lesson `id` as the user left it (its stored settings), keeping the
    /// settings of the lesson being left.
    fn switch_lesson(&mut self, id: &str) {
        let Some(entry) = registry::find(id) else {
            return;
        };
        if !self.embed {
            self.stored
                .lessons
                .insert(self.lesson.id().to_owned(), self.lesson.stored_settings());
        }
        let stored = (!self.embed)
            .then(|| self.stored.lessons.get(entry.id))
            .flatten();
        self.lesson = registry::open(
            entry,
            &LessonStart {
                pairs: &[],
                embed: self.embed,
                stored,
                many_runs: None,
            },
        );
        self.app_notices.clear();
        self.dismissed.clear();
        self.address_follows_lesson();
    }

    /// Clears the lesson's note once the run has stepped back before it: what it
    /// said (a kidnap, a load, a closure added) is no longer on screen.
    fn expire_note(&mut self) {
        let tick = self.lesson.time_info().tick;
        let note = self.lesson.frame().note().map(str::to_owned);
        match (note, &self.note_since) {
            (None, _) => self.note_since = None,
            (Some(text), Some((seen, since))) if *seen == text => {
                if tick < *since {
                    *self.lesson.frame_mut().note_mut() = None;
                    self.note_since = None;
                }
            }
            (Some(text), _) => self.note_since = Some((text, tick)),
        }
    }

    /// The notices, in one box over the foot of the map `map`: "Notices (N)", each
    /// with its Dismiss button (dismissing the lesson's note clears it). The box
    /// takes the widest stretch of the map's foot that no corner window ("Your
    /// estimates", "Your solutions") covers.
    fn notices_ui(&mut self, ctx: &egui::Context, map: egui::Rect, notices: &[String]) {
        let max_height = (0.45 * map.height()).max(60.0);
        let foot =
            egui::Rect::from_x_y_ranges(map.x_range(), (map.bottom() - max_height)..=map.bottom());
        let covered: Vec<egui::Rangef> = widgets::estimates::corner_windows(ctx)
            .iter()
            .filter(|w| w.intersects(foot))
            .map(|w| w.x_range())
            .collect();
        let (left, right) = widgets::layout::widest_gap(map.x_range().shrink(8.0), &covered, 120.0);
        let width = (right - left).clamp(120.0, 720.0);
        egui::Area::new(egui::Id::unique("slamlab_notices"))
            .order(egui::Order::Middle)
            .fixed_pos(egui::pos2(left, map.bottom() - 8.0))
            .pivot(egui::Align2::LEFT_BOTTOM)
            .constrain(false)
            .show(ctx, |ui| {
                ui.set_max_width(width);
                egui::Frame::new()
                    .fill(ui.visuals().panel_fill)
                    .corner_radius(4.0)
                    .show(ui, |ui| {
                        ui.set_width(width);
                        egui::ScrollArea::vertical()
                            .max_height(max_height)
                            .show(ui, |ui| self.notice_bar_ui(ui, notices));
                    });
            });
    }

    fn notice_bar_ui(&mut self, ui: &mut egui::Ui, notices: &[String]) {
        let mut dismiss: Vec<String> = Vec::new();
        egui::Frame::new()
            .stroke(egui::Stroke::new(1.5, palette::VERMILLION))
            .inner_margin(egui::Margin::symmetric(6, 3))
            .corner_radius(4.0)
            .show(ui, |ui| {
                ui.set_width(ui.available_width());
                // One notice shares the count's row: the box covers as little of
                // the map as it can.
                let single = notices.len() == 1;
                ui.horizontal_wrapped(|ui| {
                    ui.label(
                        egui::RichText::new(format!("Notices ({})", notices.len()))
                            .strong()
                            .color(palette::VERMILLION),
                    );
                    if notices.len() > 1 && ui.small_button("Dismiss all").clicked() {
                        dismiss.extend(notices.iter().cloned());
                    }
                    if let Some(notice) = notices.first().filter(|_| single) {
                        notice_ui(ui, notice, &mut dismiss);
                    }
                });
                for notice in notices.iter().take(8).filter(|_| !single) {
                    ui.horizontal_wrapped(|ui| notice_ui(ui, notice, &mut dismiss));
                }
                if notices.len() > 8 {
                    ui.label(format!("… and {} more", notices.len() - 8));
                }
            });
        // A dismissed note is cleared (the next note with the same words shows).
        let note = self.lesson.frame().note().map(str::to_owned);
        if let Some(note) = note.filter(|n| dismiss.contains(n)) {
            *self.lesson.frame_mut().note_mut() = None;
            dismiss.retain(|d| *d != note);
        }
        self.dismissed.extend(dismiss);
    }
}

/// One notice with its Dismiss button (which adds it to `dismiss`).
fn notice_ui(ui: &mut egui::Ui, notice: &str, dismiss: &mut Vec<String>) {
    if ui
        .small_button("Dismiss")
        .on_hover_text("Hide this notice")
        .clicked()
    {
        dismiss.push(notice.to_owned());
    }
    ui.label(notice);
}

/// Opens the figure the way the URL asks: runs `tick=` ticks, sets the legend,
/// zoom and following, starts the clock for `run=1`. What a lesson cannot do
/// becomes a notice.
fn apply_figure(lesson: &mut dyn Lesson, figure: &query::FigureOptions, notices: &mut Vec<String>) {
    for _ in 0..figure.tick.unwrap_or(0) {
        lesson.apply_time_action(TimeAction::StepTick);
    }
    if let Some(on) = figure.legend
        && !lesson.set_legend(on)
    {
        notices.push("legend: this lesson's map has no legend to switch".to_owned());
    }
    if let Some(zoom) = figure.zoom {
        match lesson.map_view_mut() {
            Some(view) => view.zoom_after_fit(zoom),
            None => notices.push("zoom: this lesson has no map to zoom".to_owned()),
        }
    }
    if let Some(on) = figure.follow
        && !lesson.set_follow(on)
    {
        notices.push("follow: this lesson's map has no robot to follow".to_owned());
    }
    match figure.speed {
        Some(query::Speed::Max) => lesson.time_mut().max_speed = true,
        Some(query::Speed::TicksPerSecond(v)) => {
            let time = lesson.time_mut();
            time.max_speed = false;
            time.speed_tps = v;
        }
        None => {}
    }
    if figure.run && !lesson.time().running {
        lesson.apply_time_action(TimeAction::ToggleRun);
    }
}

/// The menu bar's and the embed header's title: one line of fixed width.
mod title_bar {
    /// The title (strong) and the export status after it, in `width` points, cut
    /// to one line (the whole on hover).
    pub fn title_ui(ui: &mut egui::Ui, title: &str, status: Option<&str>, width: f32) {
        let width = width.max(40.0);
        let mut job = egui::text::LayoutJob::default();
        let font = egui::TextStyle::Body.resolve(ui.style());
        job.append(
            title,
            0.0,
            egui::TextFormat::simple(font.clone(), ui.visuals().strong_text_color()),
        );
        if let Some(status) = status {
            job.append(
                &format!("   {status}"),
                0.0,
                egui::TextFormat::simple(font, ui.visuals().text_color()),
            );
        }
        let height = ui.spacing().interact_size.y;
        ui.allocate_ui_with_layout(
            egui::vec2(width, height),
            egui::Layout::left_to_right(egui::Align::Center),
            |ui| {
                ui.set_min_width(width);
                ui.add(egui::Label::new(job).truncate());
            },
        );
    }

    /// The width left on the current row, points.
    pub fn room_left(ui: &egui::Ui) -> f32 {
        ui.clip_rect().right().min(ui.max_rect().right()) - ui.cursor().min.x - 4.0
    }

    /// The width of `text` in the body font, points.
    pub fn text_width(ui: &egui::Ui, text: &str) -> f32 {
        let font = egui::TextStyle::Body.resolve(ui.style());
        ui.painter()
            .layout_no_wrap(text.to_owned(), font, egui::Color32::WHITE)
            .size()
            .x
    }
}

impl eframe::App for SlamLabApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.last_cpu_ms = frame.info().cpu_usage.map(|s| s * 1000.0);
        self.app_ui(ui);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        store_settings(storage, &self.settings());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stored_landmarks(count: &str) -> Settings {
        let mut settings = Settings::default();
        settings.lessons.insert(
            landmark_slam::LESSON_ID.to_owned(),
            serde_json::json!({ "params": [["landmarks", count]] }),
        );
        settings
    }

    #[test]
    fn stored_parameters_apply_only_without_url_parameters() {
        let settings = stored_landmarks("33");
        let app = SlamLabApp::with_settings("lesson=landmark-slam", Some(settings.clone()));
        assert_eq!(app.session().map(|s| s.scenario().landmarks), Some(33));
        let app = SlamLabApp::with_settings("lesson=landmark-slam&seed=4", Some(settings.clone()));
        assert_eq!(app.session().map(|s| s.scenario().landmarks), Some(20));
        let app = SlamLabApp::with_settings("embed=1", Some(settings));
        assert_eq!(app.session().map(|s| s.scenario().landmarks), Some(20));
    }

    #[test]
    fn an_embedded_page_saves_the_settings_it_found() {
        let mut stored = stored_landmarks("33");
        stored.lessons.insert(
            landmark_slam::LESSON_ID.to_owned(),
            serde_json::json!({
                "params": [["landmarks", "33"]],
                "view": { "heatmap": true, "follow_robot": true },
            }),
        );
        let app = SlamLabApp::with_settings("embed=1&landmarks=5", Some(stored.clone()));
        let view = app.landmark_lesson().map(|l| l.frame.view.clone());
        assert!(
            view.is_some_and(|v| !v.legend && !v.heatmap && !v.follow_robot),
            "an embedded figure does not take the stored view"
        );
        assert_eq!(app.settings(), stored);
        // The full app does.
        let app = SlamLabApp::with_settings("", Some(stored.clone()));
        assert!(app.landmark_lesson().is_some_and(|l| l.frame.view.heatmap));
    }

    /// A drop refused from its size (the browser's guard) is a notice naming
    /// the file and its size; what was dropped before stays. The mapping lesson
    /// takes laser files up to 1 GiB, any other file 64 MiB.
    #[test]
    fn a_refused_drop_is_said_and_keeps_what_was_there() {
        let mut app = SlamLabApp::from_query("lesson=landmark-slam&seed=2&tick=10");
        let tum = "0 0 0 0 0 0 0 1\n0.1 0.1 0 0 0 0 0 1\n";
        app.open_estimate_files(vec![("mine.tum".to_owned(), tum.as_bytes().to_vec())]);
        assert_eq!(app.lesson().frame().estimates().items().len(), 1);
        assert_eq!(app.drop_cap_for("big.tum"), 64 << 20);
        assert_eq!(app.drop_cap_for("intel.clf"), 64 << 20);
        app.refuse_dropped("big.tum", 65 << 20);
        assert_eq!(
            app.notices().last().map(String::as_str),
            Some(
                "big.tum has 68157440 bytes, more than the 67108864 bytes SLAM Lab reads: nothing of that drop was read, and the lesson goes on"
            )
        );
        assert_eq!(app.lesson().frame().estimates().items().len(), 1);
        let mapping = SlamLabApp::from_query("lesson=mapping");
        assert_eq!(mapping.drop_cap_for("intel.clf.bz2"), 1 << 30);
        assert_eq!(mapping.drop_cap_for("big.tum"), 64 << 20);
    }

    #[test]
    fn settings_round_trip() {
        let app = SlamLabApp::from_query("landmarks=12");
        let settings = app.settings();
        assert_eq!(
            settings.lessons[landmark_slam::LESSON_ID]["params"],
            serde_json::json!([["landmarks", "12"]])
        );
        let text = serde_json::to_string(&settings).unwrap_or_default();
        let back: Settings = serde_json::from_str(&text).unwrap_or_default();
        assert_eq!(back, settings);
    }

    /// eframe's storage, in memory.
    #[derive(Default)]
    struct MemoryStorage(BTreeMap<String, String>);

    impl eframe::Storage for MemoryStorage {
        fn get_string(&self, key: &str) -> Option<String> {
            self.0.get(key).cloned()
        }
        fn set_string(&mut self, key: &str, value: String) {
            self.0.insert(key.to_owned(), value);
        }
        fn remove_string(&mut self, key: &str) {
            self.0.remove(key);
        }
        fn flush(&mut self) {}
    }

    #[test]
    fn settings_are_stored_as_json_and_read_back() {
        use eframe::Storage as _;
        let settings = stored_landmarks("33");
        let mut storage = MemoryStorage::default();
        store_settings(&mut storage, &settings);
        let text = storage.get_string(SETTINGS_KEY).unwrap_or_default();
        assert!(text.starts_with('{'), "not JSON: {text}");
        assert_eq!(load_settings(&storage), Some(settings));
        storage.set_string(SETTINGS_KEY, "not settings".to_owned());
        assert_eq!(load_settings(&storage), None);
    }

    /// The desktop still reads the RON an earlier SLAM Lab stored.
    #[test]
    fn settings_stored_as_ron_are_read_on_the_desktop() {
        let settings = stored_landmarks("33");
        let mut storage = MemoryStorage::default();
        eframe::set_value(&mut storage, SETTINGS_KEY, &settings);
        assert_eq!(load_settings(&storage), Some(settings));
    }

    #[test]
    fn stored_settings_that_do_not_fit_are_dropped_quietly() {
        let mut settings = Settings::default();
        settings.lessons.insert(
            landmark_slam::LESSON_ID.to_owned(),
            serde_json::json!({ "params": "nonsense", "view": 7 }),
        );
        let app = SlamLabApp::with_settings("", Some(settings));
        assert_eq!(app.session().map(|s| s.scenario().landmarks), Some(20));
        assert!(app.notices().is_empty());
    }
}
