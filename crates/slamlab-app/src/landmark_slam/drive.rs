//! Manual driving: arrow keys / WASD and an on-screen pad set `(v, w)` while held;
//! sliders set a steady command, as `(v, w)` or as wheel speeds `(v_l, v_r)`.

use serde::{Deserialize, Serialize};
use slamlab_core::Control;
use std::f64::consts::PI;

/// Forward speed while a drive key is held, m/s.
pub const KEY_SPEED: f64 = 1.0;
/// Turn rate while a turn key is held, rad/s.
pub const KEY_TURN_RATE: f64 = PI / 4.0;
/// Slider range of the forward speed and of each wheel's speed, m/s.
pub const SPEED_LIMIT: f64 = 2.0;
/// Slider range of the turn rate, rad/s.
pub const TURN_LIMIT: f64 = PI / 2.0;

/// How the steady command is entered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum DriveInput {
    /// Forward speed `v` and turn rate `w`.
    #[default]
    VelocityAndTurnRate,
    /// Left and right wheel speeds with the wheel base `D` (thesis Eq. 2.65-2.66).
    WheelSpeeds,
}

/// A direction of the on-screen pad.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PadDirection {
    /// Drive forward.
    Forward,
    /// Drive backward.
    Backward,
    /// Turn left on the spot.
    Left,
    /// Turn right on the spot.
    Right,
}

impl PadDirection {
    /// The command while this direction is held.
    pub fn command(self) -> Control {
        match self {
            PadDirection::Forward => Control::new(KEY_SPEED, 0.0),
            PadDirection::Backward => Control::new(-KEY_SPEED, 0.0),
            PadDirection::Left => Control::new(0.0, KEY_TURN_RATE),
            PadDirection::Right => Control::new(0.0, -KEY_TURN_RATE),
        }
    }
}

/// The manual-driving state.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DriveState {
    /// How the steady command is entered.
    pub input: DriveInput,
    /// The steady command from the sliders (used when nothing is held).
    pub steady: Control,
    /// Wheel speeds of the steady command in wheel-speed mode, m/s.
    pub wheels: (f64, f64),
    /// The command from the keys held this frame.
    pub keys: Option<Control>,
    /// The pad button held this frame.
    pub pad: Option<PadDirection>,
    /// Was a key or pad button held in the previous frame?
    pub was_active: bool,
}

impl DriveState {
    /// The command the robot gets now: held keys, else the held pad button, else the
    /// steady command.
    pub fn command(&self) -> Control {
        self.keys
            .or(self.pad.map(PadDirection::command))
            .unwrap_or(self.steady)
    }

    /// Is a key or pad button held?
    pub fn is_active(&self) -> bool {
        self.keys.is_some() || self.pad.is_some()
    }

    /// Stops the robot: steady command zero, nothing held.
    pub fn stop(&mut self) {
        self.steady = Control::default();
        self.wheels = (0.0, 0.0);
        self.keys = None;
        self.pad = None;
        self.was_active = false;
    }
}

/// The command of the drive keys held now (arrows or WASD), or `None` when none is
/// held or a text field has the keyboard. Arrow presses are consumed so that a
/// focused slider does not move too.
pub fn keyboard_command(ctx: &egui::Context) -> Option<Control> {
    if ctx.text_edit_focused() {
        return None;
    }
    use egui::Key;
    let (forward, backward, left, right) = ctx.input(|i| {
        let any = |keys: [Key; 2]| keys.iter().any(|k| i.key_down(*k));
        (
            any([Key::ArrowUp, Key::W]),
            any([Key::ArrowDown, Key::S]),
            any([Key::ArrowLeft, Key::A]),
            any([Key::ArrowRight, Key::D]),
        )
    });
    if !(forward || backward || left || right) {
        return None;
    }
    ctx.input_mut(|i| {
        for key in [
            Key::ArrowUp,
            Key::ArrowDown,
            Key::ArrowLeft,
            Key::ArrowRight,
        ] {
            let _consumed = i.consume_key(egui::Modifiers::NONE, key);
        }
    });
    let axis = |plus: bool, minus: bool| f64::from(i8::from(plus) - i8::from(minus));
    Some(Control::new(
        KEY_SPEED * axis(forward, backward),
        KEY_TURN_RATE * axis(left, right),
    ))
}

/// The "Driving" section: scripted circle or manual, the input mode, the steady
/// command's sliders, and the command shown both as `(v, w)` and as wheel speeds.
pub fn drive_panel_ui(
    ui: &mut egui::Ui,
    drive: &mut DriveState,
    manual: &mut bool,
    wheel_base: f64,
) {
    ui.heading("Driving");
    ui.horizontal(|ui| {
        ui.radio_value(manual, false, "Scripted circle")
            .on_hover_text("Thesis Experiment 1: v = 1 m/s, w = π/10 rad/s, from the next tick on");
        ui.radio_value(manual, true, "Manual").on_hover_text(
            "Take the wheel from the next tick on: the run, the map and the filters go on. \
             Drive with the arrow keys / WASD or the pad on the map",
        );
    });
    if !*manual {
        ui.label("The robot follows the scripted circle (thesis Experiment 1).");
        return;
    }
    ui.label("Hold the arrow keys or WASD, or the pad on the map: forward/back 1 m/s, turn 45°/s. Driving starts the clock.");
    ui.horizontal(|ui| {
        ui.label("Steady command as");
        ui.radio_value(&mut drive.input, DriveInput::VelocityAndTurnRate, "(v, w)");
        ui.radio_value(
            &mut drive.input,
            DriveInput::WheelSpeeds,
            "wheel speeds (v_l, v_r)",
        );
    });
    match drive.input {
        DriveInput::VelocityAndTurnRate => {
            ui.add(
                egui::Slider::new(&mut drive.steady.v, -SPEED_LIMIT..=SPEED_LIMIT)
                    .suffix(" m/s")
                    .text("v, forward speed"),
            );
            ui.add(
                egui::Slider::new(&mut drive.steady.w, -TURN_LIMIT..=TURN_LIMIT)
                    .suffix(" rad/s")
                    .text("w, turn rate"),
            );
            drive.wheels = drive.steady.to_wheel_speeds(wheel_base);
        }
        DriveInput::WheelSpeeds => {
            ui.add(
                egui::Slider::new(&mut drive.wheels.0, -SPEED_LIMIT..=SPEED_LIMIT)
                    .suffix(" m/s")
                    .text("v_l, left wheel"),
            );
            ui.add(
                egui::Slider::new(&mut drive.wheels.1, -SPEED_LIMIT..=SPEED_LIMIT)
                    .suffix(" m/s")
                    .text("v_r, right wheel"),
            );
            if let Some(control) =
                Control::from_wheel_speeds(drive.wheels.0, drive.wheels.1, wheel_base)
            {
                drive.steady = control;
            }
        }
    }
    if ui
        .button("Stop")
        .on_hover_text("Set the steady command to zero")
        .clicked()
    {
        drive.stop();
    }
    let command = drive.command();
    let (v_l, v_r) = command.to_wheel_speeds(wheel_base);
    egui::Grid::new("drive_command")
        .num_columns(2)
        .show(ui, |ui| {
            ui.label("command now");
            ui.label(format!(
                "v = {:.2} m/s, w = {:.3} rad/s ({:.1}°/s)",
                command.v,
                command.w,
                command.w.to_degrees()
            ));
            ui.end_row();
            ui.label("as wheel speeds");
            ui.label(format!(
                "v_l = {v_l:.2} m/s, v_r = {v_r:.2} m/s (D = {wheel_base:.2} m)"
            ));
            ui.end_row();
        });
    ui.label(
        egui::RichText::new("v = (v_l + v_r) / 2,  w = (v_r − v_l) / D  (thesis Eq. 2.65-2.66)")
            .small(),
    );
}

/// The on-screen drive pad, bottom right of `rect`: press and hold (mouse or touch).
/// Sets `drive.pad` to the button held now.
pub fn drive_pad_ui(ui: &mut egui::Ui, rect: egui::Rect, drive: &mut DriveState) {
    let size = egui::vec2(70.0, 34.0);
    let gap = 4.0;
    let origin = rect.right_bottom()
        - egui::vec2(
            3.0 * size.x + 2.0 * gap + 10.0,
            3.0 * size.y + 2.0 * gap + 10.0,
        );
    let cell = |col: f32, row: f32| {
        egui::Rect::from_min_size(
            origin + egui::vec2(col * (size.x + gap), row * (size.y + gap)),
            size,
        )
    };
    let buttons = [
        (cell(1.0, 0.0), "Forward", Some(PadDirection::Forward)),
        (cell(0.0, 1.0), "Left", Some(PadDirection::Left)),
        (cell(1.0, 1.0), "Stop", None),
        (cell(2.0, 1.0), "Right", Some(PadDirection::Right)),
        (cell(1.0, 2.0), "Back", Some(PadDirection::Backward)),
    ];
    let mut held = None;
    for (button_rect, label, direction) in buttons {
        let response = ui
            .put(button_rect, egui::Button::new(label))
            .on_hover_text("Press and hold to drive");
        match direction {
            Some(direction) if response.is_pointer_button_down_on() => held = Some(direction),
            None if response.clicked() => drive.stop(),
            _ => {}
        }
    }
    drive.pad = held;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn held_input_beats_the_steady_command() {
        let mut d = DriveState {
            steady: Control::new(0.5, 0.1),
            ..Default::default()
        };
        assert_eq!(d.command(), Control::new(0.5, 0.1));
        d.pad = Some(PadDirection::Left);
        assert_eq!(d.command(), Control::new(0.0, KEY_TURN_RATE));
        d.keys = Some(Control::new(1.0, 0.0));
        assert_eq!(d.command(), Control::new(1.0, 0.0));
        d.stop();
        assert_eq!(d.command(), Control::default());
        assert!(!d.is_active());
    }
}
