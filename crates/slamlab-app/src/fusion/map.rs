//! The map: the true path, the raw odometry path (grey, dashed), the SLAM poses
//! as dots, and each mode's fused path with its current pose, 95% position
//! ellipse and heading wedge.

use super::{FusionView, mode_color};
use crate::palette;
use crate::widgets::map_canvas::{
    self, CanvasColors, EstimateStyle, MapTransform, MapView, draw_estimate, draw_grid,
    draw_scale_and_axes, finite, screen_dir,
};
use crate::widgets::plots::{KeyEntry, Mark, key_ui};
use egui::{Color32, Shape, Stroke, pos2};
use slamlab_core::Pose2;
use slamlab_sim::fusion::session::FusionSim;

/// Longest polyline drawn, in points.
const MAX_POINTS: usize = 4000;

/// The map toolbar and the map.
pub fn map_ui(ui: &mut egui::Ui, sim: &FusionSim, canvas: &mut MapView, view: &mut FusionView) {
    ui.horizontal_wrapped(|ui| {
        ui.label("Map:");
        map_canvas::zoom_buttons_ui(ui, canvas, "Fit room");
        ui.separator();
        ui.checkbox(&mut view.legend, "Legend");
        ui.checkbox(&mut view.odometry_path, "Raw odometry")
            .on_hover_text("Wheel odometry integrated alone (dead reckoning), grey and dashed");
        ui.checkbox(&mut view.slam_poses, "SLAM poses")
            .on_hover_text("Every SLAM pose received so far, as a dot");
        ui.checkbox(&mut view.ellipses, "95% ellipses");
    });
    let room = sim.setup().scenario.drive.room;
    let bounds = [
        -0.5 * room[0] - 0.3,
        -0.5 * room[1] - 0.3,
        0.5 * room[0] + 0.3,
        0.5 * room[1] + 0.3,
    ];
    if view.legend {
        // The key on a line above the map, never over the room.
        key_ui(ui, &legend_entries(sim, &CanvasColors::of(ui)));
    }
    let mut follow = None;
    let (_response, t) = map_canvas::canvas_ui(ui, canvas, bounds, 0.0, &mut follow, true);
    let colors = CanvasColors::of(ui);
    let painter = ui.painter_at(t.rect);
    painter.rect_filled(t.rect, 4.0, colors.background);
    draw_grid(&painter, &t, &colors);
    let now = sim.now();
    let log = sim.log();
    // The room's walls (the drive keeps inside 80% of it).
    let corners = [
        t.xy(-0.5 * room[0], -0.5 * room[1]),
        t.xy(0.5 * room[0], -0.5 * room[1]),
        t.xy(0.5 * room[0], 0.5 * room[1]),
        t.xy(-0.5 * room[0], 0.5 * room[1]),
    ];
    painter.add(Shape::closed_line(
        corners.to_vec(),
        Stroke::new(1.0, colors.weak_text),
    ));
    // The truth up to now.
    let truth: Vec<Pose2> = log
        .truth
        .iter()
        .take_while(|s| s.t <= now)
        .map(|s| s.pose)
        .collect();
    polyline(&painter, &t, &truth, Stroke::new(2.0, colors.truth), false);
    if view.odometry_path {
        let odometry: Vec<Pose2> = log
            .odometry_path
            .iter()
            .take_while(|(s, _)| *s <= now)
            .map(|(_, p)| *p)
            .collect();
        polyline(
            &painter,
            &t,
            &odometry,
            Stroke::new(1.6, palette::DEAD_RECKONING),
            true,
        );
    }
    if view.slam_poses {
        let latency = sim.live().slam.latency;
        for (stamp, pose) in &log.slam_poses {
            if stamp + latency > now {
                break;
            }
            let at = t.pose(pose);
            if finite(at) {
                painter.circle_filled(at, 3.0, palette::VERMILLION);
            }
        }
    }
    for run in sim.runs() {
        let color = mode_color(run.mode());
        let mut path: Vec<Pose2> = run.samples().iter().map(|s| s.estimate).collect();
        let pose = run.filter().pose();
        path.push(pose);
        polyline(&painter, &t, &path, Stroke::new(1.8, color), false);
        draw_estimate(
            &painter,
            &t,
            &pose,
            &run.filter().pose_covariance(),
            EstimateStyle {
                color,
                ellipse: view.ellipses,
                wedge_radius: 22.0,
                dot: true,
            },
        );
    }
    let truth_now = log.truth_at(now);
    let at = t.pose(&truth_now);
    if finite(at) {
        painter.circle(
            at,
            6.0,
            colors.background.gamma_multiply(0.6),
            Stroke::new(2.0, colors.truth),
        );
        painter.line_segment(
            [at, at + screen_dir(truth_now.theta) * 10.0],
            Stroke::new(2.5, colors.truth),
        );
    }
    draw_scale_and_axes(&painter, &t, &colors);
    if view.ellipses {
        draw_wide_ellipse_notes(&painter, &t, sim, room);
    }
}

/// A line at the map's foot for each mode whose 95% ellipse is wider than the
/// room (the differential mode's, whose position is only dead-reckoned): its
/// size and why, so that arcs at the map's edges are not read as a fault.
fn draw_wide_ellipse_notes(
    painter: &egui::Painter,
    t: &MapTransform,
    sim: &FusionSim,
    room: [f64; 2],
) {
    use slamlab_core::geometry::{CHI2_2DOF_95, CovarianceEllipse};
    let mut y = t.rect.top() + 8.0;
    for run in sim.runs() {
        let pose = run.filter().pose();
        let block = run
            .filter()
            .pose_covariance()
            .fixed_view::<2, 2>(0, 0)
            .into_owned();
        let e = CovarianceEllipse::from_covariance(
            nalgebra::Vector2::new(pose.x, pose.y),
            &block,
            CHI2_2DOF_95,
        );
        let across = 2.0 * e.semi_major;
        if !(across.is_finite() && across > room[0].max(room[1])) {
            continue;
        }
        let text = format!(
            "{}'s 95% ellipse is {across:.1} m across:\nits position is only dead-reckoned \
             (Explain)",
            run.mode().name()
        );
        let galley = painter.layout(
            text,
            egui::FontId::proportional(12.0),
            Color32::WHITE,
            (0.45 * t.rect.width()).max(120.0),
        );
        let at = pos2(t.rect.right() - 10.0 - galley.size().x, y);
        let frame = egui::Rect::from_min_size(at, galley.size()).expand(4.0);
        painter.rect_filled(frame, 3.0, Color32::from_black_alpha(200));
        painter.rect_stroke(
            frame,
            3.0,
            Stroke::new(1.5, mode_color(run.mode())),
            egui::StrokeKind::Outside,
        );
        y += galley.size().y + 14.0;
        painter.galley(at, galley, Color32::WHITE);
    }
}

/// A path as one line (thinned to [`MAX_POINTS`]), dashed or solid.
fn polyline(
    painter: &egui::Painter,
    t: &MapTransform,
    path: &[Pose2],
    stroke: Stroke,
    dashed: bool,
) {
    let points = t.path(path, MAX_POINTS);
    if points.len() < 2 {
        return;
    }
    if dashed {
        painter.extend(Shape::dashed_line(&points, stroke, 6.0, 4.0));
    } else {
        painter.add(Shape::line(points, stroke));
    }
}

/// The map's key: the truth, the raw odometry, the SLAM poses and each mode.
fn legend_entries(sim: &FusionSim, colors: &CanvasColors) -> Vec<KeyEntry> {
    let mut rows = vec![
        KeyEntry::new("true robot and path", colors.truth, Mark::Solid),
        KeyEntry::new(
            "raw wheel odometry (dead reckoning)",
            palette::DEAD_RECKONING,
            Mark::Dashed,
        ),
        KeyEntry::new("SLAM poses", palette::VERMILLION, Mark::Dots),
    ];
    for run in sim.runs() {
        rows.push(KeyEntry::new(
            format!("{}: fused path, estimate, 95% ellipse", run.mode().name()),
            mode_color(run.mode()),
            Mark::Solid,
        ));
    }
    rows
}
