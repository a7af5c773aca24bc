//! The global map: every submap at its pose in the global frame, each in its
//! own tint; the trajectory nodes in their trajectory's colour; the
//! intra-submap constraints (thin, grey) and the loop closures (green, as the
//! thesis's Fig. 5.12); the robot and its scan. And the window of Fig. 5.7:
//! a finished submap's precomputed max grids.

use super::CartographerView;
use crate::palette;
use crate::widgets::grid_tiles::{GridAtlas, draw_scan_and_robot};
use crate::widgets::map_canvas::{self, CanvasColors, MapView, draw_grid, draw_scale_and_axes};
use crate::widgets::particles::ParticleMesh;
use crate::widgets::reference_track::ReferenceTrack;
use egui::{Color32, Stroke};
use slamlab_core::Pose2;
use slamlab_core::scan::branch_and_bound::cell_probability;
use slamlab_sim::cartographer::{CartographerSim, ConstraintKind};

/// The colour of trajectory `t` (the first blue, the one after a kidnap
/// orange, ...).
pub fn trajectory_color(t: usize) -> Color32 {
    [
        palette::BLUE,
        palette::ORANGE,
        palette::PURPLE,
        palette::SKY_BLUE,
        palette::VERMILLION,
    ][t % 5]
}

/// The tint of submap `s`: light colours in turn, so that neighbouring
/// submaps differ and black walls stay black.
pub fn submap_tint(s: usize) -> Color32 {
    [
        Color32::from_rgb(0xC6, 0xE2, 0xF5),
        Color32::from_rgb(0xFA, 0xE3, 0xB0),
        Color32::from_rgb(0xBF, 0xEB, 0xDB),
        Color32::from_rgb(0xF2, 0xCF, 0xE2),
        Color32::from_rgb(0xF8, 0xF3, 0xBE),
        Color32::from_rgb(0xF5, 0xD2, 0xB8),
    ][s % 6]
}

/// The loop closures' colour (thesis Fig. 5.12).
pub const LOOP_CLOSURE: Color32 = palette::GREEN;

/// Textures of every submap's tiles, packed into a few pages.
pub type SubmapTiles = GridAtlas;

/// The world bounds to fit: the true map's, or the submaps' known cells.
fn bounds(sim: &CartographerSim) -> [f64; 4] {
    if let Some(map) = &sim.input().true_map {
        let o = map.origin();
        let (w, h) = map.size_m();
        return [o.x, o.y, o.x + w, o.y + h];
    }
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for n in &sim.nodes {
        let p = n.global_pose;
        b = [b[0].min(p.x), b[1].min(p.y), b[2].max(p.x), b[3].max(p.y)];
    }
    if b[0].is_finite() {
        return [b[0] - 6.0, b[1] - 6.0, b[2] + 6.0, b[3] + 6.0];
    }
    let p = sim
        .input()
        .scans
        .first()
        .map_or([0.0, 0.0], |s| [s.odometry.x, s.odometry.y]);
    [p[0] - 8.0, p[1] - 8.0, p[0] + 8.0, p[1] + 8.0]
}

/// Where a submap's grid frame is in the global frame: its global pose
/// after its local pose undone (its cells are in the trajectory's frame).
fn world_from_grid(sim: &CartographerSim, s: usize) -> Pose2 {
    let submap = &sim.submaps[s];
    submap.global_pose.compose(&submap.local_pose.inverse())
}

/// The map with its toolbar. Returns a pose to kidnap the robot to when
/// `click_kidnap` is on and the map was clicked.
pub fn map_ui(
    ui: &mut egui::Ui,
    sim: &CartographerSim,
    canvas: &mut MapView,
    tiles: &mut SubmapTiles,
    view: &mut CartographerView,
    click_kidnap: bool,
    track: &ReferenceTrack,
) -> Option<Pose2> {
    let has_truth = sim.input().truth.is_some();
    let has_reference = sim.input().reference.is_some();
    ui.horizontal_wrapped(|ui| {
        ui.label("Map:");
        if map_canvas::zoom_buttons_ui(ui, canvas, "Fit map") {
            view.follow_robot = false;
        }
        ui.checkbox(&mut view.follow_robot, "Follow robot");
        ui.checkbox(&mut view.legend, "Legend");
        ui.checkbox(&mut view.scan, "Scan");
        ui.checkbox(&mut view.intra, "Intra-submap").on_hover_text(
            "The constraints from local SLAM: each node to the submaps it went into",
        );
        if has_truth {
            ui.checkbox(&mut view.truth, "True robot");
        }
        if has_reference {
            ui.checkbox(&mut view.reference, "Reference").on_hover_text(
                "The corrected log's poses at the reference scans passed, moved onto the map by \
                 the rigid alignment that fits the trajectory to them best",
            );
        }
    });
    if view.legend {
        ui.horizontal_wrapped(|ui| {
            for t in 0..sim.trajectories.len().max(1) {
                let joined = sim.trajectories.get(t).is_some_and(|tr| tr.joined_to != t);
                ui.label(
                    egui::RichText::new(format!(
                        "· trajectory {t}{}",
                        if joined { " (merged)" } else { "" }
                    ))
                    .color(trajectory_color(t))
                    .strong(),
                );
            }
            ui.label(
                egui::RichText::new("— loop closures")
                    .color(LOOP_CLOSURE)
                    .strong(),
            );
            if view.intra {
                ui.label(egui::RichText::new("— intra-submap").color(palette::DEAD_RECKONING));
            }
            if !sim.detections.is_empty() {
                ui.label(
                    egui::RichText::new("ring: kidnap detected")
                        .color(DETECTION)
                        .strong(),
                );
            }
            if !sim.merges.is_empty() {
                ui.label(
                    egui::RichText::new("ring: maps merged")
                        .color(LOOP_CLOSURE)
                        .strong(),
                );
            }
            if has_reference && view.reference {
                ui.label(
                    egui::RichText::new("— reference (corrected log)")
                        .color(CanvasColors::of(ui).truth)
                        .strong(),
                );
            }
            ui.label("submaps: one tint each, walls black");
        });
    }
    let last = sim.records.last();
    let robot = robot_pose_now(sim);
    let mut follow = view
        .follow_robot
        .then(|| robot.map(|p| [p.x, p.y]))
        .flatten();
    let following = follow.is_some();
    let (response, t) =
        map_canvas::canvas_ui(ui, canvas, bounds(sim), 0.0, &mut follow, !click_kidnap);
    if following {
        view.follow_robot = follow.is_some();
    }
    let clicked = click_kidnap
        .then(|| {
            response
                .interact_pointer_pos()
                .filter(|_| response.clicked())
        })
        .flatten()
        .map(|p| {
            let [x, y] = t.world_of(p);
            Pose2::new(x, y, 0.0)
        });
    if click_kidnap {
        response
            .clone()
            .on_hover_cursor(egui::CursorIcon::Crosshair);
    }
    let colors = CanvasColors::of(ui);
    let painter = ui.painter_at(t.rect);
    painter.rect_filled(t.rect, 4.0, colors.background);
    draw_grid(&painter, &t, &colors);
    // The submaps, oldest first: a newer one covers the overlap.
    tiles.draw(
        ui.ctx(),
        &painter,
        &t,
        sim.submaps
            .iter()
            .enumerate()
            .map(|(s, submap)| (&submap.grid, world_from_grid(sim, s), submap_tint(s))),
    );
    // Constraints: intra-submap thin grey, loop closures green. The Intel log has
    // some 16,000 of them: one mesh of plain quads, not 16,000 anti-aliased
    // strokes for egui to tessellate every frame.
    let intra = Color32::from_rgba_unmultiplied(0x8C, 0x8C, 0x8C, 110);
    let mut lines = ParticleMesh::default();
    for c in &sim.constraints {
        let (Some(submap), Some(node)) = (sim.submaps.get(c.submap), sim.nodes.get(c.node)) else {
            continue;
        };
        let (a, b) = (
            t.xy(submap.global_pose.x, submap.global_pose.y),
            t.xy(node.global_pose.x, node.global_pose.y),
        );
        match c.kind {
            ConstraintKind::IntraSubmap if view.intra => lines.segment(a, b, 0.5, intra),
            ConstraintKind::IntraSubmap => {}
            ConstraintKind::LoopClosure => lines.segment(a, b, 1.4, LOOP_CLOSURE),
            ConstraintKind::InterTrajectory => lines.segment(a, b, 2.6, LOOP_CLOSURE),
        }
    }
    lines.paint(&painter);
    // Submap origins: squares in their trajectory's colour.
    for submap in &sim.submaps {
        let p = t.xy(submap.global_pose.x, submap.global_pose.y);
        painter.rect_stroke(
            egui::Rect::from_center_size(p, egui::vec2(7.0, 7.0)),
            0.0,
            Stroke::new(1.5, trajectory_color(submap.trajectory)),
            egui::StrokeKind::Middle,
        );
    }
    // The reference under the nodes, so that the estimate stays in view.
    if has_reference && view.reference {
        track.draw_path(&painter, &t, colors.truth, colors.background);
    }
    // Nodes: dots in their trajectory's colour, one mesh (6,837 on the Intel log).
    let mut dots = ParticleMesh::default();
    for node in &sim.nodes {
        dots.dot(
            t.xy(node.global_pose.x, node.global_pose.y),
            1.8,
            trajectory_color(node.trajectory),
        );
    }
    dots.paint(&painter);
    // The key moments: where the kidnap was detected and where the maps merged,
    // on the nodes (they move with the optimization).
    for (d, scan) in moment_marks(sim) {
        let color = match d {
            Moment::Detected => DETECTION,
            Moment::Merged => LOOP_CLOSURE,
        };
        let Some(node) = sim.nodes.iter().find(|n| n.scan >= scan) else {
            continue;
        };
        let p = t.xy(node.global_pose.x, node.global_pose.y);
        painter.circle_stroke(p, 9.0, Stroke::new(2.5, colors.background));
        painter.circle_stroke(p, 9.0, Stroke::new(1.8, color));
        let text = match d {
            Moment::Detected => format!("kidnap detected, scan {scan}"),
            Moment::Merged => format!("merged, scan {scan}"),
        };
        let galley = painter.layout_no_wrap(text, egui::FontId::proportional(12.0), color);
        // The detection's label above, the merge's below: the two are often
        // a scan or two apart, on nearly the same node.
        let at = match d {
            Moment::Detected => p + egui::vec2(12.0, -galley.size().y - 2.0),
            Moment::Merged => p + egui::vec2(12.0, 2.0),
        };
        painter.rect_filled(
            egui::Rect::from_min_size(at, galley.size()).expand(2.0),
            2.0,
            colors.background.gamma_multiply(0.85),
        );
        painter.galley(at, galley, color);
    }
    // The true robot, hollow and grey (simulation only).
    if view.truth
        && let Some(truth) = &sim.input().truth
        && let Some(p) = sim.scans_done().checked_sub(1).and_then(|k| truth.get(k))
    {
        let radius = (0.2 * t.scale).max(4.0);
        painter.circle_stroke(t.xy(p.x, p.y), radius, Stroke::new(1.5, colors.truth));
    }
    if let (Some(r), Some(pose)) = (last, robot) {
        let scan = sim.input().scans.get(r.scan).map(|s| &s.scan);
        draw_scan_and_robot(
            &painter,
            &t,
            scan.filter(|_| view.scan),
            &pose,
            trajectory_color(r.trajectory),
        );
    }
    draw_scale_and_axes(&painter, &t, &colors);
    clicked
}

/// The robot's pose in the global frame as the pose graph has it now: the last
/// scan's pose as it was taken, moved as its trajectory's newest node has been
/// moved since (by a merge or an optimization), `g_node,now · g_node,then⁻¹ ·
/// g_scan,then`. Without a node it is the pose as taken.
pub fn robot_pose_now(sim: &CartographerSim) -> Option<Pose2> {
    let last = sim.records.last()?;
    let moved = sim
        .nodes
        .iter()
        .rev()
        .find(|n| n.trajectory == last.trajectory && n.scan <= last.scan)
        .and_then(|n| {
            let then = sim.records.iter().rev().find(|r| r.scan == n.scan)?;
            Some(n.global_pose.compose(&then.global_pose.inverse()))
        });
    Some(match moved {
        Some(correction) => correction.compose(&last.global_pose),
        None => last.global_pose,
    })
}

/// A key moment of a kidnap during mapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Moment {
    /// The detector declared a kidnap: a new trajectory (and map) starts.
    Detected,
    /// An inter-trajectory loop closure merged the new map into the first.
    Merged,
}

/// The colour of a detection's mark.
pub const DETECTION: Color32 = palette::VERMILLION;

/// Every detection and merge so far, with its scan: what the map marks.
pub fn moment_marks(sim: &CartographerSim) -> Vec<(Moment, usize)> {
    let detected = sim.detections.iter().map(|&d| (Moment::Detected, d));
    let merged = sim.merges.iter().map(|&m| (Moment::Merged, m));
    detected.chain(merged).collect()
}

/// The heights Fig. 5.7 shows: boxes of 1, 4, 16 and 64 cells a side.
pub const SHOWN_HEIGHTS: [u32; 4] = [0, 2, 4, 6];

/// Textures of one submap's precomputed grids.
#[derive(Default)]
pub struct MaxGridTextures {
    submap: Option<usize>,
    textures: Vec<(u32, egui::TextureHandle)>,
}

impl std::fmt::Debug for MaxGridTextures {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "MaxGridTextures(submap {:?})", self.submap)
    }
}

impl MaxGridTextures {
    /// Forgets the textures (a new run).
    pub fn clear(&mut self) {
        self.submap = None;
        self.textures.clear();
    }
}

/// The submap Fig. 5.7 shows: the last search's, else the newest finished.
pub fn shown_submap(sim: &CartographerSim) -> Option<usize> {
    sim.last_search
        .as_ref()
        .map(|s| s.submap)
        .filter(|&s| sim.submaps.get(s).is_some_and(|m| m.precomputed.is_some()))
        .or_else(|| sim.submaps.iter().rposition(|m| m.precomputed.is_some()))
}

/// The window of Fig. 5.7: the precomputed grids of heights 0, 2, 4 and 6
/// (boxes of 1, 4, 16, 64 cells) of one finished submap, darker where the
/// box's largest probability is higher. It opens at the top left of `area` (the
/// map's, under the lesson's actions) and stays inside it, off the menu, the time
/// bar and its own button.
pub fn max_grids_window(
    ctx: &egui::Context,
    area: egui::Rect,
    sim: &CartographerSim,
    cache: &mut MaxGridTextures,
    open: &mut bool,
) {
    let shown = shown_submap(sim);
    if shown != cache.submap {
        cache.clear();
        cache.submap = shown;
        if let Some(grids) = shown.and_then(|s| sim.submaps[s].precomputed.as_ref()) {
            for h in SHOWN_HEIGHTS {
                let Some((_, _, w, hgt, cells)) = grids.grid(h) else {
                    continue;
                };
                let pixels: Vec<Color32> = (0..hgt)
                    .rev()
                    .flat_map(|j| (0..w).map(move |i| (i, j)))
                    .map(|(i, j)| {
                        let p = cell_probability(cells[j * w + i]);
                        Color32::from_gray((255.0 * (1.0 - p)).round().clamp(0.0, 255.0) as u8)
                    })
                    .collect();
                let image = egui::ColorImage::new([w, hgt], pixels);
                cache.textures.push((
                    h,
                    ctx.load_texture(
                        format!("max-grid-{h}"),
                        image,
                        egui::TextureOptions::NEAREST,
                    ),
                ));
            }
        }
    }
    egui::Window::new("Precomputed max grids (Fig. 5.7)")
        .open(open)
        .constrain_to(area)
        .default_pos(area.left_top() + egui::vec2(8.0, 8.0))
        .default_width(520.0_f32.min(area.width() - 16.0))
        .resizable(true)
        .vscroll(true)
        .show(ctx, |ui| {
            let Some(s) = cache.submap else {
                ui.label(
                    "No submap is finished yet: run on until one is (2 × num_range_data scans).",
                );
                return;
            };
            ui.label(format!(
                "Submap {s}: each cell of the grid of height h holds the largest probability in \
                 the 2^h × 2^h box it starts (Eq. 5.13), so a branch of the search tree is \
                 scored from one look-up per point, an upper bound of every pose under it \
                 (Eq. 5.14)."
            ));
            let side = ((ui.available_width() - 24.0) / 2.0).clamp(80.0, 320.0);
            egui::Grid::new("max_grids").show(ui, |ui| {
                for (k, (h, texture)) in cache.textures.iter().enumerate() {
                    ui.vertical(|ui| {
                        ui.label(format!("height {h}: boxes of {} cells", 1 << h));
                        let size = texture.size_vec2();
                        let scale = side / size.x.max(size.y).max(1.0);
                        ui.image((texture.id(), size * scale));
                    });
                    if k % 2 == 1 {
                        ui.end_row();
                    }
                }
            });
        });
}
