//! The plots under the map, one point per scan: the position error against
//! the truth (simulation only) or, for a log with its corrected version, the
//! trajectory error against that reference, the matcher's cost (grid FastSLAM: the
//! effective sample size with its resamplings), and the time each scan took
//! here.

use super::map::source_color;
use crate::export::PlotSeries;
use crate::palette;
use crate::widgets::plots::{
    Figure, Mark, Styled, draw_series, figure_plot, figure_ui, plot_row, series_data,
    style_entries, title_ui,
};
use crate::widgets::reference_track::ReferenceTrack;
use slamlab_sim::mapping::MappingSession;

const ERROR: &str = "Trajectory error";
const COST: &str = "Matcher cost";
const NEFF: &str = "Effective sample size";
const TIME: &str = "Time per scan";

/// Every plotted series, defined once for the plots and the CSV export.
fn plotted(session: &MappingSession, scan_ms: &[f64], track: &ReferenceTrack) -> Vec<Styled> {
    let sim = session.sim();
    let records = session.stepper().records();
    let color = source_color(sim.source());
    let name = sim.source().name();
    let mut out = Vec::new();
    if sim.input().truth.is_none() && sim.input().reference.is_some() {
        let label = match track.latest() {
            Some([scan, ate]) => format!("{name}: ATE {ate:.3} m at scan {scan:.0}"),
            None => format!("{name}: ATE after two reference scans"),
        };
        out.push(Styled::new(
            PlotSeries::new(ERROR, "scan", "ATE (m)", label, track.ate.clone()),
            color,
            Mark::Solid,
            1.6,
        ));
    }
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
                if sim.grid_fastslam().is_some() {
                    format!("{name} heaviest particle's error")
                } else {
                    format!("{name} position error")
                },
                error,
            ),
            color,
            Mark::Solid,
            1.4,
        ));
    }
    if let Some(filter) = sim.grid_fastslam() {
        let neff: Vec<[f64; 2]> = records
            .neff
            .iter()
            .enumerate()
            .filter(|(_, n)| n.is_finite())
            .map(|(k, n)| [k as f64, *n])
            .collect();
        let resampled = records
            .neff
            .iter()
            .zip(&records.resampled)
            .enumerate()
            .filter(|(_, (n, r))| **r && n.is_finite())
            .map(|(k, (n, _))| [k as f64, *n])
            .collect();
        let threshold = filter.config().resample_threshold * filter.config().particles as f64;
        let line = match (neff.first(), neff.last()) {
            (Some(a), Some(b)) => vec![[a[0], threshold], [b[0], threshold]],
            _ => Vec::new(),
        };
        out.push(Styled::new(
            PlotSeries::new(NEFF, "scan", "N_eff", format!("{name} N_eff"), neff),
            color,
            Mark::Solid,
            1.2,
        ));
        out.push(Styled::new(
            PlotSeries::new(
                NEFF,
                "scan",
                "N_eff",
                format!("{name} resampling"),
                resampled,
            ),
            palette::VERMILLION,
            Mark::Dots,
            3.0,
        ));
        out.push(Styled::new(
            PlotSeries::new(
                NEFF,
                "scan",
                "N_eff",
                format!("{name} resample threshold"),
                line,
            ),
            color,
            Mark::Dashed,
            1.0,
        ));
    }
    let matched = sim.grid_fastslam().is_none();
    let cost = records
        .costs
        .iter()
        .enumerate()
        .filter(|(_, c)| c.is_finite())
        .map(|(k, c)| [k as f64, *c])
        .collect();
    if matched {
        out.push(Styled::new(
            PlotSeries::new(COST, "scan", "cost", format!("{name} cost"), cost),
            color,
            Mark::Solid,
            1.2,
        ));
    }
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

/// The plots side by side, each with its key on a line above it.
pub fn plots_ui(
    ui: &mut egui::Ui,
    session: &MappingSession,
    scan_ms: &[f64],
    track: &ReferenceTrack,
) {
    let all = plotted(session, scan_ms, track);
    let sim = session.sim();
    let color = source_color(sim.source());
    let height = ui.available_height().max(80.0);
    let has_truth = sim.input().truth.is_some();
    let has_reference = sim.input().reference.is_some();
    let plot = |id: &'static str| {
        move |h: f32, y: &str| figure_plot(id, "scan", y, h).include_x(0.0).include_y(0.0)
    };
    let figure = |title: &'static str, hover: &'static str, y_label: &'static str| Figure {
        title,
        hover,
        key: style_entries(&all, title, color),
        y_label,
        height,
    };
    let error_hover = if sim.grid_fastslam().is_some() {
        "Distance from the heaviest particle's pose at each scan to the true pose, metres \
         (between updates its pose moves with the odometry). A jump down marks a new heaviest \
         particle, often after a loop closes."
    } else {
        "Distance from each scan's pose (as the pose source gave it) to the true pose, \
         metres. Raw odometry drifts; a matcher holds the error down until it meets something it \
         cannot match."
    };
    // An embed shows the first two: the error and the filter's or matcher's own plot.
    plot_row(ui, 3, |k, ui| match k {
        0 if has_truth => {
            figure_ui(
                ui,
                &figure(ERROR, error_hover, "error (m)"),
                plot("mapping_error"),
                |p| draw_series(p, &all, ERROR),
            );
        }
        0 if has_reference => {
            figure_ui(
                ui,
                &figure(
                    ERROR,
                    "Against the log's corrected version (Kümmerle et al. 2009): at every \
                     reference scan passed, the absolute trajectory error (RMS position error after \
                     the rigid alignment that fits best) of every scan's pose so far. Switch the \
                     pose source to compare them on the same scans.",
                    "ATE (m)",
                ),
                plot("mapping_error"),
                |p| draw_series(p, &all, ERROR),
            );
        }
        0 => {
            title_ui(ui, ERROR, error_hover);
            ui.label(
                "A real log has no ground truth: drop its corrected version with it (or give \
                 reference= in the URL) to plot the error against it.",
            );
        }
        1 if sim.grid_fastslam().is_some() => {
            figure_ui(
                ui,
                &figure(
                    NEFF,
                    "N_eff = 1 / Σ w_i² after each update's weighting (Grisetti 2007, Eq. 20): the \
                     number of particles the weights are worth. Below the dashed threshold (resample-\
                     threshold × particles) the filter resamples (dots). With the improved proposal it \
                     stays high and resampling is rare; with odometry it drops at almost every update.",
                    "N_eff",
                ),
                plot("mapping_neff"),
                |p| draw_series(p, &all, NEFF),
            );
        }
        1 => {
            figure_ui(
                ui,
                &figure(
                    COST,
                    "The matcher's final cost per scan: scan-to-map, the sum of squared residuals of \
                     Eq. 5.5 of Xiang's thesis with its two pulls; ICP, the mean squared distance of \
                     the kept pairs (m²). A jump marks a scan the matcher found hard.",
                    "cost",
                ),
                plot("mapping_cost"),
                |p| draw_series(p, &all, COST),
            );
        }
        _ => {
            figure_ui(
                ui,
                &figure(
                    TIME,
                    "How long each scan took here (predict, match and insert), milliseconds",
                    "time (ms)",
                ),
                plot("mapping_time"),
                |p| draw_series(p, &all, TIME),
            );
        }
    });
}

/// Every plot's series, unthinned, for the CSV export.
pub fn series(
    session: &MappingSession,
    scan_ms: &[f64],
    track: &ReferenceTrack,
) -> Vec<PlotSeries> {
    series_data(plotted(session, scan_ms, track))
}
