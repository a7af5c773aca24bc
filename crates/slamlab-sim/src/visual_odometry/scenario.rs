//! The visual-odometry lesson's parameter table (`lesson=visual-odometry`): one
//! list of names, units, ranges and defaults for the URL, the app's panel,
//! `slamlab run visual-odometry` and `slamlab params --lesson visual-odometry`.

use serde::{Deserialize, Serialize};
use slamlab_core::vision::{EarlyRejection, Method};

use super::odometry::VoSettings;
use crate::params::{Param, Scenario, choice_field, count_field, number_field, switch_field};

/// The lesson's parameters: the run's settings and the VO step shown in the
/// two images.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct VoScenario {
    /// The run's settings.
    pub settings: VoSettings,
    /// The VO step shown in the two images (0 = the first).
    pub pair: usize,
}

impl Default for VoScenario {
    fn default() -> Self {
        Self {
            settings: VoSettings::default(),
            pair: DEFAULT_PAIR,
        }
    }
}

/// The step shown first: frames 25 → 30 with the default stride, on the
/// straight at 1.5 m/s (0.75 m between the images).
pub const DEFAULT_PAIR: usize = 5;

const METHODS: &[&str] = &["five-point", "eight-point"];
const EARLY_REJECTION: &[&str] = &["none", "sprt"];

/// The lesson's parameter table.
pub static PARAMS: &[Param<VoScenario>] = &[
    count_field!(
        "seed",
        "seed of the world, the pixel noise, the wrong matches, the wheels and RANSAC",
        (0, u64::MAX),
        settings.seed
    ),
    choice_field!(
        "method",
        "the minimal solver inside RANSAC: five-point (calibrated, Eq. 4.22-4.25) or eight-point (Eq. 4.18-4.21)",
        METHODS,
        [Method::FivePoint, Method::EightPoint],
        settings.method
    ),
    switch_field!(
        "normalize",
        "Hartley normalization in the eight-point solver (pixels moved to mean 0, mean distance √2)",
        settings.normalize
    ),
    switch_field!(
        "refine",
        "Levenberg-Marquardt on (R, t) over the Sampson distances of the inliers, after RANSAC and (eight-point) inside its local optimization (on), or the linear eight-point refits alone (off)",
        settings.refine
    ),
    choice_field!(
        "early-rejection",
        "none: every hypothesis is checked against every match; sprt: Matas and Chum's sequential probability ratio test rejects a bad hypothesis after a few matches",
        EARLY_REJECTION,
        [EarlyRejection::None, EarlyRejection::Sprt],
        settings.early_rejection
    ),
    number_field!(
        "outliers",
        "",
        "share of wrong matches (a random pixel in the second image)",
        (0.0, 1.0),
        settings.outliers
    ),
    number_field!(
        "noise-px",
        "px",
        "pixel noise, standard deviation on each axis of both images",
        (0.0, 20.0),
        settings.noise_px
    ),
    switch_field!(
        "pure-rotation",
        "a 20-frame turn on the spot a third of the way (no translation: a degenerate case)",
        settings.pure_rotation_segment
    ),
    switch_field!(
        "planar",
        "the middle third of the run sees only the facade (a planar scene: a degenerate case for the eight-point method)",
        settings.planar_segment
    ),
    count_field!(
        "frames",
        "frames of the docking approach, 0.1 s each",
        (10, 2000),
        settings.frames
    ),
    count_field!(
        "stride",
        "frames between the two images of a VO step",
        (1, 50),
        settings.stride
    ),
    count_field!(
        "pair",
        "the VO step shown in the two images (0 = the first); beyond the last, the last",
        (0, 2000),
        pair
    ),
];

impl Scenario for VoScenario {
    const LESSON: &'static str = "visual-odometry";

    fn params() -> &'static [Param<Self>] {
        PARAMS
    }

    fn seed(&self) -> u64 {
        self.settings.seed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params;

    #[test]
    fn the_table_round_trips_and_bad_values_get_messages() {
        let mut s = VoScenario::default();
        let pairs = [
            ("method", "eight-point"),
            ("normalize", "off"),
            ("early-rejection", "sprt"),
            ("outliers", "0.5"),
            ("noise-px", "2"),
            ("pure-rotation", "on"),
            ("planar", "on"),
            ("pair", "14"),
            ("seed", "3"),
        ];
        assert!(params::apply_pairs(&mut s, pairs, &[]).is_empty());
        assert_eq!(s.settings.method, Method::EightPoint);
        assert!(!s.settings.normalize);
        assert_eq!(s.settings.early_rejection, EarlyRejection::Sprt);
        assert!(s.settings.pure_rotation_segment && s.settings.planar_segment);
        assert_eq!((s.pair, s.settings.seed), (14, 3));
        let back = params::to_pairs(&s);
        let mut again = VoScenario::default();
        let texts: Vec<(&str, &str)> = back.iter().map(|(k, v)| (*k, v.as_str())).collect();
        assert!(params::apply_pairs(&mut again, texts, &[]).is_empty());
        assert_eq!(again, s);

        let mut s = VoScenario::default();
        let issues = params::apply_pairs(
            &mut s,
            [
                ("outliers", "2"),
                ("method", "seven-point"),
                ("noise-px", "x"),
                ("early-rejection", "wald"),
            ],
            &[],
        );
        assert_eq!(issues.len(), 4, "{issues:?}");
        assert_eq!(s.settings.early_rejection, EarlyRejection::None, "kept");
        assert_eq!(s.settings.outliers, 1.0, "clamped to the range");
        assert_eq!(s.settings.method, Method::FivePoint, "kept");
        assert_eq!(s.settings.noise_px, 1.0, "kept");
        assert!(issues[1].to_string().contains("five-point, eight-point"));
    }
}
