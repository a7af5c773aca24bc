//! Lessons as a family: the trait every lesson implements and what the shell
//! opens them with. The menu of lessons is [`crate::registry`]: this module names
//! no lesson, so every lesson imports it and it imports none of them.
//!
//! The shell (menu, time bar, notices, theme, persistence, share links, test
//! hooks) never matches on a concrete lesson: it holds a `Box<dyn Lesson>`, the
//! way egui's demo app holds its demos. A new lesson is a folder in this crate
//! that implements [`Lesson`], plus one [`crate::registry::LessonEntry`] in
//! [`crate::registry::LESSONS`] (`docs/ADDING-A-LESSON.md` has the whole recipe).

use crate::time_control::{TimeAction, TimeControl, TimeInfo};
use crate::widgets::map_canvas::MapView;
use std::any::Any;

pub use crate::panels::PanelVisibility;

/// What a lesson is opened with.
#[derive(Clone, Copy, Debug)]
pub struct LessonStart<'a> {
    /// The URL's `key=value` pairs that belong to the lesson, in order.
    pub pairs: &'a [(String, String)],
    /// The compact layout of a lecture-page figure.
    pub embed: bool,
    /// What this lesson stored last time ([`Lesson::stored_settings`]); `None` in an
    /// embedded figure, which always opens the same way for every student.
    pub stored: Option<&'a serde_json::Value>,
    /// `many-runs=N` from the URL, for lessons that have such a window.
    pub many_runs: Option<usize>,
}

impl LessonStart<'_> {
    /// The value of the last `key=` pair in the link, if any.
    pub fn last_value(&self, key: &str) -> Option<String> {
        self.pairs
            .iter()
            .rev()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.clone())
    }
}

/// What a lesson remembers between visits: its view options, its clock's speed,
/// and the user's parameters that differ from the lesson's start.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct StoredSettings<V> {
    /// Map layers and windows.
    pub view: V,
    /// The clock's speed.
    pub time: TimeControl,
    /// The user's parameters, as `key=value` pairs.
    pub params: Vec<(String, String)>,
}

impl<V: Default + serde::Serialize + serde::de::DeserializeOwned> StoredSettings<V> {
    /// What the lesson stored, unless this is an embedded figure (which opens the
    /// same way for every student) or the stored value no longer fits (dropped quietly).
    pub fn from_start(start: &LessonStart<'_>) -> Option<Self> {
        start
            .stored
            .filter(|_| !start.embed)
            .and_then(|value| serde_json::from_value(value.clone()).ok())
    }

    /// As JSON for [`Lesson::stored_settings`].
    pub fn to_value(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or_default()
    }

    /// Gives `time` the stored speed (the clock itself starts paused).
    pub fn restore_clock(&self, time: &mut TimeControl) {
        time.speed_tps = self.time.speed_tps;
        time.max_speed = self.time.max_speed;
    }
}

/// A lesson's scenario as it opens: `default`, then the stored parameters when the
/// URL gives none, then the URL's pairs. Returns it with the link's problems as
/// notices ("link: …").
pub fn scenario_from_start<S: slamlab_sim::params::Scenario>(
    start: &LessonStart<'_>,
    default: S,
    stored: Option<&[(String, String)]>,
) -> (S, Vec<String>) {
    use slamlab_sim::params;
    let mut scenario = default;
    if start.pairs.is_empty()
        && let Some(stored) = stored
    {
        let pairs = stored.iter().map(|(k, v)| (k.as_str(), v.as_str()));
        // Stored values were valid when saved; anything stale is dropped quietly.
        let _ignored = params::apply_pairs(&mut scenario, pairs, &crate::query::APP_KEYS);
    }
    let pairs = start.pairs.iter().map(|(k, v)| (k.as_str(), v.as_str()));
    let notices = params::apply_pairs(&mut scenario, pairs, &crate::query::APP_KEYS)
        .iter()
        .map(|issue| format!("link: {issue}"))
        .collect();
    (scenario, notices)
}

/// Opens lesson `L` the way every lesson opens: its scenario is the lesson's
/// `default`, then the parameters it stored last time when the link gives none,
/// then the link's `start.pairs` ([`scenario_from_start`]); `new` builds the
/// lesson on it, and `frame` reaches the lesson's [`LessonFrame`], which gets the
/// link's problems as notices (before the lesson's own) and the stored view and
/// clock speed. `Err` is why `new` refused (a lesson whose `new` cannot fail
/// says so with [`std::convert::Infallible`]): the lesson then opens
/// [`open_instead`], saying so in its own words.
pub fn open_lesson<S, V, L, E>(
    start: &LessonStart<'_>,
    default: S,
    new: impl FnOnce(S) -> Result<L, E>,
    frame: impl FnOnce(&mut L) -> &mut LessonFrame<V>,
) -> Result<L, E>
where
    S: slamlab_sim::params::Scenario,
    V: LessonView,
{
    let stored = StoredSettings::<V>::from_start(start);
    let (scenario, link_notices) =
        scenario_from_start(start, default, stored.as_ref().map(|s| s.params.as_slice()));
    let mut lesson = new(scenario)?;
    let settled = frame(&mut lesson);
    settled.notices.splice(0..0, link_notices);
    settled.restore(stored.as_ref());
    Ok(lesson)
}

/// `frame` and `frame_mut` for a lesson whose [`LessonFrame`] is its field `frame`:
/// write `frame_accessors!();` in its `impl Lesson`.
macro_rules! frame_accessors {
    () => {
        fn frame(&self) -> &dyn $crate::lesson::Frame {
            &self.frame
        }
        fn frame_mut(&mut self) -> &mut dyn $crate::lesson::Frame {
            &mut self.frame
        }
    };
}
pub(crate) use frame_accessors;

/// A share link's pairs with the seed first, when the changed parameters do not
/// already hold it: a link reproduces its run even after the lesson's default seed
/// changes.
pub fn with_seed(mut pairs: Vec<(String, String)>, seed: u64) -> Vec<(String, String)> {
    if !pairs.iter().any(|(name, _)| name == "seed") {
        pairs.insert(0, ("seed".to_owned(), seed.to_string()));
    }
    pairs
}

/// A lesson that could not open, with a notice that says `why` (only a broken build
/// gets here: every lesson's defaults are tested). The registry
/// ([`crate::registry::open`]) opens the default lesson in its place with the notice,
/// so no lesson needs to import another.
pub fn open_instead(_start: &LessonStart<'_>, why: String) -> Box<dyn Lesson> {
    let mut frame = LessonFrame::new("", ());
    frame.notices.push(why.clone());
    Box::new(CouldNotOpen { why, frame })
}

/// What [`open_instead`] returns: a placeholder the registry replaces.
#[derive(Debug)]
pub struct CouldNotOpen {
    why: String,
    frame: LessonFrame<()>,
}

impl crate::widgets::layout::LessonPanels for CouldNotOpen {
    fn plots_ui(&mut self, _ui: &mut egui::Ui) {}
    fn parameters_ui(&mut self, _ui: &mut egui::Ui) {}
    fn explanation_ui(&mut self, _ui: &mut egui::Ui) {}
    fn map_ui(&mut self, ui: &mut egui::Ui) {
        ui.label(&self.why);
    }
}

impl Lesson for CouldNotOpen {
    frame_accessors!();
    fn could_not_open(&self) -> Option<&str> {
        Some(&self.why)
    }
    fn time_info(&self) -> TimeInfo {
        TimeInfo::default()
    }
    fn on_time_action(&mut self, _action: TimeAction) {}
    fn advance(&mut self, _dt: f64) {}
    fn changed_params(&self) -> Vec<(String, String)> {
        Vec::new()
    }
    fn stored_settings(&self) -> serde_json::Value {
        serde_json::Value::Null
    }
    fn share_query(&self, _embed: bool) -> String {
        String::new()
    }
    fn test_state(&self) -> serde_json::Value {
        serde_json::Value::Null
    }
}

/// What a lesson asks of the shell, which it cannot do from inside its panels.
pub enum LessonRequest {
    /// Save these files (downloads in the browser, the working folder on the
    /// desktop).
    Save(Vec<crate::export::ExportFile>),
    /// Open the Monte Carlo localization lesson on this map (a hand-off between
    /// lessons: localizing in a map just built). The shell asks the registry
    /// ([`crate::registry::localize_in_map`]), so the lesson that asks never names
    /// the lesson that answers.
    LocalizeInMap {
        /// What the map is called in the localization lesson's notes.
        name: String,
        /// The map.
        grid: slamlab_core::grid::OccupancyGrid,
    },
}

impl std::fmt::Debug for LessonRequest {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Save(files) => write!(f, "Save({} files)", files.len()),
            Self::LocalizeInMap { name, .. } => write!(f, "LocalizeInMap({name})"),
        }
    }
}

/// A lesson's view settings (map layers, windows): saved between visits, and, when
/// the lesson has them, the map legend's switch and the switch that makes the map
/// follow the robot (the URL's `legend=` and `follow=`).
pub trait LessonView:
    Clone + Default + std::fmt::Debug + serde::Serialize + serde::de::DeserializeOwned + 'static
{
    /// The map legend's switch.
    fn legend_mut(&mut self) -> Option<&mut bool> {
        None
    }
    /// The switch that keeps the robot in the middle of the map.
    fn follow_mut(&mut self) -> Option<&mut bool> {
        None
    }
}

impl LessonView for () {}

/// Implements [`LessonView`] for a view struct from the names of its legend and
/// follow switches: `lesson_view!(KidnapView, legend: legend, follow: follow_robot);`
/// (either may be left out).
macro_rules! lesson_view {
    ($view:ty $(, legend: $legend:ident)? $(, follow: $follow:ident)?) => {
        impl $crate::lesson::LessonView for $view {
            $(fn legend_mut(&mut self) -> Option<&mut bool> {
                Some(&mut self.$legend)
            })?
            $(fn follow_mut(&mut self) -> Option<&mut bool> {
                Some(&mut self.$follow)
            })?
        }
    };
}
pub(crate) use lesson_view;

/// What every lesson holds the same way: its id, its clock, its view settings, its
/// map view, its notices and its requests to the shell. Each lesson keeps one in a
/// field named `frame`; the [`Lesson`] trait's default methods reach it (through
/// [`Frame`]), so that a lesson's `impl Lesson` is only what is particular to it.
#[derive(Debug)]
pub struct LessonFrame<V> {
    id: &'static str,
    /// The lesson's clock.
    pub time: TimeControl,
    /// What the lesson shows (saved with the user's settings).
    pub view: V,
    /// The map's pan and zoom, for a lesson with a map ([`LessonFrame::with_map`]).
    pub map: MapView,
    has_map: bool,
    /// Link problems and what the run had to change, shown in the notices.
    pub notices: Vec<String>,
    /// The latest refusal or load result: the first of the notices, counted with
    /// them. It holds until the student starts over, steps back before it, or
    /// dismisses it (the shell clears it then), or the lesson replaces it.
    pub note: Option<String>,
    /// A request for the shell ([`Lesson::take_request`]).
    pub request: Option<LessonRequest>,
    /// The lesson started over on a file the URL named
    /// ([`Lesson::take_restarted_from_link`]).
    pub restarted_from_link: bool,
    /// A student's own estimates, scored beside the lesson's estimators.
    pub estimates: crate::widgets::estimates::Estimates,
}

impl<V: LessonView> LessonFrame<V> {
    /// The frame of lesson `id` with `view`, a paused clock and no map.
    pub fn new(id: &'static str, view: V) -> Self {
        Self {
            id,
            time: TimeControl::default(),
            view,
            map: MapView::default(),
            has_map: false,
            notices: Vec::new(),
            note: None,
            request: None,
            restarted_from_link: false,
            estimates: crate::widgets::estimates::Estimates::default(),
        }
    }

    /// The same frame with a map (the URL's `zoom=` applies to it).
    pub fn with_map(mut self, map: MapView) -> Self {
        self.map = map;
        self.has_map = true;
        self
    }

    /// The same frame with the stored clock speed and view, when there are any.
    pub fn restored(mut self, stored: Option<&StoredSettings<V>>) -> Self {
        self.restore(stored);
        self
    }

    /// Gives the frame the stored clock speed and view, when there are any.
    pub fn restore(&mut self, stored: Option<&StoredSettings<V>>) {
        if let Some(stored) = stored {
            stored.restore_clock(&mut self.time);
            self.view = stored.view.clone();
        }
    }

    /// The same frame with this clock (a lesson's own speed).
    pub fn with_time(mut self, time: TimeControl) -> Self {
        self.time = time;
        self
    }

    /// The same frame with these notices.
    pub fn with_notices(mut self, notices: Vec<String>) -> Self {
        self.notices = notices;
        self
    }
}

/// A lesson's [`LessonFrame`], whatever its view type: what the [`Lesson`] trait's
/// default methods use.
pub trait Frame {
    /// The lesson's id.
    fn id(&self) -> &'static str;
    /// The clock.
    fn time(&self) -> &TimeControl;
    /// The clock, to change.
    fn time_mut(&mut self) -> &mut TimeControl;
    /// The frame's notices.
    fn notices(&self) -> &[String];
    /// The notices, to add to.
    fn notices_mut(&mut self) -> &mut Vec<String>;
    /// The view settings as JSON (for [`StoredSettings`]).
    fn view_json(&self) -> serde_json::Value;
    /// The map view, if the lesson has a map.
    fn map_view_mut(&mut self) -> Option<&mut MapView>;
    /// Switches the legend; false without one.
    fn set_legend(&mut self, on: bool) -> bool;
    /// Switches following; false when nothing can be followed.
    fn set_follow(&mut self, on: bool) -> bool;
    /// The request for the shell, taken.
    fn take_request(&mut self) -> Option<LessonRequest>;
    /// Whether the lesson started over on a linked file, taken.
    fn take_restarted_from_link(&mut self) -> bool;
    /// The student's estimates.
    fn estimates(&self) -> &crate::widgets::estimates::Estimates;
    /// The student's estimates, to add to.
    fn estimates_mut(&mut self) -> &mut crate::widgets::estimates::Estimates;
    /// The note (the latest refusal or load result), to set or clear.
    fn note_mut(&mut self) -> &mut Option<String>;
    /// The note.
    fn note(&self) -> Option<&str>;
}

impl<V: LessonView> Frame for LessonFrame<V> {
    fn id(&self) -> &'static str {
        self.id
    }
    fn time(&self) -> &TimeControl {
        &self.time
    }
    fn time_mut(&mut self) -> &mut TimeControl {
        &mut self.time
    }
    fn notices(&self) -> &[String] {
        &self.notices
    }
    fn notices_mut(&mut self) -> &mut Vec<String> {
        &mut self.notices
    }
    fn view_json(&self) -> serde_json::Value {
        serde_json::to_value(&self.view).unwrap_or_default()
    }
    fn map_view_mut(&mut self) -> Option<&mut MapView> {
        self.has_map.then_some(&mut self.map)
    }
    fn set_legend(&mut self, on: bool) -> bool {
        self.view.legend_mut().map(|l| *l = on).is_some()
    }
    fn set_follow(&mut self, on: bool) -> bool {
        self.view.follow_mut().map(|f| *f = on).is_some()
    }
    fn take_request(&mut self) -> Option<LessonRequest> {
        self.request.take()
    }
    fn take_restarted_from_link(&mut self) -> bool {
        std::mem::take(&mut self.restarted_from_link)
    }
    fn estimates(&self) -> &crate::widgets::estimates::Estimates {
        &self.estimates
    }
    fn estimates_mut(&mut self) -> &mut crate::widgets::estimates::Estimates {
        &mut self.estimates
    }
    fn note_mut(&mut self) -> &mut Option<String> {
        &mut self.note
    }
    fn note(&self) -> Option<&str> {
        self.note.as_deref()
    }
}

/// Any `'static` value as [`Any`], for [`Lesson::as_any`]'s default.
pub trait AsAny: Any {
    /// As `&dyn Any`.
    fn any_ref(&self) -> &dyn Any;
    /// As `&mut dyn Any`.
    fn any_mut(&mut self) -> &mut dyn Any;
}

impl<T: Any> AsAny for T {
    fn any_ref(&self) -> &dyn Any {
        self
    }
    fn any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// One lesson on screen. Everything the shell needs, nothing it must know about
/// the lesson's world. What every lesson does the same way is written here once,
/// on the lesson's [`LessonFrame`]; a lesson implements what is its own: what the
/// time bar shows, what a step does, how it advances, its panels
/// ([`LessonPanels`](crate::widgets::layout::LessonPanels)), its parameters in a
/// share link, and its part of the test hook's state.
pub trait Lesson: crate::widgets::layout::LessonPanels + AsAny + std::fmt::Debug {
    /// The lesson's frame ([`frame_accessors!`] writes this and the next).
    fn frame(&self) -> &dyn Frame;
    /// The lesson's frame, to change.
    fn frame_mut(&mut self) -> &mut dyn Frame;

    /// The lesson's id, as in [`crate::registry::LESSONS`].
    fn id(&self) -> &'static str {
        self.frame().id()
    }
    /// What runs now, for the top bar after the lesson's title ("EKF vs UKF");
    /// empty for nothing.
    fn subtitle(&self) -> String {
        String::new()
    }
    /// Things the user should know now, in the one notices box: the note (the
    /// latest refusal or load result), the frame's notices (link problems, what
    /// the run had to change) and the run's latest ([`Lesson::run_notices`]).
    fn notices(&self) -> Vec<String> {
        let mut all: Vec<String> = self.frame().note().map(str::to_owned).into_iter().collect();
        all.extend(self.frame().notices().iter().cloned());
        all.extend(self.run_notices());
        all
    }
    /// The run's latest notes and errors, after the frame's notices.
    fn run_notices(&self) -> Vec<String> {
        Vec::new()
    }
    /// The lesson's clock.
    fn time(&self) -> &TimeControl {
        self.frame().time()
    }
    /// The lesson's clock, to change its speed.
    fn time_mut(&mut self) -> &mut TimeControl {
        self.frame_mut().time_mut()
    }
    /// What the time bar shows.
    fn time_info(&self) -> TimeInfo;
    /// Which step buttons the time bar shows: phases and ticks unless the lesson
    /// has one kind of step.
    fn step_controls(&self) -> crate::time_control::StepControls {
        crate::time_control::StepControls::PhasesAndTicks
    }
    /// Does what a time-bar button or shortcut asks: the clock takes it first
    /// (run, pause, stop on a step), then the lesson ([`Lesson::on_time_action`]).
    /// Starting over clears the note (a reset that fails leaves its own).
    fn apply_time_action(&mut self, action: TimeAction) {
        if action == TimeAction::Reset {
            *self.frame_mut().note_mut() = None;
        }
        self.time_mut().apply(action);
        self.on_time_action(action);
    }
    /// The key moment the run has just passed ("loop closure found at scan 158"),
    /// shown in the time bar; `None` for most lessons and most ticks.
    fn moment(&self) -> Option<String> {
        None
    }
    /// The lesson's part of a time-bar action: step a phase or a tick, step back,
    /// start over.
    fn on_time_action(&mut self, action: TimeAction);
    /// Reads the lesson's own input (drive keys, dropped files) before the clock
    /// advances.
    fn read_input(&mut self, _ctx: &egui::Context) {}
    /// Runs what the clock owes after `dt` seconds of real time, within the frame budget.
    fn advance(&mut self, dt: f64);
    /// Did the last [`advance`](Self::advance) run a filter update (a heavy
    /// step the frame timing reports apart, such as grid FastSLAM's scan
    /// matching)? Lessons without heavy steps keep the default.
    fn last_advance_updated(&self) -> bool {
        false
    }
    /// Does anything need another frame soon?
    fn wants_repaint(&self) -> bool {
        self.time().running
    }
    /// The panels and the map.
    fn panels_ui(&mut self, ui: &mut egui::Ui, panels: &mut PanelVisibility, compact: bool) {
        let id = self.id();
        crate::widgets::layout::lesson_panels_ui(self, ui, panels, compact, id);
    }
    /// The lesson's entries in the View menu (map layers, windows).
    fn view_menu_ui(&mut self, _ui: &mut egui::Ui) {}
    /// The user's parameters that differ from the lesson's start, as `key=value`
    /// pairs (stored between visits).
    fn changed_params(&self) -> Vec<(String, String)>;
    /// The pairs of a share link: the changed parameters unless the lesson adds
    /// more (the seed, a loaded file's location).
    fn share_pairs(&self) -> Vec<(String, String)> {
        self.changed_params()
    }
    /// What to remember between visits (view options, clock speed, the user's
    /// parameters); given back as [`LessonStart::stored`].
    fn stored_settings(&self) -> serde_json::Value {
        StoredSettings {
            view: self.frame().view_json(),
            time: self.time().clone(),
            params: self.changed_params(),
        }
        .to_value()
    }
    /// The query string (without `?`) that reopens this setup.
    fn share_query(&self, embed: bool) -> String {
        crate::query::build(self.id(), &self.share_pairs(), embed)
    }
    /// The lesson's part of the test hook's JSON (tick, phase, seed, estimators, errors).
    fn test_state(&self) -> serde_json::Value;
    /// For tests and the shell's typed helpers.
    fn as_any(&self) -> &dyn Any {
        self.any_ref()
    }
    /// For tests and the shell's typed helpers.
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self.any_mut()
    }
    /// The lesson's map view, for the URL's `zoom=`; `None` for a lesson without a
    /// [`MapView`] (the shell then says the zoom does not apply).
    fn map_view_mut(&mut self) -> Option<&mut MapView> {
        self.frame_mut().map_view_mut()
    }
    /// Shows or hides the map's legend (the URL's `legend=`); false when the lesson
    /// has no legend to switch.
    fn set_legend(&mut self, on: bool) -> bool {
        self.frame_mut().set_legend(on)
    }
    /// Makes the map follow the robot or not (the URL's `follow=`); false when the
    /// lesson's map cannot follow anything.
    fn set_follow(&mut self, on: bool) -> bool {
        self.frame_mut().set_follow(on)
    }
    /// The lesson's own keys beside the time bar's, for the Keys menu.
    fn keys(&self) -> Vec<(&'static str, &'static str)> {
        Vec::new()
    }
    /// Has the lesson started over on a file the URL named (a map read after the
    /// first frame) since the last call? The shell then applies the URL's figure keys
    /// (`tick=`, `run=`, `zoom=`, …) again, so that the link opens as shared.
    fn take_restarted_from_link(&mut self) -> bool {
        self.frame_mut().take_restarted_from_link()
    }
    /// The run's trajectories so far: the truth (where there is one), odometry,
    /// and each estimator's estimate, for File → Export trajectories and for
    /// scoring a student's estimate beside them; none for a lesson without poses.
    fn trajectories(&self) -> Vec<slamlab_sim::metrics::NamedTrajectory> {
        Vec::new()
    }
    /// The time a student's estimate is drawn and scored up to, seconds: the time
    /// bar's; `None` for a lesson whose trajectories are not in time (a pose
    /// graph's vertices), drawn whole.
    fn estimate_clock(&self) -> Option<f64> {
        Some(self.time_info().time_s)
    }
    /// The landmark maps now: the true one (named `truth`) and each estimator's.
    fn landmark_maps(&self) -> Vec<(String, Vec<slamlab_sim::io::trajectory::LandmarkRow>)> {
        Vec::new()
    }
    /// The relative pose of the two views shown now (two-view geometry): the true
    /// one (named `truth`) and the lesson's estimate; a student's dropped relative
    /// pose is scored against the true one.
    fn relative_poses(&self) -> Vec<(String, slamlab_core::vision::RelativePose)> {
        Vec::new()
    }
    /// Does the run have a true occupancy map to score a student's map against?
    /// Then a ROS map dropped on the window is the student's map (an estimate),
    /// not a world for the lesson to open.
    fn scores_maps(&self) -> bool {
        false
    }
    /// The occupancy maps now, as ROS maps (three states): the true one (named
    /// `truth`) and each estimator's; a student's dropped map is scored against
    /// the true one with the same metric.
    fn occupancy_maps(&self) -> Vec<(String, std::sync::Arc<slamlab_core::grid::OccupancyGrid>)> {
        Vec::new()
    }
    /// Every plot's data, unthinned, for "Export plot data as CSV".
    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        Vec::new()
    }
    /// A request for the shell, taken once (polled every frame).
    fn take_request(&mut self) -> Option<LessonRequest> {
        self.frame_mut().take_request()
    }
    /// Why the lesson could not open, if it could not ([`open_instead`]).
    fn could_not_open(&self) -> Option<&str> {
        None
    }
}

/// Adds a notice to a lesson.
pub trait LessonExt {
    /// This lesson, showing `notice` first.
    fn with_notice(self, notice: String) -> Box<dyn Lesson>;
}

impl LessonExt for Box<dyn Lesson> {
    fn with_notice(mut self, notice: String) -> Box<dyn Lesson> {
        self.frame_mut().notices_mut().insert(0, notice);
        self
    }
}

/// Runs a lesson's phases until the clock's due ticks are done or the frame budget
/// is spent, whichever comes first: the one frame-budgeted advance every lesson
/// uses. `step_phase` runs one phase and says whether it finished a tick.
/// Returns the ticks finished.
pub fn advance_within_budget(
    time: &mut TimeControl,
    dt: f64,
    step_phase: impl FnMut() -> bool,
) -> u64 {
    advance_within_ms(time, dt, crate::time_control::FRAME_BUDGET_MS, step_phase)
}

/// As [`advance_within_budget`], with a budget of `budget_ms` milliseconds (a
/// lesson whose drawing needs more of the frame spends less on its phases).
pub fn advance_within_ms(
    time: &mut TimeControl,
    dt: f64,
    budget_ms: u128,
    mut step_phase: impl FnMut() -> bool,
) -> u64 {
    use crate::time_control::TicksDue;
    let due = time.ticks_due(dt);
    if due == TicksDue::Count(0) {
        return 0;
    }
    let budget_ms = time.budget_ms(budget_ms);
    let start = web_time::Instant::now();
    let mut done = 0_u64;
    loop {
        if let TicksDue::Count(n) = due
            && done >= n
        {
            break;
        }
        if start.elapsed().as_millis() >= budget_ms {
            break;
        }
        if step_phase() {
            done += 1;
        }
    }
    time.ticks_done(done);
    done
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_advance_stops_at_the_ticks_due() {
        let mut time = TimeControl::default();
        time.apply(TimeAction::ToggleRun);
        let mut phases = 0;
        // 0.25 s at 10 ticks/s: 2 ticks due, each of three phases.
        let done = advance_within_budget(&mut time, 0.25, || {
            phases += 1;
            phases % 3 == 0
        });
        assert_eq!((done, phases), (2, 6));
    }
}
