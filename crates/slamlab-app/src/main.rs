//! The native SLAM Lab desktop app. An optional first argument is a query string
//! like the web page's, e.g. `slamlab-app "lesson=landmark-slam&seed=7"`.

#[cfg(not(target_arch = "wasm32"))]
fn main() -> eframe::Result {
    env_logger::init();
    let query = std::env::args().nth(1).unwrap_or_default();
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("SLAM Lab")
            .with_inner_size([1280.0, 800.0]),
        ..Default::default()
    };
    eframe::run_native(
        "SLAM Lab",
        options,
        Box::new(move |cc| Ok(Box::new(slamlab_app::SlamLabApp::new(cc, &query)))),
    )
}

#[cfg(target_arch = "wasm32")]
fn main() {}
