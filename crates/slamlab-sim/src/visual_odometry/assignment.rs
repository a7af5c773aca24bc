//! Two-view assignments (`crate::coursework`'s [`Task`] of `two-view`
//! tasks): the essential matrix with RANSAC. A student gets the intrinsics
//! `K.txt` and pixel matches `matches.csv` (`u1,v1,u2,v2`) of one seeded
//! two-view scene, a share of them wrong, and hands back the relative pose of
//! the two views, scored as the lesson scores one
//! ([`crate::metrics::relative_pose_error`]: the angle of `R_trueᵀ R` and the
//! angle between the translation directions; a monocular `t` has no length).
//!
//! The scene is the one `slamlab experiment two-view` draws
//! ([`random_two_view_scene`]; thesis `000` Sec. 4.3): a 640 x 480 pinhole
//! with a 60 degree field of view, points 4 to 12 m deep inside the first view,
//! a rotation of 3 to 10 degrees about a random axis and a 2 m baseline in a
//! random direction; each match gets the lesson's pixel noise (`noise-px`) and
//! is replaced, with the lesson's probability (`outliers`), by a random pixel
//! of the second image. The student's seed draws the scene, `scenario.steps`
//! (plus the variant's spread) is the number of matches.
//!
//! Convention (`io::relative_pose`, OpenCV's `recoverPose`): `X_b = R X_a + t`
//! turns a point of view a's camera frame (x right, y down, z along the
//! optical axis) into view b's; camera b's centre in a's frame is `-Rᵀ t`.
//!
//! The references, replayed on the numbers exactly as handed out (printed so
//! that they read back to the same `f64`): the lesson's RANSAC with the
//! eight-point solver (Eq. 4.18-4.21, Hartley-normalized, the reference
//! solution), with the five-point solver (Eq. 4.22-4.25), and the naive answer
//! the starter code writes (no rotation, straight ahead: `R = I`,
//! `t = (0, 0, -1)`).

use super::VoScenario;
use super::experiment::random_two_view_scene;
use crate::coursework::files::{InputFiles, number};
use crate::coursework::grade::{grade_relative_pose, relative_pose_hand_in};
use crate::coursework::{
    Assignment, CourseworkError, Grade, HandIn, InputFormat, Metric, Task, TaskKind, TaskRun,
    Variant, apply_params, steps_refusal,
};
use crate::io::relative_pose::write_relative_pose;
use crate::metrics::{Trajectory, relative_pose_error};
use crate::noise::stream_seed;
use nalgebra::{Matrix3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use slamlab_core::vision::{
    Correspondence, Intrinsics, Method, RansacConfig, RelativePose, estimate_two_view,
    rotation_angle,
};
use slamlab_core::{Pose2, math};
use std::fmt::Write as _;

/// The fewest matches an assignment may hand out (RANSAC's eight-point sample
/// needs eight right ones among them).
pub const MIN_MATCHES: u64 = 16;

/// The most matches an assignment may hand out.
pub const MAX_MATCHES: u64 = 5_000;

/// The lesson's parameters a two-view assignment uses (the others set the
/// lesson's docking run, which the assignment's scene is not).
pub const USED_PARAMS: &[&str] = &[
    "outliers",
    "noise-px",
    "normalize",
    "refine",
    "early-rejection",
];

/// The most RANSAC samples the references draw (the experiment's cap).
pub const MAX_SAMPLES: usize = 5_000;

/// The lesson's link key that shows a two-view scene instead of the docking
/// run: `two-view=N` draws the scene of the link's `seed` and parameters with
/// `N` matches ([`TwoViewRun::simulate`]), as an assignment's variant does
/// ([`TwoViewRun::lesson_pairs`](TaskRun::lesson_pairs) gives it).
pub const SCENE_KEY: &str = "two-view";

/// The lesson's link key that marks the scene's wrong matches from the start
/// (`two-view-answers=on`): an assignment that includes its answers.
pub const ANSWERS_KEY: &str = "two-view-answers";

/// The naive answer: no rotation, the camera moved straight ahead along its
/// optical axis (`t = (0, 0, -1)`: b's centre at `-Rᵀ t = (0, 0, 1)` in a's
/// frame). What the starter code writes.
pub fn naive_pose() -> RelativePose {
    RelativePose {
        rotation: Matrix3::identity(),
        translation: Vector3::new(0.0, 0.0, -1.0),
    }
}

/// One student's two views.
#[derive(Clone, Debug)]
pub struct TwoViewRun {
    /// The lesson's parameters (the student's seed in them).
    pub scenario: VoScenario,
    /// The camera of both views.
    pub camera: Intrinsics,
    /// The matches handed out, in pixels.
    pub matches: Vec<Correspondence>,
    /// Which matches were made wrong (the truth; the answers hold it).
    pub wrong: Vec<bool>,
    /// The true relative pose (`|t|` = 2 m, the baseline).
    pub truth: RelativePose,
    /// The references' relative poses by name (`None`: RANSAC found none).
    pub references: Vec<(String, Option<RelativePose>)>,
    /// The RANSAC references' inliers by name, one flag per match (empty:
    /// RANSAC found no pose).
    pub inliers: Vec<(String, Vec<bool>)>,
    /// The assignment includes its answers (the instructor's switch): the
    /// lesson may mark the wrong matches before anything is graded.
    pub answers_included: bool,
}

/// The rotation error (degrees) and the translation-direction error (degrees;
/// `None` when either translation is zero) of a relative pose, by
/// [`relative_pose_error`] (the rotation's angle alone when a translation is
/// zero).
pub fn errors(pose: &RelativePose, truth: &RelativePose) -> [Option<f64>; 2] {
    match relative_pose_error(
        &pose.rotation,
        &pose.translation,
        &truth.rotation,
        &truth.translation,
    ) {
        Some(e) => [Some(e.rotation_deg), Some(e.translation_direction_deg)],
        None => [
            Some(rotation_angle(&(truth.rotation.transpose() * pose.rotation)).to_degrees()),
            None,
        ],
    }
}

/// A relative pose seen from above, for drawing: camera b's pose in camera
/// a's frame as (forward, left, heading), its direction of travel scaled to
/// `baseline` metres (a monocular `t` has no length).
pub fn top_view(pose: &RelativePose, baseline: f64) -> Pose2 {
    let t = pose.translation;
    let scale = if t.norm() > 0.0 {
        baseline / t.norm()
    } else {
        0.0
    };
    let centre = -(pose.rotation.transpose() * t) * scale;
    let axis = pose.rotation.transpose() * Vector3::z();
    Pose2::new(centre.z, -centre.x, math::atan2(-axis.x, axis.z))
}

fn k_txt(k: &Intrinsics) -> String {
    let mut out = String::from(
        "# K: the intrinsics of both views, row by row (pixels): u = fx X/Z + cx, v = fy Y/Z + cy\n",
    );
    let m = k.matrix();
    for row in 0..3 {
        let _ = writeln!(
            out,
            "{} {} {}",
            number(m[(row, 0)]),
            number(m[(row, 1)]),
            number(m[(row, 2)])
        );
    }
    out
}

fn matches_csv(matches: &[Correspondence]) -> String {
    let mut out = String::from("u1,v1,u2,v2\n");
    for m in matches {
        let _ = writeln!(
            out,
            "{},{},{},{}",
            number(m.left.x),
            number(m.left.y),
            number(m.right.x),
            number(m.right.y)
        );
    }
    out
}

impl TwoViewRun {
    /// Draws the scene of `scenario`'s seed with `matches` matches and runs the
    /// references on it.
    pub fn simulate(scenario: &VoScenario, matches: usize) -> TwoViewRun {
        let settings = &scenario.settings;
        let camera = Intrinsics::from_fov(640.0, 480.0, 60.0);
        let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
        let (truth, drawn, wrong) = random_two_view_scene(
            &mut rng,
            &camera,
            matches,
            settings.noise_px,
            settings.outliers,
        );
        let ransac = |method: Method, stream: u64| {
            let config = RansacConfig {
                method,
                normalize: settings.normalize,
                max_iterations: MAX_SAMPLES,
                early_rejection: settings.early_rejection,
                refine: settings.refine,
                ..RansacConfig::default()
            };
            let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(settings.seed, stream));
            estimate_two_view(&drawn, &camera, config, &mut rng)
                .ok()
                .and_then(|e| {
                    e.translation.map(|t| {
                        let pose = RelativePose {
                            rotation: e.rotation,
                            translation: t,
                        };
                        (pose, e.inliers)
                    })
                })
        };
        let mut references = Vec::new();
        let mut inliers = Vec::new();
        for (name, method, stream) in [
            ("eight-point", Method::EightPoint, 1),
            ("five-point", Method::FivePoint, 2),
        ] {
            let found = ransac(method, stream);
            references.push((name.to_owned(), found.as_ref().map(|(p, _)| *p)));
            inliers.push((name.to_owned(), found.map(|(_, i)| i).unwrap_or_default()));
        }
        references.push(("naive".to_owned(), Some(naive_pose())));
        TwoViewRun {
            scenario: scenario.clone(),
            camera,
            matches: drawn,
            wrong,
            truth,
            references,
            inliers,
            answers_included: false,
        }
    }

    /// The run of `variant` of a two-view `assignment` with `steps` matches
    /// (clamped to [`MIN_MATCHES`]..=[`MAX_MATCHES`]): the lesson's default
    /// scenario with the assignment's parameters and the variant's seed, as
    /// `slamlab export-inputs` and `slamlab grade` run it.
    pub fn for_variant(assignment: &Assignment, variant: &Variant, steps: u64) -> TwoViewRun {
        let (scenario, _) = apply_params::<VoScenario>(assignment);
        TwoViewRun::of_seed(scenario, variant.seed, steps).with_assignment(assignment)
    }

    /// The scene of `scenario` with its seed set to `seed` and `steps` matches
    /// (clamped to [`MIN_MATCHES`]..=[`MAX_MATCHES`]).
    fn of_seed(mut scenario: VoScenario, seed: u64, steps: u64) -> TwoViewRun {
        scenario.settings.seed = seed;
        let matches = usize::try_from(steps.clamp(MIN_MATCHES, MAX_MATCHES)).unwrap_or(200);
        TwoViewRun::simulate(&scenario, matches)
    }

    /// Camera b's top view ([`top_view`]) of `pose`, its translation scaled to
    /// the true baseline (what the lesson draws for each relative pose).
    pub fn top_view_of(&self, pose: &RelativePose) -> Pose2 {
        top_view(pose, self.truth.translation.norm())
    }

    /// The files handed out: `K.txt`, `matches.csv`, the README, the starter
    /// code; with `answers`, `answers/relative_pose.txt` (the truth, `t` of
    /// the true 2 m length) and `answers/wrong_matches.csv` (1 for each match
    /// that was made wrong, in the order of `matches.csv`).
    pub fn files(&self, readme: &str, answers: bool) -> InputFiles {
        let mut files = InputFiles::with_readme(readme);
        files.add("K.txt", k_txt(&self.camera));
        files.add("matches.csv", matches_csv(&self.matches));
        files.add("starter.py", TWO_VIEW_STARTER);
        if answers {
            files.add(
                "answers/relative_pose.txt",
                write_relative_pose(&self.truth),
            );
            let mut wrong = String::from("wrong\n");
            for w in &self.wrong {
                wrong.push_str(if *w { "1\n" } else { "0\n" });
            }
            files.add("answers/wrong_matches.csv", wrong);
        }
        files
    }

    /// What the README says about the files.
    pub fn readme_body(&self) -> String {
        let s = &self.scenario.settings;
        format!(
            "K.txt  the 3x3 intrinsics of the camera (both views), row by row, in\n\
             \x20 pixels: a point (X, Y, Z) of the camera's frame (x right, y down, z along\n\
             \x20 the optical axis, metres) is seen at u = fx X/Z + cx, v = fy Y/Z + cy.\n\
             \x20 The image is {w} x {h} pixels, (0, 0) its top left corner, u to the\n\
             \x20 right, v down.\n\
             matches.csv  'u1,v1,u2,v2': {n} matches, one a line, of a point seen at\n\
             \x20 (u1, v1) in view a and (u2, v2) in view b (pixels). Each pixel has\n\
             \x20 Gaussian noise of {noise} px on each axis, and about {pct}% of the matches\n\
             \x20 are wrong (view b's pixel is a random one): use RANSAC.\n\
             \n\
             Hand in R and t with X_b = R X_a + t: a point of view a's camera frame in\n\
             view b's (OpenCV's recoverPose convention). Camera b's centre in a's frame\n\
             is -R^T t. t is known up to scale: two views of an unknown scene cannot\n\
             tell a 2 m move past points 10 m away from a 20 cm move past points 1 m\n\
             away, so only the direction of t is scored (any positive length will do;\n\
             its sign matters: it puts the points in front of both cameras).\n",
            w = self.camera.width,
            h = self.camera.height,
            n = self.matches.len(),
            noise = number(s.noise_px),
            pct = number(s.outliers * 100.0),
        )
    }

    /// The reference `name`'s relative pose, if it found one.
    pub fn reference(&self, name: &str) -> Option<&RelativePose> {
        self.references
            .iter()
            .find(|(n, _)| n == name)
            .and_then(|(_, p)| p.as_ref())
    }
}

/// The starter code of two-view assignments.
pub const TWO_VIEW_STARTER: &str = include_str!("assignment_starter.py");

/// Two-view tasks: the lesson's parameter table checks the assignment's
/// parameters ([`Task::refusals`] adds the ones the scene does not use and the
/// matches' range); a variant is the scene of its seed
/// ([`TwoViewRun::for_variant`]), which also carries the assignment's answers
/// switch into the lesson's link.
impl Task for TwoViewRun {
    const KIND: TaskKind = TaskKind::TwoView;
    type Scenario = VoScenario;

    fn refusals(assignment: &Assignment, _scenario: &VoScenario) -> Vec<String> {
        let mut refused = Vec::new();
        for (name, _) in assignment.param_pairs() {
            if name != "seed" && name != "preset" && !USED_PARAMS.contains(&name.as_str()) {
                refused.push(format!(
                    "{name}: a two-view assignment's scene is the two-view experiment's, set by {}",
                    USED_PARAMS.join(", ")
                ));
            }
        }
        let limit =
            format!("a two-view assignment hands out {MIN_MATCHES} to {MAX_MATCHES} matches");
        refused.extend(steps_refusal(assignment, MIN_MATCHES, MAX_MATCHES, &limit));
        refused
    }

    fn run(scenario: VoScenario, seed: u64, steps: u64) -> Result<TwoViewRun, CourseworkError> {
        Ok(TwoViewRun::of_seed(scenario, seed, steps))
    }

    /// The answers switch: the lesson marks the wrong matches from the start.
    fn with_assignment(mut self, assignment: &Assignment) -> TwoViewRun {
        self.answers_included = assignment.answers_included;
        self
    }
}

impl TaskRun for TwoViewRun {
    /// `two-view=N` ([`SCENE_KEY`]): the lesson shows this scene (its seed and
    /// parameters are the variant's pairs), and `two-view-answers=on`
    /// ([`ANSWERS_KEY`]) when the assignment includes its answers.
    fn lesson_pairs(&self) -> Vec<(String, String)> {
        let mut pairs = vec![(SCENE_KEY.to_owned(), self.matches.len().to_string())];
        if self.answers_included {
            pairs.push((ANSWERS_KEY.to_owned(), "on".to_owned()));
        }
        pairs
    }

    /// Camera a at 0 and camera b's top view in its frame at 1 (for drawing;
    /// the grade uses the 3D poses).
    fn truth(&self) -> Trajectory {
        Trajectory::new(
            vec![0.0, 1.0],
            vec![Pose2::IDENTITY, self.top_view_of(&self.truth)],
        )
    }

    /// The references' top views, each `t` scaled to the true baseline.
    fn references(&self) -> Result<Vec<(String, Trajectory)>, CourseworkError> {
        Ok(self
            .references
            .iter()
            .filter_map(|(name, pose)| {
                let pose = pose.as_ref()?;
                Some((
                    name.clone(),
                    Trajectory::new(
                        vec![0.0, 1.0],
                        vec![Pose2::IDENTITY, self.top_view_of(pose)],
                    ),
                ))
            })
            .collect())
    }

    fn readme_body(&self, _inputs: &[InputFormat]) -> String {
        TwoViewRun::readme_body(self)
    }

    fn files(&self, _inputs: &[InputFormat], readme: &str, answers: bool) -> InputFiles {
        TwoViewRun::files(self, readme, answers)
    }

    fn hand_in_text(&self, assignment: &Assignment, variant: &Variant) -> Option<String> {
        Some(relative_pose_hand_in(
            assignment,
            variant,
            "views",
            "It is scored against the true relative pose of the two views (t by its\n\
             direction alone):",
        ))
    }

    /// Grades a relative pose against the truth, beside the references' 3D
    /// poses (the `references` given are their top views, which lose the
    /// third dimension: the run's own poses are scored, by the same names).
    fn grade(
        &self,
        hand_in: &HandIn<'_>,
        references: &[(String, Trajectory)],
    ) -> Result<Grade, CourseworkError> {
        let theirs = references
            .iter()
            .filter_map(|(name, _)| Some((name.clone(), *self.reference(name)?)));
        let value = |metric: Metric, e: &[Option<f64>; 2]| match metric {
            Metric::RotationErrorDeg => e[0],
            Metric::TranslationDirectionErrorDeg => e[1],
            _ => None,
        };
        grade_relative_pose(hand_in, theirs, |p| errors(p, &self.truth), value)
    }
}

#[cfg(test)]
mod tests;
