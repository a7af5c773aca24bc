//! An assignment as data: what an instructor writes in a JSON file (or picks
//! among the built-ins), read with refusals that say what to fix.
//!
//! ```json
//! {
//!   "id": "hw3",
//!   "lesson": "landmark-slam",
//!   "title": "EKF-SLAM on your own data",
//!   "task": "Implement EKF-SLAM with known correspondences ...",
//!   "scenario": { "steps": 600, "steps_spread": 100, "params": { "layout": "random" } },
//!   "inputs": ["freiburg", "velocity-csv"],
//!   "output": { "file": "estimate.tum", "format": "trajectory" },
//!   "alignment": "none",
//!   "criteria": [
//!     { "metric": "ate_rmse", "threshold": 0.35, "points": 70 },
//!     { "metric": "final_position_error", "threshold": 0.5, "points": 30 }
//!   ],
//!   "max_score": 100,
//!   "answers_included": false
//! }
//! ```
//!
//! `docs/assignments.md` lists every field, metric and built-in assignment.

use super::CourseworkError;
use crate::metrics::Alignment;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The largest assignment file read, in bytes (a task text of a few pages fits
/// many times over).
pub const MAX_ASSIGNMENT_BYTES: u64 = 256 * 1024;

/// The most steps an assignment's run may have.
pub const MAX_STEPS: u64 = 20_000;

/// The most criteria an assignment may have.
pub const MAX_CRITERIA: usize = 32;

/// What the student is asked to do, which decides the inputs they get, the
/// output they hand in and the metrics it can be scored by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TaskKind {
    /// Landmark SLAM (EKF-SLAM and kin) on odometry and range-bearing
    /// measurements; the output is the robot's trajectory.
    LandmarkSlam,
    /// Localization in a given map from odometry and laser scans (Monte Carlo
    /// localization); the output is the robot's trajectory.
    Localization,
    /// Least-squares optimization of a pose graph; the output is the optimized
    /// graph.
    PoseGraph,
    /// Occupancy-grid mapping with known poses; the output is the map (ROS
    /// map_server's YAML and PGM).
    GridMapping,
    /// Scan matching (ICP) of two laser scans; the output is their relative
    /// pose.
    Icp,
    /// Two-view geometry: the essential matrix with RANSAC from pixel matches
    /// and the intrinsics; the output is the relative pose of the two views.
    TwoView,
    /// Sensor fusion: wheel odometry, an IMU and a SLAM pose, one CSV per
    /// sensor; the output is the robot's trajectory.
    Fusion,
}

impl TaskKind {
    /// Every task kind.
    pub const ALL: [TaskKind; 7] = [
        TaskKind::LandmarkSlam,
        TaskKind::Localization,
        TaskKind::PoseGraph,
        TaskKind::GridMapping,
        TaskKind::Icp,
        TaskKind::TwoView,
        TaskKind::Fusion,
    ];

    /// The name in an assignment file.
    pub fn name(self) -> &'static str {
        match self {
            TaskKind::LandmarkSlam => "landmark-slam",
            TaskKind::Localization => "localization",
            TaskKind::PoseGraph => "pose-graph",
            TaskKind::GridMapping => "grid-mapping",
            TaskKind::Icp => "icp",
            TaskKind::TwoView => "two-view",
            TaskKind::Fusion => "fusion",
        }
    }

    /// The lesson a task of this kind opens in.
    pub fn lesson(self) -> &'static str {
        match self {
            TaskKind::LandmarkSlam => "landmark-slam",
            TaskKind::Localization => "kidnap",
            TaskKind::PoseGraph => "pose-graph",
            TaskKind::GridMapping | TaskKind::Icp => "mapping",
            TaskKind::TwoView => "visual-odometry",
            TaskKind::Fusion => "fusion",
        }
    }

    /// The kind of task a lesson's assignments are.
    pub fn of_lesson(lesson: &str) -> Option<TaskKind> {
        TaskKind::ALL.into_iter().find(|k| k.lesson() == lesson)
    }

    /// The input formats this kind can hand out.
    pub fn input_formats(self) -> &'static [InputFormat] {
        match self {
            TaskKind::LandmarkSlam => &[InputFormat::Freiburg, InputFormat::VelocityCsv],
            TaskKind::Localization => &[InputFormat::RosMap, InputFormat::CarmenLog],
            TaskKind::PoseGraph => &[InputFormat::G2o],
            TaskKind::GridMapping => &[InputFormat::CarmenLog],
            TaskKind::Icp => &[InputFormat::ScanCsv],
            TaskKind::TwoView => &[InputFormat::MatchesCsv],
            TaskKind::Fusion => &[InputFormat::SensorCsv],
        }
    }

    /// What the student hands in.
    pub fn output_format(self) -> OutputFormat {
        match self {
            TaskKind::LandmarkSlam | TaskKind::Localization | TaskKind::Fusion => {
                OutputFormat::Trajectory
            }
            TaskKind::PoseGraph => OutputFormat::G2o,
            TaskKind::GridMapping => OutputFormat::RosMap,
            TaskKind::Icp | TaskKind::TwoView => OutputFormat::RelativePose,
        }
    }

    /// The metrics an output of this kind can be scored by.
    pub fn metrics(self) -> &'static [Metric] {
        match self {
            TaskKind::LandmarkSlam | TaskKind::Localization | TaskKind::Fusion => &[
                Metric::AteRmse,
                Metric::AteMax,
                Metric::FinalPositionError,
                Metric::RpeTranslationRmse,
                Metric::RpeRotationRmseDeg,
            ],
            TaskKind::PoseGraph => &[Metric::CostRatio, Metric::AteRmse, Metric::AteMax],
            TaskKind::GridMapping => &[Metric::MapAgreement, Metric::MapCoverage],
            TaskKind::Icp => &[
                Metric::RotationErrorDeg,
                Metric::TranslationErrorM,
                Metric::TranslationDirectionErrorDeg,
            ],
            // A monocular t has no length: its direction alone is scored.
            TaskKind::TwoView => &[
                Metric::RotationErrorDeg,
                Metric::TranslationDirectionErrorDeg,
            ],
        }
    }
}

/// A file format of the inputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum InputFormat {
    /// The Freiburg Robot Mapping course's `world.dat` (`id x y`) and
    /// `sensor_data.dat` (`ODOMETRY r1 t r2`, `SENSOR id range bearing`), for the
    /// odometry motion model.
    Freiburg,
    /// `controls.csv` (`t,v,w`) and `measurements.csv` (`t,id,range,bearing`), for
    /// the velocity motion model.
    VelocityCsv,
    /// A ROS map: `map.yaml` and `map.pgm` (map_server's format).
    RosMap,
    /// A CARMEN log (`ODOM` and `FLASER` records) of the robot's run.
    CarmenLog,
    /// A g2o file (`VERTEX_SE2`, `EDGE_SE2`).
    G2o,
    /// Laser scans as CSV: `x,y`, one end point a line, in the sensor's frame.
    ScanCsv,
    /// Two views as `K.txt` (the 3x3 intrinsics) and `matches.csv`
    /// (`u1,v1,u2,v2`, pixels).
    MatchesCsv,
    /// One CSV per sensor (`odometry.csv`, `imu.csv`, `slam_pose.csv`), the
    /// time `t_s` first and each column's unit in its name.
    SensorCsv,
}

impl InputFormat {
    /// The name in an assignment file.
    pub fn name(self) -> &'static str {
        match self {
            InputFormat::Freiburg => "freiburg",
            InputFormat::VelocityCsv => "velocity-csv",
            InputFormat::RosMap => "ros-map",
            InputFormat::CarmenLog => "carmen-log",
            InputFormat::G2o => "g2o",
            InputFormat::ScanCsv => "scan-csv",
            InputFormat::MatchesCsv => "matches-csv",
            InputFormat::SensorCsv => "sensor-csv",
        }
    }
}

/// What the student hands in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OutputFormat {
    /// A trajectory: TUM (`t x y z qx qy qz qw`) or CSV (`t,x,y,theta`).
    Trajectory,
    /// An optimized pose graph in g2o format.
    G2o,
    /// An occupancy map: ROS map_server's YAML and the PGM (or PNG) it names,
    /// handed in together (a zip, or the YAML with its image beside it).
    RosMap,
    /// A relative pose: `R` (9 numbers) and `t` (3), or `t` and a quaternion
    /// (`io::relative_pose`).
    RelativePose,
}

impl OutputFormat {
    /// The name in an assignment file.
    pub fn name(self) -> &'static str {
        match self {
            OutputFormat::Trajectory => "trajectory",
            OutputFormat::G2o => "g2o",
            OutputFormat::RosMap => "ros-map",
            OutputFormat::RelativePose => "relative-pose",
        }
    }
}

/// Which side of the threshold passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Direction {
    /// The value passes when it is at most the threshold (an error).
    AtMost,
    /// The value passes when it is at least the threshold (an agreement).
    AtLeast,
}

impl Direction {
    /// `≤` or `≥`.
    pub fn symbol(self) -> &'static str {
        match self {
            Direction::AtMost => "≤",
            Direction::AtLeast => "≥",
        }
    }

    /// Whether `value` passes against `threshold` (NaN never passes).
    pub fn passes(self, value: f64, threshold: f64) -> bool {
        match self {
            Direction::AtMost => value <= threshold,
            Direction::AtLeast => value >= threshold,
        }
    }
}

/// A number an output is scored by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Metric {
    /// The absolute trajectory error's RMSE (evo's `evo_ape` translation part), metres.
    AteRmse,
    /// The largest absolute trajectory error, metres.
    AteMax,
    /// The position error at the last pose, metres.
    FinalPositionError,
    /// The relative pose error's translation RMSE over one step, metres.
    RpeTranslationRmse,
    /// The relative pose error's rotation RMSE over one step, degrees.
    RpeRotationRmseDeg,
    /// The optimized graph's cost divided by the reference solver's cost on the
    /// same graph (1 is as good as the reference).
    CostRatio,
    /// The share of the true map's free and occupied cells a map classifies
    /// the same, over the cells it knows (`grid::occupancy_agreement`, the
    /// mapping lesson's map agreement).
    MapAgreement,
    /// The share of the true map's free and occupied cells a map knows
    /// (`grid::occupancy_coverage`).
    MapCoverage,
    /// The angle of `R_trueᵀ R` of a relative pose, degrees
    /// (`metrics::relative_pose_error`).
    RotationErrorDeg,
    /// `‖t − t_true‖` of a relative pose, metres.
    TranslationErrorM,
    /// The angle between the estimated and the true direction of translation,
    /// degrees (`metrics::relative_pose_error`).
    TranslationDirectionErrorDeg,
}

impl Metric {
    /// Every metric.
    pub const ALL: [Metric; 11] = [
        Metric::AteRmse,
        Metric::AteMax,
        Metric::FinalPositionError,
        Metric::RpeTranslationRmse,
        Metric::RpeRotationRmseDeg,
        Metric::CostRatio,
        Metric::MapAgreement,
        Metric::MapCoverage,
        Metric::RotationErrorDeg,
        Metric::TranslationErrorM,
        Metric::TranslationDirectionErrorDeg,
    ];

    /// The name in an assignment file.
    pub fn name(self) -> &'static str {
        match self {
            Metric::AteRmse => "ate_rmse",
            Metric::AteMax => "ate_max",
            Metric::FinalPositionError => "final_position_error",
            Metric::RpeTranslationRmse => "rpe_translation_rmse",
            Metric::RpeRotationRmseDeg => "rpe_rotation_rmse_deg",
            Metric::CostRatio => "cost_ratio",
            Metric::MapAgreement => "map_agreement",
            Metric::MapCoverage => "map_coverage",
            Metric::RotationErrorDeg => "rotation_error_deg",
            Metric::TranslationErrorM => "translation_error_m",
            Metric::TranslationDirectionErrorDeg => "translation_direction_error_deg",
        }
    }

    /// What it is, for a student.
    pub fn label(self) -> &'static str {
        match self {
            Metric::AteRmse => "ATE RMSE",
            Metric::AteMax => "largest position error",
            Metric::FinalPositionError => "final position error",
            Metric::RpeTranslationRmse => "RPE translation RMSE (1 step)",
            Metric::RpeRotationRmseDeg => "RPE rotation RMSE (1 step)",
            Metric::CostRatio => "final cost / reference cost",
            Metric::MapAgreement => "map agreement with the true map",
            Metric::MapCoverage => "share of the true map covered",
            Metric::RotationErrorDeg => "rotation error",
            Metric::TranslationErrorM => "translation error",
            Metric::TranslationDirectionErrorDeg => "translation direction error",
        }
    }

    /// Its unit.
    pub fn unit(self) -> &'static str {
        match self {
            Metric::AteRmse
            | Metric::AteMax
            | Metric::FinalPositionError
            | Metric::RpeTranslationRmse => "m",
            Metric::RpeRotationRmseDeg
            | Metric::RotationErrorDeg
            | Metric::TranslationDirectionErrorDeg => "deg",
            Metric::TranslationErrorM => "m",
            Metric::CostRatio | Metric::MapAgreement | Metric::MapCoverage => "",
        }
    }

    /// Which side of a threshold is good: an error or a cost passes at or
    /// below it, an agreement or a coverage at or above.
    pub fn direction(self) -> Direction {
        match self {
            Metric::MapAgreement | Metric::MapCoverage => Direction::AtLeast,
            _ => Direction::AtMost,
        }
    }
}

/// One criterion: a metric, its threshold and the points a pass earns.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Criterion {
    /// The metric.
    pub metric: Metric,
    /// The pass threshold, in the metric's unit.
    pub threshold: f64,
    /// The points a pass earns.
    pub points: f64,
    /// Which side passes; the metric's own when left out (giving the other one
    /// is refused).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<Direction>,
}

impl Criterion {
    /// The side of the threshold that passes.
    pub fn direction(&self) -> Direction {
        self.direction.unwrap_or(self.metric.direction())
    }
}

/// The run the inputs come from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioSpec {
    /// Steps of the run (ticks of the lesson; poses of a pose graph).
    pub steps: u64,
    /// Each student's run is `steps + (seed mod (steps_spread + 1))` steps long,
    /// so that an estimate made for another student's variant shows in its
    /// length and last time. 0: every variant is equally long.
    #[serde(default)]
    pub steps_spread: u64,
    /// The lesson's parameters, as in its URL and `slamlab params --lesson ID`
    /// (numbers or text); the seed comes from the student.
    #[serde(default)]
    pub params: BTreeMap<String, serde_json::Value>,
}

/// What the student hands in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// The file name the task asks for (any name is graded; this one is shown).
    pub file: String,
    /// Its format; must be the task kind's.
    pub format: OutputFormat,
}

/// An assignment, as its JSON file holds it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Assignment {
    /// A short name (letters, digits, `-` and `_`), part of every student's seed.
    pub id: String,
    /// The lesson the assignment opens in (`landmark-slam`, `kidnap`, `pose-graph`,
    /// `mapping`).
    pub lesson: String,
    /// The task's kind; the lesson's when left out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<TaskKind>,
    /// A title.
    pub title: String,
    /// The task, as the student reads it (plain text; blank lines part paragraphs).
    pub task: String,
    /// The run the inputs come from.
    pub scenario: ScenarioSpec,
    /// The input formats handed out.
    pub inputs: Vec<InputFormat>,
    /// What the student hands in.
    pub output: OutputSpec,
    /// How a trajectory is aligned to the truth before it is scored: `none` (the
    /// start pose is given, the estimate is in the map's frame), `se2` or `sim2`.
    #[serde(default = "default_alignment")]
    pub alignment: String,
    /// What is scored.
    pub criteria: Vec<Criterion>,
    /// The points of all criteria together; checked against them when given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_score: Option<f64>,
    /// The score that passes; every criterion's points when left out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pass_score: Option<f64>,
    /// Whether *Download inputs* in the page includes `answers/` (the true
    /// trajectory and map). `slamlab export-inputs --answers` always does.
    #[serde(default)]
    pub answers_included: bool,
}

fn default_alignment() -> String {
    "none".to_owned()
}

impl Assignment {
    /// The task's kind (checked by [`Assignment::validate`]).
    pub fn task_kind(&self) -> Option<TaskKind> {
        self.kind.or_else(|| TaskKind::of_lesson(&self.lesson))
    }

    /// The alignment (checked by [`Assignment::validate`]).
    pub fn alignment(&self) -> Alignment {
        Alignment::from_name(&self.alignment).unwrap_or(Alignment::None)
    }

    /// The points of all criteria.
    pub fn max_score(&self) -> f64 {
        self.criteria.iter().map(|c| c.points).sum()
    }

    /// The score that passes.
    pub fn pass_score(&self) -> f64 {
        self.pass_score.unwrap_or_else(|| self.max_score())
    }

    /// The steps of one variant's run: `steps + seed mod (steps_spread + 1)`.
    pub fn steps_for(&self, seed: u64) -> u64 {
        let spread = self.scenario.steps_spread;
        self.scenario.steps + seed % spread.saturating_add(1)
    }

    /// The lesson's parameters as `(name, value)` text pairs.
    pub fn param_pairs(&self) -> Vec<(String, String)> {
        self.scenario
            .params
            .iter()
            .map(|(k, v)| {
                let text = match v {
                    serde_json::Value::String(s) => s.clone(),
                    other => other.to_string(),
                };
                (k.clone(), text)
            })
            .collect()
    }

    /// Checks what serde cannot: the kind against the lesson, the inputs and
    /// metrics against the kind, thresholds, points and the score, and the
    /// lesson's parameters (`check_params` applies them to the lesson's table and
    /// returns what it refused).
    pub fn validate(
        &self,
        check_params: impl Fn(&Assignment) -> Vec<String>,
    ) -> Result<(), CourseworkError> {
        let bad = |message: String| Err(CourseworkError::BadAssignment(message));
        if self.id.is_empty()
            || self.id.len() > 64
            || !self
                .id
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return bad(format!(
                "id {:?}: 1 to 64 letters, digits, '-' or '_'",
                self.id
            ));
        }
        let Some(kind) = self.task_kind() else {
            let lessons: Vec<&str> = TaskKind::ALL.iter().map(|k| k.lesson()).collect();
            return bad(format!(
                "lesson {:?} has no assignments; lessons with assignments: {}",
                self.lesson,
                lessons.join(", ")
            ));
        };
        if kind.lesson() != self.lesson {
            return bad(format!(
                "kind {:?} is done in the lesson {:?}, not {:?}",
                kind.name(),
                kind.lesson(),
                self.lesson
            ));
        }
        if self.title.trim().is_empty() {
            return bad("the title is empty".to_owned());
        }
        if self.task.trim().is_empty() {
            return bad("the task text is empty".to_owned());
        }
        let steps = self.scenario.steps;
        if !(1..=MAX_STEPS).contains(&steps) || self.scenario.steps_spread > MAX_STEPS - steps {
            return bad(format!(
                "scenario.steps {steps} with steps_spread {}: the run must have 1 to {MAX_STEPS} steps",
                self.scenario.steps_spread
            ));
        }
        if self.inputs.is_empty() {
            return bad("inputs is empty: name at least one input format".to_owned());
        }
        for input in &self.inputs {
            if !kind.input_formats().contains(input) {
                return bad(format!(
                    "input format {:?} is not one a {} task hands out ({})",
                    input.name(),
                    kind.name(),
                    names(kind.input_formats().iter().map(|f| f.name()))
                ));
            }
        }
        if self.output.format != kind.output_format() {
            return bad(format!(
                "output format {:?}: a {} task's output is {:?}",
                self.output.format.name(),
                kind.name(),
                kind.output_format().name()
            ));
        }
        if self.output.file.trim().is_empty() || self.output.file.contains(['/', '\\']) {
            return bad(format!(
                "output file {:?}: a plain file name",
                self.output.file
            ));
        }
        if Alignment::from_name(&self.alignment).is_none() {
            return bad(format!(
                "alignment {:?}: one of none, se2, sim2",
                self.alignment
            ));
        }
        if self.criteria.is_empty() || self.criteria.len() > MAX_CRITERIA {
            return bad(format!(
                "{} criteria: an assignment scores 1 to {MAX_CRITERIA}",
                self.criteria.len()
            ));
        }
        for (k, c) in self.criteria.iter().enumerate() {
            let which = format!("criterion {} ({})", k + 1, c.metric.name());
            if !kind.metrics().contains(&c.metric) {
                return bad(format!(
                    "{which}: a {} task has no such metric; it has {}",
                    kind.name(),
                    names(kind.metrics().iter().map(|m| m.name()))
                ));
            }
            if !(c.threshold >= 0.0 && c.threshold.is_finite()) {
                return bad(format!(
                    "{which}: threshold {}: must be a finite number at least 0",
                    c.threshold
                ));
            }
            if !(c.points > 0.0 && c.points.is_finite()) {
                return bad(format!(
                    "{which}: points {}: must be a positive number",
                    c.points
                ));
            }
            if let Some(d) = c.direction
                && d != c.metric.direction()
            {
                return bad(format!(
                    "{which}: direction {:?} contradicts the metric, which passes when it is {} the threshold",
                    d,
                    c.metric.direction().symbol()
                ));
            }
        }
        let total = self.max_score();
        if let Some(max) = self.max_score
            && (max - total).abs() > 1e-9 * total.max(1.0)
        {
            return bad(format!(
                "max_score {max} but the criteria's points add up to {total}"
            ));
        }
        if let Some(pass) = self.pass_score
            && !(pass >= 0.0 && pass <= total)
        {
            return bad(format!(
                "pass_score {pass}: must be between 0 and the criteria's {total} points"
            ));
        }
        let refused = check_params(self);
        if !refused.is_empty() {
            return bad(format!("scenario.params: {}", refused.join("; ")));
        }
        Ok(())
    }
}

fn names<'a>(it: impl Iterator<Item = &'a str>) -> String {
    it.collect::<Vec<_>>().join(", ")
}

/// Reads an assignment JSON file: refused over [`MAX_ASSIGNMENT_BYTES`], on a
/// missing, unknown or mistyped field (serde names it with its line), and on
/// whatever [`Assignment::validate`] refuses (the lesson's parameters checked by
/// the runner of the task's kind among `runners`).
pub fn read_assignment(
    name: &str,
    bytes: &[u8],
    runners: &[super::TaskRunner],
) -> Result<Assignment, CourseworkError> {
    if bytes.len() as u64 > MAX_ASSIGNMENT_BYTES {
        return Err(CourseworkError::BadAssignment(format!(
            "{name}: {} bytes, more than the {MAX_ASSIGNMENT_BYTES} an assignment file may have",
            bytes.len()
        )));
    }
    let assignment: Assignment = serde_json::from_slice(bytes)
        .map_err(|e| CourseworkError::BadAssignment(format!("{name}: not an assignment: {e}")))?;
    assignment
        .validate(|a| super::check_params(a, runners))
        .map_err(|e| match e {
            CourseworkError::BadAssignment(m) => {
                CourseworkError::BadAssignment(format!("{name}: {m}"))
            }
            other => other,
        })?;
    Ok(assignment)
}
