//! One frame of a lesson's UI, without the GPU: the app's layout and drawing
//! code (map, plots, panels) plus egui's tessellation into triangles, at
//! 1280 x 800 part way through a run. This is the CPU work a browser frame does besides
//! the simulation: `cargo bench -p slamlab-app --bench frame`.
//!
//! Targets (README): well under 16 ms (a 60 Hz frame) with 50 landmarks and EKF
//! and UKF side by side, and for the Monte Carlo lesson at 5,000 particles.

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

/// One frame: the app's UI code, then tessellation into meshes.
fn tessellated(ctx: &egui::Context, app: &mut SlamLabApp) -> Vec<egui::ClippedPrimitive> {
    let mut output = ctx.run_ui(input(), |ui| app.app_ui(ui));
    // No GPU here to upload the textures to (the grid lessons' map tiles).
    output.textures_delta.clear();
    ctx.tessellate(output.shapes, output.pixels_per_point)
}

/// One frame; returns the triangle count.
fn frame(ctx: &egui::Context, app: &mut SlamLabApp) -> usize {
    tessellated(ctx, app)
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

/// One frame of the Monte Carlo localization lesson at 5,000 particles per filter
/// (tracking on the maze, after 60 ticks): the particle clouds are one mesh each.
/// Target (README, "Monte Carlo localization"): under 16 ms with one filter.
#[divan::bench(args = ["mcl", "amcl,acmcl"])]
fn kidnap_frame_5000_particles(bencher: divan::Bencher, estimators: &str) {
    let ctx = egui::Context::default();
    let mut app = SlamLabApp::from_query(&format!(
        "lesson=kidnap&map=maze&seed=5&init=tracking&particles=5000&estimator={estimators}"
    ));
    for _ in 0..60 {
        app.apply_time_action(slamlab_app::time_control::TimeAction::StepTick);
    }
    for _ in 0..5 {
        frame(&ctx, &mut app);
    }
    bencher.bench_local(|| frame(&ctx, &mut app));
}

/// One frame of the Cartographer lesson on the Intel log (`../shared/data/laser/
/// intel.clf.bz2`, or `$SLAMLAB_SHARED/data/laser`) after `SCANS` scans: the map
/// with every submap, node and constraint so far, and the plots. What the page
/// draws between its simulation slices when the log plays at maximum speed; its
/// growth with the scans is what limits the on-screen pace (docs/cartographer.md).
/// Skipped with a message when the log is absent.
#[divan::bench(consts = [3000, 10000])]
fn cartographer_intel_frame<const SCANS: usize>(bencher: divan::Bencher) {
    let dir = std::env::var_os("SLAMLAB_SHARED")
        .map_or_else(
            || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"),
            std::path::PathBuf::from,
        )
        .join("data/laser");
    let Ok(log) = std::fs::read(dir.join("intel.clf.bz2")) else {
        eprintln!("skipped: the Intel log is not in {}", dir.display());
        return;
    };
    let ctx = egui::Context::default();
    let mut app = SlamLabApp::from_query("lesson=cartographer");
    let Some(lesson) = app.lesson_as_mut::<slamlab_app::cartographer::CartographerLesson>() else {
        eprintln!("skipped: the Cartographer lesson did not open");
        return;
    };
    lesson.load_log("intel.clf.bz2", &log, None);
    lesson.run_to(SCANS);
    for _ in 0..5 {
        frame(&ctx, &mut app);
    }
    // Each mesh is a draw call in the browser (53 at 10,000 scans, 2026-11-28).
    eprintln!(
        "{SCANS} scans: {} meshes",
        tessellated(&ctx, &mut app).len()
    );
    bencher.bench_local(|| frame(&ctx, &mut app));
}
