//! The plots under the map: robot position error with the filter's 2σ bound,
//! landmark RMS error, robot-pose NEES and per-update NIS with their 95% bands.

use crate::export::PlotSeries;
use crate::palette;
use crate::widgets::plots::{
    Figure, Mark, Styled, draw_series, figure_ui, plot_row, plot_values, row_time_plot,
    series_data, series_key_ui,
};
pub(super) use crate::widgets::plots::{line_width, thin, time_plot};
use egui_plot::{HLine, LineStyle, Plot, Span};
use slamlab_core::stats::chi2_quantile;
use slamlab_sim::LandmarkSession;
use slamlab_sim::world::recorded::MAX_TRUTH_GAP;

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
    row_time_plot(id, y_label, height, "slamlab_time_axis")
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
    let range = |f: &dyn Fn(&slamlab_sim::world::landmark_session::TickMetrics) -> Option<f64>| {
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

/// The four plots side by side (two in an embed).
/// Why a recorded world's error plots are empty or broken: no true path in
/// the data (the Freiburg files, Victoria Park), or Vicon's gaps (MRCLAM).
pub fn truth_note(session: &LandmarkSession) -> Option<String> {
    let world = session.recorded_world()?;
    match &world.truth {
        None => Some(format!(
            "{} has no true path, so the robot error, landmark error and NEES plots stay \
             empty; the NIS needs no truth.{}",
            world.name,
            if world.reference.is_empty() {
                ""
            } else {
                " The GPS (grey dots, aligned to the path) is the only independent reference; \
                 the World box gives the fit."
            }
        )),
        Some(track) => {
            let gaps = track.gaps().len();
            (gaps > 0).then(|| {
                format!(
                    "Vicon truth with {gaps} gaps: where it is missing the error plots have no \
                     samples and the map's true path breaks."
                )
            })
        }
    }
}

pub fn plots_ui(ui: &mut egui::Ui, session: &LandmarkSession) {
    if let Some(note) = coincidence_note(session, &coinciding_series(session)) {
        ui.label(egui::RichText::new(note).color(ui.visuals().warn_fg_color));
    }
    if let Some(note) = truth_note(session) {
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
    let all = split_at_gaps(plotted(session), session);
    // Inside a plot the data cannot fill: why it is empty.
    let no_truth = session
        .recorded_world()
        .is_some_and(|w| w.truth.is_none())
        .then_some("no true path in the data");
    let height = ui.available_height().max(80.0);
    let figure = |title: &'static str, hover: &'static str, y_label: &'static str| Figure {
        title,
        hover,
        key: Vec::new(),
        y_label,
        height,
    };
    // In the lesson's order: an embed shows the first two.
    plot_row(ui, 4, |k, ui| match k {
        // 1. Robot position error and the 2σ bound.
        0 => {
            figure_ui(
                ui,
                &figure(
                    ROBOT_ERROR,
                    "|true − estimated position| and the filter's own 2σ bound 2√(σx² + σy²)",
                    "error (m)",
                ),
                |h, y| plot("plot_robot_error", y, h),
                |plot_ui| {
                    draw_series(plot_ui, &all, ROBOT_ERROR);
                    empty_note(plot_ui, no_truth);
                },
            );
        }
        // 2. Landmark RMS error.
        1 => {
            figure_ui(
                ui,
                &figure(
                    LANDMARK_ERROR,
                    "Root mean square position error over the landmarks in each filter's state",
                    "RMS error (m)",
                ),
                |h, y| plot("plot_landmark_rmse", y, h),
                |plot_ui| {
                    draw_series(plot_ui, &all, LANDMARK_ERROR);
                    empty_note(plot_ui, no_truth);
                },
            );
        }
        // 3. Robot-pose NEES with the 3-dof band.
        2 => {
            let (lo, hi) = band_95(3.0);
            let nees_max = consistency_y_max(plot_values(&all, NEES), hi);
            figure_ui(
                ui,
                &figure(
                    NEES,
                    "e^T P_RR^-1 e of the robot pose each tick. Above the band: overconfident; below: conservative.",
                    "NEES",
                ),
                |h, y| plot("plot_nees", y, h).default_y_bounds(0.0, nees_max),
                |plot_ui| {
                    band_ui(plot_ui, lo, hi);
                    draw_series(plot_ui, &all, NEES);
                    empty_note(plot_ui, no_truth);
                },
            );
        }
        // 4. NIS of every update with the 2-dof band.
        _ => {
            let (lo, hi) = band_95(2.0);
            let nis_max = consistency_y_max(plot_values(&all, NIS), hi);
            figure_ui(
                ui,
                &figure(
                    NIS,
                    "ν^T S^-1 ν of every landmark update. Above the band: the innovations are larger than the filter expects.",
                    "NIS",
                ),
                |h, y| plot("plot_nis", y, h).default_y_bounds(0.0, nis_max),
                |plot_ui| {
                    band_ui(plot_ui, lo, hi);
                    draw_series(plot_ui, &all, NIS);
                },
            );
        }
    });
}

/// Writes `note` in the middle of a plot that has no data for want of it (in
/// place of the shared "press Run" text: running will not fill it).
fn empty_note(plot_ui: &mut egui_plot::PlotUi<'_>, note: Option<&str>) {
    if let Some(note) = note {
        crate::widgets::plots::note_drawn(plot_ui.ctx(), true);
        let b = plot_ui.plot_bounds();
        let centre = egui_plot::PlotPoint::new(
            0.5 * (b.min()[0] + b.max()[0]),
            0.5 * (b.min()[1] + b.max()[1]),
        );
        plot_ui.text(
            egui_plot::Text::new("", centre, note)
                .color(palette::faded(palette::DEAD_RECKONING, 0.9)),
        );
    }
}

/// The series over time split where a recorded world's truth has a gap (no
/// sample for longer than [`MAX_TRUTH_GAP`]), so that a gap is drawn as a gap
/// and not bridged by a straight line. The NIS (points) and the export are
/// not split.
fn split_at_gaps(all: Vec<Styled>, session: &LandmarkSession) -> Vec<Styled> {
    if session.recorded_world().is_none_or(|w| w.truth.is_none()) {
        return all;
    }
    let mut out = Vec::with_capacity(all.len());
    for styled in all {
        if styled.data.plot == NIS || styled.data.points.len() < 2 {
            out.push(styled);
            continue;
        }
        let points = &styled.data.points;
        let mut start = 0;
        for i in 1..=points.len() {
            if i == points.len() || points[i][0] - points[i - 1][0] > MAX_TRUTH_GAP {
                let mut piece = styled.clone();
                piece.data.points = points[start..i].to_vec();
                out.push(piece);
                start = i;
            }
        }
    }
    out
}

const ROBOT_ERROR: &str = "Robot position error";
const LANDMARK_ERROR: &str = "Mean landmark error";
const NEES: &str = "Robot pose NEES (3 dof)";
const NIS: &str = "Update NIS (2 dof)";

/// Every series, defined once: the four plots draw theirs, the CSV export
/// writes them all unthinned (with FastSLAM's N_eff, which the parameter panel
/// plots).
fn plotted(session: &LandmarkSession) -> Vec<Styled> {
    let dt = session.scenario().dt;
    let times = session.tick_times();
    let recorded = session.recorded_world().is_some();
    // An update's time: its tick's (a recorded world's steps are not `dt` apart).
    let nis_time = |tick: u64| match times.get(tick as usize) {
        Some(&time) if recorded => time,
        _ if recorded => session.time(),
        _ => tick as f64 * dt,
    };
    let mut out = Vec::new();
    for (index, run) in session.filters().iter().enumerate() {
        let name = run.kind.name().to_uppercase();
        let color = palette::estimator_color(run.kind.name());
        let over_time =
            |pick: &dyn Fn(&slamlab_sim::world::landmark_session::TickMetrics) -> Option<f64>| {
                run.history
                    .iter()
                    .filter_map(|m| pick(m).map(|v| [m.time, v]))
                    .collect::<Vec<_>>()
            };
        let mut push = |plot: &str, axis: &str, series: &str, points, mark, width| {
            out.push(Styled::new(
                PlotSeries::new(plot, "time (s)", axis, format!("{name} {series}"), points),
                color,
                mark,
                line_width(index, width),
            ));
        };
        push(
            ROBOT_ERROR,
            "error (m)",
            "error",
            over_time(&|m| Some(m.position_error)),
            Mark::Solid,
            1.2,
        );
        push(
            ROBOT_ERROR,
            "error (m)",
            "2σ bound",
            over_time(&|m| Some(m.position_bound_2sigma)),
            Mark::Dashed,
            1.0,
        );
        push(
            LANDMARK_ERROR,
            "RMS error (m)",
            "landmarks",
            over_time(&|m| m.landmark_rmse),
            Mark::Solid,
            1.2,
        );
        push(
            NEES,
            "NEES",
            "NEES",
            over_time(&|m| m.nees),
            Mark::Solid,
            1.0,
        );
        push(
            NIS,
            "NIS",
            "NIS",
            run.nis.iter().map(|s| [nis_time(s.tick), s.nis]).collect(),
            Mark::Dots,
            1.4,
        );
        if !run.n_eff.is_empty() {
            out.push(Styled::new(
                PlotSeries::new(
                    "N_eff before each resampling",
                    "tick",
                    "N_eff",
                    format!("{name} N_eff"),
                    run.n_eff.iter().map(|n| [n.tick as f64, n.n_eff]).collect(),
                ),
                color,
                Mark::Solid,
                line_width(index, 1.2),
            ));
        }
    }
    out
}

/// Every plot's series, unthinned, for the CSV export.
pub fn series(session: &LandmarkSession) -> Vec<PlotSeries> {
    series_data(plotted(session))
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
