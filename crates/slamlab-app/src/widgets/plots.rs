//! Plot helpers every lesson shares: a time axis with a 1-2-5 grid and honest
//! labels, titles with hover help, thinning of long series, line widths that keep
//! coinciding filters visible, and series defined once for both the plot and the
//! CSV export ([`Styled`]).

use crate::export::PlotSeries;
use egui::Color32;
use egui_plot::{Legend, Line, LineStyle, Plot, PlotPoints, PlotUi, Points};
use slamlab_core::math;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// A solid line.
    Solid,
    /// A dashed line (a bound, a second quantity of the same filter).
    Dashed,
    /// A dashed ±bound: the series holds the bound, drawn at +y and at −y.
    DashedPlusMinus,
    /// Separate points (one per event, such as an update).
    Dots,
}

/// A plotted series as a lesson defines it, once: its data (what the CSV export
/// writes, unthinned) and how the plot draws it.
#[derive(Clone, Debug)]
pub struct Styled {
    /// The plot it belongs to, its axes, its name and its points.
    pub data: PlotSeries,
    /// Its colour.
    pub color: Color32,
    /// Line or points.
    pub mark: Mark,
    /// Line width or point radius, points.
    pub width: f32,
}

impl Styled {
    /// `data` drawn as `mark` in `color`, `width` points wide.
    pub fn new(data: PlotSeries, color: Color32, mark: Mark, width: f32) -> Self {
        Self {
            data,
            color,
            mark,
            width,
        }
    }
}

/// Draws, in order, every series of `all` that belongs to the plot titled `plot`,
/// thinned for the screen. Series without points are left out (no legend entry
/// for nothing).
pub fn draw_series(plot_ui: &mut PlotUi<'_>, all: &[Styled], plot: &str) {
    for s in all.iter().filter(|s| s.data.plot == plot) {
        let points = thin(s.data.points.clone());
        if points.is_empty() {
            continue;
        }
        let name = s.data.series.clone();
        match s.mark {
            Mark::DashedPlusMinus => {
                let below: Vec<[f64; 2]> = points.iter().map(|p| [p[0], -p[1]]).collect();
                for side in [points, below] {
                    plot_ui.line(
                        Line::new(name.clone(), PlotPoints::new(side))
                            .color(s.color)
                            .style(LineStyle::dashed_dense())
                            .width(s.width),
                    );
                }
            }
            Mark::Solid | Mark::Dashed => {
                let line = Line::new(name, PlotPoints::new(points))
                    .color(s.color)
                    .width(s.width);
                plot_ui.line(if s.mark == Mark::Dashed {
                    line.style(LineStyle::dashed_dense())
                } else {
                    line
                });
            }
            Mark::Dots => plot_ui.points(
                Points::new(name, PlotPoints::new(points))
                    .color(s.color)
                    .radius(s.width),
            ),
        }
    }
}

/// The data of every series, for the CSV export.
pub fn series_data(all: Vec<Styled>) -> Vec<PlotSeries> {
    all.into_iter().map(|s| s.data).collect()
}

/// The y values of the series of plot `plot` (for a plot's y range).
pub fn plot_values<'a>(all: &'a [Styled], plot: &'a str) -> impl Iterator<Item = f64> + 'a {
    all.iter()
        .filter(move |s| s.data.plot == plot)
        .flat_map(|s| s.data.points.iter().map(|p| p[1]))
}

/// Line width (or point radius) of the `index`-th filter's series: the first is drawn
/// widest, so that where two filters agree the later line runs inside the earlier one
/// and both stay visible (EKF blue around UKF orange).
pub fn line_width(index: usize, base: f32) -> f32 {
    base + 0.9 * (2.0 - index.min(2) as f32)
}

/// Longest series drawn, in points; longer ones are thinned evenly.
pub const MAX_POINTS: usize = 3000;

/// Thins `points` evenly to at most [`MAX_POINTS`], keeping the last one.
pub fn thin(points: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    let points: Vec<[f64; 2]> = points
        .into_iter()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
        .collect();
    let stride = points.len() / MAX_POINTS + 1;
    if stride == 1 {
        return points;
    }
    let last = points.len().saturating_sub(1);
    points
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % stride == 0 || *i == last)
        .map(|(_, p)| p)
        .collect()
}

/// A plot's title, with what it shows on hover.
pub fn title_ui(ui: &mut egui::Ui, title: &str, hover: &str) {
    ui.label(egui::RichText::new(title).strong())
        .on_hover_text(hover);
}

/// Grid steps for the time axis, `[minor, labelled, major]`, on a 1-2-5 sequence:
/// `base_step` is the value 8 screen points span (egui_plot's finest grid), and tick
/// labels need about 60 points (the x axis's minimum label spacing). The default
/// powers-of-ten grid labels only 0 on a narrow plot of a short run.
pub fn time_axis_steps(base_step: f64) -> [f64; 3] {
    let wanted = base_step.abs() * 60.0 / 8.0;
    if !(wanted.is_finite() && wanted > 0.0) {
        return [1.0, 2.0, 10.0];
    }
    let decade = math::powf(10.0, math::log10(wanted).floor());
    let (label, minor, major) = match wanted / decade {
        m if m <= 1.0 => (1.0, 0.5, 10.0),
        m if m <= 2.0 => (2.0, 1.0, 10.0),
        m if m <= 5.0 => (5.0, 1.0, 10.0),
        _ => (10.0, 5.0, 100.0),
    };
    [minor * decade, label * decade, major * decade]
}

/// The label of a time-axis grid mark: as many decimals as its step needs (a 0.5 s
/// mark reads "1.5", not "2"), and none before the run starts.
pub fn time_axis_label(mark: egui_plot::GridMark) -> String {
    if !(mark.value.is_finite() && mark.step_size.is_finite() && mark.step_size > 0.0)
        || mark.value < -1e-9
    {
        return String::new();
    }
    let decimals = (-math::log10(mark.step_size) - 1e-9).ceil().clamp(0.0, 6.0) as usize;
    format!("{:.*}", decimals, mark.value.max(0.0))
}

/// A plot over time: the time axis with its 1-2-5 grid and labels, and the legend in
/// the top left corner.
pub fn time_plot<'a>(id: &str, y_label: &str, height: f32) -> Plot<'a> {
    time_plot_without_legend(id, y_label, height).legend(
        Legend::default()
            .position(egui_plot::Corner::LeftTop)
            .text_style(egui::TextStyle::Small)
            .background_alpha(0.55),
    )
}

/// One line above a row of plots that names each filter's colour and what solid and
/// dashed mean, instead of a legend inside every plot over the data.
pub fn series_key_ui(ui: &mut egui::Ui, filters: &[(String, egui::Color32)], styles: &str) {
    ui.horizontal_wrapped(|ui| {
        for (name, color) in filters {
            ui.label(
                egui::RichText::new(format!("— {name}"))
                    .color(*color)
                    .strong(),
            );
        }
        ui.label(styles);
    });
}

/// [`time_plot`] without a legend (the row's [`series_key_ui`] names the series).
pub fn time_plot_without_legend<'a>(id: &str, y_label: &str, height: f32) -> Plot<'a> {
    Plot::new(id)
        .height(height)
        .x_axis_label("time (s)")
        .y_axis_label(y_label.to_owned())
        .x_grid_spacer(egui_plot::uniform_grid_spacer(|input| {
            time_axis_steps(input.base_step_size)
        }))
        .x_axis_formatter(|mark, _range| time_axis_label(mark))
        .include_x(0.0)
        .allow_scroll(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plot_reads_its_own_series_and_the_export_all_of_them() {
        let series = |plot: &str, name: &str, y: f64| {
            Styled::new(
                PlotSeries::new(plot, "t", "y", name, vec![[0.0, y], [1.0, 2.0 * y]]),
                Color32::RED,
                Mark::Solid,
                1.0,
            )
        };
        let all = vec![
            series("A", "a1", 1.0),
            series("B", "b1", 5.0),
            series("A", "a2", 3.0),
        ];
        assert_eq!(
            plot_values(&all, "A").collect::<Vec<_>>(),
            [1.0, 2.0, 3.0, 6.0]
        );
        assert_eq!(plot_values(&all, "C").count(), 0);
        let names: Vec<String> = series_data(all).into_iter().map(|s| s.series).collect();
        assert_eq!(names, ["a1", "b1", "a2"], "every series, in order");
    }

    #[test]
    fn thinning_keeps_the_ends_and_bounds_the_count() {
        let points: Vec<[f64; 2]> = (0..10_000).map(|i| [i as f64, 0.0]).collect();
        let thinned = thin(points);
        assert!(thinned.len() <= MAX_POINTS + 1);
        assert_eq!(thinned.first().map(|p| p[0]), Some(0.0));
        assert_eq!(thinned.last().map(|p| p[0]), Some(9999.0));
    }

    #[test]
    fn time_axis_labels_land_60_points_or_more_apart_on_nested_steps() {
        // 45 points per second (a 6 s run on a 280-point plot): base step 8/45 s.
        assert_eq!(time_axis_steps(8.0 / 45.0), [1.0, 2.0, 10.0]);
        // A 200 s run on the same plot: 1.4 points per second.
        let [minor, label, major] = time_axis_steps(8.0 / 1.4);
        assert_eq!([minor, label, major], [10.0, 50.0, 100.0]);
        for base in [1e-3, 0.013, 0.17, 0.5, 2.2, 7.0, 31.0, 640.0] {
            let [minor, label, major] = time_axis_steps(base);
            let label_points = label / base * 8.0;
            assert!(label_points >= 60.0 - 1e-9, "{base}: {label_points}");
            assert!(
                label_points < 60.0 * 2.6,
                "{base}: labels {label_points} apart"
            );
            for (fine, coarse) in [(minor, label), (label, major)] {
                let ratio = coarse / fine;
                assert!(
                    (ratio - ratio.round()).abs() < 1e-9,
                    "{base}: {fine} vs {coarse}"
                );
            }
        }
        for bad in [0.0, f64::NAN, f64::INFINITY] {
            assert_eq!(time_axis_steps(bad), [1.0, 2.0, 10.0]);
        }
    }

    #[test]
    fn time_labels_carry_the_decimals_of_their_step_and_start_at_zero() {
        let label = |value, step_size| time_axis_label(egui_plot::GridMark { value, step_size });
        assert_eq!(label(0.5, 0.5), "0.5");
        assert_eq!(label(1.5, 0.5), "1.5");
        assert_eq!(label(2.0, 0.5), "2.0");
        assert_eq!(label(2.0, 1.0), "2");
        assert_eq!(label(20.0, 10.0), "20");
        assert_eq!(label(0.25, 0.05), "0.25");
        assert_eq!(label(0.3, 0.1), "0.3");
        assert_eq!(label(0.0, 1.0), "0");
        assert_eq!(label(-1e-12, 1.0), "0");
        assert_eq!(label(-1.0, 1.0), "");
        assert_eq!(label(f64::NAN, 1.0), "");
        assert_eq!(label(1.0, 0.0), "");
    }
}
