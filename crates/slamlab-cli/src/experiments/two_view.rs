//! `slamlab experiment two-view`: eight-point and five-point RANSAC on seeded
//! random two-view scenes, by outlier share (thesis `000` Sec. 4.3).
//!
//! ```text
//! slamlab experiment two-view --method eight-point,five-point --outliers 0,0.3,0.5 --noise-px 1 --points 200 --trials 200 --seed 1 --json
//! slamlab experiment two-view --outliers 0.5 --points 500 --sprt
//! ```

use super::first_seed_arg;
use crate::args;
use crate::command::Experiment;
use crate::flags;
use crate::output::{Output, progress_bar};
use anyhow::{Result, bail};
use clap::{ArgMatches, Command};
use slamlab_core::vision::{EarlyRejection, Method};
use slamlab_sim::visual_odometry::{TwoViewSettings, two_view_experiment};
use std::io::Write;

/// The two-view experiment.
pub struct TwoView;

/// Parses `--method`.
fn methods(text: &str) -> Result<Vec<Method>> {
    let mut out = Vec::new();
    for name in flags::items(text) {
        match Method::from_name(name) {
            Some(m) => out.push(m),
            None => bail!("--method: '{name}' is not a method (eight-point, five-point)"),
        }
    }
    if out.is_empty() {
        bail!("--method: give eight-point, five-point or both");
    }
    Ok(out)
}

/// Parses `--outliers`: shares in [0, 0.95].
fn shares(text: &str) -> Result<Vec<f64>> {
    let mut out = Vec::new();
    for part in flags::items(text) {
        let Ok(v) = part.parse::<f64>() else {
            bail!("--outliers: '{part}' is not a number");
        };
        if !(0.0..=0.95).contains(&v) {
            bail!("--outliers: {v} is outside 0 .. 0.95");
        }
        out.push(v);
    }
    if out.is_empty() {
        bail!("--outliers: give at least one share");
    }
    Ok(out)
}

impl Experiment for TwoView {
    fn command(&self) -> Command {
        Command::new("two-view")
            .about("Eight-point and five-point RANSAC on seeded two-view scenes: R and t errors, iterations, inlier precision and recall")
            .arg(
                args::list("method", "comma-separated solvers: eight-point, five-point")
                    .default_value("eight-point,five-point"),
            )
            .arg(
                args::list("outliers", "comma-separated shares of wrong matches, 0 .. 0.95")
                    .default_value("0,0.3,0.5"),
            )
            .arg(
                args::number("noise-px", "pixel noise standard deviation, pixels (0 .. 20)")
                    .default_value("1"),
            )
            .arg(args::whole("points", 8..=5000, "matches per trial").default_value("200"))
            .arg(
                args::whole(
                    "trials",
                    1..=100_000,
                    "trials per method and share; trial i uses seed + i",
                )
                .default_value("200"),
            )
            .arg(first_seed_arg())
            .arg(
                args::choice(
                    "early-rejection",
                    &["none", "sprt"],
                    "none: every hypothesis checked against every match; sprt: Matas and Chum's sequential probability ratio test rejects bad hypotheses early",
                )
                .value_name("none|sprt")
                .default_value("none"),
            )
            .arg(args::switch("sprt", "short for --early-rejection sprt"))
            .arg(args::switch(
                "no-normalize",
                "eight-point without Hartley normalization",
            ))
            .arg(args::switch(
                "no-refine",
                "end with the linear eight-point refit, without the Levenberg-Marquardt refinement of (R, t) on the Sampson distances",
            ))
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let noise_px = m.get_one::<f64>("noise-px").copied().unwrap_or(1.0);
        if !(noise_px.is_finite() && (0.0..=20.0).contains(&noise_px)) {
            bail!("--noise-px: {noise_px} is outside 0 .. 20");
        }
        let settings = TwoViewSettings {
            methods: methods(
                m.get_one::<String>("method")
                    .map_or("eight-point,five-point", String::as_str),
            )?,
            outliers: shares(
                m.get_one::<String>("outliers")
                    .map_or("0,0.3,0.5", String::as_str),
            )?,
            noise_px,
            points: m.get_one::<u64>("points").copied().unwrap_or(200) as usize,
            trials: m.get_one::<u64>("trials").copied().unwrap_or(200) as usize,
            seed: m.get_one::<u64>("seed").copied().unwrap_or(1),
            normalize: !m.get_flag("no-normalize"),
            refine: !m.get_flag("no-refine"),
            early_rejection: if m.get_flag("sprt") {
                EarlyRejection::Sprt
            } else {
                m.get_one::<String>("early-rejection")
                    .and_then(|name| EarlyRejection::from_name(name))
                    .unwrap_or_default()
            },
        };
        let report = two_view_experiment(&settings, progress_bar("two-view"));
        if out.print_json(&report)? {
            return Ok(());
        }
        writeln!(
            out,
            "SLAM Lab experiment two-view: {} trials of {} matches, {} px noise, seed {}, normalization {}, early rejection {}, refinement {}",
            settings.trials,
            settings.points,
            settings.noise_px,
            settings.seed,
            if settings.normalize { "on" } else { "off" },
            settings.early_rejection.name(),
            if settings.refine { "on" } else { "off" },
        )?;
        writeln!(out, "scene: {}", report.scene)?;
        writeln!(out)?;
        writeln!(
            out,
            "{:<12} {:>8} {:>18} {:>18} {:>11} {:>10} {:>8} {:>9}",
            "method",
            "outliers",
            "rot err deg med/90",
            "t err deg med/90",
            "iterations",
            "precision",
            "recall",
            "failures"
        )?;
        for r in &report.results {
            writeln!(
                out,
                "{:<12} {:>8.2} {:>8.3} / {:>7.3} {:>8.3} / {:>7.3} {:>11.0} {:>10.4} {:>8.4} {:>9}",
                r.method,
                r.outliers,
                r.rotation_error_deg.median,
                r.rotation_error_deg.p90,
                r.translation_angle_error_deg.median,
                r.translation_angle_error_deg.p90,
                r.ransac_iterations.median,
                r.inlier_precision,
                r.inlier_recall,
                r.failures
            )?;
        }
        let with_sprt: Vec<_> = report
            .results
            .iter()
            .filter_map(|r| r.sprt.map(|s| (r, s)))
            .collect();
        if !with_sprt.is_empty() {
            writeln!(out)?;
            writeln!(
                out,
                "{:<12} {:>8} {:>11} {:>9} {:>21} {:>20}",
                "method",
                "outliers",
                "hypotheses",
                "rejected",
                "checked if rejected",
                "checked per hyp."
            )?;
            for (r, s) in with_sprt {
                writeln!(
                    out,
                    "{:<12} {:>8.2} {:>11} {:>8.1}% {:>21.1} {:>20.1}",
                    r.method,
                    r.outliers,
                    s.hypotheses,
                    100.0 * s.rejected_share,
                    s.matches_checked_when_rejected,
                    s.matches_checked_per_hypothesis
                )?;
            }
        }
        Ok(())
    }
}
