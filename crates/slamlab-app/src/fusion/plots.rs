//! The plots under the map: each mode's x, y and yaw error over time with its
//! ±2σ bounds, and the size of every SLAM update's position jump.

use super::mode_color;
use crate::export::PlotSeries;
use crate::widgets::plots::{
    Mark, Styled, draw_series, line_width, series_data, time_plot, title_ui,
};
use slamlab_sim::fusion::lesson::FusionSim;

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

/// The plots side by side.
pub fn plots_ui(ui: &mut egui::Ui, sim: &FusionSim) {
    let all = plotted(sim);
    let height = (ui.available_height() - 26.0).max(80.0);
    let plot = |id: &str, y: &str| {
        time_plot(id, y, height)
            .link_axis(egui::Id::unique("fusion_time_axis"), [true, false])
            .include_x(1.0)
            .include_y(0.0)
    };
    ui.columns(4, |columns| {
        for (k, (title, axis, id)) in ERROR_PLOTS.iter().enumerate() {
            let ui = &mut columns[k];
            title_ui(
                ui,
                title,
                "Estimate minus truth at the output rate (solid) and the filter's own ±2σ \
                 (dashed): a consistent filter keeps its error inside about 95% of the time",
            );
            plot(id, axis).show(ui, |plot_ui| draw_series(plot_ui, &all, title));
        }
        let ui = &mut columns[3];
        title_ui(
            ui,
            "SLAM update jumps",
            "How far each fused SLAM pose moved the position estimate at its update: \
             relative and absolute correct the position itself (jumps), differential only \
             a velocity (millimetres)",
        );
        plot("fusion_jumps", "jump (m)").show(ui, |plot_ui| {
            draw_series(plot_ui, &all, "SLAM update jumps")
        });
    });
}

/// Every plot's series, unthinned, for the CSV export.
pub fn series(sim: &FusionSim) -> Vec<PlotSeries> {
    series_data(plotted(sim))
}
