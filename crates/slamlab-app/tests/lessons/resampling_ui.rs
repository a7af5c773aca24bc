//! Headless UI tests of the resampling lab through egui_kittest: it opens by URL,
//! its buttons resample, stepping back takes a press back exactly, bad weights
//! get a note and a safe value, and the rendered row shows every method's copies.

use super::common::{
    SIZE, assert_notices, count_pixels, harness, harness_themed, headless, lesson_accessors,
    render_or_skip, snapshot,
};
use egui_kittest::kittest::Queryable as _;
use slamlab_app::lesson::Lesson as _;
use slamlab_app::resampling::ResamplingLesson;
use slamlab_core::particle::Resampler;

lesson_accessors!(ResamplingLesson);

#[test]
fn the_lab_opens_by_url_and_bad_values_get_a_message_and_a_safe_value() {
    let h = harness("lesson=resampling&weights=5,1,1,3&seed=4&methods=multinomial,residual");
    assert_eq!(h.state().lesson_id(), "resampling");
    let run = lesson(&h).run();
    assert_eq!(run.lab().weights(), &[0.5, 0.1, 0.1, 0.3]);
    assert_eq!(
        run.scenario().methods,
        vec![Resampler::Multinomial, Resampler::Residual]
    );
    assert!(h.state().notices().is_empty(), "{:?}", h.state().notices());

    let h = harness("lesson=resampling&weights=heavy&particles=0");
    assert_notices(
        &h,
        2,
        &[&["weights", "two-modes"], &["particles", "out of range"]],
    );
    assert_eq!(lesson(&h).run().particles(), 1);

    // Weights that are all zero, negative or NaN: uniform or repaired, with a note.
    let mut h = harness("lesson=resampling&weights=0,0,0,0");
    assert_eq!(lesson(&h).run().lab().weights(), &[0.25; 4]);
    assert!(lesson(&h).run().note().is_some());
    let issue = lesson_mut(&mut h).set_param("weights", "1,x,2");
    assert!(issue.is_some(), "an unreadable list is refused");
    assert_eq!(
        lesson(&h).run().lab().weights(),
        &[0.25; 4],
        "and the weights stay"
    );
}

#[test]
fn the_buttons_resample_and_step_back_takes_a_press_back() {
    let mut h = harness("lesson=resampling&weights=two-modes&particles=20&seed=2");
    h.run();
    h.get_by_label("Resample once").click();
    h.run();
    let run = lesson(&h).run();
    assert_eq!(run.resamplings(), 1);
    let expected = run.lab().expected_copies();
    for method in Resampler::ALL {
        let copies = run.lab().last_copies(method);
        assert_eq!(copies.iter().sum::<usize>(), 20, "{}", method.name());
        for (i, (&c, &e)) in copies.iter().zip(&expected).enumerate() {
            match method {
                Resampler::LowVariance => assert!(
                    c == e.floor() as usize || c == e.ceil() as usize,
                    "low-variance gave particle {i} {c} copies for M·w = {e}"
                ),
                Resampler::Residual => assert!(c >= e.floor() as usize, "residual: {c} < ⌊{e}⌋"),
                _ => {}
            }
        }
    }
    let after_one: Vec<Vec<usize>> = Resampler::ALL
        .iter()
        .map(|&m| lesson(&h).run().lab().last_copies(m).to_vec())
        .collect();
    h.get_by_label("Resample ×1000").click();
    h.run();
    assert_eq!(lesson(&h).run().resamplings(), 1001);
    assert_eq!(
        lesson(&h).time_info().last_phase.as_deref(),
        Some("resample ×1000")
    );
    h.get_by_label("Step back").click();
    h.run();
    let back: Vec<Vec<usize>> = Resampler::ALL
        .iter()
        .map(|&m| lesson(&h).run().lab().last_copies(m).to_vec())
        .collect();
    assert_eq!(lesson(&h).run().resamplings(), 1);
    assert_eq!(back, after_one);
}

#[test]
fn dragging_a_bar_sets_that_weight_and_keeps_the_others_proportions() {
    let mut h = harness("lesson=resampling&weights=1,1,2&seed=1");
    lesson_mut(&mut h).set_weight(0, 0.5);
    let w = lesson(&h).run().lab().weights().to_vec();
    assert!((w[0] - 0.5).abs() < 1e-12, "{w:?}");
    assert!((w[2] - 2.0 * w[1]).abs() < 1e-12, "{w:?}");
    assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    // A NaN from a drag keeps the weight.
    lesson_mut(&mut h).set_weight(1, f64::NAN);
    assert_eq!(lesson(&h).run().lab().weights(), w.as_slice());
}

#[test]
fn the_rendered_lab_shows_every_methods_copies() {
    let mut h = harness_themed("lesson=resampling&seed=3", SIZE, egui::Theme::Light);
    h.run();
    lesson_mut(&mut h).press(1);
    lesson_mut(&mut h).press(500);
    h.run();
    let Some(image) = render_or_skip(&mut h) else {
        return;
    };
    for (name, rgb) in [
        ("multinomial purple", [0xCC, 0x79, 0xA7]),
        ("low-variance blue", [0x00, 0x72, 0xB2]),
        ("stratified green", [0x00, 0x9E, 0x73]),
        ("residual orange", [0xE6, 0x9F, 0x00]),
    ] {
        let n = count_pixels(image.as_raw(), rgb, 30);
        assert!(n > 1500, "{name} pixels {n}");
    }
    let weights_grey = count_pixels(image.as_raw(), [0x8C, 0x8C, 0x8C], 6);
    assert!(weights_grey > 1500, "weight-bar pixels {weights_grey}");
    snapshot(&image, "resampling_lab");
}

/// The seeded presses the browser test repeats in wasm (`web/tests/browser.test.mjs`).
#[test]
fn seeded_presses_give_these_exact_copies() {
    let (json, state) = headless("lesson=resampling&weights=5,1,1,3&seed=3", 5);
    assert_eq!(state["resamplings"], 5, "{json}");
    let copies: Vec<String> = state["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| format!("{}={}", m["name"].as_str().unwrap(), m["last_copies"]))
        .collect();
    assert_eq!(copies, GOLDEN, "{json}");
}

const GOLDEN: [&str; 4] = [
    "multinomial=[3,0,1,0]",
    "low-variance=[2,1,0,1]",
    "stratified=[2,0,1,1]",
    "residual=[2,1,0,1]",
];
