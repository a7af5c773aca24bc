//! The two kinds of command the CLI dispatches: a lesson `slamlab run ID` runs
//! headless ([`RunLesson`]) and an experiment `slamlab experiment NAME` reproduces
//! ([`Experiment`]). Every lesson and experiment module implements one of them;
//! [`crate::registry`] lists them. This module imports neither.

use crate::output::Output;
use anyhow::Result;
use clap::{ArgMatches, Command};

/// A lesson whose scenario `slamlab run ID` runs headless.
pub trait RunLesson: Sync {
    /// The subcommand: its name (the lesson id, the app's `?lesson=ID`), its one
    /// line for `slamlab run --help` (`about`) and the lesson's flags (`--json`
    /// and `--scenario FILE` are added by the registry).
    fn command(&self) -> Command;
    /// The lesson id: the name of its [`RunLesson::command`] (built for it,
    /// flags and all).
    fn id(&self) -> String {
        self.command().get_name().to_owned()
    }
    /// Runs it, printing to `out`.
    fn run(&self, matches: &ArgMatches, out: &mut Output) -> Result<()>;
}

/// Flags of other commands that an experiment refuses with a reason of its own
/// (the flag's name in, the message out), rather than the shared "belongs to".
pub struct Refusal {
    /// The flags (their ids, which are their long names).
    pub flags: Vec<&'static str>,
    /// The message for one of them.
    pub reason: fn(&str) -> String,
}

/// An experiment `slamlab experiment NAME` reproduces.
pub trait Experiment: Sync {
    /// The subcommand: its name on the command line, its one line for
    /// `slamlab experiment --help` (`about`) and the experiment's flags
    /// (`--json` is added by the registry).
    fn command(&self) -> Command;
    /// Its name on the command line: the name of its [`Experiment::command`]
    /// (built for it, flags and all).
    fn name(&self) -> String {
        self.command().get_name().to_owned()
    }
    /// Other experiments' flags it refuses with its own message, checked in this
    /// order; any other experiment's flag is refused as belonging to that one.
    fn refusals(&self) -> Vec<Refusal> {
        Vec::new()
    }
    /// Runs it, printing to `out`.
    fn run(&self, matches: &ArgMatches, out: &mut Output) -> Result<()>;
}
