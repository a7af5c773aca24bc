//! What the `slamlab` binary's tests share: running the binary as a user does,
//! reading the JSON it prints, a scratch folder per test, the shared data sets
//! (skipping without them), and a throwaway Python virtual environment for the
//! tests that compare with a Python tool.

// Each test binary uses the helpers it needs.
#![allow(dead_code)]

use std::ops::Deref;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[allow(unused_imports)] // as the helpers above: each test binary uses what it needs
pub use slamlab_tests::shared_data;

/// `slamlab ARGS` as it ran: its exit status and output.
pub fn slamlab_output(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_slamlab"))
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("running slamlab: {e}"))
}

/// `slamlab ARGS`: whether it succeeded, its standard output and its
/// standard error.
pub fn slamlab(args: &[&str]) -> (bool, String, String) {
    let out = slamlab_output(args);
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The standard output of `slamlab ARGS`, which must succeed (the test fails
/// with its standard error otherwise).
pub fn slamlab_stdout(args: &[&str]) -> String {
    let (ok, stdout, stderr) = slamlab(args);
    assert!(ok, "slamlab {args:?} failed: {stderr}");
    stdout
}

/// The one JSON object `slamlab ARGS` prints on one line.
pub fn run_json(args: &[&str]) -> serde_json::Value {
    let stdout = slamlab_stdout(args);
    assert_eq!(stdout.lines().count(), 1, "one JSON object on one line");
    serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("not JSON ({e}): {stdout}"))
}

/// A simulated robot's run through the maze, `steps` scans from `seed`, recorded
/// by `slamlab log record` (which must succeed) to `out` (`.mcap`: a ROS 2 bag,
/// else a CARMEN log with its truth beside it); what the command printed.
pub fn record_maze(out: &Path, steps: u32, seed: u64) -> String {
    let out = out
        .to_str()
        .unwrap_or_else(|| panic!("{} is not UTF-8", out.display()));
    let (steps, seed) = (steps.to_string(), seed.to_string());
    slamlab_stdout(&[
        "log", "record", "--map", "maze", "--steps", &steps, "--seed", &seed, "--out", out,
    ])
}

/// The JSON a run that succeeded printed (the test fails with its standard
/// error otherwise).
pub fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("not JSON: {e}"))
}

/// A new Python virtual environment in `dir/venv` with `packages` installed
/// from PyPI: its `bin` folder, or `None` with a note saying what `test`
/// skips when `python3 -m venv` or `pip install` fails (no network).
pub fn python_venv(dir: &Path, packages: &[&str], test: &str) -> Option<PathBuf> {
    let venv = dir.join("venv");
    let bin = venv.join("bin");
    let mut make = Command::new("python3");
    make.args(["-m", "venv"]).arg(&venv);
    let mut install = Command::new(bin.join("python"));
    install
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
        ])
        .args(packages);
    for (what, mut command) in [
        ("`python3 -m venv` (install python3-venv)", make),
        ("`pip install` (no package registry?)", install),
    ] {
        match command.output() {
            Ok(o) if o.status.success() => {}
            Ok(o) => {
                let why = String::from_utf8_lossy(&o.stderr);
                eprintln!("skipped {test}: {what} failed: {}", why.trim());
                return None;
            }
            Err(e) => {
                eprintln!("skipped {test}: {what} could not run: {e}");
                return None;
            }
        }
    }
    Some(bin)
}

/// A fresh folder for one test's files, `slamlab-NAME-PID` in the system's
/// temporary folder (emptied first). It reads as its path (`dir.join("x")`).
/// Dropped, it is removed with all in it when the test passed, and kept (its
/// path on stderr) when the test failed, for a look at what the run wrote.
/// It exists from the start: a test of a flag that must make its folder
/// (`--csv DIR`, `--trajectory-out DIR`) names a folder inside it.
pub struct Scratch(PathBuf);

impl Scratch {
    /// Makes the folder.
    pub fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("slamlab-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        Self(dir)
    }
}

impl Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept for a look: {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
