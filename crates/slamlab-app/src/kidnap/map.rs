//! The grid map: the occupancy grid as an image, the true robot with its lidar
//! rays, every filter's particles shaded by weight, and each estimate with its 95%
//! ellipse and heading wedge. A click (with "Kidnap by click" on) teleports the
//! robot there; dragging sets its heading.

use super::{KidnapView, filter_color};
use crate::palette;
use crate::widgets::map_canvas::{
    self, CanvasColors, EstimateStyle, MapTransform, MapView, draw_estimate, draw_grid,
    draw_scale_and_axes, finite, screen_dir,
};
use crate::widgets::particles::ParticleMesh;
use crate::widgets::plots::{KeyEntry, Mark, key_ui};
use egui::{Color32, Shape, Stroke, pos2};
use slamlab_core::grid::{Cell, Costmap, OccupancyGrid};
use slamlab_core::particle::ParticleFlag;
use slamlab_core::{Pose2, math};
use slamlab_sim::kidnap::MclRun;

/// The occupancy grid as a texture, made once per map.
#[derive(Default)]
pub struct GridTexture {
    texture: Option<(egui::TextureHandle, usize)>,
    costmap: Option<(egui::TextureHandle, usize)>,
}

impl std::fmt::Debug for GridTexture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("GridTexture")
    }
}

impl GridTexture {
    /// Forgets the texture (a new map).
    pub fn clear(&mut self) {
        self.texture = None;
        self.costmap = None;
    }

    /// The costmap's invalid zone (free cells closer to a wall than the robot's
    /// radius) in translucent pink, as thesis Fig. 5.1 draws it.
    fn costmap(
        &mut self,
        ctx: &egui::Context,
        grid: &OccupancyGrid,
        costmap: &Costmap,
    ) -> egui::TextureId {
        let (w, h) = costmap.size();
        let key = w * 31 + h * 7 + (costmap.radius() * 1000.0) as usize;
        if let Some((texture, k)) = &self.costmap
            && *k == key
        {
            return texture.id();
        }
        let pink = Color32::from_rgba_unmultiplied(0xFF, 0x69, 0xB4, 110);
        let mut pixels = Vec::with_capacity(w * h);
        for row in 0..h {
            let j = (h - 1 - row) as i64;
            for i in 0..w as i64 {
                let inflated = !costmap.is_valid_cell(i, j) && grid.get(i, j) == Some(Cell::Free);
                pixels.push(if inflated { pink } else { Color32::TRANSPARENT });
            }
        }
        let image = egui::ColorImage::new([w, h], pixels);
        let texture = ctx.load_texture("costmap", image, egui::TextureOptions::NEAREST);
        let id = texture.id();
        self.costmap = Some((texture, key));
        id
    }

    fn get(&mut self, ctx: &egui::Context, grid: &OccupancyGrid, dark: bool) -> egui::TextureId {
        let key = grid.width() * 31 + grid.height() * 7 + usize::from(dark);
        if let Some((texture, k)) = &self.texture
            && *k == key
        {
            return texture.id();
        }
        let (w, h) = (grid.width(), grid.height());
        let (free, occupied, unknown) = if dark {
            (
                Color32::from_gray(40),
                Color32::from_gray(230),
                Color32::from_gray(70),
            )
        } else {
            (
                Color32::WHITE,
                Color32::from_gray(20),
                Color32::from_gray(190),
            )
        };
        let mut pixels = Vec::with_capacity(w * h);
        // Image row 0 is the top (largest y): grid row h - 1.
        for row in 0..h {
            let j = (h - 1 - row) as i64;
            for i in 0..w as i64 {
                pixels.push(match grid.get(i, j) {
                    Some(Cell::Free) => free,
                    Some(Cell::Occupied) => occupied,
                    _ => unknown,
                });
            }
        }
        let image = egui::ColorImage::new([w, h], pixels);
        let texture = ctx.load_texture("occupancy_grid", image, egui::TextureOptions::NEAREST);
        let id = texture.id();
        self.texture = Some((texture, key));
        id
    }
}

/// The world bounds of the grid, `[x_min, y_min, x_max, y_max]`.
pub fn grid_bounds(grid: &OccupancyGrid) -> [f64; 4] {
    let (w, h) = (grid.width() as f64, grid.height() as f64);
    let corners = [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)]
        .map(|(i, j)| grid.grid_frame_to_world(i * grid.resolution(), j * grid.resolution()));
    let xs = corners.map(|c| c.0);
    let ys = corners.map(|c| c.1);
    [
        xs.iter().copied().fold(f64::INFINITY, f64::min),
        ys.iter().copied().fold(f64::INFINITY, f64::min),
        xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        ys.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    ]
}

/// What the map asks the lesson to do after a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MapRequest {
    /// Kidnap the robot to this pose.
    KidnapTo(Pose2),
}

/// Where a click-kidnap started (the press), while the pointer is down.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KidnapDrag {
    start: Option<[f64; 2]>,
}

/// The map toolbar and the map.
pub fn map_ui(
    ui: &mut egui::Ui,
    run: &MclRun,
    canvas: &mut MapView,
    texture: &mut GridTexture,
    view: &mut KidnapView,
    drag: &mut KidnapDrag,
) -> Option<MapRequest> {
    ui.horizontal_wrapped(|ui| {
        ui.label("Map:");
        if map_canvas::zoom_buttons_ui(ui, canvas, "Fit map") {
            view.follow_robot = false;
        }
        ui.checkbox(&mut view.follow_robot, "Follow robot")
            .on_hover_text("Keep the true robot in the middle of the map");
        ui.separator();
        ui.checkbox(&mut view.legend, "Legend");
        ui.checkbox(&mut view.rays, "Lidar")
            .on_hover_text("The lidar's beams as faint rays from the true robot, with their hit points");
        ui.checkbox(&mut view.particles, "Particles");
        ui.checkbox(&mut view.path, "Path");
        ui.checkbox(&mut view.costmap, "Costmap").on_hover_text(
            "Where the robot's centre cannot be: free cells closer to a wall than its radius \
             (pink, as in Fig. 5.1 of Xiang's thesis). CMCL and ACMCL regenerate particles that move into it.",
        );
        ui.separator();
        ui.toggle_value(&mut view.click_kidnap, "Kidnap by click")
            .on_hover_text("Click on the map to teleport the robot there (drag to set its heading). The filters are not told.");
    });
    let grid = run.map().grid();
    let bounds = grid_bounds(grid);
    // A log without truth: the robot is where the first filter thinks it is (the
    // lidar is drawn from there, and Follow follows it).
    let seen_from = run.truth_now().or_else(|| {
        run.filters()
            .first()
            .and_then(|f| f.current_estimate(&run.odometry()))
    });
    let truth = seen_from.unwrap_or(run.robot().pose);
    let mut follow = view.follow_robot.then_some([truth.x, truth.y]);
    if view.legend {
        // The key on a line above the map, never over the maze.
        key_ui(ui, &legend_entries(run, &CanvasColors::of(ui)));
    }
    let (response, t) =
        map_canvas::canvas_ui(ui, canvas, bounds, 0.0, &mut follow, !view.click_kidnap);
    view.follow_robot = follow.is_some();
    let colors = CanvasColors::of(ui);
    let painter = ui.painter_at(t.rect);
    painter.rect_filled(t.rect, 4.0, colors.background);
    draw_grid(&painter, &t, &colors);
    draw_occupancy(ui, &painter, &t, grid, texture);
    if view.costmap {
        draw_costmap(ui, &painter, &t, grid, run.collision_map(), texture);
    }
    if view.path {
        for stretch in run.path_stretches() {
            draw_path(&painter, &t, stretch, colors.truth);
        }
    }
    if view.rays {
        draw_rays(&painter, &t, run, seen_from);
    }
    for (k, f) in run.filters().iter().enumerate() {
        let color = filter_color(k, f.name);
        if view.particles {
            draw_particles(&painter, &t, f.mcl().particles(), color);
        }
        if let Some(e) = f.mcl().estimate() {
            draw_estimate(
                &painter,
                &t,
                &e.pose,
                &e.covariance,
                EstimateStyle {
                    color,
                    ellipse: true,
                    wedge_radius: 26.0,
                    dot: false,
                },
            );
        }
    }
    if run.has_truth() {
        draw_robot(
            &painter,
            &t,
            &truth,
            run.robot().radius,
            colors.truth,
            colors.background,
        );
    }
    draw_scale_and_axes(&painter, &t, &colors);

    // Click-kidnap: press where, drag for the heading, release to teleport.
    let mut request = None;
    if view.click_kidnap {
        if let Some(p) = response.interact_pointer_pos()
            && drag.start.is_none()
            && (response.drag_started() || response.clicked())
        {
            drag.start = Some(t.world_of(p));
        }
        if let Some([x, y]) = drag.start {
            let here = response
                .interact_pointer_pos()
                .or(response.hover_pos())
                .map(|p| t.world_of(p));
            let heading = here
                .filter(|h| math::hypot(h[0] - x, h[1] - y) > 0.05)
                .map_or(truth.theta, |h| math::atan2(h[1] - y, h[0] - x));
            let centre = t.xy(x, y);
            painter.circle_stroke(centre, 8.0, Stroke::new(2.0, palette::VERMILLION));
            painter.arrow(
                centre,
                screen_dir(heading) * 24.0,
                Stroke::new(2.0, palette::VERMILLION),
            );
            if response.drag_stopped() || response.clicked() {
                request = Some(MapRequest::KidnapTo(Pose2::new(x, y, heading)));
                drag.start = None;
            }
        }
    } else {
        drag.start = None;
    }
    if let Some(pointer) = response.hover_pos()
        && drag.start.is_none()
    {
        let [x, y] = t.world_of(pointer);
        let cell = match grid.cell_at(x, y) {
            Some(Cell::Free) => "free",
            Some(Cell::Occupied) => "occupied",
            Some(Cell::Unknown) => "unknown",
            None => "outside the map",
        };
        response.on_hover_ui_at_pointer(|ui| {
            ui.label(format!("({x:.2}, {y:.2}) m: {cell}"));
        });
    }
    request
}

fn draw_occupancy(
    ui: &egui::Ui,
    painter: &egui::Painter,
    t: &MapTransform,
    grid: &OccupancyGrid,
    texture: &mut GridTexture,
) {
    let id = texture.get(ui.ctx(), grid, ui.visuals().dark_mode);
    draw_grid_image(painter, t, grid, id, Color32::from_white_alpha(235));
}

fn draw_costmap(
    ui: &egui::Ui,
    painter: &egui::Painter,
    t: &MapTransform,
    grid: &OccupancyGrid,
    costmap: &Costmap,
    texture: &mut GridTexture,
) {
    let id = texture.costmap(ui.ctx(), grid, costmap);
    draw_grid_image(painter, t, grid, id, Color32::WHITE);
}

/// An image with one pixel per grid cell, placed where the grid lies in the world.
fn draw_grid_image(
    painter: &egui::Painter,
    t: &MapTransform,
    grid: &OccupancyGrid,
    id: egui::TextureId,
    tint: Color32,
) {
    let (w, h) = (
        grid.width() as f64 * grid.resolution(),
        grid.height() as f64 * grid.resolution(),
    );
    // The image's corners in the world (the origin may be rotated), top row first.
    let corner = |gx: f64, gy: f64| {
        let (x, y) = grid.grid_frame_to_world(gx, gy);
        t.xy(x, y)
    };
    let mut mesh = egui::Mesh::with_texture(id);
    mesh.vertices.extend([
        egui::epaint::Vertex {
            pos: corner(0.0, h),
            uv: pos2(0.0, 0.0),
            color: tint,
        },
        egui::epaint::Vertex {
            pos: corner(w, h),
            uv: pos2(1.0, 0.0),
            color: tint,
        },
        egui::epaint::Vertex {
            pos: corner(w, 0.0),
            uv: pos2(1.0, 1.0),
            color: tint,
        },
        egui::epaint::Vertex {
            pos: corner(0.0, 0.0),
            uv: pos2(0.0, 1.0),
            color: tint,
        },
    ]);
    mesh.indices.extend([0, 1, 2, 0, 2, 3]);
    painter.add(Shape::mesh(mesh));
}

fn draw_path(painter: &egui::Painter, t: &MapTransform, path: &[Pose2], color: Color32) {
    let points = t.path(path, 3000);
    if points.len() >= 2 {
        painter.add(Shape::line(
            points,
            Stroke::new(1.2, color.gamma_multiply(0.5)),
        ));
    }
}

fn draw_rays(painter: &egui::Painter, t: &MapTransform, run: &MclRun, seen_from: Option<Pose2>) {
    let Some(scan) = run.scan() else {
        return;
    };
    // From where the scan was taken: after a kidnap the robot is elsewhere until
    // its next move takes a new scan. A log without truth: from the estimate.
    let Some(robot) = run.scan_pose().or(seen_from) else {
        return;
    };
    let from = t.pose(&robot);
    let ray = Stroke::new(0.6, palette::VERMILLION.gamma_multiply(0.25));
    let stride = scan.ranges.len() / 180 + 1;
    for (angle, range) in scan.angles.iter().zip(&scan.ranges).step_by(stride) {
        if !range.is_finite() || *range < 0.0 {
            continue;
        }
        let r = range.min(scan.range_max);
        let a = robot.theta + angle;
        let (s, c) = math::sin_cos(a);
        let end = t.xy(robot.x + r * c, robot.y + r * s);
        painter.line_segment([from, end], ray);
        if *range < scan.range_max {
            painter.circle_filled(end, 1.8, palette::VERMILLION);
        }
    }
}

/// Particles as small darts (one mesh), their opacity by weight relative to the heaviest;
/// injected and regenerated ones in their own colours.
fn draw_particles(
    painter: &egui::Painter,
    t: &MapTransform,
    particles: &[slamlab_core::particle::Particle],
    color: Color32,
) {
    let max_w = particles.iter().map(|p| p.weight).fold(0.0_f64, f64::max);
    let (x0, x1, y0, y1) = t.visible();
    let length = (0.12 * t.scale).clamp(4.0, 10.0);
    let stride = particles.len() / 6000 + 1;
    let mut mesh = ParticleMesh::with_capacity(particles.len() / stride);
    for p in particles.iter().step_by(stride) {
        let pose = p.pose;
        if pose.x < x0 || pose.x > x1 || pose.y < y0 || pose.y > y1 {
            continue;
        }
        let relative = if max_w > 0.0 {
            (p.weight / max_w) as f32
        } else {
            1.0
        };
        let c = match p.flag {
            ParticleFlag::Normal => color.gamma_multiply(0.15 + 0.85 * relative.sqrt()),
            ParticleFlag::Injected => palette::VERMILLION,
            ParticleFlag::Regenerated => palette::SKY_BLUE,
        };
        mesh.dart(t.pose(&pose), screen_dir(pose.theta), length, c);
    }
    mesh.paint(painter);
}

fn draw_robot(
    painter: &egui::Painter,
    t: &MapTransform,
    pose: &Pose2,
    radius: f64,
    color: Color32,
    background: Color32,
) {
    let at = t.pose(pose);
    if !finite(at) {
        return;
    }
    let r = ((radius as f32) * t.scale).max(6.0);
    painter.circle(
        at,
        r,
        background.gamma_multiply(0.6),
        Stroke::new(2.0, color),
    );
    painter.line_segment(
        [at, at + screen_dir(pose.theta) * r * 1.4],
        Stroke::new(2.5, color),
    );
}

/// The map's key: the truth, the lidar, each filter's particles and estimate,
/// and (with Augmented or costmap-aware filters) the costmap and the particles
/// drawn anew.
fn legend_entries(run: &MclRun, colors: &CanvasColors) -> Vec<KeyEntry> {
    let mut rows = if run.has_truth() {
        vec![
            KeyEntry::new("true robot and path", colors.truth, Mark::Solid),
            KeyEntry::new("lidar rays and hits", palette::VERMILLION, Mark::Solid),
        ]
    } else {
        vec![KeyEntry::new(
            "lidar from the first estimate (no truth)",
            palette::VERMILLION,
            Mark::Solid,
        )]
    };
    for (k, f) in run.filters().iter().enumerate() {
        rows.push(KeyEntry::new(
            format!(
                "{}: particles, estimate, 95% ellipse",
                f.name.to_uppercase()
            ),
            filter_color(k, f.name),
            Mark::Dots,
        ));
    }
    rows.push(KeyEntry::new(
        "a darker particle weighs more",
        colors.weak_text,
        Mark::Dots,
    ));
    if run.filters().iter().any(|f| f.name != "mcl") {
        rows.push(KeyEntry::new(
            "costmap: too close to a wall (toggle)",
            Color32::from_rgb(0xFF, 0x69, 0xB4),
            Mark::Solid,
        ));
        rows.push(KeyEntry::new(
            "injected particles (AMCL)",
            palette::VERMILLION,
            Mark::Dots,
        ));
        rows.push(KeyEntry::new(
            "regenerated particles (CMCL, ACMCL)",
            palette::SKY_BLUE,
            Mark::Dots,
        ));
    }
    rows
}
