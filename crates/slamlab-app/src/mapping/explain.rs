//! The explanation panel: what the last phase did, with its numbers and the
//! equations it follows.

use crate::widgets::sources::source_link;
use slamlab_sim::mapping::{MappingPhase, MappingSession, PoseSource, RuleKind};

/// The panel.
pub fn explanation_ui(ui: &mut egui::Ui, session: &MappingSession) {
    let sim = session.sim();
    let scenario = session.scenario();
    ui.heading("What happens");
    ui.label(format!(
        "{} scans of {} mapped with {}.",
        sim.scans_done(),
        sim.input().scans.len(),
        sim.source().label()
    ));
    ui.add_space(4.0);
    match session.stepper().last_phase() {
        Some(MappingPhase::Predict { scan, pose }) => {
            ui.label(format!(
                "Predict, scan {scan}: the last pose moved by the odometry between the two scans \
                 gives ({:.3} m, {:.3} m, {:.1}°).",
                pose.x,
                pose.y,
                pose.theta.to_degrees()
            ));
        }
        Some(MappingPhase::Match {
            scan,
            pose,
            cost,
            iterations,
        }) => {
            if cost.is_finite() {
                ui.label(format!(
                    "Match, scan {scan}: the matcher moved the pose to ({:.3} m, {:.3} m, {:.1}°) \
                     in {iterations} iterations; cost {cost:.4}.",
                    pose.x,
                    pose.y,
                    pose.theta.to_degrees()
                ));
            } else {
                ui.label(format!(
                    "Match, scan {scan}: nothing to match against yet; the prediction stands."
                ));
            }
            if let Some(record) = sim
                .last_scan_to_map()
                .filter(|_| sim.source() == PoseSource::ScanToMap)
                && let Some((best, score)) = record.correlative
            {
                ui.label(format!(
                    "Correlative search: {} candidate poses at {:.2}° steps; best mean cell probability {score:.3} \
                     at ({:.3}, {:.3}, {:.1}°). Then {} Levenberg-Marquardt steps on Eq. 5.5.",
                    record.candidates,
                    record.angular_step.to_degrees(),
                    best.x,
                    best.y,
                    best.theta.to_degrees(),
                    record.steps.len()
                ));
            }
        }
        Some(MappingPhase::Iteration {
            scan,
            iteration,
            of,
            pose,
            mean_squared_error,
            kept,
        }) => {
            ui.label(format!(
                "ICP iteration {iteration} of {of}, scan {scan}: {kept} pairs kept, mean squared \
                 error {mean_squared_error:.5} m² before the step; the step took the scan to \
                 ({:.3} m, {:.3} m, {:.1}°). The map shows this iteration's pairs.",
                pose.x,
                pose.y,
                pose.theta.to_degrees()
            ));
        }
        Some(MappingPhase::Insert { scan, report }) => {
            ui.label(format!(
                "Insert, scan {scan}: {} end-point cells updated as hits, {} crossed cells as misses \
                 ({} seen for the first time). Each cell changes at most once per scan.",
                report.hits, report.misses, report.new_cells
            ));
        }
        Some(MappingPhase::GridStart { scan, particles }) => {
            ui.label(format!(
                "Start, scan {scan}: the first scan makes one map at the first odometry pose; all \
                 {particles} particles share it (one copy of its tiles until a particle writes)."
            ));
        }
        Some(MappingPhase::GridSkip {
            scan,
            moved,
            turned,
        }) => {
            let c = scenario.grid_fastslam_config();
            ui.label(format!(
                "Skip, scan {scan}: the robot has moved {moved:.2} m and turned {:.0}° since the last \
                 update, less than linear-update = {} m and angular-update = {:.0}°: gmapping waits \
                 (the estimate moves with the odometry until then).",
                turned.to_degrees(),
                c.linear_update,
                c.angular_update.to_degrees()
            ));
        }
        Some(MappingPhase::GridPropose {
            scan,
            proposal,
            fallbacks,
        }) => {
            if *proposal == "scan-match" {
                ui.label(format!(
                    "Propose, scan {scan}: every particle matched the scan against its own map from \
                     its odometry prediction, evaluated the scan likelihood times the motion prior at \
                     K poses around the match, fitted a Gaussian to them (Eq. 14-16 of Grisetti 2007) \
                     and drew its new pose from it; its weight is multiplied by the normalizer η \
                     (Eq. 19).{}",
                    if *fallbacks > 0 {
                        format!(
                            " {fallbacks} particle(s) could not match and took the odometry proposal."
                        )
                    } else {
                        String::new()
                    }
                ));
            } else {
                ui.label(format!(
                    "Propose, scan {scan}: every particle moved by a sample of the odometry motion \
                     model (gmapping's srr, srt, str, stt); its weight is multiplied by the scan's \
                     likelihood in its own map. Many samples land where the scan does not fit."
                ));
            }
        }
        Some(MappingPhase::GridParticle {
            scan,
            particle,
            of,
            fell_back,
        }) => {
            let proposal = sim
                .grid_fastslam()
                .and_then(|f| f.proposals().get(*particle));
            let n = particle + 1;
            match proposal {
                Some(p) if !fell_back => {
                    let cm = |v: f64| 100.0 * v.max(0.0).sqrt();
                    let (matched, gaussian) = (p.matched, p.gaussian);
                    ui.label(format!(
                        "Propose, scan {scan}, particle {n} of {of}: its odometry prediction \
                         ({:.3} m, {:.3} m, {:.1}°) (hollow circle on the map) was matched against its \
                         own map{}.",
                        p.predicted.x,
                        p.predicted.y,
                        p.predicted.theta.to_degrees(),
                        matched.map_or(String::new(), |m| format!(
                            " to ({:.3} m, {:.3} m, {:.1}°)",
                            m.x,
                            m.y,
                            m.theta.to_degrees()
                        )),
                    ));
                    if let Some(g) = gaussian {
                        let c = g.covariance;
                        ui.label(format!(
                            "Around the match, τ_j = p(z | x_j, m) · p(x_j | x_t−1, u) at K = {} poses \
                             gives the Gaussian μ = ({:.3} m, {:.3} m, {:.1}°), σ = ({:.1} cm, {:.1} cm, \
                             {:.2}°) (Eq. 14-16 of Grisetti 2007). The new pose is drawn from it \
                             ({:.3} m, {:.3} m, {:.1}°); the weight is multiplied by η, log η = {:.1} (Eq. 19).",
                            g.samples,
                            g.mean.x,
                            g.mean.y,
                            g.mean.theta.to_degrees(),
                            cm(c[(0, 0)]),
                            cm(c[(1, 1)]),
                            c[(2, 2)].max(0.0).sqrt().to_degrees(),
                            p.pose.x,
                            p.pose.y,
                            p.pose.theta.to_degrees(),
                            g.log_eta
                        ));
                        if c[(0, 0)].max(c[(1, 1)]) < 1e-6 {
                            ui.label(
                                "Nearly all of τ sits on one of the K poses: the scan fits this map so \
                                 well there that the Gaussian shrinks to a point, and the drawn pose is \
                                 that pose.",
                            );
                        }
                    }
                }
                _ => {
                    ui.label(format!(
                        "Propose, scan {scan}, particle {n} of {of}: the scan could not be matched \
                         against this particle's map (no end point near an occupied cell), so it takes \
                         the odometry proposal for this update and is weighted by the scan likelihood."
                    ));
                }
            }
        }
        Some(MappingPhase::GridWeight {
            scan,
            neff,
            threshold,
        }) => {
            ui.label(format!(
                "Weight, scan {scan}: the weights normalized (gmapping smooths them: \
                 w_i ∝ exp(Δℓ_i / (ogain · M))); N_eff = 1 / Σ w_i² = {neff:.1}. {}",
                if neff < threshold {
                    format!("Below {threshold:.1}: the particles are resampled next.")
                } else {
                    format!("At or above {threshold:.1}: no resampling, every hypothesis lives on.")
                }
            ));
        }
        Some(MappingPhase::GridResample {
            scan,
            survivors,
            of,
        }) => {
            ui.label(format!(
                "Resample, scan {scan}: low-variance resampling kept {survivors} of {of} particles; \
                 the others are copies. A copy shares its parent's map tiles until it writes, and its \
                 path: paths that share an ancestor now merge on the map."
            ));
        }
        Some(MappingPhase::GridUpdate {
            scan,
            cells,
            memory_bytes,
        }) => {
            ui.label(format!(
                "Update maps, scan {scan}: every particle inserted the scan at its own pose ({cells} \
                 cells in the heaviest particle's map). All maps together hold {:.1} MB, each shared \
                 tile counted once.",
                *memory_bytes as f64 / 1e6
            ));
        }
        Some(MappingPhase::Done) => {
            ui.label("Every scan is in the map.");
        }
        None => {
            ui.label("Press Step phase (.) or Run to insert the first scan.");
        }
    }
    ui.horizontal_wrapped(|ui| {
        ui.label("Sources:");
        source_link(ui, "xiang", "Xiang's thesis, Sec. 5.2.1 (Eq. 5.3-5.5)");
        source_link(ui, "waslander", "Waslander's slides (occupancy grids, ICP)");
        source_link(ui, "thrun", "Probabilistic Robotics, Table 9.2");
        if sim.source() == PoseSource::GridFastSlam {
            source_link(ui, "grisetti", "Grisetti et al. 2007 (gmapping)");
        }
    });
    ui.separator();
    ui.strong("The pose sources");
    ui.label(
        "True poses show what mapping with known poses gives (the map is only as wrong as the lidar). \
         Raw odometry smears the map: its error grows without bound. ICP aligns each scan to the one \
         before (point-to-point: closed form; point-to-line: linearized least squares), so errors still \
         add up, only more slowly. Scan-to-map matches each scan against the whole map built so far \
         (Cartographer's local SLAM, Sec. 5.2.1 of Xiang's thesis): a correlative search over a small window, then \
         Eq. 5.5, argmin Σ (1 − M_smooth(T_ξ h_k))², on the bicubic-interpolated grid. Grid FastSLAM \
         keeps many hypotheses at once: each particle has its own path and its own map, the weights say \
         which fit the scans, and resampling drops the ones that do not (gmapping).",
    );
    ui.separator();
    ui.strong("The update rule");
    match scenario.rule {
        RuleKind::LogOdds => ui.label(format!(
            "Log odds (Probabilistic Robotics Table 9.2): a hit adds l_occ = {}, a crossed cell adds \
             l_free = {}, clamped to [{}, {}].",
            scenario.l_occ, scenario.l_free, scenario.l_min, scenario.l_max
        )),
        RuleKind::Odds => ui.label(format!(
            "Odds (Eq. 5.3-5.4 of Xiang's thesis): odds(p) = p/(1−p); a hit multiplies a cell's odds by odds({}), \
             a crossed cell by odds({}); the probability is clamped to [{}, {}].",
            scenario.hit_probability, scenario.miss_probability, scenario.p_min, scenario.p_max
        )),
    };
    let summary = session.summary_without_agreement();
    ui.separator();
    ui.strong("So far");
    if let Some(rmse) = summary.trajectory_rmse {
        ui.label(format!("Trajectory RMSE: {rmse:.3} m"));
    }
    ui.label(format!(
        "Map: {} known cells, {:.1} MB of tiles",
        summary.map.known_cells,
        summary.map.memory_bytes as f64 / 1e6
    ));
}
