//! The plots under the map: each mode's x, y and yaw error over time with its
//! ±2σ bounds, and the size of every SLAM update's position jump.
//!
//! The error plots are scaled to the errors, not to the bands: the differential
//! filter's 2σ grows to metres (and beyond ±π in yaw) while every mode's error
//! stays at centimetres, and a scale that held the band would flatten the errors
//! onto zero. A band taller than the plot is cut at its edge, and the key says how
//! far it reaches.

use super::mode_color;
use crate::export::PlotSeries;
use crate::widgets::plots::{
    Figure, KeyEntry, Mark, Styled, draw_series, figure_ui, line_width, plot_row, row_time_plot,
    runs_key_ui, series_data, style_entries,
};
use slamlab_sim::fusion::session::FusionSim;

/// The three error plots: title, y axis, plot id.
const ERROR_PLOTS: [(&str, &str, &str); 3] = [
    ("x error", "x error (m)", "fusion_x"),
    ("y error", "y error (m)", "fusion_y"),
    ("Yaw error", "yaw error (rad)", "fusion_yaw"),
];

/// Every plotted series, defined once: the plots draw them, the CSV export
/// writes them unthinned.
fn plotted(sim: &FusionSim) -> Vec<Styled> {
    let mut out = Vec::new();
    for (i, run) in sim.runs().iter().enumerate() {
        let color = mode_color(run.mode());
        let name = run.mode().name();
        let samples = run.samples();
        for (k, (plot, axis, _)) in ERROR_PLOTS.into_iter().enumerate() {
            out.push(Styled::new(
                PlotSeries::new(
                    plot,
                    "time (s)",
                    axis,
                    format!("{name} error"),
                    samples.iter().map(|s| [s.t, s.error[k]]).collect(),
                ),
                color,
                Mark::Solid,
                line_width(i, 1.2),
            ));
            out.push(Styled::new(
                PlotSeries::new(
                    plot,
                    "time (s)",
                    axis,
                    format!("{name} ±2σ"),
                    samples.iter().map(|s| [s.t, 2.0 * s.sigma[k]]).collect(),
                ),
                color,
                Mark::DashedPlusMinus,
                line_width(i, 0.8),
            ));
        }
        out.push(Styled::new(
            PlotSeries::new(
                "SLAM update jumps",
                "time (s)",
                "jump (m)",
                format!("{name} jump"),
                run.slam_jumps().iter().map(|j| [j.t, j.jump]).collect(),
            ),
            color,
            Mark::Dots,
            line_width(i, 1.5),
        ));
    }
    out
}

/// How far an error plot reaches beyond its largest error (each side of zero).
pub const ERROR_HEADROOM: f64 = 1.25;

/// The y range `±limit` of the error plot titled `plot`: [`ERROR_HEADROOM`]
/// times its largest error (at least 1 cm, or 0.01 rad); `None` before any
/// sample. The second value is the largest 2σ when the band reaches beyond the
/// limit (it is cut there).
pub fn error_limit(all: &[Styled], plot: &str) -> Option<(f64, Option<f64>)> {
    let largest = |mark: Mark| {
        all.iter()
            .filter(|s| s.data.plot == plot && s.mark == mark)
            .flat_map(|s| s.data.points.iter().map(|p| p[1].abs()))
            .filter(|v| v.is_finite())
            .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))))
    };
    let error = largest(Mark::Solid)?;
    let band = largest(Mark::DashedPlusMinus).unwrap_or(0.0);
    // Errors of a few millimetres still get a scale of a centimetre.
    let limit = (ERROR_HEADROOM * error).max(0.01);
    Some((limit, (band > limit).then_some(band)))
}

/// The plots side by side, each with its key on a line above it.
pub fn plots_ui(ui: &mut egui::Ui, sim: &FusionSim) {
    let all = plotted(sim);
    // The modes' colours once for the row; each plot's key names only its styles.
    let modes: Vec<(String, egui::Color32)> = sim
        .runs()
        .iter()
        .map(|run| (run.mode().name().to_owned(), mode_color(run.mode())))
        .collect();
    let text = runs_key_ui(ui, &modes);
    let height = ui.available_height().max(80.0);
    let plot =
        |id: &'static str| move |h: f32, y: &str| row_time_plot(id, y, h, "fusion_time_axis");
    // An embed shows the first two: the x error and the y error.
    plot_row(ui, ERROR_PLOTS.len() + 1, |k, ui| {
        if let Some((title, axis, id)) = ERROR_PLOTS.get(k).copied() {
            let limit = error_limit(&all, title);
            let unit = crate::widgets::plots::unit_of(axis).unwrap_or("");
            let mut key = style_entries(&all, title, text);
            if let Some((_, Some(band))) = limit {
                // The band is cut at the plot's edge: say how far it reaches.
                for entry in &mut key {
                    if entry.mark == Mark::DashedPlusMinus {
                        *entry = KeyEntry::new(
                            format!("{} (cut; reaches ±{band:.2} {unit})", entry.name),
                            entry.color,
                            entry.mark,
                        );
                    }
                }
            }
            figure_ui(
                ui,
                &Figure {
                    title,
                    hover: "Estimate minus truth at the output rate (solid) and the filter's own \
                            ±2σ (dashed): a consistent filter keeps its error inside about 95% \
                            of the time. The scale fits the errors; a band taller than the plot \
                            is cut at its edge (the key says how far it reaches)",
                    key,
                    y_label: axis,
                    height,
                },
                plot(id),
                {
                    let all = &all;
                    move |plot_ui| {
                        draw_series(plot_ui, all, title);
                        if let Some((limit, _)) = limit {
                            plot_ui.set_plot_bounds_y(-limit..=limit);
                        }
                    }
                },
            );
        } else {
            figure_ui(
                ui,
                &Figure {
                    title: JUMPS,
                    hover: "How far each fused SLAM pose moved the position estimate at its update: \
                            relative and absolute correct the position itself (jumps), differential \
                            only a velocity (millimetres)",
                    key: style_entries(&all, JUMPS, text),
                    y_label: "jump (m)",
                    height,
                },
                plot("fusion_jumps"),
                |plot_ui| draw_series(plot_ui, &all, JUMPS),
            );
        }
    });
}

const JUMPS: &str = "SLAM update jumps";

/// Every plot's series, unthinned, for the CSV export.
pub fn series(sim: &FusionSim) -> Vec<PlotSeries> {
    series_data(plotted(sim))
}
