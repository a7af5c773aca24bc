//! Headless UI tests of the sensor-fusion lesson through egui_kittest: it opens
//! by URL, "Step phase" applies one named reading, the RMSE table shows the
//! numbers of a headless seeded run, bad readings are skipped and counted, and
//! the rendered map shows each mode's colour.

use super::common::{
    assert_notices, count_pixels, harness_sized, lesson_accessors, render_or_skip, snapshot,
};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use slamlab_app::SlamLabApp;
use slamlab_app::fusion::FusionLesson;
use slamlab_app::lesson::Lesson as _;
use slamlab_sim::fusion::session::{BadReading, FusionEvent};
use slamlab_sim::fusion::{FusionMode, SLAM, run_modes, simulate};

const SIZE: egui::Vec2 = egui::vec2(1500.0, 950.0);

fn harness(query: &str) -> Harness<'static, SlamLabApp> {
    harness_sized(query, SIZE)
}

lesson_accessors!(FusionLesson);

#[test]
fn the_lesson_opens_by_url_and_bad_values_get_messages() {
    let h = harness("lesson=fusion&seed=4&duration=60&modes=absolute,differential");
    assert_eq!(h.state().lesson_id(), "fusion");
    let setup = lesson(&h).sim().setup();
    assert_eq!(setup.scenario.seed, 4);
    assert_eq!(setup.scenario.drive.duration, 60.0);
    assert_eq!(
        setup.modes,
        vec![FusionMode::Absolute, FusionMode::Differential]
    );
    assert!(h.state().notices().is_empty(), "{:?}", h.state().notices());
    // A rate of 0 and a noise of 0: clamped to the minimum with a message.
    let h = harness("lesson=fusion&imu-rate=0&slam-position-noise=0&modes=kalman");
    assert_notices(
        &h,
        3,
        &[
            &["imu-rate = 0 is out of range"],
            &["slam-position-noise = 0 is out of range"],
        ],
    );
    assert_eq!(lesson(&h).sim().setup().scenario.imu.rate, 0.5);
    assert_eq!(lesson(&h).sim().runs().len(), 2, "the default modes");
}

#[test]
fn a_step_names_its_sensor_and_step_back_replays() {
    let mut h = harness("lesson=fusion&seed=2&duration=30");
    h.run();
    h.get_by_label("Step phase").click();
    h.run();
    let label = lesson(&h).time_info().last_phase.unwrap_or_default();
    assert_eq!(label, "wheel odometry: v_x, v_y, yaw rate at 0.00 s");
    h.get_by_label("Step phase").click();
    h.run();
    let label = lesson(&h).time_info().last_phase.unwrap_or_default();
    assert_eq!(label, "IMU: yaw rate at 0.00 s");
    // The explanation panel names it too.
    let _ = h.get_by_label("IMU: yaw rate at 0.00 s");
    for _ in 0..5 {
        lesson_mut(&mut h).step_tick();
    }
    h.run();
    let label = lesson(&h).time_info().last_phase.unwrap_or_default();
    assert!(
        label.starts_with("SLAM pose (differential)") && label.ends_with("at 5.00 s"),
        "{label}"
    );
    let means = |h: &Harness<'_, SlamLabApp>| -> Vec<_> {
        lesson(h)
            .sim()
            .runs()
            .iter()
            .map(|r| *r.filter().mean())
            .collect()
    };
    let before = means(&h);
    h.get_by_label("Step phase").click();
    h.run();
    h.get_by_label("Step back").click();
    h.run();
    let after = means(&h);
    assert_eq!(before, after);
    // Bad readings by button: skipped, named and counted in both modes.
    h.get_by_label("NaN IMU reading").click();
    h.run();
    h.get_by_label("SLAM pose from the past").click();
    h.run();
    lesson_mut(&mut h).step_tick();
    h.run();
    for run in lesson(&h).sim().runs() {
        let stats = run.filter().stats();
        assert_eq!(
            (stats.non_finite, stats.out_of_order),
            (1, 1),
            "{:?}",
            run.mode()
        );
    }
    let notices = h.state().notices();
    assert!(
        notices.iter().any(|n| n.contains("time went backwards")),
        "{notices:?}"
    );
    // Switching the SLAM pose off: the next SLAM reading is not fed.
    lesson_mut(&mut h).apply_event(FusionEvent::SetSensor {
        sensor: SLAM,
        on: false,
    });
    let fused = lesson(&h).sim().runs()[0].filter().stats().fused;
    lesson_mut(&mut h).step_tick();
    let stats = *lesson(&h).sim().runs()[0].filter().stats();
    assert_eq!(stats.fused - fused, 150, "50 odometry and 100 IMU readings");
    lesson_mut(&mut h).apply_event(FusionEvent::Inject(BadReading::SlamBeforeStart));
    lesson_mut(&mut h).step_tick();
    assert_eq!(
        lesson(&h).sim().runs()[0].filter().stats().before_start,
        0,
        "the SLAM pose is off: its bad reading is not fed either"
    );
}

#[test]
fn the_rmse_table_shows_a_headless_seeded_run() {
    let query = "lesson=fusion&seed=3&duration=40";
    let mut h = harness(query);
    for _ in 0..41 {
        h.state_mut()
            .apply_time_action(slamlab_app::time_control::TimeAction::StepTick);
    }
    h.run();
    assert!(lesson(&h).sim().finished());
    // The same run headless (what the browser test runs in wasm).
    let headless: serde_json::Value =
        serde_json::from_str(&SlamLabApp::headless_state(query, 41)).unwrap_or_default();
    let setup = lesson(&h).sim().setup().clone();
    // Both read by the same JSON parser: the same text gives the same numbers.
    let shown_state: serde_json::Value =
        serde_json::from_str(&h.state().test_state_json()).unwrap_or_default();
    assert_eq!(shown_state["runs"], headless["runs"]);
    let log = simulate(&setup.scenario).unwrap_or_else(|e| panic!("{e}"));
    let whole = run_modes(&setup.scenario, &log, &setup.modes).unwrap_or_else(|e| panic!("{e}"));
    for (k, run) in lesson(&h).sim().runs().iter().enumerate() {
        let e = run.rmse();
        // The table shows these numbers.
        for v in [e.x, e.y, e.yaw] {
            let text = slamlab_app::fusion::rmse_text(v);
            assert!(
                h.query_all_by_label(&text).next().is_some(),
                "{text} not in the RMSE table"
            );
        }
        // And they are the experiment runner's (to rounding: it applies the
        // readings in one sweep).
        let w = whole[k].rmse();
        for (a, b) in [(e.x, w.x), (e.y, w.y), (e.yaw, w.yaw)] {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
    }
    // Pinned (web/tests/browser.test.mjs compares the wasm run with these bits).
    let pinned = [
        [
            0.018338686029263813,
            0.009054579079795273,
            0.02768865985373698,
        ],
        [
            0.07364447075865203,
            0.05369803159610187,
            0.04716598788885103,
        ],
    ];
    for (run, pinned) in lesson(&h).sim().runs().iter().zip(pinned) {
        let e = run.rmse();
        assert_eq!([e.x, e.y, e.yaw], pinned, "{:?}", run.mode());
    }
}

#[test]
fn rendered_lesson_shows_every_mode_in_its_colour() {
    let mut h = harness("lesson=fusion&seed=1&duration=120&modes=differential,relative,absolute");
    h.run();
    for _ in 0..90 {
        lesson_mut(&mut h).step_tick();
    }
    h.run();
    let Some(image) = render_or_skip(&mut h) else {
        return;
    };
    let raw = image.as_raw();
    let blue = count_pixels(raw, [0x00, 0x72, 0xB2], 30);
    let orange = count_pixels(raw, [0xE6, 0x9F, 0x00], 30);
    let purple = count_pixels(raw, [0xCC, 0x79, 0xA7], 30);
    let vermillion = count_pixels(raw, [0xD5, 0x5E, 0x00], 30);
    let grey = count_pixels(raw, [0x8C, 0x8C, 0x8C], 12);
    eprintln!(
        "blue {blue}, orange {orange}, purple {purple}, vermillion {vermillion}, grey {grey}"
    );
    assert!(blue > 800, "differential-blue pixels {blue}");
    assert!(orange > 800, "relative-orange pixels {orange}");
    assert!(purple > 800, "absolute-purple pixels {purple}");
    assert!(vermillion > 150, "SLAM-dot pixels {vermillion}");
    assert!(grey > 200, "raw-odometry grey pixels {grey}");
    snapshot(&image, "fusion_lesson");
}

#[test]
fn at_800_by_500_nothing_stray_at_the_start_and_the_wide_ellipse_is_explained() {
    assert_eq!(slamlab_app::fusion::rmse_text(-1e-9), "0.0000");
    assert_eq!(slamlab_app::fusion::rmse_text(-0.0), "0.0000");
    let mut h = harness_sized(
        "lesson=fusion&seed=1&duration=120&modes=differential,relative,absolute",
        egui::vec2(800.0, 500.0),
    );
    h.run();
    let Some(image) = render_or_skip(&mut h) else {
        return;
    };
    let _ = image.save(std::env::temp_dir().join("slamlab-fusion-800-start.png"));
    // At t = 0 every estimate sits on the robot with a covariance of 1e-9: nothing
    // of the modes' colours may reach beyond the robot's marker (a degenerate
    // ellipse or heading wedge used to draw a line to the map's edge).
    // The map's canvas, a little inside its frame.
    let canvas = slamlab_app::widgets::plots::figure_records(&h.ctx)
        .iter()
        .find_map(|r| r.map)
        .unwrap_or(egui::Rect::NOTHING)
        .shrink(2.0);
    let inside = |x: u32, y: u32| canvas.contains(egui::pos2(x as f32, y as f32));
    let robot = {
        let (mut sx, mut sy, mut n) = (0usize, 0usize, 0usize);
        for (x, y, p) in image.enumerate_pixels() {
            if inside(x, y) && p.0[..3] == [0xCC, 0x79, 0xA7] {
                sx += x as usize;
                sy += y as usize;
                n += 1;
            }
        }
        assert!(n > 0, "the absolute estimate is drawn");
        (sx / n, sy / n)
    };
    // Any colour at any strength (the map's background, grid and walls are grey;
    // the heading wedges are filled at 18% alpha, three of them on top of each other).
    let coloured = |p: &image::Rgba<u8>| {
        let [r, g, b, _] = p.0.map(i32::from);
        r.max(g).max(b) - r.min(g).min(b) > 20
    };
    let far = image
        .enumerate_pixels()
        .filter(|(x, y, p)| {
            let (dx, dy) = (*x as i64 - robot.0 as i64, *y as i64 - robot.1 as i64);
            // Inside the map's canvas (the key is above it).
            dx * dx + dy * dy > 40 * 40 && inside(*x, *y) && coloured(p)
        })
        .count();
    assert!(
        far < 10,
        "{far} coloured pixels away from the robot at t = 0"
    );
    // After a minute the differential mode's ellipse is far wider than the 4 x 3 m
    // room, with its error at centimetres; the map says so beside it.
    for _ in 0..60 {
        lesson_mut(&mut h).step_tick();
    }
    h.run();
    let run = &lesson(&h).sim().runs()[0];
    let p = run.filter().pose_covariance();
    let across = 2.0 * (slamlab_core::geometry::CHI2_2DOF_95 * p[(0, 0)].max(p[(1, 1)])).sqrt();
    assert!(across > 4.0, "differential's ellipse {across} m across");
    // The view stays on the room: the whole room shows, and it fills the canvas in
    // one direction at least (the view does not zoom out to the ellipse).
    let records = slamlab_app::widgets::plots::figure_records(&h.ctx);
    let Some(map) = records.iter().find_map(|r| r.map) else {
        panic!("no map canvas recorded");
    };
    let (x0, x1, y0, y1) = lesson(&h).map_view().transform(map).visible();
    let room = lesson(&h).sim().setup().scenario.drive.room;
    assert!(
        x0 <= -0.5 * room[0] && x1 >= 0.5 * room[0] && y0 <= -0.5 * room[1] && y1 >= 0.5 * room[1],
        "the room {room:?} in view x {x0:.2}..{x1:.2}, y {y0:.2}..{y1:.2}"
    );
    let fill = ((x1 - x0) / room[0]).min((y1 - y0) / room[1]);
    assert!(
        fill < 1.5,
        "the view is {fill:.1} times the room ({across:.1} m ellipse)"
    );
    let Some(image) = render_or_skip(&mut h) else {
        return;
    };
    let _ = image.save(std::env::temp_dir().join("slamlab-fusion-800-60s.png"));
    // The note's frame in differential-blue at the map's top right.
    let frame = image
        .enumerate_pixels()
        .filter(|(x, y, p)| *x > 500 && *y > 120 && *y < 170 && p.0[..3] == [0x00, 0x72, 0xB2])
        .count();
    assert!(frame > 100, "the note's frame: {frame} blue pixels");
}

/// The RMSE table at 800 x 500 (in the explanation drawer): no value reads
/// "−0.0000", and every column fits the drawer.
#[test]
fn the_rmse_table_fits_the_drawer_at_800_by_500() {
    let mut h = harness_sized(
        "lesson=fusion&seed=1&duration=120&modes=differential,relative,absolute&tick=20",
        egui::vec2(800.0, 500.0),
    );
    h.run();
    h.get_by_label("Explain").click();
    h.run();
    assert!(h.query_by_label("RMSE so far").is_some(), "the table shows");
    for minus in ["-0.0000", "\u{2212}0.0000", "-0.000", "\u{2212}0.000"] {
        let found: Vec<String> = h
            .query_all_by_label_contains(minus)
            .map(|n| format!("{n:?}").chars().take(200).collect())
            .collect();
        assert!(found.is_empty(), "a value reads {minus}: {found:?}");
    }
    let Some(drawer_right) = h
        .query_all_by_label("Close")
        .map(|n| n.rect().right())
        .reduce(f32::max)
    else {
        panic!("the drawer's Close button");
    };
    // The row names and the last column's head (the table has a column per mode).
    for head in ["largest jump (m)", "absolute"] {
        let Some(cell) = h.query_all_by_label(head).map(|n| n.rect()).next() else {
            panic!("no cell '{head}'");
        };
        assert!(
            cell.right() <= drawer_right + 1.0 && cell.right() <= 800.0,
            "'{head}' {cell:?} past the drawer's edge {drawer_right}"
        );
    }
    if let Some(image) = render_or_skip(&mut h) {
        let _ = image.save(std::env::temp_dir().join("slamlab-fusion-800-rmse.png"));
    }
}
