//! `slamlab run [LESSON] --scenario FILE`: a scenario the app exported, run as if
//! its parameters were given as flags.

use crate::registry::{self, LESSONS};
use anyhow::{Context, Result, bail};
use slamlab_sim::io::scenario_file::ScenarioFile;
use std::ffi::OsString;
use std::path::PathBuf;

/// The command line with the file's parameters spelled out as flags (`--seed=7
/// ...`), so one parser reads both. Flags given on the command line win over the
/// file's; parameters the lesson's registered command has no flag for are skipped
/// with a warning. Command lines other than `slamlab run ... --scenario FILE` come
/// back unchanged.
pub fn expand_scenario_file(mut args: Vec<OsString>) -> Result<Vec<OsString>> {
    if args.get(1).is_none_or(|a| a != "run") {
        return Ok(args);
    }
    let Some(at) = args
        .iter()
        .position(|a| a == "--scenario" || a.to_string_lossy().starts_with("--scenario="))
    else {
        return Ok(args);
    };
    let inline = args[at]
        .to_string_lossy()
        .strip_prefix("--scenario=")
        .map(PathBuf::from);
    let path = match inline {
        Some(path) => {
            args.remove(at);
            path
        }
        None if at + 1 < args.len() => {
            let path = PathBuf::from(args.remove(at + 1));
            args.remove(at);
            path
        }
        None => bail!("--scenario needs a file: slamlab run --scenario FILE.json"),
    };
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("reading the scenario {}", path.display()))?;
    let file =
        ScenarioFile::parse(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let Some(lesson) = registry::lesson(&file.lesson) else {
        let ids: Vec<String> = LESSONS.iter().map(|l| l.id()).collect();
        bail!(
            "{} is a scenario of the {} lesson; `slamlab run` runs {} (the other lessons' \
             experiments: `slamlab experiment --help`)",
            path.display(),
            file.lesson,
            ids.join(" and ")
        );
    };
    match args.get(2).map(|a| a.to_string_lossy().into_owned()) {
        Some(named) if !named.starts_with('-') => {
            if named != file.lesson {
                bail!(
                    "{} is a scenario of the {} lesson, not {named}",
                    path.display(),
                    file.lesson
                );
            }
        }
        _ => args.insert(2, OsString::from(&file.lesson)),
    }
    let command = registry::lesson_command(lesson);
    let flags: Vec<String> = command
        .get_arguments()
        .filter_map(|a| a.get_long().map(str::to_owned))
        .collect();
    let given = |key: &str| {
        args.iter().any(|a| {
            let a = a.to_string_lossy();
            a == format!("--{key}") || a.starts_with(&format!("--{key}="))
        })
    };
    let mut spelled = Vec::new();
    for (key, value) in &file.params {
        if !flags.iter().any(|f| f == key) || key == "scenario" {
            eprintln!(
                "warning: {}: `{key}` is not a flag of `slamlab run {}`; ignored",
                path.display(),
                file.lesson
            );
        } else if !given(key) {
            spelled.push(OsString::from(format!("--{key}={value}")));
        }
    }
    args.splice(3..3, spelled);
    Ok(args)
}
