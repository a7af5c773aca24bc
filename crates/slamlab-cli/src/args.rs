//! The kinds of flag the commands take, each built one way. A flag's id is its
//! long name (the experiments' refusals and [`crate::flags::given`] look flags up
//! by it), so a builder takes the name once; the caller adds what is particular
//! to the flag (`.default_value(..)`, `.required(true)`, a heading).
//!
//! ```text
//! args::list("particles", "comma-separated particle counts").default_value("5,30")
//! args::whole("trials", 1..=1000, "simulated drives; trial i uses seed + i")
//! args::switch("no-refine", "end with the linear refit")
//! ```

use clap::builder::{IntoResettable, StyledStr};
use clap::{Arg, ArgAction};
use std::ops::RangeBounds;
use std::path::PathBuf;

/// `--NAME VALUE`, any text.
pub fn flag(name: &'static str, help: impl IntoResettable<StyledStr>) -> Arg {
    Arg::new(name).long(name).help(help)
}

/// `--NAME`, alone: on when given.
pub fn switch(name: &'static str, help: impl IntoResettable<StyledStr>) -> Arg {
    flag(name, help).action(ArgAction::SetTrue)
}

/// `--NAME VALUE_NAME`: text shown as `value_name` in `--help` (`FILE`, `LIST`, ...).
pub fn named(
    name: &'static str,
    value_name: &'static str,
    help: impl IntoResettable<StyledStr>,
) -> Arg {
    flag(name, help).value_name(value_name)
}

/// `--NAME LIST`: comma-separated values.
pub fn list(name: &'static str, help: impl IntoResettable<StyledStr>) -> Arg {
    named(name, "LIST", help)
}

/// `--NAME FILE`: a path.
pub fn file(name: &'static str, help: impl IntoResettable<StyledStr>) -> Arg {
    named(name, "FILE", help)
}

/// `--NAME VALUE_NAME`: a path (`FILE`, `DIR`, ...), read as a `PathBuf`.
pub fn path(
    name: &'static str,
    value_name: &'static str,
    help: impl IntoResettable<StyledStr>,
) -> Arg {
    named(name, value_name, help).value_parser(clap::value_parser!(PathBuf))
}

/// `--NAME N`: a whole number in `range`. A negative one is read as its value
/// (`--trials -3`) to be refused as out of range, as `--trials=-3` is.
pub fn whole(
    name: &'static str,
    range: impl RangeBounds<u64> + Send + Sync + 'static,
    help: impl IntoResettable<StyledStr>,
) -> Arg {
    flag(name, help)
        .allow_negative_numbers(true)
        .value_parser(clap::value_parser!(u64).range(range))
}

/// `--NAME N`: a count (any `usize`); a negative one is refused as with [`whole`].
pub fn count(name: &'static str, help: impl IntoResettable<StyledStr>) -> Arg {
    flag(name, help)
        .allow_negative_numbers(true)
        .value_parser(clap::value_parser!(usize))
}

/// `--NAME X`: a real number, negative ones too in the space form
/// (`--offset -0.5`, `--offset -.5`, `--offset -1e-3`, as with `=`); the
/// command's range check refuses those out of range. A flag where the value
/// belongs is never taken for it in silence: `--offset --json` is refused as "a
/// flag, not a number" (no flag reads as one); `--offset --max-diff 1` as an
/// unexpected argument `1` (clap reports that before the value's refusal).
pub fn number(name: &'static str, help: impl IntoResettable<StyledStr>) -> Arg {
    flag(name, help)
        .allow_hyphen_values(true)
        .value_parser(real_number)
}

/// Reads a real number as `f64`'s `FromStr` does (so `--x nan` still reaches
/// the command's own refusal); says when the "value" is a flag instead, the
/// value having been left out.
fn real_number(text: &str) -> Result<f64, String> {
    text.parse::<f64>().map_err(|e| {
        if is_flag(text) {
            format!("a flag, not a number: the value is missing ({e})")
        } else {
            e.to_string()
        }
    })
}

/// The value of a flag that takes values starting with '-' (a parameter-table
/// flag: `--w-deg -10`), as given, but a flag (`--json`, `-h`): the value was
/// left out, and the flag is not to vanish into it.
pub fn value_not_flag(text: &str) -> Result<String, String> {
    if is_flag(text) {
        Err("a flag, not a value: the value is missing".to_owned())
    } else {
        Ok(text.to_owned())
    }
}

/// Whether `text` is written as a flag: `--NAME`, or `-h` and the like (not
/// `-1` nor `-inf`, which are values).
fn is_flag(text: &str) -> bool {
    let mut chars = text.chars();
    match (chars.next(), chars.next(), chars.next()) {
        (Some('-'), Some('-'), Some(_)) => true,
        (Some('-'), Some(c), None) => c.is_ascii_alphabetic(),
        _ => false,
    }
}

/// `--NAME A`: one of `choices`.
pub fn choice(
    name: &'static str,
    choices: &'static [&'static str],
    help: impl IntoResettable<StyledStr>,
) -> Arg {
    flag(name, help).value_parser(clap::builder::PossibleValuesParser::new(
        choices.iter().copied(),
    ))
}

/// `--seed N`: any `u64`, default 1; `help` says what it seeds.
pub fn seed(help: impl IntoResettable<StyledStr>) -> Arg {
    flag("seed", help)
        .allow_negative_numbers(true)
        .value_parser(clap::value_parser!(u64))
        .default_value("1")
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Command;

    fn parse(arg: Arg, args: &[&str]) -> Result<clap::ArgMatches, clap::Error> {
        Command::new("t")
            .no_binary_name(true)
            .arg(arg)
            .try_get_matches_from(args)
    }

    #[test]
    fn each_kind_reads_its_values_and_refuses_others() {
        let m = parse(whole("n", 1..=10, "n"), &["--n", "10"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.get_one::<u64>("n"), Some(&10));
        assert!(parse(whole("n", 1..=10, "n"), &["--n", "11"]).is_err());
        assert!(parse(whole("n", 1.., "n"), &["--n", "0"]).is_err());
        // A negative count is refused by its parser, with a space as with `=`.
        for args in [&["--n", "-3"][..], &["--n=-3"][..]] {
            let e = parse(whole("n", 1.., "n"), args).map(|_| ()).unwrap_err();
            assert!(e.to_string().contains("invalid value '-3'"), "{e}");
            let e = parse(count("n", "n"), args).map(|_| ()).unwrap_err();
            assert!(e.to_string().contains("invalid value '-3'"), "{e}");
        }
        // A negative number is a value in the space form too, however it is written.
        for (text, x) in [
            ("-2.5", -2.5),
            ("-.5", -0.5),
            ("-1e-3", -1e-3),
            ("-7", -7.0),
        ] {
            let m = parse(number("x", "x"), &["--x", text]).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(m.get_one::<f64>("x"), Some(&x), "{text}");
        }
        // A flag after it stays a flag, and one where the value belongs is refused.
        let two = |args: &[&str]| {
            Command::new("t")
                .no_binary_name(true)
                .arg(number("x", "x"))
                .arg(switch("json", "json"))
                .try_get_matches_from(args)
        };
        let m = two(&["--x", "-2.5", "--json"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.get_one::<f64>("x"), Some(&-2.5));
        assert!(m.get_flag("json"));
        for missing in [&["--x", "--json"][..], &["--x", "-h"][..]] {
            let e = two(missing).map(|_| ()).unwrap_err().to_string();
            assert!(e.contains("a flag, not a number"), "{missing:?}: {e}");
        }
        assert!(is_flag("--json") && is_flag("-h"));
        assert!(!is_flag("-1") && !is_flag("-inf") && !is_flag("--") && !is_flag("-"));
        assert_eq!(value_not_flag("-10"), Ok("-10".to_owned()));
        assert!(value_not_flag("--json").is_err());
        let e = parse(number("x", "x"), &["--x", "-abc"])
            .map(|_| ())
            .unwrap_err();
        assert!(e.to_string().contains("invalid float literal"), "{e}");
        let m = parse(number("x", "x"), &["--x", "2.5"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.get_one::<f64>("x"), Some(&2.5));
        let m = parse(count("k", "k"), &["--k", "7"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.get_one::<usize>("k"), Some(&7));
        assert!(parse(choice("c", &["on", "off"], "c"), &["--c", "maybe"]).is_err());
        let m = parse(switch("s", "s"), &["--s"]).unwrap_or_else(|e| panic!("{e}"));
        assert!(m.get_flag("s"));
        let m = parse(seed("seed"), &[]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.get_one::<u64>("seed"), Some(&1));
        let a = list("l", "l");
        assert_eq!(a.get_id().as_str(), "l");
        assert_eq!(a.get_long(), Some("l"));
        let names: Vec<&str> = a
            .get_value_names()
            .into_iter()
            .flatten()
            .map(|s| s.as_str())
            .collect();
        assert_eq!(names, ["LIST"]);
    }
}
