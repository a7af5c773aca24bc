//! Flags from a lesson's parameter table (`slamlab_sim::params`), and the one way
//! every command reads them: refusing a value it cannot read, warning on stderr
//! about one it had to clamp.

use anyhow::{Result, bail};
use clap::{Arg, ArgMatches};
use slamlab_sim::params::{self, ParamIssue, Scenario};

/// The parameters of `S`'s table as flags of the same names (the URL's), those
/// for which `keep(name)` holds; each flag's help gives the unit, range and default.
pub fn table_args<S: Scenario>(keep: impl Fn(&str) -> bool) -> Vec<Arg> {
    let defaults = S::default();
    S::params()
        .iter()
        .filter(|p| keep(p.name))
        .map(|p| {
            let default = params::get(&defaults, p.name).unwrap_or_else(|| "none".to_owned());
            let unit = if p.unit.is_empty() {
                String::new()
            } else {
                format!(", {}", p.unit)
            };
            Arg::new(p.name)
                .long(p.name)
                .value_name("VALUE")
                .allow_hyphen_values(true)
                .value_parser(crate::args::value_not_flag)
                .help(format!(
                    "{}{unit} [{}]; default {default}",
                    p.help,
                    p.kind.range_text(", ")
                ))
        })
        .collect()
}

/// `S`'s default scenario with the table's flags that were given applied (a
/// preset first, then the rest; see `params::apply_pairs`), but those in `skip`
/// (the command's own flags of the same names). Refuses a value that cannot be
/// read or has no effect, and warns on stderr about one it clamped.
pub fn scenario_from<S: Scenario>(matches: &ArgMatches, skip: &[&str]) -> Result<S> {
    scenario_from_base(matches, skip, S::default())
}

/// As [`scenario_from`], on top of `base` instead of the default scenario (a
/// data set's preset: its flags apply on top of it).
pub fn scenario_from_base<S: Scenario>(matches: &ArgMatches, skip: &[&str], base: S) -> Result<S> {
    let mut scenario = base;
    apply_table_flags(matches, &mut scenario, skip)?;
    Ok(scenario)
}

/// Applies the table's flags of `scenario` that the command has and that were
/// given, but those in `skip`; see [`scenario_from`].
fn apply_table_flags<S: Scenario>(
    matches: &ArgMatches,
    scenario: &mut S,
    skip: &[&str],
) -> Result<()> {
    let given: Vec<(&str, &str)> = S::params()
        .iter()
        .filter(|p| !skip.contains(&p.name))
        .filter_map(|p| value(matches, p.name).map(|v| (p.name, v)))
        .collect();
    for issue in params::apply_pairs(scenario, given, &[]) {
        match issue {
            ParamIssue::Clamped { .. } => eprintln!("warning: {issue}"),
            ParamIssue::Unreadable {
                name,
                value,
                expected,
                ..
            } => bail!("--{name} '{value}' is not {expected}"),
            ParamIssue::Ignored { ref name, .. } | ParamIssue::Unknown { ref name } => {
                bail!("--{name}: {issue}")
            }
        }
    }
    Ok(())
}

/// The items of a comma-separated list (a list flag's text): trimmed, the
/// empty ones dropped.
pub fn items(text: &str) -> impl Iterator<Item = &str> {
    text.split(',').map(str::trim).filter(|p| !p.is_empty())
}

/// The [`items`] of list flag `id` (none without it).
pub fn list<'a>(matches: &'a ArgMatches, id: &str) -> impl Iterator<Item = &'a str> {
    items(value(matches, id).unwrap_or(""))
}

/// The text of flag `id`, if the command has that flag and it has a value.
fn value<'a>(matches: &'a ArgMatches, id: &str) -> Option<&'a str> {
    matches
        .try_get_one::<String>(id)
        .ok()
        .flatten()
        .map(String::as_str)
}

/// Whether flag `id` was given on the command line (not a default, and not a flag
/// the command does not have).
pub fn given(matches: &ArgMatches, id: &str) -> bool {
    matches.ids().any(|i| i.as_str() == id)
        && matches.value_source(id) == Some(clap::parser::ValueSource::CommandLine)
}
