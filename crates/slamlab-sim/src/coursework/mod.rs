//! Coursework: homework handed out as data, each student on their own variant,
//! graded against the truth beside the reference estimators.
//!
//! An [`Assignment`] (a built-in one, or an instructor's JSON file read by
//! [`read_assignment`]) names a lesson, the run the inputs come from, the input
//! formats, what the student hands in and the criteria it is scored by. A
//! student's text (`student=` in the page, `--student` on the command line)
//! gives their [`Variant`]: the seed of their run. [`prepare`] runs it and
//! hands out the inputs ([`Prepared::input_files`]: the same bytes in the
//! browser's zip and the command line's folder), and [`Prepared::grade`] grades
//! a handed-in file against the truth, beside the reference estimators replayed
//! on exactly the files handed out.
//!
//! Coursework knows no lesson: a lesson that hands out assignments gives a
//! [`TaskRunner`] (its run of a variant as a [`TaskRun`]), and
//! `crate::assignments` lists them (the landmark world's runner is here, in
//! [`landmarks`], as that world is shared; Monte Carlo localization's is the
//! kidnap lesson's).
//!
//! Built-in assignments ([`BUILTIN`]): `ekf-slam` (landmark SLAM on the
//! Freiburg course's files or CSV), `mcl` (Monte Carlo localization on a ROS map
//! and a CARMEN log). `docs/assignments.md` is the instructors' page.

pub mod assignment;
pub mod files;
pub mod grade;
pub mod landmarks;
pub mod variant;

pub use assignment::{
    Assignment, Criterion, Direction, InputFormat, Metric, OutputFormat, TaskKind, read_assignment,
};
pub use files::InputFiles;
pub use grade::{CriterionGrade, Grade, HandIn, ReferenceValue};
pub use variant::{Variant, sha256_hex};

use crate::grid::BuiltinMap;
use crate::metrics::Trajectory;
use crate::params::{self, ParamIssue, Scenario};
use slamlab_core::grid::OccupancyGrid;
use std::fmt::Write as _;
use std::sync::OnceLock;
use thiserror::Error;

/// Why an assignment could not be found, read, handed out or graded.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum CourseworkError {
    /// No built-in assignment of that name.
    #[error(
        "no built-in assignment {name:?}; the built-in ones are {known}, or give an assignment JSON file"
    )]
    Unknown {
        /// The name asked for.
        name: String,
        /// The built-in names.
        known: String,
    },
    /// An assignment file that cannot be used.
    #[error("{0}")]
    BadAssignment(String),
    /// The run could not be made.
    #[error("could not make the inputs: {0}")]
    Generate(String),
    /// A handed-in file that cannot be read or scored.
    #[error("{0}")]
    BadEstimate(String),
    /// A handed-in file made for another variant or assignment.
    #[error("{0}")]
    OtherVariant(String),
}

impl CourseworkError {
    /// The same error, naming the file it is about.
    pub fn in_file(self, name: &str) -> CourseworkError {
        match self {
            CourseworkError::OtherVariant(m) => {
                CourseworkError::OtherVariant(format!("{name}: {m}"))
            }
            CourseworkError::BadEstimate(m) => CourseworkError::BadEstimate(format!("{name}: {m}")),
            other => other,
        }
    }
}

/// The built-in assignments: name and JSON text (the same reader reads them as
/// an instructor's file, and `docs/assignments.md` shows them as templates).
pub const BUILTIN: &[(&str, &str)] = &[
    ("ekf-slam", include_str!("builtin/ekf-slam.json")),
    ("mcl", include_str!("builtin/mcl.json")),
    ("pose-graph", include_str!("builtin/pose-graph.json")),
    ("grid-mapping", include_str!("builtin/grid-mapping.json")),
    ("icp", include_str!("builtin/icp.json")),
    ("two-view", include_str!("builtin/two-view.json")),
    ("fusion", include_str!("builtin/fusion.json")),
];

/// One variant's run of a task, made by the lesson that runs that kind of task:
/// the truth, the reference estimators and the files handed out.
pub trait TaskRun: std::fmt::Debug + Send + Sync {
    /// The true trajectory.
    fn truth(&self) -> Trajectory;
    /// The reference estimators replayed on exactly the files handed out, by
    /// name (the first one is the reference solution).
    fn references(&self) -> Result<Vec<(String, Trajectory)>, CourseworkError>;
    /// What the README says about the files in `inputs`: formats, units,
    /// frames, noise.
    fn readme_body(&self, inputs: &[InputFormat]) -> String;
    /// The files handed out in the formats `inputs`, with `readme` as
    /// `README.txt` and, with `answers`, the instructor's `answers/`.
    fn files(&self, inputs: &[InputFormat], readme: &str, answers: bool) -> InputFiles;
    /// URL pairs the lesson needs beyond the assignment's parameters and the
    /// seed to replay this run (`init=tracking`).
    fn lesson_pairs(&self) -> Vec<(String, String)> {
        Vec::new()
    }
    /// Grades a handed-in file, `references` being [`Self::references`]. The
    /// default grades a trajectory against [`Self::truth`]; a task whose output
    /// is no trajectory (an optimized graph, a map) grades its own.
    fn grade(
        &self,
        hand_in: &HandIn<'_>,
        references: &[(String, Trajectory)],
    ) -> Result<Grade, CourseworkError> {
        grade::grade_trajectory(hand_in, &self.truth(), references)
    }
    /// What the README says under "What to hand in"; `None`: the trajectory
    /// text every trajectory task shares.
    fn hand_in_text(&self, _assignment: &Assignment, _variant: &Variant) -> Option<String> {
        None
    }
}

/// Runs a variant of an assignment for the given steps.
pub type SimulateVariant =
    fn(&Assignment, &Variant, u64) -> Result<Box<dyn TaskRun>, CourseworkError>;

/// How a lesson runs one kind of task. Coursework knows no lesson: each lesson
/// that hands out assignments provides its runner, and `crate::assignments`
/// lists them.
#[derive(Clone, Copy, Debug)]
pub struct TaskRunner {
    /// The kind of task.
    pub kind: TaskKind,
    /// The assignment's parameters applied to the lesson's table: every
    /// refusal, as text.
    pub check_params: fn(&Assignment) -> Vec<String>,
    /// Runs a variant for the given steps.
    pub simulate: SimulateVariant,
}

impl TaskRunner {
    /// The runner of the task `T`: an assignment's parameters are checked by
    /// [`apply_params`] on `T`'s scenario and then by [`Task::refusals`]; a
    /// variant is [`Task::run`] from the same scenario, then
    /// [`Task::with_assignment`].
    pub const fn of<T: Task>() -> TaskRunner {
        TaskRunner {
            kind: T::KIND,
            check_params: check_task::<T>,
            simulate: simulate_task::<T>,
        }
    }
}

/// A lesson's kind of task, written as what is particular to it: the scenario
/// whose parameter table takes the assignment's parameters, what else the
/// lesson refuses, and how it runs a student's variant. [`TaskRunner::of`]
/// makes its runner, so every lesson checks and applies the parameters alike.
pub trait Task: TaskRun + Sized + 'static {
    /// The kind of task.
    const KIND: TaskKind;
    /// The lesson's scenario: its table takes the assignment's parameters.
    type Scenario: Scenario;
    /// What the lesson refuses beyond its table, `scenario` being the
    /// assignment's parameters applied to the default (none by default).
    fn refusals(_assignment: &Assignment, _scenario: &Self::Scenario) -> Vec<String> {
        Vec::new()
    }
    /// Runs a variant for `steps`: `scenario` holds the assignment's
    /// parameters, the lesson sets the variant's `seed` in it.
    fn run(scenario: Self::Scenario, seed: u64, steps: u64) -> Result<Self, CourseworkError>;
    /// The run of a variant of `assignment`, given what it takes from the
    /// assignment beyond its parameters (the two-view scene: the answers
    /// switch, to mark the wrong matches); by default the run as it is.
    fn with_assignment(self, _assignment: &Assignment) -> Self {
        self
    }
}

fn check_task<T: Task>(assignment: &Assignment) -> Vec<String> {
    let (scenario, mut refused) = apply_params::<T::Scenario>(assignment);
    refused.extend(T::refusals(assignment, &scenario));
    refused
}

fn simulate_task<T: Task>(
    assignment: &Assignment,
    variant: &Variant,
    steps: u64,
) -> Result<Box<dyn TaskRun>, CourseworkError> {
    let (scenario, _) = apply_params::<T::Scenario>(assignment);
    let run = T::run(scenario, variant.seed, steps)?;
    Ok(Box::new(run.with_assignment(assignment)))
}

/// The refusal of a map that is not built in (an assignment's run is made
/// again from the map's name, so it must be one of SLAM Lab's own).
pub fn builtin_map_refusal(name: &str) -> Option<String> {
    BuiltinMap::from_name(name)
        .is_none()
        .then(|| format!("map {name:?}: an assignment runs on a built-in map (maze, office)"))
}

/// The built-in map `name`, loaded for a variant's run.
pub fn load_builtin_map(name: &str) -> Result<OccupancyGrid, CourseworkError> {
    BuiltinMap::from_name(name)
        .ok_or_else(|| CourseworkError::Generate(format!("no built-in map {name:?}")))?
        .load()
        .map_err(|e| CourseworkError::Generate(format!("the map: {e}")))
}

/// The refusal of an assignment whose variants' steps (`scenario.steps` up to
/// `steps + steps_spread`) leave `min..=max`; `limit` says what the lesson
/// allows.
pub fn steps_refusal(assignment: &Assignment, min: u64, max: u64, limit: &str) -> Option<String> {
    let (steps, spread) = (assignment.scenario.steps, assignment.scenario.steps_spread);
    (steps < min || steps.saturating_add(spread) > max)
        .then(|| format!("scenario.steps {steps} with steps_spread {spread}: {limit}"))
}

fn runner_for(kind: TaskKind, runners: &[TaskRunner]) -> Option<&TaskRunner> {
    runners.iter().find(|r| r.kind == kind)
}

/// The built-in assignment `name`, checked against `runners`.
pub fn builtin(name: &str, runners: &[TaskRunner]) -> Result<Assignment, CourseworkError> {
    let Some((_, text)) = BUILTIN.iter().find(|(n, _)| *n == name) else {
        return Err(CourseworkError::Unknown {
            name: name.to_owned(),
            known: BUILTIN
                .iter()
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
                .join(", "),
        });
    };
    read_assignment(&format!("{name}.json"), text.as_bytes(), runners)
}

/// The refusals of an assignment's lesson parameters, by the runner of its
/// kind (none there: the kind has no input generator yet).
pub fn check_params(assignment: &Assignment, runners: &[TaskRunner]) -> Vec<String> {
    match assignment
        .task_kind()
        .and_then(|kind| runner_for(kind, runners))
    {
        Some(runner) => (runner.check_params)(assignment),
        None => vec![format!(
            "lesson {:?} cannot make an assignment's inputs yet",
            assignment.lesson
        )],
    }
}

/// The lesson's default scenario with the assignment's parameters, and what the
/// table refused (a `seed` or `preset` among them: the seed is the student's).
pub fn apply_params<S: Scenario + Default>(assignment: &Assignment) -> (S, Vec<String>) {
    let mut scenario = S::default();
    let pairs = assignment.param_pairs();
    let mut refused: Vec<String> = pairs
        .iter()
        .filter(|(k, _)| k == "seed" || k == "preset")
        .map(|(k, _)| format!("{k}: an assignment's {k} comes from each student's variant"))
        .collect();
    refused.extend(
        params::apply_pairs(
            &mut scenario,
            pairs.iter().map(|(k, v)| (k.as_str(), v.as_str())),
            &["seed", "preset"],
        )
        .iter()
        .map(ParamIssue::to_string),
    );
    (scenario, refused)
}

/// One student's variant of an assignment, run: its inputs, truth and
/// reference estimators.
#[derive(Debug)]
pub struct Prepared {
    /// The assignment.
    pub assignment: Assignment,
    /// The student's variant.
    pub variant: Variant,
    /// The steps of this variant's run.
    pub steps: u64,
    /// The run.
    pub run: Box<dyn TaskRun>,
    references: OnceLock<Result<Vec<(String, Trajectory)>, CourseworkError>>,
}

/// Runs `student`'s variant of `assignment` with the runner of its kind.
pub fn prepare(
    assignment: &Assignment,
    student: &str,
    runners: &[TaskRunner],
) -> Result<Prepared, CourseworkError> {
    let variant = Variant::new(&assignment.id, student);
    let steps = assignment.steps_for(variant.seed);
    let runner = assignment
        .task_kind()
        .and_then(|kind| runner_for(kind, runners))
        .ok_or_else(|| {
            CourseworkError::BadAssignment(format!(
                "{}: lesson {:?} cannot make an assignment's inputs yet",
                assignment.id, assignment.lesson
            ))
        })?;
    let run = (runner.simulate)(assignment, &variant, steps)?;
    Ok(Prepared {
        assignment: assignment.clone(),
        variant,
        steps,
        run,
        references: OnceLock::new(),
    })
}

impl Prepared {
    /// The true trajectory.
    pub fn truth(&self) -> Trajectory {
        self.run.truth()
    }

    /// The reference estimators on the inputs as handed out, by name (computed
    /// once).
    pub fn references(&self) -> Result<&[(String, Trajectory)], CourseworkError> {
        self.references
            .get_or_init(|| self.run.references())
            .as_ref()
            .map(Vec::as_slice)
            .map_err(Clone::clone)
    }

    /// Grades a handed-in file.
    pub fn grade(&self, file_name: &str, bytes: &[u8]) -> Result<Grade, CourseworkError> {
        let references = self.references()?;
        let hand_in = HandIn {
            assignment: &self.assignment,
            variant: &self.variant,
            file_name,
            bytes,
        };
        self.run.grade(&hand_in, references)
    }

    /// The lesson's URL pairs that open this variant's run in the app: the
    /// assignment's parameters and the student's seed.
    pub fn lesson_pairs(&self) -> Vec<(String, String)> {
        let mut pairs: Vec<(String, String)> = self
            .assignment
            .param_pairs()
            .into_iter()
            .filter(|(k, _)| k != "seed" && k != "preset")
            .collect();
        pairs.push(("seed".to_owned(), self.variant.seed.to_string()));
        pairs.extend(self.run.lesson_pairs());
        pairs
    }

    /// The folder name of the download: `slamlab-<id>-<variant>`.
    pub fn folder_name(&self) -> String {
        format!("slamlab-{}-{}", self.assignment.id, self.variant.code)
    }

    /// The files handed out (with `answers`, the instructor's `answers/`).
    pub fn input_files(&self, answers: bool) -> InputFiles {
        let inputs = &self.assignment.inputs;
        let readme = self.readme(&self.run.readme_body(inputs));
        self.run.files(inputs, &readme, answers)
    }

    /// The download as one zip (the browser's *Download inputs*).
    pub fn zip(&self, answers: bool) -> Result<Vec<u8>, CourseworkError> {
        crate::io::archive::write_zip(&self.folder_name(), &self.input_files(answers).files)
            .map_err(|e| CourseworkError::Generate(e.to_string()))
    }

    /// The README: the task, the variant, what to hand in and how it is scored,
    /// then `body` (the files, their formats, units, frames and noise).
    fn readme(&self, body: &str) -> String {
        let a = &self.assignment;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{}\n{}\n",
            a.title,
            "=".repeat(a.title.chars().count())
        );
        let intro = format!(
            "Assignment {}, variant {} (student {:?}, seed {}). SLAM Lab made these \
             inputs for this student alone: another student's files have other noise, so \
             an answer made from them is wrong for these; where the hand-in shows it (a \
             trajectory's length and times, a graph's edges) it is refused as another \
             variant's.",
            a.id, self.variant.code, self.variant.student, self.variant.seed
        );
        let _ = writeln!(out, "{}\n", wrap(&intro, 78));
        for paragraph in a.task.trim().split("\n\n") {
            let _ = writeln!(out, "{}\n", wrap(paragraph, 78));
        }
        let _ = writeln!(out, "What to hand in\n---------------");
        if let Some(text) = self.run.hand_in_text(a, &self.variant) {
            let _ = writeln!(out, "{text}");
        } else {
            let _ = writeln!(
                out,
                "{}: one pose per step, for t = 0 and every step's time (the times of the\n\
             inputs), as TUM ('t x y z qx qy qz qw', z = 0 and a rotation about z:\n\
             qz = sin(theta/2), qw = cos(theta/2)) or CSV ('t,x,y,theta'). Check it with\n\
             {}\n",
                a.output.file,
                grade::grade_command(a, &self.variant)
            );
            let _ = writeln!(
                out,
                "It is scored against the true trajectory{}\n(poses paired by time within \
             0.01 s):",
                match a.alignment() {
                    crate::metrics::Alignment::None => ", in the map's frame, without alignment",
                    crate::metrics::Alignment::Se2 => " after a rigid (SE(2)) alignment",
                    crate::metrics::Alignment::Sim2 => " after a similarity (Sim(2)) alignment",
                }
            );
        }
        for c in &a.criteria {
            let _ = writeln!(
                out,
                "  - {} {} {}: {} points",
                c.metric.label(),
                c.direction().symbol(),
                grade::format_value(c.threshold, c.metric.unit()),
                c.points
            );
        }
        let _ = writeln!(
            out,
            "  pass: {} of {} points. starter.py (Python 3, numpy) reads the inputs and\n\
             writes a naive estimate in the right format: start from it.\n",
            a.pass_score(),
            a.max_score()
        );
        let _ = writeln!(out, "The files\n---------\n{body}");
        out
    }
}

/// `text` with its whitespace runs made single spaces and its lines broken
/// before `width` characters (a word longer than that gets its own line).
pub fn wrap(text: &str, width: usize) -> String {
    let mut out = String::new();
    let mut line = 0;
    for word in text.split_whitespace() {
        let n = word.chars().count();
        if line > 0 && line + 1 + n > width {
            out.push('\n');
            line = 0;
        } else if line > 0 {
            out.push(' ');
            line += 1;
        }
        out.push_str(word);
        line += n;
    }
    out
}
