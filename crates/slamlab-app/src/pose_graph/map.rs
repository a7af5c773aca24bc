//! The graph drawn on the shared map canvas: odometry edges and vertices in blue,
//! loop closures in vermillion (the wrong ones dashed and thicker), landmark edges
//! and landmarks in green, the true path in black (white on dark), 95% ellipses
//! from the marginals once converged. The kernel comparison draws both results
//! so that neither hides the other: without a kernel a broad faded orange band,
//! with the robust kernel a reddish-purple line over it (where they agree the line
//! runs inside the band), each with its error in the key. The key is a line above
//! the map, never over the graph.
//! A vertex dragged with the mouse moves; releasing it re-optimizes.

use super::PoseGraphView;
use crate::palette;
use crate::widgets::map_canvas::{
    self, CanvasColors, MapTransform, MapView, draw_grid, draw_scale_and_axes, finite,
};
use crate::widgets::plots::{KeyEntry, Mark, key_ui};
use egui::{Color32, Pos2, Stroke, vec2};
use slamlab_core::geometry::CHI2_2DOF_95;
use slamlab_core::graph::{EdgeKind, VertexState};
use slamlab_core::{CovarianceEllipse, math};
use slamlab_sim::pose_graph::session::{EdgeRole, KernelRun, PoseGraphSession};

/// Odometry edges and pose vertices.
pub const VERTEX: Color32 = palette::BLUE;
/// Loop closures (LESSONS.md: loop closures in vermillion).
pub const LOOP_CLOSURE: Color32 = palette::VERMILLION;
/// Landmark edges and landmarks.
pub const LANDMARK: Color32 = palette::GREEN;
/// The optimized result without a kernel, in the comparison (a broad band).
pub const WITHOUT_KERNEL: Color32 = palette::ORANGE;
/// The optimized result with the robust kernel, in the comparison (a line).
pub const WITH_KERNEL: Color32 = palette::PURPLE;
/// Width of the band of the result without a kernel, points.
pub const WITHOUT_KERNEL_WIDTH: f32 = 7.0;
/// Width of the line of the result with the kernel, points.
pub const WITH_KERNEL_WIDTH: f32 = 2.5;
/// Marginal covariance ellipses.
pub const ELLIPSE: Color32 = palette::SKY_BLUE;

/// What the map asks the lesson to do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MapRequest {
    /// Move vertex `index` to `(x, y)`.
    Move(usize, f64, f64),
    /// The drag of vertex `index` ended.
    Drop(usize),
}

/// Grab radius around a vertex, points.
const GRAB_RADIUS: f32 = 9.0;

fn bounds(session: &PoseGraphSession) -> [f64; 4] {
    let mut b = [f64::MAX, f64::MAX, f64::MIN, f64::MIN];
    for v in session.graph().vertices() {
        let p = v.state.position();
        b = [
            b[0].min(p[0]),
            b[1].min(p[1]),
            b[2].max(p[0]),
            b[3].max(p[1]),
        ];
    }
    b
}

fn nearest_vertex(session: &PoseGraphSession, t: &MapTransform, at: Pos2) -> Option<usize> {
    let mut best: Option<(usize, f32)> = None;
    for (i, v) in session.graph().vertices().iter().enumerate() {
        let d = t.v(&v.state.position()).distance(at);
        if d <= GRAB_RADIUS && best.is_none_or(|(_, b)| d < b) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

/// The map, its toolbar and the drag of a vertex.
#[allow(clippy::too_many_arguments)]
pub fn map_ui(
    ui: &mut egui::Ui,
    session: &PoseGraphSession,
    canvas: &mut MapView,
    view: &mut PoseGraphView,
    drag: &mut Option<usize>,
    last_transform: &mut Option<MapTransform>,
    marginals: Option<&[(usize, nalgebra::Matrix2<f64>)]>,
    comparison: Option<&[KernelRun; 2]>,
) -> Option<MapRequest> {
    ui.horizontal_wrapped(|ui| {
        ui.label("Map:");
        map_canvas::zoom_buttons_ui(ui, canvas, "Fit graph");
        ui.separator();
        ui.checkbox(&mut view.legend, "Legend");
        if session.truth().is_some() {
            ui.checkbox(&mut view.truth, "Truth");
        }
        ui.checkbox(&mut view.ellipses, "Ellipses").on_hover_text(
            "95% ellipses of the marginal position covariances, once the solver has converged",
        );
        ui.checkbox(&mut view.reoptimize_after_drag, "Re-optimize after a drag")
            .on_hover_text(
                "Drag a vertex to perturb the graph; on release the solver runs to convergence",
            );
    });
    // A press on a vertex starts a drag (the canvas does not pan then); not a press
    // on a menu, window or tooltip above the map.
    let (pressed, origin, down, pointer) = ui.input(|i| {
        (
            i.pointer.primary_pressed(),
            i.pointer.press_origin(),
            i.pointer.primary_down(),
            i.pointer.interact_pos(),
        )
    });
    if drag.is_none()
        && pressed
        && let (Some(t), Some(origin)) = (last_transform.as_ref(), origin)
        && t.rect.contains(origin)
        && ui.ctx().layer_id_at(origin) == Some(ui.layer_id())
    {
        *drag = nearest_vertex(session, t, origin);
    }
    if view.legend {
        // The key on a line above the map, never over the graph.
        let colors = CanvasColors::of(ui);
        key_ui(ui, &legend_entries(session, &colors, comparison, view));
    }
    let mut follow = None;
    let (response, t) = map_canvas::canvas_ui(
        ui,
        canvas,
        bounds(session),
        0.0,
        &mut follow,
        drag.is_none(),
    );
    *last_transform = Some(t);
    let colors = CanvasColors::of(ui);
    let painter = ui.painter_at(t.rect);
    painter.rect_filled(t.rect, 4.0, colors.background);
    draw_grid(&painter, &t, &colors);
    if view.truth
        && let Some(truth) = session.truth()
    {
        let points: Vec<Pos2> = truth
            .iter()
            .map(|p| t.pose(p))
            .filter(|p| finite(*p))
            .collect();
        painter.add(egui::Shape::line(points, Stroke::new(1.0, colors.truth)));
    }
    if let Some([plain, _]) = comparison {
        draw_positions(
            &painter,
            &t,
            session,
            &plain.positions,
            Stroke::new(WITHOUT_KERNEL_WIDTH, palette::faded(WITHOUT_KERNEL, 0.55)),
        );
    }
    draw_graph(&painter, &t, session, &colors);
    if let Some([_, robust]) = comparison {
        draw_positions(
            &painter,
            &t,
            session,
            &robust.positions,
            Stroke::new(WITH_KERNEL_WIDTH, WITH_KERNEL),
        );
    }
    if view.ellipses
        && let Some(marginals) = marginals
    {
        let vertices = session.graph().vertices();
        for (i, cov) in marginals {
            if let Some(v) = vertices.get(*i) {
                let e = CovarianceEllipse::from_covariance(v.state.position(), cov, CHI2_2DOF_95);
                let mut points: Vec<Pos2> = e.boundary(28).iter().map(|p| t.v(p)).collect();
                if points.iter().all(|p| finite(*p)) {
                    points.push(points[0]);
                    painter.add(egui::Shape::line(points, Stroke::new(1.2, ELLIPSE)));
                }
            }
        }
    }
    draw_scale_and_axes(&painter, &t, &colors);

    let mut request = None;
    if let Some(i) = *drag {
        if down {
            if let Some(p) = pointer {
                let [x, y] = t.world_of(p);
                let current = session
                    .graph()
                    .vertices()
                    .get(i)
                    .map(|v| v.state.position());
                if current.is_some_and(|c| math::hypot(c[0] - x, c[1] - y) > 1e-9) {
                    request = Some(MapRequest::Move(i, x, y));
                }
                painter.circle_stroke(t.xy(x, y), 8.0, Stroke::new(2.0, palette::VERMILLION));
            }
        } else {
            *drag = None;
            request = Some(MapRequest::Drop(i));
        }
    } else if let Some(pointer) = response.hover_pos() {
        let [x, y] = t.world_of(pointer);
        let near = nearest_vertex(session, &t, pointer);
        response.on_hover_ui_at_pointer(|ui| match near {
            Some(i) => {
                let v = &session.graph().vertices()[i];
                let what = match v.state {
                    VertexState::Pose(_) => "pose",
                    VertexState::Point(_) => "landmark",
                };
                ui.label(format!(
                    "{what} {}{}: drag it to perturb the graph",
                    v.id,
                    if v.fixed {
                        " (fixed: holds the gauge)"
                    } else {
                        ""
                    }
                ));
            }
            None => {
                ui.label(format!("({x:.2}, {y:.2}) m"));
            }
        });
    }
    request
}

fn draw_graph(
    painter: &egui::Painter,
    t: &MapTransform,
    session: &PoseGraphSession,
    colors: &CanvasColors,
) {
    let vertices = session.graph().vertices();
    let many = vertices.len() > 1500;
    let pos = |i: usize| t.v(&vertices[i].state.position());
    let width = if many { 1.0 } else { 1.5 };
    // Odometry and landmark edges first, loop closures over them.
    for pass in 0..2 {
        for (edge, role) in session.graph().edges().iter().zip(session.roles()) {
            let (a, b) = edge.vertices();
            let Some(b) = b else { continue };
            let (pa, pb) = (pos(a), pos(b));
            if !(finite(pa) && finite(pb)) {
                continue;
            }
            match (pass, role) {
                (0, EdgeRole::Odometry) => {
                    painter.line_segment([pa, pb], Stroke::new(width, VERTEX));
                }
                (0, EdgeRole::Landmark) => {
                    painter.line_segment([pa, pb], Stroke::new(0.8, palette::faded(LANDMARK, 0.7)));
                }
                (1, EdgeRole::LoopClosure) => {
                    painter.line_segment([pa, pb], Stroke::new(width, LOOP_CLOSURE));
                }
                (1, EdgeRole::WrongLoopClosure) => {
                    painter.extend(egui::Shape::dashed_line(
                        &[pa, pb],
                        Stroke::new(3.0, LOOP_CLOSURE),
                        8.0,
                        5.0,
                    ));
                }
                _ => {}
            }
        }
    }
    let radius = if many { 1.3 } else { 2.6 };
    for (i, v) in vertices.iter().enumerate() {
        let p = pos(i);
        if !finite(p) {
            continue;
        }
        match v.state {
            _ if v.fixed => {
                painter.rect_filled(
                    egui::Rect::from_center_size(p, vec2(8.0, 8.0)),
                    0.0,
                    colors.truth,
                );
            }
            VertexState::Pose(_) => {
                painter.circle_filled(p, radius, VERTEX);
            }
            VertexState::Point(_) => {
                painter.rect_filled(
                    egui::Rect::from_center_size(p, vec2(6.0, 6.0)),
                    0.0,
                    LANDMARK,
                );
            }
        }
    }
    // Priors: a ring around their vertex.
    for edge in session.graph().edges() {
        if let EdgeKind::PosePrior { pose: i, .. } | EdgeKind::PointPrior { point: i, .. } = *edge {
            painter.circle_stroke(pos(i), 6.0, Stroke::new(1.5, colors.truth));
        }
    }
}

fn draw_positions(
    painter: &egui::Painter,
    t: &MapTransform,
    session: &PoseGraphSession,
    positions: &[[f64; 2]],
    stroke: Stroke,
) {
    let poses: Vec<Pos2> = positions
        .iter()
        .zip(session.graph().vertices())
        .filter(|(_, v)| matches!(v.state, VertexState::Pose(_)))
        .map(|(p, _)| t.xy(p[0], p[1]))
        .filter(|p| finite(*p))
        .collect();
    painter.add(egui::Shape::line(poses, stroke));
}

/// The map's key, one entry per kind of thing drawn (with counts), and each
/// result of a kernel comparison with its error.
fn legend_entries(
    session: &PoseGraphSession,
    colors: &CanvasColors,
    comparison: Option<&[KernelRun; 2]>,
    view: &PoseGraphView,
) -> Vec<KeyEntry> {
    let count = |role: EdgeRole| session.roles().iter().filter(|r| **r == role).count();
    let mut rows = vec![
        KeyEntry::new(
            format!(
                "poses ({}) and odometry ({})",
                session.graph().pose_count(),
                count(EdgeRole::Odometry)
            ),
            VERTEX,
            Mark::Solid,
        ),
        KeyEntry::new(
            format!("loop closures ({})", count(EdgeRole::LoopClosure)),
            LOOP_CLOSURE,
            Mark::Solid,
        ),
    ];
    if count(EdgeRole::WrongLoopClosure) > 0 {
        rows.push(KeyEntry::new(
            format!(
                "wrong loop closures ({})",
                count(EdgeRole::WrongLoopClosure)
            ),
            LOOP_CLOSURE,
            Mark::Dashed,
        ));
    }
    if session.graph().point_count() > 0 {
        rows.push(KeyEntry::new(
            format!(
                "landmarks ({}) and their edges ({})",
                session.graph().point_count(),
                count(EdgeRole::Landmark)
            ),
            LANDMARK,
            Mark::Solid,
        ));
    }
    rows.push(KeyEntry::new(
        "fixed vertex (square)",
        colors.truth,
        Mark::Dots,
    ));
    if view.truth && session.truth().is_some() {
        rows.push(KeyEntry::new("true path", colors.truth, Mark::Solid));
    }
    if view.ellipses && session.is_converged() {
        let stride = session
            .graph()
            .vertices()
            .len()
            .div_ceil(super::MAX_ELLIPSES)
            .max(1);
        rows.push(KeyEntry::new(
            if stride > 1 {
                format!("95% marginal ellipses (one vertex in {stride})")
            } else {
                "95% marginal ellipses".to_owned()
            },
            ELLIPSE,
            Mark::Solid,
        ));
    }
    if let Some(runs) = comparison {
        for (run, color) in [
            (&runs[0], palette::faded(WITHOUT_KERNEL, 0.55)),
            (&runs[1], WITH_KERNEL),
        ] {
            rows.push(KeyEntry::new(comparison_label(run), color, Mark::Solid));
        }
    }
    rows
}

/// The legend line of one result of the kernel comparison: its kernel, its
/// position error against the truth (or its cost without one) and its iterations.
pub fn comparison_label(run: &KernelRun) -> String {
    let what = if run.kernel == "none" {
        "optimized with no kernel".to_owned()
    } else {
        format!("optimized with {}", run.kernel)
    };
    match (&run.error, run.rmse) {
        (Some(_), _) => format!("{what}: failed (see the explanation)"),
        (None, Some(rmse)) => format!("{what}: RMSE {rmse:.3} m, {} iterations", run.iterations),
        (None, None) => format!(
            "{what}: cost {:.3e}, {} iterations",
            run.cost, run.iterations
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_legend_names_each_result_of_the_comparison_with_its_error() {
        let mut run = KernelRun {
            kernel: "none",
            iterations: 7,
            cost: 12.5,
            rmse: Some(0.4851),
            positions: Vec::new(),
            error: None,
        };
        assert_eq!(
            comparison_label(&run),
            "optimized with no kernel: RMSE 0.485 m, 7 iterations"
        );
        run.kernel = "huber";
        run.rmse = Some(0.15249);
        assert_eq!(
            comparison_label(&run),
            "optimized with huber: RMSE 0.152 m, 7 iterations"
        );
        run.rmse = None;
        assert_eq!(
            comparison_label(&run),
            "optimized with huber: cost 1.250e1, 7 iterations"
        );
        run.error = Some("indefinite".to_owned());
        assert!(comparison_label(&run).ends_with("failed (see the explanation)"));
    }
}
