//! A probability grid drawn as tiles of textures (a tile is redrawn only when
//! a scan changed it), straight or under a rigid motion (a submap drawn at its
//! pose in the global frame), tinted on request; and a path as one polyline.

use crate::widgets::map_canvas::{self, MapTransform};
use egui::{Color32, Pos2, Stroke};
use slamlab_core::Pose2;
use slamlab_core::grid::{ProbabilityGrid, TILE, probability};
use slamlab_core::math;
use std::collections::HashMap;

/// Textures of a grid's tiles, each with the revision it shows.
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
    /// changed are redrawn) and returns each tile's texture and square in the
    /// grid's frame.
    pub fn update(
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
                            format!("grid-tile-{ti}-{tj}"),
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

    /// Draws `grid` with its frame at `world_from_grid` in the world,
    /// multiplying each cell's grey by `tint` (white: as it is).
    pub fn draw(
        &mut self,
        ctx: &egui::Context,
        painter: &egui::Painter,
        t: &MapTransform,
        grid: &ProbabilityGrid,
        world_from_grid: &Pose2,
        tint: Color32,
    ) {
        let uv = [
            Pos2::new(0.0, 1.0),
            Pos2::new(1.0, 1.0),
            Pos2::new(1.0, 0.0),
            Pos2::new(0.0, 0.0),
        ];
        for (texture, [x0, y0, x1, y1]) in self.update(ctx, grid) {
            let corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)].map(|(x, y)| {
                let w = world_from_grid.transform_point(&nalgebra::Vector2::new(x, y));
                t.xy(w.x, w.y)
            });
            let bounds = egui::Rect::from_points(&corners);
            if !bounds.intersects(t.rect) || !corners.iter().all(|p| map_canvas::finite(*p)) {
                continue;
            }
            let mut mesh = egui::Mesh::with_texture(texture);
            for (p, uv) in corners.iter().zip(uv) {
                mesh.vertices.push(egui::epaint::Vertex {
                    pos: *p,
                    uv,
                    color: tint,
                });
            }
            mesh.add_triangle(0, 1, 2);
            mesh.add_triangle(0, 2, 3);
            painter.add(egui::Shape::mesh(mesh));
        }
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

/// A path as a polyline, thinned to at most a few thousand points.
pub fn draw_path(
    painter: &egui::Painter,
    t: &MapTransform,
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

/// The rays and end points of `scan` taken at `pose`, and the robot there (a
/// disc with a heading line in `color`).
pub fn draw_scan_and_robot(
    painter: &egui::Painter,
    t: &MapTransform,
    scan: Option<&slamlab_core::scan::Scan>,
    pose: &Pose2,
    color: Color32,
) {
    if let Some(scan) = scan {
        let origin = t.xy(pose.x, pose.y);
        let ray = Color32::from_rgba_unmultiplied(0xD5, 0x5E, 0x00, 40);
        for k in 0..scan.len() {
            let hit = scan.is_end_point(k);
            if !hit && !scan.is_max_range(k) {
                continue;
            }
            let range = if hit {
                scan.ranges[k]
            } else {
                scan.range_max.min(30.0)
            };
            let (s, c) = math::sin_cos(pose.theta + scan.angles[k]);
            let end = t.xy(pose.x + range * c, pose.y + range * s);
            painter.line_segment([origin, end], Stroke::new(0.6, ray));
            if hit {
                painter.circle_filled(end, 1.6, crate::palette::VERMILLION);
            }
        }
    }
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
