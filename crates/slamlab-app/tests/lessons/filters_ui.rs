//! Headless UI tests of the filters lesson: it opens by URL with the polar
//! banana, a singular prior gets a note and keeps the last valid belief, the
//! time bar steps the corridor and steps back exactly, and the rendered views
//! show the samples, the EKF's blue, the UKF's orange and the particles' purple.

use super::common::{count_pixels, harness, lesson_of, lesson_of_mut, render_or_skip};
use egui_kittest::Harness;
use slamlab_app::SlamLabApp;
use slamlab_app::filters::{FiltersLesson, Tab};
use slamlab_app::lesson::Lesson as _;
use slamlab_app::time_control::TimeAction;

fn lesson<'h>(h: &'h Harness<'_, SlamLabApp>) -> &'h FiltersLesson {
    lesson_of(h)
}

fn lesson_mut<'h>(h: &'h mut Harness<'_, SlamLabApp>) -> &'h mut FiltersLesson {
    lesson_of_mut(h)
}

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
        .save("target/filters_one_step.png")
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
        .save("target/filters_corridor.png")
        .unwrap_or_else(|e| eprintln!("could not save the screenshot: {e}"));
    let green = count_pixels(image.as_raw(), [0x00, 0x9E, 0x73], 30);
    assert!(green > 200, "histogram bars: {green} pixels");
    let blue = count_pixels(image.as_raw(), [0x00, 0x72, 0xB2], 30);
    assert!(blue > 50, "Kalman curve: {blue} pixels");
    lesson_mut(&mut h).set_tab(Tab::OneStep);
}
