//! Victoria Park's reference map: gtsam's pose graph of the same drive
//! (`victoria_park.txt`, iSAM form, the trees associated), given with the data
//! set (dropped or picked with the three files, alone once they are open, or
//! `reference=` in the URL beside `data=`), solved by the project's
//! Levenberg-Marquardt one step per frame (about 150 steps; the tab never waits
//! for the whole solve), and drawn over the filters in the first filter's frame
//! ([`slamlab_sim::landmark_slam::reference_map`]). The World box states the
//! alignment's RMSE and each filter's landmark error against it.

use crate::widgets::fetch::LinkedFile;
use slamlab_sim::LandmarkSession;
use slamlab_sim::io::graph::{GraphFormat, detect_format};
use slamlab_sim::landmark_slam::reference_map::{
    self, LANDMARK_GATE_M, LandmarkScore, ReferenceFit, ReferenceMap, ReferenceSolver,
};
use std::sync::Arc;

/// The URL key that names the reference graph beside the page (as the
/// cartographer lesson's `reference=` beside `log=`).
pub const REFERENCE_KEY: &str = "reference";

/// Is this file a pose graph in iSAM form (`ODOMETRY`/`LANDMARK` lines), the
/// form of `victoria_park.txt`? Such a file is the reference map, not data.
pub fn is_reference_graph(name: &str, bytes: &[u8]) -> bool {
    let lower = name.to_ascii_lowercase();
    (lower.ends_with(".txt") || lower.ends_with(".graph"))
        && std::str::from_utf8(bytes)
            .ok()
            .is_some_and(|text| matches!(detect_format(text), Ok(GraphFormat::Isam)))
}

/// The reference map against one filter.
#[derive(Clone, Debug)]
pub struct FilterFit {
    /// The filter's short name.
    pub filter: String,
    /// The reference carried onto the filter's path, once two poses pair.
    pub fit: Option<ReferenceFit>,
    /// The filter's trees against the reference trees driven past.
    pub score: Option<LandmarkScore>,
}

/// What the map draws and the World box states, for the session as it is.
#[derive(Clone, Debug)]
pub struct Overlay {
    /// The map as solved so far.
    pub map: Arc<ReferenceMap>,
    /// One per filter, in the session's order (the first is the one drawn).
    pub fits: Vec<FilterFit>,
}

/// The reference graph being read, solved and laid over the run.
#[derive(Debug, Default)]
pub struct ReferenceState {
    /// The file's name.
    pub name: String,
    /// Where `reference=` read it from (kept for share links).
    pub location: Option<String>,
    solver: Option<ReferenceSolver>,
    fetch: Option<LinkedFile>,
    /// Why the reference could not be read or solved.
    pub error: Option<String>,
    map: Option<Arc<ReferenceMap>>,
    cache: Option<((u64, usize), Overlay)>,
}

impl ReferenceState {
    /// Reads `location` (a `reference=` link) on the next poll.
    pub fn fetch(&mut self, location: String) {
        *self = Self {
            name: crate::widgets::fetch::file_name(&location).to_owned(),
            fetch: Some(LinkedFile::new(location.clone())),
            location: Some(location),
            ..Self::default()
        };
    }

    /// Starts solving the graph in `text` (a dropped or fetched file).
    pub fn open(&mut self, name: String, location: Option<String>, text: &str) {
        *self = Self {
            name,
            location,
            ..Self::default()
        };
        match ReferenceSolver::new(text) {
            Ok(solver) => {
                self.map = Some(Arc::new(solver.map()));
                self.solver = Some(solver);
            }
            Err(why) => self.error = Some(format!("{}: {why}", self.name)),
        }
    }

    /// Is a reference given (read, being read, or refused)?
    pub fn is_given(&self) -> bool {
        !self.name.is_empty()
    }

    /// Is the graph still being fetched or solved?
    pub fn is_busy(&self) -> bool {
        self.fetch.is_some() || self.solver.as_ref().is_some_and(|s| !s.is_done())
    }

    /// One frame's work: the fetch's progress, or one Levenberg-Marquardt step
    /// (about 20 ms natively for Victoria Park's 7,120 vertices).
    pub fn poll(&mut self, ctx: &egui::Context) {
        if self.fetch.is_some() {
            if let Some((location, result)) = LinkedFile::poll(&mut self.fetch, ctx) {
                let name = self.name.clone();
                match result.and_then(|bytes| {
                    String::from_utf8(bytes).map_err(|_| "the file is not text (UTF-8)".to_owned())
                }) {
                    Ok(text) => self.open(name, Some(location), &text),
                    Err(why) => {
                        self.error = Some(format!(
                            "Could not load the reference graph {location}: {why}"
                        ));
                    }
                }
            }
            return;
        }
        let Some(solver) = self.solver.as_mut() else {
            return;
        };
        match solver.step() {
            None => {}
            Some(Ok(_)) => {
                self.map = Some(Arc::new(solver.map()));
                ctx.request_repaint();
            }
            Some(Err(why)) => {
                self.map = Some(Arc::new(solver.map()));
                self.error = Some(format!("{}: the solve stopped: {why}", self.name));
            }
        }
    }

    /// Solves the rest at once (tests, headless runs).
    pub fn finish(&mut self) {
        if let Some(solver) = self.solver.as_mut() {
            if let Err(why) = solver.solve() {
                self.error = Some(format!("{}: the solve stopped: {why}", self.name));
            }
            self.map = Some(Arc::new(solver.map()));
        }
    }

    /// The reference against every filter of `session`, computed again when the
    /// session (`version`) or the solve has moved on.
    pub fn overlay(&mut self, session: &LandmarkSession, version: u64) -> Option<&Overlay> {
        let map = self.map.clone()?;
        let key = (version, map.steps);
        if self.cache.as_ref().is_none_or(|(k, _)| *k != key) {
            self.cache = Some((key, overlay(map, session)));
        }
        self.cache.as_ref().map(|(_, overlay)| overlay)
    }

    /// The lines the World box shows: the solve's progress, the alignment and
    /// each filter's landmark error.
    pub fn lines(&mut self, session: &LandmarkSession, version: u64) -> Vec<String> {
        let mut lines = Vec::new();
        if self.fetch.is_some() {
            lines.push(format!("Reference map: loading {}…", self.name));
        }
        if let Some(why) = &self.error {
            lines.push(format!("Reference map: {why}"));
        }
        let Some(solver) = self.solver.as_ref() else {
            return lines;
        };
        let state = if solver.is_converged() {
            "converged"
        } else if solver.is_done() {
            "stopped"
        } else {
            "solving"
        };
        lines.push(format!(
            "Reference map ({}, gtsam's pose graph of this drive, solved here by \
             Levenberg-Marquardt): {state}, step {}, cost {:.6e} (from {:.4e}).",
            self.name,
            solver.steps,
            solver.cost(),
            solver.initial_cost
        ));
        let Some(overlay) = self.overlay(session, version) else {
            return lines;
        };
        let mut first = true;
        for f in &overlay.fits {
            let name = f.filter.to_uppercase();
            match (&f.fit, &f.score) {
                (Some(fit), Some(score)) => {
                    if first {
                        lines.push(format!(
                            "Aligned to the {name} path by distance driven: turned {:.1}° and \
                             moved by ({:.1}, {:.1}) m, {:.2} m RMS over {} graph poses.",
                            fit.rotation_deg,
                            fit.translation_m[0],
                            fit.translation_m[1],
                            fit.rmse,
                            fit.pairs
                        ));
                    }
                    lines.push(format!(
                        "{name} trees vs the {} reference trees so far: {} within {:.0} m, {}.",
                        score.reference,
                        score.matched,
                        score.gate_m,
                        score
                            .rmse
                            .map_or("none to measure".to_owned(), |r| format!("{r:.2} m RMS"))
                    ));
                }
                _ => {
                    if first {
                        lines.push("Aligned once the car has moved.".to_owned());
                    }
                }
            }
            first = false;
        }
        lines
    }

    /// The state the browser and UI tests read.
    pub fn test_state(&self, session: &LandmarkSession) -> serde_json::Value {
        let solver = self.solver.as_ref().map(|s| {
            serde_json::json!({
                "steps": s.steps,
                "rejected": s.rejected,
                "initial_cost": s.initial_cost,
                "cost": s.cost(),
                "converged": s.is_converged(),
                "done": s.is_done(),
            })
        });
        let name = self.name.clone();
        let error = self.error.clone();
        let loading = self.fetch.is_some();
        let fits = self.map.clone().map(|map| overlay(map, session)).map(|o| {
            serde_json::json!({
                "trees": o.map.trees.len(),
                "poses": o.map.path.len(),
                "filters": o.fits.iter().map(|f| serde_json::json!({
                    "filter": f.filter,
                    "fit": f.fit,
                    "landmarks": f.score,
                })).collect::<Vec<_>>(),
            })
        });
        serde_json::json!({
            "name": name,
            "loading": loading,
            "error": error,
            "solver": solver,
            "overlay": fits,
        })
    }
}

/// `map` against every filter of `session`: each filter's path aligned to it
/// and its trees scored against the reference trees driven past.
fn overlay(map: Arc<ReferenceMap>, session: &LandmarkSession) -> Overlay {
    let dead = session.dead_reckoning_path();
    let fits = session
        .filters()
        .iter()
        .map(|run| {
            let fit = reference_map::align(&map, dead, &run.records().path);
            let score = fit.as_ref().map(|fit| {
                let trees: Vec<_> = run.filter().landmarks().iter().map(|l| l.mean).collect();
                reference_map::landmark_score(&map, fit, &trees, LANDMARK_GATE_M)
            });
            FilterFit {
                filter: run.kind.name().to_owned(),
                fit,
                score,
            }
        })
        .collect();
    Overlay { map, fits }
}
