//! The explanation panel: what the phase that just ran did, in two or three
//! sentences with the source's algorithm, and its live numbers.

use crate::widgets::sources;
use slamlab_core::particle::BeamLikelihood;
use slamlab_core::wrap_angle;
use slamlab_sim::kidnap::{MclPhase, MclRun};

/// The panel for the phase that ran last.
pub fn explanation_ui(ui: &mut egui::Ui, run: &MclRun, last: Option<MclPhase>) {
    ui.heading("Status");
    let dt = run.scenario().dt;
    if let Some(kidnap) = run.kidnap_tick() {
        ui.label(format!(
            "Kidnapped at tick {kidnap}, {:.1} s ago; the filters were not told.",
            run.tick_count().saturating_sub(kidnap) as f64 * dt
        ));
    }
    for (k, f) in run.filters().iter().enumerate() {
        ui.monospace(format!("{}: {}", f.name.to_uppercase(), run.status_of(k)));
        let r = f.recovery();
        if r.log_w_slow.is_some() {
            ui.monospace(format!(
                "   w_slow {:.3e}, w_fast {:.3e}: injection probability {:.3}; last update {} injected, {} regenerated",
                r.log_w_slow.map_or(f64::NAN, slamlab_core::math::exp),
                r.log_w_fast.map_or(f64::NAN, slamlab_core::math::exp),
                r.injection_probability,
                r.injected,
                r.regenerated
            ));
        } else if r.regenerated > 0 {
            ui.monospace(format!(
                "   last update: {} particles regenerated",
                r.regenerated
            ));
        }
    }
    if run.kidnap_tick().is_some() {
        recovery_note_ui(ui, run);
    }
    ui.separator();
    ui.heading("What just happened");
    match last {
        None => {
            ui.label(
                "Nothing yet. Each tick has up to four phases: move (the robot drives, its wheels \
                 report odometry and the lidar scans), then, once the robot has moved far enough \
                 (update-min-d, update-min-a-deg), predict, weight and resample. Press \"Step phase\".",
            );
            ui.label(
                "AMCL, CMCL and ACMCL and the kidnapped robot problem follow §5.1 of Xiang's \
                 thesis (Algorithms 9-11); ACMCL updates w_slow and w_fast once per step, after \
                 the particle loop, where the thesis's Algorithm 11 prints them inside it.",
            );
            sources::source_link(ui, "xiang", "Source: Xiang's thesis §5.1");
        }
        Some(MclPhase::Move) => {
            if let Some((done, all)) = run.log_progress() {
                let odom = run.odometry();
                ui.label(format!(
                    "Move: the log's scan {done} of {all}, with the recorded odometry pose at its \
                     stamp. The filters get exactly what the robot recorded."
                ));
                ui.monospace(format!(
                    "odometry ({:.2} m, {:.2} m, {:.1}°)",
                    odom.x,
                    odom.y,
                    odom.theta.to_degrees()
                ));
            } else {
                ui.label(
                    "Move: the robot drove for one tick. The filters do not see where it went: they get \
                     the wheel odometry (which has its own noise) and the lidar scan.",
                );
            }
            if let Some(robot) = run.truth_now() {
                ui.monospace(format!(
                    "true pose ({:.2} m, {:.2} m, {:.1}°)",
                    robot.x,
                    robot.y,
                    robot.theta.to_degrees()
                ));
            }
            if let Some(scan) = run.scan() {
                let hits = scan
                    .ranges
                    .iter()
                    .filter(|r| r.is_finite() && **r < scan.range_max)
                    .count();
                ui.monospace(format!(
                    "scan: {} beams, {hits} hit a wall within {:.1} m",
                    scan.ranges.len(),
                    scan.range_max
                ));
            }
        }
        Some(MclPhase::Predict) => {
            ui.label(
                "Predict (sample_motion_model_odometry, Table 5.6 of Thrun, Burgard and Fox, \
                 Probabilistic Robotics): every particle moves by the odometry increment (rotate, \
                 translate, rotate) with its own noise drawn from odom-alpha1..4. The cloud \
                 spreads: the odometry is not trusted exactly.",
            );
            sources::source_link(ui, "thrun", "Source: Probabilistic Robotics, Table 5.6");
            for f in run.filters() {
                if let Some(p) = &f.last_predict {
                    let (r1, t, r2) = p.increment;
                    ui.monospace(format!(
                        "{}: δrot1 {:.1}°, δtrans {:.3} m, δrot2 {:.1}°",
                        f.name.to_uppercase(),
                        r1.to_degrees(),
                        t,
                        r2.to_degrees()
                    ));
                }
            }
        }
        Some(MclPhase::Weight) => {
            ui.label(
                "Weight (Algorithm 8, line 4, of Xiang's thesis, §3.5.1): each particle's weight \
                 is the likelihood of the scan seen from its pose, the product over the beams (in \
                 log space, so that 60 small numbers do not round to zero). Darker particles on \
                 the map are heavier.",
            );
            sources::source_link(ui, "xiang", "Source: Xiang's thesis §3.5.1, beam model");
            for f in run.filters() {
                let Some(w) = &f.last_weight else { continue };
                ui.separator();
                ui.strong(f.name.to_uppercase());
                ui.monospace(format!(
                    "{} beams; best particle ln p(z|x) = {:.1}, worst {:.1}; N_eff = {:.0} of {}",
                    w.beams,
                    w.best.1,
                    w.worst.1,
                    w.n_eff,
                    f.mcl().count()
                ));
                if let Some(note) = &w.note {
                    ui.colored_label(crate::palette::VERMILLION, note);
                }
                beams_ui(ui, "best particle", &w.best_beams);
                beams_ui(ui, "a poor particle", &w.poor_beams);
            }
        }
        Some(MclPhase::Resample) => {
            ui.label(
                "Resample (Algorithm 7 of Xiang's thesis, §2.3.1; low-variance by default): draw \
                 a new set of particles with probabilities proportional to the weights. Likely \
                 particles are copied, unlikely ones disappear; afterwards all weights are equal \
                 again.",
            );
            sources::source_link(ui, "xiang", "Source: Xiang's thesis §2.3.1, resampling");
            for f in run.filters() {
                if let Some(r) = &f.last_resample {
                    ui.monospace(format!(
                        "{}: N_eff before {:.0}; {}; {} distinct survivors",
                        f.name.to_uppercase(),
                        r.n_eff_before,
                        if r.resampled {
                            "resampled"
                        } else {
                            "not resampled this update"
                        },
                        r.distinct_parents
                    ));
                }
            }
        }
    }
    ui.separator();
    ui.heading("Estimates");
    let truth = run.robot().pose;
    for (k, f) in run.filters().iter().enumerate() {
        // The estimate as amcl publishes it: moved by the odometry since the update,
        // against the truth now (the status above reads the same error).
        match (f.mcl().estimate(), f.current_estimate(&run.odometry())) {
            (Some(e), Some(now)) if !run.has_truth() => {
                ui.monospace(format!(
                    "{}: ({:.2}, {:.2}) m, {:.1}°; no truth to measure its error; cluster of {} \
                     particles ({} clusters)",
                    f.name.to_uppercase(),
                    now.x,
                    now.y,
                    now.theta.to_degrees(),
                    e.count,
                    e.clusters
                ));
            }
            (Some(e), Some(now)) => {
                let error = run.error_now(k).map_or(f64::NAN, |e| e.position);
                let heading = wrap_angle(now.theta - truth.theta).to_degrees();
                ui.monospace(format!(
                    "{}: ({:.2}, {:.2}) m; position error {error:.2} m, heading error \
                     {heading:+.1}°; cluster of {} particles ({} clusters)",
                    f.name.to_uppercase(),
                    now.x,
                    now.y,
                    e.count,
                    e.clusters
                ));
            }
            _ => {
                ui.monospace(format!("{}: no estimate yet", f.name.to_uppercase()));
            }
        }
    }
    ui.label(
        "The estimate is the weighted mean of the heaviest cluster of particles, as ROS amcl \
         reports it; its ellipse is 95% of that cluster's spread.",
    );
    sources::source_link(ui, "ros", "Source: ROS amcl");
}

/// After a kidnap, what Augmented MCL's averages did, in the filter's own numbers:
/// w_fast against w_slow now, w_fast before the kidnap, and so whether it injects.
pub fn recovery_lines(run: &MclRun) -> Vec<String> {
    let Some(kidnap) = run.kidnap_tick() else {
        return Vec::new();
    };
    let mut lines = Vec::new();
    for f in run.filters() {
        let (Some(slow), Some(fast)) = (f.recovery().log_w_slow, f.recovery().log_w_fast) else {
            continue;
        };
        let before = f
            .updates
            .iter()
            .rev()
            .find(|u| u.tick < kidnap)
            .and_then(|u| u.log_w_fast);
        let since = match before {
            Some(b) => format!(
                "w_fast is {:.2} times what it was before the kidnap",
                slamlab_core::math::exp(fast - b)
            ),
            None => "no update before the kidnap".to_owned(),
        };
        let verdict = if fast < slow {
            format!(
                "w_fast is below w_slow: it injects with probability {:.3}",
                1.0 - slamlab_core::math::exp(fast - slow)
            )
        } else {
            "w_fast is above w_slow: it injects nothing".to_owned()
        };
        let injected: usize = f
            .updates
            .iter()
            .filter(|u| u.tick >= kidnap && u.randomized > 0.0)
            .count();
        lines.push(format!(
            "{}: {since}; {verdict}; {injected} updates since the kidnap drew new particles",
            f.name.to_uppercase()
        ));
    }
    lines
}

/// How Augmented MCL notices a kidnap, and why in this lesson it often does not.
fn recovery_note_ui(ui: &mut egui::Ui, run: &MclRun) {
    let lines = recovery_lines(run);
    if lines.is_empty() {
        return;
    }
    ui.label(egui::RichText::new("Does Augmented MCL notice the kidnap?").strong());
    ui.label(
        "w_slow and w_fast follow the particles' mean weight, slowly (recovery-alpha-slow) and \
         fast (recovery-alpha-fast). Random particles are injected with probability \
         1 − w_fast/w_slow, so only while w_fast is below w_slow: right after the mean weight \
         has dropped (Algorithm 9 of Xiang's thesis).",
    );
    let scoring = match run.scenario().laser_likelihood_aggregation {
        slamlab_core::particle::ScanAggregation::Product => format!(
            "Here each scan's likelihood is raised to the power laser-likelihood-exponent = {} \
             (it keeps global localization from locking onto a wrong place). That flattens it: \
             a lost filter's mean weight stays within a small factor of a tracking one's, while \
             w_slow, which moves by only recovery-alpha-slow per update, still remembers the \
             lower weights of the global localization at the start. So w_fast stays above \
             w_slow and AMCL injects nothing (its line below says what it does now): it finds \
             the robot again only if a particle happens to be near it. ACMCL regenerates the \
             particles its costmap rules out instead, at every update. preset=amcl-ros1 scores \
             scans as ROS amcl does (1 + Σ p³ over the beams).",
            run.scenario().laser_likelihood_exponent
        ),
        slamlab_core::particle::ScanAggregation::AmclCubes => {
            "Here scans are scored as ROS amcl does, 1 + Σ p³ over the beams: after a kidnap the \
             mean weight drops and AMCL injects a burst, but like amcl it restarts both averages \
             after every resampling that injected, so injection stops until the mean weight \
             drops again."
                .to_owned()
        }
    };
    ui.label(format!(
        "{scoring} docs/kidnap-tables.md compares both scorings over many kidnaps."
    ));
    for line in lines {
        ui.monospace(line);
    }
}

fn beams_ui(ui: &mut egui::Ui, label: &str, beams: &[BeamLikelihood]) {
    if beams.is_empty() {
        return;
    }
    let shown: Vec<String> = beams
        .iter()
        .take(8)
        .map(|b| match b.log_likelihood {
            Some(l) => format!("{:+.0}° z={:.2} m: {l:.1}", b.angle.to_degrees(), b.range),
            None => format!("{:+.0}° z={:.2} m: skipped", b.angle.to_degrees(), b.range),
        })
        .collect();
    ui.label(format!(
        "{label}, first beams (angle, range: ln p): {}",
        shown.join(", ")
    ));
}
