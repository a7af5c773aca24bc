//! Time control, the same in every lesson: run/pause, speed, step one phase, step
//! one tick, reset; keyboard Space, `.`, `n`, `r`.

use serde::{Deserialize, Serialize};

/// Slowest and fastest selectable speed, ticks per second.
pub const SPEED_RANGE: std::ops::RangeInclusive<f64> = 1.0..=200.0;

/// How long one frame may spend simulating, milliseconds. Past this the simulation
/// falls behind real time instead of freezing the page.
pub const FRAME_BUDGET_MS: u128 = 25;

/// The most one frame may spend simulating at maximum speed, milliseconds: the page
/// still answers a click within a quarter of a second.
pub const MAX_SPEED_BUDGET_MS: f64 = 250.0;

/// What a frame at maximum speed leaves idle on purpose, milliseconds, so that input
/// and the browser's own work still find the thread free.
const IDLE_MARGIN_MS: f64 = 5.0;

/// What the user asked the clock to do this frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeAction {
    /// Run or pause.
    ToggleRun,
    /// Run one phase (predict, one landmark update, ...).
    StepPhase,
    /// Finish the current tick, or run a whole new one.
    StepTick,
    /// Go back one phase (the lesson replays the run up to the phase before).
    StepBack,
    /// Start over with the current parameters.
    Reset,
}

/// The running state and speed of a lesson's clock.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TimeControl {
    /// Is the simulation running?
    #[serde(skip)]
    pub running: bool,
    /// Speed while running, ticks per second.
    pub speed_tps: f64,
    /// Run as fast as the frame budget allows.
    pub max_speed: bool,
    /// Fractional ticks owed by the clock.
    #[serde(skip)]
    accumulator: f64,
    /// At maximum speed, how long the next frame may simulate beyond the lesson's
    /// own budget, milliseconds (see [`TimeControl::note_frame`]).
    #[serde(skip)]
    spare_ms: f64,
}

impl Default for TimeControl {
    fn default() -> Self {
        Self {
            running: false,
            speed_tps: 10.0,
            max_speed: false,
            accumulator: 0.0,
            spare_ms: 0.0,
        }
    }
}

/// How many ticks a frame should run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TicksDue {
    /// This many whole ticks.
    Count(u64),
    /// As many as fit in the frame budget.
    AsManyAsPossible,
}

impl TimeControl {
    /// Advances the clock by `dt` seconds of real time and says how many ticks are due.
    /// Nothing is due while paused. `dt` is clamped to 0.25 s so that a stalled frame
    /// does not cause a burst.
    pub fn ticks_due(&mut self, dt: f64) -> TicksDue {
        if !self.running {
            self.accumulator = 0.0;
            return TicksDue::Count(0);
        }
        if self.max_speed {
            return TicksDue::AsManyAsPossible;
        }
        let dt = if dt.is_finite() {
            dt.clamp(0.0, 0.25)
        } else {
            0.0
        };
        let speed = if self.speed_tps.is_finite() {
            self.speed_tps
                .clamp(*SPEED_RANGE.start(), *SPEED_RANGE.end())
        } else {
            10.0
        };
        self.accumulator += dt * speed;
        let whole = self.accumulator.floor().max(0.0);
        TicksDue::Count(whole as u64)
    }

    /// Records that `done` ticks ran this frame. A backlog (the simulation was slower
    /// than asked) is dropped, so the clock never tries to catch up in a burst.
    pub fn ticks_done(&mut self, done: u64) {
        self.accumulator = (self.accumulator - done as f64).clamp(0.0, 1.0);
    }

    /// Records how the last frame went, so that at maximum speed the next one can
    /// also use the time the page's thread would sit idle: `sim_ms` is what the last
    /// frame spent simulating, `cpu_ms` the whole frame's CPU time (eframe's
    /// measurement, `None` where it gives none), `interval_ms` the time from that
    /// frame's start to this one's.
    ///
    /// Where the display is slow (software rendering in a headless browser draws a
    /// large map in a few hundred milliseconds on another thread, and the next frame
    /// waits for it), a frame's CPU time is a small part of the interval: the rest is
    /// idle. The spare time then grows by half the idle time each frame, less a small
    /// margin, and settles where the simulation fills the wait; where frames come as
    /// fast as the display's refresh, nothing is idle and the lesson's own budget
    /// holds. Capped at [`MAX_SPEED_BUDGET_MS`]; only maximum speed uses it, so a
    /// lesson run at a set speed paces exactly as before.
    pub fn note_frame(&mut self, sim_ms: f64, cpu_ms: Option<f64>, interval_ms: f64) {
        self.spare_ms = spare_budget_ms(sim_ms, cpu_ms, interval_ms);
    }

    /// How long this frame may simulate, milliseconds: the lesson's own `budget_ms`,
    /// or at maximum speed more where the last frame left the thread idle (see
    /// [`TimeControl::note_frame`]).
    pub fn budget_ms(&self, budget_ms: u128) -> u128 {
        if !(self.running && self.max_speed) {
            return budget_ms;
        }
        // `spare_ms` is finite and within 0..=MAX_SPEED_BUDGET_MS by construction.
        budget_ms.max(self.spare_ms as u128)
    }

    /// Applies one action's effect on the clock itself (the lesson does the stepping).
    /// Stepping pauses, so the student sees exactly the one step.
    pub fn apply(&mut self, action: TimeAction) {
        match action {
            TimeAction::ToggleRun => self.running = !self.running,
            TimeAction::StepPhase
            | TimeAction::StepTick
            | TimeAction::StepBack
            | TimeAction::Reset => {
                self.running = false;
            }
        }
        self.accumulator = 0.0;
    }
}

/// The simulation time a frame at maximum speed may use (see
/// [`TimeControl::note_frame`]): what the last frame simulated plus half of what it
/// left idle beyond [`IDLE_MARGIN_MS`], within `0..=MAX_SPEED_BUDGET_MS`; 0 where a
/// measurement is missing or not finite.
pub fn spare_budget_ms(sim_ms: f64, cpu_ms: Option<f64>, interval_ms: f64) -> f64 {
    let Some(cpu_ms) = cpu_ms else {
        return 0.0;
    };
    if !(sim_ms.is_finite() && cpu_ms.is_finite() && interval_ms.is_finite()) {
        return 0.0;
    }
    let idle = interval_ms - cpu_ms;
    (sim_ms + 0.5 * (idle - IDLE_MARGIN_MS)).clamp(0.0, MAX_SPEED_BUDGET_MS)
}

/// What the time bar shows about the lesson's clock.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TimeInfo {
    /// Ticks started so far.
    pub tick: u64,
    /// Simulated time, seconds; NaN for a lesson without a clock of its own (a
    /// lab whose ticks are presses, a solver whose ticks are iterations).
    pub time_s: f64,
    /// The phase that ran last ("predict", "update landmark 7 (2 of 5)").
    pub last_phase: Option<String>,
    /// The phase a "Step phase" runs next.
    pub next_phase: String,
    /// Can the lesson go back one phase now (and cheaply enough)?
    pub can_step_back: bool,
}

/// Which step buttons a lesson's clock has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StepControls {
    /// Phases within ticks: "Step phase" (naming the next phase) and "Step tick".
    #[default]
    PhasesAndTicks,
    /// One kind of step only (a solver's iteration): one button named by the
    /// lesson; `.` and `n` both run it, and the clock counts in `unit`s.
    One {
        /// The button ("Step iteration").
        label: &'static str,
        /// What one step does, for the button's tooltip.
        hover: &'static str,
        /// What a step is called in the counter and the speed ("iteration").
        unit: &'static str,
        /// What Step back undoes: `unit`, or a finer step where the lesson has
        /// buttons for parts of a step ("phase").
        back_unit: &'static str,
    },
}

/// The time bar's keys and what they do, for the Keys menu, as a lesson with
/// phases and ticks has them.
pub const SHORTCUTS: &[(&str, &str)] = &[
    ("Space", "run / pause"),
    (".", "step one phase (the time bar's Step phase)"),
    (",", "step back one phase"),
    ("n", "step one whole tick"),
    ("r", "reset the run"),
];

/// The time bar's keys and what they do in a lesson whose clock has `steps`: the
/// [`SHORTCUTS`], or for one kind of step its own button and unit ("step one
/// iteration (the time bar's Step iteration)").
pub fn shortcuts(steps: StepControls) -> Vec<(&'static str, String)> {
    match steps {
        StepControls::PhasesAndTicks => SHORTCUTS
            .iter()
            .map(|(key, what)| (*key, (*what).to_owned()))
            .collect(),
        StepControls::One {
            label,
            unit,
            back_unit,
            ..
        } => vec![
            ("Space", "run / pause".to_owned()),
            (".", format!("step one {unit} (the time bar's {label})")),
            (",", format!("step back one {back_unit} or edit")),
            ("n", format!("step one {unit}, as .")),
            ("r", "reset the run".to_owned()),
        ],
    }
}

/// Reads the keyboard shortcuts (Space, `.`, `,`, `n`, `r`) unless a text field has the
/// keyboard focus. The keys are consumed so that a focused button does not also react.
pub fn shortcut_actions(ctx: &egui::Context) -> Vec<TimeAction> {
    if ctx.text_edit_focused() {
        return Vec::new();
    }
    let keys = [
        (egui::Key::Space, TimeAction::ToggleRun),
        (egui::Key::Period, TimeAction::StepPhase),
        (egui::Key::Comma, TimeAction::StepBack),
        (egui::Key::N, TimeAction::StepTick),
        (egui::Key::R, TimeAction::Reset),
    ];
    let mut actions = Vec::new();
    ctx.input_mut(|input| {
        for (key, action) in keys {
            // Space toggles once per press; the step keys repeat while held.
            let repeats_count = key != egui::Key::Space;
            let presses = input
                .events
                .iter()
                .filter(|event| {
                    matches!(event, egui::Event::Key { key: k, pressed: true, repeat, modifiers, .. }
                        if *k == key && (repeats_count || !*repeat) && modifiers.is_none())
                })
                .count();
            // Consume even the repeats, so that a focused button does not react too.
            let _consumed = input.consume_key(egui::Modifiers::NONE, key);
            actions.extend(std::iter::repeat_n(action, presses));
        }
    });
    actions
}

/// The time bar: Run/Pause, Step back, Step phase, Step tick, Reset, speed; then
/// the tick and simulated time, the key moment the run just passed (a lesson's
/// [`Lesson::moment`](crate::lesson::Lesson::moment)), the next phase and the last.
/// A lesson with one kind of step ([`StepControls::One`]) shows one step button
/// instead of the phase and tick buttons. Returns what was clicked.
///
/// Nothing moves under the cursor: every control has a width fixed by the lesson
/// and the window (never by the text of the moment), the counter has a slot wide
/// enough for long runs, and the texts that change as the run goes (the phases,
/// the moment) come last, on one line cut to the room left (the whole text on
/// hover). Where the controls and a readable status do not fit one row (below
/// about 1100 points) the status has a row of its own: the bar's height depends on
/// the window's width only.
pub fn time_bar_ui(
    ui: &mut egui::Ui,
    time: &mut TimeControl,
    info: &TimeInfo,
    steps: StepControls,
    compact: bool,
    moment: Option<&str>,
) -> Vec<TimeAction> {
    let unit = match steps {
        StepControls::PhasesAndTicks => "tick",
        StepControls::One { unit, .. } => unit,
    };
    let mut actions = Vec::new();
    let row_height = ui.spacing().interact_size.y;
    let counter_width = text_width(ui, &counter_template(unit, info.time_s.is_finite())) + 8.0;
    ui.vertical(|ui| {
        let one_row = ui
            .horizontal_wrapped(|ui| {
                ui.set_min_height(row_height);
                controls_ui(ui, time, info, steps, unit, &mut actions);
                // The controls' widths are fixed: whether the status fits beside
                // them depends on the window's width only.
                let least = if compact {
                    STATUS_MIN_WIDTH_EMBED
                } else {
                    STATUS_MIN_WIDTH
                };
                let fits = room_left(ui) >= counter_width + least;
                if fits {
                    ui.separator();
                    status_ui(ui, info, unit, counter_width, compact, moment);
                }
                fits
            })
            .inner;
        if !one_row {
            ui.horizontal(|ui| {
                ui.set_min_height(row_height);
                status_ui(ui, info, unit, counter_width, compact, moment);
            });
        }
    });
    actions
}

/// The least width the status (moment, next and last phase) needs beside the
/// controls and the counter to share their row, points.
const STATUS_MIN_WIDTH: f32 = 300.0;

/// The same in an embedded figure, which shows only the next phase: a lecture's
/// 900-point iframe keeps the bar to one row.
const STATUS_MIN_WIDTH_EMBED: f32 = 150.0;

/// The widest counter a run is likely to reach, for its slot's width.
fn counter_template(unit: &str, timed: bool) -> String {
    if timed {
        "tick 00000   t = 0000.0 s".to_owned()
    } else {
        format!("{unit} 00000")
    }
}

/// The width of the speed value's box: its largest value with the unit.
fn speed_value_width(ui: &egui::Ui, unit: &str) -> f32 {
    text_width(ui, &format!("200 {unit}s/s")) + 2.0 * ui.spacing().button_padding.x + 6.0
}

/// The Run/Pause button's width (the longer of its two labels).
const RUN_WIDTH: f32 = 56.0;

/// Run, the steps, Reset and the speed: the same places whatever the run says.
fn controls_ui(
    ui: &mut egui::Ui,
    time: &mut TimeControl,
    info: &TimeInfo,
    steps: StepControls,
    unit: &str,
    actions: &mut Vec<TimeAction>,
) {
    let back_hover = match steps {
        StepControls::PhasesAndTicks => "Go back one phase (,)".to_owned(),
        StepControls::One { back_unit, .. } => format!("Go back one {back_unit} or edit (,)"),
    };
    let run_label = if time.running { "Pause" } else { "Run" };
    if ui
        .add(egui::Button::new(run_label).min_size(egui::vec2(RUN_WIDTH, 0.0)))
        .on_hover_text("Run or pause the simulation (Space)")
        .clicked()
    {
        actions.push(TimeAction::ToggleRun);
    }
    if ui
        .add_enabled(info.can_step_back, egui::Button::new("Step back"))
        .on_hover_text(back_hover)
        .on_disabled_hover_text("Nothing to go back to, or the run is too long to replay quickly")
        .clicked()
    {
        actions.push(TimeAction::StepBack);
    }
    match steps {
        StepControls::PhasesAndTicks => {
            if ui
                .button("Step phase")
                .on_hover_text(format!(
                    "Run one phase of the filters: the prediction, or one landmark update (.); \
                     next: {}",
                    info.next_phase
                ))
                .clicked()
            {
                actions.push(TimeAction::StepPhase);
            }
            if ui
                .button("Step tick")
                .on_hover_text(
                    "Finish the current tick, or run one whole tick: predict, then every update (n)",
                )
                .clicked()
            {
                actions.push(TimeAction::StepTick);
            }
        }
        StepControls::One { label, hover, .. } => {
            if ui
                .button(label)
                .on_hover_text(format!("{hover} (. or n); next: {}", info.next_phase))
                .clicked()
            {
                actions.push(TimeAction::StepPhase);
            }
        }
    }
    if ui
        .button("Reset")
        .on_hover_text("Start over with the parameters in the panel (r)")
        .clicked()
    {
        actions.push(TimeAction::Reset);
    }
    ui.separator();
    // The label, slider, value and max are one group: it starts a new row when
    // the rest of this one cannot hold it (a slider clips rather than wraps). Its
    // width is fixed, so where it goes depends on the window only.
    let value_width = speed_value_width(ui, unit);
    let group = text_width(ui, "Speed")
        + ui.spacing().slider_width
        + value_width
        + ui.spacing().icon_width
        + text_width(ui, "max")
        + 5.0 * ui.spacing().item_spacing.x
        + 8.0;
    if room_left(ui) < group {
        ui.end_row();
    }
    ui.label("Speed");
    ui.add_enabled(
        !time.max_speed,
        egui::Slider::new(&mut time.speed_tps, SPEED_RANGE)
            .logarithmic(true)
            .show_value(false),
    )
    .on_hover_text(format!("Speed while running, {unit}s per second"));
    let height = ui.spacing().interact_size.y;
    ui.add_enabled_ui(!time.max_speed, |ui| {
        ui.add_sized(
            egui::vec2(value_width, height),
            egui::DragValue::new(&mut time.speed_tps)
                .range(SPEED_RANGE)
                .speed(0.5)
                .max_decimals(0)
                .suffix(format!(" {unit}s/s")),
        )
        .on_hover_text(format!("Speed while running, {unit}s per second"));
    });
    ui.checkbox(&mut time.max_speed, "max")
        .on_hover_text("Run as fast as this computer can");
}

/// The tick and time in a slot of fixed width, then the key moment, the next
/// phase and the last, on one line cut to the room left (whole on hover).
fn status_ui(
    ui: &mut egui::Ui,
    info: &TimeInfo,
    unit: &str,
    counter_width: f32,
    compact: bool,
    moment: Option<&str>,
) {
    let height = ui.spacing().interact_size.y;
    let counter = if info.time_s.is_finite() {
        format!("tick {}   t = {:.1} s", info.tick, info.time_s)
    } else {
        format!("{unit} {}", info.tick)
    };
    let hover = if info.time_s.is_finite() {
        "Ticks run so far and the simulated time".to_owned()
    } else {
        format!("{unit}s run so far")
    };
    ui.allocate_ui_with_layout(
        egui::vec2(counter_width, height),
        egui::Layout::left_to_right(egui::Align::Center),
        |ui| {
            ui.set_min_width(counter_width);
            ui.label(counter).on_hover_text(hover);
        },
    );
    let next_name = match compact {
        true => "Next",
        false => "Next phase",
    };
    let mut job = egui::text::LayoutJob::default();
    let body = egui::TextStyle::Body.resolve(ui.style());
    let strong = ui.visuals().strong_text_color();
    let weak = ui.visuals().text_color();
    let mut add = |text: &str, color: egui::Color32| {
        job.append(text, 0.0, egui::TextFormat::simple(body.clone(), color));
    };
    if let Some(moment) = moment {
        add(&format!("{moment}   "), crate::palette::VERMILLION);
    }
    add(&format!("{next_name}: {}", info.next_phase), strong);
    if !compact {
        let last = info.last_phase.as_deref().unwrap_or("none yet");
        add(&format!("   Last phase: {last}"), weak);
    }
    // The room left on this row (`available_width` in a wrapping row is a whole
    // new row's, and the label would start one).
    let width = (room_left(ui) - ui.spacing().item_spacing.x).max(0.0);
    ui.allocate_ui_with_layout(
        egui::vec2(width, height),
        egui::Layout::left_to_right(egui::Align::Center),
        |ui| {
            ui.add(egui::Label::new(job).truncate()).on_hover_text(
                "What \"Step phase\" runs next, and the phase shown on the map and in the \
                 explanation",
            );
        },
    );
}

/// The width left on the current row up to the window's (or the panel's) right edge,
/// points: a row that has overflowed before widens its `Ui`, not the window.
fn room_left(ui: &egui::Ui) -> f32 {
    ui.clip_rect().right().min(ui.max_rect().right()) - ui.cursor().min.x - 4.0
}

/// The width of `text` in the body font, points.
fn text_width(ui: &egui::Ui, text: &str) -> f32 {
    let font = egui::TextStyle::Body.resolve(ui.style());
    ui.painter()
        .layout_no_wrap(text.to_owned(), font, egui::Color32::WHITE)
        .size()
        .x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A page whose display takes `display_ms` per frame (software rendering on
    /// another thread) and whose frame spends `other_ms` besides simulating: the
    /// interval is the longer of the display's time and the frame's CPU time.
    fn settle(display_ms: f64, other_ms: f64, base: u128, frames: usize) -> (u128, f64) {
        let mut time = TimeControl {
            running: true,
            max_speed: true,
            ..TimeControl::default()
        };
        let (mut sim, mut interval) = (0.0, display_ms);
        for _ in 0..frames {
            time.note_frame(sim, Some(sim + other_ms), interval);
            let budget = time.budget_ms(base);
            sim = budget as f64;
            interval = display_ms.max(sim + other_ms);
        }
        (time.budget_ms(base), sim / interval)
    }

    #[test]
    fn at_max_speed_the_simulation_fills_the_time_a_slow_display_leaves_idle() {
        // A 300 ms display and 20 ms of UI: the budget climbs from 25 ms to fill
        // the wait, less the margin (300 - 20 - 5 = 275, capped at 250).
        let (budget, share) = settle(300.0, 20.0, 25, 40);
        assert_eq!(budget, 250);
        assert!((share - 250.0 / 300.0).abs() < 1e-9, "{share}");
        // A 120 ms display: 120 - 20 - 5 = 95 ms, within a millisecond.
        let (budget, _) = settle(120.0, 20.0, 25, 60);
        assert!((94..=95).contains(&budget), "{budget}");
        // A 60 Hz display with nothing idle keeps the lesson's own budget.
        assert_eq!(settle(16.7, 4.0, 25, 60).0, 25);
        assert_eq!(settle(16.7, 4.0, 12, 60).0, 12);
    }

    #[test]
    fn the_extra_budget_needs_max_speed_and_sound_measurements() {
        let mut time = TimeControl {
            running: true,
            ..TimeControl::default()
        };
        time.note_frame(10.0, Some(30.0), 300.0);
        assert_eq!(time.budget_ms(25), 25, "a set speed paces as before");
        time.max_speed = true;
        assert_eq!(time.budget_ms(25), 142, "10 + (270 - 5) / 2");
        time.running = false;
        assert_eq!(time.budget_ms(25), 25);
        time.running = true;
        for (sim, cpu, interval) in [
            (10.0, None, 300.0),
            (f64::NAN, Some(30.0), 300.0),
            (10.0, Some(f64::INFINITY), 300.0),
            (10.0, Some(30.0), f64::NAN),
        ] {
            time.note_frame(sim, cpu, interval);
            assert_eq!(time.budget_ms(25), 25, "{sim} {cpu:?} {interval}");
        }
        // A stalled page (a background tab) is capped.
        time.note_frame(10.0, Some(30.0), 60_000.0);
        assert_eq!(time.budget_ms(25), MAX_SPEED_BUDGET_MS as u128);
    }

    #[test]
    fn the_keys_name_the_lessons_own_step() {
        let phases = shortcuts(StepControls::PhasesAndTicks);
        assert_eq!(phases.len(), SHORTCUTS.len());
        assert!(phases[1].1.contains("Step phase"));
        let one = shortcuts(StepControls::One {
            label: "Step iteration",
            hover: "Run one iteration",
            unit: "iteration",
            back_unit: "iteration",
        });
        let dot = one.iter().find(|(k, _)| *k == ".").map(|(_, w)| w.as_str());
        assert_eq!(
            dot,
            Some("step one iteration (the time bar's Step iteration)")
        );
        assert!(
            one.iter().all(|(_, what)| !what.contains("phase")),
            "{one:?}"
        );
    }

    #[test]
    fn clock_owes_ticks_at_the_set_speed_and_drops_backlogs() {
        let mut t = TimeControl {
            speed_tps: 20.0,
            ..Default::default()
        };
        assert_eq!(t.ticks_due(0.1), TicksDue::Count(0), "paused");
        t.apply(TimeAction::ToggleRun);
        assert_eq!(t.ticks_due(0.1), TicksDue::Count(2));
        t.ticks_done(2);
        assert_eq!(t.ticks_due(0.05), TicksDue::Count(1));
        t.ticks_done(0);
        assert_eq!(t.ticks_due(0.0), TicksDue::Count(1), "one tick still owed");
        t.ticks_done(0);
        assert_eq!(t.ticks_due(f64::NAN), TicksDue::Count(1));
        assert_eq!(
            t.ticks_due(100.0),
            TicksDue::Count(6),
            "dt is clamped to 0.25 s"
        );
        t.max_speed = true;
        assert_eq!(t.ticks_due(0.01), TicksDue::AsManyAsPossible);
        t.apply(TimeAction::StepPhase);
        assert!(!t.running, "stepping pauses");
    }
}
