//! One frame of the landmark-SLAM lesson's UI, without the GPU: the app's layout
//! and drawing code (map, plots, panels) plus egui's tessellation into triangles,
//! at 1280 x 800 after 150 ticks. This is the CPU work a browser frame does besides
//! the simulation: `cargo bench -p slamlab-app --bench frame`.
//!
//! Target (README, "Speed"): well under 16 ms (a 60 Hz frame) with 50 landmarks and
//! EKF and UKF side by side.

use slamlab_app::SlamLabApp;

fn main() {
    divan::main();
}

fn input() -> egui::RawInput {
    egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(
            egui::Pos2::ZERO,
            egui::vec2(1280.0, 800.0),
        )),
        ..Default::default()
    }
}

/// One frame: the app's UI code, then tessellation; returns the triangle count.
fn frame(ctx: &egui::Context, app: &mut SlamLabApp) -> usize {
    let output = ctx.run_ui(input(), |ui| app.app_ui(ui));
    let meshes = ctx.tessellate(output.shapes, output.pixels_per_point);
    meshes
        .iter()
        .map(|m| match &m.primitive {
            egui::epaint::Primitive::Mesh(mesh) => mesh.indices.len() / 3,
            egui::epaint::Primitive::Callback(_) => 0,
        })
        .sum()
}

#[divan::bench(args = ["ekf", "ekf,ukf"], consts = [20, 50])]
fn lesson_frame<const LANDMARKS: usize>(bencher: divan::Bencher, estimators: &str) {
    let ctx = egui::Context::default();
    let mut app = SlamLabApp::from_query(&format!(
        "lesson=landmark-slam&seed=1&landmarks={LANDMARKS}&estimator={estimators}"
    ));
    if let Some(lesson) = app.landmark_lesson_mut() {
        for _ in 0..150 {
            lesson.step_tick();
        }
    }
    // Fonts and layout caches settle over the first frames.
    for _ in 0..5 {
        frame(&ctx, &mut app);
    }
    bencher.bench_local(|| frame(&ctx, &mut app));
}
