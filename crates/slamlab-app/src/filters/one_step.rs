//! The one-step view: the prior (drag its mean and its covariance handles) and
//! its image under the chosen function, with the samples as a density image,
//! the EKF's, the UKF's and the particles' Gaussians as 95% ellipses, and the
//! sigma points before and after.

use crate::palette;
use crate::widgets::map_canvas::{self, CanvasColors, MapTransform, MapView};
use crate::widgets::plots::{KeyEntry, Mark, key_ui};
use egui::{Color32, ColorImage, Pos2, Stroke, TextureHandle, TextureOptions};
use nalgebra::Vector2;
use slamlab_core::filters::one_step::Gaussian2;
use slamlab_sim::filters::session::OneStep;

/// Cells per side of the density image.
const DENSITY_CELLS: usize = 160;

/// The samples binned into an image over fixed world bounds.
#[derive(Default)]
pub struct Density {
    /// `[x_min, y_min, x_max, y_max]` of the image.
    pub bounds: [f64; 4],
    texture: Option<TextureHandle>,
    /// Samples inside the bounds.
    pub inside: usize,
}

impl std::fmt::Debug for Density {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Density")
            .field("bounds", &self.bounds)
            .field("inside", &self.inside)
            .finish()
    }
}

/// Bounds around the samples: their mean ± 4 standard deviations, within the
/// samples' extent, never empty.
pub fn output_bounds(result: &OneStep) -> [f64; 4] {
    let m = &result.truth.moments;
    let (sx, sy) = (
        m.covariance[(0, 0)].max(0.0).sqrt(),
        m.covariance[(1, 1)].max(0.0).sqrt(),
    );
    let s = sx.max(sy).max(1e-6);
    let (mut x0, mut y0, mut x1, mut y1) = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    for p in &result.truth.points {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let clip = |lo: f64, hi: f64, c: f64| ((lo.max(c - 4.0 * s)), (hi.min(c + 4.0 * s)));
    let (x0, x1) = clip(x0, x1, m.mean[0]);
    let (y0, y1) = clip(y0, y1, m.mean[1]);
    let pad = 0.05 * (x1 - x0).max(y1 - y0).max(1e-6);
    [x0 - pad, y0 - pad, x1 + pad, y1 + pad]
}

/// Bounds around the prior: mean ± 3.5 standard deviations.
pub fn input_bounds(prior: &Gaussian2) -> [f64; 4] {
    let s = prior.covariance[(0, 0)]
        .max(prior.covariance[(1, 1)])
        .max(1e-12)
        .sqrt();
    let m = prior.mean;
    [
        m[0] - 3.5 * s,
        m[1] - 3.5 * s,
        m[0] + 3.5 * s,
        m[1] + 3.5 * s,
    ]
}

impl Density {
    /// Bins `points` over `bounds` into the texture (`color` at full density).
    pub fn update(
        &mut self,
        ctx: &egui::Context,
        points: &[Vector2<f64>],
        bounds: [f64; 4],
        color: Color32,
    ) {
        let n = DENSITY_CELLS;
        let mut counts = vec![0_u32; n * n];
        let [x0, y0, x1, y1] = bounds;
        let (wx, wy) = ((x1 - x0) / n as f64, (y1 - y0) / n as f64);
        let mut inside = 0;
        if wx > 0.0 && wy > 0.0 {
            for p in points {
                let i = ((p[0] - x0) / wx).floor();
                // Row 0 is the image's top: the largest y.
                let j = ((y1 - p[1]) / wy).floor();
                if (0.0..n as f64).contains(&i) && (0.0..n as f64).contains(&j) {
                    counts[j as usize * n + i as usize] += 1;
                    inside += 1;
                }
            }
        }
        let max = counts.iter().copied().max().unwrap_or(0).max(1) as f32;
        let pixels: Vec<Color32> = counts
            .iter()
            .map(|&c| {
                if c == 0 {
                    Color32::TRANSPARENT
                } else {
                    // Square root: the banana's thin tails stay visible.
                    let a = (0.12 + 0.88 * (c as f32 / max).sqrt()).min(1.0);
                    palette::faded(color, a)
                }
            })
            .collect();
        let image = ColorImage::new([n, n], pixels);
        match &mut self.texture {
            Some(t) => t.set(image, TextureOptions::NEAREST),
            None => {
                self.texture =
                    Some(ctx.load_texture("filters-density", image, TextureOptions::NEAREST))
            }
        }
        self.bounds = bounds;
        self.inside = inside;
    }

    /// Draws the image in world coordinates.
    pub fn draw(&self, painter: &egui::Painter, t: &MapTransform) {
        if let Some(texture) = &self.texture {
            let [x0, y0, x1, y1] = self.bounds;
            let rect = egui::Rect::from_two_pos(t.xy(x0, y1), t.xy(x1, y0));
            painter.image(
                texture.id(),
                rect,
                egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                Color32::WHITE,
            );
        }
    }
}

/// Draws a 95% ellipse.
pub fn ellipse(painter: &egui::Painter, t: &MapTransform, g: &Gaussian2, stroke: Stroke) {
    let points: Vec<Pos2> = g.ellipse_95().boundary(72).iter().map(|p| t.v(p)).collect();
    if points.iter().all(|p| map_canvas::finite(*p)) {
        painter.add(egui::Shape::closed_line(points, stroke));
    }
}

/// Draws a mean as a small cross.
pub fn cross(painter: &egui::Painter, at: Pos2, color: Color32) {
    let s = 5.0;
    let stroke = Stroke::new(2.0, color);
    painter.line_segment([at + egui::vec2(-s, -s), at + egui::vec2(s, s)], stroke);
    painter.line_segment([at + egui::vec2(-s, s), at + egui::vec2(s, -s)], stroke);
}

/// Draws a sigma point: a diamond.
pub fn diamond(painter: &egui::Painter, at: Pos2, color: Color32, filled: bool) {
    let r = 5.0;
    let points = vec![
        at + egui::vec2(0.0, -r),
        at + egui::vec2(r, 0.0),
        at + egui::vec2(0.0, r),
        at + egui::vec2(-r, 0.0),
    ];
    let shape = if filled {
        egui::Shape::convex_polygon(points, color, Stroke::new(1.0, Color32::BLACK))
    } else {
        egui::Shape::closed_line(points, Stroke::new(2.0, color))
    };
    painter.add(shape);
}

/// The canvas's axes named with their units on the canvas itself, as every map
/// does: the horizontal one at the bottom right (above the grid's values), the
/// vertical one at the top left (where the grid writes no value), each on a
/// patch of the background so that the density image does not hide it.
pub fn draw_axis_names(
    painter: &egui::Painter,
    t: &MapTransform,
    axes: [&str; 2],
    colors: &CanvasColors,
) {
    let font = egui::FontId::proportional(12.0);
    let place = [
        (
            t.rect.right_bottom() + egui::vec2(-6.0, -16.0),
            egui::Align2::RIGHT_BOTTOM,
        ),
        (
            t.rect.left_top() + egui::vec2(6.0, 4.0),
            egui::Align2::LEFT_TOP,
        ),
    ];
    for (name, (at, align)) in axes.iter().zip(place) {
        let galley = painter.layout_no_wrap((*name).to_owned(), font.clone(), colors.weak_text);
        let rect = align.anchor_size(at, galley.size());
        painter.rect_filled(
            rect.expand(2.0),
            2.0,
            palette::faded(colors.background, 0.85),
        );
        painter.galley(rect.min, galley, colors.weak_text);
    }
}

/// The canvas's title and its key, on lines above it (never over the data; the
/// axes are named on the canvas, [`draw_axis_names`]); `compact`: the title alone
/// on one line, the axes and the key on hover.
pub fn heading_ui(
    ui: &mut egui::Ui,
    title: &str,
    axes: [&str; 2],
    key: &[KeyEntry],
    compact: bool,
    view: &mut MapView,
) {
    let axes = format!("horizontal: {}; vertical: {}", axes[0], axes[1]);
    // The canvas zooms on scroll (and the output pans): a way back on the title's line.
    let reset = |ui: &mut egui::Ui, view: &mut MapView| {
        if ui
            .small_button("Reset view")
            .on_hover_text("Back to the view that fits the whole belief")
            .clicked()
        {
            view.refit();
        }
    };
    if compact {
        let names: Vec<&str> = key.iter().map(|k| k.name.as_str()).collect();
        ui.horizontal(|ui| {
            reset(ui, view);
            ui.add(egui::Label::new(egui::RichText::new(title).small().strong()).truncate())
                .on_hover_text(format!("{axes}\nKey: {}", names.join("; ")));
        });
        return;
    }
    ui.horizontal(|ui| {
        reset(ui, view);
        ui.add(egui::Label::new(egui::RichText::new(title).strong()).truncate())
            .on_hover_text(axes);
    });
    key_ui(ui, key);
}

/// What a drag on the input canvas does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grab {
    /// Moves the mean.
    Mean,
    /// Moves the first column of the covariance's Cholesky factor.
    Column1,
    /// Moves the second column's length.
    Column2,
}

/// The input canvas's drag: the handle held, and where the handles were drawn
/// in the last frame (mean, first and second column; screen points).
#[derive(Clone, Copy, Debug, Default)]
pub struct DragState {
    /// The handle being dragged.
    pub grab: Option<Grab>,
    /// The handles on screen.
    pub on_screen: Option<[Pos2; 3]>,
}

/// The handles: the mean and the tips of the Cholesky factor's columns
/// `μ + L e₁`, `μ + L e₂` (one standard deviation along each).
pub fn handles(prior: &Gaussian2) -> Option<[Vector2<f64>; 3]> {
    let l = prior.factor().ok()?;
    Some([
        prior.mean,
        prior.mean + l.column(0),
        prior.mean + l.column(1),
    ])
}

/// The prior with the grabbed handle at `to`; returns `(mean, std, rho)`.
/// Dragging a column to zero length (within `snap`, the world length of a few
/// screen points) makes the covariance singular: the lesson refuses it with a
/// note and keeps the last valid belief.
pub fn drag_prior(
    prior: &Gaussian2,
    grab: Grab,
    to: Vector2<f64>,
    snap: f64,
) -> ([f64; 2], [f64; 2], f64) {
    let m = prior.mean;
    let (l11, l21, l22) = match prior.factor() {
        Ok(l) => (l[(0, 0)], l[(1, 0)], l[(1, 1)]),
        Err(_) => (1.0, 0.0, 1.0),
    };
    let snapped = |v: f64| if v.abs() < snap { 0.0 } else { v };
    let (mean, l11, l21, l22) = match grab {
        Grab::Mean => (to, l11, l21, l22),
        Grab::Column1 if (to - m).norm() < snap => (m, 0.0, 0.0, l22),
        Grab::Column1 => (m, to[0] - m[0], to[1] - m[1], l22),
        Grab::Column2 => (m, l11, l21, snapped(to[1] - m[1])),
    };
    // Σ = L L^T with L = [[l11, 0], [l21, l22]].
    let s1 = l11.abs();
    let s2 = (l21 * l21 + l22 * l22).sqrt();
    let rho = if s1 > 0.0 && s2 > 0.0 {
        (l11 * l21 / (s1 * s2)).clamp(-1.0, 1.0)
    } else {
        0.0
    };
    ([mean[0], mean[1]], [s1, s2], rho)
}

/// The input canvas: prior, its handles, the sigma points before the function.
pub fn input_ui(
    ui: &mut egui::Ui,
    view: &mut MapView,
    prior: &Gaussian2,
    result: Option<&OneStep>,
    axes: [&str; 2],
    drag: &mut DragState,
    compact: bool,
) -> Option<([f64; 2], [f64; 2], f64)> {
    let colors = CanvasColors::of(ui);
    heading_ui(
        ui,
        "Prior belief: drag the mean (cross) and the handles (dots)",
        axes,
        &[
            KeyEntry::new("prior, 95% ellipse", colors.truth, Mark::Solid),
            KeyEntry::new("covariance handles", palette::VERMILLION, Mark::Dots),
            KeyEntry::new("sigma points", palette::ORANGE, Mark::Dots),
        ],
        compact,
        view,
    );
    let (response, t) = map_canvas::canvas_ui(ui, view, input_bounds(prior), 0.0, &mut None, false);
    let painter = ui.painter_at(t.rect);
    painter.rect_filled(t.rect, 0.0, colors.background);
    map_canvas::draw_grid(&painter, &t, &colors);
    ellipse(&painter, &t, prior, Stroke::new(2.0, colors.truth));
    draw_axis_names(&painter, &t, axes, &colors);
    let mut change = None;
    drag.on_screen = None;
    if let Some(h) = handles(prior) {
        drag.on_screen = Some([t.v(&h[0]), t.v(&h[1]), t.v(&h[2])]);
        cross(&painter, t.v(&h[0]), colors.truth);
        for tip in &h[1..] {
            painter.line_segment([t.v(&h[0]), t.v(tip)], Stroke::new(1.0, colors.truth));
            painter.circle_filled(t.v(tip), 6.0, palette::VERMILLION);
        }
        // The handle nearest where the button went down (not where the pointer is
        // when the drag is recognized, a few points later).
        if response.drag_started()
            && let Some(p) = ui
                .input(|i| i.pointer.press_origin())
                .or(response.interact_pointer_pos())
        {
            let nearest = [Grab::Mean, Grab::Column1, Grab::Column2]
                .into_iter()
                .zip(h.iter())
                .map(|(g, v)| (g, t.v(v).distance(p)))
                .fold((Grab::Mean, f32::INFINITY), |best, c| {
                    if c.1 < best.1 { c } else { best }
                });
            drag.grab = (nearest.1 < 24.0).then_some(nearest.0);
        }
    }
    if let Some(r) = result {
        for (i, p) in r.ukf.sigma_in.iter().enumerate() {
            diamond(&painter, t.v(p), palette::ORANGE, i == 0);
        }
    }
    if response.dragged()
        && let (Some(g), Some(p)) = (drag.grab, response.interact_pointer_pos())
    {
        let w = t.world_of(p);
        let snap = 3.0 / f64::from(t.scale);
        change = Some(drag_prior(prior, g, Vector2::new(w[0], w[1]), snap));
    }
    if response.drag_stopped() {
        drag.grab = None;
    }
    change
}

/// The output canvas: the samples' density, the three Gaussians, the sigma
/// points after the function, the particles.
pub fn output_ui(
    ui: &mut egui::Ui,
    view: &mut MapView,
    density: &Density,
    result: &OneStep,
    axes: [&str; 2],
    compact: bool,
) {
    let colors = CanvasColors::of(ui);
    heading_ui(
        ui,
        "After the function (drag to pan, scroll to zoom)",
        axes,
        &[
            KeyEntry::new(
                format!(
                    "{} samples and their 95% ellipse",
                    result.truth.points.len()
                ),
                colors.truth,
                Mark::Solid,
            ),
            KeyEntry::new("EKF", palette::BLUE, Mark::Solid),
            KeyEntry::new("UKF and sigma points", palette::ORANGE, Mark::Solid),
            KeyEntry::new(
                format!("{} particles", result.particles.points.len()),
                palette::PURPLE,
                Mark::Dots,
            ),
        ],
        compact,
        view,
    );
    let (_response, t) = map_canvas::canvas_ui(ui, view, density.bounds, 0.0, &mut None, true);
    let painter = ui.painter_at(t.rect);
    painter.rect_filled(t.rect, 0.0, colors.background);
    map_canvas::draw_grid(&painter, &t, &colors);
    density.draw(&painter, &t);
    for p in &result.particles.points {
        painter.circle_filled(t.v(p), 1.8, palette::faded(palette::PURPLE, 0.7));
    }
    ellipse(
        &painter,
        &t,
        &result.truth.moments,
        Stroke::new(2.0, colors.truth),
    );
    cross(&painter, t.v(&result.truth.moments.mean), colors.truth);
    ellipse(
        &painter,
        &t,
        &result.ekf.gaussian,
        Stroke::new(2.0, palette::BLUE),
    );
    cross(&painter, t.v(&result.ekf.gaussian.mean), palette::BLUE);
    ellipse(
        &painter,
        &t,
        &result.ukf.gaussian,
        Stroke::new(2.0, palette::ORANGE),
    );
    cross(&painter, t.v(&result.ukf.gaussian.mean), palette::ORANGE);
    ellipse(
        &painter,
        &t,
        &result.particles.moments,
        Stroke::new(2.0, palette::PURPLE),
    );
    for (i, p) in result.ukf.sigma_out.iter().enumerate() {
        diamond(&painter, t.v(p), palette::ORANGE, i == 0);
    }
    draw_axis_names(&painter, &t, axes, &colors);
}
