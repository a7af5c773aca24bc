//! Manual driving: arrow keys / WASD and an on-screen pad set `(v, w)` while held;
//! sliders set a steady command, as `(v, w)` or as wheel speeds `(v_l, v_r)`.

use crate::widgets::drive::pad_ui;
pub use crate::widgets::drive::{KEY_SPEED, KEY_TURN_RATE, PadDirection, keyboard_command};
use crate::widgets::sources;
use serde::{Deserialize, Serialize};
use slamlab_core::Control;
use std::f64::consts::PI;

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
            .on_hover_text(
                "Experiment 1 of Xiang's thesis (§3.4.3): v = 1 m/s, w = π/10 rad/s, from the next tick on",
            );
        ui.radio_value(manual, true, "Manual").on_hover_text(
            "Take the wheel from the next tick on: the run, the map and the filters go on. \
             Drive with the arrow keys / WASD or the pad above the map",
        );
    });
    if !*manual {
        ui.horizontal_wrapped(|ui| {
            ui.label("The robot follows the scripted circle of Experiment 1 in Xiang's thesis.");
            sources::source_link(ui, "xiang", "Source: §3.4.3");
        });
        return;
    }
    ui.label("Hold the arrow keys or WASD, or the pad above the map: forward/back 1 m/s, turn 45°/s. Driving starts the clock.");
    ui.horizontal_wrapped(|ui| {
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
    // Wrapped lines rather than a grid: a grid row does not wrap and would widen
    // the panel past its edge.
    ui.label(format!(
        "Command now: v = {:.2} m/s, w = {:.3} rad/s ({:.1}°/s)",
        command.v,
        command.w,
        command.w.to_degrees()
    ));
    ui.label(format!(
        "As wheel speeds: v_l = {v_l:.2} m/s, v_r = {v_r:.2} m/s (D = {wheel_base:.2} m)"
    ));
    ui.horizontal_wrapped(|ui| {
        ui.label("v = (v_l + v_r) / 2,  w = (v_r − v_l) / D  (Eq. 2.65-2.66 of Xiang's thesis)");
        sources::source_link(ui, "xiang", "Source: §2.5");
    });
}

/// The on-screen drive pad, bottom right of `rect`: press and hold (mouse or touch).
/// Sets `drive.pad` to the button held now.
pub fn drive_pad_ui(ui: &mut egui::Ui, drive: &mut DriveState) {
    let press = pad_ui(ui);
    if press.stop {
        drive.stop();
    }
    drive.pad = press.held;
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
