//! The sensor-fusion lesson (`lesson=fusion`, thesis `002` ch. 5): a robot drives
//! a room with wheel odometry at 50 Hz, an IMU at 100 Hz and a SLAM pose at 1 Hz,
//! and robot_localization's EKF fuses them, the SLAM pose taken in each chosen
//! mode (absolute, relative, differential) on the same readings. Step one
//! reading at a time (each named: "IMU: yaw rate at 12.34 s") or one second at a
//! time; switch sensors on and off and change their noise while it runs; inject a
//! bad reading and see it skipped and counted.

mod explain;
mod map;
mod plots;

pub use explain::rmse_text;
pub use plots::ERROR_HEADROOM;

use crate::lesson::{self, Lesson, LessonFrame, LessonStart};
use crate::palette;
use crate::time_control::{TimeAction, TimeInfo};
use crate::widgets::map_canvas::MapView;
use crate::widgets::params_panel::{self, PendingParams};
use egui::Color32;
use serde::{Deserialize, Serialize};
use slamlab_sim::fusion::params::{FusionLessonScenario, MODE_NAMES, mode_from_name};
use slamlab_sim::fusion::session::{BadReading, FusionEvent, FusionSim, LiveNoise, sensor_name};
use slamlab_sim::fusion::{FusionMode, IMU, ODOMETRY, SLAM};
use slamlab_sim::params;
use slamlab_sim::stepper::{CheckpointPolicy, Simulation, Stepper};

/// The truth and each mode's estimate at the output times the runs have
/// sampled, and the dead-reckoned odometry up to the run's time.
fn trajectories(sim: &FusionSim) -> Vec<slamlab_sim::metrics::NamedTrajectory> {
    use slamlab_sim::metrics::{NamedTrajectory, Trajectory, TrajectoryRole};
    let mut out = Vec::new();
    if let Some(first) = sim.runs().first() {
        let mut truth = Trajectory::default();
        for s in first.samples() {
            truth.push(s.t, s.truth, None);
        }
        out.push(NamedTrajectory::new("truth", TrajectoryRole::Truth, truth));
    }
    let now = sim.now();
    let mut odometry = Trajectory::default();
    for (t, pose) in sim
        .log()
        .odometry_path
        .iter()
        .take_while(|(t, _)| *t <= now + 1e-9)
    {
        odometry.push(*t, *pose, None);
    }
    out.push(NamedTrajectory::new(
        "odometry",
        TrajectoryRole::Odometry,
        odometry,
    ));
    for run in sim.runs() {
        let mut estimate = Trajectory::default();
        for s in run.samples() {
            estimate.push(s.t, s.estimate, None);
        }
        out.push(NamedTrajectory::new(
            run.mode().name(),
            TrajectoryRole::Estimate,
            estimate,
        ));
    }
    out
}

/// The lesson's id in URLs and the menu.
pub const LESSON_ID: &str = "fusion";

/// The parameters the panel shows, in order (the rest are in the URL and CLI).
const PANEL_PARAMS: &[&str] = &[
    "seed",
    "duration",
    "odom",
    "odom-rate",
    "odom-speed-noise",
    "odom-turn-noise-deg",
    "odom-scale-error",
    "odom-turn-slip",
    "imu",
    "imu-rate",
    "imu-gyro-noise-deg",
    "imu-gyro-bias-deg",
    "slam",
    "slam-rate",
    "slam-source",
    "slam-position-noise",
    "slam-yaw-noise-deg",
    "slam-fuse-yaw",
    "slam-drift",
    "slam-relocalization-interval",
    "slam-outlier-prob",
    "slam-latency",
    "slam-rejection",
    "filter-delay",
];

/// The colour of a mode (LESSONS.md's EKF blue for `_differential`, the thesis's
/// recommended mode; orange for `_relative`; purple for absolute; green for the
/// odometry-and-IMU-only baseline).
pub fn mode_color(mode: FusionMode) -> Color32 {
    match mode {
        FusionMode::Differential => palette::BLUE,
        FusionMode::Relative => palette::ORANGE,
        FusionMode::Absolute => palette::PURPLE,
        FusionMode::Odometry => palette::GREEN,
    }
}

/// What the map shows; saved with the user's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FusionView {
    /// The legend box.
    pub legend: bool,
    /// The raw odometry path (dead reckoning), grey and dashed.
    pub odometry_path: bool,
    /// The SLAM poses as dots.
    pub slam_poses: bool,
    /// Each mode's 95% position ellipse.
    pub ellipses: bool,
}

crate::lesson::lesson_view!(FusionView, legend: legend);

impl Default for FusionView {
    fn default() -> Self {
        Self {
            legend: true,
            odometry_path: true,
            slam_poses: true,
            ellipses: true,
        }
    }
}

/// The sensor fusion lesson.
#[derive(Debug)]
pub struct FusionLesson {
    stepper: Stepper<FusionSim>,
    pending: PendingParams<FusionLessonScenario>,
    /// The clock, the view, the map view, the notices and the requests.
    pub frame: LessonFrame<FusionView>,
    /// The live noise sliders' values while one is dragged (SI units).
    noise_edit: [f64; 5],
}

/// Opens the lesson from the URL's pairs, with what it stored last time.
pub fn open(start: &LessonStart<'_>) -> Box<dyn Lesson> {
    // The table's ranges keep every scenario valid; should one still fail, the
    // defaults open, saying why.
    let new = |setup| -> Result<FusionLesson, String> {
        FusionLesson::new(setup).or_else(|why| {
            let mut lesson = FusionLesson::new(FusionLessonScenario::default())?;
            lesson
                .frame
                .notices
                .push(format!("{why}; the default drive opens instead"));
            Ok(lesson)
        })
    };
    let opened = lesson::open_lesson(start, FusionLessonScenario::default(), new, |l| {
        &mut l.frame
    });
    let mut lesson = match opened {
        Ok(lesson) => lesson,
        Err(why) => {
            return lesson::open_instead(start, format!("Sensor fusion could not open: {why}"));
        }
    };
    if start.embed {
        lesson.frame.view.legend = false;
    }
    Box::new(lesson)
}

/// A live noise slider: the noise, its label, the factor from SI to the shown
/// unit, and the slider's range in the shown unit.
type NoiseSlider = (LiveNoise, &'static str, f64, f64, f64);

/// Checkpoints every 10 s of the drive: stepping back replays at most ten
/// seconds of readings.
const POLICY: CheckpointPolicy = CheckpointPolicy {
    every_ticks: 10,
    max_checkpoints: 40,
    budget_bytes: 64 << 20,
};

impl FusionLesson {
    /// Starts the lesson on `setup` (its parameters sanitized, with notices).
    pub fn new(mut setup: FusionLessonScenario) -> Result<Self, String> {
        let notices: Vec<String> = params::sanitize(&mut setup)
            .iter()
            .map(ToString::to_string)
            .collect();
        let sim = FusionSim::new(setup.clone())?;
        let noise_edit = LiveNoise::ALL.map(|n| n.get(sim.live()));
        Ok(Self {
            stepper: Stepper::with_policy(sim, (), POLICY),
            pending: PendingParams::new(setup),
            frame: LessonFrame::new(LESSON_ID, FusionView::default())
                .with_map(MapView::default())
                .with_notices(notices),
            noise_edit,
        })
    }

    /// The running simulation.
    pub fn sim(&self) -> &FusionSim {
        self.stepper.sim()
    }

    /// The map's view (its centre and scale): it fits the room, never the ellipses.
    pub fn map_view(&self) -> &MapView {
        &self.frame.map
    }

    /// The setup being edited in the parameter panel (applied on reset).
    pub fn pending(&self) -> &FusionLessonScenario {
        &self.pending.scenario
    }

    /// Sets a parameter of the pending setup from text, as the panel does.
    pub fn set_param(&mut self, name: &str, value: &str) -> Option<params::ParamIssue> {
        self.pending.set(name, value)
    }

    /// Starts over with the pending parameters.
    pub fn reset(&mut self) {
        let mut setup = self.pending.scenario.clone();
        let notices: Vec<String> = params::sanitize(&mut setup)
            .iter()
            .map(ToString::to_string)
            .collect();
        match FusionSim::new(setup.clone()) {
            Ok(sim) => {
                self.noise_edit = LiveNoise::ALL.map(|n| n.get(sim.live()));
                self.stepper = Stepper::with_policy(sim, (), POLICY);
                self.pending = PendingParams::new(setup);
                self.frame.notices = notices;
                self.frame.note = None;
            }
            Err(why) => {
                self.frame.note = Some(format!("Could not start over: {why}; the run goes on"))
            }
        }
        self.frame.time.apply(TimeAction::Reset);
        self.frame.map.refit();
    }

    /// Applies a live change (a sensor switch, a noise, a bad reading); it is
    /// recorded, so stepping back and forth replays it.
    pub fn apply_event(&mut self, event: FusionEvent) {
        if let FusionEvent::SetNoise { value, .. } = event
            && !(value.is_finite() && value > 0.0)
        {
            self.frame.note = Some(format!(
                "Noise {value} refused: a standard deviation must be a number above 0"
            ));
            return;
        }
        if self.sim().finished() && matches!(event, FusionEvent::Inject(_)) {
            self.frame.note =
                Some("The drive is over: step back or reset to inject a reading".into());
            return;
        }
        self.frame.note = Some(format!(
            "At {:.2} s: {}",
            self.sim().now(),
            event.describe()
        ));
        self.stepper.apply(event);
        self.noise_edit = LiveNoise::ALL.map(|n| n.get(self.sim().live()));
    }

    /// Applies the next reading.
    pub fn step_phase(&mut self) {
        self.stepper.step_phase();
    }

    /// Runs to the end of the current second, or one whole second.
    pub fn step_tick(&mut self) {
        self.stepper.step_tick();
    }

    /// Goes back one reading.
    pub fn step_back(&mut self) -> bool {
        self.stepper.step_back()
    }

    /// The last phase's name ("IMU: yaw rate at 12.34 s"), if any.
    pub fn last_phase_label(&self) -> Option<String> {
        self.stepper.last_phase().map(|p| p.label())
    }

    fn modes_ui(&mut self, ui: &mut egui::Ui) {
        ui.label(egui::RichText::new("Modes compared").strong())
            .on_hover_text(
                "How the filter takes the SLAM pose; each mode runs on the same readings. \
                 Applied with \"Apply & reset\".",
            );
        ui.horizontal_wrapped(|ui| {
            let current = self.pending.scenario.modes.clone();
            for name in MODE_NAMES {
                let Some(mode) = mode_from_name(name) else {
                    continue;
                };
                let mut on = current.contains(&mode);
                let text = egui::RichText::new(*name).color(mode_color(mode));
                if ui.checkbox(&mut on, text).changed() {
                    let mut list: Vec<&str> = MODE_NAMES
                        .iter()
                        .copied()
                        .filter(|n| {
                            let m = mode_from_name(n);
                            if *n == *name {
                                on
                            } else {
                                m.is_some_and(|m| current.contains(&m))
                            }
                        })
                        .collect();
                    if list.is_empty() {
                        list.push(name);
                    }
                    self.pending.set("modes", &list.join(","));
                }
            }
        });
    }

    fn live_sensors_ui(&mut self, ui: &mut egui::Ui) {
        ui.label(egui::RichText::new("Sensors, live").strong())
            .on_hover_text(
                "These act now, on the running drive: a switch or a noise applies to the readings \
                 that arrive from this moment on. Stepping back undoes them.",
            );
        let groups: [(usize, &[NoiseSlider]); 3] = [
            (
                ODOMETRY,
                &[
                    (LiveNoise::OdometrySpeed, "speed noise", 1.0, 1e-4, 0.5),
                    (
                        LiveNoise::OdometryTurn,
                        "yaw-rate noise",
                        180.0 / std::f64::consts::PI,
                        0.01,
                        30.0,
                    ),
                ],
            ),
            (
                IMU,
                &[(
                    LiveNoise::ImuGyro,
                    "gyro noise",
                    180.0 / std::f64::consts::PI,
                    0.001,
                    10.0,
                )],
            ),
            (
                SLAM,
                &[
                    (LiveNoise::SlamPosition, "position noise", 1.0, 1e-3, 2.0),
                    (
                        LiveNoise::SlamYaw,
                        "heading noise",
                        180.0 / std::f64::consts::PI,
                        0.01,
                        45.0,
                    ),
                ],
            ),
        ];
        let mut events = Vec::new();
        // One column: each sensor's switch, then its noise sliders indented (a
        // narrow panel keeps the map wide).
        for (sensor, noises) in groups {
            let mut on = self.sim().sensor_on(sensor);
            if ui
                .checkbox(&mut on, sensor_name(sensor))
                .on_hover_text("Feed this sensor's readings to the filters from now on")
                .changed()
            {
                events.push(FusionEvent::SetSensor { sensor, on });
            }
            ui.indent(("fusion_noise", sensor_name(sensor)), |ui| {
                // Slider, value and label within the panel's width.
                ui.spacing_mut().slider_width = (ui.available_width() - 190.0).clamp(60.0, 160.0);
                for &(noise, label, scale, min, max) in noises {
                    let k = LiveNoise::ALL.iter().position(|n| *n == noise).unwrap_or(0);
                    let unit = if scale == 1.0 {
                        if sensor == SLAM { " m" } else { " m/s" }
                    } else if sensor == SLAM {
                        " deg"
                    } else {
                        " deg/s"
                    };
                    let mut shown = self.noise_edit[k] * scale;
                    let response = ui.add(
                        egui::Slider::new(&mut shown, min..=max)
                            .logarithmic(true)
                            .suffix(unit)
                            .text(label),
                    );
                    if response.changed() {
                        self.noise_edit[k] = shown / scale;
                    }
                    let live = noise.get(self.sim().live());
                    if (response.drag_stopped() || (response.changed() && !response.dragged()))
                        && (self.noise_edit[k] - live).abs() > 1e-9 * live.abs()
                    {
                        events.push(FusionEvent::SetNoise {
                            noise,
                            value: self.noise_edit[k],
                        });
                    }
                }
            });
        }
        for event in events {
            self.apply_event(event);
        }
        ui.label(egui::RichText::new("Inject a bad reading").strong())
            .on_hover_text(
                "Hand every filter a broken reading now: each one is skipped with a message and \
                 counted (the explanation panel lists the counts).",
            );
        ui.horizontal_wrapped(|ui| {
            for bad in BadReading::ALL {
                if ui.button(bad.label()).clicked() {
                    self.apply_event(FusionEvent::Inject(bad));
                }
            }
        });
    }

    fn fusion_parameters_ui(&mut self, ui: &mut egui::Ui) {
        ui.heading("Sensor fusion");
        self.live_sensors_ui(ui);
        ui.separator();
        ui.label(egui::RichText::new("The drive (applied with \"Apply & reset\")").strong());
        self.modes_ui(ui);
        let running = self.sim().setup().clone();
        params_panel::params_ui(ui, &mut self.pending, &running, PANEL_PARAMS);
        ui.separator();
        if params_panel::apply_and_share_ui(
            ui,
            self.pending.differs_from(&running),
            "Start over with these parameters (same seed: same drive)",
            |embed| lesson::Lesson::share_query(self, embed),
            "index.html?… with these pairs opens exactly this drive",
        ) {
            self.reset();
        }
    }
}

impl crate::widgets::layout::LessonPanels for FusionLesson {
    fn plots_ui(&mut self, ui: &mut egui::Ui) {
        plots::plots_ui(ui, self.stepper.sim());
    }

    fn parameters_ui(&mut self, ui: &mut egui::Ui) {
        self.fusion_parameters_ui(ui);
    }

    fn explanation_ui(&mut self, ui: &mut egui::Ui) {
        explain::explanation_ui(ui, self.stepper.sim(), self.stepper.last_phase());
    }

    fn map_ui(&mut self, ui: &mut egui::Ui) {
        map::map_ui(
            ui,
            self.stepper.sim(),
            &mut self.frame.map,
            &mut self.frame.view,
        );
    }
}

impl Lesson for FusionLesson {
    crate::lesson::frame_accessors!();

    fn share_pairs(&self) -> Vec<(String, String)> {
        let setup = self.sim().setup();
        lesson::with_seed(
            params::changed_pairs(setup, &FusionLessonScenario::default()),
            setup.scenario.seed,
        )
    }

    fn plot_series(&self) -> Vec<crate::export::PlotSeries> {
        plots::series(self.stepper.sim())
    }

    /// The truth and each mode's fused pose at the output times so far, and
    /// the raw odometry integrated alone up to now: what File → Export
    /// trajectories writes and a dropped estimate (a fusion assignment's
    /// hand-in) is scored beside.
    fn trajectories(&self) -> Vec<slamlab_sim::metrics::NamedTrajectory> {
        trajectories(self.sim())
    }

    fn subtitle(&self) -> String {
        let names: Vec<&str> = self.sim().runs().iter().map(|r| r.mode().name()).collect();
        format!("{} on one drive", names.join(" vs "))
    }

    fn run_notices(&self) -> Vec<String> {
        self.sim().notes().iter().rev().take(3).cloned().collect()
    }

    fn changed_params(&self) -> Vec<(String, String)> {
        params::changed_pairs(&self.pending.scenario, &FusionLessonScenario::default())
    }

    fn time_info(&self) -> TimeInfo {
        TimeInfo {
            tick: self.sim().tick(),
            time_s: self.sim().now(),
            last_phase: self.last_phase_label(),
            next_phase: self.sim().next_reading(),
            can_step_back: self.stepper.phases_run() > 0,
        }
    }

    fn on_time_action(&mut self, action: TimeAction) {
        match action {
            TimeAction::ToggleRun => {}
            TimeAction::StepPhase => self.step_phase(),
            TimeAction::StepTick => self.step_tick(),
            TimeAction::StepBack => {
                self.step_back();
                self.noise_edit = LiveNoise::ALL.map(|n| n.get(self.sim().live()));
            }
            TimeAction::Reset => self.reset(),
        }
    }

    fn advance(&mut self, dt: f64) {
        let stepper = &mut self.stepper;
        lesson::advance_within_budget(&mut self.frame.time, dt, || {
            stepper.step_phase();
            !stepper.sim().is_mid_tick()
        });
        if self.sim().finished() {
            self.frame.time.running = false;
        }
    }

    fn view_menu_ui(&mut self, ui: &mut egui::Ui) {
        ui.checkbox(&mut self.frame.view.legend, "Map legend");
        ui.checkbox(&mut self.frame.view.odometry_path, "Raw odometry path");
        ui.checkbox(&mut self.frame.view.slam_poses, "SLAM poses");
        ui.checkbox(&mut self.frame.view.ellipses, "95% ellipses");
    }

    fn test_state(&self) -> serde_json::Value {
        let sim = self.sim();
        let runs: Vec<serde_json::Value> = sim
            .runs()
            .iter()
            .map(|r| {
                let e = r.rmse();
                let pose = r.filter().pose();
                let stats = r.filter().stats();
                serde_json::json!({
                    "mode": r.mode().name(),
                    "rmse": [e.x, e.y, e.yaw],
                    "estimate": [pose.x, pose.y, pose.theta],
                    "samples": r.samples().len(),
                    "max_slam_jump": r.max_slam_jump(),
                    "fused": stats.fused,
                    "skipped": stats.skipped(),
                    "non_finite": stats.non_finite,
                    "bad_noise": stats.bad_noise,
                    "before_start": stats.before_start,
                    "out_of_order": stats.out_of_order,
                })
            })
            .collect();
        serde_json::json!({
            "tick": sim.tick(),
            "time": sim.now(),
            "phase": self.last_phase_label().unwrap_or_default(),
            "seed": sim.setup().scenario.seed,
            "finished": sim.finished(),
            "injected": sim.injected(),
            "sensors": [sim.sensor_on(ODOMETRY), sim.sensor_on(IMU), sim.sensor_on(SLAM)],
            "runs": runs,
        })
    }
}
