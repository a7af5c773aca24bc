//! Headless UI tests of the pose-graph lesson through egui_kittest: it opens by
//! URL, "Step iteration" runs one solver iteration and the cost falls, a wrong
//! loop closure and the kernel comparison work from their buttons, a bad file
//! leaves the graph on screen, and the rendered map shows the blue poses and
//! odometry, the vermillion loop closures and the sparsity images.

use super::common::{
    SIZE, assert_notices, count_pixels, harness, harness_themed, lesson_accessors, render_or_skip,
    snapshot,
};
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT as _, Queryable as _};
use slamlab_app::SlamLabApp;
use slamlab_app::pose_graph::PoseGraphLesson;
use slamlab_sim::pose_graph::session::KernelChoice;

lesson_accessors!(PoseGraphLesson);

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
    let state: serde_json::Value = match serde_json::from_str(&h.state().test_state_json()) {
        Ok(state) => state,
        Err(e) => panic!("the test hook's JSON does not parse: {e}"),
    };
    let Some(h_blocks) = state["h_blocks"].as_u64() else {
        panic!("no h_blocks in {state}")
    };
    assert_eq!(state["iterations"], 1);
    assert_eq!(state["cost"].as_f64(), Some(after));
    // H over all 201 vertices: the diagonal, 200 odometry and 10 loop-closure pairs
    // (all ten close at pose 0, the fixed one, so they are drawn in its row and column).
    assert_eq!(h_blocks, 201 + 2 * 200 + 2 * 10);
    // Bad link values: a message and a safe value.
    let h = harness("lesson=pose-graph&solver=newton&kernel-width=-3");
    assert_notices(&h, 2, &[&["solver", "gn, lm, gd"]]);
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
    snapshot(&image, "pose_graph_lesson");
}

/// What the lesson draws, as bits: every vertex state, the cost history (the cost
/// plot), the cost, the edge count and the non-zero blocks of H (the sparsity image).
fn drawn(h: &Harness<'_, SlamLabApp>) -> (Vec<u64>, Vec<[u64; 2]>, u64, usize, u64) {
    use slamlab_core::graph::VertexState;
    let session = lesson(h).session();
    let states = session
        .graph()
        .vertices()
        .iter()
        .flat_map(|v| match v.state {
            VertexState::Pose(p) => vec![p.x.to_bits(), p.y.to_bits(), p.theta.to_bits()],
            VertexState::Point(q) => vec![q[0].to_bits(), q[1].to_bits()],
        })
        .collect();
    let history = session
        .history()
        .iter()
        .map(|c| [c[0].to_bits(), c[1].to_bits()])
        .collect();
    let state: serde_json::Value = match serde_json::from_str(&h.state().test_state_json()) {
        Ok(state) => state,
        Err(e) => panic!("the test hook's JSON does not parse: {e}"),
    };
    let Some(h_blocks) = state["h_blocks"].as_u64() else {
        panic!("no h_blocks in {state}")
    };
    (
        states,
        history,
        session.cost().to_bits(),
        session.graph().edges().len(),
        h_blocks,
    )
}

fn disabled(h: &Harness<'_, SlamLabApp>, label: &str) -> bool {
    h.get_by_label(label).accesskit_node().is_disabled()
}

#[test]
fn the_time_bar_steps_iterations_and_steps_back_through_them_bit_for_bit() {
    let mut h = harness("lesson=pose-graph&example=thesis&seed=1");
    h.run();
    // One kind of step: "Step iteration"; no phases or ticks to step.
    assert!(h.query_by_label("Step phase").is_none());
    assert!(h.query_by_label("Step tick").is_none());
    assert_eq!(h.query_all_by_label("Step iteration").count(), 1);
    assert!(disabled(&h, "Step back"), "nothing to go back to yet");
    let mut moments = vec![drawn(&h)];
    h.get_by_label("Step iteration").click();
    h.run();
    moments.push(drawn(&h));
    h.key_press(egui::Key::Period);
    h.run();
    moments.push(drawn(&h));
    h.get_by_label("Add wrong loop closure").click();
    h.run();
    moments.push(drawn(&h));
    h.key_press(egui::Key::N);
    h.run();
    moments.push(drawn(&h));
    assert_eq!(
        lesson(&h).session().iterations(),
        3,
        "'.' and 'n' step one iteration each"
    );
    assert_eq!(
        moments[3].3,
        moments[2].3 + 1,
        "the wrong loop closure is an edge"
    );
    assert_eq!(
        moments[3].4,
        moments[2].4 + 2,
        "and a pair of blocks in H: {} -> {}",
        moments[2].4,
        moments[3].4
    );
    assert!(!disabled(&h, "Step back"));
    // Back through every iteration and the edit, by the button and by ','.
    for (k, expected) in moments.iter().enumerate().rev().skip(1) {
        if k % 2 == 0 {
            h.get_by_label("Step back").click();
        } else {
            h.key_press(egui::Key::Comma);
        }
        h.run();
        let now = drawn(&h);
        assert!(now.0 == expected.0, "moment {k}: the vertices differ");
        assert_eq!(now.1, expected.1, "moment {k}: the cost plot differs");
        assert_eq!(
            (now.2, now.3, now.4),
            (expected.2, expected.3, expected.4),
            "moment {k}"
        );
    }
    assert_eq!(lesson(&h).session().iterations(), 0);
    assert_eq!(lesson(&h).session().wrong_closures(), 0);
    assert!(disabled(&h, "Step back"), "back at the start");
    // Forward again: the first iteration is the same iteration.
    h.get_by_label("Step iteration").click();
    h.run();
    assert!(drawn(&h) == moments[1]);
}

#[test]
fn stepping_back_over_a_kernel_switch_restores_the_panels_kernel() {
    let mut h = harness("lesson=pose-graph&example=manhattan&manhattan-poses=150&seed=3");
    h.run();
    h.get_by_label("Step iteration").click();
    h.run();
    lesson_mut(&mut h).set_param("kernel", "cauchy");
    h.run();
    assert_eq!(lesson(&h).session().scenario().kernel, KernelChoice::Cauchy);
    h.get_by_label("Step back").click();
    h.run();
    assert_eq!(lesson(&h).session().scenario().kernel, KernelChoice::None);
    assert_eq!(
        lesson(&h).pending().kernel,
        KernelChoice::None,
        "the panel follows"
    );
    // The panel applying its (now equal) values does not switch again.
    h.run();
    assert_eq!(lesson(&h).session().history().len(), 2);
    assert_eq!(lesson(&h).session().iterations(), 1);
}

/// Pixels of the faded orange band over the light map background.
const BAND: [u8; 3] = [0xF1, 0xCA, 0x73];

#[test]
fn compare_kernels_draws_both_results_and_the_time_bar_fits_a_small_window() {
    for (size, name) in [
        (SIZE, "pose_graph_compare_1400x900.png"),
        (egui::vec2(800.0, 500.0), "pose_graph_compare_800x500.png"),
    ] {
        let mut h = harness_themed(
            "lesson=pose-graph&example=manhattan&manhattan-poses=300&seed=1",
            size,
            egui::Theme::Light,
        );
        h.run();
        lesson_mut(&mut h).add_wrong_loop_closure();
        h.run();
        let before = render_or_skip(&mut h);
        lesson_mut(&mut h).compare_kernels();
        // The current graph optimized without a kernel: the plain result under it.
        lesson_mut(&mut h).start_optimize();
        lesson_mut(&mut h).advance_optimize(None);
        h.run();
        let Some([plain, robust]) = lesson(&h).comparison().cloned() else {
            panic!("no comparison")
        };
        assert!(robust.rmse.unwrap() < 0.6 * plain.rmse.unwrap());
        let Some(image) = render_or_skip(&mut h) else {
            return;
        };
        let path = std::env::temp_dir().join(name);
        let _ = image.save(&path);
        eprintln!("saved {}", path.display());
        let Some(before) = before else { return };
        let purple = |img: &image::RgbaImage| count_pixels(img.as_raw(), [0xCC, 0x79, 0xA7], 24);
        let band = |img: &image::RgbaImage| count_pixels(img.as_raw(), BAND, 20);
        let (p0, p1) = (purple(&before), purple(&image));
        let (b0, b1) = (band(&before), band(&image));
        // Both results are visible: the kernel's line and the plain result's band
        // (which the current graph, optimized the same way, runs along).
        assert!(p1 > p0 + 400, "{name}: purple pixels {p0} -> {p1}");
        assert!(b1 > b0 + 800, "{name}: band pixels {b0} -> {b1}");
    }
}

#[test]
fn the_thesis_graph_after_an_edit_renders_its_cost_line_and_block_image() {
    for (size, name) in [
        (SIZE, "pose_graph_thesis_1400x900.png"),
        (egui::vec2(800.0, 500.0), "pose_graph_thesis_800x500.png"),
    ] {
        let mut h = harness_themed(
            "lesson=pose-graph&example=thesis&seed=1",
            size,
            egui::Theme::Light,
        );
        h.run();
        for _ in 0..3 {
            lesson_mut(&mut h).step_iteration();
        }
        lesson_mut(&mut h).add_wrong_loop_closure();
        for _ in 0..3 {
            lesson_mut(&mut h).step_iteration();
        }
        h.run();
        let history = lesson(&h).session().history().to_vec();
        assert_eq!(
            history.len(),
            8,
            "start, 3 iterations, the edit, 3 iterations"
        );
        assert_eq!(
            history[3][0], history[4][0],
            "the edit adds a point at the same iteration"
        );
        let Some(image) = render_or_skip(&mut h) else {
            return;
        };
        let path = std::env::temp_dir().join(name);
        let _ = image.save(&path);
        eprintln!("saved {}", path.display());
        let blue = count_pixels(image.as_raw(), [0x00, 0x72, 0xB2], 30);
        assert!(blue > 1500, "{name}: blue pixels {blue}");
    }
}

/// With a kernel comparison (the longest key) at 800 x 500, the key is a line above
/// the map: no key rectangle overlaps the map canvas.
#[test]
fn the_comparison_key_stays_off_the_graph_at_800_by_500() {
    let mut h = super::common::harness_sized("lesson=pose-graph", egui::vec2(800.0, 500.0));
    h.run();
    lesson_mut(&mut h).compare_kernels();
    h.run();
    let records = slamlab_app::widgets::plots::figure_records(&h.ctx);
    let Some(map) = records.iter().find_map(|r| r.map) else {
        panic!("no map canvas recorded");
    };
    let keys: Vec<egui::Rect> = records.iter().filter_map(|r| r.key).collect();
    assert!(
        keys.iter().any(|k| k.bottom() <= map.top() + 0.5),
        "a key above the map: {keys:?}, map {map:?}"
    );
    super::common::assert_keys_off(&keys, map, "the map");
    assert!(super::common::label_visible(&h, "optimized with no kernel"));
}

/// The cost plot's log axis shows two values or more at iteration 0 (one cost, a
/// range under a decade), after a few iterations and after the solver converged,
/// in the app at 800 x 500 and 1280 x 800 and embedded at 900 x 600; and both
/// sparsity images are on screen whole.
#[test]
fn the_cost_plot_reads_at_every_iteration_and_size() {
    for (query, size) in [
        ("lesson=pose-graph&tick=0", egui::vec2(800.0, 500.0)),
        ("lesson=pose-graph&tick=1", egui::vec2(800.0, 500.0)),
        ("lesson=pose-graph&tick=3", egui::vec2(800.0, 500.0)),
        ("lesson=pose-graph&tick=0", egui::vec2(1280.0, 800.0)),
        ("lesson=pose-graph&tick=40", egui::vec2(1280.0, 800.0)),
        ("lesson=pose-graph&tick=0&embed=1", egui::vec2(900.0, 600.0)),
    ] {
        let mut h = super::common::harness_sized(query, size);
        h.run();
        if let Some(dir) = std::env::var_os("SLAMLAB_SCREENSHOTS")
            && let Some(image) = render_or_skip(&mut h)
        {
            let name = format!(
                "{}_{}x{}.png",
                query.replace(['=', '&'], "_"),
                size.x as u32,
                size.y as u32
            );
            let _ = image.save(std::path::Path::new(&dir).join(name));
        }
        let records = slamlab_app::widgets::plots::figure_records(&h.ctx);
        let Some(data) = records
            .iter()
            .find(|r| r.title.starts_with("Cost per iteration"))
            .and_then(|r| r.data)
        else {
            panic!("{query}: no cost plot");
        };
        let mut texts: Vec<(String, egui::Rect)> = Vec::new();
        fn walk(shape: &egui::Shape, out: &mut Vec<(String, egui::Rect)>) {
            match shape {
                egui::Shape::Text(t) => {
                    out.push((t.galley.text().to_owned(), t.visual_bounding_rect()))
                }
                egui::Shape::Vec(shapes) => shapes.iter().for_each(|s| walk(s, out)),
                _ => {}
            }
        }
        for clipped in &h.output().shapes {
            walk(&clipped.shape, &mut texts);
        }
        let values: Vec<&String> = texts
            .iter()
            .filter(|(text, rect)| {
                text.contains('e')
                    && text.chars().any(|c| c.is_ascii_digit())
                    && rect.right() <= data.left() + 1.0
                    && rect.left() >= data.left() - 80.0
                    && rect.center().y >= data.top() - 2.0
                    && rect.center().y <= data.bottom() + 2.0
            })
            .map(|(text, _)| text)
            .collect();
        let near: Vec<&(String, egui::Rect)> = texts
            .iter()
            .filter(|(_, rect)| rect.intersects(data.expand(60.0)))
            .collect();
        assert!(
            values.len() >= 2,
            "{query} at {size:?}: the cost axis {data:?} shows {values:?}; texts near: {near:?}"
        );
        let images: Vec<egui::Rect> = records.iter().filter_map(|r| r.image).collect();
        let expected = if query.contains("embed") { 1 } else { 2 };
        assert_eq!(images.len(), expected, "{query}: {images:?}");
        for image in images {
            assert!(
                image.max.y <= size.y + 0.5 && image.height() >= 40.0,
                "{query} at {size:?}: image {image:?}"
            );
        }
    }
}

/// The lesson's own optimized graph written as g2o and dropped back is a
/// solution of the problem on screen: scored with the same cost as the lesson's
/// graph (a ratio of 1 to 1e-9) and the same RMSE against the truth; a graph
/// of another problem (another seed) opens as a new problem with a note saying
/// why; a solution is drawn in its colour and removed again.
#[test]
fn a_dropped_optimized_graph_is_scored_as_a_solution_or_opens_as_a_problem() {
    use slamlab_app::widgets::estimates::COLORS;
    use slamlab_sim::io::graph::write_g2o;
    let mut h = super::common::harness_sized(
        "lesson=pose-graph&example=thesis&solver=gn&seed=1",
        egui::vec2(800.0, 500.0),
    );
    h.run();
    let start = write_g2o(lesson(&h).session().start_graph()).unwrap();
    lesson_mut(&mut h).start_optimize();
    lesson_mut(&mut h).advance_optimize(None);
    assert!(lesson(&h).session().is_converged());
    let optimized = write_g2o(lesson(&h).session().graph()).unwrap();
    lesson_mut(&mut h).open_graph_file("mine.g2o", optimized.into_bytes());
    // The problem itself, unoptimized: a solution too, far worse.
    lesson_mut(&mut h).open_graph_file("start.g2o", start.into_bytes());
    h.run();
    let state: serde_json::Value = serde_json::from_str(&h.state().test_state_json()).unwrap();
    let solutions = state["solutions"].as_array().unwrap().clone();
    assert_eq!(solutions.len(), 2, "{state}");
    let mine = &solutions[0];
    assert_eq!(mine["name"], "mine.g2o");
    let ratio = mine["cost_ratio"].as_f64().unwrap();
    assert!((ratio - 1.0).abs() <= 1e-9, "cost ratio {ratio}");
    assert_eq!(mine["ate"].as_f64(), lesson(&h).session().rmse());
    let worse = solutions[1]["cost_ratio"].as_f64().unwrap();
    assert!(worse > 10.0, "the unoptimized graph's ratio {worse}");
    assert!(
        lesson(&h)
            .note()
            .unwrap()
            .contains("start.g2o has the vertices and edges of the graph on screen"),
        "{:?}",
        lesson(&h).note()
    );
    // Drawn over the lesson's graph in its colour.
    if let Some(image) = super::common::shot(&mut h, "graph-solution-800x500.png") {
        let [r, g, b, _] = COLORS[1].to_array();
        let drawn = count_pixels(image.as_raw(), [r, g, b], 24);
        assert!(drawn > 100, "the solution's colour covers {drawn} pixels");
    }
    lesson_mut(&mut h).solutions_mut().remove(1);
    assert_eq!(lesson(&h).solutions().items().len(), 1);
    // Another seed: another problem, opened as one; its solutions set aside.
    let other = slamlab_sim::pose_graph::session::PoseGraphSession::from_scenario(
        slamlab_sim::pose_graph::session::PoseGraphScenario {
            seed: 2,
            ..lesson(&h).session().scenario().clone()
        },
    )
    .unwrap();
    let other = write_g2o(other.start_graph()).unwrap();
    lesson_mut(&mut h).open_graph_file("other.g2o", other.into_bytes());
    let note = lesson(&h).note().unwrap().to_owned();
    assert_eq!(lesson(&h).session().source(), "other.g2o");
    assert!(
        note.contains("Opened as a new problem, not scored as a solution of thesis")
            && note.contains("this is another graph"),
        "{note}"
    );
    assert!(lesson(&h).solutions().items().is_empty());
}

/// A graph named by `estimate=` is taken as a dropped one is: the lesson's own
/// optimized graph, written to a file and named in the link, is scored as a
/// solution of the problem the link opens (a ratio of 1 to 1e-9).
#[test]
fn an_optimized_graph_named_by_estimate_is_scored_as_a_solution() {
    use slamlab_sim::io::graph::write_g2o;
    let query = "lesson=pose-graph&example=thesis&solver=gn&seed=1";
    let mut h = super::common::harness_sized(query, egui::vec2(800.0, 500.0));
    h.run();
    lesson_mut(&mut h).start_optimize();
    lesson_mut(&mut h).advance_optimize(None);
    let optimized = write_g2o(lesson(&h).session().graph()).unwrap();
    let dir = std::env::temp_dir().join(format!("slamlab-estimate-g2o-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("mine.g2o");
    std::fs::write(&file, optimized).unwrap();
    let mut h = super::common::harness_sized(
        &format!("{query}&estimate={}", file.display()),
        egui::vec2(800.0, 500.0),
    );
    for _ in 0..4 {
        h.run();
    }
    let state: serde_json::Value = serde_json::from_str(&h.state().test_state_json()).unwrap();
    let solutions = state["solutions"].as_array().cloned().unwrap_or_default();
    assert_eq!(solutions.len(), 1, "{state}");
    assert_eq!(solutions[0]["name"], "mine.g2o");
    let ratio = solutions[0]["cost_ratio"].as_f64().unwrap();
    // Against the lesson's graph as it is now (unoptimized): far below 1.
    assert!(ratio < 0.1, "cost ratio {ratio}");
    assert_eq!(lesson(&h).session().source(), "thesis");
    let _ = std::fs::remove_dir_all(&dir);
}

/// At 800 x 500 and full size "Your solutions" stays in its corner, no wider
/// than it, and the notices box (here the note that the file is a solution)
/// lies beside it, not under it.
#[test]
fn your_solutions_and_the_notices_lie_apart() {
    use slamlab_sim::io::graph::write_g2o;
    for (size, shot) in [
        (
            egui::vec2(800.0, 500.0),
            "graph-solutions-notices-800x500.png",
        ),
        (SIZE, "graph-solutions-notices-full.png"),
    ] {
        let mut h =
            super::common::harness_sized("lesson=pose-graph&example=thesis&solver=gn&seed=1", size);
        h.run();
        lesson_mut(&mut h).start_optimize();
        lesson_mut(&mut h).advance_optimize(None);
        let optimized = write_g2o(lesson(&h).session().graph()).unwrap();
        lesson_mut(&mut h)
            .open_graph_file("a-long-name-of-my-solution.g2o", optimized.into_bytes());
        h.run();
        assert_eq!(lesson(&h).solutions().items().len(), 1);
        assert_eq!(h.state().notices().len(), 1, "{:?}", h.state().notices());
        super::common::assert_corner_window_beside_the_notices(&h, "Your solutions");
        super::common::shot(&mut h, shot);
    }
}
