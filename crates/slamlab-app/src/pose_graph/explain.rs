//! The explanation panel: what the solver does at this iteration, with the
//! iteration's live numbers, the graph's make-up, and the kernel comparison.

use super::OptimizeTiming;
use crate::palette;
use crate::widgets::sources;
use slamlab_core::graph::SolverKind;
use slamlab_sim::pose_graph::session::{EdgeRole, KernelRun, PoseGraphSession, kernel_name};

/// The panel.
pub fn explanation_ui(
    ui: &mut egui::Ui,
    session: &PoseGraphSession,
    optimizing: Option<usize>,
    last_optimize: Option<OptimizeTiming>,
    comparison: Option<&[KernelRun; 2]>,
) {
    let s = session.scenario();
    let k = session.iterations();
    ui.heading("What the solver does");
    ui.label(
        "Every edge says where one vertex should be as seen from another; its error e is the \
         prediction minus the measurement, and the graph's cost is F(x) = Σ e^TΩe (Eq. 4.2 \
         of Xiang's thesis, which prints Ω^-1; Ω is the information matrix, so it multiplies). \
         Linearizing every error, e(x+Δx) ~ e + JΔx, gives the sparse normal equations \
         H Δx = b with H = Σ J^TΩJ and b = -Σ J^TΩe.",
    );
    sources::source_link(
        ui,
        "xiang",
        "Source: Xiang's thesis §4.1, \"The Pose Graph\"",
    );
    ui.add_space(4.0);
    let text = match s.solver {
        SolverKind::GaussNewton => {
            "Gauss-Newton solves H Δx = b by a sparse Cholesky factorization (L L^T = H) and always \
             takes the step. Near the solution it converges in a few iterations: watch the path snap."
        }
        SolverKind::LevenbergMarquardt => {
            "Levenberg-Marquardt solves (H + λI) Δx = b. It takes the step only if the cost falls, \
             and then divides λ by 10 (towards Gauss-Newton); a rejected step multiplies λ by 10 \
             (towards a short gradient step), as g2o does (Wu's thesis §4.4.2)."
        }
        SolverKind::GradientDescent => {
            "The first-order method moves every vertex along its own block of the gradient, scaled \
             by the inverse of its diagonal block of H, halving the step until the cost falls \
             (in the spirit of TORO, Wu's thesis §4.4.1). It uses no off-diagonal blocks, so \
             a loop's correction travels around it one edge per iteration: many iterations."
        }
    };
    ui.label(text);
    match s.solver {
        SolverKind::GaussNewton => {}
        SolverKind::LevenbergMarquardt => {
            sources::source_link(ui, "wu", "Source: Wu's thesis §4.4.2, g2o");
        }
        SolverKind::GradientDescent => {
            sources::source_link(ui, "wu", "Source: Wu's thesis §4.4.1, TORO");
        }
    }
    if s.kernel != slamlab_sim::pose_graph::session::KernelChoice::None {
        ui.add_space(4.0);
        ui.label(format!(
            "Robust kernel {} (width {}): every edge is weighted by ρ'(e^TΩe), so an edge whose \
             Mahalanobis distance is far beyond {} pulls less (iteratively reweighted least squares).",
            kernel_name(s.kernel),
            s.kernel_width,
            s.kernel_width
        ));
    }
    ui.separator();
    ui.label(egui::RichText::new("This iteration").strong());
    egui::Grid::new("pose_graph_numbers")
        .num_columns(2)
        .striped(true)
        .show(ui, |ui| {
            let row = |ui: &mut egui::Ui, a: &str, b: String| {
                ui.label(a);
                ui.label(b);
                ui.end_row();
            };
            row(ui, "iterations run", k.to_string());
            if let Some(r) = session.last_report() {
                row(ui, "cost before", format!("{:.6e}", r.cost_before));
                row(ui, "cost after", format!("{:.6e}", r.cost));
                row(ui, "change", cost_change(r.cost_before, r.cost));
                row(ui, "|Δx| tried", format!("{:.4e}", r.step_norm));
                if let Some(l) = r.lambda {
                    row(ui, "λ", format!("{l:.3e}"));
                }
                if let Some(a) = r.step_length {
                    row(ui, "step length", format!("{a:.4}"));
                }
                row(
                    ui,
                    "step",
                    if r.accepted {
                        "taken"
                    } else {
                        "rejected (cost would rise)"
                    }
                    .to_owned(),
                );
                row(
                    ui,
                    "converged",
                    if r.converged { "yes" } else { "not yet" }.to_owned(),
                );
            } else {
                row(ui, "cost", format!("{:.6e}", session.cost()));
                row(
                    ui,
                    "next",
                    "press Step iteration (or '.') to run one".to_owned(),
                );
            }
            if let Some(rmse) = session.rmse() {
                row(ui, "position RMSE vs truth", format!("{rmse:.4} m"));
            }
        });
    if let Some(n) = optimizing {
        ui.label(
            egui::RichText::new(format!("Optimizing: {n} iterations so far…"))
                .color(palette::ORANGE),
        );
    }
    if let Some(t) = last_optimize {
        ui.label(format!(
            "Last Optimize: {} iterations, {} in {:.0} ms ({:.0} ms in the solver)",
            t.iterations,
            if t.converged { "converged" } else { "stopped" },
            t.wall_ms,
            t.compute_ms
        ));
    }
    ui.separator();
    ui.label(egui::RichText::new("The graph").strong());
    let count = |role: EdgeRole| session.roles().iter().filter(|r| **r == role).count();
    let g = session.graph();
    ui.label(format!(
        "{}: {} poses, {} landmarks; {} odometry edges, {} loop closures, {} landmark edges, {} priors{}",
        session.source(),
        g.pose_count(),
        g.point_count(),
        count(EdgeRole::Odometry),
        count(EdgeRole::LoopClosure),
        count(EdgeRole::Landmark),
        count(EdgeRole::Prior),
        match count(EdgeRole::WrongLoopClosure) {
            0 => String::new(),
            n => format!(", {n} wrong loop closure{}", if n == 1 { "" } else { "s" }),
        }
    ));
    for note in session.notes().iter().rev().take(3) {
        ui.label(note);
    }
    if let Some([plain, robust]) = comparison {
        ui.separator();
        ui.label(egui::RichText::new("With and without a robust kernel").strong());
        for run in [plain, robust] {
            let rmse = run
                .rmse
                .map_or_else(String::new, |r| format!(", position RMSE {r:.3} m"));
            match &run.error {
                Some(e) => ui.colored_label(palette::VERMILLION, format!("{}: {e}", run.kernel)),
                None => ui.label(format!(
                    "{}: {} iterations, cost {:.4e}{rmse}",
                    run.kernel, run.iterations, run.cost
                )),
            };
        }
        ui.label(
            "Both start from the graph's first estimate. On the map the result without a kernel \
             is the broad orange band, the result with the kernel the reddish-purple line; where \
             they agree the line runs inside the band.",
        );
    }
}

/// The relative change of the cost from `before` to `after`, in per cent: three
/// decimals with its sign ("-12.345 %"); a change too small for three decimals in
/// two significant digits ("-2.3e-5 %", never "-0.000 %"); no change "0 %".
fn cost_change(before: f64, after: f64) -> String {
    let change = if before > 0.0 && after.is_finite() {
        100.0 * (after - before) / before
    } else {
        0.0
    };
    if change == 0.0 {
        "0 %".to_owned()
    } else if change.abs() < 0.0005 {
        format!("{change:+.1e} %")
    } else {
        format!("{change:+.3} %")
    }
}

#[cfg(test)]
mod tests {
    use super::cost_change;

    #[test]
    fn a_cost_change_reads_as_a_number_never_minus_zero() {
        assert_eq!(cost_change(200.0, 150.0), "-25.000 %");
        assert_eq!(cost_change(1.0e6, 1.0e6 - 0.23), "-2.3e-5 %");
        assert_eq!(cost_change(1.0e6, 1.0e6 + 0.23), "+2.3e-5 %");
        assert_eq!(cost_change(5.0, 5.0), "0 %");
        assert_eq!(cost_change(0.0, 1.0), "0 %");
        assert_eq!(cost_change(1.0, f64::NAN), "0 %");
    }
}
