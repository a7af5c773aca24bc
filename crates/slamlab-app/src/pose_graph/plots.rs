//! The plots under the map: the cost after every iteration on a log scale, and
//! the sparsity patterns of the information matrix `H` and of its Cholesky factor
//! `L` as images, with the fill-in marked in vermillion.

use super::Patterns;
use crate::export::PlotSeries;
use crate::palette;
use crate::widgets::plots::{
    Figure, FigureRecord, KeyEntry, Mark, figure_plot, log_figure_ui, marker_radius, plot_row,
    record, thin, title_ui,
};
use egui::{Color32, ColorImage, TextureOptions};
use egui_plot::{Line, LineStyle, PlotPoints, Points, VLine};
use slamlab_core::graph::BlockPattern;
use slamlab_core::math;
use slamlab_sim::pose_graph::session::PoseGraphSession;

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
    let (h, l) = (patterns.h.clone(), patterns.l.clone());
    let patterns = &*patterns;
    // An embed shows the first two: the cost and H.
    plot_row(ui, 3, |k, ui| match k {
        0 => cost_plot(ui, session, height),
        1 => {
            title_ui(
                ui,
                "Information matrix H",
                &format!(
                    "H = Σ J^TΩJ in the graph's vertex order, one square per vertex block ({0} x {0} \
                     scalars with the fixed vertex): a block is non-zero where an edge joins two \
                     vertices (Eq. 4.8 of Xiang's thesis). Blue: non-zero; a loop closure is a \
                     square away from the diagonal band, with its mirror across the diagonal.",
                    patterns.unknowns
                ),
            );
            ui.label(format!(
                "{0} x {0} vertex blocks, {1} non-zero",
                patterns.vertices, patterns.h_blocks
            ))
            .on_hover_text(
                "The fixed vertex (the square on the map) is drawn in its place although it is \
                     not an unknown: the solver drops its row and column, so an edge to it adds \
                     only to its other vertex's diagonal block. Its row and column show the loop \
                     closures that reach it.",
            );
            image_ui(ui, h.as_ref(), "Information matrix H");
        }
        _ => {
            title_ui(
                ui,
                "Cholesky factor L",
                "L L^T = H after a fill-reducing reordering of the vertices: blue where H was already non-zero, vermillion where elimination created fill-in.",
            );
            ui.label(format!(
                "{} blocks, {} of them fill-in; {} scalar non-zeros",
                patterns.l_blocks, patterns.fill_blocks, patterns.l_nonzeros
            ));
            image_ui(ui, l.as_ref(), "Cholesky factor L");
        }
    });
    if let Some(e) = &patterns.error {
        ui.colored_label(palette::VERMILLION, e);
    }
}

/// The cost history split at the edits: one polyline per stretch of iterations
/// (an edit changes the cost without an iteration, so it starts a new stretch), and
/// the edits' points. Costs of zero or less have no logarithm and are left out.
pub fn cost_segments(history: &[[f64; 2]]) -> (Vec<Vec<[f64; 2]>>, Vec<[f64; 2]>) {
    let log = |c: f64| if c > 0.0 { math::log10(c) } else { f64::NAN };
    let mut segments: Vec<Vec<[f64; 2]>> = Vec::new();
    let mut edits = Vec::new();
    let mut current: Vec<[f64; 2]> = Vec::new();
    for (k, h) in history.iter().enumerate() {
        let point = [h[0], log(h[1])];
        let is_edit = k > 0 && history.get(k - 1).is_some_and(|before| before[0] == h[0]);
        if is_edit {
            if !current.is_empty() {
                segments.push(std::mem::take(&mut current));
            }
            if point[1].is_finite() {
                edits.push(point);
            }
        }
        if point[1].is_finite() {
            current.push(point);
        }
    }
    if !current.is_empty() {
        segments.push(current);
    }
    (segments, edits)
}

fn cost_plot(ui: &mut egui::Ui, session: &PoseGraphSession, height: f32) {
    let (segments, edits) = cost_segments(session.history());
    // The title names the one line; a key only once edits mark it.
    let key = if edits.is_empty() {
        Vec::new()
    } else {
        vec![
            KeyEntry::new("cost after each iteration", palette::BLUE, Mark::Solid),
            KeyEntry::new("edit", palette::VERMILLION, Mark::Dots),
        ]
    };
    // At least a decade of range around the costs (one cost at iteration 0, a
    // converged run), so that the axis has round values to label.
    let (low, high) = segments
        .iter()
        .flatten()
        .map(|p| p[1])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let span = if high - low < 1.0 {
        let middle = 0.5 * (low + high);
        Some((middle - 0.5, middle + 0.5))
    } else {
        None
    };
    log_figure_ui(
        ui,
        &Figure {
            title: "Cost per iteration (log scale)",
            hover: "F(x) = Σ ρ(e^TΩe) after each iteration (Eq. 4.2 of Xiang's thesis); \
                    vermillion marks edits (a drag, a wrong loop closure, another solver or \
                    kernel), where the line starts again",
            key,
            y_label: "cost",
            height,
        },
        |h, y| {
            let plot = figure_plot("pose_graph_cost", "iteration", y, h)
                .include_x(0.0)
                .include_x(5.0);
            match span {
                Some((a, b)) if a.is_finite() && b.is_finite() => plot.include_y(a).include_y(b),
                _ => plot,
            }
        },
        move |plot_ui| {
            let radius = marker_radius(4.0, plot_ui.response().rect.height());
            for edit in &edits {
                plot_ui.vline(
                    VLine::new("edit", edit[0])
                        .color(palette::faded(palette::VERMILLION, 0.6))
                        .style(LineStyle::dashed_dense())
                        .width(1.0),
                );
            }
            for segment in segments {
                if let [single] = segment[..] {
                    // One cost (iteration 0, or right after an edit): a point.
                    plot_ui.points(
                        Points::new("cost", PlotPoints::new(vec![single]))
                            .color(palette::BLUE)
                            .radius(radius),
                    );
                    continue;
                }
                plot_ui.line(
                    Line::new("cost", PlotPoints::new(thin(segment)))
                        .color(palette::BLUE)
                        .width(2.0),
                );
            }
            if !edits.is_empty() {
                plot_ui.points(
                    Points::new("edits", PlotPoints::new(edits))
                        .color(palette::VERMILLION)
                        .radius(radius),
                );
            }
        },
    );
}

/// A sparsity image as large as the space left under its title allows (every
/// block of it on screen, none cut at the panel's foot), recorded as `name`'s
/// image in the figure records.
fn image_ui(ui: &mut egui::Ui, texture: Option<&egui::TextureHandle>, name: &str) {
    let Some(texture) = texture else {
        return;
    };
    // The panel's foot, not the column's reach: a column may run past a short panel.
    let bottom = ui.clip_rect().bottom().min(ui.max_rect().bottom());
    let room = bottom - ui.cursor().top() - ui.spacing().item_spacing.y;
    let side = room.min(ui.available_width()).max(24.0);
    let response = ui
        .add(egui::Image::new((texture.id(), egui::vec2(side, side))))
        .on_hover_text(name);
    record(
        ui.ctx(),
        FigureRecord {
            title: name.to_owned(),
            data: None,
            key: None,
            map: None,
            image: Some(response.rect),
        },
    );
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
            patterns.vertices = h.dims.len();
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

/// The pattern as an image with one cell per vertex block (a 200-pose graph is a
/// 200 x 200 block image): blue non-zeros, vermillion fill-in. `symmetric` mirrors
/// each block (`H`'s pattern lists both triangles already; `L` is lower). Cells are
/// [`MAX_IMAGE`]` / n` pixels wide (at least 1), and every non-zero block is drawn at
/// least 1/[`MIN_MARK_SHARE`] of the image wide, so that a single loop closure far
/// from the diagonal stays a visible square when the image is shown 120 points wide.
pub fn raster(pattern: &BlockPattern, symmetric: bool, background: Color32) -> ColorImage {
    let n = pattern.dims.len().max(1);
    let cell = (MAX_IMAGE / n).max(1);
    let side = (n * cell).min(MAX_IMAGE.max(n)).max(1);
    let mut image = ColorImage::filled([side, side], background);
    // The block of vertices (r, c) covers pixels from px(r) to px(r + 1) - 1.
    let px = |k: usize| (k * side / n).min(side);
    let mark = (side / MIN_MARK_SHARE).max(1);
    let span = |k: usize| {
        let (a, b) = (px(k), px(k + 1).max(px(k) + 1));
        if b - a >= mark {
            (a, b)
        } else {
            let centre = (a + b) / 2;
            let a = centre.saturating_sub(mark / 2).min(side - mark.min(side));
            (a, (a + mark).min(side))
        }
    };
    // Original non-zeros last, so that fill-in never hides one that shares a pixel.
    let mut order: Vec<usize> = (0..pattern.entries.len()).collect();
    order.sort_by_key(|&k| !pattern.fill_in.get(k).copied().unwrap_or(false));
    for k in order {
        let Some(&(r, c)) = pattern.entries.get(k) else {
            continue;
        };
        let fill = pattern.fill_in.get(k).copied().unwrap_or(false);
        let color = if fill {
            palette::VERMILLION
        } else {
            palette::BLUE
        };
        let (r0, r1) = span(r);
        let (c0, c1) = span(c);
        for y in r0..r1 {
            for x in c0..c1 {
                image.pixels[y * side + x] = color;
                if symmetric {
                    image.pixels[x * side + y] = color;
                }
            }
        }
    }
    image
}

/// A non-zero block is at least 1/`MIN_MARK_SHARE` of the sparsity image wide.
pub const MIN_MARK_SHARE: usize = 45;

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
    fn the_cost_line_starts_again_after_each_edit() {
        let history = [
            [0.0, 100.0],
            [1.0, 10.0],
            [1.0, 1000.0],
            [2.0, 1.0],
            [3.0, 0.0],
        ];
        let (segments, edits) = cost_segments(&history);
        let expected = [vec![[0.0, 2.0], [1.0, 1.0]], vec![[1.0, 3.0], [2.0, 0.0]]];
        assert_eq!(
            segments.len(),
            2,
            "zero cost has no logarithm: {segments:?}"
        );
        for (got, want) in segments.iter().zip(&expected) {
            assert_eq!(got.len(), want.len());
            for (g, w) in got.iter().zip(want) {
                assert!(g[0] == w[0] && (g[1] - w[1]).abs() < 1e-12, "{got:?}");
            }
        }
        assert_eq!(edits.len(), 1);
        assert!(edits[0][0] == 1.0 && (edits[0][1] - 3.0).abs() < 1e-12);
        assert_eq!(cost_segments(&[]), (Vec::new(), Vec::new()));
    }

    #[test]
    fn a_pattern_rasters_one_cell_per_vertex_block_and_marks_fill_in() {
        let pattern = BlockPattern {
            vertex_ids: vec![1, 2, 3],
            dims: vec![3, 3, 2],
            entries: vec![(0, 0), (1, 1), (2, 0), (2, 1), (2, 2)],
            fill_in: vec![false, false, false, true, false],
        };
        let image = raster(&pattern, false, Color32::WHITE);
        // Three vertices: three cells of 120 pixels.
        assert_eq!(image.size, [360, 360]);
        let count = |c: Color32| image.pixels.iter().filter(|p| **p == c).count();
        assert_eq!(count(palette::BLUE), 4 * 120 * 120);
        assert_eq!(count(palette::VERMILLION), 120 * 120);
        assert_eq!(image.pixels[(2 * 120 + 5) * 360 + 125], palette::VERMILLION);
        assert_eq!(image.pixels[125 * 360 + 2 * 120 + 5], Color32::WHITE);
    }

    #[test]
    fn a_single_loop_closure_of_a_200_pose_graph_is_a_visible_block() {
        // A chain of 200 poses and one loop closure from pose 0 to pose 150.
        let n = 200;
        let mut entries: Vec<(usize, usize)> = (0..n).map(|k| (k, k)).collect();
        entries.extend((1..n).flat_map(|k| [(k, k - 1), (k - 1, k)]));
        entries.extend([(150, 0), (0, 150)]);
        let pattern = BlockPattern {
            vertex_ids: (0..n as u64).collect(),
            dims: vec![3; n],
            fill_in: vec![false; entries.len()],
            entries,
        };
        let image = raster(&pattern, true, Color32::WHITE);
        assert_eq!(image.size, [200, 200], "one pixel per vertex block");
        let side = image.size[0];
        let mark = side / MIN_MARK_SHARE;
        assert_eq!(mark, 4);
        // The loop closure: a mark x mark square of blue around (row 150, column 0).
        let blue_near = |row: usize, col: usize| {
            let mut n = 0;
            for y in row.saturating_sub(4)..(row + 5).min(side) {
                for x in col.saturating_sub(4)..(col + 5).min(side) {
                    n += usize::from(image.pixels[y * side + x] == palette::BLUE);
                }
            }
            n
        };
        assert_eq!(blue_near(150, 0), mark * mark);
        assert_eq!(blue_near(0, 150), mark * mark, "and its mirror");
        // Nothing between the band and the loop closure.
        assert_eq!(image.pixels[100 * side + 20], Color32::WHITE);
    }
}
