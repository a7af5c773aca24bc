//! SLAM Lab's egui front end (placeholder while the lesson is built).

#[cfg(target_arch = "wasm32")]
mod web;

/// The SLAM Lab application.
#[derive(Debug, Default)]
pub struct SlamLabApp {
    /// The page's query string, e.g. `lesson=landmark-slam&seed=7`.
    pub query: String,
    /// Frames drawn so far.
    pub frames: u64,
}

impl SlamLabApp {
    /// Creates the app from the page's query string (without the leading `?`).
    pub fn new(_cc: &eframe::CreationContext<'_>, query: &str) -> Self {
        Self::from_query(query)
    }

    /// Creates the app without an eframe context (tests).
    pub fn from_query(query: &str) -> Self {
        Self { query: query.trim_start_matches('?').to_owned(), frames: 0 }
    }

    /// A one-line JSON summary of the app's state for browser tests.
    pub fn test_state_json(&self) -> String {
        format!("{{\"frames\":{}}}", self.frames)
    }

    /// Draws the whole app.
    pub fn app_ui(&mut self, ui: &mut egui::Ui) {
        self.frames += 1;
        ui.heading("SLAM Lab");
        ui.label(format!("query: {}", self.query));
    }
}

impl eframe::App for SlamLabApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        egui::CentralPanel::default().show_inside(ui, |ui| self.app_ui(ui));
    }
}
