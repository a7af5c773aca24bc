//! A steady screen: nothing moves under the cursor while a run goes on (the time
//! bar keeps its height and its controls their places, whatever its text says),
//! the notices have one place, are counted and clear when they no longer hold, and
//! the address follows the lesson on screen.

use super::common::{harness_sized as harness, label_visible, lesson_of, lesson_of_mut};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use slamlab_app::SlamLabApp;
use slamlab_app::lesson::Lesson as _;
use slamlab_app::registry::LESSONS;
use slamlab_app::time_control::TimeAction;

/// The time bar's controls, by label: where a student's cursor rests.
const CONTROLS: [&str; 4] = ["Step back", "Reset", "max", "Speed"];

/// The rectangles of the time bar and of its controls in the last frame.
fn bar_layout(h: &Harness<'_, SlamLabApp>) -> Vec<(String, egui::Rect)> {
    let bar = h.state().time_bar_rect().unwrap_or(egui::Rect::NOTHING);
    let in_bar = |label: &str| {
        h.query_all_by_label(label)
            .map(|n| n.rect())
            .find(|r| bar.expand(1.0).contains_rect(*r))
    };
    let mut out = vec![("time bar".to_owned(), bar)];
    let run = in_bar("Run").or_else(|| in_bar("Pause"));
    out.push(("Run".to_owned(), run.unwrap_or(egui::Rect::NOTHING)));
    let steps: Vec<&str> = match h.state().lesson().step_controls() {
        slamlab_app::time_control::StepControls::PhasesAndTicks => vec!["Step phase", "Step tick"],
        slamlab_app::time_control::StepControls::One { label, .. } => vec![label],
    };
    for label in CONTROLS.iter().copied().chain(steps) {
        out.push((
            label.to_owned(),
            in_bar(label).unwrap_or(egui::Rect::NOTHING),
        ));
    }
    out
}

/// Runs `query` at `size` through ticks and phases whose names, counters and
/// moments differ (a run started, single phases, many ticks at once), and
/// returns every frame's time-bar layout that differs from the first.
fn bar_moves(query: &str, size: egui::Vec2) -> Vec<String> {
    let mut h = harness(query, size);
    h.run();
    let first = bar_layout(&h);
    let mut moves = Vec::new();
    let mut check = |h: &Harness<'_, SlamLabApp>, what: &str| {
        let now = bar_layout(h);
        for ((name, a), (_, b)) in first.iter().zip(&now) {
            if (a.min - b.min).length() > 0.5 || (a.size() - b.size()).length() > 0.5 {
                moves.push(format!(
                    "{query} at {}x{} after {what}: {name} {a:?} -> {b:?}",
                    size.x, size.y
                ));
            }
        }
    };
    // Running: the clock, the Pause label, the next phase as it comes.
    h.state_mut().apply_time_action(TimeAction::ToggleRun);
    for k in 0..6 {
        h.step();
        check(&h, &format!("running frame {k}"));
    }
    h.state_mut().apply_time_action(TimeAction::ToggleRun);
    h.run();
    check(&h, "pause");
    for (phases, ticks) in [(1, 0), (2, 0), (0, 3), (1, 12), (3, 30)] {
        for _ in 0..phases {
            h.state_mut().apply_time_action(TimeAction::StepPhase);
        }
        for _ in 0..ticks {
            h.state_mut().apply_time_action(TimeAction::StepTick);
        }
        h.run();
        check(
            &h,
            &format!(
                "{phases} phases and {ticks} ticks (tick {})",
                h.state().lesson().time_info().tick
            ),
        );
    }
    moves
}

/// Every lesson at 1280 x 800 and 800 x 500: the time bar's height and each of
/// its controls' rectangles are the same in every frame of a run (its text,
/// "Next phase: …", "tick 123", never pushes a control aside or wraps the bar).
#[test]
fn the_time_bar_keeps_its_height_and_its_controls_their_places() {
    let mut moves = Vec::new();
    for entry in LESSONS {
        let mut queries = vec![format!("lesson={}&seed=5", entry.id)];
        if entry.id == "mapping" {
            queries.push("lesson=mapping&seed=5&poses=grid-fastslam&particles=8".to_owned());
        }
        for query in &queries {
            for size in [egui::vec2(1280.0, 800.0), egui::vec2(800.0, 500.0)] {
                moves.extend(bar_moves(query, size));
            }
        }
    }
    assert!(
        moves.is_empty(),
        "{} moves:\n{}",
        moves.len(),
        moves.join("\n")
    );
}

/// At 1280 x 800 the time bar is one row, at 800 x 500 two: never a wrapped third
/// line, whatever a lesson's phase is called.
#[test]
fn the_time_bar_is_one_row_wide_and_two_narrow() {
    for entry in LESSONS {
        for (size, rows) in [
            (egui::vec2(1280.0, 800.0), 1.0),
            (egui::vec2(800.0, 500.0), 2.0),
        ] {
            let mut h = harness(&format!("lesson={}&seed=5&tick=3", entry.id), size);
            h.run();
            let bar = h.state().time_bar_rect().unwrap_or(egui::Rect::NOTHING);
            let row = 30.0;
            assert!(
                bar.height() <= rows * row + 6.0,
                "{} at {size:?}: the time bar is {:.0} points tall",
                entry.id,
                bar.height()
            );
        }
    }
}

/// The mapping lesson's note ("Mapping again with … scan 40 of 82…") is one of the
/// notices, counted in "Notices (N)" and in the test state, lies over the map
/// without moving it or the panel's controls, and clears once the run has caught
/// up (it no longer holds). A note clears on reset and when the run steps back
/// before it.
#[test]
fn the_note_is_a_counted_notice_that_moves_nothing_and_clears() {
    use slamlab_app::mapping::MappingLesson;
    use slamlab_sim::mapping::PoseSource;
    let size = egui::vec2(1280.0, 800.0);
    let mut h = harness(
        "lesson=mapping&map=maze&seed=3&steps=200&poses=odometry",
        size,
    );
    for _ in 0..80 {
        lesson_of_mut::<MappingLesson>(&mut h).step_tick();
    }
    h.run();
    let map_before = h.state().map_rect();
    let icp = |h: &Harness<'_, SlamLabApp>| {
        h.query_all_by_label("ICP scan-to-scan (point-to-point)")
            .next()
            .map(|n| n.rect())
    };
    let icp_before = icp(&h);
    assert!(h.state().notices().is_empty(), "{:?}", h.state().notices());
    lesson_of_mut::<MappingLesson>(&mut h).set_pose_source(PoseSource::Icp);
    let note = lesson_of::<MappingLesson>(&h).note().map(str::to_owned);
    assert!(
        note.as_deref()
            .is_some_and(|n| n.starts_with("Mapping again with")),
        "{note:?}"
    );
    assert_eq!(h.state().notices(), vec![note.clone().unwrap_or_default()]);
    let state: serde_json::Value = serde_json::from_str(&h.state().test_state_json()).unwrap();
    assert_eq!(state["notices"], 1, "counted in the test state");
    // An area shows from its second frame.
    h.step();
    h.step();
    assert!(label_visible(&h, "Notices (1)"), "counted on screen");
    assert_eq!(h.state().map_rect(), map_before, "the notice moves no map");
    assert_eq!(icp(&h), icp_before, "nor the pose sources");
    // Caught up: the note no longer holds.
    for _ in 0..200 {
        if !lesson_of::<MappingLesson>(&h).test_state()["catching_up"]
            .as_bool()
            .unwrap_or(false)
        {
            break;
        }
        h.step();
    }
    h.run();
    assert_eq!(lesson_of::<MappingLesson>(&h).note(), None);
    assert!(h.state().notices().is_empty(), "{:?}", h.state().notices());
    assert!(!label_visible(&h, "Notices ("));

    // A kidnap's note clears when the run steps back before it, and on reset.
    let mut h = harness("lesson=kidnap&seed=3&tick=10", size);
    h.run();
    h.get_by_label("Kidnap").click();
    h.run();
    let note = h.state().lesson().frame().note().map(str::to_owned);
    assert!(note.is_some(), "the kidnap says where the robot went");
    assert!(h.state().notices().contains(&note.unwrap_or_default()));
    h.state_mut().apply_time_action(TimeAction::StepTick);
    h.run();
    assert!(h.state().lesson().frame().note().is_some(), "still holds");
    for _ in 0..200 {
        if h.state().lesson().time_info().tick < 10 {
            break;
        }
        h.state_mut().apply_time_action(TimeAction::StepBack);
    }
    h.run();
    assert_eq!(
        h.state().lesson().frame().note(),
        None,
        "stepped back before it"
    );
    h.get_by_label("Kidnap").click();
    h.run();
    assert!(h.state().lesson().frame().note().is_some());
    h.state_mut().apply_time_action(TimeAction::Reset);
    h.run();
    assert_eq!(h.state().lesson().frame().note(), None, "cleared on reset");
}

/// After a switch of lessons from the menu, or by "Localize in this map", the
/// address names the lesson on screen (a reload opens it, not the one before).
#[test]
fn the_address_follows_the_lesson() {
    let size = egui::vec2(1280.0, 800.0);
    let mut h = harness("lesson=landmark-slam&seed=3", size);
    h.run();
    assert_eq!(h.state().address(), "lesson=landmark-slam&seed=3");
    h.get_by_label("Lessons").click();
    h.run();
    match h.query_all_by_label("Pose-graph optimization").next() {
        Some(item) => item.click(),
        None => panic!("no Pose-graph optimization in the Lessons menu"),
    }
    h.run();
    assert_eq!(h.state().lesson_id(), "pose-graph");
    assert_eq!(h.state().address(), "lesson=pose-graph");
    assert_eq!(
        h.state_mut().take_address_change().as_deref(),
        Some("lesson=pose-graph"),
        "the browser is told once"
    );
    assert_eq!(h.state_mut().take_address_change(), None);
    // The mapping lesson hands its map over to the localization lesson.
    let mut h = harness("lesson=mapping&map=maze&seed=3&steps=60&poses=truth", size);
    for _ in 0..30 {
        lesson_of_mut::<slamlab_app::mapping::MappingLesson>(&mut h).step_tick();
    }
    h.run();
    h.get_by_label("Localize in this map").click();
    h.run();
    assert_eq!(h.state().lesson_id(), "kidnap");
    assert_eq!(h.state().address(), "lesson=kidnap");
}

/// A log named by `log=` with `run=1`: the run starts once the log is in (the
/// link's figure keys hold for the log), and the map view grows with the map.
#[test]
fn a_log_link_with_run_1_runs_and_the_view_grows_with_the_map() {
    use slamlab_sim::grid::{SimulatedLogConfig, builtin_map, simulate_log};
    let map = match builtin_map("office") {
        Ok(map) => map,
        Err(why) => panic!("no office map: {why}"),
    };
    let (log, _) = simulate_log(&map, 400, 4, &SimulatedLogConfig::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let text = slamlab_sim::io::laser_log::write_carmen(&log).unwrap_or_default();
    let path = std::env::temp_dir().join("slamlab-steady-office.clf");
    std::fs::write(&path, text).unwrap_or_else(|e| panic!("{e}"));
    let query = format!("lesson=mapping&log={}&run=1", path.display());
    let mut h = harness(&query, egui::vec2(1280.0, 800.0));
    let mut tick = 0;
    for _ in 0..120 {
        h.step();
        tick = h.state().lesson().time_info().tick;
        if tick > 40 {
            break;
        }
    }
    assert!(h.state().is_running(), "run=1 holds for the log");
    assert!(tick > 0, "the log runs: tick {tick}");
    let lesson = lesson_of::<slamlab_app::mapping::MappingLesson>(&h);
    let grid = lesson.session().sim().grid();
    let Some((i0, j0, i1, j1)) = grid.known_bounds() else {
        panic!("nothing mapped");
    };
    let r = grid.resolution();
    let bounds = [
        i0 as f64 * r,
        j0 as f64 * r,
        (i1 + 1) as f64 * r,
        (j1 + 1) as f64 * r,
    ];
    let canvas = slamlab_app::widgets::plots::figure_records(&h.ctx)
        .iter()
        .find_map(|r| r.map)
        .unwrap_or(egui::Rect::NOTHING);
    assert!(
        lesson.frame.map.shows(canvas, bounds),
        "the map {bounds:?} is in view at tick {tick}"
    );
}

/// With `SLAMLAB_UI_SHOTS=DIR`, every lesson at 1280 x 800 and 800 x 500 after a
/// few ticks, saved as PNGs to look at (no check: the other tests hold the
/// numbers).
#[test]
fn steady_screen_shots() {
    let Some(dir) = std::env::var_os("SLAMLAB_UI_SHOTS") else {
        return;
    };
    let only = std::env::var("SLAMLAB_SHOTS_ONLY").unwrap_or_default();
    for entry in LESSONS {
        if !only.is_empty() && !only.split(',').any(|o| o == entry.id) {
            continue;
        }
        for size in [egui::vec2(1280.0, 800.0), egui::vec2(800.0, 500.0)] {
            let mut h = harness(&format!("lesson={}&seed=5&tick=12", entry.id), size);
            h.run();
            if let Some(image) = super::common::render_or_skip(&mut h) {
                let name = format!("steady-{}-{}x{}.png", entry.id, size.x, size.y);
                let _ = image.save(std::path::Path::new(&dir).join(name));
            }
        }
    }
}

/// At 800 x 500 no plot's key takes more height than the plot under it, in any
/// lesson and in the visual-odometry lesson's views (its top view had a 47-point key
/// over a 34-point plot); and the landmark map keeps more than a third of the
/// window's height.
#[test]
fn at_800_by_500_keys_are_never_taller_than_their_plots() {
    use slamlab_app::widgets::plots::figure_records;
    let size = egui::vec2(800.0, 500.0);
    let mut problems = Vec::new();
    let queries = LESSONS
        .iter()
        .map(|entry| format!("lesson={}&seed=5&tick=12", entry.id))
        .chain(["lesson=visual-odometry&seed=5&tick=40".to_owned()]);
    for query in queries {
        let mut h = harness(&query, size);
        h.run();
        let records = figure_records(&h.ctx);
        for key in records.iter().filter_map(|r| r.key) {
            // The plot right under the key, overlapping it side to side.
            let below = records
                .iter()
                .filter_map(|r| r.data)
                .filter(|d| d.top() >= key.bottom() - 2.0)
                .filter(|d| d.left() < key.right() && key.left() < d.right())
                .min_by(|a, b| a.top().total_cmp(&b.top()));
            if let Some(plot) = below
                && key.height() > plot.height()
            {
                problems.push(format!(
                    "{query}: a key {:.0} points tall over a plot {:.0} tall",
                    key.height(),
                    plot.height()
                ));
            }
        }
        if query.starts_with("lesson=landmark-slam&") {
            let map = records
                .iter()
                .find_map(|r| r.map)
                .unwrap_or(egui::Rect::NOTHING);
            assert!(
                map.height() > size.y / 3.0,
                "the landmark map is {:.0} points tall",
                map.height()
            );
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// A key folded for want of height is still the plot's key: at 800 x 500 the
/// visual-odometry lesson's RANSAC plot shows "key" beside its title, and pointing
/// at it shows every entry.
#[test]
fn a_folded_key_shows_its_entries_on_hover() {
    use super::common::text_drawn;
    use slamlab_app::widgets::plots::FOLDED_KEY_TEXT;
    let mut h = harness(
        "lesson=visual-odometry&seed=5&tick=12",
        egui::vec2(800.0, 500.0),
    );
    h.run();
    assert!(!text_drawn(&h, "bound N, as log10(N)"), "folded");
    let folded = h.query_all_by_label(FOLDED_KEY_TEXT).count();
    assert!(folded >= 1, "a folded key at 800 x 500");
    // The RANSAC plot is the rightmost: its "key" too.
    let rightmost = h
        .query_all_by_label(FOLDED_KEY_TEXT)
        .max_by(|a, b| a.rect().left().total_cmp(&b.rect().left()))
        .map(|n| n.rect().center());
    if let Some(at) = rightmost {
        h.hover_at(at);
    }
    h.run();
    if let Some(dir) = std::env::var_os("SLAMLAB_UI_SHOTS")
        && let Some(image) = super::common::render_or_skip(&mut h)
    {
        let _ = image.save(std::path::Path::new(&dir).join("folded-key-800x500.png"));
    }
    for entry in ["bound N, as log10(N) / 4", "best inlier share"] {
        assert!(text_drawn(&h, entry), "{entry} shown on hover");
    }
    // At 1280 x 800 nothing is folded.
    let mut h = harness(
        "lesson=visual-odometry&seed=5&tick=12",
        egui::vec2(1280.0, 800.0),
    );
    h.run();
    assert_eq!(h.query_all_by_label(FOLDED_KEY_TEXT).count(), 0);
    assert!(text_drawn(&h, "bound N, as log10(N) / 4"));
}

/// The fusion lesson's x, y and yaw error plots are scaled to the errors, not to
/// the differential filter's 2σ band (metres, beyond ±π in yaw): each plot's y
/// range reaches at least its largest error and at most `ERROR_HEADROOM` (1.25)
/// times it, and the key says how far the cut band reaches.
#[test]
fn the_fusion_error_plots_fit_the_errors_and_say_where_the_band_is_cut() {
    use super::common::text_drawn;
    use slamlab_app::fusion::{ERROR_HEADROOM, FusionLesson};
    let mut h = harness("lesson=fusion&seed=5&tick=120", egui::vec2(1280.0, 800.0));
    h.run();
    let bounds = slamlab_app::widgets::plots::figure_bounds(&h.ctx);
    let sim = lesson_of::<FusionLesson>(&h).sim();
    for (k, title) in ["x error", "y error", "Yaw error"].into_iter().enumerate() {
        let largest = sim
            .runs()
            .iter()
            .flat_map(|r| r.samples().iter().map(move |s| s.error[k].abs()))
            .fold(0.0_f64, f64::max);
        let largest_band = sim
            .runs()
            .iter()
            .flat_map(|r| r.samples().iter().map(move |s| 2.0 * s.sigma[k]))
            .fold(0.0_f64, f64::max);
        let Some((_, [_, y0, _, y1])) = bounds.iter().find(|(t, _)| t == title) else {
            panic!("no {title} plot drawn: {bounds:?}");
        };
        let reach = y0.abs().max(y1.abs());
        eprintln!(
            "{title}: largest error {largest:.4}, 2σ up to {largest_band:.3}, y to ±{reach:.4}"
        );
        assert!(largest > 0.0);
        assert!(reach >= largest, "{title}: the largest error is in view");
        assert!(
            reach <= ERROR_HEADROOM * largest * 1.001 || reach <= 0.0101,
            "{title}: ±{reach} for errors up to {largest}"
        );
        assert!(largest_band > reach, "the band is cut here");
    }
    assert!(
        text_drawn(&h, "(cut; reaches ±"),
        "the key says how far the band reaches"
    );
}

/// Every mark the visual-odometry lesson draws is in a key: the flow lines, the
/// docking station, and whose inliers the colours are (the best hypothesis so
/// far while RANSAC runs, the final estimate once it is done).
#[test]
fn the_visual_odometry_keys_name_every_mark() {
    use super::common::text_drawn;
    let mut h = harness(
        "lesson=visual-odometry&seed=5&tick=40",
        egui::vec2(1280.0, 800.0),
    );
    h.run();
    for needle in [
        "flow (right image",
        "docking station",
        "epipolar line",
        "inlier of the",
    ] {
        assert!(text_drawn(&h, needle), "{needle} is in a key");
    }
    assert!(
        text_drawn(&h, "inlier of the final E") || text_drawn(&h, "inlier of the best E so far"),
        "whose inliers"
    );
}

/// The Cartographer lesson's *Max grids* window opens over the map, below the
/// menu and the time bar (it covered the menu bar), at 1280 x 800 and 800 x 500.
#[test]
fn the_max_grids_window_stays_off_the_menu_and_the_time_bar() {
    const TITLE: &str = "Precomputed max grids (Fig. 5.7)";
    for size in [egui::vec2(1280.0, 800.0), egui::vec2(800.0, 500.0)] {
        let mut h = harness("lesson=cartographer&seed=5&tick=12", size);
        h.run();
        assert!(h.query_by_label(TITLE).is_none());
        h.get_by_label("Max grids").click();
        h.run();
        let window = h.get_by_label(TITLE).rect();
        let button = h.get_by_label("Max grids").rect();
        assert!(
            window.intersect(button).area() <= 0.0,
            "the window {window:?} leaves its button {button:?} in view"
        );
        let bar = h.state().time_bar_rect().unwrap_or(egui::Rect::NOTHING);
        assert!(bar.is_positive(), "a time bar");
        assert!(
            window.top() >= bar.bottom(),
            "at {size:?} the window's title {window:?} is under the time bar {bar:?}"
        );
        assert!(window.bottom() <= size.y && window.right() <= size.x);
        if let Some(dir) = std::env::var_os("SLAMLAB_UI_SHOTS")
            && let Some(image) = super::common::render_or_skip(&mut h)
        {
            let name = format!("max-grids-{}x{}.png", size.x, size.y);
            let _ = image.save(std::path::Path::new(&dir).join(name));
        }
    }
}

/// The corridor's Kalman gain is a ratio of variances (m² / m²) and has no unit:
/// where the gain plot is too short to name its y axis (density, 1/m) beside it,
/// the title does not append "(1/m)" to the gain's value but names the axis.
#[test]
fn the_corridor_gain_has_no_unit_in_its_title() {
    let mut h = harness(
        "lesson=filters&seed=5&view=corridor&tick=60",
        egui::vec2(800.0, 500.0),
    );
    h.run();
    let titles: Vec<String> = super::common::drawn_texts(&h)
        .into_iter()
        .map(|(text, _, _)| text)
        .filter(|t| t.starts_with("Kalman gain at step"))
        .collect();
    if let Some(dir) = std::env::var_os("SLAMLAB_UI_SHOTS")
        && let Some(image) = super::common::render_or_skip(&mut h)
    {
        let _ = image.save(std::path::Path::new(&dir).join("corridor-gain-800x500.png"));
    }
    assert!(!titles.is_empty(), "the gain plot is drawn after a door");
    for title in titles {
        // Not "K = ... = 0.295 (1/m)".
        let unit_on_value = title
            .strip_suffix(" (1/m)")
            .is_some_and(|before| before.ends_with(|c: char| c.is_ascii_digit()));
        assert!(!unit_on_value, "{title}");
        assert!(title.ends_with("; y: density (1/m)"), "{title}");
    }
}
