//! The landmark-SLAM lesson's parameter table: each parameter once, with its
//! unit, range, help, getter and setter. The URL, share links, the CLI flags,
//! `slamlab params` and the app's panel all read it through [`crate::params`].

use crate::landmark_slam::presets;
use crate::params::{self, Param, ParamIssue, Preset, Scenario, choose, choose_items, list_text};
use crate::world::landmark_scenario::{
    Association, ControllerKind, EstimatorKind, LandmarkScenario, MapMode,
};
use crate::world::landmarks::LandmarkLayout;
use slamlab_core::MotionModel;
use slamlab_core::particle::Resampler;

const LAYOUTS: &[&str] = &["teaching", "random"];
const MOTIONS: &[&str] = &["exact-arc", "euler"];
const CONTROLLERS: &[&str] = &["circle", "manual"];
const ESTIMATORS: &[&str] = &[
    "ekf",
    "ukf",
    "fej-ekf",
    "ideal-ekf",
    "fastslam1",
    "fastslam2",
];
const RESAMPLERS: &[&str] = &["multinomial", "low-variance", "stratified", "residual"];
const ASSOCIATIONS: &[&str] = &["known", "unknown"];
const MODES: &[&str] = &["slam", "localization"];

/// Why the circle's speeds are refused while the robot is driven by hand.
const MANUAL_SPEEDS: &str =
    "the scripted circle's speeds do nothing while the robot is driven by hand (controller=manual)";

/// A real-valued field in the parameter's unit.
macro_rules! field {
    ($($args:tt)*) => {
        crate::params::number_field!(LandmarkScenario, $($args)*)
    };
}

/// A field in radians, given in degrees.
macro_rules! degrees {
    ($($args:tt)*) => {
        crate::params::degrees_field!(LandmarkScenario, $($args)*)
    };
}

/// The circle's `(v, w)`, or `None` while the robot is driven by hand.
fn circle(s: &LandmarkScenario) -> Option<(f64, f64)> {
    match s.controller {
        ControllerKind::Circle { v, w } => Some((v, w)),
        ControllerKind::Manual => None,
    }
}

/// Every landmark-scenario parameter. `preset` comes first: it sets all the others
/// (but the seed), and whatever else is given applies on top of it.
pub static PARAMS: &[Param<LandmarkScenario>] = &[
    Param::words(
        "preset",
        "start from a named scenario (see the README); other parameters apply on top",
        presets::PRESET_IDS,
        |_| None,
        params::apply_preset::<LandmarkScenario>,
    ),
    Param::count(
        "seed",
        "",
        "seed of every random stream",
        (0, u64::MAX),
        |s| Some(s.seed),
        |s, v| s.seed = v,
    ),
    field!("dt", "s", "simulation time step", (0.001, 1.0), dt),
    field!(
        "world-size",
        "m",
        "side of the square world",
        (2.0, 200.0),
        world_size
    ),
    Param::count(
        "landmarks",
        "",
        "number of landmarks",
        (0, 500),
        |s| Some(s.landmarks as u64),
        |s, v| s.landmarks = usize::try_from(v).unwrap_or(usize::MAX),
    ),
    Param::words(
        "layout",
        "landmark layout",
        LAYOUTS,
        |s| Some(s.layout.name().to_owned()),
        |s, v| {
            choose(LAYOUTS, v).map(|i| {
                s.layout = [LandmarkLayout::Teaching, LandmarkLayout::Random][i];
            })
        },
    ),
    Param::words(
        "motion",
        "motion model of the estimators",
        MOTIONS,
        |s| {
            Some(
                match s.motion {
                    MotionModel::ExactArc => "exact-arc",
                    MotionModel::Euler => "euler",
                }
                .to_owned(),
            )
        },
        |s, v| {
            choose(MOTIONS, v).map(|i| s.motion = [MotionModel::ExactArc, MotionModel::Euler][i])
        },
    ),
    field!(
        "v-std",
        "m/s",
        "std of the executed forward speed (Xiang's thesis §3.4.3: q[0])",
        (1e-4, 2.0),
        v_std
    ),
    degrees!(
        "w-std-deg",
        "deg/s",
        "std of the executed turn rate (Xiang's thesis §3.4.3: q[1] = 10)",
        (0.01, 90.0),
        w_std
    ),
    field!(
        "range-std",
        "m",
        "std of range measurements (Xiang's thesis §3.4.3: v[0])",
        (1e-3, 10.0),
        range_std
    ),
    degrees!(
        "bearing-std-deg",
        "deg",
        "std of bearing measurements (Xiang's thesis §3.4.3: v[1] = 10)",
        (0.01, 90.0),
        bearing_std
    ),
    degrees!("fov-deg", "deg", "sensor field of view", (1.0, 360.0), fov),
    field!(
        "max-range",
        "m",
        "sensor maximum range",
        (0.1, 100.0),
        max_range
    ),
    field!(
        "wheel-base",
        "m",
        "distance between the wheels",
        (0.05, 5.0),
        wheel_base
    ),
    Param::words(
        "controller",
        "who drives: the scripted circle or the user",
        CONTROLLERS,
        |s| Some(CONTROLLERS[usize::from(circle(s).is_none())].to_owned()),
        |s, v| {
            choose(CONTROLLERS, v).map(|i| match i {
                0 if circle(s).is_none() => s.controller = ControllerKind::default(),
                0 => {}
                _ => s.controller = ControllerKind::Manual,
            })
        },
    ),
    Param::number(
        "v",
        "m/s",
        "forward speed of the scripted circle (Xiang's thesis §3.4.3: u_v = 1)",
        (-5.0, 5.0),
        |s| circle(s).map(|(v, _)| v),
        |s, v| {
            let (_, w) = circle(s).ok_or(MANUAL_SPEEDS)?;
            s.controller = ControllerKind::Circle { v, w };
            Ok(())
        },
    ),
    Param::number(
        "w-deg",
        "deg/s",
        "turn rate of the scripted circle (Xiang's thesis §3.4.3: u_w = 18)",
        (-180.0, 180.0),
        |s| circle(s).map(|(_, w)| w.to_degrees()),
        |s, w| {
            let (v, _) = circle(s).ok_or(MANUAL_SPEEDS)?;
            s.controller = ControllerKind::Circle {
                v,
                w: w.to_radians(),
            };
            Ok(())
        },
    ),
    Param::words(
        "estimator",
        "estimators to run, comma separated",
        ESTIMATORS,
        |s| Some(list_text(&s.estimators, |e| e.name())),
        |s, v| {
            choose_items(ESTIMATORS, v, EstimatorKind::from_name).map(|list| s.estimators = list)
        },
    ),
    field!(
        "ukf-alpha",
        "",
        "UKF sigma-point spread alpha",
        (1e-3, 2.0),
        ukf.alpha
    ),
    field!(
        "ukf-beta",
        "",
        "UKF prior-knowledge beta (2 for Gaussians)",
        (-10.0, 10.0),
        ukf.beta
    ),
    field!(
        "ukf-kappa",
        "",
        "UKF secondary scaling kappa (alpha^2 (k + kappa) must exceed 0)",
        (-10.0, 10.0),
        ukf.kappa
    ),
    Param::count(
        "particles",
        "",
        "FastSLAM's particle count M (0 is refused: at least one particle)",
        (1, 10_000),
        |s| Some(s.fastslam.particles as u64),
        |s, v| s.fastslam.particles = usize::try_from(v).unwrap_or(usize::MAX),
    ),
    Param::words(
        "fastslam-resampler",
        "FastSLAM's resampling method",
        RESAMPLERS,
        |s| Some(s.fastslam.resampler.name().to_owned()),
        |s, v| {
            choose(RESAMPLERS, v).map(|i| {
                s.fastslam.resampler = Resampler::from_name(RESAMPLERS[i]).unwrap_or_default();
            })
        },
    ),
    field!(
        "resample-threshold",
        "",
        "FastSLAM resamples when N_eff < threshold * M; a fraction in [0, 1] (0 never resamples)",
        (0.0, 1.0),
        fastslam.resample_threshold
    ),
    Param::words(
        "association",
        "known: the sensor's landmark ids; unknown: FastSLAM per-particle maximum likelihood, EKF/UKF nearest neighbour",
        ASSOCIATIONS,
        |s| Some(s.association.name().to_owned()),
        |s, v| {
            choose(ASSOCIATIONS, v)
                .map(|i| s.association = [Association::Known, Association::Unknown][i])
        },
    ),
    field!(
        "gate",
        "",
        "EKF/UKF nearest-neighbour Mahalanobis gate, chi-square with 2 dof (13.8 = 99.9 %)",
        (0.1, 100.0),
        gate
    ),
    field!(
        "new-landmark-threshold",
        "",
        "a new landmark starts beyond this squared Mahalanobis distance (unknown association); EKF/UKF drop a measurement between the gate and it as ambiguous",
        (0.1, 100.0),
        fastslam.new_landmark_threshold
    ),
    field!(
        "outlier-gate",
        "",
        "EKF/UKF refuse a known landmark's measurement beyond this squared Mahalanobis distance (chi-square, 2 dof; 13.8 = 99.9 %); 0 is off",
        (0.0, 1000.0),
        outlier_gate
    ),
    Param::words(
        "mode",
        "slam: the landmarks are estimated; localization: the true landmarks are given as the map",
        MODES,
        |s| Some(s.mode.name().to_owned()),
        |s, v| choose(MODES, v).map(|i| s.mode = [MapMode::Slam, MapMode::Localization][i]),
    ),
    Param::count(
        "robot",
        "",
        "the robot of a recorded MRCLAM data set (1 to 5 in Dataset 6; data= or --data)",
        (1, 99),
        |s| Some(u64::from(s.robot)),
        |s, v| s.robot = u32::try_from(v).unwrap_or(u32::MAX),
    ),
    // In radians, as the course states it (0.005 rad): in degrees, six decimals would
    // not give the default back.
    field!(
        "odometry-rot-std",
        "rad",
        "std of each rotation of a recorded odometry reading (the Freiburg course's data)",
        (1e-5, 0.8),
        odometry_rot_std
    ),
    field!(
        "odometry-trans-std",
        "m",
        "std of the translation of a recorded odometry reading (the Freiburg course's data)",
        (1e-4, 2.0),
        odometry_trans_std
    ),
    degrees!(
        "steering-std-deg",
        "deg",
        "std of a recorded car's steering angle (Victoria Park; its speed's is v-std)",
        (0.01, 45.0),
        steering_std
    ),
];

impl Scenario for LandmarkScenario {
    const LESSON: &'static str = "landmark-slam";

    fn params() -> &'static [Param<Self>] {
        PARAMS
    }

    fn presets() -> &'static [Preset<Self>] {
        presets::PRESETS
    }

    fn seed(&self) -> u64 {
        self.seed
    }

    /// A preset first; then who drives, so that the circle's speeds meet the same
    /// controller in any order.
    fn apply_rank(name: &str) -> u8 {
        match name {
            "preset" => 0,
            "controller" => 1,
            _ => 2,
        }
    }

    fn check(&mut self) -> Vec<ParamIssue> {
        if self.estimators.is_empty() {
            self.estimators = LandmarkScenario::default().estimators;
        }
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::checks::*;
    use crate::params::{apply_pairs, get, sanitize, set, to_pairs};

    #[test]
    fn round_trip_through_text() {
        let mut s = LandmarkScenario::default();
        assert_accepted(
            &mut s,
            &[
                ("landmarks", "33"),
                ("fov-deg", "90"),
                ("layout", "random"),
                ("w-deg", "-20"),
                ("seed", "99"),
            ],
        );
        assert_eq!(s.landmarks, 33);
        assert!((s.fov - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let mut copy = LandmarkScenario::default();
        for (k, v) in to_pairs(&s) {
            assert_eq!(set(&mut copy, k, &v), None, "{k}={v}");
        }
        assert_eq!(to_pairs(&copy), to_pairs(&s));
        assert_eq!(copy.seed, 99);
        assert_eq!(copy.landmarks, 33);
    }

    #[test]
    fn the_circle_speeds_are_refused_while_driving_by_hand_in_any_order() {
        for pairs in [
            [("controller", "manual"), ("v", "2")],
            [("v", "2"), ("controller", "manual")],
        ] {
            let mut s = LandmarkScenario::default();
            let issues = apply_pairs(&mut s, pairs, &[]);
            assert_eq!(s.controller, ControllerKind::Manual, "{pairs:?}");
            assert!(
                matches!(issues.as_slice(), [ParamIssue::Ignored { name, .. }] if name == "v"),
                "{pairs:?}: {issues:?}"
            );
            // A hand-driven scenario has no circle speeds to report or restore.
            assert_eq!(get(&s, "v"), None);
            let mut copy = LandmarkScenario::default();
            assert!(
                apply_pairs(
                    &mut copy,
                    to_pairs(&s).iter().map(|(k, v)| (*k, v.as_str())),
                    &[]
                )
                .is_empty()
            );
            assert_eq!(to_pairs(&copy), to_pairs(&s));
            assert!(sanitize(&mut s).is_empty());
        }
        // With the circle they apply as usual.
        let mut s = LandmarkScenario::default();
        assert!(apply_pairs(&mut s, [("v", "2"), ("controller", "circle")], &[]).is_empty());
        assert_eq!(get(&s, "v").as_deref(), Some("2"));
    }

    #[test]
    fn a_preset_applies_first_keeps_the_seed_and_rejects_unknown_names() {
        let mut s = LandmarkScenario::default();
        let issues = apply_pairs(
            &mut s,
            [("range-std", "1"), ("seed", "5"), ("preset", "thesis-exp2")],
            &[],
        );
        assert!(issues.is_empty(), "{issues:?}");
        assert_eq!(s.seed, 5);
        assert!(
            (s.range_std - 1.0).abs() < 1e-12,
            "given beside the preset, it wins"
        );
        assert!((s.v_std - 0.2).abs() < 1e-12 && (s.world_size - 20.0).abs() < 1e-12);
        assert_eq!(get(&s, "preset"), None, "a preset is not a parameter value");
        assert!(to_pairs(&s).iter().all(|(k, _)| *k != "preset"));
        let before = s.clone();
        let issue = set(&mut s, "preset", "thesis-exp9");
        assert!(
            matches!(issue, Some(ParamIssue::Unreadable { .. })),
            "{issue:?}"
        );
        assert_eq!(s, before);
        let text = issue.map(|i| i.to_string()).unwrap_or_default();
        assert!(
            text.contains("thesis-exp1") && text.contains("using the current parameters"),
            "{text}"
        );
    }

    #[test]
    fn estimators_and_ukf_parameters_are_named_parameters() {
        let mut s = LandmarkScenario::default();
        assert_eq!(set(&mut s, "estimator", "ekf,ukf,ekf"), None);
        assert_eq!(s.estimators, vec![EstimatorKind::Ekf, EstimatorKind::Ukf]);
        assert_eq!(get(&s, "estimator").as_deref(), Some("ekf,ukf"));
        assert_eq!(set(&mut s, "estimator", "fej-ekf"), None);
        assert_eq!(s.estimators, vec![EstimatorKind::FejEkf]);
        assert_eq!(set(&mut s, "estimator", "ekf,ukf"), None);
        assert_round_trip(
            &mut s,
            &[("ukf-alpha", "0.5"), ("ukf-beta", "0"), ("ukf-kappa", "3")],
        );
        assert!((s.ukf.alpha - 0.5).abs() < 1e-15 && (s.ukf.kappa - 3.0).abs() < 1e-15);
        assert!(matches!(
            set(&mut s, "estimator", "ekf,pf"),
            Some(ParamIssue::Unreadable { .. })
        ));
        assert_eq!(s.estimators, vec![EstimatorKind::Ekf, EstimatorKind::Ukf]);
        // Every parameter in the table but the preset can be read back.
        for p in PARAMS.iter().filter(|p| p.name != "preset") {
            assert!(
                get(&LandmarkScenario::default(), p.name).is_some(),
                "{}",
                p.name
            );
        }
    }

    #[test]
    fn bad_values_are_reported_and_safe() {
        let mut s = LandmarkScenario::default();
        let before = s.clone();
        assert!(matches!(
            set(&mut s, "bogus", "1"),
            Some(ParamIssue::Unknown { .. })
        ));
        assert_unreadable(
            &mut s,
            &[
                ("seed", "abc"),
                ("range-std", "NaN"),
                ("range-std", "inf"),
                ("landmarks", "-3"),
                ("layout", "spiral"),
            ],
        );
        assert_eq!(s, before);
        let issue = set(&mut s, "range-std", "0");
        assert!(matches!(issue, Some(ParamIssue::Clamped { .. })));
        assert!((s.range_std - 1e-3).abs() < 1e-15);
        assert!(
            issue
                .map(|i| i.to_string())
                .unwrap_or_default()
                .contains("out of range")
        );
        assert!(matches!(
            set(&mut s, "landmarks", "100000"),
            Some(ParamIssue::Clamped { .. })
        ));
        assert_eq!(s.landmarks, 500);
        assert_eq!(set(&mut s, "landmarks", "0"), None);
    }

    #[test]
    fn fastslam_and_association_parameters_round_trip_and_refuse_bad_values() {
        let mut s = LandmarkScenario::default();
        assert_round_trip(
            &mut s,
            &[
                ("estimator", "ekf,fastslam2"),
                ("particles", "250"),
                ("fastslam-resampler", "residual"),
                ("resample-threshold", "0.75"),
                ("association", "unknown"),
                ("gate", "9.21"),
                ("new-landmark-threshold", "20"),
            ],
        );
        assert_eq!(
            s.estimators,
            vec![EstimatorKind::Ekf, EstimatorKind::FastSlam2]
        );
        assert_eq!(s.fastslam.particles, 250);
        assert_eq!(s.fastslam.resampler, Resampler::Residual);
        assert_eq!(s.association, Association::Unknown);
        let mut copy = LandmarkScenario::default();
        assert_applies(&mut copy, &to_pairs(&s));
        assert_eq!(copy, s);

        // Zero particles: a clear message and one particle; a threshold outside
        // [0, 1]: clamped into it, said so.
        let issue = set(&mut s, "particles", "0").map(|i| i.to_string());
        assert_eq!(
            issue.as_deref(),
            Some("particles = 0 is out of range; using 1")
        );
        assert_eq!(s.fastslam.particles, 1);
        let issue = set(&mut s, "resample-threshold", "1.5").map(|i| i.to_string());
        assert_eq!(
            issue.as_deref(),
            Some("resample-threshold = 1.5 is out of range; using 1")
        );
        assert_eq!(s.fastslam.resample_threshold, 1.0);
        assert!(set(&mut s, "resample-threshold", "-0.2").is_some());
        assert_eq!(s.fastslam.resample_threshold, 0.0);
        assert_unreadable(
            &mut s,
            &[("fastslam-resampler", "roulette"), ("association", "guess")],
        );
        // A stored scenario with impossible values is repaired the same way.
        let mut stored = LandmarkScenario::default();
        stored.fastslam.particles = 0;
        stored.fastslam.resample_threshold = f64::NAN;
        let issues = sanitize(&mut stored);
        assert_eq!(issues.len(), 2, "{issues:?}");
        assert_eq!(stored.fastslam.particles, 1);
        assert_eq!(stored.fastslam.resample_threshold, 0.5);
    }

    #[test]
    fn sanitize_repairs_non_finite_fields() {
        let mut s = LandmarkScenario {
            dt: f64::NAN,
            bearing_std: -1.0,
            world_size: f64::INFINITY,
            ..Default::default()
        };
        let issues = sanitize(&mut s);
        assert_eq!(issues.len(), 3, "{issues:?}");
        assert!((s.dt - 0.1).abs() < 1e-12);
        assert!((s.bearing_std - 0.01_f64.to_radians()).abs() < 1e-12);
        assert!((s.world_size - 16.0).abs() < 1e-12);
        assert!(sanitize(&mut LandmarkScenario::default()).is_empty());
    }
}
