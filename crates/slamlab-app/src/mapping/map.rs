//! The map being built: the probability grid as tiles of textures (a tile is
//! redrawn only when a scan changed it), the true map faintly underneath on
//! request, the estimated and true paths, and the current scan's rays and
//! hit points from where it is placed now.

use super::MappingView;
use crate::palette;
use crate::widgets::map_canvas::{self, CanvasColors, MapView, draw_grid, draw_scale_and_axes};
use egui::{Color32, Pos2, Stroke};
use slamlab_core::grid::{ProbabilityGrid, TILE, probability};
use slamlab_core::math;
use slamlab_sim::mapping::{MappingSession, PoseSource};
use std::collections::HashMap;

/// Textures of the grid's tiles, each with the revision it shows.
#[derive(Default)]
pub struct GridTiles {
    tiles: HashMap<(i64, i64), (egui::TextureHandle, u64)>,
}

impl std::fmt::Debug for GridTiles {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "GridTiles({} textures)", self.tiles.len())
    }
}

impl GridTiles {
    /// Forgets every texture (a new map).
    pub fn clear(&mut self) {
        self.tiles.clear();
    }

    /// Brings the textures up to date with `grid` (only tiles whose revision
    /// changed are redrawn) and returns each tile's texture and world square.
    fn update(
        &mut self,
        ctx: &egui::Context,
        grid: &ProbabilityGrid,
    ) -> Vec<(egui::TextureId, [f64; 4])> {
        let r = grid.resolution();
        let side = TILE as f64 * r;
        let mut out = Vec::new();
        let mut live = std::collections::HashSet::new();
        for (ti, tj, revision) in grid.tile_revisions() {
            live.insert((ti, tj));
            let stale = self
                .tiles
                .get(&(ti, tj))
                .is_none_or(|(_, rev)| *rev != revision);
            if stale && let Some(cells) = grid.tile_cells(ti, tj) {
                let image = tile_image(cells);
                match self.tiles.get_mut(&(ti, tj)) {
                    Some((handle, rev)) => {
                        handle.set(image, egui::TextureOptions::NEAREST);
                        *rev = revision;
                    }
                    None => {
                        let handle = ctx.load_texture(
                            format!("mapping-tile-{ti}-{tj}"),
                            image,
                            egui::TextureOptions::NEAREST,
                        );
                        self.tiles.insert((ti, tj), (handle, revision));
                    }
                }
            }
            if let Some((handle, _)) = self.tiles.get(&(ti, tj)) {
                let (x0, y0) = (ti as f64 * side, tj as f64 * side);
                out.push((handle.id(), [x0, y0, x0 + side, y0 + side]));
            }
        }
        // After a step back or a restart some tiles are gone.
        self.tiles.retain(|k, _| live.contains(k));
        out
    }
}

/// A tile's cells as an image: unknown transparent, free white, occupied
/// black, greys between (the probability of occupancy).
fn tile_image(cells: &[f32]) -> egui::ColorImage {
    let mut pixels = Vec::with_capacity(TILE * TILE);
    // Image rows run top down; grid rows bottom up.
    for row in 0..TILE {
        let j = TILE - 1 - row;
        for i in 0..TILE {
            let l = cells[j * TILE + i];
            pixels.push(if l.is_nan() {
                Color32::TRANSPARENT
            } else {
                let p = probability(f64::from(l));
                let v = (255.0 * (1.0 - p)).round().clamp(0.0, 255.0) as u8;
                Color32::from_gray(v)
            });
        }
    }
    egui::ColorImage::new([TILE, TILE], pixels)
}

/// The colour of a pose source's path.
pub fn source_color(source: PoseSource) -> Color32 {
    match source {
        PoseSource::Truth => palette::SKY_BLUE,
        PoseSource::Odometry => palette::DEAD_RECKONING,
        PoseSource::Icp => palette::ORANGE,
        PoseSource::Plicp => palette::VERMILLION,
        PoseSource::ScanToMap => palette::BLUE,
        PoseSource::GridFastSlam => palette::GREEN,
    }
}

/// The map's world bounds to fit: the true map's when there is one, else the
/// built map's, else a few metres around the first scan.
fn bounds(session: &MappingSession) -> [f64; 4] {
    let sim = session.sim();
    if let Some(map) = &sim.input().true_map {
        let o = map.origin();
        let (w, h) = map.size_m();
        return [o.x, o.y, o.x + w, o.y + h];
    }
    let grid = sim.grid();
    if let Some((i0, j0, i1, j1)) = grid.known_bounds() {
        let r = grid.resolution();
        return [
            i0 as f64 * r,
            j0 as f64 * r,
            (i1 + 1) as f64 * r,
            (j1 + 1) as f64 * r,
        ];
    }
    let p = sim
        .input()
        .scans
        .first()
        .map_or([0.0, 0.0], |s| [s.odometry.x, s.odometry.y]);
    [p[0] - 5.0, p[1] - 5.0, p[0] + 5.0, p[1] + 5.0]
}

/// The colour of the shown particle's path (grid FastSLAM).
pub const SHOWN_PARTICLE: Color32 = palette::PURPLE;

/// The map with its toolbar, showing `grid` (the run's map, or with grid
/// FastSLAM the map the student chose) with `shown_particle`'s path
/// highlighted. Returns the particle the student clicked, if any.
#[allow(clippy::too_many_arguments)]
pub fn map_ui(
    ui: &mut egui::Ui,
    session: &MappingSession,
    canvas: &mut MapView,
    tiles: &mut GridTiles,
    view: &mut MappingView,
    beam: Option<usize>,
    grid: &ProbabilityGrid,
    shown_particle: Option<usize>,
) -> Option<usize> {
    let sim = session.sim();
    let has_truth = sim.input().truth.is_some();
    ui.horizontal_wrapped(|ui| {
        ui.label("Map:");
        if map_canvas::zoom_buttons_ui(ui, canvas, "Fit map") {
            view.follow_robot = false;
        }
        ui.checkbox(&mut view.follow_robot, "Follow robot");
        ui.separator();
        ui.checkbox(&mut view.legend, "Legend");
        ui.checkbox(&mut view.scan, "Scan")
            .on_hover_text("The current scan's beams and end points, placed at its pose now");
        ui.checkbox(&mut view.path, "Path");
        if has_truth {
            ui.checkbox(&mut view.truth, "True path");
            ui.checkbox(&mut view.true_map, "True map").on_hover_text(
                "The map the simulated robot drives in, faint, under the one being built",
            );
        }
    });
    let source = sim.source();
    let color = source_color(source);
    let filter = sim.grid_fastslam();
    if view.legend {
        ui.horizontal_wrapped(|ui| {
            if filter.is_some() {
                ui.label(
                    egui::RichText::new("— · particles' paths and poses (darker: heavier)")
                        .color(color)
                        .strong(),
                );
                if matches!(
                    session.stepper().last_phase(),
                    Some(slamlab_sim::mapping::MappingPhase::GridParticle { .. })
                ) {
                    ui.label(
                        egui::RichText::new("one particle's proposal: prediction (small circle) — scan match — pose drawn (ring)")
                            .color(palette::ORANGE)
                            .strong(),
                    );
                }
                if shown_particle.is_some() {
                    ui.label(
                        egui::RichText::new("— the shown map's particle")
                            .color(SHOWN_PARTICLE)
                            .strong(),
                    );
                }
            } else {
                ui.label(
                    egui::RichText::new(format!("— path ({})", source.label()))
                        .color(color)
                        .strong(),
                );
            }
            if has_truth && view.truth {
                ui.label(egui::RichText::new("— true path").strong());
            }
            ui.label(
                egui::RichText::new("· scan end points")
                    .color(palette::VERMILLION)
                    .strong(),
            );
            ui.label("cells: white free, black occupied, grey uncertain, none unknown");
        });
    }
    let records = session.stepper().records();
    let current = sim.current();
    let mut follow = view
        .follow_robot
        .then(|| current.map(|(_, _, p)| [p.x, p.y]))
        .flatten();
    let following = follow.is_some();
    let (response, t) = map_canvas::canvas_ui(ui, canvas, bounds(session), 0.0, &mut follow, true);
    let clicked = filter.and_then(|f| {
        let at = response
            .interact_pointer_pos()
            .filter(|_| response.clicked())?;
        super::particles::particle_at(&t, f, at, 12.0)
    });
    if following {
        // Dragging the map stops following.
        view.follow_robot = follow.is_some();
    }
    let colors = CanvasColors::of(ui);
    let painter = ui.painter_at(t.rect);
    painter.rect_filled(t.rect, 4.0, colors.background);
    draw_grid(&painter, &t, &colors);
    if view.true_map
        && let Some(map) = &sim.input().true_map
    {
        // The occupied cells of the true map as faint dots.
        let r = map.resolution();
        let (x0, y0, x1, y1) = t.visible();
        let size = (r as f32 * t.scale).max(1.0);
        let faint = Color32::from_rgba_unmultiplied(0x56, 0xB4, 0xE9, 90);
        let (i0, j0) = map.world_to_cell(x0, y0);
        let (i1, j1) = map.world_to_cell(x1, y1);
        let step = ((1.0 / size).ceil() as i64).max(1);
        for j in (j0.max(0)..=j1.min(map.height() as i64 - 1)).step_by(step as usize) {
            for i in (i0.max(0)..=i1.min(map.width() as i64 - 1)).step_by(step as usize) {
                if map.is_occupied(i, j) {
                    let (x, y) = map.cell_center(i, j);
                    painter.rect_filled(
                        egui::Rect::from_center_size(t.xy(x, y), egui::vec2(size, size)),
                        0.0,
                        faint,
                    );
                }
            }
        }
    }
    let mesh_color = Color32::WHITE;
    for (texture, [x0, y0, x1, y1]) in tiles.update(ui.ctx(), grid) {
        let rect = egui::Rect::from_two_pos(t.xy(x0, y1), t.xy(x1, y0));
        if rect.intersects(t.rect) {
            painter.image(
                texture,
                rect,
                egui::Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
                mesh_color,
            );
        }
    }
    if has_truth
        && view.truth
        && let Some(truth) = &sim.input().truth
    {
        let n = records.poses.len().min(truth.len());
        draw_path(
            &painter,
            &t,
            truth[..n].iter().map(|p| [p.x, p.y]),
            colors.truth,
            1.2,
        );
    }
    if view.path
        && let Some(filter) = filter
    {
        super::particles::draw_particles(
            &painter,
            &t,
            filter,
            shown_particle,
            color,
            SHOWN_PARTICLE,
        );
    } else if view.path {
        draw_path(
            &painter,
            &t,
            records.poses.iter().map(|p| [p.x, p.y]),
            color,
            1.6,
        );
    }
    super::inspect::draw_beam(&painter, &t, session, beam);
    super::inspect::draw_correspondences(&painter, &t, session);
    if let Some((_, scan, pose)) = current {
        if view.scan && beam.is_none() {
            let origin = t.xy(pose.x, pose.y);
            let ray = Color32::from_rgba_unmultiplied(0xD5, 0x5E, 0x00, 40);
            for k in 0..scan.scan.len() {
                let hit = scan.scan.is_end_point(k);
                if !hit && !scan.scan.is_max_range(k) {
                    continue;
                }
                let range = if hit {
                    scan.scan.ranges[k]
                } else {
                    scan.scan.range_max.min(30.0)
                };
                let (s, c) = math::sin_cos(pose.theta + scan.scan.angles[k]);
                let end = t.xy(pose.x + range * c, pose.y + range * s);
                painter.line_segment([origin, end], Stroke::new(0.6, ray));
                if hit {
                    painter.circle_filled(end, 1.6, palette::VERMILLION);
                }
            }
        }
        // The robot: a disc with a heading line.
        let centre = t.xy(pose.x, pose.y);
        let radius = (0.2 * t.scale).max(4.0);
        painter.circle(
            centre,
            radius,
            Color32::from_rgba_unmultiplied(0x00, 0x72, 0xB2, 60),
            Stroke::new(1.5, color),
        );
        let head = centre + map_canvas::screen_dir(pose.theta) * radius * 1.6;
        painter.line_segment([centre, head], Stroke::new(2.0, color));
    }
    // One particle's proposal, on top of the robot (its moves are centimetres).
    if view.path
        && let Some(filter) = filter
        && let Some(slamlab_sim::mapping::MappingPhase::GridParticle { particle, .. }) =
            session.stepper().last_phase()
    {
        super::particles::draw_proposal(&painter, &t, filter, *particle, palette::ORANGE);
    }
    draw_scale_and_axes(&painter, &t, &colors);
    clicked
}

/// A path as a polyline, thinned to at most a few thousand points.
fn draw_path(
    painter: &egui::Painter,
    t: &map_canvas::MapTransform,
    points: impl ExactSizeIterator<Item = [f64; 2]>,
    color: Color32,
    width: f32,
) {
    let n = points.len();
    let step = (n / 4000).max(1);
    let line: Vec<Pos2> = points
        .enumerate()
        .filter(|(k, _)| k % step == 0 || *k + 1 == n)
        .map(|(_, p)| t.xy(p[0], p[1]))
        .filter(|p| map_canvas::finite(*p))
        .collect();
    if line.len() >= 2 {
        painter.add(egui::Shape::line(line, Stroke::new(width, color)));
    }
}
