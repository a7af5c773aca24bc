//! A student's estimate in a lesson: a lesson's own estimator exported and brought
//! back scores exactly as the lesson scores it; files named in the URL, several
//! estimates and bad files; the estimate drawn on the map.

use super::common::{
    assert_corner_window_beside_the_notices, count_pixels, harness_sized as harness,
};
use egui_kittest::Harness;
use slamlab_app::SlamLabApp;
use slamlab_app::widgets::estimates::COLORS;
use slamlab_sim::io::trajectory::export_files;

fn state(h: &Harness<'_, SlamLabApp>) -> serde_json::Value {
    serde_json::from_str(&h.state().test_state_json()).unwrap_or_default()
}

fn score<'a>(state: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    state["estimates"]
        .as_array()
        .and_then(|a| a.iter().find(|s| s["name"] == name))
        .unwrap_or_else(|| panic!("no score for {name} in {}", state["estimates"]))
}

/// The lesson's files as File → Export trajectories writes them.
fn exported(h: &Harness<'_, SlamLabApp>) -> Vec<(String, Vec<u8>)> {
    let lesson = h.state().lesson();
    export_files(lesson.id(), &lesson.trajectories(), &lesson.landmark_maps())
}

/// The mapping lesson's built map as "Export map" writes it (YAML and image).
fn built_map_files(h: &Harness<'_, SlamLabApp>) -> Vec<(String, Vec<u8>)> {
    super::common::lesson_of::<slamlab_app::mapping::MappingLesson>(h)
        .map_files()
        .unwrap_or_else(|why| panic!("{why}"))
        .into_iter()
        .map(|f| (f.name, f.bytes))
        .collect()
}

fn add(h: &mut Harness<'_, SlamLabApp>, name: &str, bytes: &[u8]) -> Result<String, String> {
    h.state_mut()
        .lesson_mut()
        .frame_mut()
        .estimates_mut()
        .add(name, bytes)
}

#[test]
fn an_exported_estimator_brought_back_scores_as_the_lessons_own() {
    let mut h = harness(
        "lesson=landmark-slam&seed=5&estimator=ekf,ukf&tick=80",
        egui::vec2(1280.0, 800.0),
    );
    h.run();
    let files = exported(&h);
    let file = |name: &str| {
        files
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, b)| b.clone())
            .unwrap_or_else(|| panic!("no {name}"))
    };
    assert!(
        add(&mut h, "ekf.csv", &file("ekf.csv"))
            .unwrap()
            .contains("81 poses with covariances")
    );
    assert!(add(&mut h, "ukf.tum", &file("ukf.tum")).is_ok());
    assert!(add(&mut h, "ekf-landmarks.csv", &file("ekf-landmarks.csv")).is_ok());
    h.run();
    let st = state(&h);
    for (own, dropped) in [("ekf", "ekf.csv"), ("ukf", "ukf.tum")] {
        let (a, b) = (score(&st, own), score(&st, dropped));
        assert_eq!(a["dropped"], false);
        assert_eq!(b["dropped"], true);
        assert_eq!(a["pairs"], 81);
        assert_eq!(a["pairs"], b["pairs"]);
        for key in ["ate_rmse", "ate_max", "rpe_rmse"] {
            let (x, y) = (a[key].as_f64().unwrap(), b[key].as_f64().unwrap());
            // The TUM file holds the heading as a quaternion: 1e-9.
            assert!(
                (x - y).abs() <= 1e-9 * x.abs().max(1.0),
                "{dropped} {key}: {x} against {y}"
            );
        }
    }
    // The CSV keeps the covariances to the bit: the same ANEES; the TUM file has none.
    assert_eq!(score(&st, "ekf")["anees"], score(&st, "ekf.csv")["anees"]);
    assert!(score(&st, "ekf")["anees"].as_f64().is_some());
    assert!(score(&st, "ukf.tum")["anees"].is_null());
    // The landmarks of the EKF, matched by id, against the true map.
    let lm = score(&st, "ekf-landmarks.csv")["landmark_rmse"]
        .as_f64()
        .unwrap();
    assert!(lm > 0.0 && lm < 2.0, "{lm}");
}

#[test]
fn estimates_follow_the_time_bar_and_bad_files_change_nothing() {
    let mut h = harness(
        "lesson=landmark-slam&seed=5&tick=60",
        egui::vec2(1280.0, 800.0),
    );
    h.run();
    let ekf = exported(&h)
        .into_iter()
        .find(|(n, _)| n == "ekf.tum")
        .map(|(_, b)| b)
        .unwrap();
    add(&mut h, "mine.tum", &ekf).unwrap();
    h.run();
    assert_eq!(score(&state(&h), "mine.tum")["pairs"], 61);
    // Bad files: a zip, a NaN, a repeated time, a file too large; the estimate
    // already there stays, and each refusal names the file and the line.
    let refusals = [
        add(&mut h, "mine.zip.csv", b"PK\x03\x04xxxx").unwrap_err(),
        add(&mut h, "nan.csv", b"0,1,2,0\n0.1,NaN,2,0\n").unwrap_err(),
        add(&mut h, "twice.tum", b"0 1 2 0 0 0 0 1\n0 1 2 0 0 0 0 1\n").unwrap_err(),
        add(&mut h, "huge.csv", &vec![b'0'; 65 << 20]).unwrap_err(),
    ];
    assert!(refusals[0].contains("zip archive"), "{}", refusals[0]);
    assert_eq!(
        refusals[1],
        "nan.csv: line 2: x is NaN, not a finite number"
    );
    assert!(
        refusals[2].starts_with("twice.tum: line 2: the time 0 s repeats"),
        "{}",
        refusals[2]
    );
    assert!(
        refusals[3].contains("more than the 67108864 bytes"),
        "{}",
        refusals[3]
    );
    assert_eq!(h.state().lesson().frame().estimates().items().len(), 1);
    h.run();
    assert_eq!(score(&state(&h), "mine.tum")["pairs"], 61);
}

/// `estimate=` names a file (a path on the desktop, a file beside the page in the
/// browser), and the estimate is drawn on the map in its colour.
#[test]
fn a_linked_estimate_is_drawn_on_the_map() {
    let dir = std::env::temp_dir().join(format!("slamlab-estimate-ui-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut first = harness(
        "lesson=landmark-slam&seed=2&tick=150",
        egui::vec2(800.0, 500.0),
    );
    first.run();
    let ekf = exported(&first)
        .into_iter()
        .find(|(n, _)| n == "ekf.tum")
        .map(|(_, b)| b)
        .unwrap();
    // Someone else's: the same path, shifted by half a metre.
    let shifted: String = String::from_utf8(ekf)
        .unwrap()
        .lines()
        .map(|l| {
            let mut f: Vec<String> = l.split(' ').map(str::to_owned).collect();
            if !l.starts_with('#') {
                f[2] = format!("{}", f[2].parse::<f64>().unwrap() + 0.5);
            }
            f.join(" ") + "\n"
        })
        .collect();
    let path = dir.join("theirs.tum");
    std::fs::write(&path, shifted).unwrap();
    let query = format!(
        "lesson=landmark-slam&seed=2&tick=150&estimate={}&estimate=https://elsewhere.example/x.tum",
        path.display()
    );
    let mut h = harness(&query, egui::vec2(800.0, 500.0));
    h.run();
    let st = state(&h);
    let theirs = score(&st, "theirs.tum");
    assert_eq!(theirs["pairs"], 151);
    assert!(theirs["ate_rmse"].as_f64().unwrap() > 0.45, "{theirs}");
    assert!(
        st["notices"].as_u64().unwrap() >= 1,
        "the link to another host is refused"
    );
    if let Some(image) = super::common::shot(&mut h, "estimate-on-landmark-800x500.png") {
        let [r, g, b, _] = COLORS[0].to_array();
        let drawn = count_pixels(&image, [r, g, b], 24);
        assert!(drawn > 150, "the estimate's colour covers {drawn} pixels");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The mapping lesson's built map exported as a ROS map (as "Export map"
/// writes it) and dropped back is scored exactly as the lesson scores its
/// own: the same agreement and coverage against the true map, to the bit.
/// The same map at half the cell size (another resolution and size) is looked
/// up at the true cells' centres and scores the same; a YAML without its image
/// is refused with the reason and changes nothing; the map is drawn in its
/// colour once asked for and removed again.
#[test]
fn a_dropped_map_scores_as_the_mapping_lessons_own() {
    use slamlab_app::mapping::MappingLesson;
    use slamlab_core::grid::OccupancyGrid;
    let mut h = harness(
        "lesson=mapping&map=maze&seed=3&steps=200&poses=scan-to-map",
        egui::vec2(800.0, 500.0),
    );
    h.run();
    for _ in 0..120 {
        h.state_mut()
            .lesson_as_mut::<MappingLesson>()
            .unwrap()
            .step_tick();
    }
    let files = built_map_files(&h);
    let lesson = h.state().lesson_as::<MappingLesson>().unwrap();
    let built = lesson.built_ros_map().unwrap();
    assert!(h.state().lesson().scores_maps());
    // Half the cell size: every cell split in four, so every true cell's centre
    // finds the same state.
    let fine = {
        let (w, hh) = (built.width() * 2, built.height() * 2);
        let mut cells = Vec::with_capacity(w * hh);
        for j in 0..hh {
            for i in 0..w {
                cells.push(built.get((i / 2) as i64, (j / 2) as i64).unwrap());
            }
        }
        OccupancyGrid::new(w, hh, built.resolution() / 2.0, built.origin(), cells).unwrap()
    };
    let (yaml, image) = slamlab_sim::io::ros_map::export_map(
        &fine,
        "fine.png",
        slamlab_sim::io::ros_map::ImageFormat::Png,
    )
    .unwrap();
    h.state_mut().open_estimate_files(files.clone());
    h.state_mut().open_estimate_files(vec![
        ("fine.yaml".to_owned(), yaml.into_bytes()),
        ("fine.png".to_owned(), image),
    ]);
    // A YAML alone: refused, nothing else changes.
    let notices_before = h.state().notices().len();
    h.state_mut().open_estimate_files(vec![files[0].clone()]);
    let notices = h.state().notices();
    assert_eq!(notices.len(), notices_before + 1);
    assert!(
        notices
            .iter()
            .any(|n| n.contains("slamlab-map.yaml names the image 'slamlab-map.pgm'")),
        "{notices:?}"
    );
    assert_eq!(h.state().lesson().frame().estimates().items().len(), 2);
    h.run();
    let st = state(&h);
    let own = score(&st, "scan-to-map (map)");
    let dropped = score(&st, "slamlab-map.yaml");
    let resampled = score(&st, "fine.yaml");
    assert_eq!(own["dropped"], false);
    assert_eq!(dropped["dropped"], true);
    let truth = h
        .state()
        .lesson_as::<MappingLesson>()
        .unwrap()
        .session()
        .sim()
        .input()
        .true_map
        .clone()
        .unwrap();
    let agreement = slamlab_sim::grid::occupancy_agreement(&built, &truth).unwrap();
    let coverage = slamlab_sim::grid::occupancy_coverage(&built, &truth).unwrap();
    for s in [own, dropped, resampled] {
        assert_eq!(s["map_agreement"].as_f64(), Some(agreement), "{s}");
        assert_eq!(s["map_coverage"].as_f64(), Some(coverage), "{s}");
    }
    eprintln!("the built map after 120 scans: agreement {agreement}, coverage {coverage}");
    // Measured 0.843 and 0.104: 120 scans have seen a tenth of the maze.
    assert!(agreement > 0.8 && agreement < 0.9, "{agreement}");
    assert!(coverage > 0.05 && coverage < 0.2, "{coverage}");
    let shot = |h: &mut Harness<'_, SlamLabApp>, name: &str| {
        let image = super::common::shot(h, name)?;
        let [r, g, b, _] = COLORS[0].to_array();
        Some(count_pixels(&image, [r, g, b], 30))
    };
    // The scores beside the lesson's own.
    shot(&mut h, "map-estimate-scores-800x500.png");
    // The window closed, the map in full: drawn once asked for, in its colour.
    h.state_mut().lesson_mut().frame_mut().estimates_mut().open = false;
    h.run();
    let before = shot(&mut h, "map-estimate-hidden-800x500.png");
    h.state_mut()
        .lesson_mut()
        .frame_mut()
        .estimates_mut()
        .set_visible(0, true);
    h.run();
    if let (Some(before), Some(after)) = (before, shot(&mut h, "map-estimate-drawn-800x500.png")) {
        assert!(
            after > before + 300,
            "the map's colour covers {before} then {after} pixels"
        );
    }
    h.state_mut().lesson_mut().frame_mut().estimates_mut().open = true;
    h.state_mut()
        .lesson_mut()
        .frame_mut()
        .estimates_mut()
        .remove(0);
    h.run();
    let st = state(&h);
    assert!(
        st["estimates"]
            .as_array()
            .unwrap()
            .iter()
            .all(|s| s["name"] != "slamlab-map.yaml")
    );
    assert_eq!(
        score(&st, "fine.yaml")["map_agreement"].as_f64(),
        Some(agreement)
    );
    // Named in the URL (`estimate=` the YAML; its image is read beside it).
    let dir = std::env::temp_dir().join(format!("slamlab-map-estimate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes) in &files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let query = format!(
        "lesson=mapping&map=maze&seed=3&steps=200&estimate={}",
        dir.join("slamlab-map.yaml").display()
    );
    let mut linked = harness(&query, egui::vec2(800.0, 500.0));
    linked.run();
    let st = state(&linked);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(
        score(&st, "slamlab-map.yaml")["map_agreement"].as_f64(),
        Some(agreement),
        "{st}"
    );
}

/// A file dropped on the window, as the desktop's window system hands it over:
/// its path, read only when asked.
#[derive(Debug)]
struct DroppedPath(std::path::PathBuf);

impl egui::DroppedFile for DroppedPath {
    fn path(&self) -> &std::path::Path {
        &self.0
    }
    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

/// On the desktop a drop with a file over the cap is refused from the file's size
/// (a 65 MiB sparse file: nothing of it is read), with the browser's notice, and
/// the estimate dropped before it stays; a small file of the same drop is not
/// taken either.
#[test]
fn an_oversized_file_dropped_on_the_desktop_is_refused_unread() {
    let dir = std::env::temp_dir().join(format!("slamlab-big-drop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let big = dir.join("big.tum");
    let file = std::fs::File::create(&big).unwrap_or_else(|e| panic!("{e}"));
    file.set_len(65 << 20).unwrap_or_else(|e| panic!("{e}"));
    let mut h = harness("lesson=landmark-slam&seed=1", egui::vec2(1280.0, 800.0));
    for _ in 0..40 {
        h.state_mut()
            .apply_time_action(slamlab_app::time_control::TimeAction::StepTick);
    }
    let files = exported(&h);
    let (name, bytes) = files
        .iter()
        .find(|(n, _)| n.ends_with(".tum"))
        .unwrap_or_else(|| {
            panic!(
                "no TUM file among {:?}",
                files.iter().map(|f| &f.0).collect::<Vec<_>>()
            )
        });
    assert!(add(&mut h, name, bytes).is_ok());
    let small = dir.join("small.tum");
    std::fs::write(&small, bytes).unwrap_or_else(|e| panic!("{e}"));
    for path in [small, big] {
        h.input_mut()
            .dropped_files
            .push(std::sync::Arc::new(DroppedPath(path)));
    }
    h.run();
    let s = state(&h);
    let notices = s["notice_list"].to_string();
    assert!(
        notices.contains("big.tum has 68157440 bytes, more than the 67108864 bytes SLAM Lab reads: nothing of that drop was read"),
        "{notices}"
    );
    let names: Vec<&str> = s["estimates"]
        .as_array()
        .map(|a| a.iter().filter_map(|e| e["name"].as_str()).collect())
        .unwrap_or_default();
    assert!(names.contains(&name.as_str()), "{names:?}");
    assert!(!names.contains(&"small.tum"), "{names:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// At 800 x 500 and full size "Your estimates" stays in its corner beside
/// the mapping lesson's map (a map, its own built map and a path scored in
/// it): no wider than the corner it opens in (the tables are narrow), and the
/// notices box lies beside it, not under it.
#[test]
fn your_estimates_leaves_the_map_visible_at_800x500() {
    for (size, shot) in [
        (egui::vec2(800.0, 500.0), "estimates-mapping-800x500.png"),
        (super::common::SIZE, "estimates-mapping-full.png"),
    ] {
        let mut h = harness(
            "lesson=mapping&map=maze&seed=3&steps=200&poses=scan-to-map&tick=60&bogus=1",
            size,
        );
        h.run();
        let files = built_map_files(&h);
        let path = exported(&h)
            .into_iter()
            .find(|(n, _)| n.ends_with(".tum"))
            .unwrap();
        h.state_mut().open_estimate_files(files);
        h.state_mut().open_estimate_files(vec![path]);
        h.run();
        assert_eq!(h.state().notices().len(), 1);
        let (window, _) = assert_corner_window_beside_the_notices(&h, "Your estimates");
        let map = slamlab_app::widgets::layout::map_rect(&h.ctx).unwrap();
        // More than half of the map's width is not under the window.
        assert!(
            window.left() - map.left() > 0.5 * map.width(),
            "{window:?} over {map:?}"
        );
        super::common::shot(&mut h, shot);
    }
}

/// The mapping lesson converts its built map for "Your estimates" once per
/// change of its grid: the same map (the same `Arc`, compared with the truth
/// once) over frames that change nothing, another after a scan, each equal
/// to the map "Export map" writes.
#[test]
fn the_built_map_is_converted_once_per_change() {
    use slamlab_app::mapping::MappingLesson;
    use std::sync::Arc;
    let mut h = harness(
        "lesson=mapping&map=maze&seed=3&steps=200&tick=20",
        egui::vec2(800.0, 500.0),
    );
    h.run();
    let shared = |h: &Harness<'_, SlamLabApp>| {
        let lesson = h.state().lesson_as::<MappingLesson>().unwrap();
        let map = lesson.built_ros_map_shared().unwrap();
        assert_eq!(*map, lesson.built_ros_map().unwrap());
        map
    };
    let first = shared(&h);
    h.run();
    assert!(Arc::ptr_eq(&first, &shared(&h)));
    h.state_mut()
        .lesson_as_mut::<MappingLesson>()
        .unwrap()
        .step_tick();
    let next = shared(&h);
    assert!(!Arc::ptr_eq(&first, &next));
    assert_ne!(*first, *next);
}
