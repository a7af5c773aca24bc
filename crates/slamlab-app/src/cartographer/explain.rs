//! The explanation beside the map: what the run has (submaps, nodes,
//! trajectories, loop closures), the kidnap detector's state, and the last
//! branch-and-bound search: candidates scored and pruned per height beside
//! what exhaustive search would score.

use super::map::trajectory_color;
use slamlab_sim::cartographer::CartographerSim;
use slamlab_sim::cartographer_lesson::CartographerScenario;

/// The explanation panel.
pub fn explanation_ui(ui: &mut egui::Ui, sim: &CartographerSim, scenario: &CartographerScenario) {
    ui.heading("Submaps, loop closure and the kidnapped robot");
    ui.label(
        "Local SLAM matches each scan against the older of two active submaps (Eq. 5.5) and \
         inserts it into both (Eq. 5.3-5.4); a submap is finished after 2 × num_range_data \
         scans. Global SLAM links submaps and scans (nodes) in a pose graph: intra-submap \
         constraints from local SLAM, loop closures from branch and bound against finished \
         submaps (Algorithm 12), solved with a Huber loss every optimize_every_n_nodes nodes.",
    );
    ui.horizontal_wrapped(|ui| {
        ui.label("Sources:");
        crate::widgets::sources::source_link(
            ui,
            "xiang",
            "Xiang's thesis, Sec. 5.2 (Eq. 5.3-5.14, Algorithms 12-13)",
        );
    });
    ui.separator();
    let finished = sim.submaps.iter().filter(|s| s.finished).count();
    let closures = sim
        .constraints
        .iter()
        .filter(|c| c.kind != slamlab_sim::cartographer::ConstraintKind::IntraSubmap)
        .count();
    egui::Grid::new("cartographer_counts")
        .num_columns(2)
        .show(ui, |ui| {
            for (name, value) in [
                ("scans", sim.scans_done().to_string()),
                ("nodes", sim.nodes.len().to_string()),
                (
                    "submaps",
                    format!("{} ({finished} finished)", sim.submaps.len()),
                ),
                ("loop closures", closures.to_string()),
                ("optimizations", sim.optimizations.to_string()),
            ] {
                ui.label(name);
                ui.label(value);
                ui.end_row();
            }
        });
    ui.separator();
    ui.strong("The kidnapped robot (Algorithm 13)");
    if !scenario.detection {
        ui.label(
            "Detection is off: after a kidnap the scans go on into the same submaps, at poses \
             the matcher forces onto walls that are not there: one corrupted map (Fig. 5.10).",
        );
    }
    for (t, traj) in sim.trajectories.iter().enumerate() {
        let how = if t == 0 {
            format!("from scan {}", traj.first_scan)
        } else {
            format!("from scan {} (kidnap detected)", traj.first_scan)
        };
        let joined = if traj.joined_to != t {
            format!(", merged into trajectory {}", traj.joined_to)
        } else if t > 0 {
            ", its own map (not yet merged)".to_owned()
        } else {
            String::new()
        };
        ui.label(
            egui::RichText::new(format!("trajectory {t}: {how}{joined}"))
                .color(trajectory_color(t)),
        );
    }
    match (sim.detections.first(), sim.merges.first()) {
        (None, _) => {
            ui.label(format!(
                "No kidnap detected. T = {}, f_size = {}{}",
                scenario.t,
                scenario.f_size,
                scenario.kidnap_at.map_or(String::new(), |k| format!(
                    "; the kidnap comes before scan {k}"
                ))
            ));
        }
        (Some(d), None) => {
            ui.label(format!(
                "Detected at scan {d}. Branch and bound now searches the new trajectory's nodes \
                 against each finished submap of the first, whole and at every heading; a match \
                 above global_min_score ({}) confirmed by a second one merges the maps.",
                scenario.global_min_score
            ));
        }
        (Some(d), Some(m)) => {
            ui.label(format!(
                "Detected at scan {d}; merged at scan {m}: the inter-trajectory loop closure \
                 (thick green) moved the second map onto the first (Fig. 5.12)."
            ));
        }
    }
    ui.separator();
    ui.strong("The last branch-and-bound search");
    let Some(search) = &sim.last_search else {
        ui.label("None yet: searches begin once a submap is finished.");
        return;
    };
    let r = &search.record;
    ui.label(format!(
        "Node of scan {} in submap {}, {}: {}.",
        search.scan,
        search.submap,
        if search.global {
            "the whole submap at every heading"
        } else {
            "in the window around its estimate"
        },
        search
            .score
            .map_or("no match above the minimum score".to_owned(), |s| format!(
                "best score {s:.3}"
            ))
    ));
    ui.label(format!(
        "{} headings {:.2}° apart (Eq. 5.12).",
        r.angles,
        r.angular_step.to_degrees()
    ));
    egui::Grid::new("cartographer_bbs")
        .num_columns(3)
        .striped(true)
        .show(ui, |ui| {
            ui.strong("height");
            ui.strong("scored");
            ui.strong("pruned");
            ui.end_row();
            for h in (0..r.evaluated_per_height.len()).rev() {
                ui.label(format!("{h} (boxes of {})", 1u64 << h));
                ui.label(r.evaluated_per_height[h].to_string());
                ui.label(r.pruned_per_height.get(h).copied().unwrap_or(0).to_string());
                ui.end_row();
            }
        });
    let evaluated = r.evaluated();
    ui.label(format!(
        "{evaluated} candidates scored; exhaustive search scores {} ({:.0} times as many).",
        r.exhaustive_candidates,
        r.exhaustive_candidates as f64 / evaluated.max(1) as f64
    ));
    ui.label(format!(
        "Every search so far: {} searches, {} scored of {} exhaustive.",
        sim.bbs.searches, sim.bbs.nodes_evaluated, sim.bbs.exhaustive_candidates
    ));
}
