//! The explanation panel: what the current phase does, with the equations of Xiang's
//! thesis (or Waslander's slides for FastSLAM) and a link to the Sources window, and
//! its live numbers (innovation, NIS, gain, state size), per filter.

use crate::palette;
use crate::widgets::sources;
use slamlab_core::kalman::UpdateReport;
use slamlab_core::range_bearing::{self, RangeBearing};
use slamlab_core::stats::chi2_quantile;
use slamlab_sim::world::landmark_session::FilterRun;
use slamlab_sim::{LandmarkSession, Phase};

/// What a phase does, in two or three sentences, for an estimator family.
fn phase_text(kind: &str, phase: Option<Phase>, report: Option<&UpdateReport>) -> String {
    let text = textbook_phase_text(kind, phase, report);
    if kind == "ideal-ekf" && phase.is_some() {
        return text
            + " Ideal EKF: every Jacobian is taken at the true state, which only a \
               simulator knows. It is the yardstick: with exact linearization points its \
               average NEES over 50 runs stays in the band, so whatever the other EKFs \
               show beyond it comes from where they linearize.";
    }
    if kind != "fej-ekf" {
        return text;
    }
    let note = match phase {
        Some(Phase::Predict) => {
            " FEJ-EKF: F's heading column uses the move from the previous predicted position, \
             not from the corrected one, so the Jacobians of successive ticks fit together."
        }
        Some(Phase::Update { .. }) => {
            " FEJ-EKF: H is evaluated at this tick's predicted robot pose and at the landmark's \
             first estimate, not at the latest ones (the residual still uses the latest). The \
             filter then learns nothing about the map's absolute position and heading, which \
             range and bearing cannot tell it, and over a lap its average NEES stays near \
             the band where the plain EKF's climbs above it."
        }
        Some(Phase::Resample) | None => "",
    };
    text + note
}

/// The document and section a filter's phase texts come from, for the link under them.
fn phase_source(kind: &str) -> (&'static str, &'static str) {
    if kind.starts_with("fastslam") {
        ("waslander", "Source: Waslander's slides, \"FastSLAM\"")
    } else if kind == "ukf" {
        ("xiang", "Source: Xiang's thesis, §3.3 UKF-SLAM")
    } else {
        ("xiang", "Source: Xiang's thesis, §3.2 EKF-SLAM")
    }
}

fn textbook_phase_text(kind: &str, phase: Option<Phase>, report: Option<&UpdateReport>) -> String {
    let ukf = kind == "ukf";
    let fastslam = kind.starts_with("fastslam");
    match (phase, report) {
        (Some(Phase::Resample), _) if fastslam => "Resample (FastSLAM, Waslander's slides): when the effective \
            sample size N_eff = 1 / sum w_i^2 falls below the threshold times M, M particles \
            are drawn with the chosen resampler in proportion to their weights; heavy particles \
            are copied (their maps are shared, not copied), light ones vanish, and every \
            weight becomes 1/M."
            .to_owned(),
        (Some(Phase::Resample), _) => "Resample: only particle filters resample; this \
            Gaussian filter has nothing to do in this phase."
            .to_owned(),
        (Some(Phase::Predict), _) if fastslam => "Sample (FastSLAM, Waslander's slides): every particle draws a \
            new pose. FastSLAM 1.0 draws it from the motion model with the control noise; \
            FastSLAM 2.0 starts the proposal N(g(x, u), V M V^T) that this tick's measurements \
            will sharpen. The particles spread; their maps do not change."
            .to_owned(),
        (Some(Phase::Update { id, .. }), _) if fastslam => format!(
            "Weight (FastSLAM, Waslander's slides) with the measurement of landmark {id}: each particle associates \
             it (the sensor's id, or its own maximum-likelihood choice with association=unknown), \
             updates that landmark's 2x2 EKF in its own map, or starts it, and multiplies its \
             weight by the measurement's likelihood N(z - h; 0, S). Particles that disagree \
             with the measurement lose weight."
        ),
        (None, _) => "Nothing has run yet. The robot starts at a known pose with zero \
            uncertainty and an empty map (Eq. 3.5 of Xiang's thesis). Press Step phase (.) to run the \
            first prediction, or Run (Space)."
            .to_owned(),
        (Some(Phase::Predict), _) if ukf => "Predict (Eq. 3.26-3.30 of Xiang's thesis): sigma \
            points of the robot pose and of the control noise (augmented, so the noise is \
            carried through the motion model once; the printed Eq. 3.28 adds it twice) are \
            moved through the motion model with the command (v, w); their weighted spread is the new robot covariance. \
            Landmarks do not move, so only the robot block and the robot-landmark cross terms \
            change: the robot's ellipse grows."
            .to_owned(),
        (Some(Phase::Predict), _) => "Predict (Eq. 3.17-3.19 of Xiang's thesis, with \
            the motion Jacobians of its Eq. 3.34-3.35): the robot's mean moves by the command \
            (v, w) for one time step. Only the robot block P_RR and the robot-landmark cross terms P_RL \
            change (P_RR = F P_RR F^T + G Q G^T, P_RL = F P_RL); the motion noise makes the \
            robot's ellipse grow, and the landmarks stay where they were."
            .to_owned(),
        (Some(Phase::Update { id, .. }), Some(UpdateReport::Initialized { .. })) if ukf => {
            format!(
                "New landmark {id} (Eq. 3.21-3.25 of Xiang's thesis): the first measurement \
                 of landmark {id} is pushed through the inverse observation model with sigma points of \
                 the robot pose and the measurement noise; their spread gives its covariance \
                 and its correlation with the robot. The state grows by two numbers."
            )
        }
        (Some(Phase::Update { id, .. }), Some(UpdateReport::Initialized { .. })) => format!(
            "New landmark {id} (inverse observation model, Eq. 3.8-3.16 of Xiang's thesis): \
             landmark {id} is seen for the first time, so it is placed at the robot pose plus \
             the measured range and bearing. Its covariance combines the robot's uncertainty and the \
             measurement noise and is correlated with the robot; the state grows by two numbers."
        ),
        (Some(Phase::Update { id, .. }), _) if ukf => format!(
            "Update with landmark {id} (Eq. 3.31-3.32 of Xiang's thesis, with two printing \
             slips corrected: the gain printed as P_yM P_yy^T is K = P_My P_yy^-1, and where \
             Eq. 3.32 prints P = P̄ + K P_yy K^T the correct update subtracts, \
             P = P̄ − K P_yy K^T): sigma points of the state are pushed through the \
             measurement model; the innovation z − ȳ, weighted by K, corrects the \
             robot and every landmark correlated with it. The robot's and landmarks' ellipses shrink."
        ),
        (Some(Phase::Update { id, .. }), _) => format!(
            "Update with landmark {id} (Eq. 3.18-3.20 of Xiang's thesis, with H from its \
             Eq. 3.37-3.39; Eq. 3.38-3.39 print (L_x y − y_t) where (L_y − y_t) is meant): the \
             predicted range and bearing of landmark {id} are compared with the measurement. The innovation, weighted by the Kalman gain K, \
             corrects the robot and, through the correlations, every landmark; the robot's and \
             the landmarks' ellipses shrink."
        ),
    }
}

/// The explanation panel.
pub fn explanation_ui(ui: &mut egui::Ui, session: &LandmarkSession) {
    ui.heading("What happens now");
    let phase = session.last_phase();
    let phase_label = phase.map_or_else(|| "none yet".to_owned(), |p| p.label());
    ui.label(format!(
        "Tick {}, t = {:.1} s",
        session.tick(),
        session.time()
    ));
    ui.label(egui::RichText::new(format!("Last phase: {phase_label}")).strong());
    let next = session
        .next_phase()
        .map_or_else(|| "predict (new tick)".to_owned(), |p| p.label());
    ui.label(format!("Next phase: {next}"));
    if let Some(Phase::Update { id, index, .. }) = phase {
        ui.label(
            egui::RichText::new(format!("Landmark {id} is ringed in vermillion on the map."))
                .color(palette::VERMILLION),
        );
        if let Some(observation) = session.observations().get(index.wrapping_sub(1)) {
            let truth = session
                .world()
                .landmarks
                .iter()
                .find(|l| l.id == observation.id)
                .and_then(|l| range_bearing::predict(&session.truth(), &l.position).ok())
                .map(|p| p.measurement);
            let (reading, note) = measurement_text(
                &observation.measurement,
                truth.as_ref(),
                session.sensor().range_std,
            );
            ui.label(reading);
            if let Some(note) = note {
                ui.colored_label(palette::VERMILLION, note);
            }
        }
    }
    if session.filters().is_empty() {
        ui.colored_label(palette::VERMILLION, "No estimator is running.");
    }
    for run in session.filters() {
        ui.add_space(6.0);
        filter_ui(ui, &run, phase);
    }
    ui.add_space(8.0);
    ui.separator();
    consistency_ui(ui);
}

fn filter_ui(ui: &mut egui::Ui, run: &FilterRun, phase: Option<Phase>) {
    let name = run.kind.name();
    let color = palette::estimator_color(name);
    let filter = run.filter();
    let report = match phase {
        Some(Phase::Update { .. }) => run.last_update.as_ref(),
        _ => None,
    };
    egui::Frame::group(ui.style())
        .stroke(egui::Stroke::new(1.5, color))
        .show(ui, |ui| {
            ui.set_width(ui.available_width());
            ui.label(
                egui::RichText::new(format!("{}-SLAM", name.to_uppercase()))
                    .strong()
                    .color(color),
            );
            ui.label(phase_text(name, phase, report));
            let (key, source) = phase_source(name);
            sources::source_link(ui, key, source);
            if let Some(error) = &run.last_error {
                ui.colored_label(palette::VERMILLION, format!("This phase failed: {error}"));
            }
            let n = filter.landmark_ids().len();
            // A horizontal scroll keeps a long row from widening the whole panel
            // (which would push the wrapped texts past its edge).
            egui::ScrollArea::horizontal()
                .id_salt(("live_numbers_scroll", name))
                .show(ui, |ui| {
                    egui::Grid::new(("live_numbers", name))
                        .num_columns(2)
                        .striped(true)
                        .show(ui, |ui| {
                            row(ui, "landmarks in the state", n.to_string());
                            match (filter.gaussian(), filter.particles()) {
                                (Some(g), _) => row(
                                    ui,
                                    "state dimension",
                                    format!("{} = 3 + 2·{n}", g.mean().len()),
                                ),
                                (None, Some(p)) => row(
                                    ui,
                                    "particles, each with its own map",
                                    p.particle_count().to_string(),
                                ),
                                (None, None) => {}
                            }
                            match (phase, &run.last_predict, report) {
                                (Some(Phase::Predict), Some(predict), _) => {
                                    row(
                                        ui,
                                        "command (v, w)",
                                        format!(
                                            "{:.2} m/s, {:.3} rad/s",
                                            predict.control.v, predict.control.w
                                        ),
                                    );
                                    let growth = if predict.robot_det_before > 0.0 {
                                        format!(
                                            "×{:.3}",
                                            (predict.robot_det_after / predict.robot_det_before)
                                                .sqrt()
                                        )
                                    } else {
                                        "from zero".to_owned()
                                    };
                                    row(
                                        ui,
                                        "√det P_RR (robot)",
                                        format!(
                                            "{:.2e} to {:.2e} ({growth})",
                                            predict.robot_det_before.max(0.0).sqrt(),
                                            predict.robot_det_after.max(0.0).sqrt()
                                        ),
                                    );
                                }
                                (_, _, Some(UpdateReport::Initialized { id, position })) => {
                                    row(
                                        ui,
                                        "placed",
                                        format!(
                                            "landmark {id} at ({:.2}, {:.2}) m",
                                            position[0], position[1]
                                        ),
                                    );
                                }
                                (
                                    _,
                                    _,
                                    Some(UpdateReport::Corrected {
                                        innovation,
                                        innovation_covariance,
                                        nis,
                                        robot_gain_norm,
                                        gain_norm,
                                        ..
                                    }),
                                ) => {
                                    row(
                                        ui,
                                        "innovation, range",
                                        format!("{:+.3} m", innovation[0]),
                                    );
                                    row(
                                        ui,
                                        "innovation, bearing",
                                        format!(
                                            "{:+.4} rad ({:+.2}°)",
                                            innovation[1],
                                            innovation[1].to_degrees()
                                        ),
                                    );
                                    row(
                                        ui,
                                        "√S (range, bearing)",
                                        format!(
                                            "{:.3} m, {:.2}°",
                                            innovation_covariance[(0, 0)].max(0.0).sqrt(),
                                            innovation_covariance[(1, 1)]
                                                .max(0.0)
                                                .sqrt()
                                                .to_degrees()
                                        ),
                                    );
                                    let (lo, hi) =
                                        (chi2_quantile(0.025, 2.0), chi2_quantile(0.975, 2.0));
                                    let verdict = if *nis > hi {
                                        format!("above {hi:.2}")
                                    } else if *nis < lo {
                                        format!("below {lo:.2}")
                                    } else {
                                        format!("in {lo:.2}..{hi:.2}")
                                    };
                                    row(
                                        ui,
                                        "NIS ν^T S^-1 ν (2 dof)",
                                        format!("{nis:.2}, {verdict}"),
                                    );
                                    row(
                                        ui,
                                        "gain |K|, robot rows",
                                        format!("{robot_gain_norm:.3}"),
                                    );
                                    row(ui, "gain |K|, whole state", format!("{gain_norm:.3}"));
                                }
                                _ => {}
                            }
                            if let Some(m) = run.latest() {
                                row(
                                    ui,
                                    "robot position error",
                                    format!("{:.3} m", m.position_error),
                                );
                                row(
                                    ui,
                                    "its 2σ bound",
                                    format!("{:.3} m", m.position_bound_2sigma),
                                );
                                if let Some(nees) = m.nees {
                                    row(ui, "robot NEES (3 dof)", format!("{nees:.2}"));
                                }
                                if let Some(rmse) = m.landmark_rmse {
                                    row(ui, "landmark RMS error", format!("{rmse:.3} m"));
                                }
                            }
                        });
                });
        });
}

/// What the sensor reported for the update being shown, beside the truth only the
/// simulator knows; and, for a reading below zero, why the sensor could say that.
fn measurement_text(
    measured: &RangeBearing,
    truth: Option<&RangeBearing>,
    range_std: f64,
) -> (String, Option<String>) {
    let mut reading = format!(
        "Sensor: range {:.2} m, bearing {:+.1}°",
        measured.range,
        measured.bearing.to_degrees()
    );
    if let Some(t) = truth {
        reading += &format!(" (true {:.2} m, {:+.1}°)", t.range, t.bearing.to_degrees());
    }
    reading.push('.');
    let note = (measured.range < 0.0).then(|| {
        let distance = truth.map_or_else(String::new, |t| {
            format!("the landmark is only {:.2} m away and ", t.range)
        });
        format!(
            "A negative range: {distance}the range noise (σ = {range_std:.2} m) \
             pushed the reading below zero. A real sensor cannot report that. The filters take \
             it as their Gaussian noise model says (a first sighting cannot place the landmark \
             and waits for the next), and the map draws the ray behind the robot."
        )
    });
    (reading, note)
}

fn row(ui: &mut egui::Ui, name: &str, value: String) {
    ui.label(name);
    ui.label(value);
    ui.end_row();
}

fn consistency_ui(ui: &mut egui::Ui) {
    ui.label(egui::RichText::new("Reading NEES and NIS").strong());
    ui.label(
        "NEES (robot pose, 3 dof) and NIS (each update, 2 dof) compare the real error with \
         the error the filter believes it has. A consistent filter stays inside the 95% \
         chi-square band most of the time (about 1 sample in 20 outside). Above the band the \
         filter is overconfident: its ellipses are too small for its real errors, as \
         linearization makes EKF-SLAM over long runs. Below the band it is conservative: it \
         claims more uncertainty than it has. One run is a noisy witness: \"Many runs\" (map \
         toolbar) averages the NEES over 50 runs with other noise, where the band is narrow. \
         Tick FEJ-EKF among the estimators to run the same EKF with first-estimates \
         Jacobians: its average NEES over a lap lies inside the band.",
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reading_shows_beside_the_truth_and_a_negative_range_is_explained() {
        let truth = RangeBearing::new(0.3, 0.2);
        let (reading, note) = measurement_text(&RangeBearing::new(1.234, -0.1), Some(&truth), 0.5);
        assert_eq!(
            reading,
            "Sensor: range 1.23 m, bearing -5.7° (true 0.30 m, +11.5°)."
        );
        assert_eq!(note, None);

        let (reading, note) = measurement_text(&RangeBearing::new(-0.42, 0.2), Some(&truth), 0.5);
        assert!(reading.starts_with("Sensor: range -0.42 m"), "{reading}");
        let note = note.expect("a negative range is explained");
        assert!(
            note.starts_with("A negative range: the landmark is only 0.30 m away and the range noise (σ = 0.50 m)"),
            "{note}"
        );
        let (reading, note) = measurement_text(&RangeBearing::new(-0.42, 0.2), None, 0.5);
        assert_eq!(reading, "Sensor: range -0.42 m, bearing +11.5°.");
        assert!(
            note.unwrap()
                .starts_with("A negative range: the range noise")
        );
    }
}
