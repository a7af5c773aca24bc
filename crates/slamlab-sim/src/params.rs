//! Named scenario parameters, one declarative table per lesson, shared by the URL
//! (`?landmarks=30&seed=7`), share links, the command line (`--landmarks 30 --seed 7`),
//! `slamlab params --lesson ID` and the app's parameter panel, so a lecture figure
//! and a CLI run can be the same run.
//!
//! A lesson's scenario implements [`Scenario`]: its table lists each parameter once
//! with its name, unit, range, help and a typed getter and setter ([`Access`]).
//! Everything else (parsing text, range checks and clamping, messages, pairs for
//! links, presets first, repairing a scenario read from a file) is written once
//! here, for every lesson.
//!
//! Every value is checked: an unknown name or unreadable value is reported and
//! leaves the current value; a value outside its range is clamped to the nearest
//! allowed one and reported. Nothing here panics.

use std::fmt;

/// What kind of value a parameter takes, and its range.
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
    /// One of a list of words (or, for list parameters, several, comma separated).
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

/// How a parameter reads and writes its scenario. Getters return the value in the
/// parameter's own unit (degrees for a `-deg` parameter), `None` when the parameter
/// has no value in this scenario (a preset; the circle's speeds while driving by
/// hand). Setters receive a value already checked against the range.
pub enum Access<S> {
    /// A real number ([`ParamKind::Number`]). The setter may refuse with the reason
    /// the value has no effect.
    Number {
        /// The current value.
        get: fn(&S) -> Option<f64>,
        /// Sets the (clamped) value, or says why it has no effect.
        set: fn(&mut S, f64) -> Result<(), &'static str>,
    },
    /// A whole number ([`ParamKind::Count`]).
    Count {
        /// The current value.
        get: fn(&S) -> Option<u64>,
        /// Sets the (clamped) value.
        set: fn(&mut S, u64),
    },
    /// A word or a comma-separated list of words ([`ParamKind::Choice`]). The setter
    /// returns what it expected when it cannot read the text.
    Words {
        /// The current value as text.
        get: fn(&S) -> Option<String>,
        /// Sets the value from trimmed text, or says what was expected.
        set: fn(&mut S, &str) -> Result<(), String>,
    },
}

impl<S> Clone for Access<S> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<S> Copy for Access<S> {}
impl<S> fmt::Debug for Access<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Access::Number { .. } => "Access::Number",
            Access::Count { .. } => "Access::Count",
            Access::Words { .. } => "Access::Words",
        })
    }
}

/// One named parameter of scenario type `S`.
#[derive(Debug)]
pub struct Param<S: 'static> {
    /// The name in URLs and on the command line.
    pub name: &'static str,
    /// Unit shown beside the value.
    pub unit: &'static str,
    /// One line of help.
    pub help: &'static str,
    /// What values it takes.
    pub kind: ParamKind,
    /// How it reads and writes the scenario.
    pub access: Access<S>,
}

impl<S> Clone for Param<S> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<S> Copy for Param<S> {}

impl<S> Param<S> {
    /// A real-valued parameter in `[min, max]`.
    pub const fn number(
        name: &'static str,
        unit: &'static str,
        help: &'static str,
        (min, max): (f64, f64),
        get: fn(&S) -> Option<f64>,
        set: fn(&mut S, f64) -> Result<(), &'static str>,
    ) -> Self {
        Param {
            name,
            unit,
            help,
            kind: ParamKind::Number { min, max },
            access: Access::Number { get, set },
        }
    }

    /// A whole-number parameter in `[min, max]`.
    pub const fn count(
        name: &'static str,
        unit: &'static str,
        help: &'static str,
        (min, max): (u64, u64),
        get: fn(&S) -> Option<u64>,
        set: fn(&mut S, u64),
    ) -> Self {
        Param {
            name,
            unit,
            help,
            kind: ParamKind::Count { min, max },
            access: Access::Count { get, set },
        }
    }

    /// A parameter that takes one of `words` (or a list of them).
    pub const fn words(
        name: &'static str,
        help: &'static str,
        words: &'static [&'static str],
        get: fn(&S) -> Option<String>,
        set: fn(&mut S, &str) -> Result<(), String>,
    ) -> Self {
        Param {
            name,
            unit: "",
            help,
            kind: ParamKind::Choice(words),
            access: Access::Words { get, set },
        }
    }
}

/// A real-valued parameter read and written straight from a field (a field of a
/// field, an element of an array field) of the table's scenario type, in the
/// parameter's own unit; the `@in` form (for other macros, such as
/// `degrees_field!`) shows the field through `$shown` and keeps a value through
/// `$kept`, for a parameter given in another unit than the field's.
macro_rules! number_field {
    // The value shown is `$shown(field)`, the value kept `$kept(value)`.
    (@in $s:ty, $name:literal, $unit:literal, $help:literal, $range:expr, $shown:expr, $kept:expr, $($field:tt)+) => {
        $crate::params::Param::number(
            $name,
            $unit,
            $help,
            $range,
            |s: &$s| Some(($shown)(s.$($field)+)),
            |s: &mut $s, v: f64| {
                s.$($field)+ = ($kept)(v);
                Ok(())
            },
        )
    };
    // The table's type gives the scenario's: `number_field!("dt", "s", "time step", (0.01, 1.0), dt)`.
    ($name:literal, $unit:literal, $help:literal, $range:expr, $($field:tt)+) => {
        $crate::params::Param::number(
            $name,
            $unit,
            $help,
            $range,
            |s| Some(s.$($field)+),
            |s, v| {
                s.$($field)+ = v;
                Ok(())
            },
        )
    };
    ($s:ty, $name:literal, $unit:literal, $help:literal, $range:expr, $($field:tt)+) => {
        $crate::params::number_field!(
            @in $s, $name, $unit, $help, $range, |v: f64| v, |v: f64| v, $($field)+
        )
    };
}
pub(crate) use number_field;

/// An angle (or angular rate) parameter given in degrees and stored in radians
/// in a field (a field of a field) of scenario type `$s`.
macro_rules! degrees_field {
    ($s:ty, $name:literal, $unit:literal, $help:literal, $range:expr, $($field:tt)+) => {
        $crate::params::number_field!(
            @in $s, $name, $unit, $help, $range, f64::to_degrees, f64::to_radians, $($field)+
        )
    };
}
pub(crate) use degrees_field;

/// A whole-number parameter read and written straight from a field (or a field of
/// a field) of the table's scenario type: a `u64` or a `usize` (a seed, a count of scans
/// or particles). Counts have no unit. The range keeps every value within what
/// the field holds on every target (wasm's `usize` is 32 bits); a value it could
/// not hold would leave the field as it was.
macro_rules! count_field {
    ($name:literal, $help:literal, $range:expr, $($field:tt)+) => {
        $crate::params::Param::count(
            $name,
            "",
            $help,
            $range,
            |s| u64::try_from(s.$($field)+).ok(),
            |s, v| s.$($field)+ = v.try_into().unwrap_or(s.$($field)+),
        )
    };
}
pub(crate) use count_field;

/// The words of a switch: on or off.
pub const ON_OFF: &[&str] = &["on", "off"];

/// A switch read and written straight from a `bool` field (or a field of a
/// field) of the table's scenario type: `on` or `off` (any other word is
/// refused with the two it takes).
macro_rules! switch_field {
    ($name:literal, $help:literal, $($field:tt)+) => {
        $crate::params::Param::words(
            $name,
            $help,
            $crate::params::ON_OFF,
            |s| Some($crate::params::ON_OFF[usize::from(!s.$($field)+)].to_owned()),
            |s, v| $crate::params::choose($crate::params::ON_OFF, v).map(|i| s.$($field)+ = i == 0),
        )
    };
}
pub(crate) use switch_field;

/// A choice read and written straight from a field (or a field of a field) of
/// the table's scenario type: `words[i]` names `values[i]` (an enum's words
/// and its values, in the same order; two lists of different lengths do not
/// compile).
macro_rules! choice_field {
    ($name:literal, $help:literal, $words:expr, $values:expr, $($field:tt)+) => {{
        const _: () = assert!(
            $words.len() == $values.len(),
            "a choice parameter needs one word for each value"
        );
        $crate::params::Param::words(
            $name,
            $help,
            $words,
            |s| {
                let at = $values.iter().position(|v| *v == s.$($field)+)?;
                $words.get(at).map(|w| (*w).to_owned())
            },
            |s, v| $crate::params::choose($words, v).map(|i| s.$($field)+ = $values[i]),
        )
    }};
}
pub(crate) use choice_field;

/// A named scenario: what a source shows ("thesis Experiment 2") or a lesson's key
/// comparison. A preset sets every parameter but the seed; parameters given beside
/// it apply on top, whatever their order.
#[derive(Debug)]
pub struct Preset<S: 'static> {
    /// The name in URLs and on the command line (`preset=...`).
    pub id: &'static str,
    /// The menu entry.
    pub title: &'static str,
    /// What it shows, in one sentence.
    pub summary: &'static str,
    /// The scenario with a given seed.
    pub build: fn(u64) -> S,
}

/// A lesson's scenario: plain data with one declarative parameter table.
pub trait Scenario: Clone + Default + fmt::Debug + 'static {
    /// The lesson id (`lesson=` in URLs, `slamlab run ID`).
    const LESSON: &'static str;

    /// Every parameter, in the order panels and `slamlab params` list them.
    /// A `preset` parameter, if any, comes first.
    fn params() -> &'static [Param<Self>];

    /// The presets, in menu order.
    fn presets() -> &'static [Preset<Self>] {
        &[]
    }

    /// The seed of every random stream.
    fn seed(&self) -> u64;

    /// When pairs apply: lower first. A preset goes first so that the parameters
    /// beside it apply on top; a lesson can put others early (who drives, before
    /// the circle's speeds).
    fn apply_rank(name: &str) -> u8 {
        u8::from(name != "preset") * 2
    }

    /// Checks that need more than one parameter (say, a list that must not be
    /// empty), after [`sanitize`] has checked each one. Repairs and reports.
    fn check(&mut self) -> Vec<ParamIssue> {
        Vec::new()
    }

    /// Looks a parameter up by name.
    fn param(name: &str) -> Option<&'static Param<Self>> {
        Self::params().iter().find(|p| p.name == name)
    }

    /// Looks a preset up by id.
    fn preset(id: &str) -> Option<&'static Preset<Self>> {
        Self::presets().iter().find(|p| p.id == id)
    }
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

/// A number as the URL and the CLI write it: at most six decimals, no trailing zeros.
pub fn format_number(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-" {
        "0".to_owned()
    } else {
        s.to_owned()
    }
}

/// Looks a parameter of `S` up by name.
pub fn spec<S: Scenario>(name: &str) -> Option<&'static Param<S>> {
    S::param(name)
}

/// The current value of a parameter, as text in its URL/CLI unit. None for an
/// unknown name, a preset (not a value the scenario holds), and a parameter that
/// has no value in this scenario.
pub fn get<S: Scenario>(scenario: &S, name: &str) -> Option<String> {
    let param = S::param(name)?;
    match param.access {
        Access::Number { get, .. } => get(scenario).map(format_number),
        Access::Count { get, .. } => get(scenario).map(|v| v.to_string()),
        Access::Words { get, .. } => get(scenario),
    }
}

/// Every parameter and its current value, in table order.
pub fn to_pairs<S: Scenario>(scenario: &S) -> Vec<(&'static str, String)> {
    S::params()
        .iter()
        .filter_map(|p| get(scenario, p.name).map(|v| (p.name, v)))
        .collect()
}

/// Sets one parameter from text. Returns the issue, if any; on an issue other than
/// clamping, the scenario is unchanged.
pub fn set<S: Scenario>(scenario: &mut S, name: &str, value: &str) -> Option<ParamIssue> {
    let Some(param) = S::param(name) else {
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
    match (param.kind, param.access) {
        (ParamKind::Number { min, max }, Access::Number { set, .. }) => {
            let parsed = value.parse::<f64>().ok().filter(|v| v.is_finite());
            let Some(v) = parsed else {
                return unreadable(format!(
                    "a finite number between {} and {} {}",
                    format_number(min),
                    format_number(max),
                    param.unit
                ));
            };
            let used = v.clamp(min, max);
            if let Err(reason) = set(scenario, used) {
                return Some(ParamIssue::Ignored {
                    name: name.to_owned(),
                    reason,
                });
            }
            (!(min..=max).contains(&v)).then(|| ParamIssue::Clamped {
                name: name.to_owned(),
                value: value.to_owned(),
                used: format!("{} {}", format_number(used), param.unit)
                    .trim_end()
                    .to_owned(),
            })
        }
        (ParamKind::Count { min, max }, Access::Count { set, .. }) => {
            let Ok(v) = value.parse::<u64>() else {
                let range = param.kind.range_text(", ");
                return unreadable(format!("a whole number ({range})"));
            };
            let used = v.clamp(min, max);
            set(scenario, used);
            (used != v).then(|| ParamIssue::Clamped {
                name: name.to_owned(),
                value: value.to_owned(),
                used: used.to_string(),
            })
        }
        (_, Access::Words { set, .. }) => match set(scenario, value) {
            Ok(()) => None,
            Err(expected) => unreadable(expected),
        },
        // A table entry whose kind and access disagree: a slip in the table, which
        // `every_table_is_consistent`-style tests catch; say so rather than guess.
        _ => unreadable(format!(
            "settable: the parameter table's entry for {name} is inconsistent"
        )),
    }
}

/// The setter of a single-word parameter: `words` lists the accepted words, and
/// `apply` sets the one given (its index in `words`).
pub fn choose(words: &[&str], value: &str) -> Result<usize, String> {
    words
        .iter()
        .position(|w| *w == value)
        .ok_or_else(|| format!("one of {}", words.join(", ")))
}

/// Parses a comma-separated list of `words` (duplicates dropped, order kept); an
/// empty list or an unknown word is an error that says what was expected.
pub fn choose_list(words: &[&'static str], value: &str) -> Result<Vec<&'static str>, String> {
    let mut list: Vec<&'static str> = Vec::new();
    for item in value.split(',') {
        let item = item.trim();
        let Some(&word) = words.iter().find(|w| **w == item) else {
            return Err(format!("a comma-separated list of {}", words.join(", ")));
        };
        if !list.contains(&word) {
            list.push(word);
        }
    }
    if list.is_empty() {
        return Err(format!("a comma-separated list of {}", words.join(", ")));
    }
    Ok(list)
}

/// The text of a list parameter: the names of its items, comma separated (what
/// [`choose_items`] reads back).
pub fn list_text<T>(items: &[T], name: impl Fn(&T) -> &'static str) -> String {
    items.iter().map(name).collect::<Vec<_>>().join(",")
}

/// Parses a comma-separated list of `words` ([`choose_list`]) into the items
/// `from_name` makes of them: the setter of a list parameter.
pub fn choose_items<T>(
    words: &[&'static str],
    value: &str,
    from_name: impl Fn(&str) -> Option<T>,
) -> Result<Vec<T>, String> {
    Ok(choose_list(words, value)?
        .into_iter()
        .filter_map(from_name)
        .collect())
}

/// Replaces `scenario` with preset `id` built with the scenario's seed: the setter
/// of every lesson's `preset` parameter.
pub fn apply_preset<S: Scenario>(scenario: &mut S, id: &str) -> Result<(), String> {
    match S::preset(id) {
        Some(preset) => {
            *scenario = (preset.build)(scenario.seed());
            Ok(())
        }
        None => Err(format!(
            "one of {}",
            S::presets()
                .iter()
                .map(|p| p.id)
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

/// Applies `key=value` pairs, a `preset` first and then the others in order (see
/// [`Scenario::apply_rank`]); pairs whose key is in `skip` belong to someone else
/// (the app's `lesson` and `embed`) and are passed over.
pub fn apply_pairs<'a, S: Scenario>(
    scenario: &mut S,
    pairs: impl IntoIterator<Item = (&'a str, &'a str)>,
    skip: &[&str],
) -> Vec<ParamIssue> {
    let mut pairs: Vec<(&str, &str)> = pairs
        .into_iter()
        .filter(|(k, _)| !skip.contains(k))
        .collect();
    pairs.sort_by_key(|(k, _)| S::apply_rank(k));
    pairs
        .into_iter()
        .filter_map(|(k, v)| set(scenario, k, v))
        .collect()
}

/// Checks a whole scenario (for one read from a file or built in code) and clamps
/// whatever is out of range, with the same messages as [`set`]; a value that cannot
/// be used at all (NaN) falls back to the default.
pub fn sanitize<S: Scenario>(scenario: &mut S) -> Vec<ParamIssue> {
    let defaults = S::default();
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
    issues.extend(scenario.check());
    issues
}

/// [`sanitize`], its issues as the notices a lesson shows when it opens.
pub fn sanitize_notices<S: Scenario>(scenario: &mut S) -> Vec<String> {
    sanitize(scenario).iter().map(ToString::to_string).collect()
}

/// The parameters of `scenario` that differ from `reference`, in table order.
pub fn changed_pairs<S: Scenario>(scenario: &S, reference: &S) -> Vec<(String, String)> {
    let defaults = to_pairs(reference);
    to_pairs(scenario)
        .into_iter()
        .filter(|(name, value)| !defaults.iter().any(|(n, v)| n == name && v == value))
        .map(|(name, value)| (name.to_owned(), value))
        .collect()
}

/// One row per parameter for `slamlab params --lesson ID` and help texts:
/// `(name, unit, range, default, help)`.
pub fn describe<S: Scenario>() -> Vec<[String; 5]> {
    let defaults = S::default();
    S::params()
        .iter()
        .map(|p| {
            [
                p.name.to_owned(),
                p.unit.to_owned(),
                p.kind.range_text(" | "),
                get(&defaults, p.name).unwrap_or_else(|| "none".to_owned()),
                p.help.to_owned(),
            ]
        })
        .collect()
}

/// Assertions the parameter tables' tests share.
#[cfg(test)]
pub(crate) mod checks {
    use super::{ParamIssue, Scenario, apply_pairs, get, set};

    /// Sets each `(name, text)` and asserts it is taken without an issue.
    pub(crate) fn assert_accepted<S: Scenario>(scenario: &mut S, pairs: &[(&str, &str)]) {
        for &(k, v) in pairs {
            assert_eq!(set(scenario, k, v), None, "{k}={v}");
        }
    }

    /// [`assert_accepted`], and each reads back as the same text.
    pub(crate) fn assert_round_trip<S: Scenario>(scenario: &mut S, pairs: &[(&str, &str)]) {
        for &(k, v) in pairs {
            assert_eq!(set(scenario, k, v), None, "{k}={v}");
            assert_eq!(get(scenario, k).as_deref(), Some(v), "{k}");
        }
    }

    /// Asserts each `(name, text)` is refused as unreadable.
    pub(crate) fn assert_unreadable<S: Scenario>(scenario: &mut S, pairs: &[(&str, &str)]) {
        for &(k, v) in pairs {
            let issue = set(scenario, k, v);
            assert!(
                matches!(issue, Some(ParamIssue::Unreadable { .. })),
                "{k}={v}: {issue:?}"
            );
        }
    }

    /// Applies pairs as [`super::to_pairs`] gives them and asserts no issue.
    pub(crate) fn assert_applies<S: Scenario>(scenario: &mut S, pairs: &[(&str, String)]) {
        let issues = apply_pairs(scenario, pairs.iter().map(|(k, v)| (*k, v.as_str())), &[]);
        assert!(issues.is_empty(), "{issues:?}");
    }
}

#[cfg(test)]
mod tests {
    use super::checks::*;
    use super::*;

    /// A tiny scenario to test the machinery by itself.
    #[derive(Clone, Debug, PartialEq)]
    struct Toy {
        seed: u64,
        speed: f64,
        angle: f64,
        colour: usize,
        tools: Vec<&'static str>,
        locked: bool,
    }

    impl Default for Toy {
        fn default() -> Self {
            Toy {
                seed: 0,
                speed: 0.0,
                angle: 0.0,
                colour: 0,
                tools: vec!["saw"],
                locked: false,
            }
        }
    }

    const COLOURS: &[&str] = &["red", "green"];
    const TOOLS: &[&str] = &["saw", "drill"];

    static TOY_PARAMS: &[Param<Toy>] = &[
        Param::words(
            "preset",
            "a named toy",
            &["fast"],
            |_| None,
            apply_preset::<Toy>,
        ),
        Param::count(
            "seed",
            "",
            "seed",
            (0, u64::MAX),
            |t| Some(t.seed),
            |t, v| t.seed = v,
        ),
        Param::number(
            "speed",
            "m/s",
            "how fast",
            (0.0, 2.0),
            |t| (!t.locked).then_some(t.speed),
            |t, v| {
                if t.locked {
                    return Err("the toy is locked");
                }
                t.speed = v;
                Ok(())
            },
        ),
        Param::number(
            "angle-deg",
            "deg",
            "heading",
            (-180.0, 180.0),
            |t| Some(t.angle.to_degrees()),
            |t, v| {
                t.angle = v.to_radians();
                Ok(())
            },
        ),
        Param::words(
            "colour",
            "paint",
            COLOURS,
            |t| COLOURS.get(t.colour).map(|c| (*c).to_owned()),
            |t, v| choose(COLOURS, v).map(|i| t.colour = i),
        ),
        Param::words(
            "tools",
            "tool list",
            TOOLS,
            |t| Some(t.tools.join(",")),
            |t, v| choose_list(TOOLS, v).map(|l| t.tools = l),
        ),
    ];

    static TOY_PRESETS: &[Preset<Toy>] = &[Preset {
        id: "fast",
        title: "Fast",
        summary: "full speed",
        build: |seed| Toy {
            seed,
            speed: 2.0,
            ..Toy::default()
        },
    }];

    impl Scenario for Toy {
        const LESSON: &'static str = "toy";
        fn params() -> &'static [Param<Self>] {
            TOY_PARAMS
        }
        fn presets() -> &'static [Preset<Self>] {
            TOY_PRESETS
        }
        fn seed(&self) -> u64 {
            self.seed
        }
        fn check(&mut self) -> Vec<ParamIssue> {
            if self.colour >= COLOURS.len() {
                self.colour = 0;
                return vec![ParamIssue::Unknown {
                    name: "colour".to_owned(),
                }];
            }
            Vec::new()
        }
    }

    #[test]
    fn text_round_trips_in_the_parameters_units() {
        let mut t = Toy::default();
        assert_accepted(
            &mut t,
            &[
                ("speed", "1.25"),
                ("angle-deg", "90"),
                ("colour", "green"),
                ("tools", "drill,saw,drill"),
                ("seed", "7"),
            ],
        );
        assert!((t.angle - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert_eq!(t.tools, vec!["drill", "saw"]);
        let pairs = to_pairs(&t);
        assert_eq!(
            pairs,
            vec![
                ("seed", "7".to_owned()),
                ("speed", "1.25".to_owned()),
                ("angle-deg", "90".to_owned()),
                ("colour", "green".to_owned()),
                ("tools", "drill,saw".to_owned()),
            ]
        );
        let mut copy = Toy::default();
        assert_applies(&mut copy, &pairs);
        assert_eq!(copy, t);
        assert_eq!(changed_pairs(&t, &copy), Vec::<(String, String)>::new());
        assert_eq!(changed_pairs(&t, &Toy::default()).len(), 5);
        assert_eq!(changed_pairs(&Toy::default(), &Toy::default()).len(), 0);
    }

    #[test]
    fn bad_values_are_reported_and_leave_the_scenario() {
        let mut t = Toy::default();
        let before = t.clone();
        assert!(matches!(
            set(&mut t, "nope", "1"),
            Some(ParamIssue::Unknown { .. })
        ));
        assert_unreadable(
            &mut t,
            &[
                ("speed", "NaN"),
                ("speed", "inf"),
                ("speed", "fast"),
                ("seed", "-1"),
                ("colour", "blue"),
                ("tools", ""),
                ("tools", "saw,hammer"),
                ("preset", "slow"),
            ],
        );
        assert_eq!(t, before);
        let text = set(&mut t, "colour", "blue")
            .map(|i| i.to_string())
            .unwrap_or_default();
        assert_eq!(text, "colour = 'blue' is not one of red, green; using red");
        let issue = set(&mut t, "speed", "9");
        assert_eq!(
            issue.map(|i| i.to_string()).as_deref(),
            Some("speed = 9 is out of range; using 2 m/s")
        );
        assert_eq!(t.speed, 2.0);
        t.locked = true;
        assert!(matches!(
            set(&mut t, "speed", "1"),
            Some(ParamIssue::Ignored { .. })
        ));
        assert_eq!(get(&t, "speed"), None);
    }

    #[test]
    fn a_preset_applies_first_and_keeps_the_seed() {
        let mut t = Toy::default();
        let issues = apply_pairs(
            &mut t,
            [
                ("speed", "0.5"),
                ("seed", "3"),
                ("preset", "fast"),
                ("lesson", "x"),
            ],
            &["lesson"],
        );
        assert!(issues.is_empty(), "{issues:?}");
        assert_eq!((t.seed, t.speed), (3, 0.5));
        assert_eq!(get(&t, "preset"), None);
    }

    #[test]
    fn sanitize_clamps_and_repairs() {
        let mut t = Toy {
            speed: 7.0,
            angle: f64::NAN,
            colour: 5,
            ..Toy::default()
        };
        let issues = sanitize(&mut t);
        assert_eq!(issues.len(), 3, "{issues:?}");
        assert_eq!(t.speed, 2.0);
        assert_eq!(t.angle, 0.0);
        assert_eq!(t.colour, 0, "the lesson's own check ran");
        assert!(sanitize(&mut t).is_empty());
        let rows = describe::<Toy>();
        assert_eq!(
            rows[2],
            ["speed", "m/s", "0 .. 2", "0", "how fast"].map(str::to_owned)
        );
        assert_eq!(rows[0][3], "none");
    }
}
