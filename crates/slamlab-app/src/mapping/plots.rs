//! The plots under the map, one point per scan: the position error against
//! the truth (simulation only), the matcher's cost, and the time each scan
//! took here.

use super::map::source_color;
use crate::export::PlotSeries;
use crate::widgets::plots::{Mark, Styled, draw_series, series_data, series_key_ui, title_ui};
use egui_plot::Plot;
use slamlab_sim::mapping::MappingSession;

const ERROR: &str = "Trajectory error";
const COST: &str = "Matcher cost";
const TIME: &str = "Time per scan";

/// Every plotted series, defined once for the plots and the CSV export.
fn plotted(session: &MappingSession, scan_ms: &[f64]) -> Vec<Styled> {
    let sim = session.sim();
    let records = session.stepper().records();
    let color = source_color(sim.source());
    let name = sim.source().name();
    let mut out = Vec::new();
    if let Some(truth) = &sim.input().truth {
        let error = records
            .poses
            .iter()
            .zip(truth)
            .enumerate()
            .map(|(k, (p, t))| [k as f64, slamlab_core::math::hypot(p.x - t.x, p.y - t.y)])
            .collect();
        out.push(Styled::new(
            PlotSeries::new(
                ERROR,
                "scan",
                "error (m)",
                format!("{name} position error"),
                error,
            ),
            color,
            Mark::Solid,
            1.4,
        ));
    }
    let cost = records
        .costs
        .iter()
        .enumerate()
        .filter(|(_, c)| c.is_finite())
        .map(|(k, c)| [k as f64, *c])
        .collect();
    out.push(Styled::new(
        PlotSeries::new(COST, "scan", "cost", format!("{name} cost"), cost),
        color,
        Mark::Solid,
        1.2,
    ));
    let time = scan_ms
        .iter()
        .enumerate()
        .filter(|(_, t)| t.is_finite())
        .map(|(k, t)| [k as f64, *t])
        .collect();
    out.push(Styled::new(
        PlotSeries::new(
            TIME,
            "scan",
            "time (ms)",
            format!("{name} time per scan"),
            time,
        ),
        color,
        Mark::Solid,
        1.0,
    ));
    out
}

/// A plot over scans, without a legend inside (the key is the line above).
fn scan_plot<'a>(id: &str, y_label: &str, height: f32) -> Plot<'a> {
    Plot::new(id)
        .height(height)
        .x_axis_label("scan")
        .y_axis_label(y_label.to_owned())
        .include_x(0.0)
        .include_y(0.0)
        .allow_scroll(false)
        .allow_drag(false)
        .allow_zoom(false)
        .allow_boxed_zoom(false)
}

/// The plots side by side.
pub fn plots_ui(ui: &mut egui::Ui, session: &MappingSession, scan_ms: &[f64]) {
    let all = plotted(session, scan_ms);
    let sim = session.sim();
    series_key_ui(
        ui,
        &[(sim.source().label().to_owned(), source_color(sim.source()))],
        "one point per scan",
    );
    let height = (ui.available_height() - 26.0).max(70.0);
    let has_truth = sim.input().truth.is_some();
    ui.columns(3, |columns| {
        let ui = &mut columns[0];
        title_ui(
            ui,
            ERROR,
            "Distance from each scan's pose (as the pose source gave it) to the true pose, metres. \
             Raw odometry drifts; a matcher holds the error down until it meets something it cannot match.",
        );
        if has_truth {
            scan_plot("mapping_error", "error (m)", height).show(ui, |p| draw_series(p, &all, ERROR));
        } else {
            ui.label("A real log has no ground truth: no error to plot.");
        }
        let ui = &mut columns[1];
        title_ui(
            ui,
            COST,
            "The matcher's final cost per scan: scan-to-map, the sum of squared residuals of thesis Eq. 5.5 \
             with its two pulls; ICP, the mean squared distance of the kept pairs (m²). A jump marks a scan \
             the matcher found hard.",
        );
        scan_plot("mapping_cost", "cost", height).show(ui, |p| draw_series(p, &all, COST));
        let ui = &mut columns[2];
        title_ui(ui, TIME, "How long each scan took here (predict, match and insert), milliseconds");
        scan_plot("mapping_time", "time (ms)", height).show(ui, |p| draw_series(p, &all, TIME));
    });
}

/// Every plot's series, unthinned, for the CSV export.
pub fn series(session: &MappingSession, scan_ms: &[f64]) -> Vec<PlotSeries> {
    series_data(plotted(session, scan_ms))
}
