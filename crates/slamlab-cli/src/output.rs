//! What every lesson run and experiment prints the same way: `--json` (one object
//! on one line), `--csv DIR` files, the parameter summary of the readable output,
//! and the progress bars on stderr.

use crate::args;
use anyhow::{Context, Result};
use clap::{Arg, ArgMatches};
use serde_json::{Map, Value};
use std::io::{IsTerminal, Write};
use std::path::PathBuf;

/// `--json`: every lesson and experiment has it (the registry adds it).
pub fn json_arg() -> Arg {
    args::switch("json", "print one JSON object")
}

/// `--csv DIR`, for the commands that write files; `help` says what they write.
pub fn csv_arg(help: &'static str) -> Arg {
    args::path("csv", "DIR", help)
}

/// Where a command's results go: the readable text or `--json` on stdout, files
/// into `--csv DIR`, notes on stderr.
pub struct Output<'a> {
    json: bool,
    csv: Option<PathBuf>,
    out: Box<dyn Write + 'a>,
}

impl<'a> Output<'a> {
    /// Output to `out`, as the command line's `--json` and `--csv` ask.
    pub fn new(matches: &ArgMatches, out: Box<dyn Write + 'a>) -> Self {
        Output {
            json: matches
                .try_get_one::<bool>("json")
                .ok()
                .flatten()
                .copied()
                .unwrap_or(false),
            csv: matches
                .try_get_one::<PathBuf>("csv")
                .ok()
                .flatten()
                .cloned(),
            out,
        }
    }

    /// Whether `--json` was given.
    pub fn json(&self) -> bool {
        self.json
    }

    /// With `--json`: prints `value` as one line of JSON and returns `true`.
    pub fn print_json(&mut self, value: &impl serde::Serialize) -> Result<bool> {
        if !self.json {
            return Ok(false);
        }
        serde_json::to_writer(&mut self.out, value).context("writing JSON")?;
        writeln!(self.out)?;
        Ok(true)
    }

    /// With `--csv DIR`: writes `contents()` to `DIR/file_name` (creating DIR) and
    /// says so on stderr.
    pub fn write_csv(&self, file_name: &str, contents: impl FnOnce() -> String) -> Result<()> {
        let Some(dir) = &self.csv else {
            return Ok(());
        };
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let path = dir.join(file_name);
        std::fs::write(&path, contents()).with_context(|| format!("writing {}", path.display()))?;
        eprintln!("wrote {}", path.display());
        Ok(())
    }

    /// The parameters block of the readable output: a `parameters:` line, then one
    /// line per parameter with its value and (for the landmark table's names) unit,
    /// names padded to `width`.
    pub fn parameters(&mut self, parameters: &Map<String, Value>, width: usize) -> Result<()> {
        writeln!(self.out, "parameters:")?;
        self.rows(
            parameters,
            width,
            Some(&|k| {
                <slamlab_sim::LandmarkScenario as slamlab_sim::params::Scenario>::param(k)
                    .map_or("", |p| p.unit)
            }),
        )
    }

    /// [`Self::parameters`] as a paragraph of the experiments' reports: a
    /// blank line before and after.
    pub fn parameter_paragraph(
        &mut self,
        parameters: &Map<String, Value>,
        width: usize,
    ) -> Result<()> {
        writeln!(self.out)?;
        self.parameters(parameters, width)?;
        writeln!(self.out)?;
        Ok(())
    }

    /// Settings that are not parameters: one line each, `  name value`, names
    /// padded to `width`.
    pub fn settings(&mut self, values: &Map<String, Value>, width: usize) -> Result<()> {
        self.rows(values, width, None)
    }

    fn rows(
        &mut self,
        values: &Map<String, Value>,
        width: usize,
        unit: Option<&dyn Fn(&str) -> &'static str>,
    ) -> Result<()> {
        for (k, v) in values {
            let text = v.as_str().map_or_else(|| v.to_string(), str::to_owned);
            match unit {
                Some(unit) => writeln!(self.out, "  {k:<width$} {text} {}", unit(k))?,
                None => writeln!(self.out, "  {k:<width$} {text}")?,
            }
        }
        Ok(())
    }
}

impl Write for Output<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.out.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}

/// A progress bar on stderr for `total` trials (indicatif): drawn in place on a
/// terminal; in a log (stderr not a terminal) a line every tenth of the way
/// instead. Safe to share between threads.
pub fn trials_bar(label: &'static str, total: usize) -> indicatif::ProgressBar {
    units_bar(label, total, "trials")
}

/// A progress bar like [`trials_bar`] that counts `unit` (scans, steps, ...).
pub fn units_bar(label: &'static str, total: usize, unit: &str) -> indicatif::ProgressBar {
    let bar = if std::io::stderr().is_terminal() {
        indicatif::ProgressBar::new(total as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    if let Ok(style) = indicatif::ProgressStyle::with_template(&format!(
        "{{prefix}} [{{bar:30}}] {{pos}}/{{len}} {unit}, {{elapsed}} (about {{eta}} left)"
    )) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(label);
    bar.set_length(total as u64);
    bar
}

/// Advances `bar` to `done` of `total`, and in a log writes a line every tenth
/// of the way.
pub fn trials_progress(bar: &indicatif::ProgressBar, label: &str, done: usize, total: usize) {
    units_progress(bar, label, done, total, "trials");
}

/// [`trials_progress`] for a bar that counts `unit`.
pub fn units_progress(
    bar: &indicatif::ProgressBar,
    label: &str,
    done: usize,
    total: usize,
    unit: &str,
) {
    bar.set_position(done as u64);
    if bar.is_hidden()
        && done > 0
        && (done == total || (done * 10 / total.max(1)) != ((done - 1) * 10 / total.max(1)))
    {
        eprintln!("{label}: {done}/{total} {unit}");
    }
    if done == total {
        bar.finish();
    }
}

/// A number in a table of results: `-` for none, else `digits` decimals, or
/// `e_digits` in e-notation from 1e5 up (diverged runs can make averages
/// astronomically large).
pub fn table_number(v: Option<f64>, digits: usize, e_digits: usize) -> String {
    match v {
        None => "-".to_owned(),
        Some(v) if v.abs() >= 1e5 => format!("{v:.e_digits$e}"),
        Some(v) => format!("{v:.digits$}"),
    }
}

/// `trial(job)` for every job, on all cores (rayon), in the jobs' order, with a
/// [`trials_bar`] named `label` counting the finished ones. Each trial's numbers
/// must not depend on the thread that runs it (a trial seeds its own streams).
pub fn par_trials<J: Sync, T: Send>(
    label: &'static str,
    jobs: &[J],
    trial: impl Fn(&J) -> T + Sync,
) -> Vec<T> {
    use rayon::prelude::*;
    let total = jobs.len();
    let bar = trials_bar(label, total);
    let done = std::sync::atomic::AtomicUsize::new(0);
    jobs.par_iter()
        .map(|job| {
            let outcome = trial(job);
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            trials_progress(&bar, label, d, total);
            outcome
        })
        .collect()
}

/// A progress callback `(done, total)` for the experiments, drawing
/// [`trials_bar`].
pub fn progress_bar(label: &'static str) -> impl FnMut(usize, usize) {
    let mut bar: Option<indicatif::ProgressBar> = None;
    move |done, total| {
        let bar = bar.get_or_insert_with(|| trials_bar(label, total));
        trials_progress(bar, label, done, total);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matches(args: &[&str]) -> ArgMatches {
        clap::Command::new("t")
            .no_binary_name(true)
            .arg(json_arg())
            .arg(csv_arg("files"))
            .try_get_matches_from(args)
            .unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn json_is_one_line_and_only_when_asked() {
        let mut text = Vec::new();
        let value = serde_json::json!({"a": [1, 2], "b": {"c": "d"}});
        assert!(
            !Output::new(&matches(&[]), Box::new(&mut text))
                .print_json(&value)
                .unwrap()
        );
        assert!(text.is_empty());
        assert!(
            Output::new(&matches(&["--json"]), Box::new(&mut text))
                .print_json(&value)
                .unwrap()
        );
        let text = String::from_utf8(text).unwrap();
        assert_eq!(text, "{\"a\":[1,2],\"b\":{\"c\":\"d\"}}\n");
    }

    #[test]
    fn csv_goes_into_the_directory_and_parameters_carry_units() {
        let dir = std::env::temp_dir().join(format!("slamlab-output-{}", std::process::id()));
        let dir_arg = dir.to_string_lossy().into_owned();
        let mut text = Vec::new();
        let mut out = Output::new(&matches(&["--csv", &dir_arg]), Box::new(&mut text));
        out.write_csv("x.csv", || "a,b\n".to_owned()).unwrap();
        let mut map = Map::new();
        map.insert("range-std".into(), 0.5.into());
        map.insert("estimator".into(), "ekf".into());
        out.parameters(&map, 10).unwrap();
        drop(out);
        assert_eq!(std::fs::read_to_string(dir.join("x.csv")).unwrap(), "a,b\n");
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!(
            String::from_utf8(text).unwrap(),
            "parameters:\n  estimator  ekf \n  range-std  0.5 m\n"
        );
    }

    #[test]
    fn table_numbers_switch_to_e_notation_from_1e5() {
        assert_eq!(table_number(None, 3, 3), "-");
        assert_eq!(table_number(Some(2.0 / 3.0), 3, 3), "0.667");
        assert_eq!(table_number(Some(99_999.0), 0, 2), "99999");
        assert_eq!(table_number(Some(123_456.0), 3, 2), "1.23e5");
        assert_eq!(table_number(Some(-123_456.0), 3, 3), "-1.235e5");
    }

    #[test]
    fn parallel_trials_keep_the_jobs_order() {
        let jobs: Vec<u64> = (0..100).collect();
        let squares = par_trials("test", &jobs, |&j| j * j);
        assert_eq!(squares, jobs.iter().map(|j| j * j).collect::<Vec<_>>());
    }
}
