//! Headless UI tests of FastSLAM in the landmark-SLAM lesson: the particles are
//! drawn, the wrong-association button reaches the sensor, and the new parameters
//! survive a share link.

use super::common::{count_pixels_near as count_pixels, harness, render_or_skip};
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT as _, Queryable as _};
use slamlab_app::SlamLabApp;
use slamlab_app::lesson::Lesson as _;

/// Okabe-Ito reddish purple: FastSLAM.
const PURPLE: [u8; 3] = [0xCC, 0x79, 0xA7];

fn session<'h>(h: &'h Harness<'_, SlamLabApp>) -> &'h slamlab_sim::LandmarkSession {
    match h.state().session() {
        Some(s) => s,
        None => panic!("the landmark lesson is open"),
    }
}

/// Purple pixels after 60 ticks, or `None` without a GPU adapter.
fn purple_pixels(query: &str, snapshot: Option<&str>) -> Option<usize> {
    let mut h = harness(query);
    h.run();
    if let Some(lesson) = h.state_mut().landmark_lesson_mut() {
        for _ in 0..60 {
            lesson.step_tick();
        }
    }
    h.run();
    let image = render_or_skip(&mut h)?;
    if let Some(name) = snapshot
        && let Err(err) = egui_kittest::try_image_snapshot_options(
            &image,
            name,
            &egui_kittest::SnapshotOptions::new().threshold(2.0),
        )
    {
        if std::env::var("SLAMLAB_STRICT_SNAPSHOTS").is_ok_and(|v| v == "1") {
            panic!("{name}: {err}");
        }
        eprintln!("{name}: snapshot differs (not strict): {err}");
    }
    Some(count_pixels(image.as_raw(), PURPLE, 40))
}

#[test]
fn the_particles_are_drawn_beside_the_kalman_filters() {
    let Some(with) = purple_pixels(
        "lesson=landmark-slam&seed=7&estimator=ekf,ukf,fastslam2&particles=100",
        Some("landmark_fastslam"),
    ) else {
        return;
    };
    let Some(without) = purple_pixels("lesson=landmark-slam&seed=7&estimator=ekf,ukf", None) else {
        return;
    };
    eprintln!("purple pixels: {with} with FastSLAM, {without} without");
    assert!(
        with > without + 500,
        "FastSLAM-purple pixels {with} (without FastSLAM {without})"
    );
}

#[test]
fn the_wrong_association_button_mislabels_the_next_observation() {
    let mut h = harness("lesson=landmark-slam&seed=1&estimator=ekf,fastslam2");
    h.run();
    if let Some(lesson) = h.state_mut().landmark_lesson_mut() {
        for _ in 0..60 {
            lesson.step_tick();
        }
    }
    h.run();
    // The button sits low in the parameter panel: scroll it into view first.
    h.get_by_label("Wrong association").scroll_to_me();
    h.run();
    h.get_by_label("Wrong association").click();
    h.run();
    assert_eq!(session(&h).mislabel_ticks(), &[61]);
    if let Some(lesson) = h.state_mut().landmark_lesson_mut() {
        lesson.step_tick();
    }
    h.run();
    let m = session(&h).mislabel().map(|m| (m.true_id, m.reported_id));
    assert_eq!(m, Some((1, 19)));
    assert!(
        h.query_all_by_label_contains("landmark 1 reported as 19")
            .next()
            .is_some()
    );

    // With unknown association the sensor gives no ids: the button is greyed out and
    // a click schedules nothing.
    let mut h = harness("lesson=landmark-slam&seed=1&estimator=ekf,fastslam2&association=unknown");
    h.run();
    h.get_by_label("Wrong association").scroll_to_me();
    h.run();
    assert!(
        h.get_by_label("Wrong association")
            .accesskit_node()
            .is_disabled()
    );
    h.get_by_label("Wrong association").click();
    h.run();
    assert!(session(&h).mislabel_ticks().is_empty());
}

#[test]
fn the_fastslam_parameters_survive_a_share_link() {
    let query = "lesson=landmark-slam&seed=3&estimator=ekf,fastslam1&particles=40\
                 &fastslam-resampler=stratified&resample-threshold=0.3&association=unknown\
                 &gate=9&new-landmark-threshold=20";
    let h = harness(query);
    let Some(lesson) = h.state().landmark_lesson() else {
        panic!("landmark lesson");
    };
    let pairs = lesson.share_pairs();
    for (k, v) in [
        ("estimator", "ekf,fastslam1"),
        ("particles", "40"),
        ("fastslam-resampler", "stratified"),
        ("resample-threshold", "0.3"),
        ("association", "unknown"),
        ("gate", "9"),
        ("new-landmark-threshold", "20"),
    ] {
        assert!(
            pairs.iter().any(|(a, b)| a == k && b == v),
            "{k}={v} in {pairs:?}"
        );
    }
    let again = harness(&lesson.share_query(false));
    let Some(reopened) = again.state().landmark_lesson() else {
        panic!("landmark lesson");
    };
    assert_eq!(reopened.session().scenario(), lesson.session().scenario());
    assert_eq!(reopened.session().filters()[1].kind.name(), "fastslam1");
    // Zero particles in a link: a clear message, one particle, no panic.
    let h = harness("lesson=landmark-slam&estimator=fastslam2&particles=0&resample-threshold=7");
    let notices = h
        .state()
        .landmark_lesson()
        .map(|l| l.notices())
        .unwrap_or_default();
    let text = notices.join(" | ");
    assert!(
        text.contains("particles = 0 is out of range; using 1"),
        "{text}"
    );
    assert!(
        text.contains("resample-threshold = 7 is out of range; using 1"),
        "{text}"
    );
}
