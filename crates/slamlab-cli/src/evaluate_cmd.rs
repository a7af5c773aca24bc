//! `slamlab evaluate`: any estimate against any reference, with the metrics the
//! lessons show (association, alignment, APE, RPE, NEES) and evo's options.

use crate::args;
use anyhow::{Context, Result, anyhow};
use clap::{Arg, ArgMatches, Command};
use slamlab_sim::io::trajectory::{self, TrajectoryFile};
use slamlab_sim::metrics::{
    Alignment, DEFAULT_MAX_DIFF, DeltaUnit, ErrorStats, Evaluation, EvaluationSettings,
    RelativeDelta, evaluate,
};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The `evaluate` subcommand.
pub fn command() -> Command {
    Command::new("evaluate")
        .about("Compare a trajectory with a reference: APE, RPE and NEES, as evo computes them")
        .long_about(
            "Compare an estimated trajectory with a reference, as evo_ape and evo_rpe do.\n\n\
             Both files are TUM (t x y z qx qy qz qw) or CSV (t,x,y,theta, optionally with the \
             covariance's upper triangle c_xx,c_xy,c_xtheta,c_yy,c_ytheta,c_thetatheta). Each pose of \
             the shorter trajectory is paired with the pose of the other whose time is nearest, within \
             --max-diff seconds (evo's --t_max_diff). The estimate is then aligned to the reference \
             (--align se2 is evo's --align, sim2 adds --correct_scale) and the absolute pose error \
             (APE: translation in m, rotation in degrees) and the relative pose error over --delta \
             frames or metres (RPE, consecutive pairs unless --all-pairs) are reported with evo's \
             statistics; with covariances, NEES and its chi-square bands too. See docs/metrics.md.",
        )
        .arg(
            args::path("estimate", "FILE", "the estimated trajectory (TUM or CSV)").required(true),
        )
        .arg(
            args::path("reference", "FILE", "the reference trajectory (TUM or CSV), e.g. the true path").required(true),
        )
        .arg(
            Arg::new("align")
                .long("align")
                .value_parser(Alignment::NAMES)
                .default_value("se2")
                .help("none: as it is; se2: best rotation and translation; sim2: and scale"),
        )
        .arg(
            args::number("delta", "the RPE's step, in --delta-unit").default_value("1"),
        )
        .arg(
            args::choice("delta-unit", &["frames", "m"], "frames: poses apart; m: metres travelled by the estimate").default_value("frames"),
        )
        .arg(
            args::switch("all-pairs", "RPE over every pair --delta apart, not a chain of consecutive ones"),
        )
        .arg(
            args::number("max-diff", "the most two paired times may differ, seconds").default_value("0.01"),
        )
        .arg(
            args::number("offset", "seconds added to the estimate's times before pairing").default_value("0"),
        )
        .arg(
            args::switch("json", "print one JSON object"),
        )
}

/// Reads a trajectory file, refusing one over the size cap before reading it.
pub fn read_trajectory_file(path: &Path) -> Result<TrajectoryFile> {
    let size = std::fs::metadata(path)
        .with_context(|| format!("cannot read {}", path.display()))?
        .len();
    trajectory::check_size(size).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let name = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    trajectory::read_trajectory(&name, &bytes).map_err(|e| anyhow!("{}: {e}", path.display()))
}

/// The settings from the flags.
fn settings(m: &ArgMatches) -> Result<EvaluationSettings> {
    let number = |name: &str, default: f64| m.get_one::<f64>(name).copied().unwrap_or(default);
    let alignment = m
        .get_one::<String>("align")
        .and_then(|a| Alignment::from_name(a))
        .unwrap_or_default();
    let unit = m
        .get_one::<String>("delta-unit")
        .and_then(|u| DeltaUnit::from_name(u))
        .unwrap_or(DeltaUnit::Frames);
    Ok(EvaluationSettings {
        max_diff: number("max-diff", DEFAULT_MAX_DIFF),
        offset: number("offset", 0.0),
        alignment,
        delta: RelativeDelta {
            delta: number("delta", 1.0),
            unit,
            all_pairs: m.get_flag("all-pairs"),
        },
    })
}

/// Runs `slamlab evaluate`.
pub fn run(m: &ArgMatches, out: &mut dyn Write) -> Result<()> {
    let path = |name: &str| {
        m.get_one::<PathBuf>(name)
            .cloned()
            .ok_or_else(|| anyhow!("--{name} is required"))
    };
    let (estimate_path, reference_path) = (path("estimate")?, path("reference")?);
    let estimate = read_trajectory_file(&estimate_path)?;
    let reference = read_trajectory_file(&reference_path)?;
    let settings = settings(m)?;
    let evaluation =
        evaluate(&reference.trajectory, &estimate.trajectory, &settings).map_err(|e| {
            anyhow!(
                "{} against {}: {e}",
                estimate_path.display(),
                reference_path.display()
            )
        })?;
    let mut notices = estimate.notices.clone();
    notices.extend(reference.notices.iter().cloned());
    notices.extend(evaluation.notices.iter().cloned());
    if m.get_flag("json") {
        let mut value = serde_json::to_value(&evaluation)?;
        if let Some(object) = value.as_object_mut() {
            object.insert(
                "estimate".into(),
                estimate_path.display().to_string().into(),
            );
            object.insert(
                "reference".into(),
                reference_path.display().to_string().into(),
            );
            object.insert("notices".into(), notices.into());
        }
        writeln!(out, "{}", serde_json::to_string_pretty(&value)?)?;
        return Ok(());
    }
    print_text(out, &estimate_path, &reference_path, &evaluation, &notices)
}

fn stats_line(s: &ErrorStats) -> String {
    format!(
        "rmse {:.6}  mean {:.6}  median {:.6}  std {:.6}  min {:.6}  max {:.6}  (n = {})",
        s.rmse, s.mean, s.median, s.std, s.min, s.max, s.count
    )
}

fn print_text(
    out: &mut dyn Write,
    estimate: &Path,
    reference: &Path,
    e: &Evaluation,
    notices: &[String],
) -> Result<()> {
    let p = &e.pairing;
    writeln!(
        out,
        "estimate:  {} ({} poses)",
        estimate.display(),
        p.estimate_poses
    )?;
    writeln!(
        out,
        "reference: {} ({} poses)",
        reference.display(),
        p.reference_poses
    )?;
    writeln!(
        out,
        "pairs:     {} within {} s{}, covering {:.1} % of the reference's time ({:.3} to {:.3} s)",
        p.pairs,
        p.max_diff_s,
        if p.offset_s != 0.0 {
            format!(" (estimate shifted by {} s)", p.offset_s)
        } else {
            String::new()
        },
        100.0 * p.coverage,
        p.overlap_s.0,
        p.overlap_s.1
    )?;
    let a = &e.alignment;
    match a.kind {
        "none" => writeln!(
            out,
            "alignment: none (the estimate is in the reference's frame)"
        )?,
        kind => writeln!(
            out,
            "alignment: {}: rotation {:.4}°, translation ({:.4}, {:.4}) m{}",
            if kind == "sim2" { "Sim(2)" } else { "SE(2)" },
            a.rotation_deg,
            a.translation_m[0],
            a.translation_m[1],
            if kind == "sim2" {
                format!(", scale {:.6}", a.scale)
            } else {
                String::new()
            }
        )?,
    }
    writeln!(
        out,
        "APE translation (m):   {}",
        stats_line(&e.ape.translation)
    )?;
    writeln!(
        out,
        "APE rotation (deg):    {}",
        stats_line(&e.ape.rotation)
    )?;
    let d = &e.settings.delta;
    match (&e.rpe, &e.rpe_refused) {
        (Some(rpe), _) => {
            let step = format!(
                "{} {}{}",
                d.delta,
                d.unit.name(),
                if d.all_pairs { ", all pairs" } else { "" }
            );
            writeln!(
                out,
                "RPE translation (m) over {step}: {}",
                stats_line(&rpe.translation)
            )?;
            writeln!(
                out,
                "RPE rotation (deg) over {step}:  {}",
                stats_line(&rpe.rotation)
            )?;
        }
        (None, Some(why)) => writeln!(out, "RPE: {why}")?,
        (None, None) => {}
    }
    if let Some(n) = &e.nees {
        match n.anees {
            Some(anees) => writeln!(
                out,
                "NEES: ANEES {anees:.3} over {} poses (95 % band of the average {:.3}-{:.3}); {:.1} % of the poses inside the 95 % band {:.3}-{:.3}",
                n.count,
                n.anees_band95.0,
                n.anees_band95.1,
                100.0 * n.share_in_band.unwrap_or(0.0),
                n.band95.0,
                n.band95.1
            )?,
            None => writeln!(out, "NEES: no covariance is positive definite")?,
        }
    }
    for notice in notices {
        writeln!(out, "note: {notice}")?;
    }
    Ok(())
}
