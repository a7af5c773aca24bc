//! The map canvas every lesson draws on: world coordinates in metres (x right, y
//! up, REP-103), pan by dragging, zoom by scrolling, pinching or the toolbar's
//! buttons, follow the robot, a metric grid with labels, axis names and a scale bar.
//!
//! A lesson allocates the canvas with [`canvas_ui`], which handles the input and
//! returns the [`MapTransform`] to draw with.

use crate::palette;
use egui::{Color32, Pos2, Rect, Sense, Stroke, pos2, vec2};
use nalgebra::Vector2;
use slamlab_core::{Pose2, math};

/// Smallest and largest zoom, pixels per metre.
pub const SCALE_RANGE: (f32, f32) = (0.05, 5000.0);

/// Where the map looks: its centre (metres) and zoom (pixels per metre).
#[derive(Clone, Debug, PartialEq)]
pub struct MapView {
    pub(crate) center: [f64; 2],
    pub(crate) scale: f32,
    pub(crate) fitted: bool,
    /// The map's size at the last fit; the fit follows size changes until the user
    /// pans or zooms.
    pub(crate) fitted_size: egui::Vec2,
    /// Has the user panned or zoomed since the last fit?
    pub(crate) adjusted: bool,
    /// A zoom factor on the first fit (the URL's `zoom=`), applied once.
    pub(crate) pending_zoom: Option<f32>,
    /// Fit again whenever what is drawn grows out of view (a map built from a
    /// log), until the user pans or zooms.
    pub(crate) follows_growth: bool,
}

impl Default for MapView {
    fn default() -> Self {
        Self {
            center: [0.0, 0.0],
            scale: 30.0,
            fitted: false,
            fitted_size: egui::Vec2::ZERO,
            adjusted: false,
            pending_zoom: None,
            follows_growth: false,
        }
    }
}

impl MapView {
    /// A view that fits again whenever what is drawn grows out of it (a map built
    /// as it goes), until the user pans or zooms.
    pub fn growing() -> Self {
        Self {
            follows_growth: true,
            ..Self::default()
        }
    }

    /// Does the view at `rect` show all of `bounds` (`[x_min, y_min, x_max,
    /// y_max]`, metres)? Bounds that are not finite count as shown.
    pub fn shows(&self, rect: Rect, bounds: [f64; 4]) -> bool {
        if !bounds.iter().all(|v| v.is_finite()) {
            return true;
        }
        let t = self.transform(rect);
        let corners = [t.xy(bounds[0], bounds[1]), t.xy(bounds[2], bounds[3])];
        corners.iter().all(|c| rect.expand(1.0).contains(*c))
    }

    /// Fits the world into the map on the next frame.
    pub fn refit(&mut self) {
        self.fitted = false;
    }

    /// Fits `bounds` (`[x_min, y_min, x_max, y_max]`, metres) into `rect`, beside
    /// the legend when there is room: smaller (down to 85%) and shifted right
    /// rather than under the legend.
    pub fn fit(&mut self, rect: Rect, bounds: [f64; 4], legend_space: f32) {
        let [x0, y0, x1, y1] = bounds;
        let (width, height) = if bounds.iter().all(|v| v.is_finite()) && x1 > x0 && y1 > y0 {
            ((x1 - x0).max(1.0) * 1.08, (y1 - y0).max(1.0) * 1.08)
        } else {
            (16.0, 16.0)
        };
        let centre = if bounds.iter().all(|v| v.is_finite()) {
            [0.5 * (x0 + x1), 0.5 * (y0 + y1)]
        } else {
            [0.0, 0.0]
        };
        let (w, h) = (width as f32, height as f32);
        let full = (rect.width() / w).min(rect.height() / h);
        let beside = ((rect.width() - legend_space) / w).min(rect.height() / h);
        let scale = if legend_space > 0.0 {
            beside.max(0.85 * full).min(full)
        } else {
            full
        };
        let scale = scale.clamp(SCALE_RANGE.0, SCALE_RANGE.1);
        let half_px = 0.5 * w * scale;
        let slack = (0.5 * rect.width() - half_px).max(0.0);
        let wanted = legend_space - (0.5 * rect.width() - half_px);
        let shift = wanted.clamp(0.0, slack);
        self.center = [centre[0] - f64::from(shift / scale), centre[1]];
        self.scale = scale;
        self.fitted = true;
        self.fitted_size = rect.size();
        self.adjusted = false;
    }

    /// Zooms by `factor` keeping the world point under `anchor` where it is.
    pub fn zoom_about(&mut self, rect: Rect, factor: f32, anchor: Pos2) {
        if !(factor.is_finite() && factor > 0.0) {
            return;
        }
        self.adjusted = true;
        let before = self.transform(rect);
        let world = before.world_of(anchor);
        self.scale = (self.scale * factor).clamp(SCALE_RANGE.0, SCALE_RANGE.1);
        let offset = anchor - rect.center();
        self.center = [
            world[0] - f64::from(offset.x / self.scale),
            world[1] + f64::from(offset.y / self.scale),
        ];
    }

    /// The world-to-screen transform for a canvas at `rect`.
    pub fn transform(&self, rect: Rect) -> MapTransform {
        MapTransform {
            rect,
            center: self.center,
            scale: self.scale,
        }
    }

    /// Opens `factor` times closer than the fitted view (about the map's centre, or
    /// the followed point); a factor that is not finite and positive is ignored.
    pub fn zoom_after_fit(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            self.pending_zoom = Some(factor);
            self.fitted = false;
        }
    }

    /// Looks closer: at least `scale` pixels per metre from now on (as if the
    /// user had zoomed), e.g. to show single cells.
    pub fn zoom_to_at_least(&mut self, scale: f32) {
        if scale.is_finite() && scale > self.scale {
            self.scale = scale.clamp(SCALE_RANGE.0, SCALE_RANGE.1);
            self.fitted = true;
            self.adjusted = true;
        }
    }

    /// Pixels per metre.
    pub fn scale(&self) -> f32 {
        self.scale
    }
}

/// World (metres, y up) to screen (points, y down).
#[derive(Clone, Copy, Debug)]
pub struct MapTransform {
    /// The canvas on screen.
    pub rect: Rect,
    /// The world point at the canvas centre.
    pub center: [f64; 2],
    /// Pixels per metre.
    pub scale: f32,
}

impl MapTransform {
    /// The screen point of world `(x, y)`.
    pub fn xy(&self, x: f64, y: f64) -> Pos2 {
        let c = self.rect.center();
        pos2(
            c.x + ((x - self.center[0]) as f32) * self.scale,
            c.y - ((y - self.center[1]) as f32) * self.scale,
        )
    }

    /// The screen point of a world vector.
    pub fn v(&self, v: &Vector2<f64>) -> Pos2 {
        self.xy(v[0], v[1])
    }

    /// The screen points of `path` for one line: every k-th pose and the
    /// last, about `max_points` in all (a long path stays cheap to draw),
    /// without the non-finite ones.
    pub fn path(&self, path: &[Pose2], max_points: usize) -> Vec<Pos2> {
        let stride = path.len() / max_points.max(1) + 1;
        path.iter()
            .step_by(stride)
            .chain(path.last())
            .map(|p| self.pose(p))
            .filter(|p| finite(*p))
            .collect()
    }

    /// The screen point of a pose's position.
    pub fn pose(&self, p: &Pose2) -> Pos2 {
        self.xy(p.x, p.y)
    }

    /// The world point under screen point `p`.
    pub fn world_of(&self, p: Pos2) -> [f64; 2] {
        let c = self.rect.center();
        [
            self.center[0] + f64::from((p.x - c.x) / self.scale),
            self.center[1] - f64::from((p.y - c.y) / self.scale),
        ]
    }

    /// Metres visible: `(x_min, x_max, y_min, y_max)`.
    pub fn visible(&self) -> (f64, f64, f64, f64) {
        let a = self.world_of(self.rect.left_bottom());
        let b = self.world_of(self.rect.right_top());
        (a[0], b[0], a[1], b[1])
    }
}

/// The direction on screen of a world angle (y flips).
pub fn screen_dir(angle: f64) -> egui::Vec2 {
    let (sin, cos) = math::sin_cos(angle);
    vec2(cos as f32, -(sin as f32))
}

/// Is the screen point finite (not from a NaN estimate)?
pub fn finite(p: Pos2) -> bool {
    p.x.is_finite() && p.y.is_finite()
}

/// How a pose estimate is drawn: its colour, whether its 95% position ellipse
/// shows, the radius of its ±2σ heading wedge (points), and a dot at its centre.
#[derive(Clone, Copy, Debug)]
pub struct EstimateStyle {
    /// The estimator's colour.
    pub color: Color32,
    /// Draw the 95% position ellipse.
    pub ellipse: bool,
    /// Radius of the heading wedge and arrow, points.
    pub wedge_radius: f32,
    /// A filled dot at the estimate.
    pub dot: bool,
}

/// A pose estimate with its uncertainty: the 95% ellipse of the position block
/// of `covariance` (x, y, θ), a wedge of ±2σ in heading, and an arrow.
pub fn draw_estimate(
    painter: &egui::Painter,
    t: &MapTransform,
    pose: &Pose2,
    covariance: &nalgebra::Matrix3<f64>,
    style: EstimateStyle,
) {
    use slamlab_core::geometry::{CHI2_2DOF_95, CovarianceEllipse};
    let centre = t.pose(pose);
    if !finite(centre) {
        return;
    }
    let color = style.color;
    if style.ellipse {
        let block = covariance.fixed_view::<2, 2>(0, 0).into_owned();
        let e =
            CovarianceEllipse::from_covariance(Vector2::new(pose.x, pose.y), &block, CHI2_2DOF_95);
        // Under a pixel the ellipse is hidden by the dot, and a stroke around a
        // point-sized polygon tessellates into spikes; beyond a million pixels the
        // screen coordinates lose their precision. Neither is drawn.
        let across = (e.semi_major * f64::from(t.scale)) as f32;
        let drawable = across.is_finite() && (1.0..1.0e6).contains(&across);
        let points: Vec<Pos2> = e
            .boundary(48)
            .iter()
            .map(|p| t.v(p))
            .filter(|p| finite(*p))
            .collect();
        if drawable && points.len() > 2 {
            painter.add(egui::Shape::closed_line(points, Stroke::new(2.0, color)));
        }
    }
    // Heading wedge: ± 2 sigma.
    let sigma = covariance[(2, 2)].max(0.0).sqrt();
    let spread = (2.0 * sigma).min(std::f64::consts::PI);
    let radius = style.wedge_radius;
    // A wedge narrower than half a pixel at its rim is a sliver whose fill
    // tessellates into a spike along the heading: the arrow shows the heading.
    if spread * f64::from(radius) >= 0.25 {
        let mut rim = vec![centre];
        for k in 0..=16 {
            let a = pose.theta - spread + 2.0 * spread * f64::from(k) / 16.0;
            rim.push(centre + screen_dir(a) * radius);
        }
        painter.add(egui::Shape::convex_polygon(
            rim,
            color.gamma_multiply(0.18),
            Stroke::NONE,
        ));
    }
    if style.dot {
        painter.circle_filled(centre, 4.0, color);
    }
    painter.arrow(
        centre,
        screen_dir(pose.theta) * radius,
        Stroke::new(2.0, color),
    );
}

/// The canvas's colours in the current theme.
#[derive(Clone, Copy, Debug)]
pub struct CanvasColors {
    /// The truth: black, or white on dark.
    pub truth: Color32,
    /// The canvas background.
    pub background: Color32,
    /// Labels.
    pub weak_text: Color32,
    /// Grid lines.
    pub grid: Color32,
}

impl CanvasColors {
    /// The colours for `ui`'s theme.
    pub fn of(ui: &egui::Ui) -> Self {
        let dark = ui.visuals().dark_mode;
        Self {
            truth: palette::truth_color(dark),
            background: ui.visuals().extreme_bg_color,
            weak_text: ui.visuals().weak_text_color(),
            grid: if dark {
                Color32::from_gray(55)
            } else {
                Color32::from_gray(218)
            },
        }
    }
}

/// Allocates the canvas in the space left in `ui`, fits `bounds` on the first
/// frame (and while the user has not panned or zoomed), and applies dragging
/// (when `pan` is on; a lesson may use drags itself), scrolling, pinching and the
/// toolbar's zoom buttons. While `follow` holds a point the view centres on it;
/// panning turns following off.
pub fn canvas_ui(
    ui: &mut egui::Ui,
    view: &mut MapView,
    bounds: [f64; 4],
    legend_space: f32,
    follow: &mut Option<[f64; 2]>,
    pan: bool,
) -> (egui::Response, MapTransform) {
    let size = ui.available_size().max(vec2(120.0, 120.0));
    let (rect, response) = ui.allocate_exact_size(size, Sense::click_and_drag());
    response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, "Map"));
    crate::widgets::plots::record(
        ui.ctx(),
        crate::widgets::plots::FigureRecord {
            title: "map".to_owned(),
            data: None,
            key: None,
            map: Some(rect),
            image: None,
        },
    );
    let resized = (rect.size() - view.fitted_size).length() > 1.0;
    let outgrown =
        view.follows_growth && !view.adjusted && follow.is_none() && !view.shows(rect, bounds);
    if !view.fitted || (resized && !view.adjusted) || outgrown {
        view.fit(rect, bounds, legend_space);
    }
    if let Some(factor) = view.pending_zoom.take() {
        view.zoom_about(rect, factor, rect.center());
    }
    let request: Option<f32> = ui.data_mut(|d| d.remove_temp(zoom_request_id()));
    if let Some(factor) = request {
        view.zoom_about(rect, factor, rect.center());
    }
    // Pan by dragging, zoom by scrolling or pinching around the pointer.
    if pan && response.dragged() {
        let d = response.drag_delta();
        view.center[0] -= f64::from(d.x / view.scale);
        view.center[1] += f64::from(d.y / view.scale);
        view.adjusted = true;
        *follow = None;
    }
    if response.hovered() {
        let (scroll, zoom) = ui.input(|i| (i.smooth_scroll_delta.y, i.zoom_delta()));
        let factor = math::exp(f64::from(scroll) * 0.0025) as f32 * zoom;
        if (factor - 1.0).abs() > 1e-4 {
            let anchor = response.hover_pos().unwrap_or(rect.center());
            view.zoom_about(rect, factor, anchor);
        }
    }
    if let Some([x, y]) = *follow
        && x.is_finite()
        && y.is_finite()
    {
        view.center = [x, y];
    }
    let transform = view.transform(rect);
    record_placement(
        ui.ctx(),
        MapPlacement {
            layer: ui.layer_id(),
            rect,
            transform,
        },
    );
    (response, transform)
}

/// The zoom buttons of a map toolbar ("−", "+", "Fit"); they act on the canvas
/// drawn after the toolbar. Returns true when "Fit" was pressed.
pub fn zoom_buttons_ui(ui: &mut egui::Ui, view: &mut MapView, fit_label: &str) -> bool {
    let id = zoom_request_id();
    if ui
        .button("−")
        .on_hover_text("Zoom out (or scroll / pinch on the map)")
        .clicked()
    {
        ui.data_mut(|d| d.insert_temp(id, 1.0_f32 / 1.25));
    }
    if ui
        .button("+")
        .on_hover_text("Zoom in (or scroll / pinch on the map)")
        .clicked()
    {
        ui.data_mut(|d| d.insert_temp(id, 1.25_f32));
    }
    let fit = ui
        .button(fit_label)
        .on_hover_text("Show the whole world")
        .clicked();
    if fit {
        view.refit();
    }
    fit
}

fn zoom_request_id() -> egui::Id {
    egui::Id::unique("slamlab_map_zoom_request")
}

/// A round grid step of at least `min_step` metres: 1, 2 or 5 times a power of ten.
pub fn nice_step(min_step: f64) -> f64 {
    if !(min_step.is_finite() && min_step > 0.0) {
        return 1.0;
    }
    let power = math::powf(10.0, math::log10(min_step).floor());
    for m in [1.0, 2.0, 5.0, 10.0] {
        if m * power >= min_step {
            return m * power;
        }
    }
    10.0 * power
}

/// A grid label: as many decimals as the step needs.
pub fn format_metres(value: f64, step: f64) -> String {
    let decimals = (-math::log10(step).floor()).max(0.0) as usize;
    let value = if value.abs() < step * 1e-6 {
        0.0
    } else {
        value
    };
    format!("{value:.decimals$}")
}

/// The metric grid with its labels along the bottom and left edges.
pub fn draw_grid(painter: &egui::Painter, t: &MapTransform, colors: &CanvasColors) {
    let step = nice_step(f64::from(70.0 / t.scale));
    let (x0, x1, y0, y1) = t.visible();
    let stroke = Stroke::new(1.0, colors.grid);
    let font = egui::FontId::proportional(10.5);
    let mut x = (x0 / step).ceil() * step;
    let mut count = 0;
    while x <= x1 && count < 400 {
        let p = t.xy(x, 0.0);
        painter.vline(p.x, t.rect.y_range(), stroke);
        painter.text(
            pos2(p.x + 2.0, t.rect.bottom() - 2.0),
            egui::Align2::LEFT_BOTTOM,
            format_metres(x, step),
            font.clone(),
            colors.weak_text,
        );
        x += step;
        count += 1;
    }
    let mut y = (y0 / step).ceil() * step;
    count = 0;
    while y <= y1 && count < 400 {
        let p = t.xy(0.0, y);
        painter.hline(t.rect.x_range(), p.y, stroke);
        // The top left corner holds the axis name "y (m)".
        if p.y < t.rect.top() + 34.0 {
            y += step;
            count += 1;
            continue;
        }
        painter.text(
            pos2(t.rect.left() + 2.0, p.y - 1.0),
            egui::Align2::LEFT_BOTTOM,
            format_metres(y, step),
            font.clone(),
            colors.weak_text,
        );
        y += step;
        count += 1;
    }
}

/// Axis names and a scale bar (bottom left).
pub fn draw_scale_and_axes(painter: &egui::Painter, t: &MapTransform, colors: &CanvasColors) {
    let step = nice_step(f64::from(70.0 / t.scale));
    let font = egui::FontId::proportional(12.0);
    painter.text(
        t.rect.right_bottom() + vec2(-6.0, -16.0),
        egui::Align2::RIGHT_BOTTOM,
        "x (m)",
        font.clone(),
        colors.weak_text,
    );
    painter.text(
        t.rect.left_top() + vec2(6.0, 4.0),
        egui::Align2::LEFT_TOP,
        "y (m)",
        font.clone(),
        colors.weak_text,
    );
    let length = (step as f32) * t.scale;
    let start = t.rect.left_bottom() + vec2(40.0, -24.0);
    let end = start + vec2(length, 0.0);
    let stroke = Stroke::new(2.0, colors.truth);
    painter.line_segment([start, end], stroke);
    painter.line_segment([start - vec2(0.0, 4.0), start + vec2(0.0, 4.0)], stroke);
    painter.line_segment([end - vec2(0.0, 4.0), end + vec2(0.0, 4.0)], stroke);
    painter.text(
        pos2((start.x + end.x) / 2.0, start.y - 4.0),
        egui::Align2::CENTER_BOTTOM,
        format!("{} m", format_metres(step, step)),
        font,
        colors.truth,
    );
}

/// Where the lesson's map was drawn this frame, for the overlay: its layer, its
/// rectangle and its transform.
#[derive(Clone, Copy, Debug)]
pub struct MapPlacement {
    /// The layer the map was painted on.
    pub layer: egui::LayerId,
    /// The map's rectangle.
    pub rect: egui::Rect,
    /// World to screen.
    pub transform: MapTransform,
}

fn placement_id() -> egui::Id {
    egui::Id::unique("slamlab_map_placement")
}

/// Records where the map is drawn (the map canvas calls it every frame).
pub fn record_placement(ctx: &egui::Context, placement: MapPlacement) {
    ctx.data_mut(|d| d.insert_temp(placement_id(), placement));
}

/// Forgets the map's placement (before a frame, so that a lesson without a map
/// gets no overlay).
pub fn clear_placement(ctx: &egui::Context) {
    ctx.data_mut(|d| d.remove::<MapPlacement>(placement_id()));
}

/// The map's placement this frame, if a map was drawn.
pub fn placement(ctx: &egui::Context) -> Option<MapPlacement> {
    ctx.data(|d| d.get_temp(placement_id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn screen_and_world_agree_and_zoom_keeps_the_anchor() {
        let rect = Rect::from_min_size(pos2(10.0, 20.0), vec2(400.0, 300.0));
        let mut view = MapView::default();
        view.fit(rect, [0.0, 0.0, 10.0, 5.0], 0.0);
        let t = view.transform(rect);
        let p = t.xy(2.5, 4.0);
        let back = t.world_of(p);
        assert!((back[0] - 2.5).abs() < 1e-4 && (back[1] - 4.0).abs() < 1e-4);
        // The whole world is inside the canvas, centred.
        assert!(rect.contains(t.xy(0.0, 0.0)) && rect.contains(t.xy(10.0, 5.0)));
        assert!((t.xy(5.0, 2.5) - rect.center()).length() < 1e-3);
        let anchor = pos2(100.0, 80.0);
        let before = t.world_of(anchor);
        view.zoom_about(rect, 2.0, anchor);
        let after = view.transform(rect).world_of(anchor);
        assert!((before[0] - after[0]).abs() < 1e-4 && (before[1] - after[1]).abs() < 1e-4);
        // Bad bounds fall back to a 16 m square around the origin.
        view.fit(rect, [f64::NAN, 0.0, 1.0, 1.0], 0.0);
        assert_eq!(view.center, [0.0, 0.0]);
    }

    #[test]
    fn nice_steps() {
        assert!((nice_step(0.7) - 1.0).abs() < 1e-12);
        assert!((nice_step(1.2) - 2.0).abs() < 1e-12);
        assert!((nice_step(3.0) - 5.0).abs() < 1e-12);
        assert!((nice_step(7.0) - 10.0).abs() < 1e-12);
        assert!((nice_step(0.03) - 0.05).abs() < 1e-12);
        assert!((nice_step(f64::NAN) - 1.0).abs() < 1e-12);
        assert_eq!(format_metres(-4.0, 2.0), "-4");
        assert_eq!(format_metres(0.5, 0.5), "0.5");
    }

    #[test]
    fn transform_round_trips_and_zoom_keeps_the_anchor() {
        let rect = Rect::from_min_size(pos2(10.0, 20.0), vec2(400.0, 300.0));
        let mut view = MapView::default();
        view.fit(rect, [-8.0, -8.0, 8.0, 8.0], 0.0);
        let t = view.transform(rect);
        let p = t.xy(3.0, -2.0);
        let w = t.world_of(p);
        assert!((w[0] - 3.0).abs() < 1e-4 && (w[1] + 2.0).abs() < 1e-4);
        assert!(t.xy(0.0, 1.0).y < t.xy(0.0, 0.0).y, "y points up");
        let anchor = pos2(100.0, 80.0);
        let before = t.world_of(anchor);
        view.zoom_about(rect, 2.0, anchor);
        let after = view.transform(rect).world_of(anchor);
        assert!((before[0] - after[0]).abs() < 1e-3 && (before[1] - after[1]).abs() < 1e-3);
        view.zoom_about(rect, f32::NAN, anchor);
        assert!(view.scale.is_finite());
    }
}
