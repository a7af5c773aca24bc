//! The map: the true world and every filter's estimate, in metres, with pan, zoom,
//! follow, a legend and hover tooltips.
//!
//! Drawing order, back to front: grid, world outline, sensor field of view, paths,
//! landmarks and their ellipses, observation rays, robots, legend, tooltip.

use super::ViewOptions;
use super::drive::{self, DriveState};
use crate::palette;
use crate::widgets::map_canvas::{
    self, CanvasColors, MapTransform, MapView, draw_grid, draw_scale_and_axes, finite,
    format_metres, screen_dir,
};
use crate::widgets::particles::ParticleMesh;
use egui::{Color32, Pos2, Rect, Shape, Stroke, vec2};
use nalgebra::{Matrix2, Vector2};
use slamlab_core::Pose2;
use slamlab_core::geometry::{CHI2_2DOF_95, CovarianceEllipse};
use slamlab_core::kalman::LandmarkSlam;
use slamlab_sim::world::recorded::RecordedWorld;
use slamlab_sim::{LandmarkSession, Phase};
use std::f64::consts::PI;

/// How close (pixels) the pointer must be to an item for its tooltip.
const HOVER_RADIUS: f32 = 12.0;
/// Longest path drawn, in points; longer paths are thinned evenly.
const MAX_PATH_POINTS: usize = 4000;
/// Radius of the heading-uncertainty wedge, pixels.
const WEDGE_RADIUS: f32 = 34.0;

/// The map toolbar, (when driving by hand) the drive pad under it, the map itself,
/// its legend and tooltips.
pub fn map_ui(
    ui: &mut egui::Ui,
    session: &LandmarkSession,
    reference: Option<&super::reference::Overlay>,
    view: &mut MapView,
    opts: &mut ViewOptions,
    drive: &mut DriveState,
) {
    toolbar_ui(ui, view, opts, session);
    if matches!(session.controller(), slamlab_sim::ControllerKind::Manual) {
        drive::drive_pad_ui(ui, drive);
    } else {
        drive.pad = None;
    }
    // Two filters drawn over each other (at the scale of the last frame): said
    // in a band over the top of the map, which comes and goes without moving it.
    let coinciding = coinciding_on_screen(session, view.scale).map(|other| {
        let names = session.filters();
        format!(
            "{} and {} agree here to within a pixel or two: one is drawn over the other. \
             Try the precise-range preset, where they part.",
            filter_label(names[0].kind.name()),
            filter_label(names[other].kind.name()),
        )
    });
    // A recorded world is fitted to what it holds (MRCLAM's room is 15 m x 8 m off
    // the origin); the simulated one is the square around the origin.
    let half = 0.5 * session.world().size;
    let bounds = session
        .recorded_world()
        .map_or([-half, -half, half, half], |w| recorded_bounds(w));
    if opts.legend {
        // The key on a line above the map, never over the world.
        let colors = CanvasColors::of(ui);
        // Sigma points show in the key once they are drawn (last frame's map).
        let sigma_points_shown = ui
            .data(|d| d.get_temp::<bool>(sigma_points_id()))
            .unwrap_or(false);
        let mut entries = legend_entries(session, &colors, opts, sigma_points_shown);
        if let Some(fit) = reference.and_then(|r| r.fits.first())
            && fit.fit.is_some()
        {
            // After the references (truth, GPS), before the filters.
            let at = entries
                .iter()
                .position(|e| e.text.ends_with("path, landmarks"))
                .unwrap_or(entries.len());
            entries.insert(
                at,
                LegendEntry::new(
                    vec![
                        (Symbol::ReferenceTree, colors.truth),
                        (
                            Symbol::Line { dashed: false },
                            palette::faded(colors.truth, 0.45),
                        ),
                    ],
                    format!(
                        "reference map (pose graph solved): trees, path; aligned to {}",
                        filter_label(&fit.filter)
                    ),
                ),
            );
        }
        map_key_ui(ui, &entries, colors.background);
    }
    let truth = session.truth();
    let mut follow = opts.follow_robot.then_some([truth.x, truth.y]);
    let (response, t) = map_canvas::canvas_ui(ui, view, bounds, 0.0, &mut follow, true);
    opts.follow_robot = follow.is_some();
    let rect = t.rect;
    let colors = CanvasColors::of(ui);
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 4.0, colors.background);
    draw_grid(&painter, &t, &colors);
    draw_world(&painter, &t, session, opts, &colors);
    if let Some(overlay) = reference {
        draw_reference(&painter, &t, overlay, &colors);
    }
    // The truth first: the estimates' ellipses and wedges are drawn over its marker.
    // A recorded world shows it only where the data knows it.
    if let Some(truth) = session.true_pose() {
        draw_truth_robot(&painter, &t, truth, colors.truth, colors.background);
    }
    let sigma_points_shown = draw_filters(&painter, &t, session, opts, &colors);
    draw_gps(&painter, &t, session);
    ui.data_mut(|d| d.insert_temp(sigma_points_id(), sigma_points_shown));
    draw_scale_and_axes(&painter, &t, &colors);
    if opts.magnifier {
        draw_magnifier(&painter, &t, session, opts, &colors, None);
    }
    if let Some(note) = coinciding {
        band_over_map(
            &painter,
            rect,
            &note,
            ui.visuals().warn_fg_color,
            colors.background,
        );
    }
    if let Some(pointer) = response.hover_pos()
        && !response.dragged()
        && let Some(text) = hover_text(&t, session, pointer)
    {
        response.on_hover_ui_at_pointer(|ui| {
            ui.label(text);
        });
    }
}

/// `text` in a band across the top of the map at `rect`, on the map's
/// background: a note that comes and goes without moving the map.
fn band_over_map(
    painter: &egui::Painter,
    rect: egui::Rect,
    text: &str,
    color: Color32,
    background: Color32,
) {
    let width = (rect.width() - 60.0).clamp(80.0, 560.0);
    let galley = painter.layout(
        text.to_owned(),
        egui::FontId::proportional(13.0),
        color,
        width,
    );
    let at = egui::pos2(rect.left() + 40.0, rect.top() + 6.0);
    let band = egui::Rect::from_min_size(at, galley.size()).expand(4.0);
    painter.rect_filled(band, 3.0, background.gamma_multiply(0.9));
    painter.galley(at, galley, color);
}

fn toolbar_ui(
    ui: &mut egui::Ui,
    view: &mut MapView,
    opts: &mut ViewOptions,
    session: &LandmarkSession,
) {
    ui.horizontal_wrapped(|ui| {
        ui.label("Map:");
        if map_canvas::zoom_buttons_ui(ui, view, "Fit world") {
            opts.follow_robot = false;
        }
        ui.checkbox(&mut opts.follow_robot, "Follow robot")
            .on_hover_text("Keep the true robot in the middle of the map");
        let has_sigma_points = session
            .filters()
            .iter()
            .any(|run| !super::robot_sigma_points(run.filter()).is_empty());
        ui.separator();
        // A small map (a phone, an iframe) keeps its layers in a menu, so that the
        // toolbar stays one row and the map keeps the height.
        if ui.available_width() < 640.0 {
            ui.menu_button("Layers", |ui| layers_ui(ui, opts, has_sigma_points));
        } else {
            layers_ui(ui, opts, has_sigma_points);
        }
        ui.separator();
        ui.toggle_value(&mut opts.heatmap, "Covariance heatmap")
            .on_hover_text("Every filter's covariance as a correlation matrix");
        ui.toggle_value(&mut opts.many_runs, "Many runs")
            .on_hover_text("This scenario run again with many seeds: each filter's NEES averaged over the runs, against the band of a consistent filter");
    });
}

/// The map's layer switches.
fn layers_ui(ui: &mut egui::Ui, opts: &mut ViewOptions, has_sigma_points: bool) {
    ui.checkbox(&mut opts.legend, "Legend");
    ui.checkbox(&mut opts.magnifier, "Magnifier").on_hover_text(
        "A magnified view around the robot, whenever its ellipses are small on the map: \
         watch predict grow them and each update shrink them",
    );
    ui.checkbox(&mut opts.fov, "Field of view")
        .on_hover_text("The sensor's field of view and range, from the true robot");
    ui.checkbox(&mut opts.rays, "Observations")
        .on_hover_text("This tick's measurements as rays from the true robot");
    ui.checkbox(&mut opts.ids, "Ids");
    ui.checkbox(&mut opts.error_lines, "Errors")
        .on_hover_text("A thin line from each estimated landmark to its true position");
    if has_sigma_points {
        ui.checkbox(&mut opts.sigma_points, "Sigma points")
            .on_hover_text(
                "The UKF's sigma points of the robot pose, as its next prediction spreads them",
            );
    } else {
        // Shown unticked: no filter here has sigma points to draw.
        ui.add_enabled(false, egui::Checkbox::new(&mut false, "Sigma points"))
            .on_disabled_hover_text("Only sigma-point filters (UKF) have sigma points");
    }
}

/// Points of a path on screen, thinned to at most [`MAX_PATH_POINTS`], with `last`
/// appended (the current pose mid-tick).
fn path_points(t: &MapTransform, poses: &[Pose2], last: Option<Pose2>) -> Vec<Pos2> {
    let stride = poses.len() / MAX_PATH_POINTS + 1;
    let mut points: Vec<Pos2> = poses
        .iter()
        .enumerate()
        .filter(|(i, _)| i % stride == 0 || *i + 1 == poses.len())
        .map(|(_, p)| t.pose(p))
        .filter(|p| finite(*p))
        .collect();
    if let Some(last) = last {
        let p = t.pose(&last);
        if finite(p) {
            points.push(p);
        }
    }
    points
}

/// A filled fan (wedge) from `center` over `rim` points, plus its outline.
fn fan(center: Pos2, rim: &[Pos2], fill: Color32, outline: Stroke) -> Vec<Shape> {
    let mut mesh = egui::Mesh::default();
    mesh.colored_vertex(center, fill);
    for p in rim {
        mesh.colored_vertex(*p, fill);
    }
    for i in 1..rim.len() as u32 {
        mesh.add_triangle(0, i, i + 1);
    }
    let mut outline_points = Vec::with_capacity(rim.len() + 2);
    outline_points.push(center);
    outline_points.extend_from_slice(rim);
    outline_points.push(center);
    vec![Shape::mesh(mesh), Shape::line(outline_points, outline)]
}

/// The field of view and range set for the next tick, when they differ from this
/// tick's.
fn coming_reach(session: &LandmarkSession) -> Option<(f64, f64)> {
    let coming = session.scenario_now();
    let sensor = session.sensor();
    let reach = (coming.fov, coming.max_range);
    (reach != (sensor.fov, sensor.max_range)).then_some(reach)
}

/// The outline of a sensor's reach from the robot at `robot` (screen) heading `theta`:
/// robot, rim, robot for a wedge; the closed rim for a full circle. None when it cannot
/// be drawn (non-finite, or far too large).
fn reach_outline(
    t: &MapTransform,
    robot: Pos2,
    theta: f64,
    fov: f64,
    max_range: f64,
) -> Option<Vec<Pos2>> {
    let radius = (max_range as f32) * t.scale;
    if !(radius.is_finite() && radius < 1.0e6 && fov.is_finite() && theta.is_finite()) {
        return None;
    }
    if fov >= 2.0 * PI - 1e-9 {
        return Some(arc(robot, radius, theta - PI, theta + PI));
    }
    let mut points = vec![robot];
    points.extend(arc(robot, radius, theta - fov / 2.0, theta + fov / 2.0));
    points.push(robot);
    Some(points)
}

/// Points on a circular arc around `center` (screen), radius in points, world angles.
fn arc(center: Pos2, radius: f32, from: f64, to: f64) -> Vec<Pos2> {
    let span = (to - from).abs();
    let n = ((span / (2.0 * PI) * 96.0).ceil() as usize).clamp(2, 96);
    (0..=n)
        .map(|i| {
            let a = from + (to - from) * i as f64 / n as f64;
            center + radius * screen_dir(a)
        })
        .collect()
}

/// The 95% ellipse of a 2x2 covariance as a filled, outlined polygon. Returns nothing
/// for non-finite or absurdly large ellipses.
fn ellipse_shapes(
    t: &MapTransform,
    center: &Vector2<f64>,
    covariance: &Matrix2<f64>,
    color: Color32,
    fill_alpha: f32,
    width: f32,
    dashed: bool,
) -> Vec<Shape> {
    let e = CovarianceEllipse::from_covariance(*center, covariance, CHI2_2DOF_95);
    if !(e.semi_major.is_finite() && e.semi_minor.is_finite() && e.angle.is_finite()) {
        return Vec::new();
    }
    if (e.semi_major as f32) * t.scale > 1.0e6 {
        return Vec::new();
    }
    // About one vertex per 4 screen points of perimeter: a small ellipse needs few,
    // and a lesson with 50 landmarks and two filters draws over a hundred of them.
    let perimeter = std::f32::consts::TAU * (e.semi_major as f32) * t.scale;
    let segments = ((perimeter / 4.0).ceil() as usize).clamp(12, 64);
    let points: Vec<Pos2> = e.boundary(segments).iter().map(|p| t.v(p)).collect();
    if points.iter().any(|p| !finite(*p)) {
        return Vec::new();
    }
    let mut shapes = vec![Shape::convex_polygon(
        points.clone(),
        palette::faded(color, fill_alpha),
        Stroke::NONE,
    )];
    if dashed {
        let mut closed = points;
        if let Some(first) = closed.first().copied() {
            closed.push(first);
        }
        shapes.extend(Shape::dashed_line(
            &closed,
            Stroke::new(width + 0.4, color),
            6.0,
            4.0,
        ));
    } else {
        shapes.push(Shape::closed_line(points, Stroke::new(width, color)));
    }
    shapes
}

fn cross(painter: &egui::Painter, p: Pos2, r: f32, stroke: Stroke) {
    painter.line_segment([p - vec2(r, r), p + vec2(r, r)], stroke);
    painter.line_segment([p - vec2(r, -r), p + vec2(r, -r)], stroke);
}

/// The landmark id updated by the latest phase, if that was an update.
fn updated_landmark(session: &LandmarkSession) -> Option<usize> {
    match session.last_phase() {
        Some(Phase::Update { id, .. }) => Some(id),
        _ => None,
    }
}

fn draw_world(
    painter: &egui::Painter,
    t: &MapTransform,
    session: &LandmarkSession,
    opts: &ViewOptions,
    colors: &CanvasColors,
) {
    // World square (a recorded world has no walls: its square only frames the data).
    let recorded = session.recorded_world().cloned();
    let half = session.world().size / 2.0;
    let a = t.xy(-half, -half);
    let b = t.xy(half, half);
    if recorded.is_none() && finite(a) && finite(b) {
        painter.rect_stroke(
            Rect::from_two_pos(a, b),
            0.0,
            Stroke::new(1.5, palette::faded(colors.truth, 0.55)),
            egui::StrokeKind::Middle,
        );
    }
    // A recorded world's rays start at the true pose where it is known, else at
    // the first estimate's (as the session places the measured points).
    let truth = match (&recorded, session.true_pose()) {
        (Some(_), None) => session
            .filters()
            .first()
            .map_or(session.dead_reckoning(), |run| run.filter().robot_pose()),
        _ => session.truth(),
    };
    let robot = t.pose(&truth);
    // Sensor field of view: the reach of this tick, filled, and a reach changed from
    // the panel, which applies from the next tick, as a dashed outline.
    if opts.fov && finite(robot) {
        let sensor = session.sensor();
        let fill = palette::faded(colors.truth, 0.06);
        let outline = Stroke::new(1.0, palette::faded(colors.truth, 0.25));
        if let Some(rim) = reach_outline(t, robot, truth.theta, sensor.fov, sensor.max_range) {
            if sensor.fov >= 2.0 * PI - 1e-9 {
                let radius = (sensor.max_range as f32) * t.scale;
                painter.circle(robot, radius, fill, outline);
            } else {
                painter.extend(fan(robot, &rim[1..rim.len() - 1], fill, outline));
            }
        }
        if let Some((fov, max_range)) = coming_reach(session)
            && let Some(next) = reach_outline(t, robot, truth.theta, fov, max_range)
        {
            painter.extend(Shape::dashed_line(
                &next,
                Stroke::new(1.4, palette::faded(colors.truth, 0.6)),
                6.0,
                4.0,
            ));
        }
    }
    // Paths: dead reckoning (grey dashed), then truth.
    let dr = path_points(
        t,
        session.dead_reckoning_path(),
        Some(session.dead_reckoning()),
    );
    if dr.len() >= 2 {
        painter.extend(Shape::dashed_line(
            &dr,
            Stroke::new(1.5, palette::DEAD_RECKONING),
            7.0,
            5.0,
        ));
    }
    let dr_pose = t.pose(&session.dead_reckoning());
    if finite(dr_pose) {
        painter.circle_stroke(dr_pose, 4.0, Stroke::new(1.5, palette::DEAD_RECKONING));
    }
    let truth_stroke = Stroke::new(1.5, palette::faded(colors.truth, 0.8));
    match &recorded {
        None => {
            let truth_path = path_points(t, session.truth_path(), Some(truth));
            if truth_path.len() >= 2 {
                painter.add(Shape::line(truth_path, truth_stroke));
            }
        }
        Some(world) => draw_recorded_references(painter, t, session, world, colors),
    }
    // True landmarks.
    let highlight = updated_landmark(session);
    let show_ids = opts.ids && session.world().landmarks.len() <= 150;
    for landmark in &session.world().landmarks {
        let p = t.v(&landmark.position);
        if !finite(p) || !t.rect.expand(20.0).contains(p) {
            continue;
        }
        cross(painter, p, 4.5, Stroke::new(1.8, colors.truth));
        if show_ids {
            painter.text(
                p + vec2(6.0, -5.0),
                egui::Align2::LEFT_BOTTOM,
                landmark.id.to_string(),
                egui::FontId::proportional(10.5),
                colors.weak_text,
            );
        }
        if highlight == Some(landmark.id) {
            painter.circle_stroke(p, 10.0, Stroke::new(2.5, palette::VERMILLION));
        }
    }
    // This tick's observations.
    if opts.rays && finite(robot) {
        for o in session.observations() {
            let end = t.v(&o.measured_point);
            if !finite(end) {
                continue;
            }
            let (stroke, radius) = if highlight == Some(o.id) {
                (Stroke::new(2.2, palette::VERMILLION), 3.5)
            } else {
                (Stroke::new(0.8, palette::faded(colors.truth, 0.45)), 2.5)
            };
            painter.line_segment([robot, end], stroke);
            painter.circle_stroke(end, radius, stroke);
        }
        // Other robots seen (MRCLAM): greyed and named, never used by the filters.
        let grey = Stroke::new(0.9, palette::faded(palette::DEAD_RECKONING, 0.7));
        for o in session.other_sightings() {
            let end = t.v(&o.measured_point);
            if !finite(end) {
                continue;
            }
            painter.extend(Shape::dashed_line(&[robot, end], grey, 3.0, 3.0));
            painter.circle_stroke(end, 3.0, grey);
            painter.text(
                end + vec2(5.0, 4.0),
                egui::Align2::LEFT_TOP,
                format!("robot {} (not used)", o.robot),
                egui::FontId::proportional(10.0),
                colors.weak_text,
            );
        }
    }
}

/// What a recorded world's map is fitted to (`[x_min, y_min, x_max, y_max]`,
/// metres): its landmarks and every robot's Vicon path (MRCLAM, the Freiburg
/// files' landmarks), with a margin; Victoria Park has neither, so its GPS
/// fixes, moved so that the first is on the start.
pub fn recorded_bounds(world: &RecordedWorld) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut grow = |x: f64, y: f64| {
        if x.is_finite() && y.is_finite() {
            b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
        }
    };
    grow(world.start.x, world.start.y);
    for (l, _) in &world.landmarks {
        grow(l.position[0], l.position[1]);
    }
    let tracks = world
        .truth
        .iter()
        .chain(world.others.iter().map(|o| &o.truth));
    for track in tracks {
        for (_, p) in &track.samples {
            grow(p.x, p.y);
        }
    }
    // The GPS's extent with its first fix on the start: its frame is turned a
    // few degrees from the estimate's at most (2.3° for EKF-SLAM's whole run).
    if let Some((_, first)) = world.reference.first() {
        for (_, p) in &world.reference {
            grow(
                world.start.x + p[0] - first[0],
                world.start.y + p[1] - first[1],
            );
        }
    }
    // Without a true path (the Freiburg files) the robot drives around the
    // landmarks: a wider margin keeps its path on the map.
    let share = if world.truth.is_some() { 0.08 } else { 0.25 };
    let margin = (share * (b[2] - b[0]).max(b[3] - b[1])).max(1.0);
    [b[0] - margin, b[1] - margin, b[2] + margin, b[3] + margin]
}

/// A recorded world's references: its true path (MRCLAM's Vicon) up to now,
/// split at its gaps (a gap is drawn as a gap, not bridged); the other robots
/// where Vicon puts them now, greyed.
fn draw_recorded_references(
    painter: &egui::Painter,
    t: &MapTransform,
    session: &LandmarkSession,
    world: &RecordedWorld,
    colors: &CanvasColors,
) {
    let now = session.time();
    let stroke = Stroke::new(1.5, palette::faded(colors.truth, 0.8));
    if let Some(track) = &world.truth {
        let pieces = track.pieces(now);
        let total: usize = pieces.iter().map(|p| p.len()).sum();
        let stride = total / MAX_PATH_POINTS + 1;
        for piece in pieces {
            let points: Vec<Pos2> = piece
                .iter()
                .enumerate()
                .filter(|(i, _)| i % stride == 0 || *i + 1 == piece.len())
                .map(|(_, (_, p))| t.pose(p))
                .filter(|p| finite(*p))
                .collect();
            if points.len() >= 2 {
                painter.add(Shape::line(points, stroke));
            }
        }
    }
    let grey = palette::faded(palette::DEAD_RECKONING, 0.8);
    for other in &world.others {
        let Some(pose) = other.truth.at(now) else {
            continue;
        };
        let p = t.pose(&pose);
        if !finite(p) {
            continue;
        }
        painter.circle_stroke(p, 6.0, Stroke::new(1.2, grey));
        painter.line_segment(
            [p, p + 10.0 * screen_dir(pose.theta)],
            Stroke::new(1.2, grey),
        );
        painter.text(
            p + vec2(7.0, -7.0),
            egui::Align2::LEFT_BOTTOM,
            other.number.to_string(),
            egui::FontId::proportional(10.0),
            colors.weak_text,
        );
    }
}

/// The GPS fixes up to now (Victoria Park) as grey dots over the estimates,
/// carried into the estimate's frame by the fit of the first filter's path
/// (none before it can be fitted).
fn draw_gps(painter: &egui::Painter, t: &MapTransform, session: &LandmarkSession) {
    let Some(world) = session.recorded_world() else {
        return;
    };
    let Some(gps) = super::gps_fit_now(session) else {
        return;
    };
    let grey = palette::faded(palette::DEAD_RECKONING, 0.9);
    let now = session.time();
    let end = world.reference.partition_point(|(time, _)| *time <= now);
    let stride = end / MAX_PATH_POINTS + 1;
    for (_, fix) in world.reference[..end].iter().step_by(stride) {
        let p = t.v(&Vector2::from(gps.to_estimate_frame([fix[0], fix[1]])));
        if finite(p) && t.rect.contains(p) {
            painter.circle_filled(p, 1.8, grey);
        }
    }
}

/// Victoria Park's reference map (the solved pose graph) in the first filter's
/// frame, as far as the car has driven: the path as a thin line under the
/// estimates, each tree as a hollow square in the truth's colour.
fn draw_reference(
    painter: &egui::Painter,
    t: &MapTransform,
    overlay: &super::reference::Overlay,
    colors: &CanvasColors,
) {
    let Some(fit) = overlay.fits.first().and_then(|f| f.fit) else {
        return;
    };
    let map = &overlay.map;
    let upto = (fit.last_paired + 1).min(map.path.len());
    let stride = upto / MAX_PATH_POINTS + 1;
    let points: Vec<Pos2> = map.path[..upto]
        .iter()
        .step_by(stride)
        .map(|p| t.v(&fit.apply(&Vector2::new(p.x, p.y))))
        .filter(|p| finite(*p))
        .collect();
    painter.add(Shape::line(
        points,
        Stroke::new(1.0, palette::faded(colors.truth, 0.45)),
    ));
    for tree in map
        .trees
        .iter()
        .filter(|tr| tr.first_seen <= fit.last_paired)
    {
        let p = t.v(&fit.apply(&tree.position));
        if finite(p) && t.rect.contains(p) {
            reference_tree(painter, p, colors.truth);
        }
    }
}

/// A reference tree's mark: a hollow square.
fn reference_tree(painter: &egui::Painter, p: Pos2, color: Color32) {
    painter.rect_stroke(
        Rect::from_center_size(p, vec2(7.0, 7.0)),
        0.0,
        Stroke::new(1.4, color),
        egui::StrokeKind::Middle,
    );
}

/// Draws every filter's landmarks, path and robot. Returns whether sigma points were drawn.
fn draw_filters(
    painter: &egui::Painter,
    t: &MapTransform,
    session: &LandmarkSession,
    opts: &ViewOptions,
    colors: &CanvasColors,
) -> bool {
    let highlight = updated_landmark(session);
    let mut drew_sigma_points = false;
    for (index, run) in session.filters().iter().enumerate() {
        // Filters after the first are drawn over it: dashed outlines, hollow robot,
        // so that both stay visible where they agree.
        let secondary = index > 0;
        let color = palette::estimator_color(run.kind.name());
        let filter = run.filter();
        if let Some(particles) = filter.particle_set() {
            draw_particles(painter, t, particles, color);
        }
        // Landmarks: 95% ellipse, mean, optional line to the truth. (For FastSLAM:
        // the best particle's landmarks.)
        for estimate in filter.landmarks() {
            let p = t.v(&estimate.mean);
            if !finite(p) {
                continue;
            }
            painter.extend(ellipse_shapes(
                t,
                &estimate.mean,
                &estimate.covariance,
                color,
                0.10,
                1.2,
                secondary,
            ));
            painter.circle_filled(p, 2.8, color);
            if opts.error_lines
                && let Some(truth) = session.world().landmark(estimate.id)
            {
                let q = t.v(&truth.position);
                if finite(q) {
                    painter.line_segment([p, q], Stroke::new(1.0, palette::faded(color, 0.7)));
                }
            }
            if highlight == Some(estimate.id) {
                painter.circle_stroke(p, 7.0, Stroke::new(2.0, palette::VERMILLION));
            }
        }
        // Estimated path.
        let path = path_points(t, &run.path, Some(filter.robot_pose()));
        if path.len() >= 2 {
            if secondary {
                painter.extend(Shape::dashed_line(&path, Stroke::new(1.8, color), 8.0, 5.0));
            } else {
                painter.add(Shape::line(path, Stroke::new(1.6, color)));
            }
        }
        drew_sigma_points |= draw_robot_estimate(
            painter,
            t,
            filter,
            color,
            secondary,
            opts,
            colors,
            WEDGE_RADIUS,
        );
    }
    drew_sigma_points
}

/// Smallest magnification worth an inset: below it the robot's ellipses are already
/// readable on the map.
const MIN_MAGNIFICATION: f32 = 2.0;
/// Largest magnification: a millimetre ellipse stays a millimetre ellipse.
const MAX_MAGNIFICATION: f32 = 50.0;

/// The magnification shown: the largest of 2, 2.5, 5, 10, 20 and 50 that is not above
/// `wanted`, so that it holds while stepping (predict grows √det P by a few percent,
/// which a continuous magnification would undo, keeping the picture the same).
fn steady_magnification(wanted: f32) -> f32 {
    [50.0, 20.0, 10.0, 5.0, 2.5, MIN_MAGNIFICATION]
        .into_iter()
        .find(|&m| m <= wanted)
        .unwrap_or(wanted)
}

/// The magnifier's square: its side (points) for a map, and the corner it takes (the
/// first of top right, bottom right, bottom left, top left that stays inside the map,
/// off the legend and off the true robot).
fn magnifier_rect(map: Rect, legend: Option<Rect>, robot: Pos2) -> Option<Rect> {
    let side = (0.3 * map.width().min(map.height())).clamp(110.0, 200.0);
    let size = vec2(side, side);
    let candidates = [
        Rect::from_min_size(map.right_top() + vec2(-side - 10.0, 26.0), size),
        Rect::from_min_size(map.right_bottom() + vec2(-side - 10.0, -side - 30.0), size),
        Rect::from_min_size(map.left_bottom() + vec2(48.0, -side - 48.0), size),
        Rect::from_min_size(map.left_top() + vec2(48.0, 26.0), size),
    ];
    candidates.into_iter().find(|rect| {
        map.contains_rect(*rect)
            && !legend.is_some_and(|l| l.intersects(rect.expand(4.0)))
            && !rect.expand(16.0).contains(robot)
    })
}

/// How far (metres) the robot's estimates reach from the true robot: each filter's
/// distance plus its 95% ellipse's semi-major axis. `None` if not finite, or below a
/// tenth of a millimetre.
fn estimate_extent(session: &LandmarkSession) -> Option<f64> {
    let truth = session.truth().translation();
    let mut extent = 0.0_f64;
    for run in session.filters() {
        let filter = run.filter();
        let e = CovarianceEllipse::from_covariance(
            filter.robot_pose().translation(),
            &robot_position_covariance(filter),
            CHI2_2DOF_95,
        );
        let reach = (filter.robot_pose().translation() - truth).norm() + e.semi_major;
        if !reach.is_finite() {
            return None;
        }
        extent = extent.max(reach);
    }
    // Nothing to magnify before the first prediction (every ellipse a point).
    (extent > 1e-4).then_some(extent)
}

/// A magnified inset around the true robot: every filter's robot ellipse, heading
/// wedge and (for FastSLAM) particles, with the magnification and the width it shows,
/// and a square on the map marking where it looks. Drawn only when the ellipses are
/// small on the map (magnification of at least [`MIN_MAGNIFICATION`]).
fn draw_magnifier(
    painter: &egui::Painter,
    t: &MapTransform,
    session: &LandmarkSession,
    opts: &ViewOptions,
    colors: &CanvasColors,
    legend: Option<Rect>,
) {
    let truth = session.truth();
    let robot = t.pose(&truth);
    let Some(extent) = estimate_extent(session) else {
        return;
    };
    if !finite(robot) || !t.rect.contains(robot) {
        return;
    }
    let Some(inset) = magnifier_rect(t.rect, legend, robot) else {
        return;
    };
    let magnification = steady_magnification(
        ((0.42 * f64::from(inset.width()) / extent) as f32 / t.scale).min(MAX_MAGNIFICATION),
    );
    let scale = magnification * t.scale;
    if !(magnification.is_finite() && magnification >= MIN_MAGNIFICATION) {
        return;
    }
    // Where the inset looks, on the map, joined to the inset.
    let half = 0.5 * inset.width() / magnification;
    let looked_at = Rect::from_center_size(robot, vec2(2.0 * half, 2.0 * half).max(vec2(6.0, 6.0)));
    let frame = Stroke::new(1.0, colors.weak_text);
    painter.rect_stroke(looked_at, 0.0, frame, egui::StrokeKind::Outside);
    let nearest_corner = [
        inset.left_top(),
        inset.right_top(),
        inset.left_bottom(),
        inset.right_bottom(),
    ]
    .into_iter()
    .min_by(|a, b| a.distance(robot).total_cmp(&b.distance(robot)))
    .unwrap_or(inset.center());
    painter.line_segment(
        [
            looked_at.center() + (nearest_corner - robot).normalized() * half,
            nearest_corner,
        ],
        Stroke::new(1.0, palette::faded(colors.weak_text, 0.6)),
    );

    painter.rect(
        inset,
        4.0,
        colors.background,
        Stroke::new(1.2, colors.weak_text),
        egui::StrokeKind::Outside,
    );
    let zoomed = MapTransform {
        rect: inset,
        center: [truth.x, truth.y],
        scale,
    };
    let clipped = painter.with_clip_rect(inset);
    draw_grid(&clipped, &zoomed, colors);
    draw_truth_robot(&clipped, &zoomed, truth, colors.truth, colors.background);
    for (index, run) in session.filters().iter().enumerate() {
        let color = palette::estimator_color(run.kind.name());
        let filter = run.filter();
        if let Some(particles) = filter.particle_set() {
            draw_particles(&clipped, &zoomed, particles, color);
        }
        draw_robot_estimate(
            &clipped,
            &zoomed,
            filter,
            color,
            index > 0,
            opts,
            colors,
            0.3 * inset.width(),
        );
    }
    let across = f64::from(inset.width() / scale);
    painter.text(
        inset.left_top() + vec2(6.0, 4.0),
        egui::Align2::LEFT_TOP,
        format!(
            // Two short lines: the inset is as narrow as 110 points.
            "robot ×{magnification}\n{} m across",
            format_metres(across, across / 10.0)
        ),
        egui::FontId::proportional(12.0),
        colors.truth,
    );
}

/// The first later filter whose robot (mean, 95% ellipse axes) and every landmark mean
/// are within two screen pixels of the first filter's at `scale` pixels per metre, if
/// any: two filters drawn over each other, the later one hiding the first.
fn coinciding_on_screen(session: &LandmarkSession, scale: f32) -> Option<usize> {
    let runs = session.filters();
    let first = runs.first()?.filter();
    let pixel = 2.0 / f64::from(scale);
    let axes = |filter: &dyn LandmarkSlam| {
        let e = CovarianceEllipse::from_covariance(
            filter.robot_pose().translation(),
            &robot_position_covariance(filter),
            CHI2_2DOF_95,
        );
        (e.semi_major, e.semi_minor)
    };
    let (a_major, a_minor) = axes(first);
    let first_landmarks = first.landmarks();
    runs.iter().enumerate().skip(1).find_map(|(k, run)| {
        let other = run.filter();
        let (b_major, b_minor) = axes(other);
        let landmarks = other.landmarks();
        let same = (first.robot_pose().translation() - other.robot_pose().translation()).norm()
            < pixel
            && (a_major - b_major).abs() < pixel
            && (a_minor - b_minor).abs() < pixel
            && landmarks.len() == first_landmarks.len()
            && first_landmarks
                .iter()
                .zip(&landmarks)
                .all(|(a, b)| (a.mean - b.mean).norm() < pixel);
        (same && session.tick() > 0).then_some(k)
    })
}

/// One filter's robot: 95% position ellipse, ±2σθ heading wedge (of `wedge_radius`
/// points), sigma points when asked for, and the triangle. Returns whether it drew
/// sigma points.
#[allow(clippy::too_many_arguments)]
fn draw_robot_estimate(
    painter: &egui::Painter,
    t: &MapTransform,
    filter: &dyn LandmarkSlam,
    color: Color32,
    secondary: bool,
    opts: &ViewOptions,
    colors: &CanvasColors,
    wedge_radius: f32,
) -> bool {
    let pose = filter.robot_pose();
    let p = t.pose(&pose);
    if !finite(p) {
        return false;
    }
    painter.extend(ellipse_shapes(
        t,
        &pose.translation(),
        &robot_position_covariance(filter),
        color,
        0.14,
        2.0,
        secondary,
    ));
    let sigma_theta = filter.robot_covariance()[(2, 2)].max(0.0).sqrt();
    if sigma_theta.is_finite() {
        let half = (2.0 * sigma_theta).min(PI);
        let rim = arc(p, wedge_radius, pose.theta - half, pose.theta + half);
        painter.extend(fan(
            p,
            &rim,
            palette::faded(color, 0.22),
            Stroke::new(1.0, palette::faded(color, 0.8)),
        ));
    }
    let mut drew_sigma_points = false;
    if opts.sigma_points {
        for sigma in super::robot_sigma_points(filter) {
            let s = t.pose(&sigma);
            if finite(s) {
                painter.circle_filled(s, 2.2, color);
                drew_sigma_points = true;
            }
        }
    }
    draw_estimated_robot(painter, p, pose.theta, color, colors.background, secondary);
    drew_sigma_points
}

/// The x-y block of a filter's robot covariance.
fn robot_position_covariance(filter: &dyn LandmarkSlam) -> Matrix2<f64> {
    let cov = filter.robot_covariance();
    Matrix2::new(cov[(0, 0)], cov[(0, 1)], cov[(1, 0)], cov[(1, 1)])
}

/// FastSLAM's particles: every particle's landmark means as faint dots, then
/// every particle's pose as a dart pointing along its heading.
fn draw_particles(
    painter: &egui::Painter,
    t: &MapTransform,
    particles: &slamlab_core::particle::FastSlam,
    color: Color32,
) {
    let faint = palette::faded(color, 0.35);
    let means = particles.landmark_means();
    let mut mesh = ParticleMesh::with_capacity(particles.particle_count() + 2 * means.len());
    for mean in means {
        mesh.dot(t.v(&mean), 1.1, faint);
    }
    for particle in particles.particles() {
        let pose = particle.pose;
        mesh.dart(t.pose(&pose), screen_dir(pose.theta), 8.0, color);
    }
    mesh.paint(painter);
}

fn draw_estimated_robot(
    painter: &egui::Painter,
    p: Pos2,
    theta: f64,
    color: Color32,
    outline: Color32,
    hollow: bool,
) {
    let forward = screen_dir(theta);
    let left = vec2(forward.y, -forward.x);
    let points = vec![
        p + 12.0 * forward,
        p - 7.0 * forward + 6.5 * left,
        p - 7.0 * forward - 6.5 * left,
    ];
    if hollow {
        painter.add(Shape::closed_line(points, Stroke::new(2.2, color)));
    } else {
        painter.add(Shape::convex_polygon(
            points,
            color,
            Stroke::new(1.2, outline),
        ));
    }
}

fn draw_truth_robot(
    painter: &egui::Painter,
    t: &MapTransform,
    truth: Pose2,
    color: Color32,
    background: Color32,
) {
    let p = t.pose(&truth);
    if !finite(p) {
        return;
    }
    painter.circle(
        p,
        8.0,
        palette::faded(background, 0.6),
        Stroke::new(2.2, color),
    );
    painter.line_segment(
        [p, p + 15.0 * screen_dir(truth.theta)],
        Stroke::new(2.2, color),
    );
}

/// An axis-aligned ellipse outline for the legend, solid or dashed.
fn legend_ellipse(
    painter: &egui::Painter,
    c: Pos2,
    radius: egui::Vec2,
    stroke: Stroke,
    dashed: bool,
) {
    if dashed {
        let points: Vec<Pos2> = (0..=40)
            .map(|i| {
                let a = 2.0 * std::f32::consts::PI * i as f32 / 40.0;
                c + vec2(radius.x * a.cos(), radius.y * a.sin())
            })
            .collect();
        painter.extend(Shape::dashed_line(&points, stroke, 4.0, 3.0));
    } else {
        painter.add(Shape::ellipse_stroke(c, radius, stroke));
    }
}

/// A legend symbol.
#[derive(Clone, Copy)]
enum Symbol {
    TruthRobot,
    Line { dashed: bool },
    EstimatedRobot { secondary: bool },
    TrueLandmark,
    EstimatedLandmark { secondary: bool },
    Ray,
    FieldOfView,
    Highlight,
    SigmaPoints,
    ReferenceTree,
}

fn draw_symbol(
    painter: &egui::Painter,
    rect: Rect,
    symbol: Symbol,
    color: Color32,
    background: Color32,
) {
    let c = rect.center();
    match symbol {
        Symbol::TruthRobot => {
            painter.circle(c, 6.0, Color32::TRANSPARENT, Stroke::new(2.0, color));
            painter.line_segment([c, c + vec2(11.0, 0.0)], Stroke::new(2.0, color));
        }
        Symbol::Line { dashed } => {
            let a = rect.left_center();
            let b = rect.right_center();
            if dashed {
                painter.extend(Shape::dashed_line(
                    &[a, b],
                    Stroke::new(1.6, color),
                    5.0,
                    3.0,
                ));
            } else {
                painter.line_segment([a, b], Stroke::new(1.8, color));
            }
        }
        Symbol::EstimatedRobot { secondary } => {
            painter.add(Shape::ellipse_filled(
                c,
                vec2(11.0, 7.0),
                palette::faded(color, 0.2),
            ));
            legend_ellipse(
                painter,
                c,
                vec2(11.0, 7.0),
                Stroke::new(1.5, color),
                secondary,
            );
            draw_estimated_robot(painter, c, 0.0, color, background, secondary);
        }
        Symbol::TrueLandmark => cross(painter, c, 4.5, Stroke::new(1.8, color)),
        Symbol::EstimatedLandmark { secondary } => {
            painter.add(Shape::ellipse_filled(
                c,
                vec2(9.0, 5.5),
                palette::faded(color, 0.15),
            ));
            legend_ellipse(
                painter,
                c,
                vec2(9.0, 5.5),
                Stroke::new(1.2, color),
                secondary,
            );
            painter.circle_filled(c, 2.8, color);
        }
        Symbol::Ray => {
            painter.line_segment(
                [rect.left_center(), rect.right_center()],
                Stroke::new(0.9, color),
            );
            painter.circle_stroke(
                rect.right_center() - vec2(3.0, 0.0),
                2.5,
                Stroke::new(0.9, color),
            );
        }
        Symbol::FieldOfView => {
            let rim = arc(rect.left_center(), rect.width(), -0.45, 0.45);
            painter.extend(fan(
                rect.left_center(),
                &rim,
                palette::faded(color, 0.12),
                Stroke::new(1.0, palette::faded(color, 0.4)),
            ));
        }
        Symbol::Highlight => {
            painter.circle_stroke(c, 6.5, Stroke::new(2.2, palette::VERMILLION));
        }
        Symbol::ReferenceTree => reference_tree(painter, c, color),
        Symbol::SigmaPoints => {
            for dx in [-7.0, 0.0, 7.0] {
                painter.circle_filled(c + vec2(dx, 0.0), 2.2, color);
            }
        }
    }
}

fn filter_label(name: &str) -> String {
    name.to_uppercase()
}

fn sigma_points_id() -> egui::Id {
    egui::Id::unique("slamlab_landmark_sigma_points_shown")
}

/// One entry of the map's key: its symbols (each in its colour) and its text.
struct LegendEntry {
    symbols: Vec<(Symbol, Color32)>,
    text: String,
    highlight: bool,
}

impl LegendEntry {
    fn new(symbols: Vec<(Symbol, Color32)>, text: impl Into<String>) -> Self {
        Self {
            symbols,
            text: text.into(),
            highlight: false,
        }
    }
}

/// The map's key, one entry per kind of thing drawn; a filter's robot, path and
/// landmarks share one entry.
fn legend_entries(
    session: &LandmarkSession,
    colors: &CanvasColors,
    opts: &ViewOptions,
    sigma_points_shown: bool,
) -> Vec<LegendEntry> {
    // A recorded world names its references by what they are, and leaves out
    // what the data does not have.
    let world = session.recorded_world();
    let (truth, landmarks) = match world {
        None => (Some("true robot and path"), Some("true landmark (id)")),
        Some(w) => (
            w.truth
                .as_ref()
                .map(|_| "Vicon robot and path (broken at its gaps)"),
            (!w.landmarks.is_empty()).then_some(match w.kind {
                slamlab_sim::io::landmark_data::DataSetKind::Freiburg => "world.dat landmark (id)",
                _ => "surveyed landmark (id)",
            }),
        ),
    };
    let mut entries = Vec::new();
    if let Some(text) = truth {
        entries.push(LegendEntry::new(
            vec![
                (Symbol::TruthRobot, colors.truth),
                (Symbol::Line { dashed: false }, colors.truth),
            ],
            text,
        ));
    }
    entries.push(LegendEntry::new(
        vec![(Symbol::Line { dashed: true }, palette::DEAD_RECKONING)],
        "dead reckoning",
    ));
    if let Some(text) = landmarks {
        entries.push(LegendEntry::new(
            vec![(Symbol::TrueLandmark, colors.truth)],
            text,
        ));
    }
    let grey = palette::faded(palette::DEAD_RECKONING, 0.8);
    if world.is_some_and(|w| !w.others.is_empty()) {
        entries.push(LegendEntry::new(
            vec![(Symbol::TruthRobot, grey), (Symbol::Ray, grey)],
            "other robots (Vicon) and sightings of them: not used",
        ));
    }
    if world.is_some_and(|w| !w.reference.is_empty()) {
        entries.push(LegendEntry::new(
            vec![(Symbol::SigmaPoints, grey)],
            format!(
                "GPS fixes, aligned to the {} path",
                session
                    .filters()
                    .first()
                    .map_or("estimated".to_owned(), |r| filter_label(r.kind.name()))
            ),
        ));
    }
    for (index, run) in session.filters().iter().enumerate() {
        let secondary = index > 0;
        let color = palette::estimator_color(run.kind.name());
        let name = filter_label(run.kind.name());
        entries.push(LegendEntry::new(
            vec![
                (Symbol::EstimatedRobot { secondary }, color),
                (Symbol::Line { dashed: secondary }, color),
                (Symbol::EstimatedLandmark { secondary }, color),
            ],
            format!("{name}: robot (95% ellipse, ±2σθ), path, landmarks"),
        ));
        if sigma_points_shown && !super::robot_sigma_points(run.filter()).is_empty() {
            entries.push(LegendEntry::new(
                vec![(Symbol::SigmaPoints, color)],
                format!("{name} sigma points"),
            ));
        }
    }
    if opts.rays {
        entries.push(LegendEntry::new(
            vec![(Symbol::Ray, palette::faded(colors.truth, 0.6))],
            "observation",
        ));
    }
    if opts.fov {
        entries.push(LegendEntry::new(
            vec![(Symbol::FieldOfView, colors.truth)],
            "field of view",
        ));
        if coming_reach(session).is_some() {
            entries.push(LegendEntry::new(
                vec![(
                    Symbol::Line { dashed: true },
                    palette::faded(colors.truth, 0.6),
                )],
                "reach from the next tick",
            ));
        }
    }
    entries.push(LegendEntry {
        symbols: vec![(Symbol::Highlight, palette::VERMILLION)],
        text: "current update".to_owned(),
        highlight: true,
    });
    entries
}

/// Draws the map's key on lines above the map (wrapped when needed): each entry's
/// symbols, then its name. Records its rectangle as a key for the render tests.
fn map_key_ui(ui: &mut egui::Ui, entries: &[LegendEntry], background: Color32) {
    let response = ui
        .horizontal_wrapped(|ui| {
            ui.spacing_mut().item_spacing.x = 3.0;
            let height = ui.text_style_height(&egui::TextStyle::Small).max(14.0);
            let font = egui::TextStyle::Small.resolve(ui.style());
            let row_width = ui.max_rect().width();
            for (k, entry) in entries.iter().enumerate() {
                // An entry's symbols and its text start a new line together when
                // they do not fit on this one.
                let text_width = ui
                    .painter()
                    .layout_no_wrap(entry.text.clone(), font.clone(), Color32::WHITE)
                    .size()
                    .x;
                let width = entry.symbols.len() as f32 * 27.0 + text_width + 3.0;
                let left = ui.available_size_before_wrap().x;
                if width + 8.0 > left && left < row_width - 1.0 {
                    ui.end_row();
                } else if k > 0 {
                    ui.add_space(8.0);
                }
                for (symbol, color) in &entry.symbols {
                    let (rect, _) =
                        ui.allocate_exact_size(vec2(24.0, height), egui::Sense::hover());
                    draw_symbol(
                        &ui.painter_at(rect.expand(2.0)),
                        rect,
                        *symbol,
                        *color,
                        background,
                    );
                }
                let text = egui::RichText::new(&entry.text).small();
                ui.label(if entry.highlight {
                    text.color(palette::VERMILLION)
                } else {
                    text
                });
            }
        })
        .response;
    crate::widgets::plots::record(
        ui.ctx(),
        crate::widgets::plots::FigureRecord {
            title: String::new(),
            data: None,
            key: Some(response.rect),
            map: None,
            image: None,
        },
    );
}

fn format_xy(v: &Vector2<f64>) -> String {
    format!("({:.2}, {:.2}) m", v[0], v[1])
}

/// The tooltip text for what is under the pointer: a landmark (true and estimated),
/// the true robot or an estimated robot.
fn hover_text(t: &MapTransform, session: &LandmarkSession, pointer: Pos2) -> Option<String> {
    let near = |p: Pos2| finite(p) && p.distance(pointer) <= HOVER_RADIUS;
    // Robots first: they sit on top.
    let truth = session.truth();
    if near(t.pose(&truth)) {
        let mut text = format!(
            "True robot\nx = {:.2} m, y = {:.2} m, θ = {:.3} rad ({:.1}°)",
            truth.x,
            truth.y,
            truth.theta,
            truth.theta.to_degrees()
        );
        for run in session.filters() {
            let pose = run.filter().robot_pose();
            let cov = run.filter().robot_covariance();
            text.push_str(&format!(
                "\n{}: ({:.2}, {:.2}) m, θ = {:.3} rad; σx = {:.3} m, σy = {:.3} m, σθ = {:.2}°",
                filter_label(run.kind.name()),
                pose.x,
                pose.y,
                pose.theta,
                cov[(0, 0)].max(0.0).sqrt(),
                cov[(1, 1)].max(0.0).sqrt(),
                cov[(2, 2)].max(0.0).sqrt().to_degrees()
            ));
        }
        return Some(text);
    }
    for run in session.filters() {
        let pose = run.filter().robot_pose();
        if near(t.pose(&pose)) {
            let cov = run.filter().robot_covariance();
            let error = ((truth.x - pose.x).powi(2) + (truth.y - pose.y).powi(2)).sqrt();
            return Some(format!(
                "{} estimate of the robot\nx = {:.2} m, y = {:.2} m, θ = {:.3} rad ({:.1}°)\nσx = {:.3} m, σy = {:.3} m, σθ = {:.3} rad ({:.2}°)\nposition error {:.3} m",
                filter_label(run.kind.name()),
                pose.x,
                pose.y,
                pose.theta,
                pose.theta.to_degrees(),
                cov[(0, 0)].max(0.0).sqrt(),
                cov[(1, 1)].max(0.0).sqrt(),
                cov[(2, 2)].max(0.0).sqrt(),
                cov[(2, 2)].max(0.0).sqrt().to_degrees(),
                error
            ));
        }
    }
    // Landmarks: nearest true landmark or estimate.
    let mut best: Option<(f32, usize)> = None;
    let mut consider = |p: Pos2, id: usize| {
        if near(p) {
            let d = p.distance(pointer);
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, id));
            }
        }
    };
    for landmark in &session.world().landmarks {
        consider(t.v(&landmark.position), landmark.id);
    }
    for run in session.filters() {
        for estimate in run.filter().landmarks() {
            consider(t.v(&estimate.mean), estimate.id);
        }
    }
    let (_, id) = best?;
    let truth_position = session.world().landmark(id).map(|l| l.position);
    let mut text = format!("Landmark {id}");
    if let Some(p) = truth_position {
        text.push_str(&format!("\ntrue position {}", format_xy(&p)));
    }
    for run in session.filters() {
        let name = filter_label(run.kind.name());
        match run.filter().landmarks().into_iter().find(|l| l.id == id) {
            Some(estimate) => {
                text.push_str(&format!(
                    "\n{name}: {}, σx = {:.3} m, σy = {:.3} m",
                    format_xy(&estimate.mean),
                    estimate.covariance[(0, 0)].max(0.0).sqrt(),
                    estimate.covariance[(1, 1)].max(0.0).sqrt()
                ));
                if let Some(p) = truth_position {
                    text.push_str(&format!(", error {:.3} m", (p - estimate.mean).norm()));
                }
            }
            None => text.push_str(&format!("\n{name}: not seen yet")),
        }
    }
    if session.observations().iter().any(|o| o.id == id) {
        text.push_str("\nmeasured this tick");
    }
    Some(text)
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui::pos2;

    #[test]
    fn the_magnification_holds_on_steps_of_two() {
        assert_eq!(steady_magnification(3.0), 2.5);
        assert_eq!(steady_magnification(4.2), 2.5);
        assert_eq!(steady_magnification(2.2), 2.0);
        assert_eq!(steady_magnification(9.9), 5.0);
        assert_eq!(steady_magnification(10.0), 10.0);
        assert_eq!(steady_magnification(50.0), 50.0);
        assert_eq!(
            steady_magnification(1.0),
            1.0,
            "below the least: no inset is drawn"
        );
        assert!(steady_magnification(f32::NAN).is_nan());
    }

    #[test]
    fn the_magnifier_takes_a_free_corner() {
        let map = Rect::from_min_size(pos2(0.0, 0.0), vec2(800.0, 600.0));
        let far = pos2(400.0, 300.0);
        // Nothing in the way: top right.
        let first = magnifier_rect(map, None, far).unwrap();
        assert!(first.right() < map.right() && first.top() < 100.0);
        assert_eq!(first.width(), 180.0);
        // The legend over the top right: bottom right.
        let legend = Rect::from_min_size(pos2(500.0, 20.0), vec2(300.0, 200.0));
        let second = magnifier_rect(map, Some(legend), far).unwrap();
        assert!(second.bottom() > 400.0 && second.right() > 600.0);
        // Never over the true robot.
        let robot = first.center();
        let moved = magnifier_rect(map, None, robot).unwrap();
        assert!(!moved.expand(16.0).contains(robot));
        // A map too small for any corner: no magnifier.
        let tiny = Rect::from_min_size(pos2(0.0, 0.0), vec2(150.0, 120.0));
        assert!(magnifier_rect(tiny, None, far).is_none());
    }
}
