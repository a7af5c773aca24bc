//! The layout every lesson shares: plots along the bottom, parameters on the
//! left, the explanation on the right, the map in the middle; each side panel
//! collapsible and resizable.

use crate::lesson::PanelVisibility;

/// A lesson's four areas.
pub trait LessonPanels {
    /// The plots (bottom).
    fn plots_ui(&mut self, ui: &mut egui::Ui);
    /// The parameter panel (left).
    fn parameters_ui(&mut self, ui: &mut egui::Ui);
    /// The explanation panel (right).
    fn explanation_ui(&mut self, ui: &mut egui::Ui);
    /// The map and its toolbar (centre).
    fn map_ui(&mut self, ui: &mut egui::Ui);
}

/// Lays out `lesson`'s areas; `id` keeps each lesson's panel sizes apart.
pub fn lesson_panels_ui(
    lesson: &mut impl LessonPanels,
    ui: &mut egui::Ui,
    panels: &mut PanelVisibility,
    compact: bool,
    id: &str,
) {
    let plot_height = if compact { 150.0 } else { 230.0 };
    egui::Panel::bottom(format!("{id}_plots"))
        .resizable(true)
        .default_size(plot_height)
        .min_size(120.0)
        .show_collapsible(ui, &mut panels.plots, |ui| {
            lesson.plots_ui(ui);
            // Fill the panel to its bottom edge, whatever the plots used.
            ui.expand_to_include_rect(ui.max_rect());
        });
    egui::Panel::left(format!("{id}_parameters"))
        .resizable(true)
        .default_size(300.0)
        .min_size(220.0)
        .max_size(480.0)
        .show_collapsible(ui, &mut panels.parameters, |ui| {
            egui::ScrollArea::vertical()
                .id_salt(format!("{id}_parameters_scroll"))
                .show(ui, |ui| lesson.parameters_ui(ui));
        });
    egui::Panel::right(format!("{id}_explanation"))
        .resizable(true)
        .default_size(330.0)
        .min_size(220.0)
        .max_size(520.0)
        .show_collapsible(ui, &mut panels.explanation, |ui| {
            egui::ScrollArea::vertical()
                .id_salt(format!("{id}_explanation_scroll"))
                .show(ui, |ui| lesson.explanation_ui(ui));
        });
    egui::CentralPanel::default().show(ui, |ui| lesson.map_ui(ui));
}
