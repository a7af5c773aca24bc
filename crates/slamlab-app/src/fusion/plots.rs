//! The plots under the map: each mode's x, y and yaw error over time with its
//! ±2σ bounds, and the size of every SLAM update's position jump.

use super::mode_color;
use crate::export::PlotSeries;
use crate::widgets::plots::{line_width, thin, time_plot, title_ui};
use egui_plot::{Line, LineStyle, PlotPoints, Points};
use slamlab_sim::fusion::lesson::FusionSim;

/// The plots side by side.
pub fn plots_ui(ui: &mut egui::Ui, sim: &FusionSim) {
    let height = (ui.available_height() - 26.0).max(80.0);
    let plot = |id: &str, y: &str| {
        time_plot(id, y, height)
            .link_axis(egui::Id::unique("fusion_time_axis"), [true, false])
            .include_x(1.0)
            .include_y(0.0)
    };
    let titles = [
        ("x error", "x error (m)", "fusion_x"),
        ("y error", "y error (m)", "fusion_y"),
        ("Yaw error", "yaw error (rad)", "fusion_yaw"),
    ];
    ui.columns(4, |columns| {
        for (k, (title, axis, id)) in titles.iter().enumerate() {
            let ui = &mut columns[k];
            title_ui(
                ui,
                title,
                "Estimate minus truth at the output rate (solid) and the filter's own ±2σ \
                 (dashed): a consistent filter keeps its error inside about 95% of the time",
            );
            plot(id, axis).show(ui, |plot_ui| {
                for (i, run) in sim.runs().iter().enumerate() {
                    let color = mode_color(run.mode());
                    let name = run.mode().name();
                    let samples = run.samples();
                    let error = thin(samples.iter().map(|s| [s.t, s.error[k]]).collect());
                    let upper = thin(samples.iter().map(|s| [s.t, 2.0 * s.sigma[k]]).collect());
                    let lower = thin(samples.iter().map(|s| [s.t, -2.0 * s.sigma[k]]).collect());
                    plot_ui.line(
                        Line::new(format!("{name} error"), PlotPoints::new(error))
                            .color(color)
                            .width(line_width(i, 1.2)),
                    );
                    plot_ui.line(
                        Line::new(format!("{name} ±2σ"), PlotPoints::new(upper))
                            .color(color)
                            .style(LineStyle::dashed_dense())
                            .width(line_width(i, 0.8)),
                    );
                    plot_ui.line(
                        Line::new(format!("{name} ±2σ"), PlotPoints::new(lower))
                            .color(color)
                            .style(LineStyle::dashed_dense())
                            .width(line_width(i, 0.8)),
                    );
                }
            });
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
            for (i, run) in sim.runs().iter().enumerate() {
                let points = thin(run.slam_jumps().iter().map(|j| [j.t, j.jump]).collect());
                plot_ui.points(
                    Points::new(
                        format!("{} jump", run.mode().name()),
                        PlotPoints::new(points),
                    )
                    .color(mode_color(run.mode()))
                    .radius(line_width(i, 1.5)),
                );
            }
        });
    });
}

/// Every plot's series, unthinned, for the CSV export.
pub fn series(sim: &FusionSim) -> Vec<PlotSeries> {
    let mut out = Vec::new();
    for run in sim.runs() {
        let name = run.mode().name();
        let samples = run.samples();
        for (k, (plot, axis)) in [
            ("x error", "x error (m)"),
            ("y error", "y error (m)"),
            ("Yaw error", "yaw error (rad)"),
        ]
        .into_iter()
        .enumerate()
        {
            out.push(PlotSeries::new(
                plot,
                "time (s)",
                axis,
                format!("{name} error"),
                samples.iter().map(|s| [s.t, s.error[k]]).collect(),
            ));
            out.push(PlotSeries::new(
                plot,
                "time (s)",
                axis,
                format!("{name} 2σ"),
                samples.iter().map(|s| [s.t, 2.0 * s.sigma[k]]).collect(),
            ));
        }
        out.push(PlotSeries::new(
            "SLAM update jumps",
            "time (s)",
            "jump (m)",
            format!("{name} jump"),
            run.slam_jumps().iter().map(|j| [j.t, j.jump]).collect(),
        ));
    }
    out
}
