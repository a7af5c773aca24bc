//! The explanation panel: what the reading that just ran did in each mode (its
//! innovation, gain and NIS), the RMSE table as it stands, the skipped-reading
//! counts, and what each mode does with the SLAM pose.

use super::mode_color;
use crate::palette;
use crate::widgets::sources;
use slamlab_core::kalman::fusion::{Outcome, StepReport};
use slamlab_core::math;
use slamlab_sim::fusion::session::{FusionPhase, FusionSim};
use slamlab_sim::fusion::{FusionMode, ModeRun, SLAM};

/// The RMSE table's text for one value, as the panel shows it (metres or radians).
pub fn rmse_text(value: f64) -> String {
    // A value that rounds to zero prints as 0.0000, never −0.0000.
    let shown = if value.abs() < 5e-5 { 0.0 } else { value };
    format!("{shown:.4}")
}

/// A vector entry of the explanation, signed with four decimals; one that rounds to
/// zero prints as +0.0000, never −0.0000.
pub fn signed_text(value: f64) -> String {
    let shown = if value.abs() < 5e-5 { 0.0 } else { value };
    format!("{shown:+.4}")
}

/// The panel for the phase that ran last.
pub fn explanation_ui(ui: &mut egui::Ui, sim: &FusionSim, last: Option<&FusionPhase>) {
    ui.heading("What just happened");
    match last {
        None => {
            ui.label(
                "Nothing yet. Every reading is one step: the filter predicts its state to the \
                 reading's stamp (the omnidirectional model of the ROS package \
                 robot_localization, x' = f(x, Δt), P' = F P F^T + Q Δt) and corrects the \
                 variables that sensor measures. Wheel odometry arrives at 50 Hz, the IMU at \
                 100 Hz, the SLAM pose at 1 Hz, as in the experiments of Wu's thesis. Press \
                 \"Step phase\" for one reading, \"Step tick\" for one second.",
            );
            ui.horizontal_wrapped(|ui| {
                ui.label("Sources:");
                sources::source_link(ui, "wu", "Wu's thesis §3.5 and §5.3;");
                sources::source_link(ui, "ros", "ROS robot_localization");
            });
        }
        Some(phase) => {
            ui.label(egui::RichText::new(phase.label()).strong());
            for (run, report) in sim.runs().iter().zip(sim.last_reports()) {
                let color = mode_color(run.mode());
                match report {
                    Some(report) => report_ui(ui, run.mode(), report, color),
                    None if matches!(phase, FusionPhase::Measurement { .. }) => {
                        ui.colored_label(
                            color,
                            format!("{}: does not use this sensor", run.mode().name()),
                        );
                    }
                    None => {}
                }
            }
        }
    }
    ui.separator();
    ui.heading("RMSE so far");
    ui.horizontal_wrapped(|ui| {
        ui.label(format!(
            "Over the fused estimate sampled at {} Hz up to {:.1} s, as in Table 5.3 of Wu's \
             thesis (§5.3).",
            sim.live().output_rate,
            sim.now()
        ));
        sources::source_link(ui, "wu", "Source: Wu's thesis");
    });
    // One column per mode and a row per quantity: narrow enough for the drawer of
    // an 800 x 500 window with three modes; a horizontal scroll beyond that.
    egui::ScrollArea::horizontal()
        .id_salt("fusion_rmse_scroll")
        .show(ui, |ui| {
            egui::Grid::new("fusion_rmse")
                .num_columns(1 + sim.runs().len())
                .spacing([10.0, 2.0])
                .striped(true)
                .show(ui, |ui| {
                    ui.label("");
                    for run in sim.runs() {
                        ui.colored_label(
                            mode_color(run.mode()),
                            egui::RichText::new(run.mode().name()).strong(),
                        );
                    }
                    ui.end_row();
                    type Cell<'c> = &'c dyn Fn(&ModeRun) -> String;
                    let rows: [(&str, &str, Cell<'_>); 5] = [
                        ("x (m)", "RMSE of x", &|run| rmse_text(run.rmse().x)),
                        ("y (m)", "RMSE of y", &|run| rmse_text(run.rmse().y)),
                        ("yaw (rad)", "RMSE of the heading", &|run| {
                            rmse_text(run.rmse().yaw)
                        }),
                        (
                            "error now (m)",
                            "Distance from the estimate to the truth at the last output sample",
                            &|run| {
                                let now = run
                                    .samples()
                                    .last()
                                    .map_or(0.0, |s| math::hypot(s.error[0], s.error[1]));
                                format!("{now:.3}")
                            },
                        ),
                        (
                            "largest jump (m)",
                            "The largest move of the position estimate at a SLAM update",
                            &|run| format!("{:.3}", run.max_slam_jump()),
                        ),
                    ];
                    for (head, hover, value) in rows {
                        ui.label(egui::RichText::new(head).strong())
                            .on_hover_text(hover);
                        for run in sim.runs() {
                            ui.monospace(value(run));
                        }
                        ui.end_row();
                    }
                });
        });
    ui.separator();
    ui.heading("Readings skipped");
    for run in sim.runs() {
        let s = run.filter().stats();
        ui.colored_label(
            mode_color(run.mode()),
            format!(
                "{}: {} fused, {} stored, {} rejected; skipped {}: {} NaN, {} zero or negative noise, \
                 {} before the start, {} time going backwards, {} other",
                run.mode().name(),
                s.fused,
                s.stored,
                s.rejected,
                s.skipped(),
                s.non_finite,
                s.bad_noise,
                s.before_start,
                s.out_of_order,
                s.unusable + s.numerical
            ),
        );
    }
    if sim.injected() > 0 {
        ui.label(format!("{} bad readings injected.", sim.injected()));
    }
    for note in sim.notes() {
        ui.colored_label(palette::VERMILLION, note);
    }
    ui.separator();
    ui.heading("The three modes");
    ui.label(
        "absolute: the SLAM pose is fused as it is, x, y and yaw in the filter's world frame. \
         relative (robot_localization's _relative, Wu's thesis §3.5 and §5.3): the pose \
         relative to the first SLAM reading, inv(P0) * P, fused as a position. Here SLAM's map \
         starts where the robot starts, so the two agree.",
    );
    ui.label(
        "differential (_differential): two consecutive SLAM poses are differenced into a \
         body-frame velocity, inv(P(k-1)) * P(k) / Δt, and fused as v_x, v_y and yaw rate beside \
         the odometry's.",
    );
    ui.label(
        "Why relative jumps: each update corrects the position itself, by K ν: when the SLAM \
         pose is noisy or its map relocalizes (a loop closure resets its drift), the estimate \
         jumps there, but its error stays bounded by the SLAM error. Why differential drifts: \
         it only ever corrects a velocity, so the position is an integral, smooth at the \
         updates, but every velocity error adds up and nothing pulls the position back: it \
         drifts like odometry, only slower.",
    );
    ui.label(
        "Why differential's 95% ellipse outgrows the room while its error stays small: the \
         filter is honest about what it was told. No sensor measures its position, only \
         velocities, so the position variance grows with the process noise Q every step and \
         nothing shrinks it, exactly as for dead reckoning. With robot_localization's default Q \
         the ellipse is metres across after a minute, while the actual error (the table above) \
         is centimetres, because the velocities it integrates are good. A filter that \
         measures the position (absolute, relative) keeps its ellipse as small as the SLAM \
         noise.",
    );
    sources::source_link(
        ui,
        "wu",
        "Source: Wu's thesis §5.3.1, \"Results of _differential and _relative\"",
    );
    let jumps: Vec<String> = sim
        .runs()
        .iter()
        .filter(|r| r.mode() != FusionMode::Odometry)
        .map(|r| {
            let n = r.slam_jumps().len().max(1) as f64;
            let mean = r.slam_jumps().iter().map(|j| j.jump).sum::<f64>() / n;
            format!(
                "{}: mean jump {:.1} mm, largest {:.1} mm",
                r.mode().name(),
                mean * 1000.0,
                r.max_slam_jump() * 1000.0
            )
        })
        .collect();
    if !jumps.is_empty() {
        ui.monospace(jumps.join("\n"));
    }
    if !sim.sensor_on(SLAM) {
        ui.colored_label(
            palette::VERMILLION,
            "The SLAM pose is switched off: every mode now runs on odometry and IMU alone.",
        );
    }
}

fn report_ui(ui: &mut egui::Ui, mode: FusionMode, report: &StepReport, color: egui::Color32) {
    match &report.outcome {
        Outcome::Updated(u) => {
            ui.colored_label(color, format!("{}: {}", mode.name(), report.label()));
            let names: Vec<&str> = u.variables.iter().map(|v| v.label()).collect();
            let list = |values: &[f64]| {
                values
                    .iter()
                    .map(|v| signed_text(*v))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            ui.monospace(format!(
                "   [{}]\n   z = [{}]\n   H x' = [{}]\n   ν = [{}]\n   NIS ν^T S^-1 ν = {:.2} ({} dof), |K| = {:.3}{}",
                names.join(", "),
                list(&u.measured),
                list(&u.predicted),
                list(&u.innovation),
                u.nis,
                u.variables.len(),
                u.gain_norm,
                if u.rejected {
                    "; rejected by the Mahalanobis test"
                } else {
                    ""
                }
            ));
        }
        Outcome::Stored => {
            ui.colored_label(color, format!("{}: {}", mode.name(), report.label()));
        }
        Outcome::Skipped(_) => {
            ui.colored_label(
                palette::VERMILLION,
                format!("{}: {}", mode.name(), report.label()),
            );
        }
    }
}
