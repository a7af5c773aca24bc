//! The plots under the map: robot position error with the filter's 2σ bound,
//! landmark RMS error, robot-pose NEES and per-update NIS with their 95% bands.

use crate::export::PlotSeries;
use crate::palette;
pub(super) use crate::widgets::plots::{line_width, thin, time_plot, title_ui};
use crate::widgets::plots::{series_key_ui, time_plot_without_legend};
use egui_plot::{HLine, Line, LineStyle, Plot, PlotPoints, Points, Span};
use slamlab_core::stats::chi2_quantile;
use slamlab_sim::LandmarkSession;

/// The 95% two-sided chi-square band of one sample with `dof` degrees of freedom.
pub fn band_95(dof: f64) -> (f64, f64) {
    (chi2_quantile(0.025, dof), chi2_quantile(0.975, dof))
}

/// A y range that shows the band and most samples; extreme spikes are cut off.
fn consistency_y_max(values: impl Iterator<Item = f64>, band_hi: f64) -> f64 {
    let max = values.filter(|v| v.is_finite()).fold(0.0_f64, f64::max);
    (band_hi * 1.6).max((max * 1.1).min(band_hi * 20.0))
}

/// The 95% band: a shaded span (no label of its own) and its two edges, which carry
/// the legend entry.
pub(super) fn band_ui(plot_ui: &mut egui_plot::PlotUi<'_>, lo: f64, hi: f64) {
    plot_ui.add(
        Span::new("", lo..=hi)
            .axis(egui_plot::Axis::Y)
            .fill(palette::faded(palette::GREEN, 0.16)),
    );
    let name = format!("95% band {lo:.2}..{hi:.2}");
    for edge in [lo, hi] {
        plot_ui.hline(
            HLine::new(name.clone(), edge)
                .color(palette::GREEN)
                .style(LineStyle::dashed_dense())
                .width(1.0),
        );
    }
}

/// The plots under the map share their time axis and always show the first second.
fn plot<'a>(id: &str, y_label: &str, height: f32) -> Plot<'a> {
    time_plot_without_legend(id, y_label, height)
        .link_axis(egui::Id::unique("slamlab_time_axis"), [true, false])
        .include_x(1.0)
        .include_y(0.0)
}

/// Pairs of filters whose plotted series lie on top of each other: the first filter
/// and each later one whose robot error and NEES never differ by more than 0.5% of the
/// plot's range (a pixel on a 200-pixel plot), with the largest robot-error difference
/// in metres. Needs at least ten ticks.
pub fn coinciding_series(session: &LandmarkSession) -> Vec<(usize, f64)> {
    let runs = session.filters();
    let Some(first) = runs.first() else {
        return Vec::new();
    };
    if first.history.len() < 10 {
        return Vec::new();
    }
    let range = |f: &dyn Fn(&slamlab_sim::session::TickMetrics) -> Option<f64>| {
        runs.iter()
            .flat_map(|run| run.history.iter().filter_map(f))
            .filter(|v| v.is_finite())
            .fold(0.0_f64, |m, v| m.max(v.abs()))
    };
    let error_range = range(&|m| Some(m.position_error));
    let nees_range = range(&|m| m.nees);
    runs.iter()
        .enumerate()
        .skip(1)
        .filter_map(|(k, run)| {
            let mut error_gap = 0.0_f64;
            let mut nees_gap = 0.0_f64;
            for (a, b) in first.history.iter().zip(&run.history) {
                error_gap = error_gap.max((a.position_error - b.position_error).abs());
                if let (Some(x), Some(y)) = (a.nees, b.nees) {
                    nees_gap = nees_gap.max((x - y).abs());
                }
            }
            let same = run.history.len() == first.history.len()
                && error_gap <= 0.005 * error_range
                && nees_gap <= 0.005 * nees_range.max(1.0);
            (same && error_gap.is_finite()).then_some((k, error_gap))
        })
        .collect()
}

/// The note above the plots when two filters' series coincide, naming them.
pub fn coincidence_note(session: &LandmarkSession, pairs: &[(usize, f64)]) -> Option<String> {
    let runs = session.filters();
    let first = runs.first()?.kind.name().to_uppercase();
    let (k, gap) = *pairs.first()?;
    let other = runs.get(k)?.kind.name().to_uppercase();
    Some(format!(
        "{first} and {other} agree here: their lines lie on top of each other (robot errors \
         differ by at most {:.1} mm). Try the precise-range preset, where they part.",
        gap * 1000.0
    ))
}

/// The four plots side by side.
pub fn plots_ui(ui: &mut egui::Ui, session: &LandmarkSession) {
    if let Some(note) = coincidence_note(session, &coinciding_series(session)) {
        ui.label(egui::RichText::new(note).color(ui.visuals().warn_fg_color));
    }
    // The filters' colours once for the row, not a legend over every plot's data.
    let filters: Vec<(String, egui::Color32)> = session
        .filters()
        .iter()
        .map(|run| {
            (
                run.kind.name().to_uppercase(),
                palette::estimator_color(run.kind.name()),
            )
        })
        .collect();
    series_key_ui(
        ui,
        &filters,
        "· solid: error, NEES, NIS; dashed: the filter's own 2σ bound; green: the 95% band \
         of a consistent filter",
    );
    let height = (ui.available_height() - 26.0).max(80.0);
    let dt = session.scenario().dt;
    ui.columns(4, |columns| {
        // 1. Robot position error and the 2σ bound.
        let ui = &mut columns[0];
        title_ui(
            ui,
            "Robot position error",
            "|true − estimated position| and the filter's own 2σ bound 2√(σx² + σy²)",
        );
        plot("plot_robot_error", "error (m)", height).show(ui, |plot_ui| {
            for (index, run) in session.filters().iter().enumerate() {
                let color = palette::estimator_color(run.kind.name());
                let name = run.kind.name().to_uppercase();
                let error = thin(run.history.iter().map(|m| [m.time, m.position_error]).collect());
                let bound = thin(
                    run.history
                        .iter()
                        .map(|m| [m.time, m.position_bound_2sigma])
                        .collect(),
                );
                plot_ui.line(
                    Line::new(format!("{name} error"), PlotPoints::new(error))
                        .color(color)
                        .width(line_width(index, 1.2)),
                );
                plot_ui.line(
                    Line::new(format!("{name} 2σ bound"), PlotPoints::new(bound))
                        .color(color)
                        .style(LineStyle::dashed_dense())
                        .width(line_width(index, 1.0)),
                );
            }
        });

        // 2. Landmark RMS error.
        let ui = &mut columns[1];
        title_ui(
            ui,
            "Mean landmark error",
            "Root mean square position error over the landmarks in each filter's state",
        );
        plot("plot_landmark_rmse", "RMS error (m)", height).show(ui, |plot_ui| {
            for (index, run) in session.filters().iter().enumerate() {
                let color = palette::estimator_color(run.kind.name());
                let points = thin(
                    run.history
                        .iter()
                        .filter_map(|m| m.landmark_rmse.map(|r| [m.time, r]))
                        .collect(),
                );
                plot_ui.line(
                    Line::new(format!("{} landmarks", run.kind.name().to_uppercase()), PlotPoints::new(points))
                        .color(color)
                        .width(line_width(index, 1.2)),
                );
            }
        });

        // 3. Robot-pose NEES with the 3-dof band.
        let ui = &mut columns[2];
        let (lo, hi) = band_95(3.0);
        title_ui(
            ui,
            "Robot pose NEES (3 dof)",
            "e^T P_RR^-1 e of the robot pose each tick. Above the band: overconfident; below: conservative.",
        );
        let y_max = consistency_y_max(
            session
                .filters()
                .iter()
                .flat_map(|run| run.history.iter().filter_map(|m| m.nees)),
            hi,
        );
        plot("plot_nees", "NEES", height)
            .default_y_bounds(0.0, y_max)
            .show(ui, |plot_ui| {
                band_ui(plot_ui, lo, hi);
                for (index, run) in session.filters().iter().enumerate() {
                    let color = palette::estimator_color(run.kind.name());
                    let points = thin(
                        run.history
                            .iter()
                            .filter_map(|m| m.nees.map(|n| [m.time, n]))
                            .collect(),
                    );
                    plot_ui.line(
                        Line::new(format!("{} NEES", run.kind.name().to_uppercase()), PlotPoints::new(points))
                            .color(color)
                            .width(line_width(index, 1.0)),
                    );
                }
            });

        // 4. NIS of every update with the 2-dof band.
        let ui = &mut columns[3];
        let (lo, hi) = band_95(2.0);
        title_ui(
            ui,
            "Update NIS (2 dof)",
            "ν^T S^-1 ν of every landmark update. Above the band: the innovations are larger than the filter expects.",
        );
        let y_max = consistency_y_max(
            session
                .filters()
                .iter()
                .flat_map(|run| run.nis.iter().map(|s| s.nis)),
            hi,
        );
        plot("plot_nis", "NIS", height)
            .default_y_bounds(0.0, y_max)
            .show(ui, |plot_ui| {
                band_ui(plot_ui, lo, hi);
                for (index, run) in session.filters().iter().enumerate() {
                    let color = palette::estimator_color(run.kind.name());
                    let points = thin(
                        run.nis
                            .iter()
                            .map(|s| [s.tick as f64 * dt, s.nis])
                            .collect(),
                    );
                    plot_ui.points(
                        Points::new(format!("{} NIS", run.kind.name().to_uppercase()), PlotPoints::new(points))
                            .color(color)
                            .radius(line_width(index, 1.4)),
                    );
                }
            });
    });
}

/// Every plot's series, unthinned, for the CSV export (the same data as above, and
/// FastSLAM's N_eff from the parameter panel).
pub fn series(session: &LandmarkSession) -> Vec<PlotSeries> {
    let dt = session.scenario().dt;
    let mut out = Vec::new();
    for run in session.filters() {
        let name = run.kind.name().to_uppercase();
        let over_time = |pick: &dyn Fn(&slamlab_sim::session::TickMetrics) -> Option<f64>| {
            run.history
                .iter()
                .filter_map(|m| pick(m).map(|v| [m.time, v]))
                .collect::<Vec<_>>()
        };
        let error = "Robot position error";
        out.push(PlotSeries::new(
            error,
            "time (s)",
            "error (m)",
            format!("{name} error"),
            over_time(&|m| Some(m.position_error)),
        ));
        out.push(PlotSeries::new(
            error,
            "time (s)",
            "error (m)",
            format!("{name} 2σ bound"),
            over_time(&|m| Some(m.position_bound_2sigma)),
        ));
        out.push(PlotSeries::new(
            "Mean landmark error",
            "time (s)",
            "RMS error (m)",
            format!("{name} landmarks"),
            over_time(&|m| m.landmark_rmse),
        ));
        out.push(PlotSeries::new(
            "Robot pose NEES (3 dof)",
            "time (s)",
            "NEES",
            format!("{name} NEES"),
            over_time(&|m| m.nees),
        ));
        out.push(PlotSeries::new(
            "Update NIS (2 dof)",
            "time (s)",
            "NIS",
            format!("{name} NIS"),
            run.nis
                .iter()
                .map(|s| [s.tick as f64 * dt, s.nis])
                .collect(),
        ));
        if !run.n_eff.is_empty() {
            out.push(PlotSeries::new(
                "N_eff before each resampling",
                "tick",
                "N_eff",
                format!("{name} N_eff"),
                run.n_eff.iter().map(|n| [n.tick as f64, n.n_eff]).collect(),
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_and_y_range() {
        let (lo, hi) = band_95(3.0);
        assert!((lo - 0.2158).abs() < 1e-3 && (hi - 9.348).abs() < 1e-3);
        assert!((consistency_y_max(std::iter::empty(), 9.0) - 14.4).abs() < 1e-9);
        assert!((consistency_y_max([1e9, f64::NAN].into_iter(), 9.0) - 180.0).abs() < 1e-9);
    }
}
