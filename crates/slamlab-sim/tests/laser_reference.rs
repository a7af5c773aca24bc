//! A corrected log's reference trajectory matched through the mapping input (the
//! lessons' path) as through the raw log itself.

use slamlab_sim::grid::reference::LogReference;
use slamlab_sim::io::laser_log::LaserLog;

/// The Intel log and its corrected version, or `None` (and why) when the shared
/// data is not beside the repository.
fn shared_laser_dir() -> Option<std::path::PathBuf> {
    let dir = std::env::var_os("SLAMLAB_SHARED")
        .map_or_else(
            || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"),
            std::path::PathBuf::from,
        )
        .join("data/laser");
    if dir.join("intel.clf.bz2").exists() && dir.join("intel-corrected.log.gz").exists() {
        Some(dir)
    } else {
        eprintln!(
            "skipped: the Intel log and its corrected version are not in {} (the shared data sits beside the repository, or set SLAMLAB_SHARED)",
            dir.display()
        );
        None
    }
}

/// The Intel log's reference, matched through the mapping input as through the
/// log itself: 910 of 910, the same scans.
#[test]
fn the_intel_reference_matches_through_the_mapping_input() {
    let Some(dir) = shared_laser_dir() else {
        return;
    };
    let log = LaserLog::read_file(&dir.join("intel.clf.bz2")).unwrap();
    let bytes = std::fs::read(dir.join("intel-corrected.log.gz")).unwrap();
    let direct = LogReference::read(&bytes, "intel-corrected.log.gz", &log).unwrap();
    let input = slamlab_sim::grid::log_input(&log, "intel.clf.bz2");
    let through = input
        .reference_from(&bytes, "intel-corrected.log.gz")
        .unwrap();
    assert_eq!(direct.points.len(), 910);
    assert_eq!(through, direct);
    assert_eq!(through.points[0].scan, 169);
}
