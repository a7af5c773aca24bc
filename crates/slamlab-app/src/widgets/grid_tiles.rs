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
        for (texture, square) in self.update(ctx, grid) {
            let Some(corners) = screen_corners(t, world_from_grid, square) else {
                continue;
            };
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

/// The screen corners of the square `[x0, y0, x1, y1]` of a grid whose frame is
/// at `world_from_grid` (counter-clockwise from the lower left in the grid), or
/// `None` when it is off the canvas or not finite.
fn screen_corners(
    t: &MapTransform,
    world_from_grid: &Pose2,
    [x0, y0, x1, y1]: [f64; 4],
) -> Option<[Pos2; 4]> {
    let corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)].map(|(x, y)| {
        let w = world_from_grid.transform_point(&nalgebra::Vector2::new(x, y));
        t.xy(w.x, w.y)
    });
    let bounds = egui::Rect::from_points(&corners);
    (bounds.intersects(t.rect) && corners.iter().all(|p| map_canvas::finite(*p))).then_some(corners)
}

/// Tiles a texture page holds along each side: 32 tiles of 32 cells, 1,024
/// pixels (WebGL guarantees at least 4,096), 1,024 tiles a page.
const PAGE_TILES: usize = 32;

/// Where one tile's image sits: its page and its column and row there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Slot {
    page: usize,
    column: usize,
    row: usize,
}

/// The tiles of many grids (a Cartographer run's hundreds of submaps) packed
/// into a few large textures, so that every grid draws in a handful of meshes.
///
/// Each tile of [`GridTiles`] is a texture of its own and so a draw call of its
/// own: the Intel log's 229 submaps are some 10,000 tiles, and the browser's
/// WebGL spends far longer on 10,000 draw calls a frame than on the triangles.
/// Here a tile is a 32 x 32 slot of a 1,024 x 1,024 page, written in place when a
/// scan changes it (a partial texture update), and the grids are drawn in order
/// (a newer one covers the overlap) as one mesh per run of tiles on the same page.
#[derive(Default)]
pub struct GridAtlas {
    pages: Vec<egui::TextureHandle>,
    /// Slots given back by tiles that are gone (a step back, fewer grids).
    free: Vec<Slot>,
    /// Slots handed out from the pages so far, in order.
    issued: usize,
    /// Per grid: each tile's slot and the revision it shows.
    grids: Vec<HashMap<(i64, i64), (Slot, u64)>>,
    /// Tile images written to the pages so far.
    written: usize,
}

impl std::fmt::Debug for GridAtlas {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let tiles: usize = self.grids.iter().map(HashMap::len).sum();
        write!(
            f,
            "GridAtlas({} grids, {tiles} tiles on {} pages)",
            self.grids.len(),
            self.pages.len()
        )
    }
}

impl GridAtlas {
    /// Forgets every grid and texture (a new run).
    pub fn clear(&mut self) {
        *self = Self::default();
    }

    /// A free slot, on a new page when every page is full.
    fn allocate(&mut self, ctx: &egui::Context) -> Slot {
        if let Some(slot) = self.free.pop() {
            return slot;
        }
        let per_page = PAGE_TILES * PAGE_TILES;
        let (page, k) = (self.issued / per_page, self.issued % per_page);
        if page == self.pages.len() {
            let side = PAGE_TILES * TILE;
            let blank =
                egui::ColorImage::new([side, side], vec![Color32::TRANSPARENT; side * side]);
            self.pages.push(ctx.load_texture(
                format!("grid-atlas-{page}"),
                blank,
                egui::TextureOptions::NEAREST,
            ));
        }
        self.issued += 1;
        Slot {
            page,
            column: k % PAGE_TILES,
            row: k / PAGE_TILES,
        }
    }

    /// Brings grid `index`'s slots up to date with `grid` (only tiles whose
    /// revision changed are written) and returns its tiles' slots and squares in
    /// the grid's frame, grouped by page.
    fn update(
        &mut self,
        ctx: &egui::Context,
        index: usize,
        grid: &ProbabilityGrid,
    ) -> Vec<(Slot, [f64; 4])> {
        if self.grids.len() <= index {
            self.grids.resize_with(index + 1, HashMap::new);
        }
        let side = TILE as f64 * grid.resolution();
        let mut out = Vec::new();
        for (ti, tj, revision) in grid.tile_revisions() {
            let known = self.grids[index].get(&(ti, tj)).copied();
            if known.is_none_or(|(_, rev)| rev != revision)
                && let Some(cells) = grid.tile_cells(ti, tj)
            {
                let slot = match known {
                    Some((slot, _)) => slot,
                    None => self.allocate(ctx),
                };
                if let Some(page) = self.pages.get_mut(slot.page) {
                    page.set_partial(
                        [slot.column * TILE, slot.row * TILE],
                        tile_image(cells),
                        egui::TextureOptions::NEAREST,
                    );
                    self.written += 1;
                }
                self.grids[index].insert((ti, tj), (slot, revision));
            }
            if let Some((slot, _)) = self.grids[index].get(&(ti, tj)) {
                let (x0, y0) = (ti as f64 * side, tj as f64 * side);
                out.push((*slot, [x0, y0, x0 + side, y0 + side]));
            }
        }
        // After a step back or a restart some tiles are gone (more slots than
        // tiles drawn): their slots are free. Tiles only come otherwise, so the
        // set of live tiles is built only then, not every frame.
        if self.grids[index].len() > out.len() {
            let live: std::collections::HashSet<(i64, i64)> =
                grid.tile_revisions().map(|(ti, tj, _)| (ti, tj)).collect();
            let free = &mut self.free;
            self.grids[index].retain(|key, (slot, _)| {
                let keep = live.contains(key);
                if !keep {
                    free.push(*slot);
                }
                keep
            });
        }
        // A grid's tiles do not overlap: drawn page by page they need fewer meshes.
        out.sort_by_key(|(slot, _)| slot.page);
        out
    }

    /// Draws `grids` in order (a later one covers an earlier one), each with its
    /// frame in the world and the tint its greys are multiplied by. Grids past the
    /// last given are forgotten.
    pub fn draw<'g>(
        &mut self,
        ctx: &egui::Context,
        painter: &egui::Painter,
        t: &MapTransform,
        grids: impl Iterator<Item = (&'g ProbabilityGrid, Pose2, Color32)>,
    ) {
        let mut mesh: Option<(usize, egui::Mesh)> = None;
        let flush = |mesh: &mut Option<(usize, egui::Mesh)>| {
            if let Some((_, m)) = mesh.take()
                && !m.is_empty()
            {
                painter.add(egui::Shape::mesh(m));
            }
        };
        let mut count = 0;
        let uv_side = 1.0 / PAGE_TILES as f32;
        for (index, (grid, world_from_grid, tint)) in grids.enumerate() {
            count = index + 1;
            for (slot, square) in self.update(ctx, index, grid) {
                let Some(corners) = screen_corners(t, &world_from_grid, square) else {
                    continue;
                };
                let Some(page) = self.pages.get(slot.page) else {
                    continue;
                };
                if mesh.as_ref().is_none_or(|(p, _)| *p != slot.page) {
                    flush(&mut mesh);
                    mesh = Some((slot.page, egui::Mesh::with_texture(page.id())));
                }
                let Some((_, m)) = mesh.as_mut() else {
                    continue;
                };
                // The slot's corners in the page; image rows run top down, grid rows
                // bottom up, as in `GridTiles::draw`.
                let (u0, v0) = (slot.column as f32 * uv_side, slot.row as f32 * uv_side);
                let (u1, v1) = (u0 + uv_side, v0 + uv_side);
                let uv = [
                    Pos2::new(u0, v1),
                    Pos2::new(u1, v1),
                    Pos2::new(u1, v0),
                    Pos2::new(u0, v0),
                ];
                let base = m.vertices.len() as u32;
                for (pos, uv) in corners.into_iter().zip(uv) {
                    m.vertices.push(egui::epaint::Vertex {
                        pos,
                        uv,
                        color: tint,
                    });
                }
                m.add_triangle(base, base + 1, base + 2);
                m.add_triangle(base, base + 2, base + 3);
            }
        }
        flush(&mut mesh);
        for gone in self.grids.drain(count.min(self.grids.len())..) {
            self.free.extend(gone.into_values().map(|(slot, _)| slot));
        }
    }

    /// Texture pages made so far (each holds 1,024 tiles).
    pub fn pages(&self) -> usize {
        self.pages.len()
    }

    /// Tile images written to the pages so far (a tile is written when it first
    /// appears and again only when a scan changed it).
    pub fn tiles_written(&self) -> usize {
        self.written
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

#[cfg(test)]
mod tests {
    use super::*;
    use slamlab_core::grid::InsertParams;
    use slamlab_core::laser::Scan;

    /// A grid that has seen one full circle of 20 m beams from `at`: some forty
    /// tiles at 5 cm.
    fn grid_seen_from(at: Pose2) -> ProbabilityGrid {
        let n = 360;
        let scan = Scan {
            angles: (0..n)
                .map(|k| k as f64 * std::f64::consts::TAU / n as f64)
                .collect(),
            ranges: vec![4.0; n],
            range_min: 0.1,
            range_max: 20.0,
        };
        let mut grid = ProbabilityGrid::new(0.05);
        let inserted = grid.insert_scan(&at, &scan, &InsertParams::default());
        assert!(inserted.is_ok(), "{inserted:?}");
        grid
    }

    /// Draws `grids` through `atlas` in one frame of `ctx`; returns the meshes
    /// (their texture and triangle count) and the tiles written.
    fn frame(
        ctx: &egui::Context,
        atlas: &mut GridAtlas,
        grids: &[ProbabilityGrid],
    ) -> (Vec<(egui::TextureId, usize)>, usize) {
        let written = atlas.tiles_written();
        let output = ctx.run_ui(egui::RawInput::default(), |ui| {
            let rect = egui::Rect::from_min_size(Pos2::ZERO, egui::vec2(800.0, 600.0));
            let t = MapTransform {
                rect,
                center: [0.0, 0.0],
                scale: 20.0,
            };
            let painter = ui.painter_at(rect);
            let tints = [Color32::WHITE, Color32::LIGHT_BLUE];
            atlas.draw(
                ui.ctx(),
                &painter,
                &t,
                grids
                    .iter()
                    .enumerate()
                    .map(|(k, g)| (g, Pose2::new(0.0, 0.0, 0.0), tints[k % 2])),
            );
        });
        let meshes = output
            .shapes
            .iter()
            .filter_map(|c| match &c.shape {
                egui::Shape::Mesh(m) => Some((m.texture_id, m.indices.len() / 3)),
                _ => None,
            })
            .collect();
        let mut delta = output.textures_delta;
        delta.clear();
        (meshes, atlas.tiles_written() - written)
    }

    #[test]
    fn many_grids_draw_as_one_mesh_per_page_and_only_changed_tiles_are_written() {
        let grids: Vec<ProbabilityGrid> = (0..6)
            .map(|k| grid_seen_from(Pose2::new(k as f64, 0.5 * k as f64, 0.0)))
            .collect();
        let tiles: usize = grids.iter().map(|g| g.tile_revisions().count()).sum();
        assert!(tiles > 100, "{tiles} tiles");
        let ctx = egui::Context::default();
        let mut atlas = GridAtlas::default();
        let (meshes, written) = frame(&ctx, &mut atlas, &grids);
        // One page (1,024 slots) holds them all: one mesh, two triangles a tile.
        assert_eq!(atlas.pages(), 1);
        assert_eq!(meshes.len(), 1, "{meshes:?}");
        assert_eq!(meshes[0].1, 2 * tiles);
        assert_eq!(written, tiles);
        // Nothing changed: nothing written again.
        let (meshes, written) = frame(&ctx, &mut atlas, &grids);
        assert_eq!((meshes.len(), written), (1, 0));
        // One grid changed: only its changed tiles are written.
        let mut changed = grids.clone();
        changed[2] = grid_seen_from(Pose2::new(2.0, 1.0, 0.5));
        let (_, written) = frame(&ctx, &mut atlas, &changed);
        assert!(
            written > 0 && written <= changed[2].tile_revisions().count(),
            "{written}"
        );
        // The tiles the changed grid no longer has gave their slots back.
        let now: usize = changed.iter().map(|g| g.tile_revisions().count()).sum();
        assert_eq!(
            format!("{atlas:?}"),
            format!("GridAtlas(6 grids, {now} tiles on 1 pages)")
        );
        // Fewer grids: the others' slots are freed and reused, no new page.
        let (meshes, _) = frame(&ctx, &mut atlas, &grids[..2]);
        let two: usize = grids[..2].iter().map(|g| g.tile_revisions().count()).sum();
        assert_eq!(meshes.iter().map(|m| m.1).sum::<usize>(), 2 * two);
        let (_, written) = frame(&ctx, &mut atlas, &grids);
        assert_eq!(written, tiles - two, "the four grids back, in freed slots");
        assert_eq!(atlas.pages(), 1);
    }

    #[test]
    fn a_second_page_opens_when_the_first_is_full() {
        // Enough grids for more than 1,024 tiles: two pages, and the grids still
        // draw in order, one mesh per run of tiles on one page.
        let grids: Vec<ProbabilityGrid> = (0..40)
            .map(|k| grid_seen_from(Pose2::new(10.0 * k as f64, 0.0, 0.0)))
            .collect();
        let tiles: usize = grids.iter().map(|g| g.tile_revisions().count()).sum();
        assert!(tiles > 1024, "{tiles} tiles");
        let ctx = egui::Context::default();
        let mut atlas = GridAtlas::default();
        frame(&ctx, &mut atlas, &grids);
        assert_eq!(atlas.pages(), tiles.div_ceil(1024));
        assert_eq!(atlas.tiles_written(), tiles);
    }
}
