//! The plots under the map: the kidnap detector's input and output per scan
//! (thesis Figs. 5.8-5.9: the local matching cost, its average-filtered value,
//! the level `T · y_{t−1}` it must exceed and the detections), the last
//! branch-and-bound search's best score as it improved (or, with no match,
//! its best leaf against `min_score`), and the time each scan took here.

use super::map::LOOP_CLOSURE;
use crate::export::PlotSeries;
use crate::palette;
use crate::widgets::plots::{
    Figure, Mark, Styled, draw_series, figure_plot, figure_ui, key_entries, plot_row, series_data,
};
use crate::widgets::reference_track::ReferenceTrack;
use slamlab_sim::cartographer::CartographerSim;

const DETECTION: &str = "Kidnap detection";
const SEARCH: &str = "Last branch-and-bound search";
const TIME: &str = "Time per scan";
const REFERENCE: &str = "Error against the reference";

/// The trajectory error against a log's reference: the ATE so far with the
/// run's loop-closure setting, and the other setting's latest as a level.
fn reference_series(
    track: &ReferenceTrack,
    scores: [Option<[f64; 2]>; 2],
    loop_closures: bool,
) -> Vec<Styled> {
    let mode = |on: bool| {
        if on {
            "loop closures on"
        } else {
            "loop closures off"
        }
    };
    let name = match track.latest() {
        Some([scan, ate]) => format!("{}: ATE {ate:.3} m at scan {scan:.0}", mode(loop_closures)),
        None => format!("{}: ATE after two reference scans", mode(loop_closures)),
    };
    let color = |on: bool| {
        if on {
            LOOP_CLOSURE
        } else {
            palette::VERMILLION
        }
    };
    let mut out = vec![Styled::new(
        PlotSeries::new(REFERENCE, "scan", "ATE (m)", name, track.ate.clone()),
        color(loop_closures),
        Mark::Solid,
        1.8,
    )];
    if let Some([scan, ate]) = scores[usize::from(!loop_closures)] {
        out.push(Styled::new(
            PlotSeries::new(
                REFERENCE,
                "scan",
                "ATE (m)",
                format!("{}: {ate:.3} m at scan {scan:.0}", mode(!loop_closures)),
                vec![[0.0, ate], [scan, ate]],
            ),
            color(!loop_closures),
            Mark::Dashed,
            1.2,
        ));
    }
    out
}

/// Every plotted series, defined once for the plots and the CSV export.
fn plotted(sim: &CartographerSim, scan_ms: &[f64]) -> Vec<Styled> {
    let per_scan = |pick: &dyn Fn(&slamlab_sim::cartographer::ScanRecord) -> f64| {
        sim.records
            .iter()
            .map(|r| [r.scan as f64, pick(r)])
            .filter(|p| p[1].is_finite())
            .collect::<Vec<_>>()
    };
    let mut out = vec![
        Styled::new(
            PlotSeries::new(
                DETECTION,
                "scan",
                "cost",
                "matching cost",
                per_scan(&|r| r.cost),
            ),
            palette::BLUE,
            Mark::Solid,
            1.0,
        ),
        Styled::new(
            PlotSeries::new(
                DETECTION,
                "scan",
                "cost",
                "filtered (f_size)",
                per_scan(&|r| r.filtered),
            ),
            palette::ORANGE,
            Mark::Solid,
            1.8,
        ),
        Styled::new(
            PlotSeries::new(
                DETECTION,
                "scan",
                "cost",
                "threshold T·y",
                per_scan(&|r| r.trigger_level),
            ),
            palette::VERMILLION,
            Mark::Dashed,
            1.2,
        ),
        Styled::new(
            PlotSeries::new(
                DETECTION,
                "scan",
                "cost",
                "detection",
                sim.records
                    .iter()
                    .filter(|r| r.detected)
                    .map(|r| {
                        let y = if r.filtered.is_finite() {
                            r.filtered
                        } else {
                            0.0
                        };
                        [r.scan as f64, y]
                    })
                    .collect(),
            ),
            palette::VERMILLION,
            Mark::Dots,
            5.0,
        ),
    ];
    if let Some(search) = &sim.last_search {
        let min = search.min_score;
        let end = search.record.evaluated().max(1) as f64;
        if search.score.is_some() {
            let mut best: Vec<[f64; 2]> = search
                .record
                .best_history
                .iter()
                .map(|&(n, s)| [n as f64, s])
                .collect();
            if let Some(&[_, s]) = best.last() {
                best.push([search.record.evaluated() as f64, s]);
            }
            out.push(Styled::new(
                PlotSeries::new(SEARCH, "candidates scored", "score", "best score", best),
                LOOP_CLOSURE,
                Mark::Solid,
                1.6,
            ));
        } else {
            // No leaf above min_score: the best leaf scored anyway, or the
            // bound that kept every branch from the leaves, against it.
            let (name, value, mark) = match (search.record.best_leaf_score, search.best_bound) {
                (Some(leaf), _) => (
                    format!("best leaf {leaf:.3}: no match above min_score"),
                    leaf,
                    Mark::Solid,
                ),
                (None, Some(bound)) => (
                    format!("highest bound {bound:.3}: no match above min_score"),
                    bound,
                    Mark::Dotted,
                ),
                (None, None) => ("no match above min_score".to_owned(), f64::NAN, Mark::Solid),
            };
            let (points, mark, width) = no_match_level(value, min, end, mark);
            out.push(Styled::new(
                PlotSeries::new(SEARCH, "candidates scored", "score", name, points),
                palette::VERMILLION,
                mark,
                width,
            ));
        }
        out.push(Styled::new(
            PlotSeries::new(
                SEARCH,
                "candidates scored",
                "score",
                format!("min score {min:.3}"),
                vec![[0.0, min], [end, min]],
            ),
            palette::DEAD_RECKONING,
            Mark::Dashed,
            1.0,
        ));
    }
    out.push(Styled::new(
        PlotSeries::new(
            TIME,
            "scan",
            "time (ms)",
            "time per scan",
            scan_ms
                .iter()
                .enumerate()
                .filter(|(_, t)| t.is_finite())
                .map(|(k, t)| [k as f64, *t])
                .collect(),
        ),
        palette::BLUE,
        Mark::Solid,
        1.0,
    ));
    out
}

/// The plots side by side, each with its key on a line above it; with a
/// log's reference, the error against it takes the place of the time per
/// scan.
pub fn plots_ui(
    ui: &mut egui::Ui,
    sim: &CartographerSim,
    scan_ms: &[f64],
    track: &ReferenceTrack,
    scores: [Option<[f64; 2]>; 2],
    loop_closures: bool,
) {
    let mut all = plotted(sim, scan_ms);
    let with_reference = sim.input().reference.is_some();
    if with_reference {
        all.extend(reference_series(track, scores, loop_closures));
    }
    let height = ui.available_height().max(80.0);
    let figure = |title: &'static str, hover: &'static str, y_label: &'static str| Figure {
        title,
        hover,
        key: key_entries(&all, title),
        y_label,
        height,
    };
    plot_row(ui, 3, |k, ui| match k {
        0 => {
            figure_ui(
                ui,
                &figure(
                    DETECTION,
                    "Thesis Algorithm 13 (Figs. 5.8-5.9): each scan's local matching cost (Eq. 5.5), \
                     its average over the last f_size scans y_t, and the level T · y_(t−1) it must \
                     exceed. A kidnap makes the scan disagree with the submap: the cost jumps, the \
                     filtered value crosses the threshold and the detector ends the trajectory \
                     (dot); a new one starts at the origin with a fresh submap.",
                    "cost",
                ),
                |h, y| {
                    figure_plot("cartographer_detection", "scan", y, h)
                        .include_x(0.0)
                        .include_y(0.0)
                },
                |p| draw_series(p, &all, DETECTION),
            );
        }
        1 => {
            figure_ui(
                ui,
                &figure(
                    SEARCH,
                    "The last branch-and-bound search (Xiang's thesis, Algorithm 12): the best leaf's \
                     score (mean probability under the scan's points, Eq. 5.10) each time it \
                     improved, against the candidates scored so far at every height. Branches \
                     whose bound (Eq. 5.14) is not above the best are pruned; the explanation \
                     panel counts them per height beside what exhaustive search would score. \
                     With no match the red line is the best leaf scored (or, when no branch \
                     reached a leaf, the highest bound), under the dashed min score (red dots \
                     over the dashes when the two are nearly equal).",
                    "score",
                ),
                |h, y| {
                    figure_plot("cartographer_search", "candidates scored", y, h)
                        .include_x(0.0)
                        .include_y(0.0)
                        .include_y(1.0)
                },
                |p| draw_series(p, &all, SEARCH),
            );
        }
        _ if with_reference => {
            figure_ui(
                ui,
                &figure(
                    REFERENCE,
                    "The trajectory so far against the log's corrected version (Kümmerle et al. \
                     2009): at every reference scan passed, the absolute trajectory error (RMS \
                     position error after the rigid alignment that fits best) of every scan's \
                     pose as the pose graph has it now. Switch loop closures off and on above \
                     the map: the same scans map again, and the other setting's error stays as \
                     a dashed level.",
                    "ATE (m)",
                ),
                |h, y| {
                    figure_plot("cartographer_reference", "scan", y, h)
                        .include_x(0.0)
                        .include_y(0.0)
                },
                |p| draw_series(p, &all, REFERENCE),
            );
        }
        _ => {
            figure_ui(
                ui,
                &figure(
                    TIME,
                    "How long each scan took here: local matching, insertion, the loop-closure \
                     searches and, every optimize_every_n_nodes nodes, the optimization (ms)",
                    "time (ms)",
                ),
                |h, y| {
                    figure_plot("cartographer_time", "scan", y, h)
                        .include_x(0.0)
                        .include_y(0.0)
                },
                |p| draw_series(p, &all, TIME),
            );
        }
    });
}

/// Every plot's series, unthinned, for the CSV export.
pub fn series(
    sim: &CartographerSim,
    scan_ms: &[f64],
    track: &ReferenceTrack,
    loop_closures: bool,
) -> Vec<PlotSeries> {
    let mut all = plotted(sim, scan_ms);
    if sim.input().reference.is_some() {
        all.extend(reference_series(track, [None, None], loop_closures));
    }
    series_data(all)
}

/// How far apart (score, on the plot's 0..1 axis) the no-match level and the
/// dashed min score must be to show as two lines (about 3 points apart on a
/// 150-point plot).
const SEPARATE_LEVELS: f64 = 0.02;

/// The points, mark and width of the level a search without a match reached
/// (`value`, the best leaf or the highest bound), drawn across `0..end` against
/// the dashed min score `min`: a line in `mark`, or, nearer the min score than
/// [`SEPARATE_LEVELS`] (a bound 0.001 under it), a row of dots drawn over the
/// dashes, so that both stay in view; nothing for a level that is not a number.
fn no_match_level(value: f64, min: f64, end: f64, mark: Mark) -> (Vec<[f64; 2]>, Mark, f32) {
    if !value.is_finite() {
        return (Vec::new(), mark, 1.6);
    }
    if (value - min).abs() >= SEPARATE_LEVELS || !min.is_finite() {
        return (vec![[0.0, value], [end, value]], mark, 1.6);
    }
    let dots = 12;
    let points = (0..=dots)
        .map(|k| [end * f64::from(k) / f64::from(dots), value])
        .collect();
    (points, Mark::Dots, 2.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_level_beside_the_min_score_is_dots_over_its_dashes() {
        // Far apart: a line of two points in its own mark.
        let (points, mark, _) = no_match_level(0.42, 0.55, 100.0, Mark::Dotted);
        assert_eq!(points, vec![[0.0, 0.42], [100.0, 0.42]]);
        assert_eq!(mark, Mark::Dotted);
        // 0.001 apart: dots along the whole width, drawn after (over) the dashes.
        let (points, mark, _) = no_match_level(0.549, 0.55, 100.0, Mark::Dotted);
        assert_eq!(mark, Mark::Dots);
        assert_eq!(points.len(), 13);
        assert_eq!(points.first(), Some(&[0.0, 0.549]));
        assert_eq!(points.last(), Some(&[100.0, 0.549]));
        assert!(
            no_match_level(f64::NAN, 0.55, 100.0, Mark::Solid)
                .0
                .is_empty()
        );
    }
}
