//! Plot helpers every lesson shares: axes with a 1-2-5 grid and honest labels at
//! every size, titles with hover help, a key on a line above the plot (never over
//! its data), plots that stay where they are put (no pan or zoom a student must undo),
//! thinning of long series, line widths that keep coinciding filters visible, and
//! series defined once for both the plot and the CSV export ([`Styled`]).
//!
//! [`figure_ui`] draws one plot the way every lesson should: title, key, axes with
//! values, the y-axis name moved into the title when the plot is too short for it.
//! Each drawn plot and key leaves its rectangles in [`figure_records`], for the
//! shell's render tests.

use crate::export::PlotSeries;
use egui::Color32;
use egui_plot::{Line, LineStyle, Plot, PlotPoints, PlotUi, Points};
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
    /// A dotted line (a second bound beside a dashed one).
    Dotted,
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

/// Draws every series of `all` that belongs to the plot titled `plot`, thinned for
/// the screen: first the dashed ones (bounds), then the lines, then the markers, each
/// group in order, so that a bound never hides the curve it bounds. Series without
/// points are left out.
pub fn draw_series(plot_ui: &mut PlotUi<'_>, all: &[Styled], plot: &str) {
    let plot_height = plot_ui.response().rect.height();
    let layer = |mark: Mark| match mark {
        Mark::Dashed | Mark::DashedPlusMinus | Mark::Dotted => 0,
        Mark::Solid => 1,
        Mark::Dots => 2,
    };
    let mut ordered: Vec<&Styled> = all.iter().filter(|s| s.data.plot == plot).collect();
    ordered.sort_by_key(|s| layer(s.mark));
    let drawn = ordered.iter().any(|s| {
        s.data
            .points
            .iter()
            .any(|p| p[0].is_finite() && p[1].is_finite())
    });
    note_drawn(plot_ui.ctx(), drawn);
    for s in ordered {
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
            Mark::Solid | Mark::Dashed | Mark::Dotted => {
                let line = Line::new(name, PlotPoints::new(points))
                    .color(s.color)
                    .width(s.width);
                plot_ui.line(match s.mark {
                    Mark::Dashed => line.style(LineStyle::dashed_dense()),
                    Mark::Dotted => line.style(LineStyle::dotted_dense()),
                    _ => line,
                });
            }
            Mark::Dots => plot_ui.points(
                Points::new(name, PlotPoints::new(points))
                    .color(s.color)
                    .radius(marker_radius(s.width, plot_height)),
            ),
        }
    }
}

fn drawn_id() -> egui::Id {
    egui::Id::unique("slamlab_plot_drawn")
}

/// Tells the figure being drawn whether its series had any point ([`draw_series`]
/// calls this; a lesson that draws its own items calls it with true).
pub fn note_drawn(ctx: &egui::Context, drawn: bool) {
    ctx.data_mut(|d| {
        let seen: &mut Option<bool> = d.get_temp_mut_or_default(drawn_id());
        *seen = Some(seen.unwrap_or(false) || drawn);
    });
}

/// What an empty plot says instead of a meaningless axis.
pub const EMPTY_PLOT_TEXT: &str = "Nothing yet: press Run or Step";

/// A marker's radius on a plot `plot_height` points tall: `radius` on a plot of 150
/// points or more, smaller on a smaller one (down to 40%), so that events stay
/// separate dots instead of a blob.
pub fn marker_radius(radius: f32, plot_height: f32) -> f32 {
    let scale = if plot_height.is_finite() {
        (plot_height / 150.0).clamp(0.4, 1.0)
    } else {
        1.0
    };
    (radius * scale).max(0.8)
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

/// Grid steps `[minor, labelled, major]` on a 1-2-5 sequence for an axis whose
/// labels need `label_points` screen points between them: `base_step` is the value
/// 8 screen points span (egui_plot's finest grid). egui_plot's default grid steps by
/// powers of ten, which on a short plot labels only 0.
pub fn nice_axis_steps(base_step: f64, label_points: f64) -> [f64; 3] {
    let wanted = base_step.abs() * label_points / 8.0;
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

/// Grid steps for the time axis, `[minor, labelled, major]`, on a 1-2-5 sequence:
/// tick labels need about 60 points (the x axis's minimum label spacing).
pub fn time_axis_steps(base_step: f64) -> [f64; 3] {
    nice_axis_steps(base_step, X_LABEL_POINTS)
}

/// Screen points between two labelled marks of an x axis (a label is a few digits wide).
pub const X_LABEL_POINTS: f64 = 60.0;
/// Screen points between two labelled marks of a y axis (a label is one line high;
/// egui_plot shows y labels at full strength from 30 points apart).
pub const Y_LABEL_POINTS: f64 = 30.0;

/// The label of a time-axis grid mark: as many decimals as its step needs (a 0.5 s
/// mark reads "1.5", not "2"), and none before the run starts.
pub fn time_axis_label(mark: egui_plot::GridMark) -> String {
    if !(mark.value.is_finite() && mark.step_size.is_finite() && mark.step_size > 0.0)
        || mark.value < -1e-9
    {
        return String::new();
    }
    value_axis_label(egui_plot::GridMark {
        value: mark.value.max(0.0),
        step_size: mark.step_size,
    })
}

/// The label of a value-axis grid mark: as many decimals as its step needs (0.05 m
/// steps read "0.15", 2 m steps "4"), never "-0".
pub fn value_axis_label(mark: egui_plot::GridMark) -> String {
    if !(mark.value.is_finite() && mark.step_size.is_finite() && mark.step_size > 0.0) {
        return String::new();
    }
    let decimals = decimals_of(mark.step_size);
    // A mark within a millionth of a step of zero is zero (no "-0.00").
    let value = if mark.value.abs() < 1e-6 * mark.step_size {
        0.0
    } else {
        mark.value
    };
    format!("{:.*}", decimals, value)
}

/// A plot that shows its data and stays put: a 1-2-5 grid with labelled values on
/// both axes, the axes named, no legend over the data (the key is a line above:
/// [`key_ui`]), and no pan, zoom or axis drag that a student would have to undo.
/// `height` is the whole plot's (axes included); the y values are spaced to it
/// ([`value_axis_marks`]) so that even a short plot shows at least two.
pub fn figure_plot<'a>(id: &str, x_label: &str, y_label: &str, height: f32) -> Plot<'a> {
    let y_axis = egui_plot::AxisHints::new_y()
        .label(egui::RichText::new(y_label).small())
        .formatter(|mark, _range| value_axis_label(mark))
        .tick_label_font(egui::FontId::proportional(TICK_FONT_SIZE))
        // Every mark the spacer gives is a labelled value, at full strength.
        .label_spacing(LEAST_Y_LABEL_POINTS - 1.0..=LEAST_Y_LABEL_POINTS);
    let x_axis = egui_plot::AxisHints::new_x()
        .label(egui::RichText::new(x_label).small())
        .formatter(|mark, _range| value_axis_label(mark))
        .tick_label_font(egui::FontId::proportional(TICK_FONT_SIZE));
    Plot::new(id)
        .height(height)
        .custom_x_axes(vec![x_axis])
        .custom_y_axes(vec![y_axis])
        .x_grid_spacer(egui_plot::uniform_grid_spacer(|input| {
            nice_axis_steps(input.base_step_size, X_LABEL_POINTS)
        }))
        .y_grid_spacer(|input| {
            value_axis_marks(
                input.bounds,
                input.base_step_size,
                Y_LABEL_POINTS,
                f64::from(LEAST_Y_LABEL_POINTS),
            )
        })
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .allow_boxed_zoom(false)
        .allow_axis_zoom_drag(false)
        .allow_double_click_reset(false)
}

/// The size of tick labels, points (a little under egui's body text, so that values
/// fit a short plot).
pub const TICK_FONT_SIZE: f32 = 11.0;

/// The least room between two labelled y values, points (one tick label's height).
pub const LEAST_Y_LABEL_POINTS: f32 = 13.0;

/// The labelled marks of a value axis showing `bounds`, where `base_step` is the
/// value 8 screen points span: multiples of the 1-2-5 step that puts them
/// `preferred` points apart, or of a smaller one (down to `least` points apart) when
/// that leaves fewer than two values on the axis (a short plot, a range such as
/// −4.6..4.6 where steps of 5 label only 0). Only labelled values get grid lines.
pub fn value_axis_marks(
    bounds: (f64, f64),
    base_step: f64,
    preferred: f64,
    least: f64,
) -> Vec<egui_plot::GridMark> {
    let (lo, hi) = (bounds.0.min(bounds.1), bounds.0.max(bounds.1));
    let points_per_value = 8.0 / base_step.abs();
    if !(lo.is_finite() && hi.is_finite() && points_per_value.is_finite() && hi > lo) {
        return Vec::new();
    }
    let count = |step: f64| ((hi / step).floor() - (lo / step).ceil() + 1.0).max(0.0);
    let mut step = nice_axis_steps(base_step, preferred)[1];
    while count(step) < 2.0 {
        let smaller = step_down(step);
        if smaller * points_per_value < least {
            break;
        }
        step = smaller;
    }
    let first = (lo / step).ceil();
    let last = (hi / step).floor();
    if !(last - first < 1000.0) {
        return Vec::new();
    }
    let mut marks = Vec::new();
    let mut k = first;
    while k <= last {
        marks.push(egui_plot::GridMark {
            value: k * step,
            step_size: step,
        });
        k += 1.0;
    }
    marks
}

/// The next smaller step of the 1-2-2.5-5 ladder: 5 to 2.5, 2.5 to 2, 2 to 1, 1 to 0.5.
fn step_down(step: f64) -> f64 {
    let decade = math::powf(10.0, math::log10(step).floor());
    let mantissa = (step / decade * 10.0).round() / 10.0;
    if mantissa >= 5.0 {
        2.5 * decade
    } else if mantissa >= 2.5 {
        2.0 * decade
    } else if mantissa >= 2.0 {
        decade
    } else {
        0.5 * decade
    }
}

/// The decimals a multiple of `step` needs: 0 for 2, 1 for 0.5 and 2.5, 2 for 0.05.
fn decimals_of(step: f64) -> usize {
    (0..6)
        .find(|&d| {
            let scaled = step * math::powf(10.0, d as f64);
            (scaled - scaled.round()).abs() < 1e-6 * scaled.abs().max(1.0)
        })
        .unwrap_or(6)
}

/// A plot over time: [`figure_plot`] with the time axis's 1-2-5 grid and labels from
/// 0 s. It has no legend: draw its key above with [`key_ui`] (or a row's
/// [`series_key_ui`]).
pub fn time_plot<'a>(id: &str, y_label: &str, height: f32) -> Plot<'a> {
    figure_plot(id, "time (s)", y_label, height)
        .x_grid_spacer(egui_plot::uniform_grid_spacer(|input| {
            time_axis_steps(input.base_step_size)
        }))
        .x_axis_formatter(|mark, _range| time_axis_label(mark))
        .include_x(0.0)
}

/// A plot of the row under a lesson's map ([`time_plot`]): the row's plots
/// share their time axis (`axis` names the row's link) and always show the
/// first second and zero.
pub fn row_time_plot<'a>(id: &str, y_label: &str, height: f32, axis: &str) -> Plot<'a> {
    time_plot(id, y_label, height)
        .link_axis(egui::Id::unique(axis), [true, false])
        .include_x(1.0)
        .include_y(0.0)
}

/// One entry of a plot's key: a name, its colour and how it is drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct KeyEntry {
    /// What the entry names.
    pub name: String,
    /// Its colour.
    pub color: Color32,
    /// Line, dashes or markers, drawn as a small sample before the name.
    pub mark: Mark,
}

impl KeyEntry {
    /// An entry named `name`, drawn as `mark` in `color`.
    pub fn new(name: impl Into<String>, color: Color32, mark: Mark) -> Self {
        Self {
            name: name.into(),
            color,
            mark,
        }
    }
}

/// The key of the plot titled `plot`: one entry per series with points, in order.
pub fn key_entries(all: &[Styled], plot: &str) -> Vec<KeyEntry> {
    all.iter()
        .filter(|s| s.data.plot == plot && !s.data.points.is_empty())
        .map(|s| KeyEntry::new(s.data.series.clone(), s.color, s.mark))
        .collect()
}

/// The key of the plot titled `plot` by style only, for a row of plots whose
/// colours a [`series_key_ui`] line above the row names: one entry per distinct
/// series name without its first word (the filter's: "EKF error" and "UKF error"
/// are one "error" entry) and mark, drawn in `color` (the text colour).
pub fn style_entries(all: &[Styled], plot: &str, color: Color32) -> Vec<KeyEntry> {
    let mut out: Vec<KeyEntry> = Vec::new();
    for s in all
        .iter()
        .filter(|s| s.data.plot == plot && !s.data.points.is_empty())
    {
        let name = s
            .data
            .series
            .split_once(' ')
            .map_or(s.data.series.as_str(), |(_, rest)| rest);
        let entry = KeyEntry::new(name, color, s.mark);
        if !out.contains(&entry) {
            out.push(entry);
        }
    }
    out
}

/// Draws a key on a line (wrapped when needed) above a plot: a sample of each
/// entry's line, dashes or marker, then its name. Returns the rectangle it took
/// (recorded in [`figure_records`]).
pub fn key_ui(ui: &mut egui::Ui, entries: &[KeyEntry]) -> egui::Rect {
    if entries.is_empty() {
        return egui::Rect::NOTHING;
    }
    let rect = key_lines_ui(ui, entries);
    record_key(ui.ctx(), rect);
    rect
}

fn record_key(ctx: &egui::Context, rect: egui::Rect) {
    record(
        ctx,
        FigureRecord {
            title: String::new(),
            data: None,
            key: Some(rect),
            map: None,
            image: None,
        },
    );
}

/// The gap [`key_lines_ui`] puts between a name and the next entry's sample, points.
const KEY_ENTRY_GAP: f32 = 6.0;
/// The space between a sample and its name, points.
const KEY_ITEM_SPACING: f32 = 4.0;
/// The width of an entry's sample, points.
const KEY_SAMPLE_WIDTH: f32 = 18.0;

/// Draws `entries` on lines (wrapped when needed), without recording them. Where
/// the lines break is [`key_line_count`]'s rule, so that a figure can know the
/// key's height before it draws it.
fn key_lines_ui(ui: &mut egui::Ui, entries: &[KeyEntry]) -> egui::Rect {
    ui.horizontal_wrapped(|ui| {
        ui.spacing_mut().item_spacing.x = KEY_ITEM_SPACING;
        let row_width = ui.max_rect().width();
        for (k, entry) in entries.iter().enumerate() {
            // A sample and its name start a new line together when they do not
            // fit on this one; the gap between entries never runs past the edge.
            let left = ui.available_size_before_wrap().x;
            if k > 0 && key_entry_breaks(key_entry_width(ui, entry), left, row_width) {
                ui.end_row();
            } else if k > 0 {
                ui.add_space(KEY_ENTRY_GAP);
            }
            mark_sample_ui(ui, entry.color, entry.mark);
            ui.label(egui::RichText::new(&entry.name).small());
        }
    })
    .response
    .rect
}

/// The width of an entry's sample and name, points.
fn key_entry_width(ui: &egui::Ui, entry: &KeyEntry) -> f32 {
    KEY_SAMPLE_WIDTH + KEY_ITEM_SPACING + text_width(ui, &entry.name, egui::TextStyle::Small)
}

/// Whether an entry `width` points wide starts a new line where `left` points are
/// left of a line `row_width` wide (never on a line of its own already).
fn key_entry_breaks(width: f32, left: f32, row_width: f32) -> bool {
    width + KEY_ENTRY_GAP + KEY_ITEM_SPACING > left && left < row_width - 1.0
}

/// How many lines [`key_ui`] draws `entries` on in a line `row_width` points wide,
/// and how many of its entries are wider than the line (their names wrap): after
/// each entry the cursor has moved by its width and the spacing, before the next by
/// the gap, and an entry that does not fit starts a new line.
fn key_line_count(ui: &egui::Ui, entries: &[KeyEntry], row_width: f32) -> (usize, usize) {
    let mut lines = 0;
    let mut wrapped = 0;
    let mut used = 0.0;
    for (k, entry) in entries.iter().enumerate() {
        let width = key_entry_width(ui, entry);
        if k == 0 || key_entry_breaks(width, row_width - used, row_width) {
            lines += 1;
            used = 0.0;
        } else {
            used += KEY_ENTRY_GAP;
        }
        used += width + KEY_ITEM_SPACING;
        if width > row_width {
            // Each further line of its name; rounded up, as the name breaks at words.
            wrapped += (width / row_width.max(1.0)).ceil() as usize;
        }
    }
    (lines, wrapped)
}

/// The height [`key_ui`] takes for `entries` in a line `row_width` points wide:
/// the first line as tall as a row of buttons (`interact_size.y`, egui's wrapped
/// layouts start there), each further line a line of small text and the spacing;
/// names wider than the line add lines of their own (overestimated, never under).
pub fn key_height(ui: &egui::Ui, entries: &[KeyEntry], row_width: f32) -> f32 {
    let (lines, wrapped) = key_line_count(ui, entries, row_width);
    if lines == 0 {
        return 0.0;
    }
    let spacing = ui.spacing();
    let small = ui.text_style_height(&egui::TextStyle::Small);
    let further = (lines - 1 + wrapped) as f32;
    spacing.interact_size.y.max(small) + further * (small + spacing.item_spacing.y)
}

/// A key that does not fit above its plot, folded into one word on the title's
/// line: "key", whose hover (or tap) shows every entry. Returns its rectangle.
fn folded_key_ui(ui: &mut egui::Ui, entries: &[KeyEntry]) -> egui::Rect {
    if entries.is_empty() {
        return egui::Rect::NOTHING;
    }
    let response = ui
        .add(
            egui::Label::new(egui::RichText::new(FOLDED_KEY_TEXT).small().underline())
                .sense(egui::Sense::click()),
        )
        .on_hover_ui(|ui| {
            ui.set_max_width(320.0);
            key_lines_ui(ui, entries);
        });
    record_key(ui.ctx(), response.rect);
    response.rect
}

/// The word a folded key shows on its plot's title line.
pub const FOLDED_KEY_TEXT: &str = "key";

/// A small sample of a series' look: a line, dashes or a marker.
fn mark_sample_ui(ui: &mut egui::Ui, color: Color32, mark: Mark) {
    let height = ui.text_style_height(&egui::TextStyle::Small);
    let (rect, _) = ui.allocate_exact_size(egui::vec2(18.0, height), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    let y = rect.center().y;
    let stroke = egui::Stroke::new(1.8, color);
    match mark {
        Mark::Solid => {
            painter.line_segment(
                [egui::pos2(rect.left(), y), egui::pos2(rect.right(), y)],
                stroke,
            );
        }
        Mark::Dashed | Mark::DashedPlusMinus => {
            painter.extend(egui::Shape::dashed_line(
                &[egui::pos2(rect.left(), y), egui::pos2(rect.right(), y)],
                stroke,
                4.0,
                3.0,
            ));
        }
        Mark::Dotted => {
            painter.extend(egui::Shape::dotted_line(
                &[egui::pos2(rect.left(), y), egui::pos2(rect.right(), y)],
                color,
                4.0,
                1.0,
            ));
        }
        Mark::Dots => {
            painter.circle_filled(rect.center(), 2.5, color);
        }
    }
}

/// The runs' colours above a row of plots, once for the row, each plot's key
/// then naming only its styles: one run alone needs no row of colours (the
/// title bar names it) and its plots' keys take its colour; several get the
/// row ([`series_key_ui`]) and keys in the text colour. Returns the keys'
/// colour.
pub fn runs_key_ui(ui: &mut egui::Ui, runs: &[(String, egui::Color32)]) -> egui::Color32 {
    match runs {
        [(_, color)] => *color,
        _ => {
            series_key_ui(ui, runs, "");
            ui.visuals().text_color()
        }
    }
}

/// One line above a row of plots that names each filter's colour and what solid and
/// dashed mean, instead of a legend inside every plot over the data.
pub fn series_key_ui(ui: &mut egui::Ui, filters: &[(String, egui::Color32)], styles: &str) {
    let response = ui
        .horizontal_wrapped(|ui| {
            for (name, color) in filters {
                ui.label(
                    egui::RichText::new(format!("— {name}"))
                        .color(*color)
                        .strong(),
                );
            }
            if !styles.is_empty() {
                ui.label(egui::RichText::new(styles).small());
            }
        })
        .response;
    record(
        ui.ctx(),
        FigureRecord {
            title: String::new(),
            data: None,
            key: Some(response.rect),
            map: None,
            image: None,
        },
    );
}

/// A plot as a lesson describes it to [`figure_ui`].
#[derive(Clone, Debug)]
pub struct Figure<'s> {
    /// The title above it (and the key of its series in [`Styled`] lists).
    pub title: &'s str,
    /// What it shows, on hover over the title.
    pub hover: &'s str,
    /// Its key, drawn on a line between the title and the plot.
    pub key: Vec<KeyEntry>,
    /// The y axis's name with its unit.
    pub y_label: &'s str,
    /// The whole height it may take (title, key and plot), points.
    pub height: f32,
}

/// The least height of a plot's data area that still holds two labelled y values.
pub const MIN_PLOT_HEIGHT: f32 = 60.0;

/// The height a plot's x axis (its values and its name) takes below the data,
/// points: a [`MIN_PLOT_HEIGHT`] plot has a 34-point data area.
const X_AXIS_POINTS: f32 = 26.0;

/// Draws `figure`: its title (with the y axis's name when the plot is too short to
/// write it beside the axis), its key on a line, then `plot` (made from the height
/// left and the y label to use, e.g. by [`time_plot`]) with `add` drawing the data.
/// Records the plot's data rectangle and key in [`figure_records`].
pub fn figure_ui<'a, R>(
    ui: &mut egui::Ui,
    figure: &Figure<'_>,
    plot: impl FnOnce(f32, &str) -> Plot<'a>,
    add: impl FnOnce(&mut PlotUi<'a>) -> R + 'a,
) -> egui_plot::PlotResponse<R> {
    figure_scaled_ui(ui, figure, false, plot, add)
}

/// [`figure_ui`] for a plot whose y values are decimal logarithms (a cost over
/// orders of magnitude): the y axis is labelled with the values themselves
/// ([`log_axis_marks`], [`log_axis_label`]): decades when two or more fit,
/// otherwise 1-2-5 or 1..9 times a power of ten, otherwise round values in
/// between, so that a short plot or a cost that barely changes still shows two
/// values or more.
pub fn log_figure_ui<'a, R>(
    ui: &mut egui::Ui,
    figure: &Figure<'_>,
    plot: impl FnOnce(f32, &str) -> Plot<'a>,
    add: impl FnOnce(&mut PlotUi<'a>) -> R + 'a,
) -> egui_plot::PlotResponse<R> {
    figure_scaled_ui(ui, figure, true, |h, y| log_y_axis(plot(h, y)), add)
}

/// `plot` with a logarithmic y axis: its y values are decimal logarithms, its
/// marks and labels those of [`log_axis_marks`] and [`log_axis_label`].
pub fn log_y_axis(plot: Plot<'_>) -> Plot<'_> {
    plot.y_grid_spacer(|input| {
        log_axis_marks(
            input.bounds,
            input.base_step_size,
            Y_LABEL_POINTS,
            f64::from(LEAST_Y_LABEL_POINTS),
        )
    })
    .y_axis_formatter(|mark, _range| log_axis_label(mark))
}

/// The labelled marks of a logarithmic axis showing `bounds` (decimal logarithms),
/// where `base_step` is the logarithm 8 screen points span: 1, 2 and 5 times each
/// power of ten when fewer than three decades show and those stand nearly
/// `preferred` points apart; else every n-th decade (`preferred` points apart)
/// when two or more show; otherwise 1, 2 and 5 times
/// each power of ten, or 1 and 3 times, or 1 to 9 times, when two or more show at
/// least `least` points apart; otherwise round values of the range itself (a cost from 1.02e3
/// to 1.07e3). Each mark's `step_size` is the smallest gap between two marks, so
/// that every mark is labelled.
pub fn log_axis_marks(
    bounds: (f64, f64),
    base_step: f64,
    preferred: f64,
    least: f64,
) -> Vec<egui_plot::GridMark> {
    let (lo, hi) = (bounds.0.min(bounds.1), bounds.0.max(bounds.1));
    let points_per_unit = 8.0 / base_step.abs();
    if !(lo.is_finite() && hi.is_finite() && points_per_unit.is_finite() && hi > lo)
        || hi - lo > 600.0
    {
        return Vec::new();
    }
    let marks_of = |values: Vec<f64>| -> Option<Vec<egui_plot::GridMark>> {
        let gap = values
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        (values.len() >= 2 && gap * points_per_unit >= least - 1e-9).then(|| {
            values
                .iter()
                .map(|&value| egui_plot::GridMark {
                    value,
                    step_size: gap,
                })
                .collect()
        })
    };
    // Whole decades, every n-th of them so that labels stand `preferred` apart.
    let mut every = 1.0_f64;
    while every * points_per_unit < preferred && every < 100.0 {
        every = match every {
            e if e < 2.0 => 2.0,
            e if e < 5.0 => 5.0,
            e => 2.0 * e,
        };
    }
    let decades_of = |step: f64| -> Vec<f64> {
        ((lo / step).ceil() as i64..=(hi / step).floor() as i64)
            .map(|k| k as f64 * step)
            .collect()
    };
    // Two decades alone leave most values far from a label: 1, 2 and 5 times each
    // power of ten instead where they stand nearly as far apart as the plot prefers.
    if decades_of(1.0).len() < 3 {
        let values = round_multiples(lo, hi, &[1.0, 2.0, 5.0]);
        let gap = values
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        if values.len() >= 3
            && gap * points_per_unit >= 0.8 * preferred
            && let Some(marks) = marks_of(values)
        {
            return marks;
        }
    }
    for step in [every, 1.0] {
        if let Some(marks) = marks_of(decades_of(step)) {
            return marks;
        }
    }
    // Round multiples of each power of ten.
    for mantissas in [
        &[1.0, 2.0, 5.0][..],
        &[1.0, 3.0],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
    ] {
        if let Some(marks) = marks_of(round_multiples(lo, hi, mantissas)) {
            return marks;
        }
    }
    // A range within one step of 1..9: round values in between, by the linear
    // axis's rule (near enough to evenly spaced over so small a range).
    let (a, b) = (math::powf(10.0, lo), math::powf(10.0, hi));
    let height = (hi - lo) * points_per_unit;
    let linear = value_axis_marks((a, b), (b - a) / height * 8.0, preferred, least);
    // The logarithm squeezes the upper marks together: keep those `least` apart.
    let mut values: Vec<f64> = Vec::new();
    for value in linear
        .iter()
        .filter(|m| m.value > 0.0)
        .map(|m| math::log10(m.value))
    {
        if values
            .last()
            .is_none_or(|last| (value - last) * points_per_unit >= least - 1e-9)
        {
            values.push(value);
        }
    }
    marks_of(values).unwrap_or_default()
}

/// The logarithms of `mantissas` times each power of ten that lie in `lo..=hi`, in
/// order.
fn round_multiples(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    (lo.floor() as i64..=hi.ceil() as i64)
        .flat_map(|k| mantissas.iter().map(move |m| k as f64 + math::log10(*m)))
        .filter(|v| *v >= lo - 1e-12 && *v <= hi + 1e-12)
        .collect()
}

/// The label of a mark of a logarithmic axis ([`log_axis_marks`]): the value
/// itself, as a mantissa and a power of ten with the digits the gap to the next
/// mark needs ("1e3", "2e3", "1.05e3").
pub fn log_axis_label(mark: egui_plot::GridMark) -> String {
    if !(mark.value.is_finite() && mark.step_size.is_finite() && mark.step_size > 0.0) {
        return String::new();
    }
    // The relative gap between neighbouring marks sets the significant digits.
    let relative = math::powf(10.0, mark.step_size) - 1.0;
    let digits = ((-math::log10(relative)).ceil() + 2.0).clamp(1.0, 6.0) as i32;
    let mut exponent = mark.value.floor();
    let scale = math::powf(10.0, f64::from(digits - 1));
    let mut mantissa = (math::powf(10.0, mark.value - exponent) * scale).round() / scale;
    if mantissa >= 10.0 {
        mantissa /= 10.0;
        exponent += 1.0;
    }
    let text = format!("{mantissa:.*}", (digits - 1) as usize);
    let text = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        text
    };
    format!("{text}e{exponent:.0}")
}

fn figure_scaled_ui<'a, R>(
    ui: &mut egui::Ui,
    figure: &Figure<'_>,
    log: bool,
    plot: impl FnOnce(f32, &str) -> Plot<'a>,
    add: impl FnOnce(&mut PlotUi<'a>) -> R + 'a,
) -> egui_plot::PlotResponse<R> {
    let top = ui.cursor().top();
    // Below the title and key: the x axis (labels and name) takes about 34 points.
    let estimated_plot = figure.height - 2.0 * ui.text_style_height(&egui::TextStyle::Body) - 34.0;
    let fits = y_label_fits(ui, figure.y_label, estimated_plot);
    let title = match unit_of(figure.y_label).filter(|_| !fits) {
        // A title ending in a number (the corridor's "K = ... = 0.308") would seem
        // to give that number the axis's unit: it names the axis instead.
        Some(_) if figure.title.ends_with(|c: char| c.is_ascii_digit()) => {
            format!("{}; y: {}", figure.title, figure.y_label)
        }
        // Too short to name the axis beside it: the title carries the unit.
        Some(unit) => format!("{} ({unit})", figure.title),
        None => figure.title.to_owned(),
    };
    // The key beside the title when both fit on one line, else on lines of its own
    // when the plot under them stays at least as tall as they are, else folded
    // into a "key" on the title's line that shows the entries on hover.
    let title_width = text_width(ui, &title, egui::TextStyle::Body) + 12.0;
    let title_height = ui.spacing().interact_size.y + ui.spacing().item_spacing.y;
    let stacked_key = key_height(ui, &figure.key, ui.available_width());
    let plot_left =
        (figure.height - title_height - stacked_key).max(MIN_PLOT_HEIGHT) - X_AXIS_POINTS;
    if title_width + key_width(ui, &figure.key) <= ui.available_width() {
        ui.horizontal(|ui| {
            title_ui(ui, &title, figure.hover);
            key_ui(ui, &figure.key);
        });
    } else if stacked_key <= plot_left {
        title_ui(ui, &title, figure.hover);
        key_ui(ui, &figure.key);
    } else {
        // Wrapped: a long title breaks onto a second line with "key" after it,
        // within the plot's width.
        ui.horizontal_wrapped(|ui| {
            title_ui(ui, &title, figure.hover);
            folded_key_ui(ui, &figure.key);
        });
    }
    let used = ui.cursor().top() - top;
    let height = (figure.height - used).max(MIN_PLOT_HEIGHT);
    ui.ctx()
        .data_mut(|d| d.insert_temp::<Option<bool>>(drawn_id(), None));
    let response = plot(height, if fits { figure.y_label } else { "" }).show(ui, add);
    let drawn: Option<bool> = ui.ctx().data(|d| d.get_temp(drawn_id())).flatten();
    if drawn == Some(false) {
        // No data yet: say what to do over the axes rather than show a scale
        // that means nothing.
        let rect = response.response.rect;
        ui.painter().rect_filled(
            rect,
            0.0,
            ui.visuals().extreme_bg_color.gamma_multiply(0.85),
        );
        ui.painter().text(
            rect.center(),
            egui::Align2::CENTER_CENTER,
            EMPTY_PLOT_TEXT,
            egui::FontId::proportional(TICK_FONT_SIZE + 1.0),
            ui.visuals().weak_text_color(),
        );
    } else {
        edge_values_ui(ui, &response, log);
    }
    record_bounds(ui.ctx(), figure.title, response.transform.bounds());
    record(
        ui.ctx(),
        FigureRecord {
            title: figure.title.to_owned(),
            data: Some(response.response.rect),
            key: None,
            map: None,
            image: None,
        },
    );
    response
}

/// The width of `text` in `style`, points.
fn text_width(ui: &egui::Ui, text: &str, style: egui::TextStyle) -> f32 {
    let font = style.resolve(ui.style());
    ui.painter()
        .layout_no_wrap(text.to_owned(), font, Color32::WHITE)
        .size()
        .x
}

/// The width [`key_ui`] takes on one line, points.
fn key_width(ui: &egui::Ui, entries: &[KeyEntry]) -> f32 {
    entries
        .iter()
        .map(|e| 18.0 + 4.0 + text_width(ui, &e.name, egui::TextStyle::Small) + 4.0 + 6.0 + 4.0)
        .sum()
}

/// The unit of an axis name, the text in its last parentheses: "m" of "error (m)".
pub fn unit_of(axis: &str) -> Option<&str> {
    let open = axis.rfind('(')?;
    let close = open + axis[open..].find(')')?;
    let unit = axis[open + 1..close].trim();
    (!unit.is_empty()).then_some(unit)
}

/// Where the plot is too short for two labelled y values (a value axis's marks
/// need [`LEAST_Y_LABEL_POINTS`] between them), writes the values of its top and
/// bottom edges beside the axis instead, so that its scale can still be read.
fn edge_values_ui<R>(ui: &egui::Ui, response: &egui_plot::PlotResponse<R>, log: bool) {
    let rect = response.response.rect;
    let bounds = response.transform.bounds();
    let (lo, hi) = (bounds.min()[1], bounds.max()[1]);
    let base = (hi - lo) / f64::from(rect.height().max(1.0)) * 8.0;
    let marks = if log {
        log_axis_marks
    } else {
        value_axis_marks
    }(
        (lo, hi),
        base,
        Y_LABEL_POINTS,
        f64::from(LEAST_Y_LABEL_POINTS),
    );
    if marks.len() >= 2 || !(lo.is_finite() && hi.is_finite()) {
        return;
    }
    // A logarithmic axis's edges are written as the values themselves ("5.6e5"),
    // three significant digits at most.
    let label = |value: f64| {
        if log {
            log_axis_label(egui_plot::GridMark {
                value,
                step_size: 0.05,
            })
        } else {
            two_significant(value)
        }
    };
    let painter = ui.painter();
    let font = egui::FontId::proportional(TICK_FONT_SIZE);
    let color = ui.visuals().text_color();
    for (value, y, align) in [
        (hi, rect.top(), egui::Align2::RIGHT_TOP),
        (lo, rect.bottom(), egui::Align2::RIGHT_BOTTOM),
    ] {
        painter.text(
            egui::pos2(rect.left() - 3.0, y),
            align,
            label(value),
            font.clone(),
            color,
        );
    }
}

/// `value` with two significant digits: 0.45, 12, 1300.
pub fn two_significant(value: f64) -> String {
    if !value.is_finite() {
        return String::new();
    }
    if value.abs() < 1e-12 {
        return "0".to_owned();
    }
    let magnitude = math::log10(value.abs()).floor();
    let decimals = (1.0 - magnitude).clamp(0.0, 6.0) as usize;
    format!("{value:.decimals$}")
}

/// Does the y axis's name, written along the axis in small text, fit a plot of
/// `plot_height` points?
pub fn y_label_fits(ui: &egui::Ui, y_label: &str, plot_height: f32) -> bool {
    let font = egui::TextStyle::Small.resolve(ui.style());
    let width = ui
        .painter()
        .layout_no_wrap(y_label.to_owned(), font, Color32::WHITE)
        .size()
        .x;
    width + 8.0 <= plot_height
}

/// Where a plot, a plot's key or a map was drawn in the last frame (for the shell's
/// render tests: tick labels in the axis strip, no key over any plot's data or map).
#[derive(Clone, Debug, PartialEq)]
pub struct FigureRecord {
    /// The plot's title (empty for a key).
    pub title: String,
    /// The plot's data rectangle (the area inside its axes).
    pub data: Option<egui::Rect>,
    /// A key's rectangle.
    pub key: Option<egui::Rect>,
    /// A map canvas's rectangle (no key lies on a map either).
    pub map: Option<egui::Rect>,
    /// An image figure's rectangle (the pose graph's sparsity images), all of it on
    /// screen.
    pub image: Option<egui::Rect>,
}

/// How many plots an embedded figure (`embed=1`, a lecture page's iframe) shows side
/// by side: the lesson's first ones, each tall enough to read, and the map keeps the
/// rest of the height. The full app shows them all.
pub const EMBED_PLOTS: usize = 2;

fn embed_layout_id() -> egui::Id {
    egui::Id::unique("slamlab_embed_plots")
}

/// Tells this frame's plots whether they are an embed's ([`plot_row`] shows fewer
/// then); the shared layout sets it before the plots are drawn.
pub fn set_embed_layout(ctx: &egui::Context, embed: bool) {
    ctx.data_mut(|d| d.insert_temp(embed_layout_id(), embed));
}

/// Are this frame's plots an embed's?
pub fn is_embed_layout(ctx: &egui::Context) -> bool {
    ctx.data(|d| d.get_temp(embed_layout_id()).unwrap_or(false))
}

/// How many of a row's `count` plots show: all of them, or in an embed the first
/// [`EMBED_PLOTS`].
pub fn shown_plots(count: usize, embed: bool) -> usize {
    if embed { count.min(EMBED_PLOTS) } else { count }
}

/// A lesson's row of `count` plots side by side, `add(k, ui)` drawing the `k`-th
/// (in the lesson's order of importance) into its column. An embed shows only the
/// first [`EMBED_PLOTS`] ([`shown_plots`]), each in a wider column.
pub fn plot_row(ui: &mut egui::Ui, count: usize, add: impl FnMut(usize, &mut egui::Ui)) {
    let shown = shown_plots(count, is_embed_layout(ui.ctx()));
    if shown == 0 {
        return;
    }
    columns_ui(ui, shown, add);
}

/// `count` columns side by side, `add(k, ui)` drawing the `k`-th: egui's
/// `ui.columns`, but each column lays out top-down without justifying, since egui
/// justifies the words of a wrapped label in a justified column (a plot's title
/// spread out word by word).
pub fn columns_ui(ui: &mut egui::Ui, count: usize, mut add: impl FnMut(usize, &mut egui::Ui)) {
    if count == 0 {
        return;
    }
    ui.columns(count, |columns| {
        for (k, column) in columns.iter_mut().enumerate() {
            column.with_layout(egui::Layout::top_down(egui::Align::LEFT), |ui| add(k, ui));
        }
    });
}

fn bounds_id() -> egui::Id {
    egui::Id::unique("slamlab_figure_bounds")
}

/// Records the bounds a plot showed in this pass ([`figure_bounds`]).
fn record_bounds(ctx: &egui::Context, title: &str, bounds: &egui_plot::PlotBounds) {
    let pass = ctx.cumulative_pass_nr();
    let entry = (
        title.to_owned(),
        [
            bounds.min()[0],
            bounds.min()[1],
            bounds.max()[0],
            bounds.max()[1],
        ],
    );
    ctx.data_mut(|d| {
        let all = d.get_temp_mut_or_default::<(u64, Vec<(String, [f64; 4])>)>(bounds_id());
        if all.0 != pass {
            *all = (pass, Vec::new());
        }
        all.1.push(entry);
    });
}

/// The bounds `[x_min, y_min, x_max, y_max]` of every plot drawn with
/// [`figure_ui`] in the latest pass, by title (for tests: a scale that fits the
/// data).
pub fn figure_bounds(ctx: &egui::Context) -> Vec<(String, [f64; 4])> {
    let pass = ctx.cumulative_pass_nr();
    ctx.data(|d| d.get_temp::<(u64, Vec<(String, [f64; 4])>)>(bounds_id()))
        .filter(|(p, _)| p + 1 >= pass)
        .map(|(_, all)| all)
        .unwrap_or_default()
}

fn records_id() -> egui::Id {
    egui::Id::unique("slamlab_figure_records")
}

/// Records `record` for this pass.
pub fn record(ctx: &egui::Context, record: FigureRecord) {
    let pass = ctx.cumulative_pass_nr();
    ctx.data_mut(|d| {
        let entry = d.get_temp_mut_or_default::<(u64, Vec<FigureRecord>)>(records_id());
        if entry.0 != pass {
            *entry = (pass, Vec::new());
        }
        entry.1.push(record);
    });
}

/// The plots and keys drawn in the latest pass (this one while it draws, the one
/// that just ended between passes).
pub fn figure_records(ctx: &egui::Context) -> Vec<FigureRecord> {
    let pass = ctx.cumulative_pass_nr();
    ctx.data(|d| d.get_temp::<(u64, Vec<FigureRecord>)>(records_id()))
        .filter(|(p, _)| p + 1 >= pass)
        .map(|(_, records)| records)
        .unwrap_or_default()
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
    fn every_value_axis_shows_two_values_or_more_when_they_fit() {
        // (bounds, data height in points): short plots of an 800 x 500 window, a
        // symmetric ±2σ range, a tall plot.
        for ((lo, hi), height) in [
            ((0.0, 0.35), 43.0),
            ((0.0, 0.012), 43.0),
            ((-4.6, 4.6), 52.0),
            ((-10.4, 10.4), 40.0),
            ((0.0, 9.5), 70.0),
            ((0.0, 1234.0), 270.0),
            ((2.36, 3.72), 150.0),
        ] {
            let base = (hi - lo) / height * 8.0;
            let marks = value_axis_marks((lo, hi), base, 30.0, 13.0);
            assert!(marks.len() >= 2, "{lo}..{hi} on {height}: {marks:?}");
            let step = marks[1].value - marks[0].value;
            assert!(
                step / (hi - lo) * height >= 13.0 - 1e-9,
                "{lo}..{hi}: {step}"
            );
            for m in &marks {
                assert!(m.value >= lo - 1e-12 && m.value <= hi + 1e-12);
                assert!((m.value / m.step_size - (m.value / m.step_size).round()).abs() < 1e-9);
            }
        }
        // Steps of 5 would label only 0 of -4.6..4.6 on 52 points: steps of 2.5 fit three.
        let marks = value_axis_marks((-4.6, 4.6), 9.2 / 52.0 * 8.0, 30.0, 13.0);
        assert_eq!(
            marks.iter().map(|m| m.value).collect::<Vec<_>>(),
            [-2.5, 0.0, 2.5]
        );
        let label = |value, step_size| value_axis_label(egui_plot::GridMark { value, step_size });
        assert_eq!(label(2.5, 2.5), "2.5");
        assert_eq!(label(-25.0, 25.0), "-25");
        assert_eq!(step_down(2.5), 2.0);
        // Where two values cannot fit, one; nothing for nonsense.
        assert_eq!(value_axis_marks((0.0, 1.0), 1.0, 30.0, 13.0).len(), 1);
        assert!(value_axis_marks((f64::NAN, 1.0), 0.1, 30.0, 13.0).is_empty());
        assert!(value_axis_marks((1.0, 1.0), 0.1, 30.0, 13.0).is_empty());
        assert_eq!(step_down(5.0), 2.5);
        assert_eq!(step_down(0.2), 0.1);
        assert_eq!(step_down(1.0), 0.5);
    }

    #[test]
    fn a_log_axis_shows_two_values_or_more_at_every_size() {
        // (log10 bounds, data height in points): three decades on a tall plot, one
        // cost at iteration 0 (egui widens a single value's range), a cost that
        // barely changes, tiny plots of an 800 x 500 window.
        for ((lo, hi), height) in [
            ((0.0, 3.2), 200.0),
            ((-1.0, 12.0), 40.0),
            ((-0.5, 0.5), 30.0),
            ((2.31, 2.52), 43.0),
            ((3.01, 3.03), 43.0),
            ((3.0101, 3.0102), 60.0),
            ((-6.2, -5.9), 35.0),
        ] {
            let base = (hi - lo) / height * 8.0;
            let marks = log_axis_marks((lo, hi), base, 30.0, 13.0);
            assert!(marks.len() >= 2, "{lo}..{hi} on {height}: {marks:?}");
            let labels: Vec<String> = marks.iter().map(|m| log_axis_label(*m)).collect();
            for (w, m) in marks.windows(2).zip(&marks) {
                assert!(
                    (w[1].value - w[0].value) / (hi - lo) * height >= 13.0 - 1e-6,
                    "{lo}..{hi}: {labels:?}"
                );
                assert!(m.value >= lo - 1e-9 && m.value <= hi + 1e-9);
            }
            let mut unique = labels.clone();
            unique.dedup();
            assert_eq!(unique, labels, "{lo}..{hi}: distinct labels");
        }
        let labels = |lo: f64, hi: f64, height: f64| -> Vec<String> {
            log_axis_marks((lo, hi), (hi - lo) / height * 8.0, 30.0, 13.0)
                .into_iter()
                .map(log_axis_label)
                .collect()
        };
        // Decades when two fit; 1-2-5 within one decade; round values in between.
        assert_eq!(labels(0.0, 3.2, 200.0), ["1e0", "1e1", "1e2", "1e3"]);
        // A cost from 1e3 down to 43 on 140 points: not only 1e2 and 1e3.
        assert_eq!(
            labels(1.6, 3.05, 140.0),
            ["5e1", "1e2", "2e2", "5e2", "1e3"]
        );
        assert_eq!(labels(-0.5, 0.5, 60.0), ["5e-1", "1e0", "2e0"]);
        assert_eq!(labels(2.31, 2.52, 43.0), ["2.5e2", "3e2"]);
        let narrow = labels(3.01, 3.03, 43.0);
        assert!(
            narrow.len() >= 2 && narrow.iter().all(|l| l.starts_with("1.0")),
            "{narrow:?}"
        );
        assert!(log_axis_marks((f64::NAN, 1.0), 0.1, 30.0, 13.0).is_empty());
        assert!(log_axis_marks((1.0, 1.0), 0.1, 30.0, 13.0).is_empty());
        let label = |value, step_size| log_axis_label(egui_plot::GridMark { value, step_size });
        assert_eq!(label(3.0, 1.0), "1e3");
        assert_eq!(label(math::log10(2000.0), 0.3), "2e3");
        assert_eq!(label(math::log10(1050.0), 0.004), "1.05e3");
        assert_eq!(label(math::log10(999.999_999), 0.3), "1e3");
        assert_eq!(label(f64::NAN, 1.0), "");
    }

    #[test]
    fn value_labels_carry_the_decimals_of_their_step_and_never_read_minus_zero() {
        let label = |value, step_size| value_axis_label(egui_plot::GridMark { value, step_size });
        assert_eq!(label(0.15, 0.05), "0.15");
        assert_eq!(label(-0.2, 0.1), "-0.2");
        assert_eq!(label(-1e-17, 0.1), "0.0");
        assert_eq!(label(4.0, 2.0), "4");
        assert_eq!(label(2000.0, 500.0), "2000");
        assert_eq!(label(f64::NAN, 1.0), "");
    }

    #[test]
    fn edge_values_keep_two_significant_digits() {
        assert_eq!(two_significant(0.4531), "0.45");
        assert_eq!(two_significant(-0.04531), "-0.045");
        assert_eq!(two_significant(12.3), "12");
        assert_eq!(two_significant(1300.0), "1300");
        assert_eq!(two_significant(0.0), "0");
        assert_eq!(two_significant(f64::NAN), "");
    }

    #[test]
    fn the_unit_of_an_axis_name_is_its_last_parentheses() {
        assert_eq!(unit_of("RMS error (m)"), Some("m"));
        assert_eq!(unit_of("yaw error (rad)"), Some("rad"));
        assert_eq!(unit_of("NEES"), None);
        assert_eq!(unit_of("odd ( )"), None);
        assert_eq!(unit_of("broken (m"), None);
    }

    #[test]
    fn markers_shrink_on_short_plots_but_stay_visible() {
        assert_eq!(marker_radius(2.0, 300.0), 2.0);
        assert_eq!(marker_radius(2.0, 75.0), 1.0);
        assert_eq!(marker_radius(1.0, 10.0), 0.8);
        assert_eq!(marker_radius(2.0, f32::NAN), 2.0);
    }

    #[test]
    fn a_plots_key_lists_its_series_with_points_in_order() {
        let series = |plot: &str, name: &str, points: Vec<[f64; 2]>, mark| {
            Styled::new(
                PlotSeries::new(plot, "t", "y", name, points),
                Color32::RED,
                mark,
                1.0,
            )
        };
        let all = vec![
            series("A", "error", vec![[0.0, 1.0]], Mark::Solid),
            series("B", "other", vec![[0.0, 1.0]], Mark::Solid),
            series("A", "bound", vec![[0.0, 2.0]], Mark::Dashed),
            series("A", "empty", Vec::new(), Mark::Dots),
        ];
        let key = key_entries(&all, "A");
        assert_eq!(
            key,
            vec![
                KeyEntry::new("error", Color32::RED, Mark::Solid),
                KeyEntry::new("bound", Color32::RED, Mark::Dashed),
            ]
        );
    }

    /// Draws `entries` with [`key_ui`] in a line `width` points wide and returns
    /// (the height [`key_height`] expects, the height drawn).
    fn key_heights(entries: &[KeyEntry], width: f32) -> (f32, f32) {
        let ctx = egui::Context::default();
        crate::fonts::install(&ctx);
        let mut heights = (f32::NAN, f32::NAN);
        let input = || egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(width + 16.0, 600.0),
            )),
            ..Default::default()
        };
        // The second pass has the fonts the first one loaded.
        for _ in 0..2 {
            let mut output = ctx.run_ui(input(), |ui| {
                let expected = key_height(ui, entries, ui.available_width());
                let drawn = key_ui(ui, entries).height();
                heights = (expected, drawn);
            });
            output.textures_delta.clear();
        }
        heights
    }

    #[test]
    fn a_keys_height_is_known_before_it_is_drawn() {
        let names = [
            "truth",
            "wheel odometry",
            "VO scaled by wheel speeds",
            "VO, unit steps",
            "this step",
            "docking station",
        ];
        let entries: Vec<KeyEntry> = names
            .iter()
            .map(|n| KeyEntry::new(*n, Color32::RED, Mark::Solid))
            .collect();
        let mut lines_seen = Vec::new();
        for width in [60.0, 100.0, 150.0, 240.0, 300.0, 420.0, 530.0, 640.0, 900.0] {
            for count in 1..=entries.len() {
                let (expected, drawn) = key_heights(&entries[..count], width);
                let what = format!(
                    "{count} entries in {width} points: {expected} expected, {drawn} drawn"
                );
                if width >= 150.0 {
                    // Every name fits on a line: the height is known to the point.
                    assert!((expected - drawn).abs() <= 1.0, "{what}");
                } else {
                    // Names wrap inside their entries: never less than drawn.
                    assert!(expected >= drawn - 1.0, "{what}");
                }
                lines_seen.push(drawn);
            }
        }
        lines_seen.sort_by(f32::total_cmp);
        lines_seen.dedup_by(|a, b| (*a - *b).abs() < 1.0);
        assert!(
            lines_seen.len() >= 4,
            "one, two, three lines and more: {lines_seen:?}"
        );
        assert_eq!(key_heights(&[], 300.0).0, 0.0, "no key, no height");
    }

    #[test]
    fn a_rows_plots_name_their_styles_once_for_every_filter() {
        let series = |name: &str, mark| {
            Styled::new(
                PlotSeries::new("A", "t", "y", name, vec![[0.0, 1.0]]),
                Color32::RED,
                mark,
                1.0,
            )
        };
        let all = vec![
            series("EKF error", Mark::Solid),
            series("EKF 2σ bound", Mark::Dashed),
            series("UKF error", Mark::Solid),
            series("UKF 2σ bound", Mark::Dashed),
        ];
        assert_eq!(
            style_entries(&all, "A", Color32::GRAY),
            vec![
                KeyEntry::new("error", Color32::GRAY, Mark::Solid),
                KeyEntry::new("2σ bound", Color32::GRAY, Mark::Dashed),
            ]
        );
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
