//! Lessons as a family: the trait every lesson implements and the registry the
//! shell opens them from.
//!
//! The shell (menu, time bar, notices, theme, persistence, share links, test
//! hooks) never matches on a concrete lesson: it holds a `Box<dyn Lesson>`, the
//! way egui's demo app holds its demos. A new lesson is a folder in this crate
//! that implements [`Lesson`], plus one [`LessonEntry`] in [`LESSONS`]
//! (`docs/ADDING-A-LESSON.md` has the whole recipe).

use crate::time_control::{TimeAction, TimeControl, TimeInfo};
use std::any::Any;

/// Which panels are open around the map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct PanelVisibility {
    /// The parameter panel (left).
    pub parameters: bool,
    /// The explanation panel (right).
    pub explanation: bool,
    /// The plots (bottom).
    pub plots: bool,
}

impl Default for PanelVisibility {
    fn default() -> Self {
        Self {
            parameters: true,
            explanation: true,
            plots: true,
        }
    }
}

impl PanelVisibility {
    /// The embed layout: map, plots and the time bar; the side panels closed.
    pub fn embedded() -> Self {
        Self {
            parameters: false,
            explanation: false,
            plots: true,
        }
    }
}

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

/// The landmark lesson, opened in place of a lesson that could not open, with
/// a notice that says `why` (only a broken build gets here: every lesson's
/// defaults are tested).
pub fn open_instead(start: &LessonStart<'_>, why: String) -> Box<dyn Lesson> {
    crate::landmark_slam::open(&LessonStart {
        pairs: &[],
        embed: start.embed,
        stored: None,
        many_runs: None,
    })
    .with_notice(why)
}

/// What a lesson asks of the shell, which it cannot do from inside its panels.
pub enum LessonRequest {
    /// Save these files (downloads in the browser, the working folder on the
    /// desktop).
    Save(Vec<crate::export::ExportFile>),
    /// Replace the lesson on screen with this one (a hand-off between lessons,
    /// such as localizing in a map just built).
    Open(Box<dyn Lesson>),
}

impl std::fmt::Debug for LessonRequest {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Save(files) => write!(f, "Save({} files)", files.len()),
            Self::Open(lesson) => write!(f, "Open({})", lesson.id()),
        }
    }
}

/// One lesson on screen. Everything the shell needs, nothing it must know about
/// the lesson's world.
pub trait Lesson: std::fmt::Debug {
    /// The lesson's id, as in [`LESSONS`].
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
    /// Does what a time-bar button or shortcut asks.
    fn apply_time_action(&mut self, action: TimeAction);
    /// Reads the lesson's own input (drive keys) before the clock advances.
    fn read_input(&mut self, _ctx: &egui::Context) {}
    /// Runs what the clock owes after `dt` seconds of real time, within the frame budget.
    fn advance(&mut self, dt: f64);
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
    fn apply_time_action(&mut self, action: TimeAction) {
        self.inner.apply_time_action(action);
    }
    fn read_input(&mut self, ctx: &egui::Context) {
        self.inner.read_input(ctx);
    }
    fn advance(&mut self, dt: f64) {
        self.inner.advance(dt);
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
}

/// One entry of the lesson menu.
#[derive(Clone, Copy, Debug)]
pub struct LessonEntry {
    /// The URL's `lesson=` value, e.g. `landmark-slam`.
    pub id: &'static str,
    /// The title in the menu and the top bar.
    pub title: &'static str,
    /// One line on what the student sees.
    pub summary: &'static str,
    /// Opens the lesson.
    pub open: fn(&LessonStart<'_>) -> Box<dyn Lesson>,
}

/// Every lesson, in menu order. The first is the default.
pub const LESSONS: &[LessonEntry] = &[
    LessonEntry {
        id: crate::landmark_slam::LESSON_ID,
        title: "Landmark SLAM",
        summary: "A robot drives among landmarks; EKF-SLAM and UKF-SLAM estimate its pose and \
                  the map, with 95% ellipses, NEES/NIS consistency plots and the covariance heatmap.",
        open: crate::landmark_slam::open,
    },
    LessonEntry {
        id: crate::kidnap::LESSON_ID,
        title: "Monte Carlo localization",
        summary: "A robot with a lidar in a maze or an office; a cloud of particles finds it \
                  (global localization) and follows it: predict, weight, resample. Kidnap it.",
        open: crate::kidnap::open,
    },
    LessonEntry {
        id: crate::pose_graph::LESSON_ID,
        title: "Pose-graph optimization",
        summary: "A graph of poses, odometry and loop closures optimized one solver iteration at \
                  a time (GN, LM, first-order); drag vertices, add a wrong loop closure, try \
                  robust kernels, open g2o/TORO files.",
        open: crate::pose_graph::open,
    },
    LessonEntry {
        id: crate::resampling::LESSON_ID,
        title: "Resampling lab",
        summary: "One row of weighted particles and four resamplers side by side: press \
                  resample once or a thousand times and see how many copies each particle \
                  gets, and how much they scatter.",
        open: crate::resampling::open,
    },
    LessonEntry {
        id: crate::fusion::LESSON_ID,
        title: "Sensor fusion",
        summary: "Wheel odometry, an IMU and a 1 Hz SLAM pose fused by robot_localization's EKF; \
                  the SLAM pose taken absolute, relative or differential, side by side.",
        open: crate::fusion::open,
    },
    LessonEntry {
        id: crate::mapping::LESSON_ID,
        title: "Mapping with a lidar",
        summary: "A lidar's scans build an occupancy grid; poses from the truth, raw odometry, \
                  ICP or scan-to-map matching, switched live on the same scans; a simulated \
                  robot or a real CARMEN log (the Intel lab).",
        open: crate::mapping::open,
    },
    LessonEntry {
        id: crate::filters::LESSON_ID,
        title: "Filters: from Bayes to particles",
        summary: "One Gaussian through one nonlinear step by the EKF, the unscented transform \
                  and particles against 100,000 samples; a histogram Bayes filter beside a \
                  Kalman filter in a corridor with doors.",
        open: crate::filters::open,
    },
];

/// The lesson that opens when none (or an unknown one) is asked for.
pub const DEFAULT_LESSON: &str = "landmark-slam";

/// Looks a lesson up by id.
pub fn find(id: &str) -> Option<&'static LessonEntry> {
    LESSONS.iter().find(|l| l.id == id)
}

/// The default lesson's entry.
pub fn default_lesson() -> &'static LessonEntry {
    find(DEFAULT_LESSON).unwrap_or(&LESSONS[0])
}

/// Runs a lesson's phases until the clock's due ticks are done or the frame budget
/// is spent, whichever comes first: the one frame-budgeted advance every lesson
/// uses. `step_phase` runs one phase and says whether it finished a tick.
/// Returns the ticks finished.
pub fn advance_within_budget(
    time: &mut TimeControl,
    dt: f64,
    mut step_phase: impl FnMut() -> bool,
) -> u64 {
    use crate::time_control::{FRAME_BUDGET_MS, TicksDue};
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
        if start.elapsed().as_millis() >= FRAME_BUDGET_MS {
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
    fn the_default_lesson_is_in_the_catalogue_and_ids_are_unique() {
        assert_eq!(default_lesson().id, DEFAULT_LESSON);
        for (i, a) in LESSONS.iter().enumerate() {
            for b in &LESSONS[i + 1..] {
                assert_ne!(a.id, b.id);
            }
        }
        assert!(find("nope").is_none());
    }

    #[test]
    fn every_lesson_opens_with_its_id_and_a_share_link_that_reopens_it() {
        for entry in LESSONS {
            let lesson = (entry.open)(&LessonStart {
                pairs: &[],
                embed: false,
                stored: None,
                many_runs: None,
            });
            assert_eq!(lesson.id(), entry.id);
            let query = lesson.share_query(true);
            assert!(
                query.starts_with(&format!("lesson={}", entry.id)),
                "{query}"
            );
            assert!(query.ends_with("embed=1"), "{query}");
            assert!(
                lesson.notices().is_empty(),
                "{}: {:?}",
                entry.id,
                lesson.notices()
            );
        }
    }

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
