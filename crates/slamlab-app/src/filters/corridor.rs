//! The corridor view: the histogram Bayes filter's belief beside the Kalman
//! filter's Gaussian, the doors and the robot; and the Kalman gain's plot (the
//! prediction, the measurement and the posterior of the last update).

use crate::export::PlotSeries;
use crate::palette;
use crate::widgets::plots::{Figure, KeyEntry, Mark, figure_plot, figure_ui, title_ui};
use egui_plot::{Bar, BarChart, Line, LineStyle, PlotPoints, Polygon, VLine};
use slamlab_core::math;
use slamlab_sim::filters::session::CorridorSim;

/// `N(x; mean, variance)`.
fn normal(x: f64, mean: f64, variance: f64) -> f64 {
    if !(variance > 0.0) {
        return 0.0;
    }
    let d = x - mean;
    math::exp(-0.5 * d * d / variance) / (2.0 * std::f64::consts::PI * variance).sqrt()
}

/// A Gaussian density over the corridor, 400 points.
fn density_points(length: f64, mean: f64, variance: f64) -> Vec<[f64; 2]> {
    (0..=400)
        .map(|i| {
            let x = length * i as f64 / 400.0;
            [x, normal(x, mean, variance)]
        })
        .collect()
}

/// The plot's series, for the plot and the CSV export.
pub fn series(sim: &CorridorSim) -> Vec<PlotSeries> {
    let h = sim.histogram();
    let plot = "Corridor belief";
    let (x, y) = ("position (m)", "probability density (1/m)");
    let mk = |series: &str, points: Vec<[f64; 2]>| PlotSeries {
        plot: plot.to_owned(),
        x_axis: x.to_owned(),
        y_axis: y.to_owned(),
        series: series.to_owned(),
        points,
    };
    let mut out = vec![
        mk(
            "histogram Bayes filter",
            h.belief()
                .iter()
                .enumerate()
                .map(|(i, p)| [h.center(i), p / h.cell()])
                .collect(),
        ),
        mk(
            "Kalman filter",
            density_points(
                sim.corridor().length,
                sim.kalman().mean,
                sim.kalman().variance,
            ),
        ),
    ];
    if let Some((u, _)) = sim.last_update() {
        let g = "Kalman gain (last door sighting)";
        let length = sim.corridor().length;
        for (name, m, v) in [
            ("prediction", u.prior_mean, u.prior_variance),
            ("measurement", u.measurement, u.measurement_variance),
            ("posterior", u.posterior_mean, u.posterior_variance),
        ] {
            out.push(PlotSeries {
                plot: g.to_owned(),
                x_axis: x.to_owned(),
                y_axis: y.to_owned(),
                series: name.to_owned(),
                points: density_points(length, m, v),
            });
        }
    }
    out
}

/// The belief plot (centre): its key on a line above it, values on both axes.
pub fn belief_ui(ui: &mut egui::Ui, sim: &CorridorSim) {
    let truth = palette::truth_color(ui.visuals().dark_mode);
    let reading = match sim.saw_door() {
        None => "no reading yet".to_owned(),
        Some(true) => "the sensor said: door".to_owned(),
        Some(false) => "the sensor said: wall".to_owned(),
    };
    ui.label(egui::RichText::new(format!(
        "Step {}: {reading}. Robot at {:.2} m (the filters never see it).",
        slamlab_sim::stepper::Simulation::tick(sim),
        sim.truth()
    )));
    let h = sim.histogram();
    let length = sim.corridor().length;
    let peak = h.belief().iter().copied().fold(0.0, f64::max) / h.cell();
    let kf_peak = normal(sim.kalman().mean, sim.kalman().mean, sim.kalman().variance);
    let top = peak.max(kf_peak.min(5.0 * peak.max(0.05))).max(0.06) * 1.1;
    let bars: Vec<Bar> = h
        .belief()
        .iter()
        .enumerate()
        .map(|(i, p)| Bar::new(h.center(i), p / h.cell()).width(h.cell()))
        .collect();
    let door_half = 0.5 * sim.corridor().door_width;
    let doors = sim.corridor().doors.clone();
    let kalman = density_points(length, sim.kalman().mean, sim.kalman().variance);
    let robot = sim.truth();
    let figure = Figure {
        title: "Corridor: histogram Bayes filter vs Kalman filter",
        hover: "Bars: the histogram filter's belief per cell (any shape). Blue curve: the \
                Kalman filter's Gaussian. Black line: the robot (the filters never see it). \
                Shaded: doors.",
        key: vec![
            KeyEntry::new("histogram belief", palette::GREEN, Mark::Solid),
            KeyEntry::new("Kalman Gaussian", palette::BLUE, Mark::Solid),
            KeyEntry::new("robot (truth)", truth, Mark::Solid),
            KeyEntry::new("doors", palette::faded(palette::SKY_BLUE, 0.6), Mark::Solid),
        ],
        y_label: "density (1/m)",
        height: ui.available_height().max(120.0),
    };
    figure_ui(
        ui,
        &figure,
        |height, y_label| {
            figure_plot(
                "filters_corridor",
                "position along the corridor (m)",
                y_label,
                height,
            )
            .include_x(0.0)
            .include_x(length)
            .include_y(0.0)
            .include_y(top)
        },
        move |plot_ui| {
            for d in doors {
                plot_ui.polygon(
                    Polygon::new(
                        "doors",
                        PlotPoints::new(vec![
                            [d - door_half, 0.0],
                            [d + door_half, 0.0],
                            [d + door_half, top],
                            [d - door_half, top],
                        ]),
                    )
                    .fill_color(palette::faded(palette::SKY_BLUE, 0.25))
                    .stroke(egui::Stroke::NONE),
                );
            }
            plot_ui.bar_chart(
                BarChart::new("histogram belief", bars)
                    .color(palette::GREEN)
                    .element_formatter(Box::new(|b, _| {
                        format!("x = {:.2} m, {:.3} /m", b.argument, b.value)
                    })),
            );
            plot_ui.line(
                Line::new("Kalman Gaussian", PlotPoints::new(kalman))
                    .color(palette::BLUE)
                    .width(2.0),
            );
            plot_ui.vline(VLine::new("robot (truth)", robot).color(truth).width(2.0));
        },
    );
}

/// The gain plot (bottom): prediction, measurement and posterior of the last update.
pub fn gain_ui(ui: &mut egui::Ui, sim: &CorridorSim, height: f32) {
    let truth = palette::truth_color(ui.visuals().dark_mode);
    let Some((u, door)) = sim.last_update() else {
        title_ui(
            ui,
            "Kalman gain",
            "Shown after an update in which the sensor saw a door.",
        );
        ui.label(
            "The Kalman filter updates only when the sensor says \"door\": it takes the door \
             nearest its mean as a position measurement. Step until it sees one.",
        );
        return;
    };
    let title = format!(
        "Kalman gain at step {} (the last door sighting): K = P_p / (P_p + R) = {:.3} / ({:.3} + {:.3}) = {:.3}",
        sim.last_update_tick(),
        u.prior_variance,
        u.prior_variance,
        u.measurement_variance,
        u.gain
    );
    let length = sim.corridor().length;
    let prediction = density_points(length, u.prior_mean, u.prior_variance);
    let measurement = density_points(length, u.measurement, u.measurement_variance);
    let posterior = density_points(length, u.posterior_mean, u.posterior_variance);
    let figure = Figure {
        title: &title,
        hover: "Eq. 2.8 of Wu's thesis. K near 1: the filter trusts the measurement; near 0: \
                its prediction. Move motion-std (Q) and measurement-std (R) and watch K and \
                the posterior.",
        key: vec![
            KeyEntry::new("prediction N(x_p, P_p)", palette::BLUE, Mark::Dashed),
            KeyEntry::new(
                format!("measurement N(z = door at {door} m, R)"),
                palette::VERMILLION,
                Mark::Solid,
            ),
            KeyEntry::new(
                "posterior N(x_p + K (z − x_p), (1 − K) P_p)",
                truth,
                Mark::Solid,
            ),
        ],
        y_label: "density (1/m)",
        height: height.max(90.0),
    };
    figure_ui(
        ui,
        &figure,
        |height, y_label| {
            figure_plot("filters_gain", "position (m)", y_label, height)
                .include_x(0.0)
                .include_x(length)
                .include_y(0.0)
        },
        move |plot_ui| {
            plot_ui.line(
                Line::new("prediction", PlotPoints::new(prediction))
                    .color(palette::BLUE)
                    .style(LineStyle::dashed_loose())
                    .width(2.0),
            );
            plot_ui.line(
                Line::new("measurement", PlotPoints::new(measurement))
                    .color(palette::VERMILLION)
                    .width(2.0),
            );
            plot_ui.line(
                Line::new("posterior", PlotPoints::new(posterior))
                    .color(truth)
                    .width(2.5),
            );
        },
    );
}
