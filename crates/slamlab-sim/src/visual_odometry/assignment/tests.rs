//! The `two-view` assignment: the naive answer fails and the lesson's RANSAC
//! with the eight-point solver passes, for every one of 60 students; a
//! student's inputs are the same bytes every time and another student's differ;
//! the reference replays on the files as handed out.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // a failing test stops

use super::*;
use crate::coursework::{self, Prepared, TaskRunner};

// The lesson's own runner, as `crate::assignments` lists it (not imported
// from there: the list imports this lesson).
const RUNNER: TaskRunner = TaskRunner::of::<TwoViewRun>();

fn builtin(name: &str) -> Assignment {
    coursework::builtin(name, &[RUNNER]).unwrap()
}

fn prepare(a: &Assignment, student: &str) -> Result<Prepared, CourseworkError> {
    coursework::prepare(a, student, &[RUNNER])
}

fn read(name: &str, bytes: &[u8]) -> Result<Assignment, CourseworkError> {
    coursework::read_assignment(name, bytes, &[RUNNER])
}

fn file(p: &Prepared, path: &str) -> Vec<u8> {
    p.input_files(true).get(path).unwrap().to_vec()
}

/// The variant's run, simulated again as the runner does.
fn simulate(p: &Prepared) -> TwoViewRun {
    let (mut scenario, _) = apply_params::<VoScenario>(&p.assignment);
    scenario.settings.seed = p.variant.seed;
    TwoViewRun::simulate(&scenario, p.steps as usize)
}

fn pose_file(pose: &RelativePose) -> Vec<u8> {
    write_relative_pose(pose).into_bytes()
}

#[test]
fn the_naive_answer_fails_and_the_eight_point_ransac_passes() {
    let a = builtin("two-view");
    assert_eq!(
        (a.lesson.as_str(), a.max_score(), a.pass_score()),
        ("visual-odometry", 100.0, 100.0)
    );
    for student in ["ada@uni.edu", "alan@uni.edu", "grace@uni.edu", "s0123456"] {
        // (The truth passes: `tests/assignments.rs`, with ICP's.)
        let p = prepare(&a, student).unwrap();
        let again = simulate(&p);
        let eight = again.reference("eight-point").unwrap();
        let g = p.grade("eight.txt", &pose_file(eight)).unwrap();
        assert!(g.pass, "{student}: {g:#?}");
        // The reference's value beside the student's: the same pose, written
        // and read back (17 digits).
        for c in &g.criteria {
            let reference = c.references[0].value.unwrap();
            assert_eq!(c.references[0].name, "eight-point");
            assert!((c.value.unwrap() - reference).abs() < 1e-6, "{c:?}");
        }
        let naive = p.grade("naive.txt", &pose_file(&naive_pose())).unwrap();
        assert!(!naive.pass, "{student}: {naive:#?}");
        // The naive rotation error is the true rotation's angle.
        let angle = rotation_angle(&again.truth.rotation).to_degrees();
        assert!((naive.criteria[0].value.unwrap() - angle).abs() < 1e-9);
    }
    let p = prepare(&a, "ada@uni.edu").unwrap();
    let err = p.grade("bad.txt", b"1 2 3\n").unwrap_err().to_string();
    assert!(err.starts_with("bad.txt"), "{err}");
    // A zero t has no direction: refused by the reader, saying so.
    let zero = RelativePose {
        rotation: Matrix3::identity(),
        translation: Vector3::zeros(),
    };
    let err = p
        .grade("zero.txt", &pose_file(&zero))
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("zero.txt") && err.contains("t is zero"),
        "{err}"
    );
}

/// What every assignment's student gets (the same bytes every time, another
/// student other ones) is checked for all of them in `tests/assignments.rs`;
/// here, which of the two-view files are a student's own.
#[test]
fn a_student_always_gets_the_same_bytes_and_two_students_different_ones() {
    let a = builtin("two-view");
    let ada = prepare(&a, "ada@uni.edu").unwrap();
    let alan = prepare(&a, "alan@uni.edu").unwrap();
    assert_eq!(
        ada.zip(true).unwrap(),
        prepare(&a, "ada@uni.edu").unwrap().zip(true).unwrap()
    );
    assert_eq!(
        ada.input_files(false).paths(),
        ["README.txt", "K.txt", "matches.csv", "starter.py"]
    );
    // One camera for every student; their own matches, truth and outliers.
    for path in [
        "README.txt",
        "matches.csv",
        "answers/relative_pose.txt",
        "answers/wrong_matches.csv",
    ] {
        assert_ne!(file(&ada, path), file(&alan, path), "{path}");
    }
    assert_eq!(file(&ada, "K.txt"), file(&alan, "K.txt"));
    let readme = String::from_utf8(file(&ada, "README.txt")).unwrap();
    assert!(readme.contains("up to scale") && readme.contains("-R^T t"));
    // steps + seed mod (spread + 1) matches, one line each after the header.
    let lines = String::from_utf8(file(&ada, "matches.csv"))
        .unwrap()
        .lines()
        .count();
    assert_eq!(lines as u64, 1 + ada.steps);
    assert!((200..=250).contains(&ada.steps));
}

/// Reads `K.txt` and `matches.csv` back as a student's program would: the very
/// numbers the references got, so RANSAC on them gives the same pose, bit for
/// bit.
#[test]
fn the_reference_replays_on_the_files_as_handed_out() {
    let a = builtin("two-view");
    let p = prepare(&a, "grace@uni.edu").unwrap();
    let numbers = |line: &str, sep: char| -> Vec<f64> {
        line.split(sep)
            .filter(|s| !s.is_empty())
            .map(|s| s.trim().parse().unwrap())
            .collect()
    };
    let k_text = String::from_utf8(file(&p, "K.txt")).unwrap();
    let k: Vec<Vec<f64>> = k_text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| numbers(l, ' '))
        .collect();
    let camera = Intrinsics {
        fx: k[0][0],
        fy: k[1][1],
        cx: k[0][2],
        cy: k[1][2],
        width: 640.0,
        height: 480.0,
    };
    assert_eq!((k[0][1], k[1][0], k[2][2]), (0.0, 0.0, 1.0));
    let text = String::from_utf8(file(&p, "matches.csv")).unwrap();
    let matches: Vec<Correspondence> = text
        .lines()
        .skip(1)
        .map(|l| {
            let n = numbers(l, ',');
            Correspondence::new(
                nalgebra::Vector2::new(n[0], n[1]),
                nalgebra::Vector2::new(n[2], n[3]),
            )
        })
        .collect();
    let original = simulate(&p);
    assert_eq!(camera, original.camera);
    assert_eq!(matches, original.matches);
    let s = &original.scenario.settings;
    let config = RansacConfig {
        method: Method::EightPoint,
        normalize: s.normalize,
        max_iterations: MAX_SAMPLES,
        early_rejection: s.early_rejection,
        refine: s.refine,
        ..RansacConfig::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(s.seed, 1));
    let e = estimate_two_view(&matches, &camera, config, &mut rng).unwrap();
    let eight = original.reference("eight-point").unwrap();
    assert_eq!(e.rotation, eight.rotation);
    assert_eq!(e.translation, Some(eight.translation));
    // The share of wrong matches is the lesson's 30 %, give or take.
    let wrong = original.wrong.iter().filter(|w| **w).count() as f64;
    let share = wrong / original.wrong.len() as f64;
    assert!((0.2..0.4).contains(&share), "{share}");
}

/// The thresholds' measurement (docs/assignments.md): over 60 students the
/// eight-point reference passes every one and the naive answer fails every
/// one. `cargo test -p slamlab-sim --lib two_view_over -- --nocapture` prints
/// the min/median/max.
#[test]
fn two_view_over_sixty_students_the_reference_passes_and_the_naive_fails() {
    let a = builtin("two-view");
    let mut rows = Vec::new();
    for k in 0..60 {
        let p = prepare(&a, &format!("student{k}@uni.edu")).unwrap();
        let run = simulate(&p);
        let eight = p
            .grade(
                "eight.txt",
                &pose_file(run.reference("eight-point").unwrap()),
            )
            .unwrap();
        let naive = p.grade("naive.txt", &pose_file(&naive_pose())).unwrap();
        assert!(eight.pass, "student{k}: {eight:#?}");
        assert!(!naive.pass, "student{k}: {naive:#?}");
        let five = run
            .reference("five-point")
            .map_or([None, None], |pose| errors(pose, &run.truth));
        rows.push([
            eight.criteria[0].value.unwrap(),
            eight.criteria[1].value.unwrap(),
            naive.criteria[0].value.unwrap(),
            naive.criteria[1].value.unwrap(),
            five[0].unwrap_or(f64::NAN),
            five[1].unwrap_or(f64::NAN),
        ]);
    }
    let sorted = |column: usize| {
        let mut v: Vec<f64> = rows.iter().map(|r| r[column]).collect();
        v.sort_by(f64::total_cmp);
        (v[0], v[v.len() / 2], v[v.len() - 1])
    };
    eprintln!(
        "two-view over 60 students, min/median/max: eight-point rotation {:.3?} deg, direction {:.3?} deg; five-point rotation {:.3?} deg, direction {:.3?} deg; naive rotation {:.2?} deg, direction {:.1?} deg",
        sorted(0),
        sorted(1),
        sorted(4),
        sorted(5),
        sorted(2),
        sorted(3)
    );
}

#[test]
fn the_top_view_of_a_forward_move_is_ahead_and_turned_left() {
    // Camera b 2 m ahead of a, turned 10 degrees left (about a's -y axis,
    // which points up).
    let yaw = 10f64.to_radians();
    let (s, c) = math::sin_cos(yaw);
    // b's axes in a's frame: x_b = (c, 0, -s)... as columns of R_ab = Rᵀ.
    let r_ab = Matrix3::new(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);
    let centre = Vector3::new(0.0, 0.0, 2.0);
    let pose = RelativePose {
        rotation: r_ab.transpose(),
        translation: -(r_ab.transpose() * centre),
    };
    let top = top_view(&pose, 2.0);
    assert!(
        (top.x - 2.0).abs() < 1e-12 && top.y.abs() < 1e-12,
        "{top:?}"
    );
    assert!((top.theta - yaw).abs() < 1e-12, "{top:?}");
    // The naive answer is straight ahead.
    let naive = top_view(&naive_pose(), 1.0);
    assert_eq!((naive.x, naive.y, naive.theta), (1.0, 0.0, 0.0));
}

#[test]
fn an_assignment_with_parameters_the_scene_has_not_is_refused() {
    let text = coursework::BUILTIN
        .iter()
        .find(|(n, _)| *n == "two-view")
        .unwrap()
        .1;
    let bad = text.replace("\"noise-px\": 1", "\"noise-px\": 1, \"pair\": 3");
    let err = read("hw.json", bad.as_bytes()).unwrap_err().to_string();
    assert!(err.contains("hw.json") && err.contains("pair"), "{err}");
    let few = text.replace("\"steps\": 200", "\"steps\": 5");
    let err = read("hw.json", few.as_bytes()).unwrap_err().to_string();
    assert!(err.contains("16 to 5000"), "{err}");
    let metres = text.replace("translation_direction_error_deg", "translation_error_m");
    let err = read("hw.json", metres.as_bytes()).unwrap_err().to_string();
    assert!(err.contains("translation_error_m"), "{err}");
}

/// The lesson is told the scene by its link pairs (`two-view=N`, the variant's
/// seed and parameters): the scene they draw is the variant's, to the bit; the
/// RANSAC references' inliers are kept, the eight-point one's agreeing with
/// the truth's wrong matches; answers on adds `two-view-answers=on`.
#[test]
fn the_lesson_pairs_draw_the_variants_scene() {
    let a = builtin("two-view");
    let p = prepare(&a, "ada@uni.edu").unwrap();
    let pairs = p.lesson_pairs();
    assert!(pairs.contains(&(SCENE_KEY.to_owned(), p.steps.to_string())));
    assert!(!pairs.iter().any(|(k, _)| k == ANSWERS_KEY));
    let mut scenario = VoScenario::default();
    let params: Vec<(&str, &str)> = pairs
        .iter()
        .filter(|(k, _)| k != SCENE_KEY)
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    assert!(crate::params::apply_pairs(&mut scenario, params, &[]).is_empty());
    let from_link = TwoViewRun::simulate(&scenario, p.steps as usize);
    let variant = TwoViewRun::for_variant(&p.assignment, &p.variant, p.steps);
    assert_eq!(from_link.matches, variant.matches);
    assert_eq!(from_link.truth, variant.truth);
    assert_eq!(from_link.references, variant.references);
    assert_eq!(from_link.inliers, variant.inliers);
    let (name, inliers) = &variant.inliers[0];
    assert_eq!(name, "eight-point");
    assert_eq!(inliers.len(), variant.matches.len());
    // RANSAC keeps the right matches and drops the wrong ones, nearly all.
    let count = |inlier: bool, wrong: bool| {
        inliers
            .iter()
            .zip(&variant.wrong)
            .filter(|(i, w)| **i == inlier && **w == wrong)
            .count()
    };
    println!(
        "{} matches: right kept {}, right dropped {}, wrong kept {}, wrong dropped {}",
        variant.matches.len(),
        count(true, false),
        count(false, false),
        count(true, true),
        count(false, true)
    );
    // No wrong match is kept (a random pixel seldom lands within the
    // threshold of its epipolar line); Ada's variant: 10 of 163 right ones are
    // dropped, their 1 px noise (on each axis of both images) putting them
    // past the threshold.
    assert_eq!(count(true, true), 0);
    assert_eq!(
        count(false, true),
        variant.wrong.iter().filter(|w| **w).count()
    );
    assert_eq!((count(true, false), count(false, false)), (153, 10));
    // The top view of the truth: camera b's centre -Rᵀt (2 m from a) seen
    // from above, forward (z) and left (-x).
    let b = variant.top_view_of(&variant.truth);
    let centre = -(variant.truth.rotation.transpose() * variant.truth.translation);
    assert!((centre.norm() - 2.0).abs() < 1e-12);
    assert!((b.x - centre.z).abs() < 1e-12 && (b.y + centre.x).abs() < 1e-12);
    let mut with_answers = a.clone();
    with_answers.answers_included = true;
    let p = coursework::prepare(&with_answers, "ada@uni.edu", &[RUNNER]).unwrap();
    assert!(
        p.lesson_pairs()
            .contains(&(ANSWERS_KEY.to_owned(), "on".to_owned()))
    );
}
