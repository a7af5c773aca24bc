//! The one-step view's plot: the marginal of the output's first coordinate, the
//! samples' histogram against each method's Gaussian marginal, so that a mean
//! or a spread that is off shows as a curve beside the bars.

use crate::export::PlotSeries;
use crate::palette;
use crate::widgets::plots::{
    Figure, Mark, Styled, draw_series, figure_plot, figure_ui, key_entries, series_data,
};
use slamlab_core::math;
use slamlab_sim::filters::session::OneStep;

/// The plot's title (and its key in the series list).
const TITLE: &str = "Marginal of the first output";

/// Bins of the samples' histogram.
const BINS: usize = 60;

/// `N(x; mean, variance)`, 0 for a variance that is not positive.
fn normal(x: f64, mean: f64, variance: f64) -> f64 {
    if !(variance > 0.0) {
        return 0.0;
    }
    let d = x - mean;
    math::exp(-0.5 * d * d / variance) / (2.0 * std::f64::consts::PI * variance).sqrt()
}

/// The samples' histogram of the first coordinate (density per unit, as a step
/// line) over the samples' mean ± 4 standard deviations, and the range.
pub fn histogram(result: &OneStep) -> (Vec<[f64; 2]>, [f64; 2]) {
    let m = &result.truth.moments;
    let s = m.covariance[(0, 0)].max(0.0).sqrt().max(1e-9);
    let (lo, hi) = (m.mean[0] - 4.0 * s, m.mean[0] + 4.0 * s);
    let width = (hi - lo) / BINS as f64;
    let mut counts = [0_u32; BINS];
    for p in &result.truth.points {
        let i = ((p[0] - lo) / width).floor();
        if (0.0..BINS as f64).contains(&i) {
            counts[i as usize] += 1;
        }
    }
    let n = result.truth.points.len().max(1) as f64;
    let mut points = Vec::with_capacity(2 * BINS);
    for (i, c) in counts.iter().enumerate() {
        let density = f64::from(*c) / (n * width);
        points.push([lo + i as f64 * width, density]);
        points.push([lo + (i + 1) as f64 * width, density]);
    }
    (points, [lo, hi])
}

/// Every series of the plot, for the plot and the CSV export.
fn plotted(
    result: &OneStep,
    histogram: &[[f64; 2]],
    range: [f64; 2],
    text: egui::Color32,
) -> Vec<Styled> {
    let x_axis = "first output";
    let y_axis = "density (1/unit)";
    let mut out = vec![Styled::new(
        PlotSeries::new(
            TITLE,
            x_axis,
            y_axis,
            "samples (histogram)",
            histogram.to_vec(),
        ),
        text,
        Mark::Solid,
        1.0,
    )];
    for (row, color) in result
        .rows
        .iter()
        .zip([palette::BLUE, palette::ORANGE, palette::PURPLE])
    {
        let (mean, variance) = (row.gaussian.mean[0], row.gaussian.covariance[(0, 0)]);
        let points = (0..=200)
            .map(|k| {
                let x = range[0] + (range[1] - range[0]) * f64::from(k) / 200.0;
                [x, normal(x, mean, variance)]
            })
            .collect();
        let name = match row.method {
            "ekf" => "EKF",
            "ukf" => "UKF",
            _ => "particles",
        };
        out.push(Styled::new(
            PlotSeries::new(TITLE, x_axis, y_axis, name, points),
            color,
            Mark::Solid,
            1.8,
        ));
    }
    out
}

/// The plot, `height` points tall with its title and key.
pub fn marginal_ui(
    ui: &mut egui::Ui,
    result: &OneStep,
    histogram: &[[f64; 2]],
    range: [f64; 2],
    height: f32,
) {
    let text = palette::truth_color(ui.visuals().dark_mode);
    let all = plotted(result, histogram, range, text);
    let figure = Figure {
        title: TITLE,
        hover: "The samples' histogram of the output's first coordinate against the first \
                coordinate of each method's Gaussian: where a curve misses the bars, that \
                Gaussian's mean or spread is off.",
        key: key_entries(&all, TITLE),
        y_label: "density (1/unit)",
        height,
    };
    figure_ui(
        ui,
        &figure,
        |h, y| figure_plot("filters_marginal", "first output (its unit)", y, h).include_y(0.0),
        |p| draw_series(p, &all, TITLE),
    );
}

/// The plot's series, unthinned, for the CSV export.
pub fn series(result: &OneStep, histogram: &[[f64; 2]], range: [f64; 2]) -> Vec<PlotSeries> {
    series_data(plotted(result, histogram, range, egui::Color32::BLACK))
}
