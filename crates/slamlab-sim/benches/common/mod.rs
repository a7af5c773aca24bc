//! What the benchmarks share: where the shared data sets are, and the landmark
//! world the tick benchmarks warm up in.

use slamlab_sim::LandmarkScenario;
use slamlab_sim::io::laser_log::LaserLog;
use slamlab_sim::world::landmarks::LandmarkLayout;
use std::path::PathBuf;

/// The Intel Research Lab log: `../shared/data/laser/intel.clf.bz2` beside
/// the repository, or under `$SLAMLAB_SHARED`.
#[allow(dead_code)] // the landmark benchmarks read no log
pub fn intel_log_path() -> PathBuf {
    std::env::var_os("SLAMLAB_SHARED")
        .map_or_else(
            || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"),
            PathBuf::from,
        )
        .join("data/laser/intel.clf.bz2")
}

/// The Intel log read and parsed, or None (with a message saying where it
/// was looked for) when it cannot be read.
#[allow(dead_code)] // not every benchmark reads the log whole
pub fn intel_log() -> Option<LaserLog> {
    let path = intel_log_path();
    match LaserLog::read_file(&path) {
        Ok(log) => Some(log),
        Err(e) => {
            eprintln!(
                "skipped: the Intel log is not readable at {} ({e})",
                path.display()
            );
            None
        }
    }
}

/// The folder that holds `data/`: `../shared` beside the repository, or `$SLAMLAB_SHARED`.
#[allow(dead_code)] // not every benchmark reads the shared data
pub fn shared_root() -> PathBuf {
    std::env::var_os("SLAMLAB_SHARED").map_or_else(
        || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"),
        PathBuf::from,
    )
}

/// `landmarks` landmarks in a random layout, seen by the lesson's sensor (120°,
/// 4 m; about 6 in view at 100 landmarks) or, under `stress`, by one that sees
/// all around to 6 m (about 40 in view).
#[allow(dead_code)] // only the landmark benchmarks use it
pub fn random_landmarks(landmarks: usize, stress: bool) -> LandmarkScenario {
    let lesson = LandmarkScenario {
        landmarks,
        layout: LandmarkLayout::Random,
        ..Default::default()
    };
    if stress {
        LandmarkScenario {
            fov: std::f64::consts::TAU,
            max_range: 6.0,
            ..lesson
        }
    } else {
        lesson
    }
}
