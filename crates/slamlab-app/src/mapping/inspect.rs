//! Looking inside one scan: an ICP match iteration by iteration (its
//! correspondences drawn as short lines, its error per iteration plotted), and
//! one beam's update of the grid (the cells it crosses and the cell it ends in,
//! with their log odds before and after the scan).

use crate::palette;
use crate::widgets::map_canvas::MapTransform;
use crate::widgets::plots::{Figure, KeyEntry, Mark, figure_plot, figure_ui};
use egui::{Color32, Stroke};
use egui_plot::{Line, PlotPoints, Points};
use slamlab_core::Pose2;
use slamlab_core::grid::{BeamCell, probability};
use slamlab_core::scan::icp::PairStatus;
use slamlab_sim::mapping::{IcpScanRecord, MappingSession, PoseSource};

/// The colour of a kept ICP pair and of the cells a beam updates as free.
const KEPT: Color32 = palette::SKY_BLUE;
/// The colour of a rejected pair and of a cell another beam updated.
const REJECTED: Color32 = Color32::from_rgb(0x9A, 0x9A, 0x9A);
/// The reference scan's points (the previous scan).
const REFERENCE: Color32 = palette::GREEN;

/// The ICP match of the current scan, the iteration to draw (the one being
/// shown while stepping through it, else its last) and whether it is being
/// stepped through. `None` unless the pose source is ICP and the current scan
/// was matched with it.
fn iteration_to_draw(session: &MappingSession) -> Option<(&IcpScanRecord, usize, bool)> {
    let sim = session.sim();
    if !matches!(sim.source(), PoseSource::Icp | PoseSource::Plicp) {
        return None;
    }
    let (record, shown) = sim.icp_record()?;
    let (current, _, _) = sim.current()?;
    if record.scan != current || record.iterations.is_empty() {
        return None;
    }
    let i = shown.unwrap_or(record.iterations.len() - 1);
    Some((record, i, shown.is_some()))
}

/// Draws the current ICP iteration's correspondences: from each scan point
/// (where the iteration started) to its nearest reference point, blue when the
/// pair was kept, grey when gated or trimmed; the reference scan's points green.
pub fn draw_correspondences(painter: &egui::Painter, t: &MapTransform, session: &MappingSession) {
    let Some((record, i, _)) = iteration_to_draw(session) else {
        return;
    };
    let reference = session.sim().input().scans[record.reference_scan]
        .scan
        .points();
    let world = |p: &Pose2, x: f64, y: f64| {
        let q = p.transform_point(&nalgebra::Vector2::new(x, y));
        t.xy(q.x, q.y)
    };
    let base = &record.reference_pose;
    for r in &reference {
        painter.circle_filled(world(base, r[0], r[1]), 1.4, REFERENCE);
    }
    for c in &record.iterations[i].correspondences {
        let Some(r) = reference.get(c.reference_index) else {
            continue;
        };
        let (color, width) = match c.status {
            PairStatus::Kept => (KEPT, 1.2),
            _ => (REJECTED, 0.7),
        };
        painter.line_segment(
            [
                world(base, c.scan_point[0], c.scan_point[1]),
                world(base, r[0], r[1]),
            ],
            Stroke::new(width, color),
        );
    }
}

/// The ICP section of the explanation panel: the iteration shown, its numbers,
/// and the error of every iteration of this match with the shown one marked.
pub fn iteration_ui(ui: &mut egui::Ui, session: &MappingSession) {
    let Some((record, i, stepping)) = iteration_to_draw(session) else {
        return;
    };
    let of = record.iterations.len();
    let it = &record.iterations[i];
    ui.separator();
    ui.strong(format!(
        "ICP on scan {}: iteration {} of {of}",
        record.scan,
        i + 1
    ));
    ui.label(format!(
        "{} of {} pairs kept (the rest beyond the distance gate or trimmed); mean squared error \
         {:.5} m² at the iteration's start; the step moved the scan {:.4} m and {:.3}°{}.",
        it.kept,
        it.correspondences.len(),
        it.mean_squared_error,
        it.step_translation,
        it.step_rotation.to_degrees(),
        if it.converged {
            ": below both tolerances, so ICP stops"
        } else {
            ""
        }
    ));
    if !stepping {
        ui.label(
            "Tick \"ICP one iteration per phase\" and step phase by phase (.) to see the match \
             iteration by iteration.",
        );
    }
    let errors: Vec<[f64; 2]> = record
        .iterations
        .iter()
        .map(|r| [r.iteration as f64, r.mean_squared_error])
        .collect();
    let marker = [[it.iteration as f64, it.mean_squared_error]];
    let figure = Figure {
        title: "ICP error per iteration",
        hover: "Mean squared error of the kept pairs at the start of each iteration of this scan's \
                match, m²; the dot is the iteration drawn on the map.",
        key: vec![
            KeyEntry::new("error", KEPT, Mark::Solid),
            KeyEntry::new("shown", palette::VERMILLION, Mark::Dots),
        ],
        y_label: "error (m²)",
        height: 150.0,
    };
    figure_ui(
        ui,
        &figure,
        |h, y| {
            figure_plot("mapping_icp_iterations", "iteration", y, h)
                .include_x(0.0)
                .include_y(0.0)
        },
        move |p| {
            p.line(
                Line::new("error", PlotPoints::new(errors))
                    .color(KEPT)
                    .width(1.4),
            );
            p.points(
                Points::new("shown", PlotPoints::new(marker.to_vec()))
                    .color(palette::VERMILLION)
                    .radius(4.0),
            );
        },
    );
}

/// The number of beams of the scan the beam view works on.
fn beam_count(session: &MappingSession) -> usize {
    session
        .sim()
        .current()
        .map_or(0, |(_, scan, _)| scan.scan.len())
}

/// The beam section of the explanation panel: pick a beam, step to the next,
/// and read what the scan does to each of its cells.
pub fn beam_ui(ui: &mut egui::Ui, session: &MappingSession, beam: &mut Option<usize>) {
    ui.separator();
    let n = beam_count(session);
    let mut on = beam.is_some();
    ui.checkbox(&mut on, "Inspect one beam's update")
        .on_hover_text("The cells one beam of the current scan crosses and the cell it ends in");
    if !on || n == 0 {
        *beam = None;
        if on {
            ui.label("No scan yet: step once (.) first.");
        }
        return;
    }
    let mut b = beam.unwrap_or(n / 2).min(n - 1);
    ui.horizontal_wrapped(|ui| {
        if ui.button("Previous beam").clicked() {
            b = (b + n - 1) % n;
        }
        ui.add(egui::Slider::new(&mut b, 0..=n - 1).text("beam"));
        if ui.button("Next beam").clicked() {
            b = (b + 1) % n;
        }
    });
    *beam = Some(b);
    let sim = session.sim();
    let when = if sim.next_is_insert() {
        "The next phase inserts this scan; the beam will change these cells:"
    } else {
        "The last insertion changed these cells of this beam:"
    };
    match sim.explain_beam(b) {
        None => {
            ui.label(
                "This scan went in before the beam view was on: step to the next scan's \
                 insertion (.) to see its beams.",
            );
        }
        Some(Err(why)) => {
            ui.label(egui::RichText::new(why).color(palette::VERMILLION));
        }
        Some(Ok(update)) => {
            let here = update.cells.iter().filter(|c| c.updated_here).count();
            ui.label(format!(
                "{when} {} cells on its way, {} of them updated by this beam (a cell changes once \
                 per scan: another beam may have crossed it first, and a cell holding any beam's \
                 end point is a hit, not a miss).",
                update.cells.len(),
                here
            ));
            if update.cells.is_empty() {
                ui.label("This beam returned nothing usable and marks no cell.");
                return;
            }
            beam_table_ui(ui, &update.cells);
            ui.label(
                egui::RichText::new(
                    "From the end cell back to the sensor. * updated by another beam of this scan \
                     (the value shown is still the one the cell gets).",
                )
                .small(),
            );
        }
    }
}

fn value(l: Option<f64>) -> String {
    match l {
        Some(l) => format!("{l:+.2} (p {:.2})", probability(l)),
        None => "unknown (p 0.50)".to_owned(),
    }
}

/// The beam's cells, from the sensor out (the end cell last), with their log
/// odds before and after.
fn beam_table_ui(ui: &mut egui::Ui, cells: &[BeamCell]) {
    egui::ScrollArea::vertical()
        .id_salt("mapping_beam_cells")
        .max_height(160.0)
        .show(ui, |ui| {
            egui::Grid::new("mapping_beam_table")
                .striped(true)
                .num_columns(4)
                .show(ui, |ui| {
                    ui.strong("cell");
                    ui.strong("before");
                    ui.strong("after");
                    ui.strong("update");
                    ui.end_row();
                    for c in cells.iter().rev() {
                        ui.label(format!("({}, {})", c.cell.0, c.cell.1));
                        ui.label(value(c.before));
                        ui.label(value(Some(c.after)));
                        ui.label(match (c.updated_here, c.hit) {
                            (true, true) => "hit",
                            (true, false) => "miss",
                            (false, true) => "hit*",
                            (false, false) => "miss*",
                        });
                        ui.end_row();
                    }
                });
        });
}

/// Draws the inspected beam: its ray, the crossed cells (blue where this beam
/// updates them, grey where another did) and its end cell (vermillion).
pub fn draw_beam(
    painter: &egui::Painter,
    t: &MapTransform,
    session: &MappingSession,
    beam: Option<usize>,
) {
    let Some(Some(Ok(update))) = beam.map(|b| session.sim().explain_beam(b)) else {
        return;
    };
    let r = session.sim().grid().resolution();
    for c in &update.cells {
        let (x, y) = (c.cell.0 as f64 * r, c.cell.1 as f64 * r);
        let rect = egui::Rect::from_two_pos(t.xy(x, y + r), t.xy(x + r, y));
        let color = if c.end {
            palette::VERMILLION
        } else if c.updated_here {
            KEPT
        } else {
            REJECTED
        };
        painter.rect_filled(rect, 0.0, color.gamma_multiply(0.55));
        painter.rect_stroke(rect, 0.0, Stroke::new(1.0, color), egui::StrokeKind::Inside);
    }
    if let (Some(last), (ox, oy)) = (update.cells.last(), update.origin) {
        let (x, y) = (
            (last.cell.0 as f64 + 0.5) * r,
            (last.cell.1 as f64 + 0.5) * r,
        );
        painter.line_segment(
            [t.xy(ox, oy), t.xy(x, y)],
            Stroke::new(1.5, palette::VERMILLION),
        );
    }
}
