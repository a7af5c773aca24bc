//! SLAM Lab's egui front end (placeholder while the lesson is built).

/// The SLAM Lab application.
#[derive(Debug, Default)]
pub struct SlamLabApp {
    /// The page's query string, e.g. `lesson=landmark-slam&seed=7`.
    pub query: String,
}

impl SlamLabApp {
    /// Creates the app from the page's query string.
    pub fn new(query: &str) -> Self {
        Self { query: query.to_owned() }
    }

    /// Draws the whole app.
    pub fn app_ui(&mut self, ui: &mut egui::Ui) {
        ui.heading("SLAM Lab");
        ui.label(format!("query: {}", self.query));
    }
}

impl eframe::App for SlamLabApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        egui::CentralPanel::default().show_inside(ui, |ui| self.app_ui(ui));
    }
}
