//! The parameter panel. Every widget edits the pending scenario through
//! [`LandmarkSlamLesson::set_param`] with the parameter's URL name, so the panel, the
//! URL and the command line share one vocabulary and one validation.

use super::LandmarkSlamLesson;
use crate::lesson::Lesson as _;
use crate::palette;
use crate::widgets::sources;
use slamlab_sim::EstimatorKind;
use slamlab_sim::LandmarkScenario;
use slamlab_sim::io::landmark_data::DataSetKind;
use slamlab_sim::params::{self, ParamKind, Scenario};
use slamlab_sim::world::landmark_scenario::{Association, ControllerKind};

/// The parameter's current pending value as a number.
fn pending_number(lesson: &LandmarkSlamLesson, name: &str) -> Option<f64> {
    params::get(&lesson.pending, name).and_then(|v| v.parse::<f64>().ok())
}

/// Does the pending value differ from the running one?
fn differs(lesson: &LandmarkSlamLesson, name: &str) -> bool {
    params::get(&lesson.pending, name) != params::get(&lesson.session.scenario_now(), name)
}

fn changed_marker_ui(ui: &mut egui::Ui, lesson: &LandmarkSlamLesson, name: &str) {
    if differs(lesson, name) {
        ui.label(egui::RichText::new("•").color(palette::ORANGE))
            .on_hover_text("Changed: press \"Apply & reset\" to use it");
    }
}

fn issue_ui(ui: &mut egui::Ui, lesson: &LandmarkSlamLesson, name: &str) {
    if let Some(issue) = lesson.param_issue(name) {
        ui.colored_label(palette::VERMILLION, issue);
    }
}

/// A slider for a real-valued parameter over its allowed range.
fn number_ui(ui: &mut egui::Ui, lesson: &mut LandmarkSlamLesson, name: &str, label: &str) {
    let Some(spec) = LandmarkScenario::param(name) else {
        return;
    };
    let ParamKind::Number { min, max } = spec.kind else {
        return;
    };
    let Some(mut value) = pending_number(lesson, name) else {
        return;
    };
    // The name above its slider, so that a narrow panel does not cut it.
    let name_label = ui.label(label);
    ui.horizontal(|ui| {
        let logarithmic = min > 0.0 && max / min >= 100.0;
        let suffix = if spec.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", spec.unit)
        };
        let response = ui
            .add(
                egui::Slider::new(&mut value, min..=max)
                    .logarithmic(logarithmic)
                    .suffix(suffix),
            )
            .labelled_by(name_label.id)
            .on_hover_text(format!("{} ({name})", spec.help));
        if response.changed() {
            let _issue = lesson.set_param_live(name, &format!("{value}"));
        }
        changed_marker_ui(ui, lesson, name);
    });
    issue_ui(ui, lesson, name);
}

/// One of a list of words, as radio buttons.
fn choice_ui(
    ui: &mut egui::Ui,
    lesson: &mut LandmarkSlamLesson,
    name: &str,
    label: &str,
    options: &[(&str, &str)],
) {
    let current = params::get(&lesson.pending, name).unwrap_or_default();
    ui.horizontal_wrapped(|ui| {
        ui.label(label);
        for (value, text) in options {
            if ui.radio(current == *value, *text).clicked() {
                let _issue = lesson.set_param(name, value);
            }
        }
        changed_marker_ui(ui, lesson, name);
    });
    issue_ui(ui, lesson, name);
}

fn seed_ui(ui: &mut egui::Ui, lesson: &mut LandmarkSlamLesson) {
    let mut seed = lesson.pending.seed;
    ui.horizontal(|ui| {
        let label = ui.label("seed");
        let response = ui
            .add(egui::DragValue::new(&mut seed).speed(1.0))
            .labelled_by(label.id)
            .on_hover_text("The seed of every random stream: the same seed replays the same run");
        if response.changed() {
            let _issue = lesson.set_param("seed", &seed.to_string());
        }
        if ui
            .button("Next seed")
            .on_hover_text("Another world (random layout) and other noise")
            .clicked()
        {
            let _issue = lesson.set_param("seed", &seed.wrapping_add(1).to_string());
        }
        changed_marker_ui(ui, lesson, "seed");
    });
    issue_ui(ui, lesson, "seed");
}

fn landmarks_ui(ui: &mut egui::Ui, lesson: &mut LandmarkSlamLesson) {
    let (min, max) = match LandmarkScenario::param("landmarks").map(|s| s.kind) {
        Some(ParamKind::Count { min, max }) => (min, max),
        _ => (0, 500),
    };
    let mut count = lesson.pending.landmarks as u64;
    ui.horizontal(|ui| {
        let response = ui
            .add(egui::Slider::new(&mut count, min..=max).text("landmarks"))
            .on_hover_text("Number of landmarks (landmarks)");
        if response.changed() {
            let _issue = lesson.set_param("landmarks", &count.to_string());
        }
        changed_marker_ui(ui, lesson, "landmarks");
    });
    issue_ui(ui, lesson, "landmarks");
}

fn estimators_ui(ui: &mut egui::Ui, lesson: &mut LandmarkSlamLesson) {
    ui.horizontal_wrapped(|ui| {
        ui.label("estimators");
        let mut chosen: Vec<EstimatorKind> = lesson.pending.estimators.clone();
        let mut changed = false;
        for kind in EstimatorKind::LESSON {
            let mut on = chosen.contains(&kind);
            let text = egui::RichText::new(kind.name().to_uppercase())
                .color(palette::estimator_color(kind.name()));
            if ui.checkbox(&mut on, text).changed() {
                changed = true;
                if on {
                    chosen.push(kind);
                } else {
                    chosen.retain(|k| *k != kind);
                }
            }
        }
        if changed {
            if chosen.is_empty() {
                lesson.pending_issues.insert(
                    "estimator".to_owned(),
                    "at least one estimator must run".to_owned(),
                );
            } else {
                // Keep menu order, whatever the click order.
                let list: Vec<&str> = EstimatorKind::ALL
                    .iter()
                    .filter(|k| chosen.contains(k))
                    .map(|k| k.name())
                    .collect();
                let _issue = lesson.set_param("estimator", &list.join(","));
            }
        }
        changed_marker_ui(ui, lesson, "estimator");
    });
    issue_ui(ui, lesson, "estimator");
}

/// FastSLAM's particles and resampling, the association, the wrong-association
/// button and the particle filters' N_eff over time.
fn fastslam_ui(ui: &mut egui::Ui, lesson: &mut LandmarkSlamLesson) {
    let (min, max) = match LandmarkScenario::param("particles").map(|s| s.kind) {
        Some(ParamKind::Count { min, max }) => (min, max),
        _ => (1, 10_000),
    };
    let mut count = lesson.pending.fastslam.particles as u64;
    ui.horizontal(|ui| {
        let response = ui
            .add(
                egui::Slider::new(&mut count, min..=max)
                    .logarithmic(true)
                    .text("particles M"),
            )
            .on_hover_text("FastSLAM's particle count (particles)");
        if response.changed() {
            let _issue = lesson.set_param("particles", &count.to_string());
        }
        changed_marker_ui(ui, lesson, "particles");
    });
    issue_ui(ui, lesson, "particles");
    choice_ui(
        ui,
        lesson,
        "fastslam-resampler",
        "resampler",
        &[
            ("multinomial", "multinomial"),
            ("low-variance", "low variance"),
            ("stratified", "stratified"),
            ("residual", "residual"),
        ],
    );
    number_ui(ui, lesson, "resample-threshold", "resample when N_eff/M <");
    choice_ui(
        ui,
        lesson,
        "association",
        "association",
        &[("known", "known ids"), ("unknown", "unknown")],
    );
    number_ui(ui, lesson, "gate", "EKF/UKF gate χ²");
    number_ui(
        ui,
        lesson,
        "new-landmark-threshold",
        "FastSLAM new landmark χ²",
    );
    // A mislabel is a wrong id; with unknown association the estimators get no ids,
    // so the fault is offered only where it changes something.
    let ids_used = lesson.session.scenario().association == Association::Known;
    ui.horizontal(|ui| {
        let button = ui
            .add_enabled(ids_used, egui::Button::new("Wrong association"))
            .on_hover_text(
                "The sensor gives one observation of the next tick the id of another landmark \
                 (the nearest one seen before). With known ids every estimator trusts it.",
            )
            .on_disabled_hover_text(
                "With unknown association the sensor reports no ids, so it cannot mislabel one: \
                 EKF/UKF pick the nearest landmark inside the gate, each FastSLAM particle its \
                 own most likely one. Choose known ids (and reset) to try the fault.",
            );
        if button.clicked() {
            lesson.session.mislabel_next_observation();
        }
        if let Some(m) = lesson.session.mislabel() {
            ui.colored_label(
                palette::VERMILLION,
                format!(
                    "this tick: landmark {} reported as {}",
                    m.true_id, m.reported_id
                ),
            );
        }
    });
    let runs: Vec<_> = lesson
        .session
        .filters()
        .into_iter()
        .filter(|r| !r.n_eff.is_empty())
        .collect();
    if !runs.is_empty() {
        ui.label("N_eff before each resampling (dots: resampled)");
        egui_plot::Plot::new("plot_n_eff")
            .height(90.0)
            .allow_scroll(false)
            .allow_drag(false)
            .allow_zoom(false)
            .include_y(0.0)
            .show(ui, |plot_ui| {
                for run in runs {
                    let color = palette::estimator_color(run.kind.name());
                    let name = run.kind.name().to_uppercase();
                    let line: Vec<[f64; 2]> =
                        run.n_eff.iter().map(|n| [n.tick as f64, n.n_eff]).collect();
                    let resampled: Vec<[f64; 2]> = run
                        .n_eff
                        .iter()
                        .filter(|n| n.resampled)
                        .map(|n| [n.tick as f64, n.n_eff])
                        .collect();
                    plot_ui.line(egui_plot::Line::new(format!("{name} N_eff"), line).color(color));
                    plot_ui.points(
                        egui_plot::Points::new(format!("{name} resampled"), resampled)
                            .color(color)
                            .radius(2.0),
                    );
                }
            });
    }
}

/// The presets menu: a source's experiment or a key comparison, opened at once
/// (with the panel's seed).
fn preset_ui(ui: &mut egui::Ui, lesson: &mut LandmarkSlamLesson) {
    let mut chosen = None;
    ui.horizontal(|ui| {
        egui::ComboBox::new("landmark_preset", "preset")
            .selected_text("open a preset…")
            .width(ui.available_width() - 60.0)
            .show_ui(ui, |ui| {
                for preset in slamlab_sim::landmark_slam::presets::PRESETS {
                    if ui
                        .selectable_label(false, preset.title)
                        .on_hover_text(preset.summary)
                        .clicked()
                    {
                        chosen = Some(preset.id);
                    }
                }
            })
            .response
            .on_hover_text(
                "Open an experiment of Xiang's thesis (§3.4.3) or a key comparison; the seed stays",
            );
    });
    if let Some(id) = chosen {
        lesson.open_preset(id);
    }
    if let Some(issue) = lesson.param_issue("preset") {
        ui.colored_label(palette::VERMILLION, issue);
    }
}

fn group_ui(ui: &mut egui::Ui, title: &str, add: impl FnOnce(&mut egui::Ui)) {
    egui::CollapsingHeader::new(egui::RichText::new(title).strong())
        .default_open(true)
        .show(ui, add);
}

/// The parameter panel. Returns true when "Apply & reset" was pressed.
pub fn parameters_ui(ui: &mut egui::Ui, lesson: &mut LandmarkSlamLesson) -> bool {
    let mut apply = false;
    ui.heading("Parameters");
    ui.label("Changes apply when the run is reset; the sensor's reach changes at once.");
    ui.horizontal(|ui| {
        if ui
            .button("Apply & reset")
            .on_hover_text("Start over with these parameters (r)")
            .clicked()
        {
            apply = true;
        }
        if ui
            .button("Defaults")
            .on_hover_text("Put every parameter back to its default (apply to use them)")
            .clicked()
        {
            let controller = lesson.pending.controller;
            lesson.pending = slamlab_sim::LandmarkScenario {
                controller,
                ..super::default_scenario()
            };
            lesson.pending_issues.clear();
        }
    });
    if lesson.params_changed() {
        ui.colored_label(palette::ORANGE, "• changed: reset to apply");
    }
    preset_ui(ui, lesson);
    ui.add_space(4.0);

    if let Some(kind) = lesson.data_kind() {
        recorded_params_ui(ui, lesson, kind);
        share_ui(ui, lesson);
        return apply;
    }
    group_ui(ui, "Noise (the filters assume the same)", |ui| {
        number_ui(ui, lesson, "v-std", "forward speed σ_v");
        number_ui(ui, lesson, "w-std-deg", "turn rate σ_w");
        number_ui(ui, lesson, "range-std", "range σ_r");
        number_ui(ui, lesson, "bearing-std-deg", "bearing σ_b");
    });
    group_ui(ui, "Sensor (live: from the next tick)", |ui| {
        number_ui(ui, lesson, "fov-deg", "field of view");
        number_ui(ui, lesson, "max-range", "maximum range");
    });
    group_ui(ui, "World", |ui| {
        landmarks_ui(ui, lesson);
        choice_ui(
            ui,
            lesson,
            "layout",
            "layout",
            &[("teaching", "teaching rings"), ("random", "random")],
        );
        number_ui(ui, lesson, "world-size", "world side");
    });
    group_ui(ui, "Motion", |ui| {
        choice_ui(
            ui,
            lesson,
            "motion",
            "filter model",
            &[
                ("exact-arc", "exact arc (Xiang Eq. 2.70)"),
                ("euler", "Euler (Waslander's slides)"),
            ],
        );
        number_ui(ui, lesson, "dt", "time step Δt");
        ui.label(
            "Xiang's thesis (§3.4.2) gives no Δt; 0.1 s makes its 200 iterations one lap of \
             the circle.",
        );
        ui.horizontal_wrapped(|ui| {
            ui.label("Sources:");
            sources::source_link(ui, "xiang", "Xiang's thesis §2.5 and §3.4.2;");
            sources::source_link(ui, "waslander", "Waslander's slides, \"EKF SLAM\"");
        });
        number_ui(ui, lesson, "wheel-base", "wheel base D");
        if matches!(lesson.pending.controller, ControllerKind::Circle { .. }) {
            number_ui(ui, lesson, "v", "circle speed v");
            number_ui(ui, lesson, "w-deg", "circle turn rate w");
        }
    });
    group_ui(ui, "Run", |ui| {
        seed_ui(ui, lesson);
        estimators_ui(ui, lesson);
    });
    // Shown when FastSLAM is chosen (or runs), so the Kalman-only panel stays as it was.
    let particle_filters = lesson
        .pending
        .estimators
        .iter()
        .chain(&lesson.session.scenario().estimators)
        .any(EstimatorKind::is_particle_filter);
    if particle_filters {
        group_ui(ui, "FastSLAM and data association", |ui| {
            fastslam_ui(ui, lesson);
        });
    }
    group_ui(ui, "UKF sigma points", |ui| {
        number_ui(ui, lesson, "ukf-alpha", "spread α");
        number_ui(ui, lesson, "ukf-beta", "prior β");
        number_ui(ui, lesson, "ukf-kappa", "κ");
    });
    ui.add_space(6.0);
    share_ui(ui, lesson);
    apply
}

/// The parameters of a recorded world: the noise the filters assume (the data
/// set's measured defaults; the data's own noise is what it is), the sensor's
/// reach on the recorded measurements, the estimators and association.
fn recorded_params_ui(ui: &mut egui::Ui, lesson: &mut LandmarkSlamLesson, kind: DataSetKind) {
    group_ui(ui, "Noise the filters assume (the data's is fixed)", |ui| {
        match kind {
            DataSetKind::Mrclam => {
                number_ui(ui, lesson, "v-std", "forward speed σ_v");
                number_ui(ui, lesson, "w-std-deg", "turn rate σ_w");
            }
            DataSetKind::Freiburg => {
                number_ui(ui, lesson, "odometry-rot-std", "odometry rotations σ_rot");
                number_ui(
                    ui,
                    lesson,
                    "odometry-trans-std",
                    "odometry translation σ_trans",
                );
            }
            DataSetKind::VictoriaPark => {
                number_ui(ui, lesson, "v-std", "encoder speed σ_v");
                number_ui(ui, lesson, "steering-std-deg", "steering σ_α");
            }
        }
        number_ui(ui, lesson, "range-std", "range σ_r");
        number_ui(ui, lesson, "bearing-std-deg", "bearing σ_b");
        ui.label(
            "Defaults are measured from the data (MRCLAM: residuals against Vicon). Make              them smaller and watch the NEES leave its band.",
        );
    });
    group_ui(ui, "Sensor (live: from the next tick)", |ui| {
        number_ui(ui, lesson, "max-range", "use measurements up to");
    });
    group_ui(ui, "Run", |ui| {
        seed_ui(ui, lesson);
        estimators_ui(ui, lesson);
        number_ui(ui, lesson, "outlier-gate", "outlier gate (known ids)");
    });
    let particle_filters = lesson
        .pending
        .estimators
        .iter()
        .chain(&lesson.session.scenario().estimators)
        .any(EstimatorKind::is_particle_filter);
    if particle_filters || kind == DataSetKind::VictoriaPark {
        group_ui(ui, "FastSLAM and data association", |ui| {
            fastslam_ui(ui, lesson);
        });
    }
    ui.add_space(6.0);
}

/// The link that reproduces the running setup, for instructors to share or embed.
fn share_ui(ui: &mut egui::Ui, lesson: &LandmarkSlamLesson) {
    crate::widgets::share::share_ui(
        ui,
        |embed| lesson.share_query(embed),
        "The query string that reproduces the running setup: the lesson, the seed, every \
         parameter that is not at its default, the Many runs window when it is open, and \
         the figure keys (the current tick)",
        lesson
            .params_changed()
            .then_some("The link describes the running setup; reset to include your changes."),
    );
}
