//! Grid-mapping assignments (`crate::coursework`'s [`Task`] of grid-mapping
//! tasks): occupancy-grid mapping with known poses. One student's run of the
//! mapping lesson's simulated robot is handed out as a CARMEN log whose scans
//! carry their true poses (and the same poses as CSV) with the true map's size
//! and resolution; the student hands back a ROS map (YAML and PGM), scored by
//! the mapping lesson's map agreement with the true map and by how much of the
//! true map it covers.
//!
//! The reference is the lesson's own mapping with true poses: every scan of the
//! log as read back (ranges printed to 1 mm) inserted at its true pose with the
//! lesson's update rule, read out at the true map's cells (occupied above
//! probability 0.5, free below: exactly `grid::map_agreement`'s classes).

use super::MappingScenario;
use super::scenario::simulated_log_config;
use crate::coursework::files::{InputFiles, number};
use crate::coursework::grade::{assemble_scores, grade_command};
use crate::coursework::{
    Assignment, CourseworkError, Grade, HandIn, InputFormat, Metric, Task, TaskKind, TaskRun,
    Variant, builtin_map_refusal, load_builtin_map, steps_refusal,
};
use crate::grid::{occupancy_agreement, occupancy_coverage, simulate_log};
use crate::io::laser_log::{LaserLog, write_carmen};
use crate::io::map_archive::read_map_zip;
use crate::io::ros_map::{ImageFormat, export_map};
use crate::io::trajectory::{write_csv, write_tum};
use crate::metrics::Trajectory;
use slamlab_core::grid::{Cell, OccupancyGrid, ProbabilityGrid};
use std::fmt::Write as _;

/// The most steps a grid-mapping assignment's run may have.
pub const MAX_MAPPING_STEPS: u64 = 5000;

/// One student's mapping run: the log and poses handed out, the true map and
/// the reference map.
#[derive(Clone, Debug)]
pub struct GridMappingRun {
    /// The scenario (the student's seed in it).
    pub scenario: MappingScenario,
    /// `robot.log`.
    pub log_text: String,
    /// The log as read back from `log_text`.
    pub log: LaserLog,
    /// The true pose at each scan.
    pub truth: Trajectory,
    /// The true map.
    pub true_map: OccupancyGrid,
    /// The reference map (the lesson's mapping with true poses) on the true
    /// map's cells.
    pub reference_map: OccupancyGrid,
}

impl GridMappingRun {
    /// Runs the lesson's robot for `steps` scans through the built-in map and
    /// maps its log with the true poses.
    pub fn simulate(
        scenario: &MappingScenario,
        true_map: OccupancyGrid,
        steps: u64,
    ) -> Result<GridMappingRun, CourseworkError> {
        let config = simulated_log_config(scenario);
        let (mut log, truth) = simulate_log(&true_map, steps as usize, scenario.seed, &config)
            .map_err(|e| CourseworkError::Generate(format!("the robot's run: {e}")))?;
        // Known poses: each scan's laser pose is the true one (CARMEN's FLASER
        // "x y theta"); its odometry fields keep the drifting odometry.
        for (scan, t) in log.scans.iter_mut().zip(&truth) {
            scan.laser_pose = Some(t.pose);
        }
        let log_text =
            write_carmen(&log).map_err(|e| CourseworkError::Generate(format!("the log: {e}")))?;
        let log = LaserLog::from_bytes(log_text.as_bytes())
            .map_err(|e| CourseworkError::Generate(format!("the log read back: {e}")))?;
        let mut path = Trajectory::default();
        for s in &log.scans {
            path.push(s.timestamp, s.laser_pose(), None);
        }
        let reference_map = reference_map(scenario, &log, &true_map)?;
        Ok(GridMappingRun {
            scenario: scenario.clone(),
            log_text,
            log,
            truth: path,
            true_map,
            reference_map,
        })
    }

    /// `(map.yaml, map.pgm)` of a grid.
    fn ros_map(grid: &OccupancyGrid) -> (String, Vec<u8>) {
        export_map(grid, "map.pgm", ImageFormat::Pgm).unwrap_or_default()
    }

    /// The naive map of the starter code: every cell of the true map's extent
    /// free (what a program that ignores the scans can say).
    pub fn all_free_map(&self) -> OccupancyGrid {
        let m = &self.true_map;
        OccupancyGrid::new(
            m.width(),
            m.height(),
            m.resolution(),
            m.origin(),
            vec![Cell::Free; m.width() * m.height()],
        )
        .unwrap_or_else(|_| m.clone())
    }

    /// The map's score: agreement and coverage against the true map.
    pub fn score(&self, map: &OccupancyGrid) -> (Option<f64>, Option<f64>) {
        (
            occupancy_agreement(map, &self.true_map),
            occupancy_coverage(map, &self.true_map),
        )
    }
}

/// The lesson's occupancy mapping with known poses: every scan of `log` at its
/// laser pose (the true one) into a probability grid of the true map's
/// resolution with the scenario's update rule, read out at the true map's cells:
/// occupied above probability 0.5, free below, unknown where never observed.
pub fn reference_map(
    scenario: &MappingScenario,
    log: &LaserLog,
    true_map: &OccupancyGrid,
) -> Result<OccupancyGrid, CourseworkError> {
    let mut grid = ProbabilityGrid::new(true_map.resolution());
    let params = scenario.insert_params();
    for s in &log.scans {
        grid.insert_scan(&s.laser_pose(), &s.scan, &params)
            .map_err(|e| CourseworkError::Generate(format!("the reference map: {e}")))?;
    }
    let (w, h) = (true_map.width(), true_map.height());
    let mut cells = vec![Cell::Unknown; w * h];
    for j in 0..h {
        for i in 0..w {
            let (x, y) = true_map.cell_center(i as i64, j as i64);
            let (bi, bj) = grid.cell_of(x, y);
            if let Some(l) = grid.log_odds_at(bi, bj).filter(|l| *l != 0.0) {
                cells[j * w + i] = if l > 0.0 { Cell::Occupied } else { Cell::Free };
            }
        }
    }
    OccupancyGrid::new(w, h, true_map.resolution(), true_map.origin(), cells)
        .map_err(|e| CourseworkError::Generate(format!("the reference map: {e}")))
}

/// The starter code of grid-mapping assignments.
pub const GRID_MAPPING_STARTER: &str = include_str!("assignment_starter.py");

/// Grid-mapping tasks: the mapping lesson's parameter table checks the
/// assignment's parameters (the map must be a built-in one), and a variant is
/// the lesson's robot run with the student's seed, mapped with the true poses.
impl Task for GridMappingRun {
    const KIND: TaskKind = TaskKind::GridMapping;
    type Scenario = MappingScenario;

    fn refusals(assignment: &Assignment, scenario: &MappingScenario) -> Vec<String> {
        let mut refused: Vec<String> = builtin_map_refusal(&scenario.map).into_iter().collect();
        let pairs = assignment.param_pairs();
        for name in ["steps", "poses"] {
            if pairs.iter().any(|(k, _)| k == name) {
                refused.push(format!(
                    "{name}: an assignment's scans are its scenario.steps, with the true poses"
                ));
            }
        }
        refused.extend(steps_refusal(
            assignment,
            0,
            MAX_MAPPING_STEPS,
            &format!("a grid-mapping assignment has at most {MAX_MAPPING_STEPS} scans"),
        ));
        refused
    }

    fn run(mut scenario: MappingScenario, seed: u64, steps: u64) -> Result<Self, CourseworkError> {
        scenario.seed = seed;
        let map = load_builtin_map(&scenario.map)?;
        GridMappingRun::simulate(&scenario, map, steps)
    }
}

impl TaskRun for GridMappingRun {
    fn truth(&self) -> Trajectory {
        self.truth.clone()
    }

    /// The poses the maps were made from (a mapping task has no estimated
    /// trajectory): the true ones.
    fn references(&self) -> Result<Vec<(String, Trajectory)>, CourseworkError> {
        Ok(vec![("known-poses".to_owned(), self.truth.clone())])
    }

    /// What the README says about the files.
    fn readme_body(&self, _inputs: &[InputFormat]) -> String {
        let s = &self.scenario;
        let m = &self.true_map;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "The run: {} scans, dt = 0.1 s; a round robot explores the map. Frames: ROS\n\
             REP-103 (x forward, y left, angles counter-clockwise), metres, radians,\n\
             seconds; the map's frame is the world's.\n\
             \n\
             robot.log     a CARMEN log. 'FLASER n r1 .. rn x y theta odom_x odom_y\n\
             \x20             odom_theta ts host ts': a scan of n = {} ranges (metres, printed\n\
             \x20             to 1 mm) over the full circle, the first beam at -fov/2 and the\n\
             \x20             others the resolution apart (the PARAM lines give\n\
             \x20             laser_front_laser_fov and _resolution in degrees and\n\
             \x20             robot_front_laser_max in metres: a reading at {} m or more is no\n\
             \x20             return, free space along it but no hit), taken at the robot's\n\
             \x20             centre. x y theta is the robot's TRUE pose at the scan (known\n\
             \x20             poses); odom_* is the drifting wheel odometry (not needed).\n\
             poses.csv     t,x,y,theta: the same true poses, one line per scan.\n\
             map_spec.txt  the true map's resolution ({} m), width and height ({} x {}\n\
             \x20             cells) and origin (the world position of cell (0, 0)'s corner).\n\
             \x20             Write your map on this grid (any grid is read: each true cell\n\
             \x20             is looked up in your map at its centre).\n\
             \n\
             Noise: range std {} m.\n",
            self.truth.len(),
            self.log.beams().unwrap_or(0),
            number(s.lidar_range),
            number(m.resolution()),
            m.width(),
            m.height(),
            number(s.range_std),
        );
        out
    }

    /// The files handed out: `robot.log`, `poses.csv`, `map_spec.txt`, the
    /// README and the starter code; with `answers`, `answers/truth.tum`, the
    /// true map and the reference map (each `.yaml` with its `.pgm`).
    fn files(&self, _inputs: &[InputFormat], readme: &str, answers: bool) -> InputFiles {
        let mut files = InputFiles::with_readme(readme);
        files.add("robot.log", &self.log_text);
        files.add("poses.csv", write_csv(&self.truth));
        let m = &self.true_map;
        let o = m.origin();
        files.add(
            "map_spec.txt",
            format!(
                "# resolution (m per cell), width and height (cells), origin x y theta (m, m, rad)\n\
                 {} {} {} {} {} {}\n",
                number(m.resolution()),
                m.width(),
                m.height(),
                number(o.x),
                number(o.y),
                number(o.theta)
            ),
        );
        files.add("starter.py", GRID_MAPPING_STARTER);
        if answers {
            files.add("answers/truth.tum", write_tum(&self.truth));
            let (yaml, pgm) = Self::ros_map(&self.true_map);
            files.add(
                "answers/true_map.yaml",
                yaml.replace("map.pgm", "true_map.pgm"),
            );
            files.add("answers/true_map.pgm", pgm);
            let (yaml, pgm) = Self::ros_map(&self.reference_map);
            files.add(
                "answers/reference.yaml",
                yaml.replace("map.pgm", "reference.pgm"),
            );
            files.add("answers/reference.pgm", pgm);
        }
        files
    }

    fn lesson_pairs(&self) -> Vec<(String, String)> {
        vec![
            ("poses".to_owned(), "truth".to_owned()),
            ("steps".to_owned(), self.truth.len().to_string()),
        ]
    }

    fn hand_in_text(&self, assignment: &Assignment, variant: &Variant) -> Option<String> {
        Some(format!(
            "{file}: your occupancy map as a ROS map_server map, map.yaml and the map.pgm\n\
             it names ('image: map.pgm', resolution, origin; black occupied, white free,\n\
             grey 205 unknown), the two files zipped together. Check it with\n\
             \x20 {check}\n\
             (or --estimate map.yaml, with map.pgm beside it).\n\n\
             It is scored against the true map: each of the true map's free and\n\
             occupied cells is looked up in your map at its centre; the agreement is\n\
             the share of those your map knows (free or occupied) that it classifies as\n\
             the true map does, the coverage the share it knows at all:",
            file = assignment.output.file,
            check = grade_command(assignment, variant),
        ))
    }

    fn grade(
        &self,
        hand_in: &HandIn<'_>,
        _references: &[(String, Trajectory)],
    ) -> Result<Grade, CourseworkError> {
        let (map, _) =
            read_map_zip(hand_in.file_name, hand_in.bytes).map_err(CourseworkError::BadEstimate)?;
        let value =
            |metric: Metric, &(agreement, coverage): &(Option<f64>, Option<f64>)| match metric {
                Metric::MapAgreement => agreement,
                Metric::MapCoverage => coverage,
                _ => None,
            };
        let mine = self.score(&map);
        let references = [
            (
                "known-poses mapping".to_owned(),
                self.score(&self.reference_map),
            ),
            ("all free".to_owned(), self.score(&self.all_free_map())),
        ];
        let notices = vec![format!(
            "{}: a map of {} x {} cells of {} m",
            hand_in.file_name,
            map.width(),
            map.height(),
            map.resolution()
        )];
        Ok(assemble_scores(hand_in, &mine, &references, value, notices))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{BuiltinMap, map_agreement};

    #[test]
    fn the_reference_map_scores_the_lessons_map_agreement() {
        let scenario = MappingScenario {
            seed: 5,
            ..MappingScenario::default()
        };
        let map = BuiltinMap::Maze.load().unwrap();
        let run = GridMappingRun::simulate(&scenario, map.clone(), 300).unwrap();
        // The lesson's probability grid from the same scans at the same poses.
        let mut grid = ProbabilityGrid::new(map.resolution());
        for s in &run.log.scans {
            grid.insert_scan(&s.laser_pose(), &s.scan, &scenario.insert_params())
                .unwrap();
        }
        let lesson = map_agreement(&grid, &map).unwrap();
        let (agreement, coverage) = run.score(&run.reference_map);
        assert_eq!(agreement, Some(lesson));
        assert!(lesson > 0.9, "{lesson}");
        assert!(coverage.unwrap() > 0.1 && coverage.unwrap() < 1.0);
        // The scans' laser poses are the truth, to the log's printed precision.
        let first = run.log.scans[0].laser_pose();
        let t = run.truth.poses()[0];
        assert!((first.x - t.x).abs() < 1e-12 && (first.theta - t.theta).abs() < 1e-12);
        // The all-free map covers every known cell of the true map.
        assert_eq!(run.score(&run.all_free_map()).1, Some(1.0));
    }
}
