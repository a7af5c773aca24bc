//! Headless UI tests of the pose-graph lesson through egui_kittest: it opens by
//! URL, "Step iteration" runs one solver iteration and the cost falls, a wrong
//! loop closure and the kernel comparison work from their buttons, a bad file
//! leaves the graph on screen, and the rendered map shows the blue poses and
//! odometry, the vermillion loop closures and the sparsity images.

use super::common::{
    SIZE, count_pixels, harness, harness_themed, lesson_of, lesson_of_mut, render_or_skip,
};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use slamlab_app::SlamLabApp;
use slamlab_app::pose_graph::PoseGraphLesson;

fn lesson<'h>(h: &'h Harness<'_, SlamLabApp>) -> &'h PoseGraphLesson {
    lesson_of(h)
}

fn lesson_mut<'h>(h: &'h mut Harness<'_, SlamLabApp>) -> &'h mut PoseGraphLesson {
    lesson_of_mut(h)
}

#[test]
fn the_lesson_opens_by_url_and_one_iteration_lowers_the_cost() {
    let mut h = harness("lesson=pose-graph&example=thesis&solver=gn&seed=1");
    h.run();
    assert_eq!(h.state().lesson_id(), "pose-graph");
    assert!(h.state().notices().is_empty(), "{:?}", h.state().notices());
    let session = lesson(&h).session();
    assert_eq!(session.graph().vertices().len(), 201);
    assert_eq!(session.graph().edges().len(), 210);
    let before = session.cost();
    h.get_by_label("Step iteration").click();
    h.run();
    let session = lesson(&h).session();
    assert_eq!(session.iterations(), 1);
    let after = session.cost();
    assert!(
        (before - 999.610_655_587).abs() < 1e-6,
        "start cost {before}"
    );
    assert!(
        (after - 45.554_529_007).abs() < 1e-6,
        "cost {before} -> {after}"
    );
    // The test hook reports the same numbers.
    let state: serde_json::Value = serde_json::from_str(&h.state().test_state_json()).unwrap();
    assert_eq!(state["iterations"], 1);
    assert_eq!(state["cost"].as_f64(), Some(after));
    // Bad link values: a message and a safe value.
    let h = harness("lesson=pose-graph&solver=newton&kernel-width=-3");
    let notices = h.state().notices();
    assert_eq!(notices.len(), 2, "{notices:?}");
    assert!(
        notices
            .iter()
            .any(|n| n.contains("solver") && n.contains("gn, lm, gd"))
    );
    assert_eq!(lesson(&h).session().scenario().kernel_width, 0.01);
}

#[test]
fn a_wrong_loop_closure_and_the_kernel_comparison_from_their_buttons() {
    let mut h = harness("lesson=pose-graph&example=manhattan&manhattan-poses=300&seed=1");
    h.run();
    h.get_by_label("Add wrong loop closure").click();
    h.run();
    assert_eq!(lesson(&h).session().wrong_closures(), 1);
    h.get_by_label("Compare kernels").click();
    h.run();
    let Some([plain, robust]) = lesson(&h).comparison() else {
        panic!("no comparison")
    };
    let (p, r) = (plain.rmse.unwrap(), robust.rmse.unwrap());
    assert!(r < 0.6 * p, "without kernel {p} m, with Huber {r} m");
    // The solver switches live: LM keeps the estimate and iterates on.
    lesson_mut(&mut h).set_param("solver", "lm");
    h.run();
    assert_eq!(lesson(&h).session().scenario().solver.short_name(), "lm");
    let cost = lesson(&h).session().cost();
    h.get_by_label("Optimize").click();
    for _ in 0..200 {
        h.step();
        if !lesson(&h).is_optimizing() {
            break;
        }
    }
    let timing = lesson(&h).last_optimize().unwrap();
    assert!(timing.converged && timing.iterations >= 2, "{timing:?}");
    assert!(lesson(&h).session().cost() < cost);
}

#[test]
fn a_bad_file_leaves_the_graph_on_screen_with_a_message() {
    let mut h = harness("lesson=pose-graph&example=thesis");
    h.run();
    let cost = lesson(&h).session().cost();
    lesson_mut(&mut h).load_file(
        "broken.g2o",
        b"VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 9 1 0 0 1 0 0 1 0 1\n".to_vec(),
    );
    h.run();
    let note = lesson(&h).note().unwrap_or_default().to_owned();
    assert!(
        note.contains("broken.g2o") && note.contains("line 3") && note.contains("vertex 9"),
        "{note}"
    );
    assert_eq!(lesson(&h).session().source(), "thesis");
    assert_eq!(lesson(&h).session().cost(), cost);
    // A good file opens and optimizes to convergence.
    let mut text = String::new();
    for k in 0..6 {
        text.push_str(&format!("VERTEX_SE2 {k} {} 0.3 0\n", k as f64 * 1.1));
    }
    for k in 0..5 {
        text.push_str(&format!("EDGE_SE2 {k} {} 1 0 0 10 0 0 10 0 10\n", k + 1));
    }
    text.push_str("EDGE_SE2 0 5 5 0 0 10 0 0 10 0 10\n");
    lesson_mut(&mut h).load_file("small.g2o", text.into_bytes());
    for _ in 0..100 {
        h.step();
        if !lesson(&h).is_optimizing() {
            break;
        }
    }
    let session = lesson(&h).session();
    assert_eq!(session.source(), "small.g2o");
    assert!(session.is_converged());
    assert!(session.cost() < 1e-12, "{}", session.cost());
}

#[test]
fn rendered_lesson_shows_poses_odometry_loop_closures_and_the_sparsity_images() {
    let mut h = harness_themed(
        "lesson=pose-graph&example=manhattan&seed=2",
        SIZE,
        egui::Theme::Light,
    );
    h.run();
    lesson_mut(&mut h).add_wrong_loop_closure();
    lesson_mut(&mut h).step_iteration();
    h.run();
    let Some(image) = render_or_skip(&mut h) else {
        return;
    };
    let blue = count_pixels(image.as_raw(), [0x00, 0x72, 0xB2], 30);
    let vermillion = count_pixels(image.as_raw(), [0xD5, 0x5E, 0x00], 30);
    assert!(blue > 4000, "blue (poses, odometry, H and L) pixels {blue}");
    assert!(
        vermillion > 800,
        "vermillion (loop closures, fill-in) pixels {vermillion}"
    );
    let _ = egui_kittest::try_image_snapshot_options(
        &image,
        "pose_graph_lesson",
        &egui_kittest::SnapshotOptions::new().threshold(2.0),
    );
}
