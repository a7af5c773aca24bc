//! `slamlab experiment resampling`: the resamplers' copy-count variance on fixed
//! weight sets.
//!
//! ```text
//! slamlab experiment resampling --method all --trials 10000 --json
//! ```

use super::fastslam::parse_counts;
use super::{landmark_flags_but_seed, seed_arg, trials_arg};
use crate::args;
use crate::command::{Experiment, Refusal};
use crate::flags;
use crate::lessons::landmark::scenario_from;
use crate::output::{Output, progress_bar};
use anyhow::{Result, bail};
use clap::{ArgMatches, Command};
use slamlab_core::particle::{Resampler, WeightPreset};
use slamlab_sim::resampling::experiment::{self, resampling_experiment};
use std::io::Write;

/// The resamplers compared.
pub struct Resampling;

impl Experiment for Resampling {
    fn command(&self) -> Command {
        Command::new("resampling")
            .about("The resamplers' copy-count variance and bias on four weight sets, against multinomial theory")
            .arg(
                args::list(
                    "method",
                    "all, or comma-separated methods (multinomial, low-variance, stratified, residual)",
                )
                .default_value("all"),
            )
            .arg(args::named(
                "particles",
                "COUNT",
                format!(
                    "particles per weight set (1 .. 10000); default {}",
                    experiment::DEFAULT_PARTICLES
                ),
            ))
            .arg(trials_arg("10000"))
            .args(seed_arg())
    }

    fn refusals(&self) -> Vec<Refusal> {
        vec![Refusal {
            flags: landmark_flags_but_seed(&["particles"]),
            reason: |flag| {
                format!(
                    "--{flag} is a landmark-world parameter; the resampling experiment uses only --method, --particles, --trials and --seed"
                )
            },
        }]
    }

    fn run(&self, matches: &ArgMatches, out: &mut Output) -> Result<()> {
        let seed = scenario_from(matches, &["particles"])?.seed;
        let methods: Vec<Resampler> = match matches.get_one::<String>("method").map(String::as_str)
        {
            None | Some("all") => Resampler::ALL.to_vec(),
            Some(list) => {
                let mut methods = Vec::new();
                for name in flags::items(list) {
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
            None => experiment::DEFAULT_PARTICLES,
            Some(text) => match parse_counts(text)?[..] {
                [n] => n,
                _ => bail!("--particles: the resampling experiment takes one count"),
            },
        };
        let trials = matches.get_one::<u64>("trials").copied().unwrap_or(10_000) as usize;
        let result = resampling_experiment(
            &methods,
            particles,
            trials,
            seed,
            progress_bar("resampling"),
        );
        if out.print_json(&result)? {
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
}
