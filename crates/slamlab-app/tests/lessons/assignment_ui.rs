//! Homework by link: `assignment=ekf-slam&student=…` opens the landmark lesson
//! on the student's variant (the run `slamlab export-inputs` hands out), the
//! reference EKF's trajectory and dead reckoning dropped on the window are
//! graded as `slamlab grade` grades them, another student's file is refused
//! and what was graded stays; bad links give notices.

use super::common::{harness_sized as harness, label_visible, render_or_skip};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use slamlab_app::SlamLabApp;
use slamlab_sim::coursework::{Grade, Prepared};
use slamlab_sim::io::trajectory::{read_trajectory, write_tum};
use slamlab_sim::metrics::TrajectoryRole;
use std::path::{Path, PathBuf};

const LINK: &str = "assignment=ekf-slam&student=alice@example.edu";

fn state(h: &Harness<'_, SlamLabApp>) -> serde_json::Value {
    serde_json::from_str(&h.state().test_state_json()).unwrap_or_default()
}

/// A file dropped on the window, as the desktop's window system hands it over.
#[derive(Debug)]
struct Dropped {
    path: PathBuf,
    bytes: Vec<u8>,
}

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &Path {
        &self.path
    }
    fn bytes(&self) -> Result<Vec<u8>, String> {
        Ok(self.bytes.clone())
    }
}

fn drop_file(h: &mut Harness<'_, SlamLabApp>, name: &str, bytes: Vec<u8>) {
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped {
            path: PathBuf::from(name),
            bytes,
        }));
    h.run();
}

/// The reference estimator `name` of `prepared`'s variant as a TUM file, the
/// way a student's program would hand it in.
fn reference_tum(prepared: &Prepared, name: &str) -> Vec<u8> {
    let references = prepared.references().unwrap_or_else(|e| panic!("{e}"));
    references
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, t)| write_tum(t).into_bytes())
        .unwrap_or_else(|| panic!("no reference {name}"))
}

/// Drops the variant's reference estimator `ekf` as `ekf.tum` and its dead
/// reckoning as `dead-reckoning.tum`: the two grades the lesson lists (the
/// test fails unless there are two), with the library's grades of the same
/// files.
fn drop_ekf_and_dead_reckoning(
    h: &mut Harness<'_, SlamLabApp>,
    prepared: &Prepared,
    ekf: &str,
) -> (Vec<serde_json::Value>, Grade, Grade) {
    let (ekf, dead_reckoning) = (
        reference_tum(prepared, ekf),
        reference_tum(prepared, "dead-reckoning"),
    );
    drop_file(h, "ekf.tum", ekf.clone());
    drop_file(h, "dead-reckoning.tum", dead_reckoning.clone());
    let st = state(h);
    let graded = st["assignment"]["graded"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    assert_eq!(graded.len(), 2, "{}", st["assignment"]);
    let grade = |name: &str, bytes: &[u8]| {
        prepared
            .grade(name, bytes)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    (
        graded,
        grade("ekf.tum", &ekf),
        grade("dead-reckoning.tum", &dead_reckoning),
    )
}

/// Alice's variant as the command line makes it (`slamlab export-inputs` and
/// `slamlab grade` call the same library).
fn alices() -> Prepared {
    slamlab_sim::assignments::builtin("ekf-slam")
        .and_then(|a| slamlab_sim::assignments::prepare(&a, "alice@example.edu"))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The link opens the landmark lesson on Alice's variant: the lesson's true
/// path is, pose for pose, `answers/truth.tum` of `slamlab export-inputs
/// ekf-slam --student alice@example.edu --answers`.
#[test]
fn the_link_opens_the_students_variant_in_its_lesson() {
    let mut h = harness(&format!("{LINK}&tick=150"), egui::vec2(1280.0, 800.0));
    h.run();
    let st = state(&h);
    let prepared = alices();
    assert_eq!(st["lesson"], "landmark-slam");
    assert_eq!(st["seed"], prepared.variant.seed);
    assert_eq!(st["assignment"]["stage"], "ready");
    assert_eq!(st["assignment"]["variant"], prepared.variant.code.as_str());
    assert_eq!(st["assignment"]["steps"], prepared.steps);
    assert_eq!(st["notices"], 0, "{}", h.state().notices().join("; "));
    let files = prepared.input_files(true).files;
    let truth_file = files
        .iter()
        .find(|(name, _)| name == "answers/truth.tum")
        .map(|(_, b)| b.clone())
        .unwrap();
    let answers = read_trajectory("truth.tum", &truth_file)
        .unwrap()
        .trajectory;
    let truth = lesson_truth(&h);
    assert_eq!(truth.len(), 151);
    for (k, (a, b)) in truth.poses().iter().zip(answers.poses()).enumerate() {
        assert_eq!((a.x, a.y), (b.x, b.y), "pose {k}");
        assert!((a.theta - b.theta).abs() < 1e-12, "pose {k}");
        assert_eq!(truth.stamps()[k], answers.stamps()[k]);
    }
    // The library's own truth, to the bit.
    assert_eq!(
        truth.poses(),
        &prepared.truth().poses()[..151],
        "the lesson's run is the variant's"
    );
    assert!(label_visible(&h, "Download inputs"));
    assert!(label_visible(&h, "Open your estimate"));
}

/// The reference EKF's trajectory passes, dead reckoning fails, each with the
/// library's grade; the two are listed; another student's file is refused with
/// the grader's message and changes nothing.
#[test]
fn dropped_estimates_are_graded_and_another_variant_is_refused() {
    let mut h = harness(LINK, egui::vec2(1280.0, 800.0));
    h.run();
    let prepared = alices();
    let (graded, expected_ekf, expected_dr) = drop_ekf_and_dead_reckoning(&mut h, &prepared, "ekf");
    assert_eq!(graded[0]["file"], "ekf.tum");
    assert_eq!(graded[0]["score"], 100.0);
    assert_eq!(graded[0]["pass"], true);
    assert_eq!(graded[0]["score"], expected_ekf.score);
    assert_eq!(graded[0]["sha256"], expected_ekf.estimate_sha256.as_str());
    assert_eq!(graded[1]["pass"], false);
    assert_eq!(graded[1]["score"], expected_dr.score);
    let ate = graded[1]["criteria"][0]["value"].as_f64().unwrap();
    assert_eq!(Some(ate), expected_dr.criteria[0].value);
    assert!(ate > 0.5, "dead reckoning's ATE {ate} m");
    // Both are drawn on the map as the lesson's estimates.
    let items = h.state().lesson().frame().estimates().items().len();
    assert_eq!(items, 2);
    // Bob's file: refused with the grader's reason; Alice's two grades stay.
    let bob = {
        let assignment = slamlab_sim::assignments::builtin("ekf-slam").unwrap();
        let theirs = slamlab_sim::assignments::prepare(&assignment, "bob@example.edu").unwrap();
        write_tum(&theirs.references().unwrap()[0].1).into_bytes()
    };
    drop_file(&mut h, "bob.tum", bob);
    let st = state(&h);
    assert_eq!(st["assignment"]["graded"].as_array().map(Vec::len), Some(2));
    let message = st["assignment"]["message"].as_str().unwrap_or_default();
    assert!(
        message.starts_with("bob.tum: the estimate has")
            && message.contains("another student's variant"),
        "{message}"
    );
    assert!(h.state().notices().iter().any(|n| n == message));
    assert_eq!(h.state().lesson().frame().estimates().items().len(), 2);
    super::common::shot(&mut h, "assignment-1280x800.png");
}

/// Bad links: an unknown assignment, an empty student, a student without an
/// assignment, a seed the variant sets: notices that name the value, and the
/// lesson runs.
#[test]
fn bad_homework_links_give_notices_and_the_lesson_runs() {
    let mut h = harness(
        "lesson=kidnap&assignment=ekf-slamm&student=ada",
        egui::vec2(1280.0, 800.0),
    );
    h.run();
    let notices = h.state().notices();
    assert!(
        notices
            .iter()
            .any(|n| n.contains("'ekf-slamm'") && n.contains("ekf-slam, mcl")),
        "{notices:?}"
    );
    assert_eq!(h.state().lesson_id(), "kidnap");
    let mut h = harness(
        "student=&assignment=https://x.example/a.json",
        egui::vec2(800.0, 500.0),
    );
    h.run();
    let notices = h.state().notices();
    assert!(
        notices.iter().any(|n| n.starts_with("student = ''")),
        "{notices:?}"
    );
    assert!(
        notices
            .iter()
            .any(|n| n.starts_with("assignment = 'https://x.example/a.json'")),
        "{notices:?}"
    );
    assert!(h.state().assignment().is_none());
    let mut h = harness("student=ada", egui::vec2(800.0, 500.0));
    h.run();
    assert!(h.state().notices()[0].contains("give the assignment too"));
    let mut h = harness(
        &format!("{LINK}&seed=3&estimator=ekf"),
        egui::vec2(800.0, 500.0),
    );
    h.run();
    let st = state(&h);
    assert_eq!(st["seed"], alices().variant.seed);
    assert_eq!(st["filters"], serde_json::json!(["ekf"]));
    let notices = h.state().notices();
    assert_eq!(notices.len(), 1, "{notices:?}");
    assert!(
        notices[0].starts_with("link: seed = 3 is left out"),
        "{notices:?}"
    );
}

/// Without `student=` the window asks for the id; typed, it opens the
/// variant.
#[test]
fn a_student_types_their_id() {
    let mut h = harness("assignment=ekf-slam", egui::vec2(800.0, 500.0));
    h.run();
    assert_eq!(state(&h)["assignment"]["stage"], "needs-student");
    assert!(label_visible(&h, "Open my variant"));
    h.get_by_role_and_label(egui::accesskit::Role::TextInput, "id")
        .focus();
    h.run();
    h.get_by_role_and_label(egui::accesskit::Role::TextInput, "id")
        .type_text("alice@example.edu");
    h.run();
    h.get_by_label("Open my variant").click();
    h.run();
    let st = state(&h);
    assert_eq!(st["assignment"]["stage"], "ready", "{}", st["assignment"]);
    assert_eq!(st["assignment"]["variant"], alices().variant.code.as_str());
    // The lesson opened on the variant.
    assert_eq!(st["seed"], alices().variant.seed);
    assert!(
        h.state()
            .share_query(false)
            .contains("student=alice%40example.edu")
    );
}

/// An assignment file beside the page (a path on the desktop) is read, and a
/// bad one is refused with its name.
#[test]
fn an_assignment_file_is_read_or_refused() {
    let dir = std::env::temp_dir().join(format!("slamlab-assignment-ui-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = dir.join("hw3.json");
    let text = slamlab_sim::coursework::BUILTIN[0]
        .1
        .replace("\"id\": \"ekf-slam\"", "\"id\": \"hw3\"");
    std::fs::write(&good, text).unwrap();
    let bad = dir.join("bad.json");
    std::fs::write(&bad, "{\"id\": \"hw3\", \"lesson\": \"landmark-slam\"").unwrap();
    let mut h = harness(
        &format!("lesson=kidnap&assignment={}&student=ada", good.display()),
        egui::vec2(1280.0, 800.0),
    );
    h.run();
    let st = state(&h);
    assert_eq!(st["assignment"]["stage"], "ready", "{}", st["assignment"]);
    assert_eq!(st["assignment"]["id"], "hw3");
    assert_eq!(st["lesson"], "landmark-slam");
    let variant = slamlab_sim::coursework::Variant::new("hw3", "ada");
    assert_eq!(st["seed"], variant.seed);
    let mut h = harness(
        &format!("assignment={}&student=ada", bad.display()),
        egui::vec2(1280.0, 800.0),
    );
    h.run();
    let st = state(&h);
    assert_eq!(st["assignment"]["stage"], "failed");
    let problem = st["assignment"]["problem"].as_str().unwrap_or_default();
    assert!(problem.contains("bad.json"), "{problem}");
    assert!(h.state().notices().iter().any(|n| n == problem));
    let _ = std::fs::remove_dir_all(&dir);
}

/// At 800 x 500 the Assignment panel sits beside the map (the map keeps the
/// rest of the window, nothing of it covered), its actions reachable, and the
/// graded estimate drawn on the map in its colour.
#[test]
fn the_panel_sits_beside_the_map_at_800_by_500() {
    let mut h = harness(&format!("{LINK}&tick=300"), egui::vec2(800.0, 500.0));
    h.run();
    let prepared = alices();
    let ekf = write_tum(&prepared.references().unwrap()[0].1).into_bytes();
    drop_file(&mut h, "estimate.tum", ekf);
    h.run();
    let st = state(&h);
    assert_eq!(st["assignment"]["graded"][0]["pass"], true);
    for action in [
        "Download inputs",
        "Open your estimate",
        "Report (JSON)",
        "Picture (PNG)",
    ] {
        assert!(label_visible(&h, action), "{action}");
    }
    let map = h.state().map_rect().unwrap();
    let panel_left = 800.0 - 0.36 * 800.0;
    assert!(
        map.right() <= panel_left + 2.0,
        "the map {map:?} reaches under the panel"
    );
    super::common::shot(&mut h, "assignment-800x500.png");
    assert!(
        map.width() >= 400.0 && map.height() >= 150.0,
        "the map {map:?}"
    );
    if let Some(image) = super::common::shot(&mut h, "assignment-800x500.png") {
        let [r, g, b, _] = slamlab_app::widgets::estimates::COLORS[0].to_array();
        let drawn = super::common::count_pixels(&image, [r, g, b], 24);
        assert!(drawn > 100, "the estimate's colour covers {drawn} pixels");
    }
}

/// The `mcl` assignment opens the Monte Carlo localization lesson on the
/// variant's run: tracking from the given start, never kidnapped, the robot's
/// true path the one the CARMEN log was written from.
#[test]
fn the_mcl_link_opens_the_variants_localization_run() {
    let mut h = harness(
        "assignment=mcl&student=alice@example.edu&tick=400&kidnap-at=200",
        egui::vec2(1280.0, 800.0),
    );
    h.run();
    let st = state(&h);
    assert_eq!(st["lesson"], "kidnap");
    // A kidnap would change the run the log was written from: refused.
    let notices = h.state().notices();
    assert_eq!(notices.len(), 1, "{notices:?}");
    assert!(
        notices[0].starts_with("link: kidnap-at = 200 is left out"),
        "{notices:?}"
    );
    let assignment = slamlab_sim::assignments::builtin("mcl").unwrap();
    let prepared = slamlab_sim::assignments::prepare(&assignment, "alice@example.edu").unwrap();
    assert_eq!(st["seed"], prepared.variant.seed);
    let expected = prepared.truth();
    let truth = &lesson_truth(&h);
    let mut compared = 0;
    for (t, pose) in truth.stamps().iter().zip(truth.poses()) {
        if let Some(k) = expected.stamps().iter().position(|s| s == t) {
            assert_eq!(pose, &expected.poses()[k], "t = {t}");
            compared += 1;
        }
    }
    assert!(compared >= 400, "{compared} poses compared");
}

/// The open lesson's true trajectory (the test fails when it has none).
fn lesson_truth(h: &Harness<'_, SlamLabApp>) -> slamlab_sim::metrics::Trajectory {
    h.state()
        .lesson()
        .trajectories()
        .into_iter()
        .find(|t| t.role == TrajectoryRole::Truth)
        .map(|t| t.trajectory)
        .unwrap_or_else(|| panic!("the lesson has no truth"))
}

/// Saves what the Assignment panel's `button` makes to `path` (the desktop's
/// save window) and returns its bytes; `None` without a renderer (a PNG).
fn save_from_panel(h: &mut Harness<'_, SlamLabApp>, button: &str, path: &Path) -> Option<Vec<u8>> {
    h.get_by_label(button).click();
    for _ in 0..4 {
        h.step();
    }
    let save_path = h.state_mut().exporter.save_path_mut()?;
    *save_path = path.to_string_lossy().into_owned();
    h.run();
    h.get_by_label("Save").click();
    h.run();
    let status = h.state().exporter.status.clone().unwrap_or_default();
    assert!(status.starts_with("Saved"), "{button}: {status}");
    std::fs::read(path).ok()
}

/// The report: the JSON names the assignment, the variant, the seed, each
/// criterion, the score and the SHA-256 of the graded file, and the link that
/// opens the variant again; the picture is the window with the grade.
#[test]
fn the_grade_report_names_the_variant_and_the_file() {
    let dir = std::env::temp_dir().join(format!("slamlab-grade-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut h = harness(&format!("{LINK}&tick=200"), egui::vec2(1280.0, 800.0));
    h.run();
    let prepared = alices();
    let ekf = write_tum(&prepared.references().unwrap()[0].1).into_bytes();
    drop_file(&mut h, "estimate.tum", ekf.clone());
    let json = save_from_panel(&mut h, "Report (JSON)", &dir.join("report.json")).unwrap();
    let report: serde_json::Value = serde_json::from_slice(&json).unwrap();
    let expected = prepared.grade("estimate.tum", &ekf).unwrap();
    assert_eq!(report["format"], "slamlab-grade-report");
    assert_eq!(report["assignment"], "ekf-slam");
    assert_eq!(report["student"], "alice@example.edu");
    assert_eq!(report["variant"], expected.variant.as_str());
    assert_eq!(report["seed"], expected.seed);
    assert_eq!(report["steps"], prepared.steps);
    assert_eq!(
        report["estimate_sha256"],
        slamlab_sim::coursework::sha256_hex(&ekf)
    );
    assert_eq!(report["score"], 100.0);
    assert_eq!(report["max_score"], 100.0);
    assert_eq!(report["pass"], true);
    // Each criterion as the library grades it (serde_json reads a number back
    // to within one unit in the last place).
    let criteria = report["criteria"].as_array().unwrap();
    assert_eq!(criteria.len(), expected.criteria.len());
    for (got, want) in criteria.iter().zip(&expected.criteria) {
        assert_eq!(got["metric"], want.metric.as_str());
        assert_eq!(got["threshold"], want.threshold);
        assert_eq!(got["earned"], want.earned);
        assert_eq!(got["pass"], want.pass);
        let close = |a: &serde_json::Value, b: Option<f64>| {
            (a.as_f64().unwrap() - b.unwrap()).abs() <= 1e-15 * b.unwrap().abs()
        };
        assert!(close(&got["value"], want.value));
        for (r, w) in got["references"]
            .as_array()
            .unwrap()
            .iter()
            .zip(&want.references)
        {
            assert_eq!(r["name"], w.name.as_str());
            assert!(close(&r["value"], w.value));
        }
    }
    // The link opens the same variant at the same tick.
    let link = report["link"].as_str().unwrap();
    let again = SlamLabApp::from_query(link);
    assert_eq!(again.lesson().time_info().tick, 200);
    assert_eq!(
        again
            .assignment()
            .and_then(|d| d.prepared())
            .map(|p| p.variant.seed),
        Some(expected.seed)
    );
    assert!(again.notices().is_empty(), "{:?}", again.notices());
    if let Some(png) = save_from_panel(&mut h, "Picture (PNG)", &dir.join("report.png")) {
        assert!(png.starts_with(b"\x89PNG"));
        if let Some(shots) = std::env::var_os("SLAMLAB_UI_SHOTS") {
            let _ = std::fs::write(Path::new(&shots).join("grade-report.png"), &png);
        }
        // The picture shows the whole estimate (1,108 steps), the window the part
        // up to the time bar's tick 200: far more of the estimate's colour.
        let [r, g, b, _] = slamlab_app::widgets::estimates::COLORS[0].to_array();
        let decoder = png::Decoder::new(std::io::Cursor::new(&png));
        let mut reader = decoder.read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut pixels).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgba);
        let in_picture = super::common::count_pixels(&pixels[..info.buffer_size()], [r, g, b], 24);
        if let Some(image) = render_or_skip(&mut h) {
            let on_screen = super::common::count_pixels(&image, [r, g, b], 24);
            assert!(
                in_picture > 2 * on_screen.max(50),
                "the estimate's colour covers {in_picture} pixels in the picture, {on_screen} on screen"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every built-in assignment's link opens its lesson on the variant, without a
/// notice (the panel uses only the generic `Prepared` API, so new kinds of
/// assignment open as the first two do).
#[test]
fn every_built_in_assignment_opens_its_lesson() {
    for name in slamlab_sim::assignments::builtin_names() {
        let mut h = harness(
            &format!("assignment={name}&student=alice@example.edu"),
            egui::vec2(1280.0, 800.0),
        );
        h.run();
        let st = state(&h);
        let prepared = slamlab_sim::assignments::builtin(name)
            .and_then(|a| slamlab_sim::assignments::prepare(&a, "alice@example.edu"))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            st["assignment"]["stage"], "ready",
            "{name}: {}",
            st["assignment"]
        );
        assert_eq!(st["lesson"], prepared.assignment.lesson.as_str(), "{name}");
        assert_eq!(st["assignment"]["seed"], prepared.variant.seed, "{name}");
        assert_eq!(h.state().notices(), Vec::<String>::new(), "{name}");
        assert!(label_visible(&h, "Download inputs"), "{name}");
    }
}

/// `assignment=fusion`: the fusion lesson opens on the student's drive (the
/// seed, the drive's length, the reference's mode first), its true path is the
/// one `answers/truth.tum` holds, and the reference EKF's trajectory dropped on
/// the window passes with every point while dead reckoning (the starter's)
/// fails, each with the library's grade.
#[test]
fn the_fusion_link_opens_the_variants_drive_and_grades_a_dropped_estimate() {
    let mut h = harness(
        "assignment=fusion&student=alice@example.edu&tick=30",
        egui::vec2(1280.0, 800.0),
    );
    h.run();
    let st = state(&h);
    let prepared = slamlab_sim::assignments::builtin("fusion")
        .and_then(|a| slamlab_sim::assignments::prepare(&a, "alice@example.edu"))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(st["lesson"], "fusion");
    assert_eq!(st["seed"], prepared.variant.seed);
    assert_eq!(st["assignment"]["stage"], "ready");
    assert_eq!(st["notices"], 0, "{}", h.state().notices().join("; "));
    assert_eq!(st["runs"][0]["mode"], "absolute", "{}", st["runs"]);
    // The lesson's truth (sampled at 30 Hz) is the variant's at every 0.1 s.
    let expected = prepared.truth();
    let truth = &lesson_truth(&h);
    let mut compared = 0;
    for (t, pose) in truth.stamps().iter().zip(truth.poses()) {
        if let Some(k) = expected.stamps().iter().position(|s| (s - t).abs() < 1e-9) {
            let e = expected.poses()[k];
            assert!(
                (pose.x - e.x).abs() < 1e-9 && (pose.y - e.y).abs() < 1e-9,
                "t = {t}: {pose:?} vs {e:?}"
            );
            compared += 1;
        }
    }
    assert!(compared >= 290, "{compared} poses compared");
    let (graded, expected_ekf, expected_dr) =
        drop_ekf_and_dead_reckoning(&mut h, &prepared, "ekf-absolute");
    assert_eq!(graded[0]["score"], 100.0);
    assert_eq!(graded[0]["pass"], true);
    assert_eq!(
        graded[0]["criteria"][0]["value"].as_f64(),
        expected_ekf.criteria[0].value
    );
    assert_eq!(graded[1]["pass"], false);
    assert_eq!(graded[1]["score"], expected_dr.score);
    assert_eq!(
        graded[1]["criteria"][0]["value"].as_f64(),
        expected_dr.criteria[0].value
    );
    // Both are drawn on the room as the lesson's estimates.
    assert_eq!(h.state().lesson().frame().estimates().items().len(), 2);
    super::common::shot(&mut h, "assignment-fusion-1280x800.png");
}

/// The answer a reference estimator writes for each of the four hand-ins that
/// are no trajectory, and a naive one, as files a student drops: the
/// reference solver's optimized graph and the problem's initial guess
/// (`pose-graph`); the map made with the true poses and a map of free cells
/// only (`grid-mapping`); the reference ICP's relative pose and the odometry's
/// (`icp`); the eight-point RANSAC's relative pose and "no rotation, straight
/// ahead" (`two-view`).
#[allow(clippy::unwrap_used)] // a test's fixture: a failure stops the test
fn reference_and_naive(name: &str, p: &Prepared) -> [(&'static str, Vec<u8>); 2] {
    let file = |path: &str| {
        p.input_files(true)
            .get(path)
            .unwrap_or_else(|| panic!("{name}: no {path}"))
            .to_vec()
    };
    let zip = |yaml: String, pgm: Vec<u8>| {
        slamlab_sim::io::archive::write_zip(
            "hand-in",
            &[
                ("map.yaml".to_owned(), yaml.into_bytes()),
                ("map.pgm".to_owned(), pgm),
            ],
        )
        .unwrap()
    };
    let pose_of = |reference: &str| {
        let (_, t) = p
            .references()
            .unwrap()
            .iter()
            .find(|(n, _)| n == reference)
            .unwrap();
        slamlab_sim::io::relative_pose::write_relative_pose(
            &slamlab_sim::mapping::icp_assignment::relative_pose_of(&t.poses()[1]),
        )
        .into_bytes()
    };
    match name {
        "pose-graph" => [
            ("reference.g2o", file("answers/reference.g2o")),
            ("estimate.g2o", file("problem.g2o")),
        ],
        "grid-mapping" => {
            let yaml = String::from_utf8(file("answers/reference.yaml"))
                .unwrap()
                .replace("reference.pgm", "map.pgm");
            let reference = zip(yaml, file("answers/reference.pgm"));
            let (truth, _) = slamlab_sim::io::map_archive::read_map_zip(
                "true.zip",
                &zip(
                    String::from_utf8(file("answers/true_map.yaml"))
                        .unwrap()
                        .replace("true_map.pgm", "map.pgm"),
                    file("answers/true_map.pgm"),
                ),
            )
            .unwrap();
            let free = slamlab_core::grid::OccupancyGrid::new(
                truth.width(),
                truth.height(),
                truth.resolution(),
                truth.origin(),
                vec![slamlab_core::grid::Cell::Free; truth.width() * truth.height()],
            )
            .unwrap();
            let (yaml, pgm) = slamlab_sim::io::ros_map::export_map(
                &free,
                "map.pgm",
                slamlab_sim::io::ros_map::ImageFormat::Pgm,
            )
            .unwrap();
            [("reference.zip", reference), ("map.zip", zip(yaml, pgm))]
        }
        "icp" => [
            ("icp.txt", pose_of("icp")),
            ("pose.txt", pose_of("odometry")),
        ],
        "two-view" => {
            use slamlab_sim::visual_odometry::assignment::{TwoViewRun, naive_pose};
            let (mut scenario, _) = slamlab_sim::coursework::apply_params::<
                slamlab_sim::visual_odometry::VoScenario,
            >(&p.assignment);
            scenario.settings.seed = p.variant.seed;
            let run = TwoViewRun::simulate(&scenario, p.steps as usize);
            let eight = run
                .references
                .iter()
                .find(|(n, _)| n == "eight-point")
                .and_then(|(_, pose)| *pose)
                .unwrap();
            let write =
                |pose| slamlab_sim::io::relative_pose::write_relative_pose(pose).into_bytes();
            [
                ("eight-point.txt", write(&eight)),
                ("pose.txt", write(&naive_pose())),
            ]
        }
        _ => panic!("no hand-in for {name}"),
    }
}

/// In-page grading of the hand-ins that are no trajectory: the link
/// `assignment=pose-graph|grid-mapping|icp|two-view&student=alice` opens the
/// lesson, the reference's answer file dropped on the window scores what
/// `slamlab grade` gives (every point, pass) and a naive answer fails with the
/// library's values, read from the Assignment panel's state.
#[test]
fn the_four_other_hand_ins_are_graded_in_the_page() {
    for name in ["pose-graph", "grid-mapping", "icp", "two-view"] {
        let mut h = harness(
            &format!("assignment={name}&student=alice"),
            egui::vec2(1280.0, 800.0),
        );
        h.run();
        assert_eq!(state(&h)["assignment"]["stage"], "ready", "{name}");
        let prepared = slamlab_sim::assignments::builtin(name)
            .and_then(|a| slamlab_sim::assignments::prepare(&a, "alice"))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let [reference, naive] = reference_and_naive(name, &prepared);
        drop_file(&mut h, reference.0, reference.1.clone());
        drop_file(&mut h, naive.0, naive.1.clone());
        let st = state(&h);
        let graded = st["assignment"]["graded"].as_array().unwrap();
        assert_eq!(graded.len(), 2, "{name}: {}", st["assignment"]);
        for (k, (file, bytes)) in [reference, naive].iter().enumerate() {
            let expected = prepared.grade(file, bytes).unwrap();
            assert_eq!(graded[k]["file"], *file, "{name}");
            assert_eq!(graded[k]["score"], expected.score, "{name} {file}");
            assert_eq!(graded[k]["pass"], expected.pass, "{name} {file}");
            assert_eq!(
                graded[k]["sha256"],
                expected.estimate_sha256.as_str(),
                "{name} {file}"
            );
            // The page's state is JSON text read back: equal to an ulp
            // (serde_json's default float parsing may be one ulp off).
            for (c, criterion) in expected.criteria.iter().enumerate() {
                let page = graded[k]["criteria"][c]["value"].as_f64().unwrap();
                let library = criterion.value.unwrap();
                assert!(
                    (page - library).abs() <= 1e-12 * library.abs().max(1.0),
                    "{name} {file} {}: {page} vs {library}",
                    criterion.metric
                );
            }
        }
        assert_eq!(graded[0]["score"], 100.0, "{name}");
        assert_eq!(graded[0]["pass"], true, "{name}");
        assert_eq!(graded[1]["pass"], false, "{name}");
        assert!(graded[1]["score"].as_f64() < Some(prepared.assignment.pass_score()));
        assert_eq!(h.state().notices(), Vec::<String>::new(), "{name}");
        super::common::shot(&mut h, &format!("assignment-{name}-1280x800.png"));
    }
}
