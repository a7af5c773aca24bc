//! SLAM Lab's colours: the Okabe-Ito palette, used the same way in every lesson
//! (see `design/LESSONS.md`, "Visual language").

use egui::Color32;

/// Okabe-Ito blue: EKF.
pub const BLUE: Color32 = Color32::from_rgb(0x00, 0x72, 0xB2);
/// Okabe-Ito orange: UKF.
pub const ORANGE: Color32 = Color32::from_rgb(0xE6, 0x9F, 0x00);
/// Okabe-Ito reddish purple: FastSLAM and particle filters; also the fallback.
pub const PURPLE: Color32 = Color32::from_rgb(0xCC, 0x79, 0xA7);
/// Okabe-Ito bluish green: costmap-aware filters.
pub const GREEN: Color32 = Color32::from_rgb(0x00, 0x9E, 0x73);
/// Okabe-Ito vermillion: errors and things to notice (the landmark being updated).
pub const VERMILLION: Color32 = Color32::from_rgb(0xD5, 0x5E, 0x00);
/// Okabe-Ito sky blue: the first-estimates Jacobian EKF (a lighter EKF blue).
pub const SKY_BLUE: Color32 = Color32::from_rgb(0x56, 0xB4, 0xE9);
/// Okabe-Ito yellow: the ideal EKF (linearized at the truth), reachable by URL only.
pub const YELLOW: Color32 = Color32::from_rgb(0xF0, 0xE4, 0x42);
/// Dead reckoning: grey (drawn dashed).
pub const DEAD_RECKONING: Color32 = Color32::from_rgb(0x8C, 0x8C, 0x8C);

/// The colour of an estimator, by its short name ("ekf", "ukf", ...).
pub fn estimator_color(name: &str) -> Color32 {
    match name {
        "ekf" => BLUE,
        "ukf" => ORANGE,
        "fej-ekf" => SKY_BLUE,
        "ideal-ekf" => YELLOW,
        "fastslam" | "mcl" | "amcl" | "pf" => PURPLE,
        "acmcl" => GREEN,
        _ => PURPLE,
    }
}

/// Ground truth: black on a light background, white on a dark one.
pub fn truth_color(dark_mode: bool) -> Color32 {
    if dark_mode {
        Color32::WHITE
    } else {
        Color32::BLACK
    }
}

/// `color` with its alpha multiplied by `alpha` (0..1).
pub fn faded(color: Color32, alpha: f32) -> Color32 {
    color.gamma_multiply(alpha.clamp(0.0, 1.0))
}

/// A diverging colour map for correlations in `[-1, 1]`: blue (-1), light grey (0),
/// vermillion (+1). Non-finite values are a neutral mid grey.
pub fn diverging(value: f64) -> Color32 {
    if !value.is_finite() {
        return Color32::from_gray(128);
    }
    let t = value.clamp(-1.0, 1.0) as f32;
    let mid = [0.93_f32, 0.93, 0.93];
    let end = if t < 0.0 {
        [0.0_f32, 0.447, 0.698]
    } else {
        [0.835_f32, 0.369, 0.0]
    };
    let s = t.abs().powf(0.8);
    let mix = |a: f32, b: f32| ((a + (b - a) * s) * 255.0).round().clamp(0.0, 255.0) as u8;
    Color32::from_rgb(
        mix(mid[0], end[0]),
        mix(mid[1], end[1]),
        mix(mid[2], end[2]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimators_get_their_palette_colours() {
        assert_eq!(estimator_color("ekf"), BLUE);
        assert_eq!(estimator_color("ukf"), ORANGE);
        assert_eq!(estimator_color("something-new"), PURPLE);
    }

    #[test]
    fn diverging_map_ends_and_middle() {
        assert_eq!(diverging(-1.0), BLUE);
        assert_eq!(diverging(1.0), VERMILLION);
        assert_eq!(diverging(0.0), Color32::from_rgb(237, 237, 237));
        assert_eq!(diverging(f64::NAN), Color32::from_gray(128));
        assert_eq!(diverging(5.0), VERMILLION);
    }
}
