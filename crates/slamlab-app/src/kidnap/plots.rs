//! The plots under the map, one point per filter update: position error against
//! the estimate's own 2σ bound, the effective sample size, and the particle count.

use super::filter_color;
use crate::widgets::plots::{line_width, thin, time_plot, title_ui};
use egui_plot::{Line, LineStyle, PlotPoints};
use slamlab_sim::localization::MclRun;

/// The plots side by side.
pub fn plots_ui(ui: &mut egui::Ui, run: &MclRun) {
    let height = (ui.available_height() - 26.0).max(80.0);
    let dt = run.scenario().dt;
    let plot = |id: &str, y: &str| {
        time_plot(id, y, height)
            .link_axis(egui::Id::unique("kidnap_time_axis"), [true, false])
            .include_x(1.0)
            .include_y(0.0)
    };
    ui.columns(4, |columns| {
        let ui = &mut columns[0];
        title_ui(
            ui,
            "Position error",
            "Distance from the estimate (the heaviest cluster's weighted mean) to the true robot, \
             and the estimate's own 2σ bound along its longest axis",
        );
        plot("kidnap_error", "error (m)").show(ui, |plot_ui| {
            for (k, f) in run.filters().iter().enumerate() {
                let color = filter_color(k, f.name);
                let name = f.name.to_uppercase();
                let error = thin(
                    f.updates
                        .iter()
                        .map(|u| [u.tick as f64 * dt, u.position_error])
                        .collect(),
                );
                let bound = thin(
                    f.updates
                        .iter()
                        .map(|u| [u.tick as f64 * dt, u.position_2sigma])
                        .collect(),
                );
                plot_ui.line(
                    Line::new(format!("{name} error"), PlotPoints::new(error))
                        .color(color)
                        .width(line_width(k, 1.2)),
                );
                plot_ui.line(
                    Line::new(format!("{name} 2σ bound"), PlotPoints::new(bound))
                        .color(color)
                        .style(LineStyle::dashed_dense())
                        .width(line_width(k, 1.0)),
                );
            }
        });
        let ui = &mut columns[1];
        title_ui(
            ui,
            "Effective sample size",
            "N_eff = 1 / Σ w² after weighting: the particle count when all weights are equal, \
             1 when one particle holds all the weight",
        );
        plot("kidnap_neff", "N_eff").show(ui, |plot_ui| {
            for (k, f) in run.filters().iter().enumerate() {
                let points = thin(
                    f.updates
                        .iter()
                        .map(|u| [u.tick as f64 * dt, u.n_eff])
                        .collect(),
                );
                plot_ui.line(
                    Line::new(
                        format!("{} N_eff", f.name.to_uppercase()),
                        PlotPoints::new(points),
                    )
                    .color(filter_color(k, f.name))
                    .width(line_width(k, 1.2)),
                );
            }
        });
        let ui = &mut columns[3];
        title_ui(
            ui,
            "Recovery",
            "Augmented MCL's injection probability max(0, 1 − w_fast/w_slow) (solid) and the \
             fraction of particles injected or regenerated in each update (dashed)",
        );
        plot("kidnap_recovery", "fraction")
            .include_y(1.0)
            .show(ui, |plot_ui| {
                for (k, f) in run.filters().iter().enumerate() {
                    let color = filter_color(k, f.name);
                    let name = f.name.to_uppercase();
                    let p = thin(
                        f.updates
                            .iter()
                            .map(|u| [u.tick as f64 * dt, u.injection_probability])
                            .collect(),
                    );
                    let r = thin(
                        f.updates
                            .iter()
                            .map(|u| [u.tick as f64 * dt, u.randomized])
                            .collect(),
                    );
                    plot_ui.line(
                        Line::new(format!("{name} injection probability"), PlotPoints::new(p))
                            .color(color)
                            .width(line_width(k, 1.2)),
                    );
                    plot_ui.line(
                        Line::new(format!("{name} drawn anew"), PlotPoints::new(r))
                            .color(color)
                            .style(LineStyle::dashed_dense())
                            .width(line_width(k, 1.0)),
                    );
                }
            });
        let ui = &mut columns[2];
        title_ui(
            ui,
            "Particles",
            "How many particles each filter carries (KLD-sampling adapts it)",
        );
        plot("kidnap_count", "particles").show(ui, |plot_ui| {
            for (k, f) in run.filters().iter().enumerate() {
                let points = thin(
                    f.updates
                        .iter()
                        .map(|u| [u.tick as f64 * dt, u.particles as f64])
                        .collect(),
                );
                plot_ui.line(
                    Line::new(
                        format!("{} particles", f.name.to_uppercase()),
                        PlotPoints::new(points),
                    )
                    .color(filter_color(k, f.name))
                    .width(line_width(k, 1.2)),
                );
            }
        });
    });
}
