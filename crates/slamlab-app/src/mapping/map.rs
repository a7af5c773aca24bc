//! The map being built: the probability grid as tiles of textures (a tile is
//! redrawn only when a scan changed it), the true map faintly underneath on
//! request, the estimated and true paths, and the current scan's rays and
//! hit points from where it is placed now.

use super::MappingView;
use crate::palette;
pub use crate::widgets::grid_tiles::GridTiles;
use crate::widgets::grid_tiles::{draw_path, draw_scan_and_robot};
use crate::widgets::map_canvas::{self, CanvasColors, MapView, draw_grid, draw_scale_and_axes};
use crate::widgets::reference_track::ReferenceTrack;
use egui::{Color32, Pos2};
use slamlab_core::grid::ProbabilityGrid;
use slamlab_sim::mapping::{MappingSession, PoseSource};

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
    track: &ReferenceTrack,
) -> Option<usize> {
    let sim = session.sim();
    let has_truth = sim.input().truth.is_some();
    let has_reference = !has_truth && sim.input().reference.is_some();
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
        if has_reference {
            ui.checkbox(&mut view.truth, "Reference").on_hover_text(
                "The corrected log's poses at the reference scans passed, moved onto the map by \
                 the rigid alignment that fits the path to them best",
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
            if has_reference && view.truth {
                ui.label(egui::RichText::new("— reference (corrected log)").strong());
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
    if has_reference && view.truth {
        track.draw_path(&painter, &t, colors.truth, colors.background);
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
        let shown = (view.scan && beam.is_none()).then_some(&scan.scan);
        draw_scan_and_robot(&painter, &t, shown, &pose, color);
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
