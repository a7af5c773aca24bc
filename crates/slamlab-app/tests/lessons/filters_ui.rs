//! Headless UI tests of the filters lesson: it opens by URL with the polar
//! banana, a singular prior gets a note and keeps the last valid belief, the
//! time bar steps the corridor and steps back exactly, and the rendered views
//! show the samples, the EKF's blue, the UKF's orange and the particles' purple.

use super::common::{count_pixels, harness, headless, lesson_accessors, render_or_skip};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use slamlab_app::SlamLabApp;
use slamlab_app::filters::{FiltersLesson, Tab};
use slamlab_app::lesson::Lesson as _;
use slamlab_app::time_control::TimeAction;
use slamlab_core::math;

/// Where a screenshot goes: the tests' scratch folder in the target directory.
fn shot(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}.png"))
}

lesson_accessors!(FiltersLesson);

#[test]
fn the_polar_banana_opens_by_url_and_the_ukf_beats_the_ekf() {
    let mut h = harness(
        "lesson=filters&function=polar&bearing-std-deg=30&range-std=0.1&samples=20000&seed=1",
    );
    h.run();
    assert_eq!(h.state().lesson_id(), "filters");
    assert!(h.state().notices().is_empty(), "{:?}", h.state().notices());
    let r = lesson(&h).result().expect("a valid comparison");
    assert_eq!(r.truth.points.len(), 20_000);
    let (ekf, ukf) = (&r.rows[0].comparison, &r.rows[1].comparison);
    assert!(ukf.mean_error < ekf.mean_error, "{ukf:?} vs {ekf:?}");
    // E[r cos b] = e^(−σ²/2) = 0.8712 for σ = 30°: the EKF's mean stays at 1.
    assert!((ekf.mean_error - 0.1288).abs() < 0.01, "{ekf:?}");
    let Some(image) = render_or_skip(&mut h) else {
        return;
    };
    image
        .save(shot("filters_one_step"))
        .unwrap_or_else(|e| eprintln!("could not save the screenshot: {e}"));
    for (name, rgb) in [
        ("EKF blue", [0x00, 0x72, 0xB2]),
        ("UKF orange", [0xE6, 0x9F, 0x00]),
        ("particles purple", [0xCC, 0x79, 0xA7]),
    ] {
        let n = count_pixels(image.as_raw(), rgb, 30);
        assert!(n > 150, "{name}: {n} pixels");
    }
}

#[test]
fn a_singular_prior_or_zero_particles_get_a_note_and_the_last_valid_belief_stays() {
    let mut h = harness("lesson=filters&samples=5000");
    h.run();
    let before = lesson(&h).result().expect("valid").rows.clone();
    lesson_mut(&mut h).set_param("rho", "1");
    assert!(
        lesson(&h)
            .note()
            .expect("a note")
            .contains("not positive definite")
    );
    assert_eq!(lesson(&h).result().expect("kept").rows, before);
    assert!(
        lesson(&h).scenario().rho.abs() < 1.0,
        "the last valid setting stays"
    );
    lesson_mut(&mut h).set_param("particles", "0");
    assert!(lesson(&h).note().expect("a note").contains("0 particles"));
    lesson_mut(&mut h).set_param("kappa", "-2");
    assert!(lesson(&h).note().expect("a note").contains("unscented"));
    h.run();
    // A link with a singular prior opens on the function's own prior, with a notice.
    let h = harness("lesson=filters&std-1=0&samples=5000");
    assert!(lesson(&h).result().is_some());
    assert!(
        h.state()
            .notices()
            .iter()
            .any(|n| n.contains("not positive definite")),
        "{:?}",
        h.state().notices()
    );
}

#[test]
fn the_time_bar_steps_the_corridor_and_steps_back_exactly() {
    let mut h = harness("lesson=filters&view=corridor&seed=3&samples=5000");
    h.run();
    assert_eq!(lesson(&h).corridor().histogram().belief().len(), 400);
    for _ in 0..12 {
        lesson_mut(&mut h).apply_time_action(TimeAction::StepTick);
    }
    let belief = lesson(&h).corridor().histogram().belief().to_vec();
    let kalman = *lesson(&h).corridor().kalman();
    assert!((belief.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    lesson_mut(&mut h).apply_time_action(TimeAction::StepPhase);
    lesson_mut(&mut h).apply_time_action(TimeAction::StepBack);
    assert_eq!(lesson(&h).corridor().histogram().belief(), &belief[..]);
    assert_eq!(*lesson(&h).corridor().kalman(), kalman);
    h.run();
    let Some(image) = render_or_skip(&mut h) else {
        return;
    };
    image
        .save(shot("filters_corridor"))
        .unwrap_or_else(|e| eprintln!("could not save the screenshot: {e}"));
    let green = count_pixels(image.as_raw(), [0x00, 0x9E, 0x73], 30);
    assert!(green > 200, "histogram bars: {green} pixels");
    let blue = count_pixels(image.as_raw(), [0x00, 0x72, 0xB2], 30);
    assert!(blue > 50, "Kalman curve: {blue} pixels");
    lesson_mut(&mut h).set_tab(Tab::OneStep);
}

/// Presses the left button at `from`, moves to `to` in a few frames, releases.
fn drag(h: &mut Harness<'_, SlamLabApp>, from: egui::Pos2, to: egui::Pos2) {
    let button = |pos, pressed| egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    };
    h.event(egui::Event::PointerMoved(from));
    h.step();
    h.event(button(from, true));
    h.step();
    for k in 1..=8 {
        let p = from + (to - from) * (k as f32 / 8.0);
        h.event(egui::Event::PointerMoved(p));
        h.step();
    }
    h.event(button(to, false));
    h.step();
    h.run();
}

fn handles(h: &Harness<'_, SlamLabApp>) -> [egui::Pos2; 3] {
    match lesson(h).handles_on_screen() {
        Some(handles) => handles,
        None => panic!("the prior's handles are not on screen"),
    }
}

#[test]
fn dragging_the_mean_and_a_handle_moves_the_prior_and_every_gaussian_follows() {
    // The linear function y = [[1, 0.5], [0, 1]] x: the EKF and the UKF are exact.
    let mut h = harness("lesson=filters&function=linear&samples=20000&seed=2");
    h.run();
    let s = lesson(&h).scenario().clone();
    assert_eq!((s.mean, s.std, s.rho), ([0.0, 0.0], [1.0, 0.5], 0.3));
    let [mean, col1, _] = handles(&h);
    // The first handle is μ + L e₁ = (1, 0.15): one metre to the right of the mean.
    let scale = col1.x - mean.x;
    assert!(scale > 20.0, "{scale} points per unit");
    drag(&mut h, mean, mean + egui::vec2(60.0, 0.0));
    let moved = lesson(&h).scenario().mean;
    let expected = f64::from(60.0 / scale);
    assert!(
        (moved[0] - expected).abs() < 0.03 * expected && moved[1].abs() < 0.03 * expected,
        "mean {moved:?}, expected x {expected}"
    );
    assert!(lesson(&h).note().is_none(), "{:?}", lesson(&h).note());
    let r = lesson(&h).result().expect("valid");
    assert_eq!([r.prior.mean[0], r.prior.mean[1]], moved);
    // Linear: the EKF's mean is A μ exactly, and the UKF agrees with it to 1e-12.
    let (ekf, ukf) = (&r.rows[0].gaussian, &r.rows[1].gaussian);
    assert!((ekf.mean[0] - (moved[0] + 0.5 * moved[1])).abs() < 1e-12);
    assert!((ekf.mean - ukf.mean).norm() < 1e-12);
    assert!((ekf.covariance - ukf.covariance).norm() < 1e-12);
    let j = r.ekf.jacobian;
    assert_eq!(
        [j[(0, 0)], j[(0, 1)], j[(1, 0)], j[(1, 1)]],
        [1.0, 0.5, 0.0, 1.0]
    );
    // The samples' moments are within sampling error of the exact ones.
    assert!(
        r.rows[0].comparison.covariance_error < 0.05,
        "{:?}",
        r.rows[0]
    );
    // Drag the first handle out: the first deviation grows, the mean stays.
    let [mean, col1, _] = handles(&h);
    drag(&mut h, col1, col1 + egui::vec2(col1.x - mean.x, 0.0));
    let s = lesson(&h).scenario().clone();
    assert_eq!(s.mean, moved);
    assert!(s.std[0] > 1.8 && s.std[0] < 2.2, "{:?}", s.std);
    // Drag the second handle onto the mean's height: the covariances on the way
    // are taken, the singular one at the end is refused with a note, and the
    // last valid belief (the one just before) stays, consistent with its setting.
    let [mean, _, col2] = handles(&h);
    drag(&mut h, col2, egui::pos2(col2.x, mean.y));
    assert!(
        lesson(&h)
            .note()
            .is_some_and(|n| n.contains("not positive definite")),
        "{:?}",
        lesson(&h).note()
    );
    let kept = lesson(&h).scenario().clone();
    assert!(
        kept.std[1] > 0.0 && kept.std[1] < 0.5 && kept.rho.abs() < 1.0,
        "{kept:?}"
    );
    let r = lesson(&h).result().expect("kept");
    assert_eq!(r.prior, kept.prior());
    assert!(r.rows.iter().all(|row| row.gaussian.is_finite()));
    // The share link reopens the dragged prior (to the link's six decimals).
    let query = h.state().share_query(false);
    let reopened = harness(&query);
    let again = lesson(&reopened).scenario();
    let close = |a: f64, b: f64| (a - b).abs() < 1e-5;
    assert!(
        close(again.mean[0], moved[0]) && close(again.mean[1], moved[1]),
        "{query}"
    );
    assert!(
        close(again.std[0], kept.std[0]) && close(again.std[1], kept.std[1]),
        "{query}"
    );
    assert!(close(again.rho, kept.rho), "{query}");
    assert!(lesson(&reopened).note().is_none(), "{query}");
}

#[test]
fn the_function_menu_the_unscented_weights_and_overflow() {
    let mut h = harness("lesson=filters&samples=5000&seed=1");
    h.run();
    h.get_by_label("function").click();
    h.run();
    h.get_by_label("motion").click();
    h.run();
    assert_eq!(lesson(&h).scenario().function.name(), "motion");
    assert_eq!(lesson(&h).scenario().mean, [1.0, 0.5], "the motion prior");
    let r = lesson(&h).result().expect("valid");
    // The exact arc from the origin, heading 0, after dt = 1 s at v = 1 m/s,
    // w = 0.5 rad/s: (v/w sin(w), v/w (1 − cos w)).
    let (v, w) = (1.0_f64, 0.5_f64);
    let arc = [v / w * math::sin(w), v / w * (1.0 - math::cos(w))];
    assert!(
        (r.ekf.gaussian.mean[0] - arc[0]).abs() < 1e-12,
        "{:?}",
        r.ekf.gaussian.mean
    );
    assert!((r.ekf.gaussian.mean[1] - arc[1]).abs() < 1e-12);
    // ∂x/∂v = sin(w)/w.
    assert!((r.ekf.jacobian[(0, 0)] - math::sin(w) / w).abs() < 1e-9);
    // α = 0.5, β = 2, κ = 1, n = 2: λ = 0.25·3 − 2 = −1.25, W₀(m) = λ/(n + λ) = −5/3,
    // W₀(c) = W₀(m) + 1 − α² + β = 13/12, W_i = 1/(2(n + λ)) = 2/3.
    assert!(lesson_mut(&mut h).set_param("alpha", "0.5").is_none());
    assert!(lesson_mut(&mut h).set_param("kappa", "1").is_none());
    let wts = lesson(&h).result().expect("valid").ukf.weights;
    assert!((wts.lambda + 1.25).abs() < 1e-12, "{wts:?}");
    assert!((wts.mean0 + 5.0 / 3.0).abs() < 1e-12, "{wts:?}");
    assert!((wts.cov0 - 13.0 / 12.0).abs() < 1e-12, "{wts:?}");
    assert!((wts.other - 2.0 / 3.0).abs() < 1e-12, "{wts:?}");
    // α²(n + κ) ≤ 0: refused, the weights stay.
    lesson_mut(&mut h).set_param("kappa", "-3");
    assert!(lesson(&h).note().is_some_and(|n| n.contains("unscented")));
    assert_eq!(lesson(&h).scenario().kappa, 1.0);
    assert_eq!(lesson(&h).result().expect("kept").ukf.weights, wts);
    // Samples that overflow (e^(100 x₂) with x₂ spread over ±13): a note, the last
    // valid belief, no NaN in the state.
    lesson_mut(&mut h).set_param("function", "exp");
    lesson_mut(&mut h).set_param("coefficient", "100");
    let kept = lesson(&h).result().expect("valid").rows.clone();
    lesson_mut(&mut h).set_param("std-2", "3");
    let note = lesson(&h).note().unwrap_or_default().to_owned();
    assert!(
        note.contains("overflow") || note.contains("infinite"),
        "{note}"
    );
    assert_eq!(lesson(&h).result().expect("kept").rows, kept);
    h.run();
    let state: serde_json::Value = serde_json::from_str(&h.state().test_state_json()).unwrap();
    assert_eq!(state["lesson"], "filters");
    // serde_json writes a NaN or an infinity as null: every number is a number.
    for row in state["results"].as_array().unwrap() {
        for key in ["mean_error", "covariance_error"] {
            assert!(row[key].as_f64().is_some_and(f64::is_finite), "{row}");
        }
        assert!(
            row["mean"].as_array().unwrap().iter().all(|v| v.is_f64()),
            "{row}"
        );
    }
}

#[test]
fn corridor_buttons_step_both_filters_and_the_gain_is_the_balance() {
    let mut h = harness("lesson=filters&view=corridor&seed=1&samples=5000");
    h.run();
    for step in 0..28 {
        h.get_by_label("Step phase").click();
        h.run();
        let b = lesson(&h).corridor().histogram().belief();
        let total: f64 = b.iter().sum();
        assert!((total - 1.0).abs() < 1e-12, "step {step}: {total}");
        assert!(b.iter().all(|p| p.is_finite() && *p >= 0.0));
    }
    let sim = lesson(&h).corridor();
    assert_eq!(slamlab_sim::stepper::Simulation::tick(sim), 14);
    // Seed 1: after the doors at 3 m and 6 m the histogram has found the robot.
    let hist = sim.histogram();
    let mass = hist.mass_within(sim.truth() - 1.0, sim.truth() + 1.0);
    assert!(
        mass > 0.7 && (hist.mode() - sim.truth()).abs() < 0.25,
        "{mass}"
    );
    let state: serde_json::Value = serde_json::from_str(&h.state().test_state_json()).unwrap();
    assert_eq!(state["tick"], 14);
    assert_eq!(state["view"], "corridor");
    // K = P_p / (P_p + R) of the last door sighting, as the gain plot states.
    if let Some((u, _)) = sim.last_update() {
        let k = u.prior_variance / (u.prior_variance + u.measurement_variance);
        assert!((u.gain - k).abs() < 1e-12);
        assert!((u.posterior_variance - (1.0 - k) * u.prior_variance).abs() < 1e-12);
    }
    // A larger R lowers every gain: the corridor replays to the same step.
    let gain = state["corridor"]["gain"].as_f64();
    lesson_mut(&mut h).set_param("measurement-std", "2");
    assert_eq!(
        slamlab_sim::stepper::Simulation::tick(lesson(&h).corridor()),
        14
    );
    let after = lesson(&h).corridor().last_update().map(|(u, _)| u.gain);
    if let (Some(before), Some(after)) = (gain, after) {
        assert!(after < before, "{after} vs {before}");
    }
    h.get_by_label("Step back").click();
    h.run();
    assert_eq!(
        lesson(&h).time_info().last_phase.as_deref(),
        Some("corridor predict")
    );
}

#[test]
fn the_lesson_renders_readably_at_800_by_500_and_full_size() {
    use super::common::{harness_sized, harness_themed};
    for (size, name) in [
        (egui::vec2(800.0, 500.0), "filters_800x500"),
        (egui::vec2(1400.0, 900.0), "filters_full"),
    ] {
        let mut h = harness_sized("lesson=filters&samples=20000&seed=1", size);
        h.run();
        assert!(
            lesson(&h).handles_on_screen().is_some(),
            "{name}: no prior on screen"
        );
        let Some(image) = render_or_skip(&mut h) else {
            return;
        };
        image
            .save(shot(name))
            .unwrap_or_else(|e| eprintln!("could not save the screenshot: {e}"));
        let blue = count_pixels(image.as_raw(), [0x00, 0x72, 0xB2], 30);
        assert!(blue > 100, "{name}: EKF blue {blue} pixels");
        let mut h = harness_themed(
            "lesson=filters&view=corridor&seed=1",
            size,
            egui::Theme::Light,
        );
        for _ in 0..14 {
            lesson_mut(&mut h).apply_time_action(TimeAction::StepTick);
        }
        h.run();
        if let Some(image) = render_or_skip(&mut h) {
            image
                .save(shot(&format!("{name}_corridor")))
                .unwrap_or_else(|e| eprintln!("could not save the screenshot: {e}"));
        }
    }
}

/// The seeded table the browser test repeats in wasm (`web/tests/browser.test.mjs`,
/// `FILTERS_NATIVE`): the same bits natively and in the browser.
#[test]
fn the_seeded_table_has_these_exact_numbers() {
    let (json, state) = headless("lesson=filters&samples=20000&seed=1", 0);
    let table: Vec<String> = state["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| format!("{}={}", r["method"].as_str().unwrap(), r["mean_error"]))
        .collect();
    assert_eq!(table, FILTERS_NATIVE, "{json}");
}

const FILTERS_NATIVE: [&str; 3] = [
    "ekf=0.12957845707913004",
    "ukf=0.001541246456905519",
    "particles=0.021033324669198564",
];

/// The output canvas zooms on scroll; its *Reset view* brings back the fitted view.
#[test]
fn reset_view_undoes_a_zoom_of_the_output() {
    let mut h = super::common::harness_sized("lesson=filters", egui::vec2(1280.0, 800.0));
    h.run();
    let fitted = lesson(&h).output_scale();
    let maps: Vec<egui::Rect> = slamlab_app::widgets::plots::figure_records(&h.ctx)
        .iter()
        .filter_map(|r| r.map)
        .collect();
    let Some(output) = maps.last().copied() else {
        panic!("no canvas recorded");
    };
    h.event(egui::Event::PointerMoved(output.center()));
    for _ in 0..10 {
        h.event(egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Point,
            delta: egui::vec2(0.0, 60.0),
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Unknown,
            modifiers: egui::Modifiers::NONE,
        });
        h.step();
    }
    h.run();
    let zoomed = lesson(&h).output_scale();
    assert!(
        (zoomed / fitted - 1.0).abs() > 0.05,
        "scrolling zooms: {fitted} -> {zoomed}"
    );
    let buttons: Vec<_> = h.get_all_by_label("Reset view").collect();
    assert_eq!(buttons.len(), 2, "one per canvas");
    buttons[1].click();
    h.run();
    let back = lesson(&h).output_scale();
    assert!(
        (back / fitted - 1.0).abs() < 1e-3,
        "{fitted} -> {zoomed} -> {back}"
    );
}

/// Only the corridor has time, and the time bar acts on what is shown: a step, a
/// step key or Run pressed in the One step view opens the Corridor view and acts
/// there; leaving the Corridor view pauses it, so it never moves unseen. A link's
/// `tick=` still steps the corridor and keeps the link's view; `run=1` shows the
/// corridor it runs.
#[test]
fn run_and_the_steps_act_on_the_view_shown() {
    use super::common::harness_sized;
    let size = egui::vec2(800.0, 500.0);
    let tick = |h: &Harness<'_, SlamLabApp>| h.state().lesson().time_info().tick;
    let mut h = harness_sized("lesson=filters&seed=5&samples=5000&tick=3", size);
    h.run();
    assert_eq!(tick(&h), 3, "the link's tick= steps the corridor");
    assert_eq!(lesson(&h).tab(), Tab::OneStep, "and keeps the link's view");
    assert!(lesson(&h).handles_on_screen().is_some());
    assert!(
        lesson(&h)
            .time_info()
            .next_phase
            .contains("open the Corridor view"),
        "the bar says where the steps act: {}",
        lesson(&h).time_info().next_phase
    );
    if let Some(image) = render_or_skip(&mut h) {
        image
            .save(shot("filters_800x500_one_step_bar"))
            .unwrap_or_else(|e| eprintln!("could not save the screenshot: {e}"));
    }
    // The button: the corridor it steps is what the centre shows now.
    h.get_by_label("Step phase").click();
    h.run();
    assert_eq!(lesson(&h).tab(), Tab::Corridor);
    assert!(
        lesson(&h).handles_on_screen().is_none(),
        "the corridor drawn"
    );
    assert_eq!(
        lesson(&h).time_info().last_phase.as_deref(),
        Some("corridor predict")
    );
    if let Some(image) = render_or_skip(&mut h) {
        image
            .save(shot("filters_800x500_stepped_from_one_step"))
            .unwrap_or_else(|e| eprintln!("could not save the screenshot: {e}"));
    }
    // The key: the same (in a window wide enough for the panel's view buttons).
    let mut h = harness_sized(
        "lesson=filters&seed=5&samples=5000&tick=3",
        egui::vec2(1280.0, 800.0),
    );
    h.run();
    assert_eq!(lesson(&h).tab(), Tab::OneStep);
    h.key_press(egui::Key::Period);
    h.run();
    assert_eq!(lesson(&h).tab(), Tab::Corridor);
    assert_eq!(
        lesson(&h).time_info().last_phase.as_deref(),
        Some("corridor predict")
    );
    h.get_by_label("Step phase").click();
    h.run();
    assert_eq!(
        tick(&h),
        4,
        "the corridor's fourth tick, predict and update"
    );
    // Run from the One step view runs the corridor in sight; leaving it pauses.
    h.get_by_label("One step").click();
    h.run();
    h.get_by_label("Run").click();
    for _ in 0..3 {
        h.step();
    }
    assert_eq!(lesson(&h).tab(), Tab::Corridor);
    assert!(h.state().is_running());
    h.get_by_label("One step").click();
    h.step();
    assert!(!h.state().is_running(), "leaving the corridor pauses it");
    let held = tick(&h);
    for _ in 0..8 {
        h.step();
    }
    assert_eq!(tick(&h), held, "the hidden corridor stays where it was");
    assert_eq!(lesson(&h).tab(), Tab::OneStep);
    // A link that runs shows what it runs.
    let mut h = harness_sized("lesson=filters&seed=5&samples=5000&run=1", size);
    h.step();
    h.step();
    assert!(h.state().is_running());
    assert_eq!(lesson(&h).tab(), Tab::Corridor);
}

/// The screen rectangles of the canvases (input, output) in the last frame.
fn canvases(h: &Harness<'_, SlamLabApp>) -> [egui::Rect; 2] {
    let maps: Vec<egui::Rect> = slamlab_app::widgets::plots::figure_records(&h.ctx)
        .iter()
        .filter_map(|r| r.map)
        .collect();
    match maps[..] {
        [input, output] => [input, output],
        _ => panic!("two canvases expected: {maps:?}"),
    }
}

/// `[x_min, y_min, x_max, y_max]` of the output's four 95% ellipses.
fn ellipses_bounds(h: &Harness<'_, SlamLabApp>) -> [f64; 4] {
    let Some(r) = lesson(h).result() else {
        panic!("no valid comparison");
    };
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for g in [
        &r.truth.moments,
        &r.ekf.gaussian,
        &r.ukf.gaussian,
        &r.particles.moments,
    ] {
        for p in g.ellipse_95().boundary(72) {
            b = [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ];
        }
    }
    b
}

/// The output keeps its view while the prior is dragged (nothing jumps under
/// the hand) and fits the new ellipses when the drag ends: none is left cut at
/// the edge. Both canvases name their axes, with units, on the canvas, also in a
/// short window where the heading keeps only the title.
#[test]
fn the_output_refits_after_a_drag_and_the_canvases_name_their_axes() {
    use super::common::{drawn_texts, harness_sized};
    let size = egui::vec2(800.0, 500.0);
    let mut h = harness_sized("lesson=filters&function=linear&samples=20000&seed=2", size);
    h.run();
    let [input, output] = canvases(&h);
    assert!(lesson(&h).output_view().shows(output, ellipses_bounds(&h)));
    let before = lesson(&h).output_view().clone();
    let [mean, ..] = handles(&h);
    let to = mean + egui::vec2(0.4 * input.width(), -0.4 * input.height());
    drag(&mut h, mean, to);
    assert!(lesson(&h).note().is_none(), "{:?}", lesson(&h).note());
    let moved = ellipses_bounds(&h);
    assert!(
        !before.shows(output, moved),
        "the drag moves the ellipses out of the old view: {moved:?}"
    );
    let [_, output] = canvases(&h);
    assert!(
        lesson(&h).output_view().shows(output, moved),
        "after the drag the output shows every ellipse: {moved:?}"
    );
    // The axes, inside their canvases: linear y = A x, then the polar banana.
    let named = |h: &Harness<'_, SlamLabApp>, name: &str, canvas: egui::Rect| {
        drawn_texts(h)
            .iter()
            .any(|(text, rect, _)| text == name && canvas.contains_rect(*rect))
    };
    let [input, output] = canvases(&h);
    for (name, canvas) in [("x₁", input), ("x₂", input), ("y₁", output), ("y₂", output)] {
        assert!(named(&h, name, canvas), "{name} not on its canvas");
    }
    if let Some(image) = render_or_skip(&mut h) {
        image
            .save(shot("filters_800x500_after_drag"))
            .unwrap_or_else(|e| eprintln!("could not save the screenshot: {e}"));
    }
    let mut h = harness_sized("lesson=filters&samples=5000&seed=1", size);
    h.run();
    let [input, output] = canvases(&h);
    for (name, canvas) in [
        ("range r (m)", input),
        ("bearing b (rad)", input),
        ("x (m)", output),
        ("y (m)", output),
    ] {
        assert!(named(&h, name, canvas), "{name} not on its canvas");
    }
}
