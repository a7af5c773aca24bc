//! Exports from the File menu, natively: the save window writes the file where the
//! user says; the CSV has every plot's points, the scenario JSON reopens the same
//! setup, and the map PNG is the map panel's size.

use super::common::harness;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use slamlab_app::SlamLabApp;
use slamlab_app::registry::LESSONS;
use slamlab_sim::io::scenario_file::ScenarioFile;
use std::path::PathBuf;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("slamlab-exports-{}-{name}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    dir
}

/// Clicks File → `item`, lets the file arrive in the save window, saves it to `path`
/// and returns its bytes (`None` when nothing came: no renderer for a PNG).
fn export_via_menu(h: &mut Harness<'_, SlamLabApp>, item: &str, path: &PathBuf) -> Option<Vec<u8>> {
    h.get_by_label("File").click();
    h.run();
    h.get_by_label(item).click();
    // The click, the screenshot after that frame (PNG), the frame that encodes it.
    for _ in 0..4 {
        h.step();
    }
    let target = path.to_string_lossy().into_owned();
    let Some(save_path) = h.state_mut().exporter.save_path_mut() else {
        eprintln!(
            "{item}: no file to save; status {:?}",
            h.state().exporter.status
        );
        return None;
    };
    *save_path = target;
    h.run();
    h.get_by_label("Save").click();
    h.run();
    let status = h.state().exporter.status.clone().unwrap_or_default();
    assert!(status.starts_with("Saved"), "{item}: {status}");
    std::fs::read(path).ok()
}

#[test]
fn every_lesson_exports_its_plots_as_csv_and_its_scenario_as_json() {
    let dir = temp_dir("all");
    for entry in LESSONS {
        let mut h = harness(&format!("lesson={}&seed=4&tick=30", entry.id));
        h.run();
        if entry.id == "resampling" || entry.id == "pose-graph" {
            // One resampling press / solver iteration, so that the plots have data.
            h.state_mut()
                .apply_time_action(slamlab_app::time_control::TimeAction::StepTick);
            h.run();
        }
        let before = h.state().share_query(false);
        let csv = export_via_menu(&mut h, "Export plot data as CSV", &dir.join("plots.csv"))
            .unwrap_or_default();
        let text = String::from_utf8(csv).unwrap_or_default();
        let mut lines = text.lines();
        assert_eq!(
            lines.next(),
            Some("plot,x_axis,y_axis,series,x,y"),
            "{}",
            entry.id
        );
        let rows: Vec<&str> = lines.collect();
        assert!(rows.len() >= 10, "{}: {} rows", entry.id, rows.len());
        for row in &rows {
            let fields: Vec<&str> = row.rsplitn(3, ',').collect();
            assert!(
                fields.len() == 3
                    && fields[0].parse::<f64>().is_ok()
                    && fields[1].parse::<f64>().is_ok(),
                "{}: {row}",
                entry.id
            );
        }

        // Clicks on the menu and the save window above the map leave the lesson alone
        // (a pose-graph vertex under the menu is not dragged).
        assert_eq!(h.state().share_query(false), before, "{}", entry.id);
        let json = export_via_menu(
            &mut h,
            "Export scenario as JSON",
            &dir.join("scenario.json"),
        )
        .unwrap_or_default();
        let file = match ScenarioFile::parse(&String::from_utf8(json).unwrap_or_default()) {
            Ok(file) => file,
            Err(e) => panic!("{}: {e}", entry.id),
        };
        assert_eq!(file.lesson, entry.id);
        assert_eq!(file.param("seed"), Some("4"), "{}: {file:?}", entry.id);
        // Reopened in a fresh app: the same setup, at the same tick.
        let mut again = harness("lesson=landmark-slam");
        again.run();
        again.state_mut().open_scenario(&file, "scenario.json");
        again.run();
        assert_eq!(again.state().lesson_id(), entry.id);
        assert_eq!(
            again.state().share_query(false),
            h.state().share_query(false),
            "{}",
            entry.id
        );
        assert!(
            again.state().notices().is_empty(),
            "{}: {:?}",
            entry.id,
            again.state().notices()
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_map_exports_as_a_png_of_the_map_panel() {
    let dir = temp_dir("png");
    let mut h = harness("lesson=landmark-slam&seed=7&tick=20");
    h.run();
    if h.render().is_err() {
        eprintln!("skipping: no GPU adapter for the screenshot");
        return;
    }
    let Some(bytes) = export_via_menu(&mut h, "Export map as PNG", &dir.join("map.png")) else {
        panic!("no PNG was written");
    };
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let info = match decoder.read_info() {
        Ok(reader) => reader.info().clone(),
        Err(e) => panic!("not a PNG: {e}"),
    };
    let map = h.state().map_rect().unwrap_or(egui::Rect::NOTHING);
    let ppp = h.ctx.pixels_per_point();
    assert!(
        (info.width as f32 - map.width() * ppp).abs() <= 2.0
            && (info.height as f32 - map.height() * ppp).abs() <= 2.0,
        "{}x{} against the map's {map:?}",
        info.width,
        info.height
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_scenario_file_is_a_notice_and_the_lesson_stays() {
    let mut h = harness("lesson=kidnap&seed=2");
    h.run();
    let file = ScenarioFile {
        lesson: "nope".into(),
        ..ScenarioFile::default()
    };
    h.state_mut().open_scenario(&file, "odd.json");
    h.run();
    assert_eq!(h.state().lesson_id(), "kidnap");
    let notices = h.state().notices().join(" | ");
    assert!(notices.contains("odd.json: no lesson 'nope'"), "{notices}");
    // Parameters out of range in a file: the link's messages, and a safe value.
    let file = ScenarioFile {
        lesson: "landmark-slam".into(),
        params: vec![
            ("landmarks".into(), "100000".into()),
            ("seed".into(), "x".into()),
        ],
        view: vec![],
    };
    h.state_mut().open_scenario(&file, "big.json");
    h.run();
    assert_eq!(h.state().lesson_id(), "landmark-slam");
    let notices = h.state().notices().join(" | ");
    assert!(notices.contains("landmarks"), "{notices}");
}

/// Opening a scenario of another lesson keeps the lesson being left as the user had
/// it: its settings are stored, as when switching lessons from the menu.
#[test]
fn opening_a_scenario_keeps_the_left_lessons_settings() {
    let mut h = harness("lesson=landmark-slam&seed=3&landmarks=30");
    h.run();
    let file = ScenarioFile {
        lesson: "kidnap".into(),
        params: vec![("seed".into(), "2".into())],
        view: vec![],
    };
    h.state_mut().open_scenario(&file, "kidnap.json");
    h.run();
    assert_eq!(h.state().lesson_id(), "kidnap");
    let stored = h.state().settings();
    let landmark = stored.lessons.get("landmark-slam").map(ToString::to_string);
    assert!(
        landmark
            .as_deref()
            .is_some_and(|s| s.contains("\"landmarks\"") && s.contains("\"30\"")),
        "{landmark:?}"
    );
}
