//! The plots under the map, one point per filter update: position error against
//! the estimate's own 2σ bound; Augmented MCL's w_slow and w_fast; the particle
//! count beside the effective sample size; and the injection probability beside
//! the fraction of particles drawn anew.

use super::filter_color;
use crate::export::PlotSeries;
use crate::widgets::plots::{
    Figure, Mark, Styled, draw_series, figure_ui, line_width, plot_row, row_time_plot, runs_key_ui,
    series_data, style_entries, title_ui,
};
use slamlab_sim::kidnap::{MclRun, UpdateRecord};

/// Every plotted series, defined once: the plots draw them, the CSV export
/// writes them unthinned.
fn plotted(run: &MclRun) -> Vec<Styled> {
    let dt = run.scenario().dt;
    // The simulated robot's ticks are dt apart; a log's scans have their own times.
    let time = |tick: u64| {
        if run.log().is_some() {
            run.tick_time(tick as usize)
        } else {
            tick as f64 * dt
        }
    };
    let log10 = |l: f64| l / std::f64::consts::LN_10;
    let mut out = Vec::new();
    for (k, f) in run.filters().iter().enumerate() {
        let color = filter_color(k, f.name);
        let name = f.name.to_uppercase();
        let over_time = |pick: &dyn Fn(&UpdateRecord) -> Option<f64>| {
            f.updates
                .iter()
                .filter_map(|u| pick(u).filter(|v| !v.is_nan()).map(|v| [time(u.tick), v]))
                .collect::<Vec<_>>()
        };
        // Per plot: the solid series, then the dashed one.
        for (plot, axis, series, mark, points) in [
            (
                "Position error",
                "error (m)",
                "error",
                Mark::Solid,
                over_time(&|u| Some(u.position_error)),
            ),
            (
                "Position error",
                "error (m)",
                "2σ bound",
                Mark::Dashed,
                over_time(&|u| Some(u.position_2sigma)),
            ),
            (
                "w_slow and w_fast",
                "log10 w",
                "w_fast",
                Mark::Solid,
                over_time(&|u| u.log_w_fast.map(log10)),
            ),
            (
                "w_slow and w_fast",
                "log10 w",
                "w_slow",
                Mark::Dashed,
                over_time(&|u| u.log_w_slow.map(log10)),
            ),
            (
                "Particles and N_eff",
                "particles",
                "particles",
                Mark::Solid,
                over_time(&|u| Some(u.particles as f64)),
            ),
            (
                "Particles and N_eff",
                "particles",
                "N_eff",
                Mark::Dashed,
                over_time(&|u| Some(u.n_eff)),
            ),
            (
                "Recovery",
                "fraction",
                "injection probability",
                Mark::Solid,
                over_time(&|u| Some(u.injection_probability)),
            ),
            (
                "Recovery",
                "fraction",
                "drawn anew",
                Mark::Dashed,
                over_time(&|u| Some(u.randomized)),
            ),
        ] {
            let width = line_width(k, if mark == Mark::Solid { 1.2 } else { 1.0 });
            out.push(Styled::new(
                PlotSeries::new(plot, "time (s)", axis, format!("{name} {series}"), points),
                color,
                mark,
                width,
            ));
        }
    }
    out
}

/// What the error plot says when the log has no truth.
pub const NO_TRUTH: &str = "No truth in this log: 2σ bounds only";

/// The plots side by side, each with its key on a line above it.
pub fn plots_ui(ui: &mut egui::Ui, run: &MclRun) {
    let all = plotted(run);
    // The filters' colours once for the row; each plot's key names only its styles.
    let filters: Vec<(String, egui::Color32)> = run
        .filters()
        .iter()
        .enumerate()
        .map(|(k, f)| (f.name.to_uppercase(), filter_color(k, f.name)))
        .collect();
    let text = runs_key_ui(ui, &filters);
    let height = ui.available_height().max(80.0);
    let plot =
        |id: &'static str| move |h: f32, y: &str| row_time_plot(id, y, h, "kidnap_time_axis");
    let figure = |title: &'static str, hover: &'static str, y_label: &'static str| Figure {
        title,
        hover,
        key: style_entries(&all, title, text),
        y_label,
        height,
    };
    let wslow_hover = "Augmented MCL's short-term (w_fast, solid) and long-term (w_slow, dashed) \
         averages of the particles' mean weight, as log10 (Algorithm 9 of Xiang's thesis, \
         §5.1.2). When the mean weight drops, w_fast falls faster than w_slow; once it is below \
         w_slow, the gap is the injection probability 1 − w_fast/w_slow. With the lesson's \
         tempered likelihood (laser-likelihood-exponent) a kidnap lowers the mean weight only \
         a little and w_slow still remembers the global localization's low weights: w_fast \
         stays above w_slow and AMCL injects nothing (the explanation says more). Filters \
         without recovery (MCL, CMCL) have none.";
    // An embed shows the first two: the error and w_slow against w_fast, or (with no
    // Augmented MCL, which alone keeps those averages) the particle count and N_eff.
    let augmented = run.filters().iter().any(|f| f.filter.kind().injects());
    let order = if augmented {
        [0, 1, 2, 3]
    } else {
        [0, 2, 1, 3]
    };
    plot_row(ui, 4, |k, ui| match order[k] {
        0 => {
            let mut error_figure = figure(
                "Position error",
                "Distance from the estimate (the heaviest cluster's weighted mean) to the true \
                 robot, and the estimate's own 2σ bound along its longest axis",
                "error (m)",
            );
            if !run.has_truth() {
                // Above the plot, so that it is read before the empty error lines.
                let said = ui.label(NO_TRUTH).on_hover_text(
                    "The log has no true poses (only a bag SLAM Lab simulated carries them, \
                         on /ground_truth): nothing to measure the error against. The dashed \
                         lines are each estimate's own 2σ bound.",
                );
                error_figure.height -= said.rect.height() + ui.spacing().item_spacing.y;
            }
            figure_ui(ui, &error_figure, plot("kidnap_error"), |plot_ui| {
                draw_series(plot_ui, &all, "Position error")
            });
        }
        1 => {
            if augmented {
                figure_ui(
                    ui,
                    &figure("w_slow and w_fast", wslow_hover, "log10 w"),
                    plot("kidnap_wslow"),
                    |plot_ui| draw_series(plot_ui, &all, "w_slow and w_fast"),
                );
            } else {
                title_ui(ui, "w_slow and w_fast", wslow_hover);
                ui.label(
                    "Only Augmented MCL keeps these averages: choose amcl or acmcl as the \
                     estimator to see them.",
                );
            }
        }
        2 => {
            figure_ui(
                ui,
                &figure(
                    "Particles and N_eff",
                    "How many particles each filter carries (solid; KLD-sampling adapts it) and the \
                     effective sample size N_eff = 1 / Σ w² after weighting (dashed): the particle \
                     count when all weights are equal, 1 when one particle holds all the weight",
                    "particles",
                ),
                plot("kidnap_count"),
                |plot_ui| draw_series(plot_ui, &all, "Particles and N_eff"),
            );
        }
        _ => {
            figure_ui(
                ui,
                &figure(
                    "Recovery",
                    "Augmented MCL's injection probability max(0, 1 − w_fast/w_slow) (solid) and \
                     the fraction of particles injected or regenerated in each update (dashed)",
                    "fraction",
                ),
                |h, y| plot("kidnap_recovery")(h, y).include_y(1.0),
                |plot_ui| draw_series(plot_ui, &all, "Recovery"),
            );
        }
    });
}

/// Every plot's series, unthinned, for the CSV export.
pub fn series(run: &MclRun) -> Vec<PlotSeries> {
    series_data(plotted(run))
}
