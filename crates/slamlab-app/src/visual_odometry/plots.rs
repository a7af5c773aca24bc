//! The plots under the centre: every VO step's rotation error and
//! translation-direction error against the truth, its inlier ratio, and the
//! shown step's RANSAC: the best inlier count and the adaptive bound
//! `N = log(1 − p) / log(1 − wˢ)` after each sample.

use super::images::{INLIER, OUTLIER, SAMPLE};
use crate::export::PlotSeries;
use crate::palette;
use crate::widgets::plots::{
    Figure, Mark, Styled, draw_series, figure_plot, figure_ui, is_embed_layout, key_entries,
    plot_row, series_data,
};
use slamlab_core::vision::EarlyRejection;
use slamlab_sim::visual_odometry::{TwoViewSession, VoRun};

const ROTATION: &str = "Rotation error per step";
const TRANSLATION: &str = "Translation-direction error per step";
const RATIO: &str = "Inlier ratio per step";
const RANSAC: &str = "RANSAC on this step";

/// Every plotted series, defined once: the plots draw them, the CSV export
/// writes them unthinned. x is the later frame of each step.
fn plotted(run: &VoRun, session: Option<&TwoViewSession>) -> Vec<Styled> {
    let mut out = Vec::new();
    let per_step =
        |pick: &dyn Fn(&slamlab_sim::visual_odometry::odometry::VoStep) -> Option<f64>| {
            run.steps
                .iter()
                .filter_map(|s| pick(s).map(|v| [s.to as f64, v]))
                .collect::<Vec<_>>()
        };
    out.push(Styled::new(
        PlotSeries::new(
            ROTATION,
            "frame",
            "error (°)",
            "rotation error",
            per_step(&|s| s.rotation_error_deg),
        ),
        palette::BLUE,
        Mark::Solid,
        1.5,
    ));
    out.push(Styled::new(
        PlotSeries::new(
            TRANSLATION,
            "frame",
            "error (°)",
            "translation-direction error",
            per_step(&|s| s.translation_angle_error_deg),
        ),
        palette::BLUE,
        Mark::Dots,
        3.0,
    ));
    out.push(Styled::new(
        PlotSeries::new(
            TRANSLATION,
            "frame",
            "error (°)",
            "pure rotation: t unobservable",
            per_step(&|s| (s.outcome == "pure-rotation").then_some(0.0)),
        ),
        palette::ORANGE,
        Mark::Dots,
        3.0,
    ));
    out.push(Styled::new(
        PlotSeries::new(
            TRANSLATION,
            "frame",
            "error (°)",
            "no estimate",
            per_step(&|s| (s.outcome != "pure-rotation" && s.outcome != "general").then_some(0.0)),
        ),
        OUTLIER,
        Mark::Dots,
        3.0,
    ));
    out.push(Styled::new(
        PlotSeries::new(
            RATIO,
            "frame",
            "inliers / matches",
            "inlier ratio",
            per_step(&|s| Some(s.inlier_ratio)),
        ),
        INLIER,
        Mark::Solid,
        1.5,
    ));
    out.push(Styled::new(
        PlotSeries::new(
            RATIO,
            "frame",
            "inliers / matches",
            "true share of good matches",
            per_step(&|_| Some(1.0 - run.settings.outliers)),
        ),
        palette::DEAD_RECKONING,
        Mark::Dashed,
        1.2,
    ));
    if let Some(session) = session {
        let n = session.matches().len().max(1) as f64;
        let reports = session.reports();
        out.push(Styled::new(
            PlotSeries::new(
                RANSAC,
                "sample",
                "share of matches",
                "best inlier share w",
                reports
                    .iter()
                    .map(|r| [r.iteration as f64, r.best_inliers as f64 / n])
                    .collect(),
            ),
            INLIER,
            Mark::Solid,
            1.5,
        ));
        out.push(Styled::new(
            PlotSeries::new(
                RANSAC,
                "sample",
                "share of matches",
                "this sample's inlier share",
                reports
                    .iter()
                    // With the SPRT a sample whose hypotheses were all rejected
                    // has no count: it is drawn in the series below instead.
                    .filter(|r| {
                        r.sprt
                            .as_ref()
                            .is_none_or(|s| s.checks.iter().any(|c| !c.rejected))
                    })
                    .map(|r| [r.iteration as f64, r.inliers as f64 / n])
                    .collect(),
            ),
            SAMPLE,
            Mark::Dots,
            2.0,
        ));
        if session.config().early_rejection == EarlyRejection::Sprt {
            out.push(Styled::new(
                PlotSeries::new(
                    RANSAC,
                    "sample",
                    "share of matches",
                    "SPRT: share checked before rejecting",
                    reports
                        .iter()
                        .filter_map(|r| Some((r.iteration, r.sprt.as_ref()?)))
                        .flat_map(|(i, s)| {
                            s.checks
                                .iter()
                                .filter(|c| c.rejected)
                                .map(move |c| [i as f64, c.evaluated as f64 / n])
                        })
                        .collect(),
                ),
                OUTLIER,
                Mark::Dots,
                2.0,
            ));
        }
    }
    out
}

/// The bound N after each sample (its own plot: it spans thousands).
fn bound_series(session: Option<&TwoViewSession>) -> Vec<[f64; 2]> {
    session.map_or_else(Vec::new, |s| {
        s.reports()
            .iter()
            .map(|r| [r.iteration as f64, r.bound as f64])
            .collect()
    })
}

/// The plots side by side.
pub fn plots_ui(ui: &mut egui::Ui, run: &VoRun, pair: usize, session: Option<&TwoViewSession>) {
    let height = ui.available_height().max(80.0);
    let all = plotted(run, session);
    let here = run.steps.get(pair).map(|s| s.to as f64);
    let frames = run.settings.frames as f64;
    let marker = |plot_ui: &mut egui_plot::PlotUi<'_>| {
        if let Some(x) = here {
            plot_ui.vline(
                egui_plot::VLine::new("this step", x)
                    .color(SAMPLE.gamma_multiply(0.7))
                    .width(1.0),
            );
        }
    };
    let specs = [
        (
            ROTATION,
            "error (°)",
            "The angle of R_estimated^-1 R_true for every VO step; the orange line is the \
                 step shown above.",
        ),
        (
            TRANSLATION,
            "error (°)",
            "The angle between the estimated and the true translation direction. A pure \
                 rotation has none to give (orange dots at 0: reported as unobservable); red \
                 dots at 0: RANSAC found no estimate.",
        ),
        (
            RATIO,
            "inliers / matches",
            "The share of matches the final E keeps, against the share of good matches \
                 the simulator made (dashed).",
        ),
    ];
    // An embed shows the rotation error alone: with the top view above, that
    // makes the two plots an embed holds.
    let count = if is_embed_layout(ui.ctx()) { 1 } else { 4 };
    plot_row(ui, count, |column, ui| {
        if let Some(&(title, y, hover)) = specs.get(column) {
            figure_ui(
                ui,
                &Figure {
                    title,
                    hover,
                    key: key_entries(&all, title),
                    y_label: y,
                    height,
                },
                |h, y| {
                    figure_plot(title, "frame", y, h)
                        .include_x(0.0)
                        .include_x(frames)
                        .include_y(0.0)
                        .include_y(1.0)
                },
                |plot_ui| {
                    marker(plot_ui);
                    draw_series(plot_ui, &all, title);
                },
            );
            return;
        }
        let bound = bound_series(session);
        let drawn = session.map_or(0, TwoViewSession::iteration);
        let title = format!(
            "{RANSAC}: {drawn} samples, N = {}",
            session.map_or(0, TwoViewSession::bound)
        );
        let mut key = key_entries(&all, RANSAC);
        key.push(crate::widgets::plots::KeyEntry::new(
            "bound N, as log10(N) / 4",
            palette::BLUE,
            Mark::Dashed,
        ));
        figure_ui(
            ui,
            &Figure {
                title: &title,
                hover: "After each sample: the best inlier share w so far and this sample's \
                        (dots), and the adaptive bound N = log(1 − p) / log(1 − w^s) as \
                        log10(N) / 4 (0.5 is 100 samples, 0.75 is 1000): it falls each time w \
                        grows, and RANSAC stops when the samples drawn reach it.",
                key,
                y_label: "share of matches",
                height,
            },
            |h, y| {
                figure_plot("vo_ransac", "sample", y, h)
                    .include_x(0.0)
                    .include_x((drawn as f64).max(10.0))
                    .include_y(0.0)
                    .include_y(1.0)
            },
            |plot_ui| {
                draw_series(plot_ui, &all, RANSAC);
                let scaled: Vec<[f64; 2]> = bound
                    .iter()
                    .map(|p| [p[0], slamlab_core::math::log10(p[1].max(1.0)) / 4.0])
                    .collect();
                plot_ui.line(
                    egui_plot::Line::new("bound N", egui_plot::PlotPoints::new(scaled))
                        .color(palette::BLUE)
                        .style(egui_plot::LineStyle::dashed_dense())
                        .width(1.5),
                );
            },
        );
    });
}

/// Every plot's series, for the CSV export (the bound N unscaled).
pub fn series(run: &VoRun, session: Option<&TwoViewSession>) -> Vec<PlotSeries> {
    let mut out = series_data(plotted(run, session));
    out.push(PlotSeries::new(
        RANSAC,
        "sample",
        "samples",
        "bound N",
        bound_series(session),
    ));
    out
}
