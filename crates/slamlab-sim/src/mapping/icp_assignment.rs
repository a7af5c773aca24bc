//! ICP assignments (`crate::coursework`'s [`Task`] of scan-matching tasks):
//! two laser scans of the mapping lesson's simulated robot, taken a variant's
//! number of steps apart, handed out as CSV points in each scan's own frame;
//! the student hands back their relative pose, scored as the two-view lesson
//! scores a relative pose (`metrics::relative_pose_error`: the rotation's
//! angle and the translation's direction) and by the translation's error in
//! metres (a laser scan, unlike a camera, measures the distance). The wheel
//! odometry between the scans is handed out too: ICP's start, and the naive
//! answer (the reference ICP starts from it).
//!
//! Convention (`io::relative_pose`, OpenCV's `recoverPose`): `X_b = R X_a + t`
//! turns a point of scan A's frame into scan B's. ICP's match of scan B
//! against scan A is `a_from_b`, the pose of B's frame in A's; `R, t` are its
//! inverse, as 3D: a rotation about z and `t = (x, y, 0)`.

use super::MappingScenario;
use super::scenario::simulated_log_config;
use crate::coursework::files::{InputFiles, number};
use crate::coursework::grade::{grade_relative_pose, relative_pose_hand_in};
use crate::coursework::{
    Assignment, CourseworkError, Grade, HandIn, InputFormat, Metric, Task, TaskKind, TaskRun,
    Variant, builtin_map_refusal, load_builtin_map, steps_refusal,
};
use crate::grid::simulate_log;
use crate::io::relative_pose::write_relative_pose;
use crate::metrics::{Trajectory, relative_pose_error};
use nalgebra::{Matrix3, Vector3};
use slamlab_core::laser::Point2;
use slamlab_core::scan::icp::{IcpConfig, align};
use slamlab_core::vision::RelativePose;
use slamlab_core::{Pose2, math, wrap_angle};
use std::fmt::Write as _;

/// The first scan the pair may start at: the explorer is under way by then.
pub const FIRST_SCAN: usize = 20;

/// The scans the pair may start at, after [`FIRST_SCAN`].
pub const WINDOW: usize = 100;

/// The most steps between the two scans.
pub const MAX_GAP: u64 = 200;

/// One student's pair of scans.
#[derive(Clone, Debug)]
pub struct IcpRun {
    /// The scenario (the student's seed in it).
    pub scenario: MappingScenario,
    /// Scan A's end points in its frame.
    pub scan_a: Vec<Point2>,
    /// Scan B's end points in its frame.
    pub scan_b: Vec<Point2>,
    /// The true pose of B's frame in A's.
    pub a_from_b: Pose2,
    /// The wheel odometry's `a_from_b` (handed out as the initial guess).
    pub odometry: Pose2,
    /// The reference ICP's `a_from_b` (point-to-line, from the odometry).
    pub icp: Option<Pose2>,
    /// The steps between the scans.
    pub gap: u64,
}

/// `X_b = R X_a + t` of a planar `a_from_b`.
pub fn relative_pose_of(a_from_b: &Pose2) -> RelativePose {
    let b_from_a = a_from_b.inverse();
    let (s, c) = math::sin_cos(b_from_a.theta);
    RelativePose {
        rotation: Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0),
        translation: Vector3::new(b_from_a.x, b_from_a.y, 0.0),
    }
}

fn points_csv(points: &[Point2]) -> String {
    let mut out = String::from("x,y\n");
    for p in points {
        let _ = writeln!(out, "{},{}", number(p[0]), number(p[1]));
    }
    out
}

/// The three errors of a relative pose against the truth: rotation (degrees),
/// translation (metres), translation direction (degrees; `None` when either
/// translation is zero).
pub fn errors(pose: &RelativePose, truth: &RelativePose) -> [Option<f64>; 3] {
    let e = relative_pose_error(
        &pose.rotation,
        &pose.translation,
        &truth.rotation,
        &truth.translation,
    );
    let rotation = {
        let r = truth.rotation.transpose() * pose.rotation;
        math::acos(((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0)).to_degrees()
    };
    [
        Some(rotation),
        Some((pose.translation - truth.translation).norm()),
        e.map(|e| e.translation_direction_deg),
    ]
}

impl IcpRun {
    /// Runs the lesson's robot through the built-in map for
    /// [`FIRST_SCAN`] + [`WINDOW`] + `gap` scans and takes the pair `gap`
    /// apart, starting in the window, over which the wheel odometry's heading
    /// drifts most (where scan matching earns its keep: a pair the odometry
    /// already gets right teaches nothing).
    pub fn simulate(
        scenario: &MappingScenario,
        map: &slamlab_core::grid::OccupancyGrid,
        gap: u64,
    ) -> Result<IcpRun, CourseworkError> {
        let config = simulated_log_config(scenario);
        let gap = gap as usize;
        let steps = FIRST_SCAN + WINDOW + gap + 1;
        let (log, truth) = simulate_log(map, steps, scenario.seed, &config)
            .map_err(|e| CourseworkError::Generate(format!("the robot's run: {e}")))?;
        let pair = |k: usize| {
            Some((
                (log.scans.get(k)?, truth.get(k)?),
                (log.scans.get(k + gap)?, truth.get(k + gap)?),
            ))
        };
        let drift = |k: usize| {
            pair(k).map_or(0.0, |(a, b)| {
                let odometry = a.0.odometry.between(&b.0.odometry);
                let true_motion = a.1.pose.between(&b.1.pose);
                wrap_angle(odometry.theta - true_motion.theta).abs()
            })
        };
        let start = (FIRST_SCAN..FIRST_SCAN + WINDOW)
            .max_by(|&i, &j| drift(i).total_cmp(&drift(j)))
            .unwrap_or(FIRST_SCAN);
        let Some((a, b)) = pair(start) else {
            return Err(CourseworkError::Generate(
                "the run has fewer scans than the pair needs".to_owned(),
            ));
        };
        let (scan_a, scan_b) = (a.0.scan.points(), b.0.scan.points());
        let a_from_b = a.1.pose.between(&b.1.pose);
        let odometry = a.0.odometry.between(&b.0.odometry);
        let icp = align(&scan_a, &scan_b, odometry, &IcpConfig::default())
            .ok()
            .map(|(m, _)| m.pose);
        Ok(IcpRun {
            scenario: scenario.clone(),
            scan_a,
            scan_b,
            a_from_b,
            odometry,
            icp,
            gap: gap as u64,
        })
    }
}

/// The starter code of ICP assignments.
pub const ICP_STARTER: &str = include_str!("icp_assignment_starter.py");

/// ICP tasks: the mapping lesson's parameter table checks the assignment's
/// parameters (the map must be a built-in one), and a variant is a pair of
/// the lesson's scans with the student's seed.
impl Task for IcpRun {
    const KIND: TaskKind = TaskKind::Icp;
    type Scenario = MappingScenario;

    fn refusals(assignment: &Assignment, scenario: &MappingScenario) -> Vec<String> {
        let limit = format!("an ICP assignment's scans are at most {MAX_GAP} steps apart");
        builtin_map_refusal(&scenario.map)
            .into_iter()
            .chain(steps_refusal(assignment, 0, MAX_GAP, &limit))
            .collect()
    }

    fn run(mut scenario: MappingScenario, seed: u64, steps: u64) -> Result<Self, CourseworkError> {
        scenario.seed = seed;
        let map = load_builtin_map(&scenario.map)?;
        IcpRun::simulate(&scenario, &map, steps)
    }
}

impl TaskRun for IcpRun {
    /// Scan A's frame at 0 and scan B's pose in it at 1.
    fn truth(&self) -> Trajectory {
        Trajectory::new(vec![0.0, 1.0], vec![Pose2::IDENTITY, self.a_from_b])
    }

    fn references(&self) -> Result<Vec<(String, Trajectory)>, CourseworkError> {
        let mut out = Vec::new();
        if let Some(icp) = self.icp {
            out.push((
                "icp".to_owned(),
                Trajectory::new(vec![0.0, 1.0], vec![Pose2::IDENTITY, icp]),
            ));
        }
        out.push((
            "odometry".to_owned(),
            Trajectory::new(vec![0.0, 1.0], vec![Pose2::IDENTITY, self.odometry]),
        ));
        Ok(out)
    }

    /// What the README says about the files.
    fn readme_body(&self, _inputs: &[InputFormat]) -> String {
        let s = &self.scenario;
        format!(
            "scan_a.csv, scan_b.csv  'x,y': the end points of one laser scan each (metres),\n\
             \x20 in that scan's own frame (the robot's: x forward, y left), one line per\n\
             \x20 beam that returned ({} beams over the full circle, range std {} m, no\n\
             \x20 return beyond {} m). Scan B was taken {} steps of 0.1 s after scan A by\n\
             \x20 the robot exploring a maze.\n\
             odometry.txt  'x y theta': scan B's pose in scan A's frame by the wheel\n\
             \x20 odometry (it drifts: a start for ICP, not the answer).\n\
             \n\
             Hand in R and t with X_b = R X_a + t: a point of scan A's frame in scan\n\
             B's frame (OpenCV's recoverPose convention; 3D, a rotation about z and\n\
             t = (x, y, 0)). If ICP gives you the pose (x, y, theta) of B's frame in\n\
             A's, R is the rotation by -theta and t = -R (x, y, 0).\n",
            s.beams,
            number(s.range_std),
            number(s.lidar_range),
            self.gap
        )
    }

    /// The files handed out: `scan_a.csv`, `scan_b.csv`, the README and the
    /// odometry, the starter code; with `answers`, `answers/relative_pose.txt`.
    fn files(&self, _inputs: &[InputFormat], readme: &str, answers: bool) -> InputFiles {
        let mut files = InputFiles::with_readme(readme);
        files.add("scan_a.csv", points_csv(&self.scan_a));
        files.add("scan_b.csv", points_csv(&self.scan_b));
        let o = self.odometry;
        files.add(
            "odometry.txt",
            format!(
                "# x y theta (m, m, rad): scan B's pose in scan A's frame by the wheel odometry\n{} {} {}\n",
                number(o.x),
                number(o.y),
                number(o.theta)
            ),
        );
        files.add("starter.py", ICP_STARTER);
        if answers {
            files.add(
                "answers/relative_pose.txt",
                write_relative_pose(&relative_pose_of(&self.a_from_b)),
            );
        }
        files
    }

    fn lesson_pairs(&self) -> Vec<(String, String)> {
        vec![("poses".to_owned(), "icp".to_owned())]
    }

    fn hand_in_text(&self, assignment: &Assignment, variant: &Variant) -> Option<String> {
        Some(relative_pose_hand_in(
            assignment,
            variant,
            "scans",
            "It is scored against the true relative pose of the two scans:",
        ))
    }

    fn grade(
        &self,
        hand_in: &HandIn<'_>,
        references: &[(String, Trajectory)],
    ) -> Result<Grade, CourseworkError> {
        let truth = relative_pose_of(&self.a_from_b);
        let theirs = references.iter().filter_map(|(name, t)| {
            let p = t.poses().get(1)?;
            Some((name.clone(), relative_pose_of(p)))
        });
        let value = |metric: Metric, e: &[Option<f64>; 3]| match metric {
            Metric::RotationErrorDeg => e[0],
            Metric::TranslationErrorM => e[1],
            Metric::TranslationDirectionErrorDeg => e[2],
            _ => None,
        };
        grade_relative_pose(hand_in, theirs, |p| errors(p, &truth), value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_relative_pose_turns_scan_a_points_into_scan_b() {
        let a_from_b = Pose2::new(0.4, -0.2, 0.3);
        let rp = relative_pose_of(&a_from_b);
        // A point of B's frame, seen in A's frame, back through R, t.
        let p_b = Pose2::new(1.5, 0.7, 0.0);
        let p_a = a_from_b.compose(&p_b);
        let back = rp.rotation * Vector3::new(p_a.x, p_a.y, 0.0) + rp.translation;
        assert!((back[0] - 1.5).abs() < 1e-12 && (back[1] - 0.7).abs() < 1e-12);
        assert_eq!(errors(&rp, &rp)[1], Some(0.0));
    }
}
