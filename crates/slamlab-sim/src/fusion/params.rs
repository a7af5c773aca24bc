//! The fusion lesson's parameter table (`lesson=fusion`): the drive, the three
//! sensors and the filter, each parameter once with its unit, range and help, and
//! which modes run side by side. The URL, share links, `slamlab params --lesson
//! fusion` and the app's panel read it through [`crate::params`].
//!
//! Rates and noises have positive minimums: `imu-rate=0` or
//! `slam-position-noise=0` in a link is clamped to the minimum with a message
//! (a rate of 0 would never fire, a noise of 0 would make the filter refuse
//! every reading).

use super::runner::FusionMode;
use super::scenario::{FusionScenario, SlamSource};
use crate::params::{Param, ParamIssue, Scenario, choose, choose_items, list_text};

/// The modes the lesson can run, as the URL spells them.
pub const MODE_NAMES: &[&str] = &["differential", "relative", "absolute", "odometry"];
const SWITCH: &[&str] = &["0", "1"];
const SOURCES: &[&str] = &["simulated", "landmark-ekf"];

/// The fusion lesson's setup: the scenario and the modes compared on it.
#[derive(Clone, Debug, PartialEq)]
pub struct FusionLessonScenario {
    /// The drive, the sensors and the filter.
    pub scenario: FusionScenario,
    /// The modes run side by side on the same sensor data, in order.
    pub modes: Vec<FusionMode>,
}

impl Default for FusionLessonScenario {
    /// The thesis's drive and sensors; `_differential` beside `_relative`, the
    /// two modes thesis `002` Table 5.3 compares.
    fn default() -> Self {
        Self {
            scenario: FusionScenario::default(),
            modes: vec![FusionMode::Differential, FusionMode::Relative],
        }
    }
}

/// The mode named `name` ("differential", "relative", "absolute", "odometry").
pub fn mode_from_name(name: &str) -> Option<FusionMode> {
    FusionMode::ALL.into_iter().find(|m| m.name() == name)
}

/// A real-valued field of the scenario, in the parameter's unit.
macro_rules! field {
    ($name:literal, $unit:literal, $help:literal, $range:expr, $($field:ident).+) => {
        crate::params::number_field!(
            FusionLessonScenario, $name, $unit, $help, $range, scenario.$($field).+
        )
    };
}

/// An angle (or angular rate) field stored in radians, shown in degrees.
macro_rules! degrees {
    ($name:literal, $unit:literal, $help:literal, $range:expr, $($field:ident).+) => {
        crate::params::degrees_field!(
            FusionLessonScenario, $name, $unit, $help, $range, scenario.$($field).+
        )
    };
}

/// An on/off field ("1" or "0").
macro_rules! switch {
    ($name:literal, $help:literal, $($field:ident).+) => {
        Param::words(
            $name,
            $help,
            SWITCH,
            |s: &FusionLessonScenario| Some(SWITCH[usize::from(s.scenario.$($field).+)].to_owned()),
            |s: &mut FusionLessonScenario, v| {
                choose(SWITCH, v).map(|i| s.scenario.$($field).+ = i == 1)
            },
        )
    };
}

/// Every parameter of the lesson, in the order `slamlab params --lesson fusion`
/// lists them.
pub static PARAMS: &[Param<FusionLessonScenario>] = &[
    Param::count(
        "seed",
        "",
        "seed of every random stream (drive, each sensor)",
        (0, u64::MAX),
        |s| Some(s.scenario.seed),
        |s, v| s.scenario.seed = v,
    ),
    Param::words(
        "modes",
        "how the SLAM pose is fused, runs side by side, comma separated (odometry: without it)",
        MODE_NAMES,
        |s| Some(list_text(&s.modes, |m| m.name())),
        |s, v| choose_items(MODE_NAMES, v, mode_from_name).map(|list| s.modes = list),
    ),
    field!(
        "duration",
        "s",
        "length of the drive",
        (5.0, 1200.0),
        drive.duration
    ),
    field!(
        "max-speed",
        "m/s",
        "top forward speed of the joystick drive (Wu's thesis: 0.1)",
        (0.01, 2.0),
        drive.max_speed
    ),
    switch!(
        "odom",
        "fuse wheel odometry (1) or not (0)",
        odometry.enabled
    ),
    field!(
        "odom-rate",
        "Hz",
        "wheel odometry rate",
        (0.5, 200.0),
        odometry.rate
    ),
    field!(
        "odom-speed-noise",
        "m/s",
        "white noise on the reported forward speed",
        (1e-4, 1.0),
        odometry.speed_noise_std
    ),
    degrees!(
        "odom-turn-noise-deg",
        "deg/s",
        "white noise on the reported yaw rate",
        (0.01, 60.0),
        odometry.turn_noise_std
    ),
    field!(
        "odom-scale-error",
        "",
        "standard deviation of each wheel's scale error (drawn once per drive)",
        (0.0, 0.2),
        odometry.scale_error_std
    ),
    field!(
        "odom-turn-slip",
        "",
        "skid: the wheels report (1 + slip) times the body's yaw rate",
        (-0.5, 1.0),
        odometry.turn_slip
    ),
    switch!("imu", "fuse the IMU's yaw rate (1) or not (0)", imu.enabled),
    field!("imu-rate", "Hz", "IMU rate", (0.5, 200.0), imu.rate),
    degrees!(
        "imu-gyro-noise-deg",
        "deg/s",
        "white noise on the gyroscope's yaw rate (MPU-9250: 0.1)",
        (0.001, 30.0),
        imu.gyro_noise_std
    ),
    degrees!(
        "imu-gyro-bias-deg",
        "deg/s",
        "standard deviation of the gyroscope's bias at the start",
        (0.0, 10.0),
        imu.gyro_bias_std
    ),
    switch!("slam", "fuse the SLAM pose (1) or not (0)", slam.enabled),
    field!(
        "slam-rate",
        "Hz",
        "SLAM pose rate (RTAB-Map: about 1)",
        (0.05, 20.0),
        slam.rate
    ),
    Param::words(
        "slam-source",
        "simulated: truth plus noise, drift and jumps; landmark-ekf: the landmark lesson's EKF-SLAM",
        SOURCES,
        |s| {
            Some(
                match s.scenario.slam.source {
                    SlamSource::Simulated => "simulated",
                    SlamSource::LandmarkEkf => "landmark-ekf",
                }
                .to_owned(),
            )
        },
        |s, v| {
            choose(SOURCES, v).map(|i| {
                s.scenario.slam.source = [SlamSource::Simulated, SlamSource::LandmarkEkf][i];
            })
        },
    ),
    field!(
        "slam-position-noise",
        "m",
        "white noise on the SLAM pose's x and y",
        (1e-3, 5.0),
        slam.position_noise_std
    ),
    degrees!(
        "slam-yaw-noise-deg",
        "deg",
        "white noise on the SLAM pose's heading",
        (0.01, 90.0),
        slam.yaw_noise_std
    ),
    switch!(
        "slam-fuse-yaw",
        "fuse the SLAM heading too (1) or only x and y (0)",
        slam.fuse_yaw
    ),
    field!(
        "slam-drift",
        "m/sqrt(s)",
        "drift of the SLAM map between relocalizations",
        (0.0, 0.5),
        slam.drift_per_sqrt_s
    ),
    field!(
        "slam-relocalization-interval",
        "s",
        "mean time between relocalizations that reset the drift (a jump); 0: never",
        (0.0, 3600.0),
        slam.relocalization_interval
    ),
    field!(
        "slam-outlier-prob",
        "",
        "probability that a SLAM pose is a wrong relocalization",
        (0.0, 1.0),
        slam.outlier_probability
    ),
    field!(
        "slam-latency",
        "s",
        "delay between a SLAM pose's stamp and its arrival",
        (0.0, 5.0),
        slam.latency
    ),
    Param::words(
        "slam-rejection",
        "Mahalanobis rejection threshold in standard deviations (none: fuse every pose)",
        &["none", "a number above 0"],
        |s| {
            Some(
                s.scenario
                    .slam
                    .rejection_threshold
                    .map_or_else(|| "none".to_owned(), crate::params::format_number),
            )
        },
        |s, v| match v {
            "none" | "" => {
                s.scenario.slam.rejection_threshold = None;
                Ok(())
            }
            _ => match v.parse::<f64>() {
                Ok(t) if t.is_finite() && t > 0.0 => {
                    s.scenario.slam.rejection_threshold = Some(t);
                    Ok(())
                }
                _ => Err("none or a number of standard deviations above 0".to_owned()),
            },
        },
    ),
    field!(
        "output-rate",
        "Hz",
        "rate at which the fused estimate is sampled for plots and RMSE (Wu's thesis: 30)",
        (1.0, 200.0),
        output_rate
    ),
    field!(
        "filter-delay",
        "s",
        "how long the filter waits for late readings before it applies a stamp",
        (0.0, 5.0),
        filter_delay
    ),
];

impl Scenario for FusionLessonScenario {
    const LESSON: &'static str = "fusion";

    fn params() -> &'static [Param<Self>] {
        PARAMS
    }

    fn seed(&self) -> u64 {
        self.scenario.seed
    }

    fn check(&mut self) -> Vec<ParamIssue> {
        let mut issues = Vec::new();
        if self.modes.is_empty() {
            self.modes = FusionLessonScenario::default().modes;
        }
        if self.scenario.validate().is_err() {
            issues.push(ParamIssue::Ignored {
                name: "scenario".to_owned(),
                reason: "a parameter outside the simulator's limits; the defaults are used",
            });
            self.scenario = FusionScenario {
                seed: self.scenario.seed,
                ..FusionScenario::default()
            };
        }
        issues
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::checks::*;
    use crate::params::{apply_pairs, describe, get, sanitize, to_pairs};

    #[test]
    fn every_parameter_round_trips_and_the_defaults_are_in_range() {
        let mut s = FusionLessonScenario::default();
        assert!(sanitize(&mut s).is_empty(), "{:?}", sanitize(&mut s));
        let pairs = to_pairs(&s);
        assert_eq!(pairs.len(), PARAMS.len(), "every parameter has a value");
        let mut copy = FusionLessonScenario {
            modes: vec![FusionMode::Absolute],
            ..FusionLessonScenario::default()
        };
        copy.scenario.seed = 99;
        copy.scenario.imu.gyro_noise_std = 1.0;
        assert_applies(&mut copy, &pairs);
        assert_eq!(to_pairs(&copy), pairs);
        assert_eq!(copy.modes, s.modes);
        // Degrees in, radians inside: 0.1 °/s is the scenario's default.
        assert_eq!(get(&s, "imu-gyro-noise-deg").as_deref(), Some("0.1"));
        assert_round_trip(
            &mut s,
            &[
                ("modes", "absolute,odometry"),
                ("slam-rejection", "3"),
                ("slam-source", "landmark-ekf"),
                ("odom", "0"),
                ("slam-yaw-noise-deg", "5"),
            ],
        );
        assert_eq!(s.modes, vec![FusionMode::Absolute, FusionMode::Odometry]);
        assert_eq!(s.scenario.slam.rejection_threshold, Some(3.0));
        assert!(!s.scenario.odometry.enabled);
        assert!((s.scenario.slam.yaw_noise_std - 5f64.to_radians()).abs() < 1e-15);
        assert_eq!(describe::<FusionLessonScenario>().len(), PARAMS.len());
    }

    #[test]
    fn a_rate_of_zero_and_a_noise_of_zero_are_clamped_with_a_message() {
        let mut s = FusionLessonScenario::default();
        let issues = apply_pairs(
            &mut s,
            [
                ("imu-rate", "0"),
                ("slam-position-noise", "0"),
                ("odom-speed-noise", "-1"),
                ("slam-rate", "NaN"),
                ("modes", "kalman"),
                ("slam-rejection", "-2"),
            ],
            &[],
        );
        let text: Vec<String> = issues.iter().map(ToString::to_string).collect();
        assert_eq!(text.len(), 6, "{text:?}");
        assert_eq!(text[0], "imu-rate = 0 is out of range; using 0.5 Hz");
        assert_eq!(
            text[1],
            "slam-position-noise = 0 is out of range; using 0.001 m"
        );
        assert!(text[2].starts_with("odom-speed-noise = -1 is out of range"));
        assert!(text[3].contains("is not a finite number"), "{}", text[3]);
        assert!(text[4].contains("differential, relative"), "{}", text[4]);
        assert!(text[5].contains("none or a number"), "{}", text[5]);
        assert_eq!(s.scenario.imu.rate, 0.5);
        assert_eq!(
            s.scenario.slam.rate, 1.0,
            "an unreadable value keeps the current one"
        );
        assert_eq!(s.modes, FusionLessonScenario::default().modes);
        assert!(s.scenario.validate().is_ok());
    }
}
