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

/// A lesson that could not open, with a notice that says `why` (only a broken build
/// gets here: every lesson's defaults are tested). The registry
/// ([`crate::registry::open`]) opens the default lesson in its place with the notice,
/// so no lesson needs to import another.
pub fn open_instead(_start: &LessonStart<'_>, why: String) -> Box<dyn Lesson> {
    Box::new(CouldNotOpen {
        why,
        time: TimeControl::default(),
    })
}

/// What [`open_instead`] returns: a placeholder the registry replaces.
#[derive(Debug)]
pub struct CouldNotOpen {
    why: String,
    time: TimeControl,
}

impl Lesson for CouldNotOpen {
    fn id(&self) -> &'static str {
        ""
    }
    fn could_not_open(&self) -> Option<&str> {
        Some(&self.why)
    }
    fn notices(&self) -> Vec<String> {
        vec![self.why.clone()]
    }
    fn time(&self) -> &TimeControl {
        &self.time
    }
    fn time_mut(&mut self) -> &mut TimeControl {
        &mut self.time
    }
    fn time_info(&self) -> TimeInfo {
        TimeInfo::default()
    }
    fn apply_time_action(&mut self, _action: TimeAction) {}
    fn advance(&mut self, _dt: f64) {}
    fn panels_ui(&mut self, ui: &mut egui::Ui, _panels: &mut PanelVisibility, _compact: bool) {
        ui.label(&self.why);
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
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
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

/// One lesson on screen. Everything the shell needs, nothing it must know about
/// the lesson's world.
pub trait Lesson: std::fmt::Debug {
    /// The lesson's id, as in [`crate::registry::LESSONS`].
    fn id(&self) -> &'static str;
    /// What runs now, for the top bar after the lesson's title ("EKF vs UKF");
    /// empty for nothing.
    fn subtitle(&self) -> String {
        String::new()
    }
    /// Things the user should know now: link problems, what the run had to change,
    /// the latest errors.
    fn notices(&self) -> Vec<String>;
    /// The lesson's clock.
    fn time(&self) -> &TimeControl;
    /// The lesson's clock, to change its speed.
    fn time_mut(&mut self) -> &mut TimeControl;
    /// What the time bar shows.
    fn time_info(&self) -> TimeInfo;
    /// Which step buttons the time bar shows: phases and ticks unless the lesson
    /// has one kind of step.
    fn step_controls(&self) -> crate::time_control::StepControls {
        crate::time_control::StepControls::PhasesAndTicks
    }
    /// Does what a time-bar button or shortcut asks.
    fn apply_time_action(&mut self, action: TimeAction);
    /// Reads the lesson's own input (drive keys) before the clock advances.
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
    fn panels_ui(&mut self, ui: &mut egui::Ui, panels: &mut PanelVisibility, compact: bool);
    /// The lesson's entries in the View menu (map layers, windows).
    fn view_menu_ui(&mut self, _ui: &mut egui::Ui) {}
    /// What to remember between visits (view options, clock speed, the user's
    /// parameters); given back as [`LessonStart::stored`].
    fn stored_settings(&self) -> serde_json::Value;
    /// The query string (without `?`) that reopens this setup.
    fn share_query(&self, embed: bool) -> String;
    /// The lesson's part of the test hook's JSON (tick, phase, seed, estimators, errors).
    fn test_state(&self) -> serde_json::Value;
    /// For tests and the shell's typed helpers.
    fn as_any(&self) -> &dyn Any;
    /// For tests and the shell's typed helpers.
    fn as_any_mut(&mut self) -> &mut dyn Any;
    /// The lesson's map view, for the URL's `zoom=`; `None` for a lesson without a
    /// [`MapView`](crate::widgets::map_canvas::MapView) (the shell then says the
    /// zoom does not apply).
    fn map_view_mut(&mut self) -> Option<&mut crate::widgets::map_canvas::MapView> {
        None
    }
    /// Shows or hides the map's legend (the URL's `legend=`); false when the lesson
    /// has no legend to switch.
    fn set_legend(&mut self, _on: bool) -> bool {
        false
    }
    /// Makes the map follow the robot or not (the URL's `follow=`); false when the
    /// lesson's map cannot follow anything.
    fn set_follow(&mut self, _on: bool) -> bool {
        false
    }
    /// The lesson's own keys beside the time bar's, for the Keys menu.
    fn keys(&self) -> Vec<(&'static str, &'static str)> {
        Vec::new()
    }
    /// Has the lesson started over on a file the URL named (a map read after the
    /// first frame) since the last call? The shell then applies the URL's figure keys
    /// (`tick=`, `run=`, `zoom=`, …) again, so that the link opens as shared.
    fn take_restarted_from_link(&mut self) -> bool {
        false
    }
    /// Every plot's data, unthinned, for "Export plot data as CSV".
    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        Vec::new()
    }
    /// A request for the shell, taken once (polled every frame).
    fn take_request(&mut self) -> Option<LessonRequest> {
        None
    }
    /// Why the lesson could not open, if it could not ([`open_instead`]).
    fn could_not_open(&self) -> Option<&str> {
        None
    }
}

/// A lesson with one more notice in front of its own (a lesson that opened in
/// place of another says why).
#[derive(Debug)]
pub struct WithNotice {
    inner: Box<dyn Lesson>,
    notice: String,
}

/// Adds a notice to a lesson.
pub trait LessonExt {
    /// This lesson, showing `notice` first.
    fn with_notice(self, notice: String) -> Box<dyn Lesson>;
}

impl LessonExt for Box<dyn Lesson> {
    fn with_notice(self, notice: String) -> Box<dyn Lesson> {
        Box::new(WithNotice {
            inner: self,
            notice,
        })
    }
}

impl Lesson for WithNotice {
    fn id(&self) -> &'static str {
        self.inner.id()
    }
    fn subtitle(&self) -> String {
        self.inner.subtitle()
    }
    fn notices(&self) -> Vec<String> {
        let mut all = vec![self.notice.clone()];
        all.extend(self.inner.notices());
        all
    }
    fn time(&self) -> &TimeControl {
        self.inner.time()
    }
    fn time_mut(&mut self) -> &mut TimeControl {
        self.inner.time_mut()
    }
    fn time_info(&self) -> TimeInfo {
        self.inner.time_info()
    }
    fn step_controls(&self) -> crate::time_control::StepControls {
        self.inner.step_controls()
    }
    fn apply_time_action(&mut self, action: TimeAction) {
        self.inner.apply_time_action(action);
    }
    fn read_input(&mut self, ctx: &egui::Context) {
        self.inner.read_input(ctx);
    }
    fn advance(&mut self, dt: f64) {
        self.inner.advance(dt);
    }
    fn last_advance_updated(&self) -> bool {
        self.inner.last_advance_updated()
    }
    fn wants_repaint(&self) -> bool {
        self.inner.wants_repaint()
    }
    fn panels_ui(&mut self, ui: &mut egui::Ui, panels: &mut PanelVisibility, compact: bool) {
        self.inner.panels_ui(ui, panels, compact);
    }
    fn view_menu_ui(&mut self, ui: &mut egui::Ui) {
        self.inner.view_menu_ui(ui);
    }
    fn stored_settings(&self) -> serde_json::Value {
        self.inner.stored_settings()
    }
    fn share_query(&self, embed: bool) -> String {
        self.inner.share_query(embed)
    }
    fn test_state(&self) -> serde_json::Value {
        self.inner.test_state()
    }
    fn as_any(&self) -> &dyn Any {
        self.inner.as_any()
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self.inner.as_any_mut()
    }
    fn map_view_mut(&mut self) -> Option<&mut crate::widgets::map_canvas::MapView> {
        self.inner.map_view_mut()
    }
    fn set_legend(&mut self, on: bool) -> bool {
        self.inner.set_legend(on)
    }
    fn set_follow(&mut self, on: bool) -> bool {
        self.inner.set_follow(on)
    }
    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        self.inner.plot_series()
    }
    fn keys(&self) -> Vec<(&'static str, &'static str)> {
        self.inner.keys()
    }
    fn take_request(&mut self) -> Option<LessonRequest> {
        self.inner.take_request()
    }
    fn take_restarted_from_link(&mut self) -> bool {
        self.inner.take_restarted_from_link()
    }
    fn could_not_open(&self) -> Option<&str> {
        self.inner.could_not_open()
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
