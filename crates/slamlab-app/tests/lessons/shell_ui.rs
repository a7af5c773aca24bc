//! Headless UI tests of the shell every lesson shares: the layout at small window
//! sizes (the map keeps its share, side panels become drawers), the embed header,
//! and the URL's figure keys (`tick=`, `run=`, `legend=`, `panels=`, `zoom=`,
//! `follow=`) with their bad values.

use super::common::{
    count_pixels, drawn_texts, harness_sized as harness, harness_themed, label_visible,
    render_or_skip, snapshot, visit_texts,
};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use slamlab_app::SlamLabApp;
use slamlab_app::registry::LESSONS;

fn state(h: &Harness<'_, SlamLabApp>) -> serde_json::Value {
    serde_json::from_str(&h.state().test_state_json()).unwrap_or_default()
}

/// The map's share of the window.
fn map_share(h: &Harness<'_, SlamLabApp>, size: egui::Vec2) -> f32 {
    let Some(rect) = h.state().map_rect() else {
        panic!("no map rectangle recorded");
    };
    rect.area() / (size.x * size.y)
}

/// The smallest share of the window the map gets, by window size, in the full
/// app and in an embed (which has no menu bar and smaller plots). At 360 x 480 the
/// plots are a drawer, closed at first.
const SIZES: [(f32, f32, f32); 3] = [
    (360.0, 480.0, 0.60),
    (800.0, 500.0, 0.45),
    (1280.0, 800.0, 0.30),
];

#[test]
fn every_lesson_keeps_the_map_at_every_window_size() {
    for entry in LESSONS {
        for embed in [false, true] {
            for (w, h_px, min_share) in SIZES {
                let size = egui::vec2(w, h_px);
                let query = format!("lesson={}{}", entry.id, if embed { "&embed=1" } else { "" });
                let mut h = harness(&query, size);
                h.run();
                let share = map_share(&h, size);
                let rect = h.state().map_rect().unwrap_or(egui::Rect::NOTHING);
                assert!(
                    share >= min_share,
                    "{query} at {w}x{h_px}: the map has {:.0}% of the window ({rect:?})",
                    100.0 * share
                );
                // Nothing is cut off: the map lies inside the window and is usable.
                assert!(
                    rect.min.x >= -0.5 && rect.max.x <= w + 0.5,
                    "{query} {w}: {rect:?}"
                );
                assert!(rect.max.y <= h_px + 0.5, "{query} {h_px}: {rect:?}");
                assert!(
                    rect.width() >= 0.9 * w || w >= 1000.0,
                    "{query} {w}: {rect:?}"
                );
                assert_eq!(h.state().is_narrow(), w < 1000.0, "{query} {w}");
                let panels = h.state().panels();
                if w < 1000.0 {
                    assert!(
                        !panels.parameters && !panels.explanation,
                        "{query} at {w}: the drawers start closed"
                    );
                }
            }
        }
    }
}

#[test]
fn a_narrow_window_opens_one_drawer_over_the_map() {
    let size = egui::vec2(800.0, 500.0);
    let mut h = harness("lesson=landmark-slam&seed=7", size);
    h.run();
    let before = h.state().map_rect();
    assert!(
        !label_visible(&h, "Share this setup"),
        "parameters start closed"
    );
    h.get_by_label("Parameters").click();
    h.run();
    assert!(h.state().panels().parameters);
    assert!(
        label_visible(&h, "Share this setup"),
        "the parameter drawer shows"
    );
    assert_eq!(
        h.state().map_rect(),
        before,
        "a drawer does not squeeze the map"
    );
    // Opening the explanation closes the parameters.
    h.get_by_label("Explain").click();
    h.run();
    let panels = h.state().panels();
    assert!(panels.explanation && !panels.parameters, "{panels:?}");
    h.get_by_label("Close").click();
    h.run();
    assert!(!h.state().panels().explanation);
    // The full layout keeps its own panels.
    let wide = harness("lesson=landmark-slam&seed=7", egui::vec2(1280.0, 800.0));
    let mut wide = wide;
    wide.run();
    assert!(wide.state().panels().parameters && wide.state().panels().explanation);
    assert!(label_visible(&wide, "Share this setup"));
}

#[test]
fn the_embed_header_replaces_the_menu_bar() {
    let size = egui::vec2(800.0, 500.0);
    let mut h = harness("lesson=kidnap&seed=3&embed=1&tick=12", size);
    h.run();
    assert!(!label_visible(&h, "Lessons"), "no menu bar in an embed");
    assert!(label_visible(&h, "Monte Carlo localization"), "the title");
    assert!(label_visible(&h, "Open full app"));
    assert!(label_visible(&h, "Ctrl+wheel to zoom"));
    let link = h.state().share_query(false);
    assert!(link.starts_with("lesson=kidnap&seed=3"), "{link}");
    assert!(link.ends_with("&tick=12"), "{link}");
    assert!(!link.contains("embed"), "{link}");
    let mut full = harness("lesson=kidnap&seed=3", size);
    full.run();
    assert!(label_visible(&full, "Lessons"));
    assert!(!label_visible(&full, "Open full app"));
}

#[test]
fn tick_and_run_open_the_figure_mid_run() {
    for entry in LESSONS {
        let app = SlamLabApp::from_query(&format!("lesson={}&seed=7&tick=30", entry.id));
        let s: serde_json::Value = serde_json::from_str(&app.test_state_json()).unwrap_or_default();
        assert_eq!(s["tick"], 30, "{}: {s}", entry.id);
        assert!(!app.is_running());
        assert!(
            app.notices().is_empty(),
            "{}: {:?}",
            entry.id,
            app.notices()
        );
        // The same as stepping 30 ticks by hand.
        assert_eq!(
            without_clock(&app.test_state_json()),
            without_clock(&SlamLabApp::headless_state(
                &format!("lesson={}&seed=7", entry.id),
                30
            )),
            "{}",
            entry.id
        );
    }
    let app = SlamLabApp::from_query("lesson=landmark-slam&tick=5&run=1");
    assert!(app.is_running());
    let app = SlamLabApp::from_query("lesson=resampling&tick=99999");
    let s: serde_json::Value = serde_json::from_str(&app.test_state_json()).unwrap_or_default();
    assert_eq!(s["tick"], 2000, "{s}");
    assert!(
        app.notices().iter().any(|n| n.contains("tick 2000")),
        "{:?}",
        app.notices()
    );
}

#[test]
fn zoom_legend_follow_and_panels_from_the_url() {
    let size = egui::vec2(1280.0, 800.0);
    let scale = |query: &str| {
        let mut h = harness(query, size);
        h.run();
        let scale = h.state_mut().lesson_mut().map_view_mut().map(|v| v.scale());
        (scale.unwrap_or(f32::NAN), h.state().notices())
    };
    for lesson in ["landmark-slam", "kidnap"] {
        let (fitted, notices) = scale(&format!("lesson={lesson}&seed=7"));
        assert!(notices.is_empty(), "{notices:?}");
        let (zoomed, notices) = scale(&format!("lesson={lesson}&seed=7&zoom=2"));
        assert!(notices.is_empty(), "{notices:?}");
        assert!(
            (zoomed / fitted - 2.0).abs() < 1e-3,
            "{lesson}: {fitted} -> {zoomed}"
        );
        for bad in ["0", "NaN", "-1", "x"] {
            let (same, notices) = scale(&format!("lesson={lesson}&seed=7&zoom={bad}"));
            // The fitted view (a little smaller: the notice bar takes some height).
            let ratio = same / fitted;
            assert!(
                (0.7..=1.0001).contains(&ratio),
                "{lesson} zoom={bad}: {fitted} -> {same}"
            );
            assert_eq!(notices.len(), 1, "{lesson} zoom={bad}: {notices:?}");
        }
    }
    // The resampling lab has no map: zoom, legend and follow say so.
    let app = SlamLabApp::from_query("lesson=resampling&zoom=2&legend=1&follow=1");
    assert_eq!(app.notices().len(), 3, "{:?}", app.notices());

    // An embed hides the legend unless the URL asks for it.
    let app = SlamLabApp::from_query("lesson=landmark-slam&embed=1&legend=1&follow=1");
    assert!(
        app.landmark_lesson()
            .is_some_and(|l| l.frame.view.legend && l.frame.view.follow_robot)
    );
    let app = SlamLabApp::from_query("lesson=landmark-slam&embed=1");
    assert!(app.landmark_lesson().is_some_and(|l| !l.frame.view.legend));

    // panels= sets exactly those panels, an unknown name is a notice.
    let mut h = harness("lesson=kidnap&panels=explanation,maps", size);
    h.run();
    let panels = h.state().panels();
    assert!(
        panels.explanation && !panels.parameters && !panels.plots,
        "{panels:?}"
    );
    assert_eq!(h.state().notices().len(), 1, "{:?}", h.state().notices());
    assert!(
        map_share(&h, size) > 0.6,
        "without plots and parameters the map has the room"
    );
    let s = state(&h);
    assert_eq!(s["panels"]["explanation"], true);
}

#[test]
fn rendered_narrow_figure_at_tick_120_shows_map_and_plots() {
    let size = egui::vec2(800.0, 500.0);
    let mut h = harness_themed(
        "lesson=landmark-slam&seed=7&embed=1&tick=120&legend=1",
        size,
        egui::Theme::Dark,
    );
    h.run();
    let s = state(&h);
    assert_eq!(s["tick"], 120);
    let Some(image) = render_or_skip(&mut h) else {
        return;
    };
    let Some(map) = h.state().map_rect() else {
        panic!("no map rectangle");
    };
    // The EKF estimate (blue) is drawn in the map and in the plots below it.
    let width = image.width() as usize;
    let ppp = image.width() as f32 / size.x;
    let split = ((map.bottom() * ppp) as usize).min(image.height() as usize);
    let raw = image.as_raw();
    let blue_map = count_pixels(&raw[..split * width * 4], [0x00, 0x72, 0xB2], 40);
    let blue_plots = count_pixels(&raw[split * width * 4..], [0x00, 0x72, 0xB2], 40);
    assert!(blue_map > 200, "EKF-blue pixels in the map: {blue_map}");
    assert!(
        blue_plots > 100,
        "EKF-blue pixels in the plots: {blue_plots}"
    );
    snapshot(&image, "shell_embed_800x500_tick120");
    // The smallest window: the full app at 360 x 480.
    let mut h = harness_themed(
        "lesson=kidnap&seed=3&tick=20",
        egui::vec2(360.0, 480.0),
        egui::Theme::Dark,
    );
    h.run();
    if let Ok(image) = h.render() {
        let purple = count_pixels(image.as_raw(), [0xCC, 0x79, 0xA7], 50);
        assert!(purple > 100, "particle-purple pixels {purple}");
        snapshot(&image, "shell_kidnap_360x480");
    }
}

/// The Keys menu lists every shortcut at body size: the time bar's five, and the
/// drive keys in lessons that drive by hand.
#[test]
fn the_keys_menu_lists_every_shortcut() {
    for (query, drive) in [
        ("lesson=landmark-slam", true),
        ("lesson=kidnap", true),
        ("lesson=resampling", false),
    ] {
        let mut h = super::common::harness(query);
        h.run();
        h.get_by_label("Keys").click();
        h.run();
        for key in ["Space", ".", ",", "n", "r"] {
            assert!(
                h.query_all_by_label(key).next().is_some(),
                "{query}: key {key:?} is not listed"
            );
        }
        assert!(super::common::label_visible(&h, "step back one phase"));
        assert_eq!(
            super::common::label_visible(&h, "drive forward"),
            drive,
            "{query}"
        );
    }
}

/// A tiny window (a phone in landscape): the plots leave the bottom for a drawer,
/// closed at first; the Plots button opens it over the map, Close shuts it.
#[test]
fn a_tiny_window_keeps_the_plots_in_a_drawer() {
    let size = egui::vec2(360.0, 480.0);
    let mut h = harness("lesson=landmark-slam&seed=7&tick=40", size);
    h.run();
    assert!(!h.state().panels().plots);
    let closed = map_share(&h, size);
    h.get_by_label("Plots").click();
    h.run();
    assert!(h.state().panels().plots);
    assert!(
        label_visible(&h, "Robot position error"),
        "no plots in the drawer"
    );
    assert!(
        (map_share(&h, size) - closed).abs() < 1e-3,
        "the drawer moved the map"
    );
    if let Ok(dir) = std::env::var("SLAMLAB_SCREENSHOTS")
        && let Ok(image) = h.render()
    {
        let _ = image.save(format!("{dir}/tiny-plots.png"));
    }
    h.get_by_label("Close").click();
    h.run();
    assert!(!h.state().panels().plots);
}

/// Every lesson's "Share this setup" link carries the figure keys: opened at tick 12,
/// stepped once, its link reopens at tick 13.
#[test]
fn every_lessons_share_link_carries_the_figure_keys() {
    for entry in LESSONS {
        let size = egui::vec2(1400.0, 900.0);
        let mut h = harness(&format!("lesson={}&seed=3&tick=12", entry.id), size);
        h.run();
        h.state_mut()
            .apply_time_action(slamlab_app::time_control::TimeAction::StepTick);
        h.run();
        // The link's text field (its text runs are its rows, cut where a narrow
        // panel wraps the link).
        let links: Vec<String> = h
            .query_all_by(|node| {
                node.role() == egui::accesskit::Role::MultilineTextInput
                    && node.value().is_some_and(|v| v.starts_with("?lesson="))
            })
            .filter_map(|node| node.value())
            .collect();
        let expected = format!("?{}", h.state().share_query(false));
        assert!(
            expected.ends_with("&tick=13"),
            "{}: the app's link {expected}",
            entry.id
        );
        assert!(
            !links.is_empty() && links.iter().all(|l| *l == expected),
            "{}: {links:?}, expected {expected}",
            entry.id
        );
    }
}

/// The share link wraps at its punctuation, never inside a lesson's name: in every
/// lesson's parameter panel at 1280 x 800 the link's first row holds the whole
/// `?lesson=ID`, and no row ends in a hyphen.
#[test]
fn the_share_link_wraps_between_its_parameters() {
    for entry in LESSONS {
        // 1280 points wide (the panel's width there), tall enough to show the link.
        let mut h = harness(
            &format!("lesson={}&seed=3&tick=12", entry.id),
            egui::vec2(1280.0, 2400.0),
        );
        h.run();
        let mut rows_of_links: Vec<Vec<String>> = Vec::new();
        fn walk(shape: &egui::Shape, out: &mut Vec<Vec<String>>) {
            match shape {
                egui::Shape::Text(t) if t.galley.text().starts_with("?lesson=") => {
                    out.push(
                        t.galley
                            .rows
                            .iter()
                            .map(|r| r.glyphs.iter().map(|g| g.chr).collect())
                            .collect(),
                    );
                }
                egui::Shape::Vec(shapes) => shapes.iter().for_each(|s| walk(s, out)),
                _ => {}
            }
        }
        for clipped in &h.output().shapes {
            walk(&clipped.shape, &mut rows_of_links);
        }
        assert!(!rows_of_links.is_empty(), "{}: no link drawn", entry.id);
        let id: String = entry.id.replace('-', "\u{2011}");
        for rows in &rows_of_links {
            assert!(
                rows[0].starts_with(&format!("?lesson={id}")),
                "{}: {rows:?}",
                entry.id
            );
            assert!(
                rows.iter()
                    .all(|r| !r.ends_with('-') && !r.ends_with('\u{2011}')),
                "{}: {rows:?}",
                entry.id
            );
        }
    }
}

/// Every lesson rendered at 1280 x 800, 800 x 500 and 360 x 480 after 40 ticks draws a picture
/// (hundreds of colours, not a blank frame). With `SLAMLAB_SCREENSHOTS=DIR` the PNGs
/// are saved there for a look.
#[test]
fn every_lesson_renders_at_three_sizes() {
    for entry in LESSONS {
        for size in [
            egui::vec2(1280.0, 800.0),
            egui::vec2(800.0, 500.0),
            egui::vec2(360.0, 480.0),
        ] {
            let mut h = harness(&format!("lesson={}&seed=5&tick=40", entry.id), size);
            h.run();
            let Ok(image) = h.render() else {
                eprintln!("skipping: no GPU adapter");
                return;
            };
            let colours: std::collections::HashSet<[u8; 4]> = image
                .as_raw()
                .chunks_exact(4)
                .map(|p| [p[0], p[1], p[2], p[3]])
                .collect();
            assert!(
                colours.len() > 100,
                "{} at {size:?}: {} colours",
                entry.id,
                colours.len()
            );
            if let Ok(dir) = std::env::var("SLAMLAB_SCREENSHOTS") {
                let _ = image.save(format!("{dir}/{}-{}x{}.png", entry.id, size.x, size.y));
            }
        }
    }
}

/// The app opened with `query` over `settings` stored by an earlier visit.
fn harness_with_settings(
    query: &str,
    settings: slamlab_app::Settings,
    size: egui::Vec2,
) -> Harness<'static, SlamLabApp> {
    let query = query.to_owned();
    Harness::builder()
        .with_size(size)
        .with_max_steps(40)
        .build_eframe(move |_cc| SlamLabApp::with_settings(&query, Some(settings.clone())))
}

/// What an earlier visit stored: the landmark lesson with its Many runs and heatmap
/// windows open, every panel open, the dark theme.
fn settings_with_windows_open() -> slamlab_app::Settings {
    let mut app = SlamLabApp::from_query("lesson=landmark-slam");
    let Some(lesson) = app.lesson_as_mut::<slamlab_app::landmark_slam::LandmarkSlamLesson>() else {
        panic!("the landmark lesson did not open");
    };
    lesson.frame.view.many_runs = true;
    lesson.frame.view.heatmap = true;
    let stored = app.lesson().stored_settings();
    let mut settings = slamlab_app::Settings {
        dark_mode: Some(true),
        panels: slamlab_app::PanelVisibility {
            parameters: true,
            explanation: true,
            plots: false,
        },
        ..Default::default()
    };
    settings.lessons.insert("landmark-slam".to_owned(), stored);
    settings
}

#[test]
fn a_link_opens_as_shared_over_stored_windows() {
    let size = egui::vec2(1280.0, 800.0);
    // Without a setup in the link, the earlier visit comes back (its windows too).
    let mut h = harness_with_settings("lesson=landmark-slam", settings_with_windows_open(), size);
    h.run();
    assert!(
        label_visible(&h, "Consistency over many runs"),
        "the stored Many runs window reopens on a plain visit"
    );
    assert!(!h.state().panels().plots, "the stored panels come back");
    // A link with a setup opens with the link's setup and the lesson's default windows.
    let link = "lesson=landmark-slam&estimator=ekf,fastslam2";
    let mut h = harness_with_settings(link, settings_with_windows_open(), size);
    h.run();
    let lesson = super::common::lesson_of::<slamlab_app::landmark_slam::LandmarkSlamLesson>(&h);
    assert!(
        !lesson.frame.view.many_runs && !lesson.frame.view.heatmap,
        "stored windows stay closed"
    );
    assert!(!label_visible(&h, "Consistency over many runs"));
    assert!(!label_visible(&h, "Covariance as correlations"));
    let names: Vec<String> = lesson
        .session()
        .filters()
        .iter()
        .map(|f| f.kind.name().to_owned())
        .collect();
    assert_eq!(names, ["ekf", "fastslam2"], "the link's estimators");
    assert_eq!(
        h.state().panels(),
        slamlab_app::PanelVisibility::default(),
        "the lesson's default panels, not the stored ones"
    );
    assert_eq!(h.ctx.theme(), egui::Theme::Dark, "the stored theme stays");
    // A figure key alone is a setup too.
    let mut h = harness_with_settings(
        "lesson=landmark-slam&tick=10",
        settings_with_windows_open(),
        size,
    );
    h.run();
    assert!(!label_visible(&h, "Consistency over many runs"));
}

/// Every text drawn in the last frame with its rectangle.
fn texts(h: &Harness<'_, SlamLabApp>) -> Vec<(String, egui::Rect)> {
    let mut out = Vec::new();
    visit_texts(h, |t, _| {
        out.push((t.galley.text().to_owned(), t.visual_bounding_rect()));
    });
    out
}

/// Every text of the last frame laid out justified over two rows or more (its
/// words spread apart to fill the width, as egui does in a justified column).
fn justified_texts(h: &Harness<'_, SlamLabApp>) -> Vec<String> {
    let mut out = Vec::new();
    visit_texts(h, |t, _| {
        if t.galley.job.justify && t.galley.rows.len() > 1 {
            out.push(t.galley.text().to_owned());
        }
    });
    out
}

/// Every text of the last frame that its clip rectangle cuts at the left or right
/// (a line running past a panel's edge), with its rectangle and its clip.
fn texts_cut_sideways(h: &Harness<'_, SlamLabApp>) -> Vec<(String, egui::Rect, egui::Rect)> {
    let mut out = drawn_texts(h);
    out.retain(|(_, rect, clip)| {
        let visible = rect.intersect(*clip);
        // Shown in part: cut at a side, not scrolled out of view.
        let shown = visible.width() > 0.5 && visible.height() > 0.5;
        shown && (rect.right() > clip.right() + 1.5 || rect.left() < clip.left() - 1.5)
    });
    out
}

/// Every lesson's side panels (open, as drawers at 800 x 500 and 360 x 480) and
/// time bar wrap their text: no line runs past a panel's edge.
#[test]
fn no_text_runs_past_a_panel_edge() {
    let mut failures = Vec::new();
    for entry in LESSONS {
        for (w, h_px) in [(360.0, 480.0), (800.0, 500.0), (1280.0, 800.0)] {
            let drawers: &[&str] = if w < 1000.0 {
                &["Parameters", "Explain"]
            } else {
                &["panels"]
            };
            for drawer in drawers {
                let query = format!("lesson={}&tick=40", entry.id);
                let mut h = harness(&query, egui::vec2(w, h_px));
                h.run();
                if w < 1000.0 {
                    h.get_by_label(drawer).click();
                    h.run();
                }
                if std::env::var_os("SLAMLAB_SCREENSHOTS").is_some()
                    && let Some(image) = render_or_skip(&mut h)
                {
                    save_screenshot(
                        &image,
                        &format!("{}_{}x{}_{drawer}", entry.id, w as u32, h_px as u32),
                    );
                }
                // A map's own labels (axis values at its edge) are cut by the map.
                let maps: Vec<egui::Rect> = slamlab_app::widgets::plots::figure_records(&h.ctx)
                    .iter()
                    .filter_map(|r| r.map)
                    .collect();
                for (text, rect, clip) in texts_cut_sideways(&h) {
                    if maps.iter().any(|m| m.expand(1.0).contains_rect(clip)) {
                        continue;
                    }
                    failures.push(format!(
                        "{query} at {w}x{h_px} ({drawer}): '{text}' {rect:?} cut by {clip:?}"
                    ));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} cut:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Saves `image` as `name`.png in `SLAMLAB_SCREENSHOTS` when that folder is set (to
/// look at every lesson at every size).
fn save_screenshot(image: &image::RgbaImage, name: &str) {
    if let Some(dir) = std::env::var_os("SLAMLAB_SCREENSHOTS") {
        let path = std::path::Path::new(&dir).join(format!("{name}.png"));
        if let Err(err) = image.save(&path) {
            eprintln!("could not save {}: {err}", path.display());
        }
    }
}

/// At 800 x 500 and 1280 x 800, in the app and embedded, every plot of every lesson
/// has numbers in its y-axis strip, and no key lies on any plot's data.
#[test]
fn every_plot_shows_its_values_and_no_key_sits_on_data() {
    let render = std::env::var_os("SLAMLAB_SCREENSHOTS").is_some();
    for entry in LESSONS {
        for embed in [false, true] {
            for (w, h_px) in [(800.0, 500.0), (1280.0, 800.0)] {
                let query = format!(
                    "lesson={}&tick=40{}",
                    entry.id,
                    if embed { "&embed=1" } else { "" }
                );
                let mut h = harness(&query, egui::vec2(w, h_px));
                h.run();
                if render && let Some(image) = render_or_skip(&mut h) {
                    let name = format!(
                        "{}_{}x{}{}",
                        entry.id,
                        w as u32,
                        h_px as u32,
                        if embed { "_embed" } else { "" }
                    );
                    save_screenshot(&image, &name);
                }
                let records = slamlab_app::widgets::plots::figure_records(&h.ctx);
                let plots: Vec<_> = records
                    .iter()
                    .filter_map(|r| r.data.map(|d| (r, d)))
                    .collect();
                let keys: Vec<egui::Rect> = records.iter().filter_map(|r| r.key).collect();
                assert!(!plots.is_empty(), "{query} at {w}x{h_px}: no plot drawn");
                // No key on a map either (the pose graph's key is a line above it).
                for map in records.iter().filter_map(|r| r.map) {
                    let figure = format!("{query} at {w}x{h_px}: the map");
                    super::common::assert_keys_off(&keys, map, &figure);
                }
                // An image figure (the pose graph's sparsity images) is on screen
                // whole: none of its blocks cut at the panel's foot.
                for image in records.iter().filter_map(|r| r.image) {
                    assert!(
                        image.min.x >= -0.5
                            && image.min.y >= -0.5
                            && image.max.x <= w + 0.5
                            && image.max.y <= h_px + 0.5
                            && image.height() >= 40.0,
                        "{query} at {w}x{h_px}: an image {image:?} is cut or tiny"
                    );
                }
                // No title or note spread out word by word to the column's width.
                let spread = justified_texts(&h);
                assert!(
                    spread.is_empty(),
                    "{query} at {w}x{h_px}: justified text {spread:?}"
                );
                let texts = texts(&h);
                for (record, data) in &plots {
                    // Room for two tick labels (13 points apart) and the data.
                    assert!(
                        data.height() >= 30.0,
                        "{query} at {w}x{h_px}: '{}' is {:.0} points tall",
                        record.title,
                        data.height()
                    );
                    // Tick labels: numbers right of the axis strip's left edge, left of the data.
                    let numbers = texts
                        .iter()
                        .filter(|(text, rect)| {
                            text.chars().any(|c| c.is_ascii_digit())
                                && rect.right() <= data.left() + 1.0
                                && rect.left() >= data.left() - 80.0
                                && rect.center().y >= data.top() - 2.0
                                && rect.center().y <= data.bottom() + 2.0
                        })
                        .count();
                    assert!(
                        numbers >= 2,
                        "{query} at {w}x{h_px}: '{}' {data:?} has {numbers} y-axis values",
                        record.title
                    );
                    let figure = format!("{query} at {w}x{h_px}: '{}'", record.title);
                    super::common::assert_keys_off(&keys, *data, &figure);
                }
            }
        }
    }
}

/// A lecture figure (`embed=1` in a 900 x 600 iframe, as web/lecture.html has
/// them) shows at most two plots, each at least 90 points tall, and the map the
/// rest: at least half the window.
#[test]
fn an_embedded_figure_has_few_tall_plots_and_a_large_map() {
    let size = egui::vec2(900.0, 600.0);
    for entry in LESSONS {
        let query = format!("lesson={}&tick=40&embed=1", entry.id);
        let mut h = harness(&query, size);
        h.run();
        if std::env::var_os("SLAMLAB_SCREENSHOTS").is_some()
            && let Some(image) = render_or_skip(&mut h)
        {
            save_screenshot(&image, &format!("{}_900x600_embed", entry.id));
        }
        let records = slamlab_app::widgets::plots::figure_records(&h.ctx);
        let plots: Vec<_> = records.iter().filter_map(|r| r.data).collect();
        assert!(
            (1..=slamlab_app::widgets::plots::EMBED_PLOTS).contains(&plots.len()),
            "{query}: {} plots",
            plots.len()
        );
        for data in &plots {
            assert!(
                data.height() >= 90.0,
                "{query}: a plot {data:?} is {:.0} points tall",
                data.height()
            );
        }
        let share = map_share(&h, size);
        assert!(share >= 0.5, "{query}: the map has {:.0}%", 100.0 * share);
    }
}

#[test]
fn esc_closes_the_windows_over_the_map_one_at_a_time() {
    let mut h = harness(
        "lesson=landmark-slam&many-runs=5",
        egui::vec2(1280.0, 800.0),
    );
    {
        let Some(lesson) = h
            .state_mut()
            .lesson_as_mut::<slamlab_app::landmark_slam::LandmarkSlamLesson>()
        else {
            panic!("the landmark lesson did not open");
        };
        lesson.frame.view.heatmap = true;
    }
    h.step();
    assert!(label_visible(&h, "Consistency over many runs"));
    h.key_press(egui::Key::Escape);
    h.step();
    h.step();
    let lesson = super::common::lesson_of::<slamlab_app::landmark_slam::LandmarkSlamLesson>(&h);
    assert!(
        !lesson.frame.view.many_runs && lesson.frame.view.heatmap,
        "Many runs first"
    );
    h.key_press(egui::Key::Escape);
    h.step();
    h.step();
    let lesson = super::common::lesson_of::<slamlab_app::landmark_slam::LandmarkSlamLesson>(&h);
    assert!(!lesson.frame.view.heatmap, "then the heatmap");
}

#[test]
fn the_lessons_menu_names_every_lesson_in_readable_text_at_800_by_500() {
    let mut h = harness("lesson=mapping", egui::vec2(800.0, 500.0));
    h.run();
    h.get_by_label("Lessons").click();
    h.run();
    for info in LESSONS {
        assert!(
            h.query_by_label(info.summary).is_some(),
            "{}'s description is in the menu",
            info.id
        );
    }
    // The descriptions are body text, not small print: a line of one is as tall as
    // a line of the menu's titles.
    let title = h.get_by_label(LESSONS[0].title).rect();
    let summary = h.get_by_label(LESSONS[0].summary).rect();
    let lines = (summary.height() / title.height()).round();
    assert!(
        lines >= 1.0 && summary.height() >= lines * title.height() * 0.8,
        "title {title:?}, description {summary:?}"
    );
    if let Some(image) = render_or_skip(&mut h) {
        let _ = image.save(std::env::temp_dir().join("slamlab-lessons-menu-800.png"));
    }
    // Choosing one opens it.
    h.get_by_label(LESSONS[1].title).click();
    h.run();
    assert_eq!(h.state().lesson_id(), LESSONS[1].id);
}

/// A lesson's state without what depends on the clock or the frame count
/// (`frames`, and `compute_ms`, how long a computation took): what two
/// runs of the same steps must agree on.
fn without_clock(state: &str) -> serde_json::Value {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(map) => {
                map.remove("frames");
                map.remove("compute_ms");
                // The Cartographer lesson's wall-clock time per scan.
                map.remove("scan_ms_median");
                map.remove("scan_ms_max");
                map.remove("phase_ms_max");
                map.remove("frame_ms_max");
                map.values_mut().for_each(strip);
            }
            serde_json::Value::Array(items) => items.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let mut v: serde_json::Value = serde_json::from_str(state).unwrap_or_default();
    strip(&mut v);
    v
}

#[test]
fn the_keys_menu_names_each_lessons_own_step() {
    let mut h = harness("lesson=pose-graph", egui::vec2(1280.0, 800.0));
    h.run();
    h.get_by_label("Keys").click();
    h.run();
    assert!(label_visible(&h, "the time bar's Step iteration"));
    assert!(
        !label_visible(&h, "Step phase"),
        "the pose graph has no phases"
    );
    let mut h = harness("lesson=kidnap", egui::vec2(1280.0, 800.0));
    h.run();
    h.get_by_label("Keys").click();
    h.run();
    assert!(label_visible(&h, "the time bar's Step phase"));
}
