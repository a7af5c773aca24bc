//! The input of every mapping run (the mapping lesson's pose sources, grid
//! FastSLAM, the Cartographer lesson): scans with the odometry pose of each, from
//! a simulated robot or a laser log, with the truth beside them when there is one
//! (for the metrics only); and the two metrics the laser lessons share.

use crate::grid::builtin::BuiltinMap;
use crate::io::laser_log::LaserLog;
use crate::metrics::{NamedTrajectory, Trajectory, TrajectoryRole};
use slamlab_core::Pose2;
use slamlab_core::grid::{Cell, OccupancyGrid, ProbabilityGrid};
use slamlab_core::scan::Scan;
use std::sync::Arc;

/// One scan of the input.
#[derive(Clone, Debug, PartialEq)]
pub struct InputScan {
    /// Seconds since the log's start.
    pub time: f64,
    /// The scan, in the sensor frame (the sensor at the robot's centre).
    pub scan: Scan,
    /// The odometry pose when it was taken.
    pub odometry: Pose2,
}

/// What a run maps: scans with odometry, and for a simulated log the truth
/// (metrics only).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MappingInput {
    /// What the input is ("simulated maze, seed 3", "intel.clf.bz2").
    pub name: String,
    /// The scans in time order.
    pub scans: Vec<InputScan>,
    /// The true pose at each scan (simulation only).
    pub truth: Option<Vec<Pose2>>,
    /// The map the simulated robot drove in (simulation only).
    pub true_map: Option<Arc<OccupancyGrid>>,
    /// A laser log's reference trajectory (a corrected log), when one came
    /// with it (metrics only, as the truth).
    pub reference: Option<Arc<crate::grid::reference::LogReference>>,
    /// A laser log's clock at its first scan (`time` counts from it),
    /// seconds: what a reference is matched by.
    pub time_origin: f64,
}

impl MappingInput {
    /// The reference trajectory of this input when it was read from a log: a
    /// corrected log's bytes, its scans matched to the input's in the log's clock
    /// (through [`MappingInput::time_origin`]) by time and identical ranges.
    pub fn reference_from(
        &self,
        bytes: &[u8],
        name: &str,
    ) -> Result<crate::grid::reference::LogReference, crate::io::laser_reference::ReferenceError>
    {
        let reference = crate::io::laser_reference::ReferenceLog::from_bytes(bytes)?;
        let scans: Vec<(usize, f64, &[f64])> = self
            .scans
            .iter()
            .enumerate()
            .map(|(k, s)| (k, s.time + self.time_origin, s.scan.ranges.as_slice()))
            .collect();
        let association = crate::io::laser_reference::associate_scans(&reference, &scans)?;
        Ok(crate::grid::reference::LogReference::from_association(
            name,
            &reference,
            &association,
        ))
    }

    /// The times of `scans` (indices into [`MappingInput::scans`]; NaN for one
    /// past the end) and, at them, the truth (when the input has one) and the
    /// odometry: what the laser lessons export beside their estimate.
    pub fn truth_and_odometry(&self, scans: &[usize]) -> (Vec<f64>, Vec<NamedTrajectory>) {
        let stamps: Vec<f64> = scans
            .iter()
            .map(|&k| self.scans.get(k).map_or(f64::NAN, |s| s.time))
            .collect();
        let mut all = Vec::new();
        if let Some(truth) = &self.truth {
            let poses = scans.iter().filter_map(|&k| truth.get(k).copied());
            all.push(NamedTrajectory::new(
                "truth",
                TrajectoryRole::Truth,
                Trajectory::new(stamps.clone(), poses.collect()),
            ));
        }
        let odometry = scans
            .iter()
            .filter_map(|&k| self.scans.get(k).map(|s| s.odometry));
        all.push(NamedTrajectory::new(
            "odometry",
            TrajectoryRole::Odometry,
            Trajectory::new(stamps.clone(), odometry.collect()),
        ));
        (stamps, all)
    }

    /// Seconds from the first scan to the last.
    pub fn duration(&self) -> f64 {
        match (self.scans.first(), self.scans.last()) {
            (Some(a), Some(b)) => (b.time - a.time).max(0.0),
            _ => 0.0,
        }
    }
}

/// The input of a laser log: its scans with the odometry pose of each, times
/// from the first scan. The laser is taken to sit at the robot's centre (the
/// Intel log's `robot_frontlaser_offset` is 0).
pub fn log_input(log: &LaserLog, name: &str) -> MappingInput {
    let t0 = log.scans.first().map_or(0.0, |s| s.timestamp);
    MappingInput {
        name: name.to_owned(),
        scans: log
            .scans
            .iter()
            .map(|s| InputScan {
                time: s.timestamp - t0,
                scan: s.scan.clone(),
                odometry: s.odometry,
            })
            .collect(),
        truth: None,
        true_map: None,
        reference: None,
        time_origin: t0,
    }
}

/// The built-in map a scenario names (the maze for anything else).
pub fn builtin_map(name: &str) -> Result<OccupancyGrid, String> {
    BuiltinMap::from_name(name)
        .unwrap_or(BuiltinMap::Maze)
        .load()
        .map_err(|e| e.to_string())
}

/// The root-mean-square position error of `poses` against `truth` (the first
/// `poses.len()` true poses), metres; `None` without truth or poses.
pub fn trajectory_rmse(poses: &[Pose2], truth: Option<&[Pose2]>) -> Option<f64> {
    let truth = truth?;
    let n = poses.len().min(truth.len());
    if n == 0 {
        return None;
    }
    let sum: f64 = poses
        .iter()
        .zip(truth)
        .take(n)
        .map(|(p, t)| (p.x - t.x) * (p.x - t.x) + (p.y - t.y) * (p.y - t.y))
        .sum();
    Some((sum / n as f64).sqrt())
}

/// The share of the true map's free and occupied cells that the built map
/// classifies the same (occupied above probability 0.5, free below), over the
/// cells the built map knows (looked up at each true cell's centre). `None`
/// when the built map knows none of them.
pub fn map_agreement(built: &ProbabilityGrid, truth: &OccupancyGrid) -> Option<f64> {
    agreement_by(truth, |x, y| {
        let (i, j) = built.cell_of(x, y);
        built
            .log_odds_at(i, j)
            .filter(|l| *l != 0.0)
            .map(|l| l > 0.0)
    })
    .0
}

/// [`map_agreement`] of a three-state map (a ROS map a student handed in or
/// dropped): the share of the true map's free and occupied cells that `built`
/// classifies the same, over the cells `built` knows (free or occupied at the
/// true cell's centre). The same definition, the same cells.
pub fn occupancy_agreement(built: &OccupancyGrid, truth: &OccupancyGrid) -> Option<f64> {
    agreement_by(truth, |x, y| occupied_at(built, x, y)).0
}

/// The share of the true map's free and occupied cells that `built` knows at
/// all (free or occupied): what [`occupancy_agreement`] is computed over. A map
/// that knows one cell right agrees fully and covers nothing; a grade needs
/// both.
pub fn occupancy_coverage(built: &OccupancyGrid, truth: &OccupancyGrid) -> Option<f64> {
    agreement_by(truth, |x, y| occupied_at(built, x, y)).1
}

/// Occupied (`true`), free (`false`) or unknown (`None`) at a world point.
fn occupied_at(grid: &OccupancyGrid, x: f64, y: f64) -> Option<bool> {
    let (i, j) = grid.world_to_cell(x, y);
    match grid.get(i, j)? {
        Cell::Occupied => Some(true),
        Cell::Free => Some(false),
        Cell::Unknown => None,
    }
}

/// Over the true map's free and occupied cells: (the share of those `built`
/// knows that it classifies the same, the share it knows).
fn agreement_by(
    truth: &OccupancyGrid,
    built: impl Fn(f64, f64) -> Option<bool>,
) -> (Option<f64>, Option<f64>) {
    let (mut cells, mut known, mut same) = (0usize, 0usize, 0usize);
    for j in 0..truth.height() as i64 {
        for i in 0..truth.width() as i64 {
            let Some(cell) = truth.get(i, j) else {
                continue;
            };
            if cell == Cell::Unknown {
                continue;
            }
            cells += 1;
            let (x, y) = truth.cell_center(i, j);
            let Some(occupied) = built(x, y) else {
                continue;
            };
            known += 1;
            same += usize::from(occupied == (cell == Cell::Occupied));
        }
    }
    (
        (known > 0).then(|| same as f64 / known as f64),
        (cells > 0).then(|| known as f64 / cells as f64),
    )
}

#[cfg(test)]
mod tests {
    use crate::io::laser_log::LaserLog;

    /// The Intel log's reference, matched through the mapping input (the lessons'
    /// path) as through the log itself: 910 of 910, the same scans.
    #[test]
    fn the_intel_reference_matches_through_the_mapping_input() {
        let Some(dir) = crate::io::laser_reference::tests::shared_laser_dir() else {
            return;
        };
        let log = LaserLog::read_file(&dir.join("intel.clf.bz2")).unwrap();
        let bytes = std::fs::read(dir.join("intel-corrected.log.gz")).unwrap();
        let direct =
            crate::grid::reference::LogReference::read(&bytes, "intel-corrected.log.gz", &log)
                .unwrap();
        let input = crate::grid::log_input(&log, "intel.clf.bz2");
        let through = input
            .reference_from(&bytes, "intel-corrected.log.gz")
            .unwrap();
        assert_eq!(direct.points.len(), 910);
        assert_eq!(through, direct);
        assert_eq!(through.points[0].scan, 169);
    }
}
