//! The explanation panel: what resampling is for, what each method does, and
//! the live numbers (mean copy-count variance, the largest bias of the mean).

use super::method_color;
use crate::widgets::sources;
use slamlab_core::particle::Resampler;
use slamlab_core::particle::lab::multinomial_variance;
use slamlab_sim::resampling::session::LabRun;

/// What `method` does, in two sentences.
pub fn method_text(method: Resampler) -> &'static str {
    match method {
        Resampler::Multinomial => {
            "M independent draws, each picking particle i with probability w_i (Algorithm 6 \
             of Xiang's thesis, §2.3.1, the \"naive sampler\"; its search loop is printed \
             inverted, and here it finds the first i whose cumulative weight reaches the \
             draw). Copy counts are binomial, variance M w_i (1 − w_i)."
        }
        Resampler::LowVariance => {
            "One random offset r in [0, 1/M) and M pointers r + m/M spaced evenly over the \
             cumulative weights (Algorithm 7 of Xiang's thesis, §2.3.1; Table 4.4 of Thrun, \
             Burgard and Fox, Probabilistic Robotics). A particle gets floor(M w_i) or \
             ceil(M w_i) copies, never anything else."
        }
        Resampler::Stratified => {
            "One independent draw in each of the M strata [m/M, (m+1)/M) of the cumulative \
             weights. Between multinomial and low-variance: a heavy particle still gets about \
             M w_i copies, but not always floor(M w_i) or ceil(M w_i)."
        }
        Resampler::Residual => {
            "First floor(M w_i) copies of every particle, deterministically; the few places left are \
             drawn multinomially from what remains of the weights. Every particle gets at least \
             floor(M w_i) copies."
        }
    }
}

/// The panel.
pub fn explanation_ui(ui: &mut egui::Ui, run: &LabRun) {
    let lab = run.lab();
    let m = run.particles();
    ui.heading("Resampling");
    ui.label(
        "A particle filter's weights say how well each particle explains the measurements. \
         Resampling draws a new set of M particles, each a copy of an old one picked with \
         probability equal to its weight: likely particles multiply, unlikely ones die out.",
    );
    ui.label(
        "Every method here is unbiased: on average particle i gets M w_i copies (the ticks on \
         the bars). They differ in how much the copies scatter around that average. That \
         scatter is noise the filter did not ask for: it can lose a good particle by bad luck.",
    );
    if let Some(note) = run.note() {
        ui.colored_label(crate::palette::VERMILLION, format!("Weights: {note}"));
    }
    ui.separator();
    ui.label(
        egui::RichText::new(format!(
            "Now: M = {m} particles, {} resampling{} per method",
            run.resamplings(),
            if run.resamplings() == 1 { "" } else { "s" }
        ))
        .strong(),
    );
    let theory = multinomial_variance(lab.weights(), m);
    egui::Grid::new("resampling_numbers")
        .num_columns(3)
        .striped(true)
        .show(ui, |ui| {
            ui.label("method").on_hover_text("in the row's order");
            ui.label("mean variance")
                .on_hover_text("the copy-count variance averaged over the particles");
            ui.label("largest bias").on_hover_text(
                "the largest |mean copies − M w_i| over the particles: near 0 for an unbiased \
                 method, shrinking as 1/√(resamplings)",
            );
            ui.end_row();
            for &method in &run.scenario().methods {
                ui.colored_label(method_color(method), method.name());
                match lab.stats(method).filter(|s| s.trials() > 1) {
                    Some(stats) => {
                        ui.label(format!("{:.4}", stats.mean_variance()));
                        ui.label(format!("{:.4}", stats.max_bias(lab.weights())));
                    }
                    None => {
                        ui.label("–");
                        ui.label("–");
                    }
                }
                ui.end_row();
            }
            ui.label("binomial theory")
                .on_hover_text("(1/M) Σ M w_i (1 − w_i): what multinomial should measure");
            ui.label(format!("{theory:.4}"));
            ui.label("");
            ui.end_row();
            let least = (0..m).map(|i| run.least_variance_of(i)).sum::<f64>() / m.max(1) as f64;
            ui.label("least possible")
                .on_hover_text("(1/M) Σ f (1 − f), f the fractional part of M w_i");
            ui.label(format!("{least:.4}"));
            ui.label("");
            ui.end_row();
        });
    ui.separator();
    for &method in &run.scenario().methods {
        ui.label(
            egui::RichText::new(method.name())
                .strong()
                .color(method_color(method)),
        );
        ui.label(method_text(method));
    }
    ui.horizontal_wrapped(|ui| {
        ui.label("Sources:");
        sources::source_link(ui, "xiang", "Xiang's thesis §2.3.1;");
        sources::source_link(ui, "thrun", "Probabilistic Robotics, Table 4.4");
    });
    ui.separator();
    ui.label(
        "Try: \"one-dominant\" (who keeps the heavy particle's copies exact?), \"many-tiny\" \
         (most particles expect less than one copy: who survives?), and \"uniform\" (\
         low-variance keeps every particle exactly once; multinomial loses about a third of \
         them, (1 − 1/M)^M ≈ 1/e, at every resampling).",
    );
    ui.label(
        "In a filter, resample only when the weights have degenerated: when N_eff = 1/Σw_i² \
         falls below a threshold times M (Waslander's slides, \"Occupancy Grid SLAM: \
         Resampling\"). The Monte Carlo localization lesson's resampler parameter chooses \
         among these four.",
    );
    sources::source_link(ui, "waslander", "Source: Waslander's slides");
}
