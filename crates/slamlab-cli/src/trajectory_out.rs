//! `--trajectory-out DIR`: a headless run's trajectories as files, the same
//! files as the app's File > Export trajectories (TUM and CSV for each
//! estimator and the truth, landmark CSVs, a README), ready for
//! `slamlab evaluate` and evo.

use crate::args;
use anyhow::{Context, Result};
use clap::{Arg, ArgMatches};
use slamlab_sim::io::trajectory::{LandmarkRow, export_files};
use slamlab_sim::metrics::NamedTrajectory;
use std::path::PathBuf;

/// The flag.
pub fn arg() -> Arg {
    args::path(
        "trajectory-out",
        "DIR",
        "write the trajectories (TUM and CSV, with covariances where the estimator has them) and landmarks to DIR",
    )
}

/// Writes the files when the flag was given; says where on stderr.
pub fn write(
    m: &ArgMatches,
    lesson: &str,
    trajectories: &[NamedTrajectory],
    landmarks: &[(String, Vec<LandmarkRow>)],
) -> Result<()> {
    let Some(dir) = m.try_get_one::<PathBuf>("trajectory-out").ok().flatten() else {
        return Ok(());
    };
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let files = export_files(lesson, trajectories, landmarks);
    for (name, bytes) in &files {
        let path = dir.join(name);
        std::fs::write(&path, bytes).with_context(|| format!("writing {}", path.display()))?;
    }
    eprintln!("wrote {} files to {}", files.len(), dir.display());
    Ok(())
}
