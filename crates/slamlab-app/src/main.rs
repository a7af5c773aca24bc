//! The native SLAM Lab desktop app.

#[cfg(not(target_arch = "wasm32"))]
fn main() -> eframe::Result {
    env_logger::init();
    let query = std::env::args().nth(1).unwrap_or_default();
    eframe::run_native(
        "SLAM Lab",
        eframe::NativeOptions::default(),
        Box::new(move |_cc| Ok(Box::new(slamlab_app::SlamLabApp::new(&query)))),
    )
}

#[cfg(target_arch = "wasm32")]
fn main() {}
