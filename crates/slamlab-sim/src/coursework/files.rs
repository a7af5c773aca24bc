//! The files of an assignment's download, in memory: one list for the CLI's
//! folder and the browser's zip, so both hold the same bytes.

use slamlab_core::Pose2;
use std::fmt::Write as _;

/// The files handed out, by their path inside the download (`answers/` for the
/// instructor's).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct InputFiles {
    /// `(path, bytes)`, in the order written.
    pub files: Vec<(String, Vec<u8>)>,
}

impl InputFiles {
    /// A download that opens with its `README.txt`.
    pub fn with_readme(readme: &str) -> InputFiles {
        let mut files = InputFiles::default();
        files.add("README.txt", readme);
        files
    }

    /// Adds `start_pose.txt`: the true start pose, `x y theta` (metres,
    /// radians) on one line.
    pub fn add_start_pose(&mut self, start: &Pose2) {
        self.add(
            "start_pose.txt",
            format!(
                "{} {} {}\n",
                number(start.x),
                number(start.y),
                number(start.theta)
            ),
        );
    }

    /// Adds a file.
    pub fn add(&mut self, path: &str, bytes: impl AsRef<[u8]>) {
        self.files.push((path.to_owned(), bytes.as_ref().to_vec()));
    }

    /// The bytes of the file at `path`.
    pub fn get(&self, path: &str) -> Option<&[u8]> {
        self.files
            .iter()
            .find(|(p, _)| p == path)
            .map(|(_, b)| b.as_slice())
    }

    /// The paths, in order.
    pub fn paths(&self) -> Vec<&str> {
        self.files.iter().map(|(p, _)| p.as_str()).collect()
    }

    /// A listing for the README: each path with its size.
    pub fn listing(&self) -> String {
        let mut out = String::new();
        for (path, bytes) in &self.files {
            let _ = writeln!(out, "  {path:<22} {:>9} bytes", bytes.len());
        }
        out
    }
}

/// A number as the files print it: Rust's shortest representation that reads
/// back as the same `f64` (so a program reading the files gets the very numbers
/// the reference estimator got).
pub fn number(v: f64) -> String {
    format!("{v}")
}
