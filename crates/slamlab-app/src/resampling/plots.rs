//! The lab's plots: the plotted particle's copy counts over every resampling so
//! far, per method, against the binomial law that multinomial resampling
//! follows; and every particle's copy-count variance per method against the
//! binomial variance `M wᵢ (1 − wᵢ)` and the least any unbiased method can give,
//! `f (1 − f)` with `f` the fractional part of `M wᵢ`.

use super::method_color;
use crate::export::PlotSeries;
use crate::palette;
use crate::widgets::plots::{
    Figure, KeyEntry, Mark, columns_ui, figure_plot, figure_ui, line_width, marker_radius,
};
use egui_plot::{Bar, BarChart, Line, LineStyle, PlotPoints, Points};
use slamlab_sim::resampling::session::LabRun;

/// The two plots side by side.
pub fn plots_ui(ui: &mut egui::Ui, run: &LabRun) {
    let height = ui.available_height().max(80.0);
    let lab = run.lab();
    let methods = &run.scenario().methods;
    let m = run.particles();
    let focus = run.focus();
    let truth = palette::truth_color(ui.visuals().dark_mode);
    let method_keys = |mark: Mark| {
        methods
            .iter()
            .map(|&method| KeyEntry::new(method.name(), method_color(method), mark))
            .collect::<Vec<_>>()
    };
    columns_ui(ui, 2, |k, ui| {
        if k == 0 {
            let expected = lab.expected_copies().get(focus).copied().unwrap_or(0.0);
            // Up to the largest count seen or likely, so a histogram is never cut.
            let seen = methods
                .iter()
                .filter_map(|&method| lab.histogram(method, focus).iter().rposition(|&n| n > 0))
                .max()
                .unwrap_or(0);
            let k_max = seen
                .max((expected + 4.0 * expected.sqrt() + 2.0).ceil() as usize)
                .min(m);
            let width = 0.8 / methods.len().max(1) as f64;
            let title = format!("Copies of particle {focus} (M·w = {expected:.2})");
            let mut key = method_keys(Mark::Solid);
            key.push(KeyEntry::new(
                "binomial (multinomial's law)",
                truth,
                Mark::Dots,
            ));
            figure_ui(
                ui,
                &Figure {
                    title: &title,
                    hover: "How often each method gave this particle 0, 1, 2, … copies, over every \
                        resampling so far; the dots are the binomial law of multinomial \
                        resampling. Click a column of the row above to pick another particle.",
                    key,
                    y_label: "fraction of resamplings",
                    height,
                },
                |h, y| {
                    figure_plot("resampling_histogram", "copies", y, h)
                        .include_y(0.0)
                        .include_y(1.0)
                        .include_x(-0.5)
                        .include_x(k_max as f64 + 0.5)
                },
                |plot_ui| {
                    for (j, &method) in methods.iter().enumerate() {
                        let histogram = lab.histogram(method, focus);
                        let total: u64 = histogram.iter().sum();
                        if total == 0 {
                            continue;
                        }
                        let offset = (j as f64 - (methods.len() as f64 - 1.0) / 2.0) * width;
                        let bars: Vec<Bar> = histogram
                            .iter()
                            .enumerate()
                            .take(k_max + 1)
                            .map(|(k, &n)| {
                                Bar::new(k as f64 + offset, n as f64 / total as f64)
                                    .width(width * 0.95)
                                    .name(format!("{} copies", k))
                            })
                            .collect();
                        plot_ui.bar_chart(
                            BarChart::new(method.name(), bars).color(method_color(method)),
                        );
                    }
                    let binomial: Vec<[f64; 2]> = (0..=k_max)
                        .map(|k| [k as f64, run.binomial_pmf(focus, k)])
                        .collect();
                    let radius = marker_radius(3.0, plot_ui.response().rect.height());
                    plot_ui.points(
                        Points::new("binomial (multinomial's law)", PlotPoints::new(binomial))
                            .color(truth)
                            .radius(radius),
                    );
                },
            );
        } else {
            let mut key = vec![
                KeyEntry::new("M w (1 − w): multinomial", truth, Mark::Dashed),
                KeyEntry::new("f (1 − f): least possible", truth, Mark::Dotted),
            ];
            key.extend(method_keys(Mark::Solid));
            figure_ui(
                ui,
                &Figure {
                    title: "Copy-count variance per particle",
                    hover: "The variance of each particle's copy count over every resampling so \
                        far, per method: the noise resampling adds. Dashed: multinomial's \
                        binomial variance M w (1 − w). Dotted: the least any unbiased method \
                        can give, f (1 − f) with f the fractional part of M w; low-variance \
                        resampling reaches it.",
                    key,
                    y_label: "variance of copies",
                    height,
                },
                |h, y| {
                    figure_plot("resampling_variance", "particle", y, h)
                        .include_y(0.0)
                        .include_x(0.0)
                        .include_x(m.saturating_sub(1) as f64)
                },
                |plot_ui| {
                    let binomial: Vec<[f64; 2]> = (0..m)
                        .map(|i| [i as f64, run.multinomial_variance_of(i)])
                        .collect();
                    plot_ui.line(
                        Line::new("M w (1 − w)", PlotPoints::new(binomial))
                            .color(truth)
                            .style(LineStyle::dashed_dense())
                            .width(1.2),
                    );
                    let least: Vec<[f64; 2]> = (0..m)
                        .map(|i| [i as f64, run.least_variance_of(i)])
                        .collect();
                    plot_ui.line(
                        Line::new("f (1 − f): least possible", PlotPoints::new(least))
                            .color(truth)
                            .style(LineStyle::dotted_dense())
                            .width(1.2),
                    );
                    for (j, &method) in methods.iter().enumerate() {
                        let Some(stats) = lab.stats(method).filter(|s| s.trials() > 1) else {
                            continue;
                        };
                        let points: Vec<[f64; 2]> = stats
                            .variances()
                            .iter()
                            .enumerate()
                            .map(|(i, &v)| [i as f64, v])
                            .collect();
                        plot_ui.line(
                            Line::new(method.name(), PlotPoints::new(points))
                                .color(method_color(method))
                                .width(line_width(j.min(2), 1.0)),
                        );
                    }
                },
            );
        }
    });
}

/// Every plot's series, for the CSV export: each method's copy-count histogram of
/// the plotted particle (fractions), the binomial law, and every particle's
/// copy-count variance per method with the two reference curves.
pub fn series(run: &LabRun) -> Vec<PlotSeries> {
    let lab = run.lab();
    let m = run.particles();
    let focus = run.focus();
    let copies = format!("Copies of particle {focus}");
    let mut out = Vec::new();
    for &method in &run.scenario().methods {
        let histogram = lab.histogram(method, focus);
        let total: u64 = histogram.iter().sum();
        if total > 0 {
            out.push(PlotSeries::new(
                &copies,
                "copies",
                "fraction of resamplings",
                method.name(),
                histogram
                    .iter()
                    .enumerate()
                    .map(|(k, &n)| [k as f64, n as f64 / total as f64])
                    .collect(),
            ));
        }
    }
    out.push(PlotSeries::new(
        &copies,
        "copies",
        "fraction of resamplings",
        "binomial (multinomial's law)",
        (0..=m)
            .map(|k| [k as f64, run.binomial_pmf(focus, k)])
            .collect(),
    ));
    let variance = "Copy-count variance per particle";
    out.push(PlotSeries::new(
        variance,
        "particle",
        "variance of copies",
        "M w (1 − w)",
        (0..m)
            .map(|i| [i as f64, run.multinomial_variance_of(i)])
            .collect(),
    ));
    out.push(PlotSeries::new(
        variance,
        "particle",
        "variance of copies",
        "f (1 − f): least possible",
        (0..m)
            .map(|i| [i as f64, run.least_variance_of(i)])
            .collect(),
    ));
    for &method in &run.scenario().methods {
        if let Some(stats) = lab.stats(method).filter(|s| s.trials() > 1) {
            out.push(PlotSeries::new(
                variance,
                "particle",
                "variance of copies",
                method.name(),
                stats
                    .variances()
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| [i as f64, v])
                    .collect(),
            ));
        }
    }
    out
}
