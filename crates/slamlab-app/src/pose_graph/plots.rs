//! The plots under the map: the cost after every iteration on a log scale, and
//! the sparsity patterns of the information matrix `H` and of its Cholesky factor
//! `L` as images, with the fill-in marked in vermillion.

use super::Patterns;
use crate::export::PlotSeries;
use crate::palette;
use crate::widgets::plots::{thin, title_ui};
use egui::{Color32, ColorImage, TextureOptions};
use egui_plot::{Line, Plot, PlotPoints, Points};
use slamlab_core::graph::BlockPattern;
use slamlab_core::math;
use slamlab_sim::pose_graph_lesson::PoseGraphSession;

/// Largest side of a sparsity image, pixels (larger matrices are scaled down; a
/// pixel is set if any entry it covers is non-zero).
const MAX_IMAGE: usize = 360;

/// The cost plot and the two sparsity images side by side.
pub fn plots_ui(ui: &mut egui::Ui, session: &mut PoseGraphSession, patterns: &mut Patterns) {
    let height = (ui.available_height() - 26.0).max(80.0);
    let dark = ui.visuals().dark_mode;
    if patterns.dirty || patterns.dark != dark {
        rebuild(ui.ctx(), session, patterns, dark);
    }
    ui.columns(3, |columns| {
        cost_plot(&mut columns[0], session, height);
        let (h, l) = (patterns.h.clone(), patterns.l.clone());
        let ui = &mut columns[1];
        title_ui(
            ui,
            &format!(
                "Information matrix H ({0} x {0})",
                patterns.unknowns
            ),
            "H = Σ J^TΩJ in the graph's vertex order: a block is non-zero where an edge joins two vertices (Eq. 4.8 of Xiang's thesis). Blue: non-zero.",
        );
        ui.label(format!("{} non-zero blocks", patterns.h_blocks));
        image_ui(ui, h.as_ref(), height - 20.0, "Information matrix H");
        let ui = &mut columns[2];
        title_ui(
            ui,
            "Cholesky factor L",
            "L L^T = H after a fill-reducing reordering of the vertices: blue where H was already non-zero, vermillion where elimination created fill-in.",
        );
        ui.label(format!(
            "{} blocks, {} of them fill-in; {} scalar non-zeros",
            patterns.l_blocks, patterns.fill_blocks, patterns.l_nonzeros
        ));
        image_ui(ui, l.as_ref(), height - 20.0, "Cholesky factor L");
        if let Some(e) = &patterns.error {
            ui.colored_label(palette::VERMILLION, e);
        }
    });
}

fn cost_plot(ui: &mut egui::Ui, session: &PoseGraphSession, height: f32) {
    title_ui(
        ui,
        "Cost per iteration (log scale)",
        "F(x) = Σ ρ(e^TΩe) after each iteration (Eq. 4.2 of Xiang's thesis); dots mark edits (a drag, a wrong loop closure, another solver or kernel)",
    );
    let log = |c: f64| if c > 0.0 { math::log10(c) } else { f64::NAN };
    let history = session.history();
    let points: Vec<[f64; 2]> = history.iter().map(|h| [h[0], log(h[1])]).collect();
    // Edits: a point at the same iteration as the one before.
    let edits: Vec<[f64; 2]> = history
        .windows(2)
        .filter(|w| w[1][0] == w[0][0])
        .map(|w| [w[1][0], log(w[1][1])])
        .filter(|p| p[1].is_finite())
        .collect();
    Plot::new("pose_graph_cost")
        .height(height)
        .x_axis_label("iteration")
        .y_axis_label("cost")
        .y_axis_formatter(|mark, _| format!("1e{:.0}", mark.value))
        .y_grid_spacer(egui_plot::uniform_grid_spacer(|_| [1.0, 1.0, 10.0]))
        .include_x(0.0)
        .include_x(5.0)
        .allow_scroll(false)
        .show(ui, |plot_ui| {
            plot_ui.line(
                Line::new("cost", PlotPoints::new(thin(points.clone())))
                    .color(palette::BLUE)
                    .width(2.0),
            );
            plot_ui.points(
                Points::new("iterations", PlotPoints::new(thin(points)))
                    .color(palette::BLUE)
                    .radius(2.5),
            );
            if !edits.is_empty() {
                plot_ui.points(
                    Points::new("edits", PlotPoints::new(edits))
                        .color(palette::VERMILLION)
                        .radius(4.0),
                );
            }
        });
}

fn image_ui(ui: &mut egui::Ui, texture: Option<&egui::TextureHandle>, height: f32, name: &str) {
    let Some(texture) = texture else {
        return;
    };
    let side = height.min(ui.available_width()).max(40.0);
    ui.add(egui::Image::new((texture.id(), egui::vec2(side, side))))
        .on_hover_text(name);
}

fn rebuild(
    ctx: &egui::Context,
    session: &mut PoseGraphSession,
    patterns: &mut Patterns,
    dark: bool,
) {
    patterns.dirty = false;
    patterns.dark = dark;
    match session.patterns() {
        Ok((h, l, nnz)) => {
            patterns.unknowns = h.dims.iter().sum();
            patterns.h_blocks = h.entries.len();
            patterns.l_blocks = l.entries.len();
            patterns.fill_blocks = l.fill_in.iter().filter(|f| **f).count();
            patterns.l_nonzeros = nnz;
            patterns.error = None;
            let background = if dark {
                Color32::from_gray(30)
            } else {
                Color32::WHITE
            };
            let h_image = raster(&h, true, background);
            let l_image = raster(&l, false, background);
            patterns.h = Some(ctx.load_texture("pose_graph_h", h_image, TextureOptions::NEAREST));
            patterns.l = Some(ctx.load_texture("pose_graph_l", l_image, TextureOptions::NEAREST));
        }
        Err(why) => {
            patterns.error = Some(why);
            patterns.h = None;
            patterns.l = None;
        }
    }
}

/// The pattern as an image: blue non-zeros, vermillion fill-in. `symmetric`
/// mirrors each block (`H`'s pattern lists both triangles already; `L` is lower).
pub fn raster(pattern: &BlockPattern, symmetric: bool, background: Color32) -> ColorImage {
    let n: usize = pattern.dims.iter().sum();
    let side = n.clamp(1, MAX_IMAGE);
    let mut image = ColorImage::filled([side, side], background);
    let mut offset = Vec::with_capacity(pattern.dims.len());
    let mut o = 0;
    for &d in &pattern.dims {
        offset.push(o);
        o += d;
    }
    let px = |k: usize| (k * side / n.max(1)).min(side - 1);
    for (k, &(r, c)) in pattern.entries.iter().enumerate() {
        let fill = pattern.fill_in.get(k).copied().unwrap_or(false);
        let color = if fill {
            palette::VERMILLION
        } else {
            palette::BLUE
        };
        let (r0, r1) = (px(offset[r]), px(offset[r] + pattern.dims[r] - 1));
        let (c0, c1) = (px(offset[c]), px(offset[c] + pattern.dims[c] - 1));
        for y in r0..=r1 {
            for x in c0..=c1 {
                let i = y * side + x;
                // Fill-in never hides an original non-zero that shares its pixel.
                if !(fill && image.pixels[i] == palette::BLUE) {
                    image.pixels[i] = color;
                }
                if symmetric {
                    image.pixels[x * side + y] = color;
                }
            }
        }
    }
    image
}

/// The cost plot's series (cost, not its logarithm), for the CSV export.
pub fn series(session: &PoseGraphSession) -> Vec<PlotSeries> {
    vec![PlotSeries::new(
        "Cost per iteration",
        "iteration",
        "cost",
        "cost",
        session.history().iter().map(|h| [h[0], h[1]]).collect(),
    )]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pattern_rasters_its_blocks_and_marks_fill_in() {
        let pattern = BlockPattern {
            vertex_ids: vec![1, 2, 3],
            dims: vec![3, 3, 2],
            entries: vec![(0, 0), (1, 1), (2, 0), (2, 1), (2, 2)],
            fill_in: vec![false, false, false, true, false],
        };
        let image = raster(&pattern, false, Color32::WHITE);
        assert_eq!(image.size, [8, 8]);
        let count = |c: Color32| image.pixels.iter().filter(|p| **p == c).count();
        assert_eq!(count(palette::BLUE), 9 + 9 + 6 + 4);
        assert_eq!(count(palette::VERMILLION), 6);
        assert_eq!(image.pixels[6 * 8 + 3], palette::VERMILLION);
        assert_eq!(image.pixels[3 * 8 + 6], Color32::WHITE);
    }
}
