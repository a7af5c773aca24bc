//! The explanation panel and the comparison table.

use crate::palette;
use crate::widgets::sources::source_link;
use slamlab_sim::filters::session::{CorridorSim, FiltersScenario, OneStep};
use slamlab_sim::stepper::Stepper;

fn method_color(method: &str) -> egui::Color32 {
    match method {
        "ekf" => palette::BLUE,
        "ukf" => palette::ORANGE,
        _ => palette::PURPLE,
    }
}

/// The documents this lesson follows, as links to the Sources window.
fn sources_line(ui: &mut egui::Ui) {
    ui.horizontal_wrapped(|ui| {
        ui.label("Sources:");
        source_link(
            ui,
            "xiang",
            "Xiang's thesis, ch. 2 (Bayes, EKF, UKF, particles)",
        );
        source_link(
            ui,
            "wu",
            "Wu's thesis, ch. 2 (the Kalman filter's derivation)",
        );
        source_link(
            ui,
            "thrun",
            "Probabilistic Robotics, ch. 2-4 (the corridor)",
        );
    });
}

/// The comparison table: each Gaussian against the samples' moments.
pub fn table_ui(ui: &mut egui::Ui, result: Option<&OneStep>, compute_ms: f64) {
    let Some(r) = result else {
        ui.label("No valid belief yet.");
        return;
    };
    ui.label(egui::RichText::new(format!(
        "How far each Gaussian is from the moments of {} samples (computed in {compute_ms:.1} ms)",
        r.truth.points.len()
    ))
    .strong());
    egui::Grid::new("filters_comparison")
        .striped(true)
        .num_columns(5)
        .spacing(egui::vec2(14.0, 2.0))
        .show(ui, |ui| {
            for title in [
                "method",
                "mean error",
                "covariance error",
                "KL(samples || method)",
                "mean",
            ] {
                ui.strong(title);
            }
            ui.end_row();
            for row in &r.rows {
                let c = &row.comparison;
                ui.colored_label(method_color(row.method), row.method);
                ui.monospace(format!("{:.5}", c.mean_error));
                ui.monospace(format!("{:.2}%", 100.0 * c.covariance_error));
                ui.monospace(
                    c.kl_divergence
                        .map_or_else(|| "— (not PD)".to_owned(), |v| format!("{v:.5} nats")),
                );
                ui.monospace(format!(
                    "({:.4}, {:.4})",
                    row.gaussian.mean[0], row.gaussian.mean[1]
                ));
                ui.end_row();
            }
        });
    ui.label(
        egui::RichText::new(
            "mean error: |μ − μ_samples| in the output's units; covariance error: \
             ||Σ − Σ_samples||_F / ||Σ_samples||_F; KL: the information lost when the method's \
             Gaussian stands for the samples' Gaussian.",
        )
        .small(),
    );
}

/// The one-step explanation: what each method does, the Jacobian and the weights.
pub fn one_step_ui(ui: &mut egui::Ui, result: Option<&OneStep>, scenario: &FiltersScenario) {
    ui.heading("One Gaussian, one nonlinear step");
    ui.label(
        "The prior (left) goes through the function. The samples show the true result: \
         not a Gaussian. Each filter replaces it with a Gaussian, in its own way.",
    );
    sources_line(ui);
    let Some(r) = result else {
        return;
    };
    ui.add_space(6.0);
    ui.colored_label(
        palette::BLUE,
        egui::RichText::new("EKF: linearize at the mean").strong(),
    );
    ui.horizontal_wrapped(|ui| {
        ui.label("μ_y = f(μ), Σ_y = J Σ J^T (");
        source_link(ui, "xiang", "Xiang Eq. 2.23-2.25");
        ui.label(";");
        source_link(ui, "wu", "Wu Eq. 2.15-2.18");
        ui.label("). The tangent plane's Jacobian at the mean:");
    });
    // + 0.0 writes −0 as 0.
    let j = r.ekf.jacobian.map(|v| v + 0.0);
    ui.monospace(format!(
        "J = [{:>9.4} {:>9.4}]\n    [{:>9.4} {:>9.4}]",
        j[(0, 0)],
        j[(0, 1)],
        j[(1, 0)],
        j[(1, 1)]
    ));
    ui.add_space(6.0);
    ui.colored_label(
        palette::ORANGE,
        egui::RichText::new("UKF: five sigma points").strong(),
    );
    ui.horizontal_wrapped(|ui| {
        ui.label("χ = μ, μ ± √(n + λ) L e_i with λ = α²(n + κ) − n; the mean and covariance of their images (");
        source_link(ui, "xiang", "Xiang Eq. 2.26-2.28");
        ui.label(";");
        source_link(ui, "wu", "Wu Eq. 2.19-2.22");
        ui.label(").");
    });
    let w = r.ukf.weights;
    ui.monospace(format!(
        "α = {}, β = {}, κ = {}, λ = {:.4}\nW₀(m) = {:.4}, W₀(c) = {:.4}, W_i = {:.4} (i = 1…4)",
        scenario.alpha, scenario.beta, scenario.kappa, w.lambda, w.mean0, w.cov0, w.other
    ));
    if !r.ukf.is_positive_definite() {
        ui.colored_label(
            palette::VERMILLION,
            "The UKF's covariance is not positive definite here (a negative W₀(c)): its ellipse \
             is drawn with the negative part clipped, and it has no KL divergence.",
        );
    }
    ui.add_space(6.0);
    ui.colored_label(
        palette::PURPLE,
        egui::RichText::new(format!(
            "Particles: {} samples of the prior, moved",
            r.particles.points.len()
        ))
        .strong(),
    );
    ui.horizontal_wrapped(|ui| {
        ui.label(
            "Each particle goes through f exactly; their mean and covariance are the Gaussian (",
        );
        source_link(ui, "xiang", "Xiang §2.3");
        ui.label("). More particles, less scatter around the samples' moments.");
    });
}

/// The corridor explanation: the phase that ran and the Kalman filter's steps.
pub fn corridor_ui(ui: &mut egui::Ui, stepper: &Stepper<CorridorSim>) {
    let sim = stepper.sim();
    ui.heading("A robot in a corridor");
    ui.horizontal_wrapped(|ui| {
        ui.label("The Bayes filter on a histogram (");
        source_link(ui, "xiang", "Xiang §2.1, Algorithm 1");
        ui.label(") against the Kalman filter (");
        source_link(ui, "wu", "Wu §2.1.1");
        ui.label(") on the same motions and sensor readings.");
    });
    sources_line(ui);
    ui.add_space(6.0);
    match stepper.last_phase() {
        None => {
            ui.label(
                "Nothing yet: the histogram is uniform (the robot could be anywhere), the \
                 Kalman filter a wide Gaussian in the middle. Step to predict.",
            );
        }
        Some(p) if p.name() == "predict" => {
            ui.strong("predict");
            ui.label(
                "The robot moved. Histogram: bel_pred(x) = Σ p(x | u, x') bel(x'), a convolution \
                 with the motion kernel (Xiang Eq. 2.14): the belief shifts and blurs. Kalman: \
                 x_pred = x + u (Wu Eq. 2.10), P_pred = P + Q (Eq. 2.18).",
            );
        }
        Some(_) => {
            ui.strong("update");
            ui.label(
                "The sensor said door or wall. Histogram: bel(x) = η p(z | x) bel_pred(x) (Xiang \
                 Eq. 2.16): every cell times the likelihood, normalized; after one door it has \
                 a peak at every door. The Kalman filter can only hold one peak: a door becomes \
                 the position of the door nearest its mean, and if that is the wrong door, the \
                 Gaussian is confidently wrong.",
            );
        }
    }
    ui.add_space(6.0);
    let h = sim.histogram();
    let k = sim.kalman();
    ui.monospace(format!(
        "histogram: mean {:.2} m, sd {:.2} m, mode {:.2} m\nKalman:    mean {:.2} m, sd {:.2} m",
        h.mean(),
        h.variance().max(0.0).sqrt(),
        h.mode(),
        k.mean,
        k.variance.max(0.0).sqrt()
    ));
    if let Some((u, door)) = sim.last_update() {
        ui.add_space(6.0);
        ui.strong(format!(
            "The Kalman update of step {} (the last door sighting), step by step (Wu Eq. 2.5-2.10)",
            sim.last_update_tick()
        ));
        ui.monospace(format!(
            "1 prediction   x_p = {:.3} m, P_p = {:.4} m²      (2.10, 2.18)\n\
             2 measurement  z = {door:.3} m (door), R = {:.4} m²\n\
             3 gain         K = P_p / (P_p + R) = {:.4}       (2.8)\n\
             4 innovation   z − x_p = {:.3} m\n\
             5 mean         x = x_p + K (z − x_p) = {:.3} m  (2.5)\n\
             6 variance     P = (1 − K) P_p = {:.4} m²      (2.9)",
            u.prior_mean,
            u.prior_variance,
            u.measurement_variance,
            u.gain,
            u.innovation,
            u.posterior_mean,
            u.posterior_variance
        ));
    }
    if let Some(note) = sim.note() {
        ui.colored_label(palette::VERMILLION, note);
    }
}
