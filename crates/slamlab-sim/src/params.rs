//! Named scenario parameters, shared by the URL (`?landmarks=30&seed=7`) and the
//! command line (`--landmarks 30 --seed 7`), so a lecture figure and a CLI run can
//! be the same run.
//!
//! Every value is checked: an unknown name or unreadable value is reported and
//! leaves the current value; a value outside its range is clamped to the nearest
//! allowed one and reported. Nothing here panics.

use crate::scenario::{ControllerKind, EstimatorKind, LandmarkScenario};
use crate::world::LandmarkLayout;
use slamlab_core::MotionModel;
use std::fmt;

/// What kind of value a parameter takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamKind {
    /// A real number in `[min, max]`.
    Number {
        /// Smallest allowed value.
        min: f64,
        /// Largest allowed value.
        max: f64,
    },
    /// A whole number in `[min, max]`.
    Count {
        /// Smallest allowed value.
        min: u64,
        /// Largest allowed value.
        max: u64,
    },
    /// One of a list of words.
    Choice(&'static [&'static str]),
}

impl ParamKind {
    /// The allowed values as a reader wants them: "0 .. 500", "0 or more" (for a
    /// seed, whose largest value nobody types), or the words joined by `separator`.
    pub fn range_text(&self, separator: &str) -> String {
        match *self {
            ParamKind::Number { min, max } => format!("{min} .. {max}"),
            ParamKind::Count { min, max: u64::MAX } => format!("{min} or more"),
            ParamKind::Count { min, max } => format!("{min} .. {max}"),
            ParamKind::Choice(words) => words.join(separator),
        }
    }
}

/// One named parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    /// The name in URLs and on the command line.
    pub name: &'static str,
    /// Unit shown beside the value.
    pub unit: &'static str,
    /// One line of help.
    pub help: &'static str,
    /// What values it takes.
    pub kind: ParamKind,
}

const fn number(
    name: &'static str,
    unit: &'static str,
    help: &'static str,
    min: f64,
    max: f64,
) -> ParamSpec {
    ParamSpec {
        name,
        unit,
        help,
        kind: ParamKind::Number { min, max },
    }
}

/// Every landmark-scenario parameter. `preset` comes first: it sets all the others
/// (but the seed), and whatever else is given applies on top of it.
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "preset",
        unit: "",
        help: "start from a named scenario (see the README); other parameters apply on top",
        kind: ParamKind::Choice(crate::presets::PRESET_IDS),
    },
    ParamSpec {
        name: "seed",
        unit: "",
        help: "seed of every random stream",
        kind: ParamKind::Count {
            min: 0,
            max: u64::MAX,
        },
    },
    number("dt", "s", "simulation time step", 0.001, 1.0),
    number("world-size", "m", "side of the square world", 2.0, 200.0),
    ParamSpec {
        name: "landmarks",
        unit: "",
        help: "number of landmarks",
        kind: ParamKind::Count { min: 0, max: 500 },
    },
    ParamSpec {
        name: "layout",
        unit: "",
        help: "landmark layout",
        kind: ParamKind::Choice(&["teaching", "random"]),
    },
    ParamSpec {
        name: "motion",
        unit: "",
        help: "motion model of the estimators",
        kind: ParamKind::Choice(&["exact-arc", "euler"]),
    },
    number(
        "v-std",
        "m/s",
        "std of the executed forward speed (thesis q[0])",
        1e-4,
        2.0,
    ),
    number(
        "w-std-deg",
        "deg/s",
        "std of the executed turn rate (thesis q[1] = 10)",
        0.01,
        90.0,
    ),
    number(
        "range-std",
        "m",
        "std of range measurements (thesis v[0])",
        1e-3,
        10.0,
    ),
    number(
        "bearing-std-deg",
        "deg",
        "std of bearing measurements (thesis v[1] = 10)",
        0.01,
        90.0,
    ),
    number("fov-deg", "deg", "sensor field of view", 1.0, 360.0),
    number("max-range", "m", "sensor maximum range", 0.1, 100.0),
    number("wheel-base", "m", "distance between the wheels", 0.05, 5.0),
    ParamSpec {
        name: "controller",
        unit: "",
        help: "who drives: the scripted circle or the user",
        kind: ParamKind::Choice(&["circle", "manual"]),
    },
    number(
        "v",
        "m/s",
        "forward speed of the scripted circle (thesis u_v = 1)",
        -5.0,
        5.0,
    ),
    number(
        "w-deg",
        "deg/s",
        "turn rate of the scripted circle (thesis u_w = 18)",
        -180.0,
        180.0,
    ),
    ParamSpec {
        name: "estimator",
        unit: "",
        help: "estimators to run, comma separated",
        kind: ParamKind::Choice(&["ekf", "ukf", "fej-ekf", "ideal-ekf"]),
    },
    number("ukf-alpha", "", "UKF sigma-point spread alpha", 1e-3, 2.0),
    number(
        "ukf-beta",
        "",
        "UKF prior-knowledge beta (2 for Gaussians)",
        -10.0,
        10.0,
    ),
    number(
        "ukf-kappa",
        "",
        "UKF secondary scaling kappa (alpha^2 (k + kappa) must exceed 0)",
        -10.0,
        10.0,
    ),
];

/// Looks a parameter up by name.
pub fn spec(name: &str) -> Option<&'static ParamSpec> {
    PARAMS.iter().find(|p| p.name == name)
}

/// A problem with one parameter, worded for the person who typed it.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamIssue {
    /// No parameter has this name.
    Unknown {
        /// The name given.
        name: String,
    },
    /// The value could not be read; the current value stays.
    Unreadable {
        /// The parameter.
        name: String,
        /// The value given.
        value: String,
        /// What was expected.
        expected: String,
        /// The value kept.
        kept: String,
    },
    /// The value has no effect in this scenario (the circle's speeds while the
    /// robot is driven by hand); nothing changed.
    Ignored {
        /// The parameter.
        name: String,
        /// Why it has no effect.
        reason: &'static str,
    },
    /// The value was outside its range and was clamped.
    Clamped {
        /// The parameter.
        name: String,
        /// The value given.
        value: String,
        /// The value used.
        used: String,
    },
}

impl fmt::Display for ParamIssue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamIssue::Unknown { name } => {
                write!(f, "unknown parameter '{name}' was ignored")
            }
            ParamIssue::Unreadable {
                name,
                value,
                expected,
                kept,
            } => {
                write!(f, "{name} = '{value}' is not {expected}; using {kept}")
            }
            ParamIssue::Clamped { name, value, used } => {
                write!(f, "{name} = {value} is out of range; using {used}")
            }
            ParamIssue::Ignored { name, reason } => write!(f, "{name} was ignored: {reason}"),
        }
    }
}

fn format_number(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-" {
        "0".to_owned()
    } else {
        s.to_owned()
    }
}

/// The current value of a parameter, as text in its URL/CLI unit. None for a
/// preset (not a value the scenario holds) and for the circle's speeds while the
/// robot is driven by hand.
pub fn get(scenario: &LandmarkScenario, name: &str) -> Option<String> {
    let circle = match scenario.controller {
        ControllerKind::Circle { v, w } => Some((v, w)),
        ControllerKind::Manual => None,
    };
    Some(match name {
        "seed" => scenario.seed.to_string(),
        "dt" => format_number(scenario.dt),
        "world-size" => format_number(scenario.world_size),
        "landmarks" => scenario.landmarks.to_string(),
        "layout" => scenario.layout.name().to_owned(),
        "motion" => match scenario.motion {
            MotionModel::ExactArc => "exact-arc".to_owned(),
            MotionModel::Euler => "euler".to_owned(),
        },
        "v-std" => format_number(scenario.v_std),
        "w-std-deg" => format_number(scenario.w_std.to_degrees()),
        "range-std" => format_number(scenario.range_std),
        "bearing-std-deg" => format_number(scenario.bearing_std.to_degrees()),
        "fov-deg" => format_number(scenario.fov.to_degrees()),
        "max-range" => format_number(scenario.max_range),
        "wheel-base" => format_number(scenario.wheel_base),
        "controller" => match scenario.controller {
            ControllerKind::Circle { .. } => "circle".to_owned(),
            ControllerKind::Manual => "manual".to_owned(),
        },
        "v" => format_number(circle?.0),
        "w-deg" => format_number(circle?.1.to_degrees()),
        "estimator" => scenario
            .estimators
            .iter()
            .map(|e| e.name())
            .collect::<Vec<_>>()
            .join(","),
        "ukf-alpha" => format_number(scenario.ukf.alpha),
        "ukf-beta" => format_number(scenario.ukf.beta),
        "ukf-kappa" => format_number(scenario.ukf.kappa),
        _ => return None,
    })
}

/// Every parameter and its current value, in table order.
pub fn to_pairs(scenario: &LandmarkScenario) -> Vec<(&'static str, String)> {
    PARAMS
        .iter()
        .filter_map(|p| get(scenario, p.name).map(|v| (p.name, v)))
        .collect()
}

/// Sets one parameter from text. Returns the issue, if any; on an issue other than
/// clamping, the scenario is unchanged.
pub fn set(scenario: &mut LandmarkScenario, name: &str, value: &str) -> Option<ParamIssue> {
    let Some(spec) = spec(name) else {
        return Some(ParamIssue::Unknown {
            name: name.to_owned(),
        });
    };
    let value = value.trim();
    // A preset is not a value the scenario holds: a bad one keeps the parameters.
    let kept = get(scenario, name).unwrap_or_else(|| "the current parameters".to_owned());
    let unreadable = |expected: String| {
        Some(ParamIssue::Unreadable {
            name: name.to_owned(),
            value: value.to_owned(),
            expected,
            kept: kept.clone(),
        })
    };
    match spec.kind {
        ParamKind::Number { min, max } => {
            let parsed = value.parse::<f64>().ok().filter(|v| v.is_finite());
            let Some(v) = parsed else {
                return unreadable(format!(
                    "a finite number between {} and {} {}",
                    format_number(min),
                    format_number(max),
                    spec.unit
                ));
            };
            if matches!(name, "v" | "w-deg")
                && matches!(scenario.controller, ControllerKind::Manual)
            {
                return Some(ParamIssue::Ignored {
                    name: name.to_owned(),
                    reason: "the scripted circle's speeds do nothing while the robot is \
                             driven by hand (controller=manual)",
                });
            }
            let used = v.clamp(min, max);
            apply_number(scenario, name, used);
            (!(min..=max).contains(&v)).then(|| ParamIssue::Clamped {
                name: name.to_owned(),
                value: value.to_owned(),
                used: format!("{} {}", format_number(used), spec.unit)
                    .trim_end()
                    .to_owned(),
            })
        }
        ParamKind::Count { min, max } => {
            let Ok(v) = value.parse::<u64>() else {
                let range = spec.kind.range_text(", ");
                return unreadable(format!("a whole number ({range})"));
            };
            let used = v.clamp(min, max);
            match name {
                "seed" => scenario.seed = used,
                _ => scenario.landmarks = usize::try_from(used).unwrap_or(usize::MAX),
            }
            (used != v).then(|| ParamIssue::Clamped {
                name: name.to_owned(),
                value: value.to_owned(),
                used: used.to_string(),
            })
        }
        ParamKind::Choice(choices) => {
            let expected = format!("one of {}", choices.join(", "));
            match name {
                "preset" => match crate::presets::scenario(value, scenario.seed) {
                    Some(preset) => *scenario = preset,
                    None => return unreadable(expected),
                },
                "layout" => match value {
                    "teaching" => scenario.layout = LandmarkLayout::Teaching,
                    "random" => scenario.layout = LandmarkLayout::Random,
                    _ => return unreadable(expected),
                },
                "motion" => match value {
                    "exact-arc" => scenario.motion = MotionModel::ExactArc,
                    "euler" => scenario.motion = MotionModel::Euler,
                    _ => return unreadable(expected),
                },
                "controller" => match value {
                    "circle" => {
                        if matches!(scenario.controller, ControllerKind::Manual) {
                            scenario.controller = ControllerKind::default();
                        }
                    }
                    "manual" => scenario.controller = ControllerKind::Manual,
                    _ => return unreadable(expected),
                },
                _ => {
                    let parsed: Option<Vec<EstimatorKind>> = value
                        .split(',')
                        .map(|s| EstimatorKind::from_name(s.trim()))
                        .collect();
                    match parsed {
                        Some(mut list) if !list.is_empty() => {
                            let mut seen = Vec::new();
                            list.retain(|e| {
                                if seen.contains(e) {
                                    false
                                } else {
                                    seen.push(*e);
                                    true
                                }
                            });
                            scenario.estimators = list;
                        }
                        _ => {
                            return unreadable(format!(
                                "a comma-separated list of {}",
                                choices.join(", ")
                            ));
                        }
                    }
                }
            }
            None
        }
    }
}

fn apply_number(scenario: &mut LandmarkScenario, name: &str, v: f64) {
    match name {
        "dt" => scenario.dt = v,
        "world-size" => scenario.world_size = v,
        "v-std" => scenario.v_std = v,
        "w-std-deg" => scenario.w_std = v.to_radians(),
        "range-std" => scenario.range_std = v,
        "bearing-std-deg" => scenario.bearing_std = v.to_radians(),
        "fov-deg" => scenario.fov = v.to_radians(),
        "max-range" => scenario.max_range = v,
        "wheel-base" => scenario.wheel_base = v,
        "ukf-alpha" => scenario.ukf.alpha = v,
        "ukf-beta" => scenario.ukf.beta = v,
        "ukf-kappa" => scenario.ukf.kappa = v,
        "v" | "w-deg" => {
            // Under manual driving `set` refuses these before they get here.
            let ControllerKind::Circle {
                v: mut cv,
                w: mut cw,
            } = scenario.controller
            else {
                return;
            };
            if name == "v" {
                cv = v;
            } else {
                cw = v.to_radians();
            }
            scenario.controller = ControllerKind::Circle { v: cv, w: cw };
        }
        _ => {}
    }
}

/// Applies `key=value` pairs, a `preset` first and then the others in order; pairs
/// whose key is in `skip` belong to someone else (the app's `lesson` and `embed`)
/// and are passed over.
pub fn apply_pairs<'a>(
    scenario: &mut LandmarkScenario,
    pairs: impl IntoIterator<Item = (&'a str, &'a str)>,
    skip: &[&str],
) -> Vec<ParamIssue> {
    let mut pairs: Vec<(&str, &str)> = pairs
        .into_iter()
        .filter(|(k, _)| !skip.contains(k))
        .collect();
    // A preset first, so that the parameters beside it apply on top, and who drives
    // next, so that the circle's speeds meet the same controller in any order.
    pairs.sort_by_key(|(k, _)| match *k {
        "preset" => 0,
        "controller" => 1,
        _ => 2,
    });
    pairs
        .into_iter()
        .filter_map(|(k, v)| set(scenario, k, v))
        .collect()
}

/// Checks a whole scenario (for one read from a file or built in code) and clamps
/// whatever is out of range, with the same messages as [`set`].
pub fn sanitize(scenario: &mut LandmarkScenario) -> Vec<ParamIssue> {
    let defaults = LandmarkScenario::default();
    let mut issues = Vec::new();
    for (name, value) in to_pairs(scenario) {
        let mut probe = scenario.clone();
        if let Some(issue) = set(&mut probe, name, &value) {
            match issue {
                ParamIssue::Clamped { .. } => *scenario = probe,
                _ => {
                    // NaN or infinite: fall back to the default.
                    if let Some(default) = get(&defaults, name) {
                        set(scenario, name, &default);
                    }
                }
            }
            issues.push(issue);
        }
    }
    if scenario.estimators.is_empty() {
        scenario.estimators = defaults.estimators;
    }
    issues
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::EstimatorKind;

    #[test]
    fn round_trip_through_text() {
        let mut s = LandmarkScenario::default();
        for (k, v) in [
            ("landmarks", "33"),
            ("fov-deg", "90"),
            ("layout", "random"),
            ("w-deg", "-20"),
            ("seed", "99"),
        ] {
            assert_eq!(set(&mut s, k, v), None, "{k}");
        }
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
        for (k, v) in [("ukf-alpha", "0.5"), ("ukf-beta", "0"), ("ukf-kappa", "3")] {
            assert_eq!(set(&mut s, k, v), None, "{k}");
            assert_eq!(get(&s, k).as_deref(), Some(v), "{k}");
        }
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
        assert!(matches!(
            set(&mut s, "seed", "abc"),
            Some(ParamIssue::Unreadable { .. })
        ));
        assert!(matches!(
            set(&mut s, "range-std", "NaN"),
            Some(ParamIssue::Unreadable { .. })
        ));
        assert!(matches!(
            set(&mut s, "range-std", "inf"),
            Some(ParamIssue::Unreadable { .. })
        ));
        assert!(matches!(
            set(&mut s, "landmarks", "-3"),
            Some(ParamIssue::Unreadable { .. })
        ));
        assert!(matches!(
            set(&mut s, "layout", "spiral"),
            Some(ParamIssue::Unreadable { .. })
        ));
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
