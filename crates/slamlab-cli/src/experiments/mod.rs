//! The experiments `slamlab experiment` reproduces, one module each (listed in
//! [`crate::registry::EXPERIMENTS`]), and the flags several of them share.

pub mod consistency;
pub mod ekf_vs_ukf;
pub mod fastslam;
pub mod fusion;
pub mod grid_fastslam;
pub mod kidnap;
pub mod krp;
pub mod laser_slam;
pub mod pose_graph;
pub mod real_data;
pub mod resampling;
pub mod two_view;
pub mod unscented;

use crate::args;
use clap::Arg;
use slamlab_sim::landmark_slam::scenario::PARAMS;

/// `--trials N` (1 ..= 100000) with the experiment's default.
fn trials_arg(default: &'static str) -> Arg {
    args::whole(
        "trials",
        1..=100_000,
        "Monte Carlo trials; trial i uses seed + i",
    )
    .default_value(default)
}

/// `--seed N`: the first trial's seed (trial i uses seed + i).
fn first_seed_arg() -> Arg {
    args::seed("first seed")
}

/// `--steps N`: ticks per trial.
fn steps_arg() -> Arg {
    args::whole(
        "steps",
        1..=1_000_000,
        "ticks per trial (200 ticks of 0.1 s are one lap of the circle)",
    )
    .default_value("200")
}

/// `--noise-scale X`: the control-noise multiplier of the thesis's experiments.
fn noise_scale_arg() -> Arg {
    args::number(
        "noise-scale",
        "control-noise multiplier: 1 is thesis Experiment 1, 2 is Experiment 2 (0 .. 20]",
    )
    .default_value("1")
}

/// The landmark world's `--seed`, for the experiments that fix the rest of it.
fn seed_arg() -> Vec<Arg> {
    crate::lessons::landmark::scenario_args_where(|name| name == "seed")
}

/// The landmark scenario's flags under a heading of their own, but `--particles`
/// (the experiments' own list of counts).
fn scenario_args() -> Vec<Arg> {
    crate::lessons::landmark::scenario_args(&["particles"])
        .into_iter()
        .map(|a| a.help_heading("Scenario (the flags of `slamlab run landmark-slam`)"))
        .collect()
}

/// The landmark scenario's flags but the seed and those in `except`: what the
/// experiments with a fixed scenario refuse.
fn landmark_flags_but_seed(except: &[&str]) -> Vec<&'static str> {
    PARAMS
        .iter()
        .map(|p| p.name)
        .filter(|n| *n != "seed" && !except.contains(n))
        .collect()
}
