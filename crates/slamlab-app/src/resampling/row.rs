//! The lab's centre: the particle row. On top, each particle's expected copies
//! `M wᵢ` as a bar (drag a bar to change that weight); below, one band per
//! method with the copies its latest resampling gave, and a tick at `M wᵢ` on
//! each bar so that the student sees at a glance which particles got more or
//! fewer copies than they deserved. All bands share one vertical scale.

use super::method_color;
use crate::palette;
use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Stroke, StrokeKind, vec2};
use slamlab_sim::resampling::session::LabRun;

/// What the student asked for on the row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RowRequest {
    /// Set particle `.0`'s normalized weight to `.1` (the others keep theirs, then
    /// the row is normalized).
    SetWeight(usize, f64),
    /// Plot particle `.0`'s histogram.
    Focus(usize),
}

/// Width of the band labels on the left, points.
const LABEL_WIDTH: f32 = 116.0;

/// Draws the row and returns what a drag or click asked for.
pub fn row_ui(ui: &mut egui::Ui, run: &LabRun) -> Option<RowRequest> {
    let lab = run.lab();
    let m = run.particles();
    let methods = &run.scenario().methods;
    let expected = lab.expected_copies();
    let dark = ui.visuals().dark_mode;
    let text_color = ui.visuals().text_color();
    let truth = palette::truth_color(dark);

    let (rect, response) = ui.allocate_exact_size(ui.available_size(), Sense::click_and_drag());
    let painter = ui.painter_at(rect);
    if m == 0 || rect.width() < LABEL_WIDTH + 20.0 || rect.height() < 80.0 {
        return None;
    }

    // One vertical scale for every band: copies.
    let most_copies = methods
        .iter()
        .flat_map(|&method| lab.last_copies(method).iter().copied())
        .max()
        .unwrap_or(0) as f64;
    let most_expected = expected.iter().copied().fold(0.0_f64, f64::max);
    let y_max = most_copies.max(most_expected).max(1.0).ceil();

    let bands = 1 + methods.len();
    let gap = 10.0;
    let band_height = (rect.height() - gap * bands as f32) / bands as f32;
    let x0 = rect.left() + LABEL_WIDTH;
    let column = (rect.right() - x0 - 4.0) / m as f32;
    let bar = (column * 0.72).max(1.0);
    let focus = run.focus();

    let band_rect = |b: usize| {
        let top = rect.top() + gap + b as f32 * (band_height + gap);
        Rect::from_min_max(
            Pos2::new(x0, top),
            Pos2::new(x0 + column * m as f32, top + band_height),
        )
    };
    let y_of = |band: Rect, v: f64| band.bottom() - (v / y_max) as f32 * band.height();
    let column_x = |i: usize| x0 + column * (i as f32 + 0.5);

    let small = FontId::proportional(12.0);
    let axis_stroke = Stroke::new(1.0, text_color.gamma_multiply(0.5));
    let band_frame = |b: usize, title: &str, color: Color32| {
        let band = band_rect(b);
        // The plotted particle's column, faintly.
        let cx = column_x(focus);
        painter.rect_filled(
            Rect::from_center_size(Pos2::new(cx, band.center().y), vec2(column, band.height())),
            0.0,
            text_color.gamma_multiply(0.08),
        );
        painter.line_segment([band.left_bottom(), band.right_bottom()], axis_stroke);
        painter.line_segment([band.left_top(), band.left_bottom()], axis_stroke);
        painter.text(
            Pos2::new(rect.left() + 4.0, band.center().y - 8.0),
            Align2::LEFT_CENTER,
            title,
            FontId::proportional(13.0),
            color,
        );
        painter.text(
            Pos2::new(band.left() - 4.0, band.top()),
            Align2::RIGHT_TOP,
            format!("{y_max:.0}"),
            small.clone(),
            text_color,
        );
        painter.text(
            Pos2::new(band.left() - 4.0, band.bottom()),
            Align2::RIGHT_BOTTOM,
            "0",
            small.clone(),
            text_color,
        );
        band
    };

    // The weights, as expected copies M wᵢ.
    let weights_band = band_frame(0, "M·w_i (drag)", text_color);
    painter.text(
        Pos2::new(rect.left() + 4.0, weights_band.center().y + 8.0),
        Align2::LEFT_CENTER,
        "expected copies",
        small.clone(),
        text_color.gamma_multiply(0.7),
    );
    for (i, &e) in expected.iter().enumerate() {
        let x = column_x(i);
        let top = y_of(weights_band, e);
        painter.rect_filled(
            Rect::from_min_max(
                Pos2::new(x - bar / 2.0, top),
                Pos2::new(x + bar / 2.0, weights_band.bottom()),
            ),
            1.0,
            palette::DEAD_RECKONING,
        );
    }

    // Each method's latest copies, with the expected count as a tick.
    for (k, &method) in methods.iter().enumerate() {
        let color = method_color(method);
        let band = band_frame(k + 1, method.name(), color);
        let copies = lab.last_copies(method);
        if copies.is_empty() {
            painter.text(
                band.center(),
                Align2::CENTER_CENTER,
                "not resampled yet: press \"Resample once\"",
                small.clone(),
                text_color.gamma_multiply(0.7),
            );
        }
        for (i, &c) in copies.iter().enumerate() {
            let x = column_x(i);
            if c > 0 {
                painter.rect_filled(
                    Rect::from_min_max(
                        Pos2::new(x - bar / 2.0, y_of(band, c as f64)),
                        Pos2::new(x + bar / 2.0, band.bottom()),
                    ),
                    1.0,
                    color,
                );
            }
        }
        for (i, &e) in expected.iter().enumerate() {
            let x = column_x(i);
            let y = y_of(band, e);
            painter.line_segment(
                [
                    Pos2::new(x - column / 2.0 + 1.0, y),
                    Pos2::new(x + column / 2.0 - 1.0, y),
                ],
                Stroke::new(2.0, truth),
            );
        }
    }
    // The focus column's outline across every band.
    let all = band_rect(0).union(band_rect(bands - 1));
    painter.rect_stroke(
        Rect::from_center_size(
            Pos2::new(column_x(focus), all.center().y),
            vec2(column, all.height()),
        ),
        0.0,
        Stroke::new(1.0, text_color.gamma_multiply(0.35)),
        StrokeKind::Inside,
    );

    // Which particle is under the pointer.
    let particle_at = |pos: Pos2| -> Option<usize> {
        let i = ((pos.x - x0) / column).floor();
        (i >= 0.0 && (i as usize) < m).then_some(i as usize)
    };
    if let Some(pos) = response.hover_pos()
        && let Some(i) = particle_at(pos)
    {
        let w = lab.weights()[i];
        let mut text = format!(
            "particle {i}: w = {w:.4}, M·w = {:.3} expected copies",
            expected[i]
        );
        for &method in methods {
            let copies = lab.last_copies(method).get(i).copied();
            let stats = lab.stats(method).filter(|s| s.trials() > 0);
            text.push_str(&format!(
                "\n{}: {} now{}",
                method.name(),
                copies.map_or("–".to_owned(), |c| c.to_string()),
                stats.map_or(String::new(), |s| format!(
                    ", mean {:.3}, variance {:.3} over {}",
                    s.means()[i],
                    s.variances()[i],
                    s.trials()
                ))
            ));
        }
        text.push_str(
            "\nClick: plot this particle's copies. Drag in the top band: change its weight.",
        );
        response.clone().on_hover_text_at_pointer(text);
    }

    // A drag in the weights band sets the weight under the pointer; a click
    // anywhere picks the plotted particle.
    if (response.dragged() || response.clicked())
        && let Some(pos) = response.interact_pointer_pos()
        && let Some(i) = particle_at(pos)
    {
        if weights_band.expand2(vec2(0.0, gap / 2.0)).contains(pos) {
            let e = ((weights_band.bottom() - pos.y) / weights_band.height()) as f64 * y_max;
            let w = (e.clamp(0.0, y_max) / m as f64).min(1.0);
            if (w - lab.weights()[i]).abs() > 1e-9 {
                return Some(RowRequest::SetWeight(i, w));
            }
        } else if response.clicked() && i != focus {
            return Some(RowRequest::Focus(i));
        }
    }
    None
}
