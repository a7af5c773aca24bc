//! Visual odometry (`lesson=visual-odometry`, thesis `000` Sec. 4.3, Eq.
//! 4.9-4.28, Figs. 4.11-4.14): a camera on a vehicle docking at a station sees
//! the station, the ground and a facade; matched features between two images
//! give the essential matrix by the eight-point or five-point method inside
//! RANSAC, E gives four (R, t) and cheirality picks one, and the steps chained
//! along the approach, scaled by the wheel speeds, give a trajectory.
//!
//! The centre shows the two images of one VO step side by side with the
//! features and matches, coloured as RANSAC classifies them (hover a feature for
//! its epipolar line in the other image), and the top view of the trajectories.
//! The clock steps RANSAC one sample at a time: the sample drawn, its
//! hypotheses' inliers, the best so far and the adaptive bound. The explanation
//! panel has the four decompositions of E with their cheirality counts and E
//! with its singular values; the plots, every step's errors and inlier ratio.
//!
//! `two-view=N` (what a `two-view` assignment's link gives) shows a two-view
//! scene instead, the very one handed out ([`scene`]); the docking run stays a
//! checkbox away.

mod explain;
mod images;
mod photos;
mod plots;
pub mod scene;

use crate::lesson::{self, Lesson, LessonFrame, LessonStart, LessonView};
use crate::time_control::{StepControls, TimeAction, TimeControl, TimeInfo};
use crate::widgets::params_panel::{self, PendingParams};
use serde::{Deserialize, Serialize};
use slamlab_core::vision::{Motion, rotation_angle};
use slamlab_sim::params;
use slamlab_sim::visual_odometry::{
    TwoViewSession, VoRun, VoScenario, odometry::run_in_world, world::CameraWorld,
};

/// The lesson's id in URLs and the menu.
pub const LESSON_ID: &str = "visual-odometry";

/// The parameters the panel shows (the step shown has its own slider).
const PANEL_PARAMS: &[&str] = &[
    "method",
    "normalize",
    "refine",
    "early-rejection",
    "outliers",
    "noise-px",
    "pure-rotation",
    "planar",
    "frames",
    "stride",
    "seed",
];

/// What the images show; saved with the user's settings.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct VoView {
    /// Mark the matches that are truly wrong (the simulator's truth).
    pub true_outliers: bool,
    /// Lines across the two images for every match (thesis Fig. 4.14), not
    /// only for the sample drawn.
    pub match_lines: bool,
}

impl LessonView for VoView {}

/// The visual-odometry lesson.
#[derive(Debug)]
pub struct VisualOdometryLesson {
    /// The parameters the run was made with.
    scenario: VoScenario,
    pending: PendingParams<VoScenario>,
    run: VoRun,
    /// The step shown (clamped to the run's steps).
    pair: usize,
    session: Option<TwoViewSession>,
    /// The clock, the view, the map view, the notices and the requests.
    pub frame: LessonFrame<VoView>,
    /// The feature under the pointer: (right image?, match index).
    hovered: Option<(bool, usize)>,
    /// The student's own photos.
    photos: photos::PhotoPair,
    /// The two-view scene the link asked for (`two-view=N`).
    scene: Option<scene::TwoViewScene>,
}

/// Opens the lesson from the URL's pairs, with what it stored last time.
pub fn open(start: &LessonStart<'_>) -> Box<dyn Lesson> {
    let (link, pairs) = scene::SceneLink::from_pairs(start.pairs);
    let start = &LessonStart {
        pairs: &pairs,
        ..*start
    };
    let new = |scenario| {
        let mut lesson = VisualOdometryLesson::new(scenario);
        lesson.frame.notices.extend(link.notices);
        if let Some(matches) = link.matches {
            lesson.scene = Some(scene::TwoViewScene::new(
                &lesson.scenario,
                matches,
                link.answers,
            ));
        }
        Ok::<_, std::convert::Infallible>(lesson)
    };
    let Ok(lesson) = lesson::open_lesson(start, VoScenario::default(), new, |l| &mut l.frame);
    Box::new(lesson)
}

/// The run of a scenario (the world rebuilt from its seed).
fn make_run(scenario: &VoScenario) -> VoRun {
    let settings = slamlab_sim::visual_odometry::odometry::clamped(scenario.settings);
    let world = CameraWorld::new(
        settings.seed,
        settings.frames,
        settings.pure_rotation_segment,
    );
    run_in_world(settings, &world)
}

impl VisualOdometryLesson {
    /// The lesson on `scenario`, RANSAC of the shown step before its first sample.
    pub fn new(scenario: VoScenario) -> Self {
        let run = make_run(&scenario);
        let mut time = TimeControl::default();
        // Twenty samples a second while running: each one visible.
        time.speed_tps = 20.0;
        let mut lesson = Self {
            pending: PendingParams::new(scenario.clone()),
            scenario,
            run,
            pair: 0,
            session: None,
            frame: LessonFrame::new(LESSON_ID, VoView::default()).with_time(time),
            hovered: None,
            photos: photos::PhotoPair::default(),
            scene: None,
        };
        let wanted = lesson.scenario.pair;
        lesson.show_pair(wanted);
        if lesson.pair != wanted {
            lesson.frame.notices.push(format!(
                "pair = {wanted} is past the last VO step of this run; showing step {}",
                lesson.pair
            ));
        }
        lesson
    }

    /// The run along the approach.
    pub fn run(&self) -> &VoRun {
        &self.run
    }

    /// The parameters the run was made with.
    pub fn scenario(&self) -> &VoScenario {
        &self.scenario
    }

    /// The two-view scene the link asked for (`two-view=N`), if any.
    pub fn scene(&self) -> Option<&scene::TwoViewScene> {
        self.scene.as_ref()
    }

    /// The two-view scene, to switch what it shows.
    pub fn scene_mut(&mut self) -> Option<&mut scene::TwoViewScene> {
        self.scene.as_mut()
    }

    /// Whether the centre shows the two-view scene (not the docking run).
    fn showing_scene(&self) -> bool {
        !self.photos.showing() && self.scene.as_ref().is_some_and(|s| s.show)
    }

    /// The VO step shown in the images.
    pub fn pair(&self) -> usize {
        self.pair
    }

    /// RANSAC on the shown step (`None` when the run has no step).
    pub fn session(&self) -> Option<&TwoViewSession> {
        self.session.as_ref()
    }

    /// Shows VO step `k` (the last one if `k` is past it), RANSAC before its
    /// first sample.
    pub fn show_pair(&mut self, k: usize) {
        let last = self.run.steps.len().saturating_sub(1);
        self.pair = k.min(last);
        self.scenario.pair = self.pair;
        self.pending.scenario.pair = self.pair;
        self.hovered = None;
        self.frame.time.apply(TimeAction::Reset);
        self.session = match (
            self.run.pairs.get(self.pair),
            self.run.camera,
            self.run.config,
        ) {
            (Some(pair), Some(camera), Some(config)) => {
                Some(TwoViewSession::new(pair, &camera, config))
            }
            _ => None,
        };
    }

    /// Sets a parameter from text, as the panel does, and applies it (the run
    /// is made again).
    pub fn set_param(&mut self, name: &str, value: &str) -> Option<params::ParamIssue> {
        let issue = self.pending.set(name, value);
        self.apply_pending();
        issue
    }

    /// Makes the run again with the panel's parameters (same seed: same world),
    /// or, when only the step shown changed, shows that step.
    pub fn apply_pending(&mut self) {
        let mut wanted = self.pending.scenario.clone();
        let pair = wanted.pair;
        wanted.pair = self.scenario.pair;
        if wanted != self.scenario {
            self.run = make_run(&wanted);
            self.scenario = wanted;
            if let Some(scene) = &mut self.scene {
                scene.follow(&self.scenario);
            }
        }
        self.show_pair(pair);
    }

    /// Loads photos as if picked or dropped (one: the next empty place; two:
    /// both).
    pub fn load_photos(&mut self, files: Vec<(String, Result<Vec<u8>, String>)>) {
        self.photos.load_batch(files);
    }

    /// One RANSAC sample.
    pub fn step_sample(&mut self) {
        if let Some(session) = &mut self.session {
            session.step();
        }
    }

    /// RANSAC to its adaptive bound, then the refit, the decomposition and
    /// the pure-rotation test.
    pub fn run_ransac_to_end(&mut self) {
        self.frame.time.apply(TimeAction::StepTick);
        if let Some(session) = &mut self.session {
            session.run_to_end();
        }
    }

    /// The first step in the degenerate segment (`planar`: the planar part;
    /// else the turn on the spot), where the run has one.
    fn degenerate_pair(&self, planar: bool) -> Option<usize> {
        let frames = self.run.settings.frames;
        let start = frames / 3 + if planar { self.run.settings.stride } else { 0 };
        self.run.steps.iter().position(|s| s.from >= start)
    }

    fn lesson_parameters_ui(&mut self, ui: &mut egui::Ui) {
        ui.heading("Visual odometry");
        if let Some(scene) = &mut self.scene {
            scene.controls_ui(ui, self.frame.estimates.items());
            ui.checkbox(
                &mut self.frame.view.match_lines,
                "Lines across the images (Fig. 4.14)",
            );
            ui.separator();
            ui.strong("The docking run");
        }
        ui.label(
            "Two images of one VO step: RANSAC draws samples of matches, fits E to each, \
             and keeps the hypothesis most matches agree with.",
        );
        ui.horizontal_wrapped(|ui| {
            // The two views' RANSAC has run; these step the docking run's.
            let done =
                self.showing_scene() || self.session.as_ref().is_none_or(TwoViewSession::is_done);
            if ui
                .add_enabled(!done, egui::Button::new("Step one sample"))
                .on_hover_text("Draw one RANSAC sample (the time bar's step: . or n)")
                .clicked()
            {
                self.apply_time_action(TimeAction::StepPhase);
            }
            if ui
                .add_enabled(!done, egui::Button::new("Run RANSAC to the end"))
                .on_hover_text(
                    "Draw samples until the adaptive bound N is reached, then refit E on the \
                     inliers and decompose it",
                )
                .clicked()
            {
                self.run_ransac_to_end();
            }
            if ui
                .button("Restart RANSAC")
                .on_hover_text("Back to before the first sample (same draws again)")
                .clicked()
            {
                self.apply_time_action(TimeAction::Reset);
            }
        });
        ui.separator();
        let steps = self.run.steps.len();
        ui.label(egui::RichText::new("VO step shown").strong());
        if steps > 0 {
            let mut k = self.pair;
            ui.horizontal(|ui| {
                if ui
                    .add_enabled(k > 0, egui::Button::new("<"))
                    .on_hover_text("The step before")
                    .clicked()
                {
                    k -= 1;
                }
                ui.add(egui::Slider::new(&mut k, 0..=steps - 1).text("pair"))
                    .on_hover_text("Which pair of images (VO step) the centre shows");
                if ui
                    .add_enabled(k + 1 < steps, egui::Button::new(">"))
                    .on_hover_text("The step after")
                    .clicked()
                {
                    k += 1;
                }
            });
            if let Some(step) = self.run.steps.get(k) {
                ui.label(format!(
                    "frames {} to {} ({:.1} s apart), {} matches",
                    step.from,
                    step.to,
                    (step.to - step.from) as f64 * slamlab_sim::visual_odometry::world::FRAME_DT,
                    step.matches
                ));
            }
            ui.horizontal_wrapped(|ui| {
                if self.run.settings.pure_rotation_segment
                    && let Some(p) = self.degenerate_pair(false)
                    && ui
                        .button("Go to the turn on the spot")
                        .on_hover_text("A pure rotation: no translation to observe")
                        .clicked()
                {
                    k = p;
                }
                if self.run.settings.planar_segment
                    && let Some(p) = self.degenerate_pair(true)
                    && ui
                        .button("Go to the planar part")
                        .on_hover_text("Only the facade is seen: every point on one plane")
                        .clicked()
                {
                    k = p;
                }
            });
            if k != self.pair {
                self.show_pair(k);
            }
        }
        ui.checkbox(
            &mut self.frame.view.true_outliers,
            "Mark the truly wrong matches",
        )
        .on_hover_text(
            "The simulator knows which matches are wrong: a ring in the truth colour \
                 around each. RANSAC does not know it.",
        );
        ui.checkbox(
            &mut self.frame.view.match_lines,
            "Lines across the images (Fig. 4.14)",
        )
        .on_hover_text("A line from each feature in the first image to its match in the second");
        ui.separator();
        let running = self.scenario.clone();
        params_panel::params_ui(ui, &mut self.pending, &running, PANEL_PARAMS);
        let mut pending_without_pair = self.pending.scenario.clone();
        pending_without_pair.pair = running.pair;
        let changed = pending_without_pair != running;
        if ui
            .add_enabled(changed, egui::Button::new("Apply & reset"))
            .on_hover_text("Make the run again with these parameters (same seed: same world)")
            .clicked()
        {
            self.apply_pending();
        }
        ui.separator();
        crate::widgets::share::share_ui(
            ui,
            |embed| Lesson::share_query(self, embed),
            "index.html?… with these pairs opens this run at this step; RANSAC's samples are \
             not in it (add tick=N for N samples)",
            changed.then_some("Parameters not applied yet are not in the link."),
        );
        self.photos.controls_ui(ui);
    }
}

impl crate::widgets::layout::LessonPanels for VisualOdometryLesson {
    fn plots_ui(&mut self, ui: &mut egui::Ui) {
        if self.showing_scene() {
            scene::docking_note(ui);
        }
        plots::plots_ui(ui, &self.run, self.pair, self.session.as_ref());
    }

    fn parameters_ui(&mut self, ui: &mut egui::Ui) {
        self.lesson_parameters_ui(ui);
    }

    fn explanation_ui(&mut self, ui: &mut egui::Ui) {
        if self.showing_scene() {
            scene::docking_note(ui);
        }
        explain::explanation_ui(ui, &self.run, self.pair, self.session.as_ref());
    }

    fn map_ui(&mut self, ui: &mut egui::Ui) {
        self.photos.poll(ui.ctx());
        if self.photos.showing() {
            egui::ScrollArea::vertical()
                .id_salt("vo_photos_scroll")
                .auto_shrink([false, false])
                .show(ui, |ui| self.photos.centre_ui(ui));
            return;
        }
        if self.showing_scene()
            && let Some(scene) = &mut self.scene
        {
            let estimates = self.frame.estimates.items();
            let lines = self.frame.view.match_lines;
            egui::ScrollArea::vertical()
                .id_salt("vo_scene_scroll")
                .auto_shrink([false, false])
                .show(ui, |ui| scene.centre_ui(ui, estimates, lines));
            return;
        }
        // In a small window the images, the top view and their keys may need more
        // room than there is: they scroll instead of running past the window.
        let hovered = egui::ScrollArea::vertical()
            .id_salt("vo_centre_scroll")
            .auto_shrink([false, false])
            .show(ui, |ui| {
                images::centre_ui(
                    ui,
                    &self.run,
                    self.pair,
                    self.session.as_ref(),
                    &self.frame.view,
                    self.hovered,
                )
            })
            .inner;
        self.hovered = hovered;
    }
}

impl Lesson for VisualOdometryLesson {
    crate::lesson::frame_accessors!();

    fn trajectories(&self) -> Vec<slamlab_sim::metrics::NamedTrajectory> {
        slamlab_sim::visual_odometry::export::trajectories(&self.run)
    }

    fn estimate_clock(&self) -> Option<f64> {
        None
    }

    fn relative_poses(&self) -> Vec<(String, slamlab_core::vision::RelativePose)> {
        if self.photos.showing() {
            return Vec::new();
        }
        if self.showing_scene()
            && let Some(scene) = &self.scene
        {
            return scene.relative_poses();
        }
        let mut poses: Vec<(String, slamlab_core::vision::RelativePose)> = self
            .run
            .pairs
            .get(self.pair)
            .map(|p| ("truth".to_owned(), p.truth))
            .into_iter()
            .collect();
        // RANSAC's answer so far: the rotation and, for general motion, the
        // direction of translation (a pure rotation's has none).
        if let Some(Ok(e)) = self.session.as_ref().and_then(|s| s.estimate())
            && let Some(translation) = e.translation
        {
            poses.push((
                "ransac".to_owned(),
                slamlab_core::vision::RelativePose {
                    rotation: e.rotation,
                    translation,
                },
            ));
        }
        poses
    }

    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        plots::series(&self.run, self.session.as_ref())
    }

    fn subtitle(&self) -> String {
        if let Some(photos) = self.photos.subtitle() {
            return photos;
        }
        if self.showing_scene()
            && let Some(scene) = &self.scene
        {
            return scene.subtitle();
        }
        let s = &self.run.settings;
        format!(
            "{}, {:.0}% wrong matches, {} px noise, step {}",
            s.method.name(),
            100.0 * s.outliers,
            params::format_number(s.noise_px),
            self.pair
        )
    }

    fn run_notices(&self) -> Vec<String> {
        self.session
            .as_ref()
            .and_then(TwoViewSession::start_error)
            .map(|error| format!("RANSAC cannot start on this step: {error}"))
            .into_iter()
            .collect()
    }

    fn time_info(&self) -> TimeInfo {
        if self.photos.showing()
            && let Some(phase) = self.photos.phase()
        {
            return TimeInfo {
                time_s: f64::NAN,
                next_phase: phase,
                ..TimeInfo::default()
            };
        }
        if self.showing_scene() {
            return TimeInfo {
                time_s: f64::NAN,
                next_phase: format!(
                    "the two views' RANSAC ran to its bound (at most {} samples); the docking run's steps one sample at a time",
                    slamlab_sim::visual_odometry::assignment::MAX_SAMPLES
                ),
                ..TimeInfo::default()
            };
        }
        let Some(session) = &self.session else {
            return TimeInfo {
                time_s: f64::NAN,
                next_phase: "nothing: the run has no VO step".to_owned(),
                ..TimeInfo::default()
            };
        };
        let next = session.iteration() + 1;
        TimeInfo {
            tick: session.iteration() as u64,
            time_s: f64::NAN,
            last_phase: session.last_report().map(|r| {
                format!(
                    "sample {}: {} inliers (best {}, N = {})",
                    r.iteration, r.inliers, r.best_inliers, r.bound
                )
            }),
            next_phase: if session.is_done() {
                "done: the bound is reached".to_owned()
            } else {
                format!("sample {next} of at most {}", session.bound())
            },
            can_step_back: session.iteration() > 0,
        }
    }

    fn step_controls(&self) -> StepControls {
        StepControls::One {
            label: "Step sample",
            hover: "Draw one RANSAC sample, fit its hypotheses and count their inliers",
            unit: "sample",
            back_unit: "sample",
        }
    }

    fn on_time_action(&mut self, action: TimeAction) {
        if self.showing_scene() && action != TimeAction::Reset {
            self.frame.time.running = false;
            return;
        }
        match action {
            TimeAction::ToggleRun => {
                if self.session.as_ref().is_none_or(TwoViewSession::is_done) {
                    self.frame.time.running = false;
                }
            }
            TimeAction::StepPhase | TimeAction::StepTick => self.step_sample(),
            TimeAction::StepBack => {
                if let Some(session) = &mut self.session {
                    session.step_back();
                }
            }
            TimeAction::Reset => {
                self.apply_pending();
            }
        }
    }

    fn advance(&mut self, dt: f64) {
        if self.showing_scene() {
            self.frame.time.running = false;
            return;
        }
        let Some(session) = &mut self.session else {
            self.frame.time.running = false;
            return;
        };
        lesson::advance_within_budget(&mut self.frame.time, dt, || {
            session.step();
            true
        });
        if session.is_done() {
            self.frame.time.running = false;
        }
    }

    fn view_menu_ui(&mut self, ui: &mut egui::Ui) {
        ui.checkbox(&mut self.frame.view.true_outliers, "Truly wrong matches");
        ui.checkbox(&mut self.frame.view.match_lines, "Lines across the images");
    }

    fn changed_params(&self) -> Vec<(String, String)> {
        params::changed_pairs(&self.scenario, &VoScenario::default())
    }

    fn share_pairs(&self) -> Vec<(String, String)> {
        let mut pairs = lesson::with_seed(self.changed_params(), self.scenario.settings.seed);
        if let Some(scene) = &self.scene {
            pairs.extend(scene.share_pairs());
        }
        pairs
    }

    fn test_state(&self) -> serde_json::Value {
        let session = self.session.as_ref();
        let step = self.run.steps.get(self.pair);
        let estimate = session.and_then(|s| s.estimate()).map(|e| match e {
            Ok(e) => {
                let truth = self.run.pairs.get(self.pair).map(|p| p.truth);
                serde_json::json!({
                    "inliers": e.inlier_count,
                    "iterations": e.iterations,
                    "motion": match e.motion {
                        Motion::General => "general",
                        Motion::PureRotation => "pure-rotation",
                    },
                    "chosen": e.decomposition.best,
                    "in_front": e.decomposition.in_front,
                    "singular_values": [
                        e.decomposition.singular_values.x,
                        e.decomposition.singular_values.y,
                        e.decomposition.singular_values.z,
                    ],
                    "rotation_error_deg": truth.map(|t| {
                        rotation_angle(&(e.rotation.transpose() * t.rotation)).to_degrees()
                    }),
                })
            }
            Err(error) => serde_json::json!({ "error": error.to_string() }),
        });
        let r = self.run.trajectory_rmse;
        serde_json::json!({
            "tick": session.map_or(0, TwoViewSession::iteration),
            "seed": self.run.settings.seed,
            "method": self.run.settings.method.name(),
            "early_rejection": self.run.settings.early_rejection.name(),
            "last_sample_checks": session
                .and_then(TwoViewSession::last_report)
                .and_then(|r| r.sprt.as_ref())
                .map(|s| {
                    s.checks
                        .iter()
                        .map(|c| serde_json::json!({
                            "evaluated": c.evaluated,
                            "consistent": c.consistent,
                            "rejected": c.rejected,
                        }))
                        .collect::<Vec<_>>()
                }),
            "pair": self.pair,
            "step_frames": [step.map(|s| s.from), step.map(|s| s.to)],
            "matches": session.map_or(0, |s| s.matches().len()),
            "iteration": session.map_or(0, TwoViewSession::iteration),
            "bound": session.map_or(0, TwoViewSession::bound),
            "best_inliers": session.map_or(0, TwoViewSession::best_inlier_count),
            "done": session.is_none_or(TwoViewSession::is_done),
            "estimate": estimate,
            "vo_steps": self.run.steps.len(),
            "photos": self.photos.test_state(),
            "two_view": self
                .scene
                .as_ref()
                .map(|s| s.test_state(self.frame.estimates.items())),
            "trajectory_rmse": {
                "wheel_odometry": r.wheel_odometry,
                "visual_odometry": r.visual_odometry,
                "visual_odometry_unit_scale": r.visual_odometry_unit_scale,
            },
        })
    }
}
