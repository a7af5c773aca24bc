//! The explanation beside the map: what the run has (submaps, nodes,
//! trajectories, loop closures), the kidnap detector's state, and the last
//! branch-and-bound search: candidates scored and pruned per height beside
//! what exhaustive search would score, and the search tree as it was
//! walked.

use super::map::{LOOP_CLOSURE, trajectory_color};
use crate::palette;
use egui::{Color32, Pos2, Rect, Sense, Stroke, Vec2};
use slamlab_core::scan::branch_and_bound::SearchNode;
use slamlab_sim::cartographer::CartographerSim;
use slamlab_sim::cartographer::session::CartographerScenario;

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
            let then = if sim.last_optimization.is_some_and(|o| o.scan >= *m) {
                "; the optimization after it refined both"
            } else {
                "; the optimization that refines both runs next"
            };
            ui.label(format!(
                "Detected at scan {d}; merged at scan {m}: the inter-trajectory loop closure \
                 (thick green) moved the second map onto the first (Fig. 5.12){then}."
            ));
        }
    }
    ui.separator();
    ui.strong("The last optimization");
    match &sim.last_optimization {
        None => {
            ui.label(format!(
                "None yet: the pose graph is solved every {} nodes and after a merge.",
                sim.params().optimize_every_n_nodes
            ));
        }
        Some(o) => {
            ui.label(format!(
                "After scan {}: cost Σ ρ(e^T Ω e) {} → {} in {} Levenberg-Marquardt iterations \
                 (Eq. 5.8, Huber Eq. 5.9); the nodes moved {:.3} m on average, {:.3} m at most.",
                o.scan,
                cost_text(o.cost_before),
                cost_text(o.cost_after),
                o.iterations,
                o.mean_node_move,
                o.max_node_move
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
            .map_or_else(|| no_match_text(search), |s| format!("best score {s:.3}"))
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
    if !r.nodes.is_empty() {
        ui.add_space(4.0);
        ui.label(format!(
            "The tree, its first {} nodes in the order the depth-first search visited them \
             (rows: height, top: boxes of {} cells; lines: parent to child):",
            r.nodes.len(),
            1u64 << (r.evaluated_per_height.len().saturating_sub(1))
        ));
        search_tree_ui(ui, &r.nodes, r.evaluated_per_height.len());
        ui.horizontal_wrapped(|ui| {
            for (color, what) in [
                (palette::BLUE, "branched"),
                (LOOP_CLOSURE, "leaf, new best"),
                (palette::DEAD_RECKONING, "pruned (bound not above the best)"),
            ] {
                let (rect, _) = ui.allocate_exact_size(Vec2::splat(10.0), Sense::hover());
                ui.painter().circle_filled(rect.center(), 4.0, color);
                ui.label(what);
            }
        });
    }
}

/// The parent of each recorded node: the latest earlier node one height up,
/// at the same heading, branched, whose box holds the node's (the search is
/// depth-first, so that is the box it was branched from); None for a node at
/// the top.
pub fn tree_parents(nodes: &[SearchNode]) -> Vec<Option<usize>> {
    nodes
        .iter()
        .enumerate()
        .map(|(k, n)| {
            let size = 1i64 << (n.height + 1);
            nodes[..k].iter().rposition(|p| {
                p.height == n.height + 1
                    && p.expanded
                    && p.angle == n.angle
                    && (p.di..p.di + size).contains(&n.di)
                    && (p.dj..p.dj + size).contains(&n.dj)
            })
        })
        .collect()
}

/// Draws the search tree: one row per height (the tallest on top), nodes
/// left to right in the order visited, a line from each to its parent.
fn search_tree_ui(ui: &mut egui::Ui, nodes: &[SearchNode], heights: usize) {
    let row = 16.0;
    let width = ui.available_width().max(120.0);
    let (rect, _) = ui.allocate_exact_size(
        Vec2::new(width, row * heights.max(1) as f32 + 6.0),
        Sense::hover(),
    );
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
    let label_w = 28.0;
    let inner = Rect::from_min_max(
        Pos2::new(rect.left() + label_w, rect.top() + 3.0),
        Pos2::new(rect.right() - 4.0, rect.bottom() - 3.0),
    );
    let top = heights.saturating_sub(1) as f32;
    let y_of = |h: u32| inner.top() + row * (top - h as f32) + row / 2.0;
    let step = inner.width() / nodes.len().max(1) as f32;
    let x_of = |k: usize| inner.left() + step * (k as f32 + 0.5);
    let text = ui.visuals().text_color();
    for h in 0..heights {
        painter.text(
            Pos2::new(rect.left() + 3.0, y_of(h as u32)),
            egui::Align2::LEFT_CENTER,
            format!("h{h}"),
            egui::FontId::proportional(10.0),
            text,
        );
    }
    let parents = tree_parents(nodes);
    let line = Stroke::new(0.6, Color32::from_gray(150));
    for (k, parent) in parents.iter().enumerate() {
        if let Some(p) = *parent {
            painter.line_segment(
                [
                    Pos2::new(x_of(p), y_of(nodes[p].height)),
                    Pos2::new(x_of(k), y_of(nodes[k].height)),
                ],
                line,
            );
        }
    }
    let radius = (step * 0.45).clamp(1.2, 3.5);
    for (k, n) in nodes.iter().enumerate() {
        let color = match (n.expanded, n.height) {
            (false, _) => palette::DEAD_RECKONING,
            (true, 0) => LOOP_CLOSURE,
            (true, _) => palette::BLUE,
        };
        painter.circle_filled(Pos2::new(x_of(k), y_of(n.height)), radius, color);
    }
}

/// A cost as the notes write it ("–" for none).
pub fn cost_text(cost: f64) -> String {
    if !cost.is_finite() {
        "–".to_owned()
    } else if cost != 0.0 && (cost.abs() >= 1e5 || cost.abs() < 1e-2) {
        format!("{cost:.2e}")
    } else if cost.abs() >= 100.0 {
        format!("{cost:.0}")
    } else {
        format!("{cost:.3}")
    }
}

/// What a search without a match found: its best leaf, or the bound no
/// leaf could beat, against the minimum.
pub fn no_match_text(search: &slamlab_sim::cartographer::SearchEvent) -> String {
    let min = search.min_score;
    match (search.record.best_leaf_score, search.best_bound) {
        (Some(leaf), _) => {
            format!("no match above min_score: the best leaf scored {leaf:.3}, not above {min:.3}")
        }
        (None, Some(bound)) => format!(
            "no match above min_score: no branch could score above {bound:.3} (Eq. 5.14), \
             not above {min:.3}"
        ),
        (None, None) => format!("no match above min_score {min:.3}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(height: u32, angle: usize, di: i64, dj: i64, expanded: bool) -> SearchNode {
        SearchNode {
            height,
            angle,
            di,
            dj,
            score: 0.5,
            expanded,
        }
    }

    /// A dive from height 2 to a leaf, a pruned sibling, and a second top
    /// box at another heading: each node finds the box it was branched from.
    #[test]
    fn each_tree_node_finds_the_box_it_was_branched_from() {
        let nodes = [
            node(2, 0, 0, 0, true),  // 0: top
            node(1, 0, 2, 0, true),  // 1: child of 0
            node(0, 0, 3, 1, true),  // 2: leaf under 1
            node(0, 0, 2, 0, false), // 3: pruned leaf under 1
            node(1, 0, 0, 2, false), // 4: pruned child of 0
            node(2, 1, 0, 0, true),  // 5: top, other heading
            node(1, 1, 0, 0, true),  // 6: child of 5, not of 0
            node(2, 0, 4, 0, false), // 7: pruned top
        ];
        assert_eq!(
            tree_parents(&nodes),
            vec![
                None,
                Some(0),
                Some(1),
                Some(1),
                Some(0),
                None,
                Some(5),
                None
            ]
        );
    }
}
