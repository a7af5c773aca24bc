//! Grid FastSLAM on the map: every particle's path drawn thin and shaded by
//! its weight, the paths that share ancestors drawn once (so the ancestry
//! visibly collapses after resampling), each particle's pose as a dot, and a
//! choice of which map is shown: the heaviest particle's, one the student
//! clicked, or the weighted mean of all.

use crate::widgets::map_canvas::MapTransform;
use egui::{Color32, Pos2, Stroke};
use slamlab_core::grid::ProbabilityGrid;
use slamlab_core::particle::{GridFastSlam, PathNode};
use std::collections::HashSet;
use std::sync::Arc;

/// Which particle's map is shown.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShownMap {
    /// The heaviest particle's (the estimate).
    #[default]
    Best,
    /// Particle `i`'s (clicked on its path's end or chosen in the panel).
    Particle(usize),
    /// Every particle's map averaged cell by cell, weighted by the weights.
    Mean,
}

/// The weighted mean map, computed when asked and kept until the filter
/// changes (it reads every particle's every tile).
#[derive(Debug, Default)]
pub struct MeanMapCache {
    /// The phase count it was computed at, and the map.
    cached: Option<(u64, Arc<ProbabilityGrid>)>,
}

impl MeanMapCache {
    /// The mean map of `filter` at phase `phase` (computed if the phase
    /// moved since the last call).
    pub fn get(&mut self, filter: &GridFastSlam, phase: u64) -> Option<Arc<ProbabilityGrid>> {
        if let Some((at, map)) = &self.cached
            && *at == phase
        {
            return Some(Arc::clone(map));
        }
        let map = Arc::new(filter.mean_map()?);
        self.cached = Some((phase, Arc::clone(&map)));
        Some(map)
    }

    /// Forgets the map (a new run).
    pub fn clear(&mut self) {
        self.cached = None;
    }
}

/// The map `shown` selects (`None`: the run's own grid, as before the first
/// scan or with another pose source).
pub fn shown_grid<'a>(
    filter: &'a GridFastSlam,
    shown: ShownMap,
    mean: Option<&'a ProbabilityGrid>,
) -> Option<&'a ProbabilityGrid> {
    match shown {
        ShownMap::Best => filter.best().map(|p| &p.map),
        ShownMap::Particle(i) => filter
            .particles()
            .get(i)
            .or_else(|| filter.best())
            .map(|p| &p.map),
        ShownMap::Mean => mean.or_else(|| filter.best().map(|p| &p.map)),
    }
}

/// A particle's shade: its weight relative to the heaviest, from faint to
/// full `color`.
fn shade(color: Color32, weight: f64, heaviest: f64) -> Color32 {
    let share = if heaviest > 0.0 {
        (weight / heaviest).clamp(0.0, 1.0)
    } else {
        1.0
    };
    let alpha = (50.0 + 205.0 * share).round() as u8;
    Color32::from_rgba_unmultiplied(color.r(), color.g(), color.b(), alpha)
}

/// Draws the particles: the path tree (each branch once, in the shade of the
/// heaviest particle that descends from it), every particle's pose, and the
/// shown particle's whole path on top in `highlight`.
pub fn draw_particles(
    painter: &egui::Painter,
    t: &MapTransform,
    filter: &GridFastSlam,
    shown: Option<usize>,
    color: Color32,
    highlight: Color32,
) {
    let particles = filter.particles();
    let weights = filter.weights();
    if particles.is_empty() {
        return;
    }
    let heaviest = weights.iter().copied().fold(0.0, f64::max);
    let mut order: Vec<usize> = (0..particles.len()).collect();
    order.sort_by(|&a, &b| weights[b].total_cmp(&weights[a]));
    // Heaviest first: a shared trunk takes the shade of its heaviest
    // descendant, and each node is drawn once.
    let mut drawn: HashSet<*const PathNode> = HashSet::new();
    for &i in &order {
        let w = weights.get(i).copied().unwrap_or(0.0);
        let stroke = Stroke::new(1.0, shade(color, w, heaviest));
        let mut line: Vec<Pos2> = Vec::new();
        let mut node: Option<&Arc<PathNode>> = Some(&particles[i].path);
        while let Some(n) = node {
            line.push(t.xy(n.pose.x, n.pose.y));
            if !drawn.insert(Arc::as_ptr(n)) {
                break;
            }
            node = n.parent.as_ref();
        }
        if line.len() >= 2 {
            painter.add(egui::Shape::line(line, stroke));
        }
    }
    // The shown particle's path, whole.
    if let Some(p) = shown.and_then(|i| particles.get(i)) {
        let line: Vec<Pos2> = p
            .path
            .path()
            .iter()
            .map(|(_, pose)| t.xy(pose.x, pose.y))
            .collect();
        if line.len() >= 2 {
            painter.add(egui::Shape::line(line, Stroke::new(2.0, highlight)));
        }
    }
    // The poses, lightest first so the heavy ones stay on top; a proposed
    // pose not yet in the path is joined to the path's end.
    for &i in order.iter().rev() {
        let p = &particles[i];
        let w = weights.get(i).copied().unwrap_or(0.0);
        let fill = shade(color, w, heaviest);
        let at = t.xy(p.pose.x, p.pose.y);
        let end = t.xy(p.path.pose.x, p.path.pose.y);
        if at.distance(end) > 1.0 {
            painter.line_segment([end, at], Stroke::new(1.0, fill));
        }
        painter.circle_filled(at, 3.0, fill);
    }
    if let Some(p) = shown.and_then(|i| particles.get(i)) {
        painter.circle_stroke(t.xy(p.pose.x, p.pose.y), 6.0, Stroke::new(2.0, highlight));
    }
}

/// The proposal of particle `i` in the update under way: its odometry
/// prediction (a hollow circle), the scan match (a line from the
/// prediction), and the pose drawn (a ring).
pub fn draw_proposal(
    painter: &egui::Painter,
    t: &MapTransform,
    filter: &GridFastSlam,
    i: usize,
    color: Color32,
) {
    let Some(p) = filter.proposals().get(i) else {
        return;
    };
    let predicted = t.xy(p.predicted.x, p.predicted.y);
    let stroke = Stroke::new(1.5, color);
    painter.circle_stroke(predicted, 5.0, stroke);
    let mut to = predicted;
    if let Some(m) = p.matched {
        let matched = t.xy(m.x, m.y);
        painter.line_segment([predicted, matched], stroke);
        to = matched;
    }
    let drawn = t.xy(p.pose.x, p.pose.y);
    painter.line_segment([to, drawn], Stroke::new(1.0, color));
    painter.circle_stroke(drawn, 8.0, stroke);
}

/// The particle whose pose is nearest the screen point `at`, within
/// `radius` pixels.
pub fn particle_at(
    t: &MapTransform,
    filter: &GridFastSlam,
    at: Pos2,
    radius: f32,
) -> Option<usize> {
    filter
        .particles()
        .iter()
        .enumerate()
        .map(|(i, p)| (i, t.xy(p.pose.x, p.pose.y).distance(at)))
        .filter(|(_, d)| *d <= radius)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// The panel's part: which map is shown, and the particles' numbers.
pub fn particles_ui(ui: &mut egui::Ui, filter: &GridFastSlam, shown: &mut ShownMap) {
    let m = filter.particles().len();
    ui.horizontal_wrapped(|ui| {
        ui.label("Map shown:");
        ui.radio_value(shown, ShownMap::Best, "heaviest particle")
            .on_hover_text("The map of the particle with the largest weight: the estimate");
        ui.radio_value(shown, ShownMap::Mean, "weighted mean")
            .on_hover_text(
                "Every particle's map averaged cell by cell, each weighted by its particle's weight",
            );
        let mut chosen = match shown {
            ShownMap::Particle(i) => *i,
            _ => filter.best_index(),
        };
        let picked = matches!(shown, ShownMap::Particle(_));
        let response = ui.add_enabled(
            m > 0,
            egui::DragValue::new(&mut chosen)
                .range(0..=m.saturating_sub(1))
                .prefix("particle #"),
        );
        let response = response.on_hover_text(
            "Show one particle's map (or click a particle's dot at the end of its path on the map)",
        );
        if response.changed() || (picked && response.clicked()) {
            *shown = ShownMap::Particle(chosen);
        }
    });
    if m == 0 {
        ui.label("The particles start at the first scan.");
        return;
    }
    let shown_weight = match shown {
        ShownMap::Particle(i) => filter.weights().get(*i).copied(),
        _ => None,
    };
    ui.label(format!(
        "{m} particles, N_eff {:.1}; {} updates, {} resamplings, {} fallbacks to odometry; maps {:.1} MB (peak {:.1} MB){}",
        filter.neff(),
        filter.updates(),
        filter.resamplings(),
        filter.fallbacks(),
        filter.memory_bytes() as f64 / 1e6,
        filter.peak_memory_bytes() as f64 / 1e6,
        shown_weight.map_or(String::new(), |w| format!("; weight of the shown particle {w:.3}")),
    ));
}
