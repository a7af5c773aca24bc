//! The grade of one handed-in file: each criterion with the student's value, the
//! threshold, the points and pass or fail, beside the reference estimators'
//! values on the same variant; the score; and the SHA-256 of the file, so a
//! report names exactly what was graded.

use super::CourseworkError;
use super::assignment::{Assignment, Metric};
use super::variant::{Variant, sha256_hex};
use crate::io::relative_pose::read_relative_pose;
use crate::io::trajectory::{check_size, read_trajectory};
use crate::metrics::{Evaluation, EvaluationSettings, Trajectory, evaluate};
use serde::Serialize;
use slamlab_core::vision::RelativePose;

/// A reference estimator's value of a criterion's metric.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReferenceValue {
    /// The estimator (`ekf`, `dead-reckoning`, `mcl`, `odometry`, ...).
    pub name: String,
    /// Its value; `None` when it has none.
    pub value: Option<f64>,
    /// Whether it would pass.
    pub pass: bool,
}

/// One criterion, graded.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CriterionGrade {
    /// The metric's name (`ate_rmse`).
    pub metric: String,
    /// What it is (`ATE RMSE`).
    pub label: String,
    /// Its unit.
    pub unit: String,
    /// The student's value; `None` when it cannot be computed.
    pub value: Option<f64>,
    /// The threshold.
    pub threshold: f64,
    /// `at-most` or `at-least`.
    pub direction: String,
    /// The points a pass earns.
    pub points: f64,
    /// The points earned.
    pub earned: f64,
    /// Whether it passes.
    pub pass: bool,
    /// The reference estimators' values on the same variant.
    pub references: Vec<ReferenceValue>,
}

impl CriterionGrade {
    /// One line for a student: `ATE RMSE 0.213 m ≤ 0.35 m: pass, 70 of 70 points`.
    pub fn summary(&self) -> String {
        let value = self
            .value
            .map_or("no value".to_owned(), |v| format_value(v, &self.unit));
        let sign = if self.direction == "at-least" {
            "≥"
        } else {
            "≤"
        };
        format!(
            "{} {value} (pass: {sign} {}): {}, {} of {} points",
            self.label,
            format_value(self.threshold, &self.unit),
            if self.pass { "pass" } else { "fail" },
            trim_number(self.earned),
            trim_number(self.points)
        )
    }

    /// The reference estimators' values on the student's variant, for a
    /// student: `ekf 0.2130 m, dead-reckoning 1.204 m` (`-` where one has none).
    pub fn references_summary(&self) -> String {
        let values: Vec<String> = self
            .references
            .iter()
            .map(|r| {
                let value = r
                    .value
                    .map_or("-".to_owned(), |v| format_value(v, &self.unit));
                format!("{} {value}", r.name)
            })
            .collect();
        values.join(", ")
    }
}

/// A value with its unit, four significant figures.
pub fn format_value(v: f64, unit: &str) -> String {
    let text = if v == 0.0 || (1e-3..1e5).contains(&v.abs()) {
        let a = v.abs();
        let digits = match a {
            _ if a == 0.0 || a >= 1000.0 => 0,
            _ if a >= 100.0 => 1,
            _ if a >= 10.0 => 2,
            _ if a >= 1.0 => 3,
            _ if a >= 0.1 => 4,
            _ if a >= 0.01 => 5,
            _ => 6,
        };
        format!("{v:.digits$}")
    } else {
        format!("{v:.3e}")
    };
    if unit.is_empty() {
        text
    } else {
        format!("{text} {unit}")
    }
}

fn trim_number(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        format!("{v}")
    }
}

/// A graded file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Grade {
    /// The assignment's id.
    pub assignment: String,
    /// Its title.
    pub title: String,
    /// The student, as given.
    pub student: String,
    /// The variant's code.
    pub variant: String,
    /// The variant's seed.
    pub seed: u64,
    /// The graded file's name.
    pub estimate_file: String,
    /// The SHA-256 of its bytes.
    pub estimate_sha256: String,
    /// Its size in bytes.
    pub estimate_bytes: usize,
    /// Each criterion.
    pub criteria: Vec<CriterionGrade>,
    /// The points earned.
    pub score: f64,
    /// The points of all criteria.
    pub max_score: f64,
    /// The score that passes.
    pub pass_score: f64,
    /// Whether the score passes.
    pub pass: bool,
    /// What the grader had to say (the evaluation's overlap, dropped poses).
    pub notices: Vec<String>,
}

impl Grade {
    /// Gradescope's `results.json`: the score, the maximum, and one test per
    /// criterion with its output (Gradescope autograder specification).
    pub fn gradescope(&self) -> serde_json::Value {
        let tests: Vec<serde_json::Value> = self
            .criteria
            .iter()
            .map(|c| {
                serde_json::json!({
                    "name": format!("{} ({})", c.label, c.metric),
                    "score": c.earned,
                    "max_score": c.points,
                    "status": if c.pass { "passed" } else { "failed" },
                    "output": format!("{}\nReferences on your variant: {}.", c.summary(), c.references_summary()),
                })
            })
            .collect();
        serde_json::json!({
            "score": self.score,
            "max_score": self.max_score,
            "output": format!(
                "{}: variant {} of {}; graded {} (SHA-256 {}).{}",
                self.title,
                self.variant,
                self.student,
                self.estimate_file,
                self.estimate_sha256,
                if self.notices.is_empty() { String::new() } else { format!(" {}", self.notices.join(" ")) }
            ),
            "tests": tests,
        })
    }
}

/// The settings trajectories are scored with: evo's association tolerance, the
/// assignment's alignment, RPE over one step.
pub fn trajectory_settings(assignment: &Assignment) -> EvaluationSettings {
    EvaluationSettings {
        alignment: assignment.alignment(),
        ..EvaluationSettings::default()
    }
}

/// A trajectory metric of an evaluation.
pub fn trajectory_metric(metric: Metric, e: &Evaluation) -> Option<f64> {
    match metric {
        Metric::AteRmse => Some(e.ape.translation.rmse),
        Metric::AteMax => Some(e.ape.translation.max),
        Metric::FinalPositionError => e.ape.translation_m.last().copied(),
        Metric::RpeTranslationRmse => e.rpe.as_ref().map(|r| r.translation.rmse),
        Metric::RpeRotationRmseDeg => e.rpe.as_ref().map(|r| r.rotation.rmse),
        _ => None,
    }
}

/// Refuses an estimate that cannot be for this variant: one that ends after or
/// well before the variant's run (its times say which run it was made for).
pub fn check_times(
    truth: &Trajectory,
    estimate: &Trajectory,
    max_diff: f64,
) -> Result<Vec<String>, CourseworkError> {
    let (Some((_, end)), Some((first, last))) = (truth.span(), estimate.span()) else {
        return Err(CourseworkError::BadEstimate(
            "the estimate holds no pose".to_owned(),
        ));
    };
    let describe = |t: &Trajectory| {
        t.span().map_or(String::new(), |(a, b)| {
            format!("{} poses from {a:.3} to {b:.3} s", t.len())
        })
    };
    if last > end + max_diff {
        return Err(CourseworkError::OtherVariant(format!(
            "the estimate has {}, past the end of your variant's run ({}): it was made for another student's variant or another assignment; download your own inputs (student= your id) and run your program on them",
            describe(estimate),
            describe(truth)
        )));
    }
    if last < end - max_diff {
        return Err(CourseworkError::OtherVariant(format!(
            "the estimate has {}, but your variant's run goes on to {end:.3} s ({}): it is cut short, or was made for another student's variant; write one pose per step up to the end",
            describe(estimate),
            describe(truth)
        )));
    }
    let mut notices = Vec::new();
    if first > truth.span().map_or(0.0, |s| s.0) + max_diff {
        notices.push(format!(
            "the estimate starts at {first:.3} s; it is scored from there"
        ));
    }
    Ok(notices)
}

/// Grades a trajectory file against the variant's truth, beside the references.
pub fn grade_trajectory(
    hand_in: &HandIn<'_>,
    truth: &Trajectory,
    references: &[(String, Trajectory)],
) -> Result<Grade, CourseworkError> {
    check_size(hand_in.bytes.len() as u64).map_err(|e| hand_in.bad(e))?;
    let file = read_trajectory(hand_in.file_name, hand_in.bytes).map_err(|e| hand_in.bad(e))?;
    let settings = trajectory_settings(hand_in.assignment);
    let mut notices = check_times(truth, &file.trajectory, settings.max_diff)
        .map_err(|e| e.in_file(hand_in.file_name))?;
    notices.extend(hand_in.notices(&file.notices));
    let evaluation = evaluate(truth, &file.trajectory, &settings).map_err(|e| hand_in.bad(e))?;
    notices.extend(evaluation.notices.iter().cloned());
    let theirs: Vec<(String, Option<Evaluation>)> = references
        .iter()
        .map(|(name, t)| (name.clone(), evaluate(truth, t, &settings).ok()))
        .collect();
    let value = |metric: Metric, e: &Option<Evaluation>| {
        e.as_ref().and_then(|e| trajectory_metric(metric, e))
    };
    Ok(assemble_scores(
        hand_in,
        &Some(evaluation),
        &theirs,
        value,
        notices,
    ))
}

/// A file a student handed in for one variant of an assignment: what a grade
/// names besides its scores (the assignment, the variant, the file's name and
/// the SHA-256 of its bytes).
#[derive(Clone, Copy, Debug)]
pub struct HandIn<'a> {
    /// The assignment it is handed in for.
    pub assignment: &'a Assignment,
    /// The student's variant.
    pub variant: &'a Variant,
    /// The file's name, as dropped or given (`--estimate`).
    pub file_name: &'a str,
    /// The file's bytes.
    pub bytes: &'a [u8],
}

impl HandIn<'_> {
    /// The file cannot be graded: `why`, after the file's name.
    pub fn bad(&self, why: impl std::fmt::Display) -> CourseworkError {
        CourseworkError::BadEstimate(format!("{}: {why}", self.file_name))
    }

    /// A file reader's notices, each after the file's name.
    pub fn notices(&self, notices: &[String]) -> Vec<String> {
        notices
            .iter()
            .map(|n| format!("{}: {n}", self.file_name))
            .collect()
    }
}

/// A grade from each criterion's value and the references' values.
pub fn assemble(
    hand_in: &HandIn<'_>,
    values: &[Option<f64>],
    reference_values: &[Vec<(String, Option<f64>)>],
    notices: Vec<String>,
) -> Grade {
    let HandIn {
        assignment,
        variant,
        file_name,
        bytes,
    } = *hand_in;
    let criteria: Vec<CriterionGrade> = assignment
        .criteria
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let direction = c.direction();
            let value = values.get(k).copied().flatten().filter(|v| !v.is_nan());
            let pass = value.is_some_and(|v| direction.passes(v, c.threshold));
            CriterionGrade {
                metric: c.metric.name().to_owned(),
                label: c.metric.label().to_owned(),
                unit: c.metric.unit().to_owned(),
                value,
                threshold: c.threshold,
                direction: match direction {
                    super::assignment::Direction::AtMost => "at-most",
                    super::assignment::Direction::AtLeast => "at-least",
                }
                .to_owned(),
                points: c.points,
                earned: if pass { c.points } else { 0.0 },
                pass,
                references: reference_values
                    .get(k)
                    .map(|refs| {
                        refs.iter()
                            .map(|(name, v)| ReferenceValue {
                                name: name.clone(),
                                value: *v,
                                pass: v.is_some_and(|v| direction.passes(v, c.threshold)),
                            })
                            .collect()
                    })
                    .unwrap_or_default(),
            }
        })
        .collect();
    let score: f64 = criteria.iter().map(|c| c.earned).sum();
    let max_score = assignment.max_score();
    let pass_score = assignment.pass_score();
    Grade {
        assignment: assignment.id.clone(),
        title: assignment.title.clone(),
        student: variant.student.clone(),
        variant: variant.code.clone(),
        seed: variant.seed,
        estimate_file: file_name.to_owned(),
        estimate_sha256: sha256_hex(bytes),
        estimate_bytes: bytes.len(),
        criteria,
        score,
        max_score,
        pass_score,
        pass: score >= pass_score - 1e-9,
        notices,
    }
}

/// The command that grades `variant`'s hand-in of `assignment`, as a README
/// gives it: `slamlab grade ID --student 'STUDENT' --estimate FILE`.
pub fn grade_command(assignment: &Assignment, variant: &Variant) -> String {
    format!(
        "slamlab grade {} --student '{}' --estimate {}",
        assignment.id, variant.student, assignment.output.file
    )
}

/// What the README of a relative-pose task says under "What to hand in": the
/// file of the relative pose of the two `of` (`scans`, `views`) as
/// [`read_relative_pose`] reads it, the command that checks it, then `scored`
/// (how it is scored).
pub fn relative_pose_hand_in(
    assignment: &Assignment,
    variant: &Variant,
    of: &str,
    scored: &str,
) -> String {
    format!(
        "{file}: the relative pose of the two {of} as text: R row by row (9\n\
         numbers), then t (3), white space or commas, '#' comments; or 7 numbers\n\
         'tx ty tz qx qy qz qw'. Check it with\n\
         \x20 {check}\n\n\
         {scored}",
        file = assignment.output.file,
        check = grade_command(assignment, variant),
    )
}

/// Grades a relative pose handed in (as [`read_relative_pose`] reads it):
/// `score` gives a pose's errors against the truth, for the student's and for
/// each reference estimator's pose in `theirs` (by name); `value` reads each
/// criterion's metric off them ([`assemble_scores`]).
pub fn grade_relative_pose<E>(
    hand_in: &HandIn<'_>,
    theirs: impl IntoIterator<Item = (String, RelativePose)>,
    score: impl Fn(&RelativePose) -> E,
    value: impl Fn(Metric, &E) -> Option<f64>,
) -> Result<Grade, CourseworkError> {
    let file = read_relative_pose(hand_in.bytes).map_err(|e| hand_in.bad(e))?;
    let mine = score(&file.pose);
    let theirs: Vec<(String, E)> = theirs
        .into_iter()
        .map(|(name, pose)| (name, score(&pose)))
        .collect();
    let notices = hand_in.notices(&file.notices);
    Ok(assemble_scores(hand_in, &mine, &theirs, value, notices))
}

/// Grades a hand-in whose every criterion is read off one score of type `E` by
/// `value`: the student's score `mine` beside each reference estimator's
/// `theirs`, by name; then [`assemble`].
pub fn assemble_scores<E>(
    hand_in: &HandIn<'_>,
    mine: &E,
    theirs: &[(String, E)],
    value: impl Fn(Metric, &E) -> Option<f64>,
    notices: Vec<String>,
) -> Grade {
    let criteria = &hand_in.assignment.criteria;
    let values: Vec<Option<f64>> = criteria.iter().map(|c| value(c.metric, mine)).collect();
    let reference_values: Vec<Vec<(String, Option<f64>)>> = criteria
        .iter()
        .map(|c| {
            theirs
                .iter()
                .map(|(name, e)| (name.clone(), value(c.metric, e)))
                .collect()
        })
        .collect();
    assemble(hand_in, &values, &reference_values, notices)
}
