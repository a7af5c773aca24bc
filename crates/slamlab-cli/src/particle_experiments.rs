//! `slamlab experiment fastslam` and `slamlab experiment resampling`.
//!
//! ```text
//! slamlab experiment fastslam --version 1|2 --particles 5,10,30,100 --trials 20 --seed 1 --json
//! slamlab experiment resampling --method all --trials 10000 --json
//! ```

use anyhow::{Result, bail};
use clap::{Arg, ArgMatches};
use slamlab_core::particle::{FastSlamVersion, Resampler, WeightPreset};
use slamlab_sim::fastslam::fastslam_experiment;
use slamlab_sim::landmark_params::PARAMS;
use slamlab_sim::resampling::{self, resampling_experiment};
use std::io::Write;

/// Trials when `--trials` is not given.
const FASTSLAM_TRIALS: u64 = 20;
const RESAMPLING_TRIALS: u64 = 10_000;
/// The largest particle count the command accepts.
const MAX_PARTICLES: usize = 10_000;

/// The flags of the two experiments (added to `slamlab experiment`).
pub fn args() -> Vec<Arg> {
    vec![
        Arg::new("version")
            .long("version")
            .value_parser(["1", "2"])
            .help("fastslam: FastSLAM 1.0 (motion-model proposal) or 2.0 (measurement-informed proposal); default 2"),
        Arg::new("particles")
            .long("particles")
            .value_name("LIST")
            .help("fastslam: comma-separated particle counts (1 .. 10000), default 5,10,30,100; resampling: particles per weight set, default 20"),
        Arg::new("method")
            .long("method")
            .value_name("LIST")
            .help("resampling: all, or comma-separated methods (multinomial, low-variance, stratified, residual)"),
    ]
}

fn given(matches: &ArgMatches, id: &str) -> bool {
    matches.value_source(id) == Some(clap::parser::ValueSource::CommandLine)
}

fn parse_counts(text: &str) -> Result<Vec<usize>> {
    let mut counts = Vec::new();
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let Ok(n) = part.parse::<usize>() else {
            bail!("--particles: '{part}' is not a whole number");
        };
        if n == 0 {
            bail!("--particles: a particle filter needs at least one particle (got 0)");
        }
        if n > MAX_PARTICLES {
            bail!("--particles: {n} is more than the {MAX_PARTICLES} this command runs");
        }
        counts.push(n);
    }
    if counts.is_empty() {
        bail!("--particles: give at least one count, e.g. 5,10,30,100");
    }
    Ok(counts)
}

/// `slamlab experiment fastslam`.
pub fn fastslam(matches: &ArgMatches) -> Result<()> {
    for other in ["noise-scale", "method"] {
        if given(matches, other) {
            bail!("--{other} does not belong to the fastslam experiment");
        }
    }
    let scenario = crate::scenario_from(matches)?;
    if matches!(scenario.controller, slamlab_sim::ControllerKind::Manual) {
        bail!("--controller manual has nobody to drive headless; use the circle (--v, --w-deg)");
    }
    let version = match matches.get_one::<String>("version").map(String::as_str) {
        Some("1") => FastSlamVersion::V1,
        _ => FastSlamVersion::V2,
    };
    let counts = parse_counts(
        matches
            .get_one::<String>("particles")
            .map_or("5,10,30,100", String::as_str),
    )?;
    let trials = if given(matches, "trials") {
        matches
            .get_one::<u64>("trials")
            .copied()
            .unwrap_or(FASTSLAM_TRIALS)
    } else {
        FASTSLAM_TRIALS
    } as usize;
    let steps = matches.get_one::<u64>("steps").copied().unwrap_or(200);
    let result = fastslam_experiment(
        &scenario,
        version,
        &counts,
        trials,
        steps,
        crate::progress_bar("fastslam"),
    )?;
    crate::write_csv(
        matches,
        &format!(
            "fastslam{}-seed{}-trials{trials}-steps{steps}.csv",
            version.number(),
            scenario.seed
        ),
        || {
            let mut csv = String::from(
                "particles,robot_rmse_mean,robot_rmse_std,landmark_rmse_mean,landmark_rmse_std,mean_n_eff\n",
            );
            for r in &result.results {
                csv.push_str(&format!(
                    "{},{},{},{},{},{}\n",
                    r.particles,
                    r.robot_rmse.mean,
                    r.robot_rmse.std,
                    r.landmark_rmse.mean,
                    r.landmark_rmse.std,
                    r.mean_n_eff
                ));
            }
            csv
        },
    )?;
    let mut out = std::io::stdout().lock();
    if crate::print_json_if_asked(matches, &mut out, &result)? {
        return Ok(());
    }
    writeln!(
        out,
        "SLAM Lab experiment fastslam: FastSLAM {}.0, {trials} trials of {steps} ticks ({:.1} s) from seed {}",
        version.number(),
        steps as f64 * scenario.dt,
        scenario.seed
    )?;
    writeln!(out)?;
    for (k, v) in &result.settings {
        let text = v.as_str().map_or_else(|| v.to_string(), str::to_owned);
        writeln!(out, "  {k:<32} {text}")?;
    }
    crate::print_parameters(&mut out, &result.parameters)?;
    writeln!(out)?;
    writeln!(
        out,
        "{:>9} {:>20} {:>20} {:>10}",
        "particles", "robot RMSE (m)", "landmark RMSE (m)", "mean N_eff"
    )?;
    for r in &result.results {
        writeln!(
            out,
            "{:>9} {:>11.3} ± {:<6.3} {:>11.3} ± {:<6.3} {:>10.2}",
            r.particles,
            r.robot_rmse.mean,
            r.robot_rmse.std,
            r.landmark_rmse.mean,
            r.landmark_rmse.std,
            r.mean_n_eff
        )?;
    }
    writeln!(out)?;
    writeln!(
        out,
        "mean ± standard deviation over trials; N_eff after each tick's updates, before resampling."
    )?;
    Ok(())
}

/// `slamlab experiment resampling`.
pub fn resampling(matches: &ArgMatches) -> Result<()> {
    for other in ["noise-scale", "version", "steps", "csv"] {
        if given(matches, other) {
            bail!("--{other} does not belong to the resampling experiment");
        }
    }
    if let Some(p) = PARAMS
        .iter()
        .find(|p| p.name != "seed" && given(matches, p.name))
    {
        bail!(
            "--{} is a landmark-world parameter; the resampling experiment uses only --method, --particles, --trials and --seed",
            p.name
        );
    }
    let seed = crate::scenario_from(matches)?.seed;
    let methods: Vec<Resampler> = match matches.get_one::<String>("method").map(String::as_str) {
        None | Some("all") => Resampler::ALL.to_vec(),
        Some(list) => {
            let mut methods = Vec::new();
            for name in list.split(',').map(str::trim).filter(|p| !p.is_empty()) {
                let Some(m) = Resampler::from_name(name) else {
                    bail!(
                        "--method: '{name}' is not a resampler (all, multinomial, low-variance, stratified, residual)"
                    );
                };
                methods.push(m);
            }
            if methods.is_empty() {
                bail!("--method: give 'all' or at least one method");
            }
            methods
        }
    };
    let particles = match matches.get_one::<String>("particles") {
        None => resampling::DEFAULT_PARTICLES,
        Some(text) => match parse_counts(text)?[..] {
            [n] => n,
            _ => bail!("--particles: the resampling experiment takes one count"),
        },
    };
    let trials = if given(matches, "trials") {
        matches
            .get_one::<u64>("trials")
            .copied()
            .unwrap_or(RESAMPLING_TRIALS)
    } else {
        RESAMPLING_TRIALS
    } as usize;
    let result = resampling_experiment(
        &methods,
        particles,
        trials,
        seed,
        crate::progress_bar("resampling"),
    );
    let mut out = std::io::stdout().lock();
    if crate::print_json_if_asked(matches, &mut out, &result)? {
        return Ok(());
    }
    writeln!(
        out,
        "SLAM Lab experiment resampling: {trials} resamplings of {particles} particles per method and weight set, seed {seed}"
    )?;
    writeln!(out)?;
    writeln!(
        out,
        "copy-count variance, averaged over particles (max |mean copies − M w| in brackets):"
    )?;
    write!(out, "{:<14}", "method")?;
    for p in WeightPreset::ALL {
        write!(out, " {:>22}", p.name())?;
    }
    writeln!(out)?;
    for r in &result.results {
        write!(out, "{:<14}", r.method)?;
        for p in &r.presets {
            write!(
                out,
                " {:>12.4} [{:>7.4}]",
                p.copy_count_variance, p.max_bias
            )?;
        }
        writeln!(out)?;
    }
    write!(out, "{:<14}", "theory (mult.)")?;
    for (_, v) in &result.multinomial_theory {
        write!(out, " {:>12.4} {:>9}", v, "")?;
    }
    writeln!(out)?;
    Ok(())
}
