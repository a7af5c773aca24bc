//! The explanation panel: what the step just done means, RANSAC's live
//! numbers (the sample, its hypotheses, the inliers, the best so far, the
//! adaptive bound), E with its singular values, the four decompositions with
//! their cheirality counts, and what goes wrong in the degenerate cases.

use super::images::{INLIER, OUTLIER, SAMPLE};
use crate::palette;
use crate::widgets::sources;
use slamlab_core::vision::{Method, Motion, angle_between, rotation_angle};
use slamlab_sim::visual_odometry::{TwoViewSession, VoRun};

/// The names of the four candidates, in [`slamlab_core::vision::Decomposition`]'s order.
pub const CANDIDATES: [&str; 4] = [
    "R1 = U W V^T, +u3",
    "R1 = U W V^T, −u3",
    "R2 = U W^T V^T, +u3",
    "R2 = U W^T V^T, −u3",
];

/// The panel.
pub fn explanation_ui(
    ui: &mut egui::Ui,
    run: &VoRun,
    pair: usize,
    session: Option<&TwoViewSession>,
) {
    let settings = &run.settings;
    ui.heading("Two views, one essential matrix");
    ui.label(
        "A point seen in both images satisfies x_r^T E x_l = 0 with E = [t]× R (Eq. 4.13-4.14): \
         its match in the second image lies on the epipolar line E x_l. E has five degrees of \
         freedom (R, and t up to scale), so five matches fix it (Eq. 4.22-4.25, up to ten \
         solutions); the linear eight-point method (Eq. 4.18-4.21) needs eight.",
    );
    let Some(session) = session else {
        ui.label("This run has no VO step.");
        return;
    };
    let n = session.matches().len();
    let s = settings.method.sample_size();
    ui.separator();
    ui.label(egui::RichText::new("RANSAC, now").strong());
    if let Some(error) = session.start_error() {
        ui.colored_label(OUTLIER, format!("RANSAC cannot start: {error}"));
    }
    match session.last_report() {
        None => {
            ui.label(format!(
                "No sample drawn yet. {n} matches, {:.0}% of them wrong (the simulator's \
                 share). Step one sample: RANSAC draws {s} matches at random, fits E to them \
                 and counts the matches whose Sampson distance is at most {} px.",
                100.0 * settings.outliers,
                session.config().threshold_px
            ));
        }
        Some(report) => {
            let wrong_in_sample = report
                .sample
                .iter()
                .filter(|&&i| session.wrong().get(i).copied().unwrap_or(false))
                .count();
            egui::Grid::new("vo_ransac_numbers")
                .num_columns(2)
                .striped(true)
                .show(ui, |ui| {
                    ui.label("sample");
                    ui.colored_label(
                        SAMPLE,
                        format!("{} of at most {}", report.iteration, report.bound),
                    );
                    ui.end_row();
                    ui.label("truly wrong").on_hover_text(
                        "Wrong matches in the sample: the simulator's truth, RANSAC cannot see it",
                    );
                    // Short values: a grid cell does not wrap, and a wide one
                    // would push the panel's text past its right edge.
                    ui.label(if wrong_in_sample == 0 {
                        "none".to_owned()
                    } else {
                        wrong_in_sample.to_string()
                    });
                    ui.end_row();
                    ui.label("hypotheses").on_hover_text(
                        "five-point: up to 10 real solutions; eight-point: 1 (0 if degenerate)",
                    );
                    ui.label(report.hypotheses.to_string());
                    ui.end_row();
                    if let Some(sprt) = &report.sprt {
                        ui.label("SPRT").on_hover_text(
                            "Matas and Chum's sequential probability ratio test: the matches \
                             are checked in a random order; each that agrees multiplies λ by \
                             δ/ε, each that does not by (1 − δ)/(1 − ε); the hypothesis is \
                             rejected once λ > A",
                        );
                        ui.label(if sprt.threshold.is_finite() {
                            format!(
                                "ε {:.3}, δ {:.4}, A {:.0}",
                                sprt.epsilon, sprt.delta, sprt.threshold
                            )
                        } else {
                            format!("ε {:.3} ≤ δ {:.4}: no test", sprt.epsilon, sprt.delta)
                        });
                        ui.end_row();
                        for (i, check) in sprt.checks.iter().enumerate() {
                            ui.label(if sprt.checks.len() > 1 {
                                format!("hypothesis {}", i + 1)
                            } else {
                                "the hypothesis".to_owned()
                            });
                            if check.rejected {
                                ui.colored_label(
                                    OUTLIER,
                                    format!("rejected after {} of {n}", check.evaluated),
                                )
                                .on_hover_text(format!(
                                    "λ passed A after {} matches, {} of them agreeing",
                                    check.evaluated, check.consistent
                                ));
                            } else {
                                ui.colored_label(
                                    INLIER,
                                    format!("accepted: {} of {n} agree", check.consistent),
                                );
                            }
                            ui.end_row();
                        }
                    }
                    ui.label("its inliers");
                    ui.label(match &report.sprt {
                        Some(sprt) if sprt.checks.iter().all(|c| c.rejected) => {
                            "not counted: all rejected".to_owned()
                        }
                        _ => format!("{} of {n}", report.inliers),
                    });
                    ui.end_row();
                    ui.label("best so far");
                    ui.colored_label(
                        INLIER,
                        format!(
                            "{} ({:.1}%){}",
                            report.best_inliers,
                            100.0 * report.best_inliers as f64 / n.max(1) as f64,
                            if report.improved { ": new best" } else { "" }
                        ),
                    );
                    ui.end_row();
                    ui.label("bound N").on_hover_text(if report.sprt.is_some() {
                        "With the SPRT a good hypothesis is rejected with probability about \
                         1/A, so N is the sample count at which η = Π (1 − w^s (1 − 1/A_i))^k_i \
                         falls to 1 − p (each test i used for k_i samples)"
                    } else {
                        "N = log(1 − p) / log(1 − w^s) with p = 0.99 and w the best inlier \
                         share: after N samples one was all inliers with probability p"
                    });
                    ui.label(report.bound.to_string());
                    ui.end_row();
                });
            ui.label(format!(
                "{} N from w = {:.2} (the best share), s = {s}, p = {}.",
                if wrong_in_sample == 0 {
                    "An all-inlier sample: its best hypothesis fits the true motion."
                } else {
                    "A wrong match in the sample: its hypotheses fit few matches."
                },
                report.best_inliers as f64 / n.max(1) as f64,
                session.config().confidence
            ));
            ui.colored_label(SAMPLE, format!("matches drawn: {:?}", report.sample));
            ui.label(match (session.config().method, session.config().refine) {
                (Method::FivePoint, _) => {
                    "A new best is refitted at once on all its inliers (local optimization), so \
                     the best share jumps close to the true one and the bound falls steeply."
                }
                (Method::EightPoint, true) => {
                    "A sample whose F has more inliers than any sample's before is optimized \
                     locally: F refitted on its inliers, then E refined by Levenberg-Marquardt \
                     on the Sampson distances of the matches within 3τ, 2τ and τ. It becomes \
                     the best when it has more inliers, so the best share jumps close to the \
                     true one and the bound falls steeply."
                }
                (Method::EightPoint, false) => {
                    "A sample whose F has more inliers than any sample's before is refitted on \
                     its inliers (local optimization); it becomes the best when it has more \
                     inliers, so the best share jumps close to the true one and the bound \
                     falls steeply."
                }
            });
            if report.sprt.is_some() {
                ui.label(
                    "Early rejection (SPRT): a hypothesis from a sample with a wrong match \
                     agrees with almost no match, so a dozen or two checked in a random order \
                     are enough evidence to drop it; only hypotheses that survive every match \
                     get an inlier count. ε is the best inlier share so far, δ the mean share \
                     of the rejected hypotheses; A is chosen to minimise the run's time and \
                     changes with them.",
                );
            }
        }
    }
    ui.separator();
    estimate_ui(ui, run, pair, session);
    ui.separator();
    degenerate_ui(ui, settings.method);
    ui.separator();
    ui.label(
        "Scale: a monocular camera gives each step's direction, never its length. The top view \
         scales every step by the distance the wheels measured (the thesis's choice), and \
         shows VO with steps of length 1 beside it.",
    );
    ui.horizontal_wrapped(|ui| {
        ui.label("Sources:");
        sources::source_link(
            ui,
            "xiang",
            "Xiang's thesis §4.3 (Eq. 4.9-4.28, Figs. 4.11-4.14)",
        );
    });
    ui.label(
        "Decomposition: Hartley and Zisserman, Result 9.19; RANSAC's bound: Fischler and \
         Bolles (1981); Sampson distance: Hartley and Zisserman, Eq. 11.9; early rejection: \
         Matas and Chum, Randomized RANSAC with SPRT (ICCV 2005), Chum and Matas, Optimal \
         Randomized RANSAC (PAMI 2008).",
    );
}

/// E, its singular values and the four decompositions, once RANSAC is done.
fn estimate_ui(ui: &mut egui::Ui, run: &VoRun, pair: usize, session: &TwoViewSession) {
    ui.label(egui::RichText::new("E and its four decompositions").strong());
    let Some(estimate) = session.estimate() else {
        ui.label(
            "When the samples drawn reach the bound, RANSAC refits E on the best hypothesis's \
             inliers and splits it into R and t. Run RANSAC to the end to see it.",
        );
        return;
    };
    let estimate = match estimate {
        Ok(e) => e,
        Err(error) => {
            ui.colored_label(OUTLIER, format!("No estimate for this step: {error}"));
            return;
        }
    };
    let d = &estimate.decomposition;
    let e = &estimate.essential;
    ui.label(format!(
        "{} inliers after {} samples{}.",
        estimate.inlier_count,
        estimate.iterations,
        if estimate.refitted {
            ", refitted on them by the eight-point method"
        } else {
            ""
        }
    ));
    if let Some(r) = &estimate.refinement {
        let text = format!(
            "Refined by Levenberg-Marquardt on (R, t) (3 + 2 parameters), minimizing the \
             Sampson distances: RMS {:.3} px over {} inliers before, {:.3} px over {} after \
             ({} steps in {} rounds){}.",
            r.rms_before_px,
            r.inliers_before,
            r.rms_after_px,
            r.inliers_after,
            r.steps,
            r.rounds,
            if r.applied {
                ""
            } else {
                "; not kept, its truncated cost was not lower"
            }
        );
        ui.label(text).on_hover_text(
            "The linear refit minimizes an algebraic error and is then projected onto the \
             essential matrices; the refinement minimizes the distances in pixels, first on \
             the matches within 3τ, then 2.5τ, 2τ, 1.5τ and τ (refine=off skips it).",
        );
    }
    egui::Grid::new("vo_essential")
        .num_columns(3)
        .show(ui, |ui| {
            for r in 0..3 {
                for c in 0..3 {
                    ui.monospace(format!("{:+.4}", e[(r, c)]));
                }
                ui.end_row();
            }
        });
    let sv = d.singular_values;
    ui.label(format!(
        "singular values: {:.4}, {:.4}, {:.2e}",
        sv.x, sv.y, sv.z
    ))
    .on_hover_text(
        "An essential matrix has two equal singular values and a zero one (Eq. 4.15-4.16); \
         the refit is projected onto that form.",
    );
    ui.label(
        "E = U diag(s, s, 0) V^T gives two rotations and two signs of t; only one puts the \
         triangulated points in front of both cameras (cheirality). The thesis's Eq. 4.28 \
         writes one of the four.",
    );
    egui::Grid::new("vo_decompositions")
        .num_columns(3)
        .striped(true)
        .show(ui, |ui| {
            ui.label("candidate (R, t)");
            ui.label("in front")
                .on_hover_text("inliers that triangulate with positive depth in both cameras");
            ui.label("");
            ui.end_row();
            for (k, name) in CANDIDATES.iter().enumerate() {
                let chosen = k == d.best;
                let text = egui::RichText::new(*name);
                ui.label(if chosen { text.strong() } else { text });
                ui.label(format!("{} of {}", d.in_front[k], estimate.inlier_count));
                if chosen {
                    ui.colored_label(INLIER, "chosen");
                } else {
                    ui.label("");
                }
                ui.end_row();
            }
        });
    let truth = run.pairs.get(pair).map(|p| p.truth);
    match estimate.motion {
        Motion::General => {
            if let (Some(truth), Some(t)) = (truth, estimate.translation) {
                ui.label(format!(
                    "Against the truth: rotation error {:.3}°, translation direction off by {:.2}°.",
                    rotation_angle(&(estimate.rotation.transpose() * truth.rotation)).to_degrees(),
                    angle_between(&t, &truth.translation).to_degrees()
                ));
            }
        }
        Motion::PureRotation => {
            ui.colored_label(
                palette::ORANGE,
                format!(
                    "Pure rotation: translation unobservable. After the best rotation-only \
                     fit the median parallax is {:.2} px (below {} px), so no t is reported \
                     and the chosen decomposition above means nothing.",
                    estimate.parallax_px,
                    session.config().min_parallax_px
                ),
            );
            if let Some(truth) = truth {
                ui.label(format!(
                    "Rotation error against the truth: {:.3}°.",
                    rotation_angle(&(estimate.rotation.transpose() * truth.rotation)).to_degrees()
                ));
            }
        }
    }
}

/// What goes wrong in the degenerate cases.
fn degenerate_ui(ui: &mut egui::Ui, method: Method) {
    ui.label(egui::RichText::new("When it fails").strong());
    ui.label(
        "Pure rotation (switch pure-rotation on): with t = 0 every match fits E = [t]× R for \
         any t, so RANSAC returns some E and its decomposition a confident but meaningless \
         direction. SLAM Lab checks the parallax a rotation alone cannot explain and reports \
         \"pure rotation: translation unobservable\" instead.",
    );
    ui.label(
        "Planar scene (switch planar on: only the facade is seen): the eight-point method's \
         linear system (Eq. 4.19) loses rank and it refuses the sample as degenerate; the \
         five-point method still finds E, but a plane seen from afar barely constrains t.",
    );
    ui.label(match method {
        Method::EightPoint => {
            "Eight-point without normalization (normalize off): pixel coordinates in the \
             hundreds make the 9-column system badly conditioned; errors grow several-fold \
             with 1 px noise."
        }
        Method::FivePoint => {
            "The five-point method uses the camera's calibration K; the eight-point method \
             estimates F in pixels without it, which is why it needs Hartley normalization."
        }
    });
}
