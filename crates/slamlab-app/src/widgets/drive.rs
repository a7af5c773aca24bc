//! Driving by hand, for every lesson with a robot: arrow keys / WASD and an
//! on-screen pad (mouse or touch) give a command `(v, w)` while held.

use slamlab_core::Control;
use std::f64::consts::PI;

/// Forward speed while a drive key is held, m/s.
pub const KEY_SPEED: f64 = 1.0;
/// Turn rate while a turn key is held, rad/s.
pub const KEY_TURN_RATE: f64 = PI / 4.0;
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

/// The drive keys, for the Keys menu of lessons that drive by hand.
pub const DRIVE_KEYS: &[(&str, &str)] = &[
    ("↑ or W", "drive forward (while held)"),
    ("↓ or S", "drive backward"),
    ("← or A", "turn left"),
    ("→ or D", "turn right"),
];

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

/// What the pad was asked this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PadPress {
    /// The direction held now.
    pub held: Option<PadDirection>,
    /// "Stop" was clicked.
    pub stop: bool,
}

/// The on-screen drive pad: one row of buttons above the map (docked outside it, so
/// it never covers the world): press and hold to drive, Stop to halt.
pub fn pad_ui(ui: &mut egui::Ui) -> PadPress {
    let buttons = [
        ("Left", Some(PadDirection::Left)),
        ("Forward", Some(PadDirection::Forward)),
        ("Stop", None),
        ("Back", Some(PadDirection::Backward)),
        ("Right", Some(PadDirection::Right)),
    ];
    let mut press = PadPress::default();
    ui.horizontal_wrapped(|ui| {
        ui.label("Drive (press and hold, or arrow keys / WASD):");
        for (label, direction) in buttons {
            let response = ui.add(egui::Button::new(label).min_size(egui::vec2(64.0, 26.0)));
            match direction {
                Some(direction) if response.is_pointer_button_down_on() => {
                    press.held = Some(direction);
                }
                None if response.clicked() => press.stop = true,
                _ => {}
            }
        }
    });
    press
}
