//! A student's optimized graph dropped on the pose-graph lesson: when its
//! vertices and edges are the graph on screen's (`metrics::graph::with_states_of`,
//! which names the first difference otherwise), it is a solution of this
//! problem, scored as `slamlab graph evaluate` scores it
//! (`metrics::graph::score_graph`):
//!
//! ```text
//! F(x) = Σ_ij e_ij(x)ᵀ Ω_ij e_ij(x)     (plain least squares, the problem's edges)
//! ratio = F(x_student) / F(x_lesson)
//! ```
//!
//! where `x_lesson` is the lesson's graph as its solver has it now (optimize it to
//! convergence for the reference solver's final cost), and, where the example has
//! a truth, the position RMSE against it (the lesson's own "RMSE", by vertex). It
//! is drawn over the lesson's graph in its own colour and can be removed.

use egui::{Color32, Stroke};
use slamlab_core::graph::{PoseGraph, RobustKernel, VertexState, graph_cost};
use slamlab_sim::metrics::graph::{GraphScore, score_graph, with_states_of};
use slamlab_sim::pose_graph::session::PoseGraphSession;

/// Solutions held at most.
pub const MAX_SOLUTIONS: usize = 5;

/// One student's solution.
#[derive(Clone, Debug)]
pub struct Solution {
    /// The file's name.
    pub name: String,
    /// Its colour.
    pub color: Color32,
    /// The problem with the file's vertex states.
    pub graph: PoseGraph,
    /// Drawn on the map.
    pub visible: bool,
    /// Its score against the lesson's graph now.
    pub score: Option<GraphScore>,
    /// Position RMSE against the truth, metres (built-in examples).
    pub ate: Option<f64>,
    /// The pose vertices in id order and the point vertices, as drawn (sorted
    /// once, when the file came).
    path: Vec<slamlab_core::Pose2>,
    points: Vec<[f64; 2]>,
}

/// The solutions and when they were scored.
#[derive(Debug, Default)]
pub struct Solutions {
    items: Vec<Solution>,
    /// (iterations, history length, edges) of the lesson's graph when scored.
    scored: Option<(usize, usize, usize)>,
    /// The lesson's graph's cost then ([`lesson_cost`]).
    reference_cost: f64,
    /// The window is open.
    pub open: bool,
}

/// The position RMSE of `graph`'s vertices (in order) against `truth`, metres.
fn position_rmse(graph: &PoseGraph, truth: Option<&[slamlab_core::Pose2]>) -> Option<f64> {
    let truth = truth?;
    let n = truth.len().min(graph.vertices().len());
    if n == 0 {
        return None;
    }
    let sum: f64 = truth
        .iter()
        .zip(graph.vertices())
        .map(|(t, v)| {
            let p = v.state.position();
            (t.x - p[0]) * (t.x - p[0]) + (t.y - p[1]) * (t.y - p[1])
        })
        .sum();
    Some((sum / n as f64).sqrt())
}

/// The lesson's graph's plain least-squares cost (what a solution is scored by).
pub fn lesson_cost(session: &PoseGraphSession) -> f64 {
    graph_cost(session.graph(), &RobustKernel::None)
}

impl Solutions {
    /// The solutions, in the order they came.
    pub fn items(&self) -> &[Solution] {
        &self.items
    }

    /// Takes `file` as a solution of the lesson's problem if it is one;
    /// otherwise says why not (the first difference).
    pub fn try_add(
        &mut self,
        session: &PoseGraphSession,
        name: &str,
        file: &PoseGraph,
    ) -> Result<String, String> {
        let solved = with_states_of(session.start_graph(), file)?;
        if self.items.len() >= MAX_SOLUTIONS {
            return Ok(format!(
                "{name} solves the graph on screen, but the lesson holds {MAX_SOLUTIONS} solutions at most: remove one first"
            ));
        }
        let color = crate::widgets::estimates::free_color(self.items.iter().map(|s| s.color));
        self.items.retain(|s| s.name != name);
        let mut path: Vec<(u64, slamlab_core::Pose2)> = Vec::new();
        let mut points = Vec::new();
        for v in solved.vertices() {
            match v.state {
                VertexState::Pose(q) => path.push((v.id, q)),
                VertexState::Point(q) => points.push([q[0], q[1]]),
            }
        }
        path.sort_by_key(|(id, _)| *id);
        self.items.push(Solution {
            name: name.to_owned(),
            color,
            ate: position_rmse(&solved, session.truth()),
            graph: solved,
            visible: true,
            score: None,
            path: path.into_iter().map(|(_, q)| q).collect(),
            points,
        });
        self.scored = None;
        self.open = true;
        self.refresh(session);
        Ok(format!(
            "{name} has the vertices and edges of the graph on screen: scored as your solution in \"Your solutions\""
        ))
    }

    /// Scores every solution again at the next refresh (the lesson's graph was
    /// replaced: a Reset, a new seed or parameters).
    pub fn rescore(&mut self) {
        self.scored = None;
    }

    /// Forgets every solution (another problem opened).
    pub fn clear(&mut self) -> usize {
        let n = self.items.len();
        self.items.clear();
        self.scored = None;
        n
    }

    /// Removes solution `index`.
    pub fn remove(&mut self, index: usize) {
        if index < self.items.len() {
            self.items.remove(index);
        }
    }

    /// Scores the solutions against the lesson's graph as it is now (again only
    /// when the lesson's graph changed).
    pub fn refresh(&mut self, session: &PoseGraphSession) {
        let key = (
            session.iterations(),
            session.history().len(),
            session.start_graph().edges().len(),
        );
        if self.scored == Some(key) || self.items.is_empty() {
            return;
        }
        let reference = lesson_cost(session);
        for s in &mut self.items {
            s.score = score_graph(session.start_graph(), &s.graph, reference).ok();
        }
        self.scored = Some(key);
        self.reference_cost = reference;
    }

    /// The scores for the test hook.
    pub fn state(&self) -> serde_json::Value {
        serde_json::Value::Array(
            self.items
                .iter()
                .map(|s| {
                    serde_json::json!({
                        "name": s.name,
                        "cost": s.score.as_ref().map(|g| g.cost),
                        "reference_cost": s.score.as_ref().map(|g| g.reference_cost),
                        "cost_ratio": s.score.as_ref().and_then(|g| g.cost_ratio),
                        "ate": s.ate,
                        "visible": s.visible,
                    })
                })
                .collect(),
        )
    }

    /// Draws the visible solutions over the lesson's graph: the pose vertices
    /// joined in id order, and the point vertices as crosses.
    pub fn draw(&self, ctx: &egui::Context) {
        let Some(p) = crate::widgets::map_canvas::placement(ctx) else {
            return;
        };
        let painter = egui::Painter::new(ctx.clone(), p.layer, p.rect);
        let t = &p.transform;
        for s in self.items.iter().filter(|s| s.visible) {
            let line: Vec<egui::Pos2> = s
                .path
                .iter()
                .map(|q| t.pose(q))
                .filter(|q| crate::widgets::map_canvas::finite(*q))
                .collect();
            painter.add(egui::Shape::line(line, Stroke::new(2.0, s.color)));
            for q in &s.points {
                let c = t.xy(q[0], q[1]);
                if crate::widgets::map_canvas::finite(c) {
                    let d = 4.0;
                    let stroke = Stroke::new(1.5, s.color);
                    painter.line_segment([c + egui::vec2(-d, -d), c + egui::vec2(d, d)], stroke);
                    painter.line_segment([c + egui::vec2(-d, d), c + egui::vec2(d, -d)], stroke);
                }
            }
        }
    }

    /// The "Your solutions" window: the lesson's graph and each solution, with
    /// its cost, its ratio to the lesson's and its error against the truth.
    pub fn window_ui(&mut self, ctx: &egui::Context, session: &PoseGraphSession) {
        if self.items.is_empty() || !self.open {
            return;
        }
        self.refresh(session);
        let mut open = self.open;
        let mut remove = None;
        crate::widgets::estimates::show_corner_window(
            ctx,
            "Your solutions",
            &mut open,
            160.0,
            |ui| {
                ui.label(format!(
                    "F = Σ e^T Ω e over the problem's edges at each graph's vertices, against the lesson's graph now ({} iteration{}{}), as `slamlab graph evaluate` scores it.",
                    session.iterations(),
                    if session.iterations() == 1 { "" } else { "s" },
                    if session.is_converged() { ", converged" } else { ", not converged: press Optimize" }
                ));
                let fmt = crate::widgets::estimates::number;
                // The costs themselves where the window is wide enough; at
                // 800 points their ratio (and the costs in its tooltip).
                let costs = ui.available_width() >= 420.0;
                let cost = |f: Option<f64>| f.map_or("–".to_owned(), |f| format!("{f:.6e}"));
                // What does not fit the corner scrolls sideways.
                egui::ScrollArea::horizontal().show(ui, |ui| {
                    egui::Grid::new("graph_solutions").striped(true).show(ui, |ui| {
                        ui.label("");
                        ui.strong("graph");
                        if costs {
                            ui.strong("cost F");
                        }
                        ui.strong("ratio");
                        ui.strong("RMSE m");
                        ui.end_row();
                        let (rect, _) =
                            ui.allocate_exact_size(egui::vec2(12.0, 12.0), egui::Sense::hover());
                        ui.painter().rect_filled(rect, 2.0, super::map::VERTEX);
                        ui.label("the lesson's");
                        if costs {
                            ui.label(cost(Some(self.reference_cost)));
                        }
                        ui.label("1");
                        ui.label(fmt(session.rmse(), 4));
                        ui.end_row();
                        for (k, s) in self.items.iter_mut().enumerate() {
                            let (rect, _) =
                                ui.allocate_exact_size(egui::vec2(12.0, 12.0), egui::Sense::hover());
                            ui.painter().rect_filled(rect, 2.0, s.color);
                            // The switch and the remove button before the
                            // name, in reach however narrow the window.
                            ui.horizontal(|ui| {
                                ui.checkbox(&mut s.visible, "")
                                    .on_hover_text("Draw this graph over the lesson's");
                                if ui
                                    .small_button("×")
                                    .on_hover_text("Remove this solution")
                                    .clicked()
                                {
                                    remove = Some(k);
                                }
                                ui.label(crate::widgets::estimates::short_name(&s.name))
                                    .on_hover_text(&s.name);
                            });
                            let f = s.score.as_ref().map(|g| g.cost);
                            if costs {
                                ui.label(cost(f));
                            }
                            ui.label(fmt(s.score.as_ref().and_then(|g| g.cost_ratio), 9))
                                .on_hover_text(format!(
                                    "F(yours) / F(the lesson's) = {} / {}: 1 is as good as the lesson's solver, above 1 worse",
                                    cost(f),
                                    cost(Some(self.reference_cost))
                                ));
                            ui.label(fmt(s.ate, 4));
                            ui.end_row();
                        }
                    });
                });
            },
        );
        if let Some(k) = remove {
            self.remove(k);
        }
        self.open = open;
    }
}
