//! The covariance heatmap: a filter's covariance as a correlation matrix
//! `ρ_ij = P_ij / √(P_ii P_jj)`, robot block first, then the landmarks in order of
//! discovery, on a diverging colour map from -1 to +1.

use crate::palette;
use egui::{Color32, Rect, Sense, Stroke, pos2, vec2};
use slamlab_sim::LandmarkSession;

/// Largest image side, pixels: bigger states are sampled.
const MAX_SIDE: usize = 600;

/// The heatmap's texture and which state it shows.
#[derive(Default)]
pub struct HeatmapState {
    selected: usize,
    texture: Option<egui::TextureHandle>,
    built_for: Option<(u64, usize)>,
}

impl std::fmt::Debug for HeatmapState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HeatmapState")
            .field("selected", &self.selected)
            .field("built_for", &self.built_for)
            .finish_non_exhaustive()
    }
}

/// The name of state index `i`: "x", "y", "θ", then "L7.x", "L7.y", ...
pub fn state_name(i: usize, landmark_ids: &[usize]) -> String {
    match i {
        0 => "x".to_owned(),
        1 => "y".to_owned(),
        2 => "θ".to_owned(),
        _ => {
            let slot = (i - 3) / 2;
            let axis = if (i - 3).is_multiple_of(2) { "x" } else { "y" };
            match landmark_ids.get(slot) {
                Some(id) => format!("L{id}.{axis}"),
                None => format!("#{i}"),
            }
        }
    }
}

/// The correlation of entries `i` and `j`, or `None` when a variance is zero.
pub fn correlation(p: &nalgebra::DMatrix<f64>, i: usize, j: usize) -> Option<f64> {
    let (n, m) = p.shape();
    if i >= n || j >= m || i >= m || j >= n {
        return None;
    }
    let denominator = (p[(i, i)] * p[(j, j)]).sqrt();
    (denominator.is_finite() && denominator > 0.0)
        .then(|| (p[(i, j)] / denominator).clamp(-1.0, 1.0))
        .filter(|r| r.is_finite())
}

fn build_image(p: &nalgebra::DMatrix<f64>) -> egui::ColorImage {
    let n = p.nrows().min(p.ncols()).max(1);
    let side = n.min(MAX_SIDE);
    let sqrt_diag: Vec<f64> = (0..n)
        .map(|i| {
            if i < p.nrows() && i < p.ncols() {
                p[(i, i)].max(0.0).sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let mut pixels = Vec::with_capacity(side * side);
    for r in 0..side {
        let i = r * n / side;
        for c in 0..side {
            let j = c * n / side;
            let d = sqrt_diag[i] * sqrt_diag[j];
            let value = if d > 0.0 && i < p.nrows() && j < p.ncols() {
                p[(i, j)] / d
            } else {
                f64::NAN
            };
            pixels.push(palette::diverging(value));
        }
    }
    egui::ColorImage::new([side, side], pixels)
}

/// The heatmap window's contents.
pub fn heatmap_ui(
    ui: &mut egui::Ui,
    session: &LandmarkSession,
    state: &mut HeatmapState,
    version: u64,
) {
    let filters = session.filters();
    if filters.is_empty() {
        ui.label("No estimator is running.");
        return;
    }
    // Particle filters keep no joint covariance: say so, and offer the others.
    for run in filters.iter().filter(|r| r.filter().gaussian().is_none()) {
        ui.label(format!(
            "{} keeps no joint covariance. Each of its {} particles carries a map of its own, \
             and given the particle's path its landmarks are independent: one 2x2 filter each, \
             no robot–landmark or landmark–landmark correlations to show. The map draws the \
             particles and the best particle's landmark ellipses.",
            run.kind.name().to_uppercase(),
            run.filter().particles().map_or(0, |p| p.particle_count()),
        ));
    }
    let gaussian_runs: Vec<usize> = (0..filters.len())
        .filter(|&k| filters[k].filter().gaussian().is_some())
        .collect();
    if gaussian_runs.is_empty() {
        ui.label("No Gaussian filter is running.");
        return;
    }
    if !gaussian_runs.contains(&state.selected) {
        state.selected = gaussian_runs[0];
    }
    ui.horizontal(|ui| {
        ui.label("Filter:");
        for &k in &gaussian_runs {
            let name = filters[k].kind.name();
            let text =
                egui::RichText::new(name.to_uppercase()).color(palette::estimator_color(name));
            ui.selectable_value(&mut state.selected, k, text);
        }
    });
    let run = &filters[state.selected];
    let filter = run.filter();
    let ids = filter.landmark_ids();
    let Some(gaussian) = filter.gaussian() else {
        return;
    };
    let p = gaussian.covariance();
    let n = p.nrows();
    ui.label(format!(
        "Correlation ρ = P_ij / √(P_ii P_jj) of the {}×{} covariance: robot x, y, θ first, then the {} landmarks in order of discovery. Hover a cell for the pair.",
        n,
        n,
        ids.len()
    ));
    if state.built_for != Some((version, state.selected)) || state.texture.is_none() {
        let image = build_image(p);
        match &mut state.texture {
            Some(texture) => texture.set(image, egui::TextureOptions::NEAREST),
            None => {
                state.texture = Some(ui.ctx().load_texture(
                    "slamlab_covariance",
                    image,
                    egui::TextureOptions::NEAREST,
                ));
            }
        }
        state.built_for = Some((version, state.selected));
    }
    let Some(texture) = &state.texture else {
        return;
    };
    let label_margin = 44.0;
    let side = (ui.available_width() - label_margin - 8.0)
        .min(ui.available_height() - 70.0)
        .max(120.0);
    let (outer, response) = ui.allocate_exact_size(
        vec2(side + label_margin, side + label_margin),
        Sense::hover(),
    );
    response
        .widget_info(|| egui::WidgetInfo::labeled(egui::Role::Image, true, "Covariance heatmap"));
    let rect = Rect::from_min_size(
        outer.min + vec2(label_margin, label_margin),
        vec2(side, side),
    );
    let painter = ui.painter_at(outer);
    painter.image(
        texture.id(),
        rect,
        Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0)),
        Color32::WHITE,
    );
    let text_color = ui.visuals().text_color();
    let line_color = ui.visuals().text_color().gamma_multiply(0.6);
    let cell = side / n.max(1) as f32;
    // The robot block's border and landmark separators.
    if n > 3 {
        let edge = rect.min.x + 3.0 * cell;
        painter.vline(edge, rect.y_range(), Stroke::new(1.5, line_color));
        painter.hline(
            rect.x_range(),
            rect.min.y + 3.0 * cell,
            Stroke::new(1.5, line_color),
        );
    }
    if cell >= 6.0 {
        for k in 0..ids.len() {
            let at = 3.0 + 2.0 * k as f32;
            painter.vline(
                rect.min.x + at * cell,
                rect.y_range(),
                Stroke::new(0.5, line_color.gamma_multiply(0.5)),
            );
            painter.hline(
                rect.x_range(),
                rect.min.y + at * cell,
                Stroke::new(0.5, line_color.gamma_multiply(0.5)),
            );
        }
    }
    // Labels: every entry when there is room, else one per landmark, else the blocks.
    let font = egui::FontId::proportional(10.0);
    let row_label = |i: usize, text: &str| {
        let y = rect.min.y + (i as f32 + 0.5) * cell;
        painter.text(
            pos2(rect.min.x - 3.0, y),
            egui::Align2::RIGHT_CENTER,
            text,
            font.clone(),
            text_color,
        );
    };
    let column_label = |i: usize, text: &str| {
        let x = rect.min.x + (i as f32 + 0.5) * cell;
        painter.text(
            pos2(x, rect.min.y - 3.0),
            egui::Align2::CENTER_BOTTOM,
            text,
            font.clone(),
            text_color,
        );
    };
    if cell >= 12.0 {
        for i in 0..n {
            row_label(i, &state_name(i, ids));
        }
    } else if 2.0 * cell >= 12.0 {
        for (k, id) in ids.iter().enumerate() {
            let y = rect.min.y + (3.0 + 2.0 * k as f32 + 1.0) * cell;
            painter.text(
                pos2(rect.min.x - 3.0, y),
                egui::Align2::RIGHT_CENTER,
                format!("L{id}"),
                font.clone(),
                text_color,
            );
        }
    }
    if cell >= 30.0 {
        for i in 0..n {
            column_label(i, &state_name(i, ids));
        }
    } else if cell >= 10.0 {
        for (i, name) in ["x", "y", "θ"].iter().enumerate() {
            column_label(i, name);
        }
        for (k, id) in ids.iter().enumerate() {
            let x = rect.min.x + (3.0 + 2.0 * k as f32 + 1.0) * cell;
            painter.text(
                pos2(x, rect.min.y - 3.0),
                egui::Align2::CENTER_BOTTOM,
                format!("L{id}"),
                font.clone(),
                text_color,
            );
        }
    }
    if cell < 12.0 && 2.0 * cell < 12.0 {
        row_label(1, "robot");
        if n > 3 {
            painter.text(
                pos2(
                    rect.min.x - 3.0,
                    rect.min.y + (3.0 + (n as f32 - 3.0) / 2.0) * cell,
                ),
                egui::Align2::RIGHT_CENTER,
                "land-\nmarks",
                font.clone(),
                text_color,
            );
        }
    }
    if cell < 10.0 {
        column_label(1, "robot");
        if n > 3 {
            painter.text(
                pos2(
                    rect.min.x + (3.0 + (n as f32 - 3.0) / 2.0) * cell,
                    rect.min.y - 3.0,
                ),
                egui::Align2::CENTER_BOTTOM,
                "landmarks",
                font.clone(),
                text_color,
            );
        }
    }
    // Hover: name the pair.
    if let Some(pointer) = response.hover_pos()
        && rect.contains(pointer)
    {
        let i = (((pointer.y - rect.min.y) / cell) as usize).min(n.saturating_sub(1));
        let j = (((pointer.x - rect.min.x) / cell) as usize).min(n.saturating_sub(1));
        let text = match correlation(p, i, j) {
            Some(rho) => format!(
                "{} with {}: ρ = {rho:.2}\n(covariance {:.3e})",
                state_name(i, ids),
                state_name(j, ids),
                p[(i, j)]
            ),
            None => format!(
                "{} with {}: ρ undefined (a variance is zero)",
                state_name(i, ids),
                state_name(j, ids)
            ),
        };
        response.on_hover_ui_at_pointer(|ui| {
            ui.label(text);
        });
    }
    colour_bar_ui(ui);
}

fn colour_bar_ui(ui: &mut egui::Ui) {
    let width = ui.available_width().clamp(120.0, 320.0);
    let (rect, _) = ui.allocate_exact_size(vec2(width, 30.0), Sense::hover());
    let painter = ui.painter_at(rect);
    let bar = Rect::from_min_size(rect.min, vec2(width, 12.0));
    let steps = 64;
    for k in 0..steps {
        let value = -1.0 + 2.0 * (k as f64 + 0.5) / steps as f64;
        let x0 = bar.min.x + width * k as f32 / steps as f32;
        let x1 = bar.min.x + width * (k + 1) as f32 / steps as f32;
        painter.rect_filled(
            Rect::from_min_max(pos2(x0, bar.min.y), pos2(x1 + 0.5, bar.max.y)),
            0.0,
            palette::diverging(value),
        );
    }
    let color = ui.visuals().text_color();
    let font = egui::FontId::proportional(11.0);
    for (value, anchor) in [
        (-1.0_f32, egui::Align2::LEFT_TOP),
        (0.0, egui::Align2::CENTER_TOP),
        (1.0, egui::Align2::RIGHT_TOP),
    ] {
        let x = bar.min.x + width * (value + 1.0) / 2.0;
        let label = match value {
            v if v < 0.0 => "ρ = −1",
            v if v > 0.0 => "+1",
            _ => "0",
        };
        painter.text(pos2(x, bar.max.y + 2.0), anchor, label, font.clone(), color);
    }
    painter.text(
        pos2(bar.min.x + width * 0.75, bar.max.y + 2.0),
        egui::Align2::CENTER_TOP,
        "grey: undefined",
        font,
        ui.visuals().weak_text_color(),
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    #[test]
    fn names_and_correlations() {
        let ids = [7, 2];
        assert_eq!(state_name(0, &ids), "x");
        assert_eq!(state_name(2, &ids), "θ");
        assert_eq!(state_name(3, &ids), "L7.x");
        assert_eq!(state_name(6, &ids), "L2.y");
        assert_eq!(state_name(9, &ids), "#9");
        let p = DMatrix::from_row_slice(3, 3, &[4.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!(correlation(&p, 0, 1), Some(1.0));
        assert_eq!(correlation(&p, 0, 2), None);
        assert_eq!(correlation(&p, 5, 0), None);
        let image = build_image(&p);
        assert_eq!(image.size, [3, 3]);
        assert_eq!(image.pixels[0], palette::VERMILLION);
        assert_eq!(image.pixels[8], Color32::from_gray(128));
        let big = DMatrix::<f64>::identity(1003, 1003);
        assert_eq!(build_image(&big).size, [MAX_SIDE, MAX_SIDE]);
    }
}
