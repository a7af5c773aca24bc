//! The explorer: a controller that tours seeded random goals through the free
//! space of any map without touching walls, so localization runs headless.
//!
//! Planning: Dijkstra on the grid (8-connected, no corner cutting) over the
//! cells farther than `radius + clearance` from every obstacle, with a cost
//! that grows near walls so paths keep to the middle of corridors. Goals are
//! drawn uniformly among the cells reachable from the robot, at least
//! `min_goal_distance` away. Following: pure pursuit on the path with a short
//! look-ahead, turning on the spot when the path turns sharply.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use slamlab_core::grid::{Cell, OccupancyGrid, squared_distance_transform};
use slamlab_core::{Pose2, math, wrap_angle};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::sync::Arc;

/// The explorer's parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ExplorerConfig {
    /// Top speed, m/s.
    pub v_max: f64,
    /// Top turn rate, rad/s.
    pub w_max: f64,
    /// Extra distance kept from walls beyond the robot's radius, metres.
    pub clearance: f64,
    /// Distance from walls below which paths cost more, metres.
    pub preferred_clearance: f64,
    /// Pure-pursuit look-ahead, metres.
    pub lookahead: f64,
    /// Goals are at least this far away (straight line), metres.
    pub min_goal_distance: f64,
}

impl Default for ExplorerConfig {
    fn default() -> Self {
        Self {
            v_max: 0.5,
            w_max: 1.5,
            clearance: 0.08,
            preferred_clearance: 0.6,
            lookahead: 0.3,
            min_goal_distance: 2.0,
        }
    }
}

/// The planning grid, shared by clones.
#[derive(Debug)]
struct PlanMap {
    width: usize,
    height: usize,
    frame: OccupancyGrid,
    valid: Vec<bool>,
    penalty: Vec<u32>,
}

/// A seeded explorer. Cloning it (a checkpoint) shares the planning grid.
#[derive(Clone, Debug)]
pub struct Explorer {
    config: ExplorerConfig,
    plan: Arc<PlanMap>,
    rng: ChaCha8Rng,
    path: Vec<(f64, f64)>,
    next: usize,
    budget: u32,
}

impl Explorer {
    /// An explorer for a robot of radius `radius` on `grid`, goals drawn from
    /// the random stream `seed`.
    pub fn new(grid: &OccupancyGrid, radius: f64, config: ExplorerConfig, seed: u64) -> Self {
        let (w, h) = (grid.width(), grid.height());
        let seeds: Vec<bool> = grid.cells().iter().map(|c| *c == Cell::Occupied).collect();
        let sq = squared_distance_transform(&seeds, w, h);
        let res = grid.resolution();
        let keep = (radius.max(0.0) + config.clearance.max(0.0)) / res;
        let pref = config.preferred_clearance.max(0.0) / res;
        let valid = grid
            .cells()
            .iter()
            .zip(&sq)
            .map(|(c, &d)| *c == Cell::Free && d > keep * keep)
            .collect();
        let penalty = sq
            .iter()
            .map(|&d| {
                let d = d.sqrt();
                if d < pref {
                    ((pref - d) / pref * 40.0) as u32
                } else {
                    0
                }
            })
            .collect();
        let frame = OccupancyGrid::filled(1, 1, res, grid.origin(), Cell::Unknown)
            .unwrap_or_else(|_| grid.clone());
        Self {
            config,
            plan: Arc::new(PlanMap {
                width: w,
                height: h,
                frame,
                valid,
                penalty,
            }),
            rng: ChaCha8Rng::seed_from_u64(seed),
            path: Vec::new(),
            next: 0,
            budget: 0,
        }
    }

    /// The path being followed (world points), for drawing.
    pub fn path(&self) -> &[(f64, f64)] {
        &self.path
    }

    /// Drops the current path (after a collision, or a kidnap), so the next
    /// command plans a new one from where the robot is.
    pub fn replan(&mut self) {
        self.path.clear();
        self.next = 0;
    }

    /// The nearest valid cell to `(i, j)` within about 1.5 m.
    fn nearest_valid(&self, i: i64, j: i64) -> Option<usize> {
        let p = &self.plan;
        let r = (1.5 / p.frame.resolution()).ceil() as i64;
        let mut best: Option<(i64, usize)> = None;
        for dj in -r..=r {
            for di in -r..=r {
                let (a, b) = (i + di, j + dj);
                if a < 0 || b < 0 || a as usize >= p.width || b as usize >= p.height {
                    continue;
                }
                let k = b as usize * p.width + a as usize;
                let d = di * di + dj * dj;
                if p.valid[k] && best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, k));
                }
            }
        }
        best.map(|(_, k)| k)
    }

    /// Plans a path from `pose` to a new random goal.
    fn plan_from(&mut self, pose: &Pose2) {
        self.path.clear();
        self.next = 0;
        let p = Arc::clone(&self.plan);
        let (i, j) = p.frame.world_to_cell(pose.x, pose.y);
        let Some(start) = self.nearest_valid(i, j) else {
            return;
        };
        let n = p.width * p.height;
        let mut dist = vec![u32::MAX; n];
        let mut parent = vec![u32::MAX; n];
        let mut reached = Vec::new();
        let mut heap = BinaryHeap::new();
        dist[start] = 0;
        heap.push(Reverse((0u32, start)));
        let w = p.width as i64;
        while let Some(Reverse((d, k))) = heap.pop() {
            if d > dist[k] {
                continue;
            }
            reached.push(k);
            let (ci, cj) = ((k % p.width) as i64, (k / p.width) as i64);
            for (di, dj, step) in [
                (1, 0, 10),
                (-1, 0, 10),
                (0, 1, 10),
                (0, -1, 10),
                (1, 1, 14),
                (1, -1, 14),
                (-1, 1, 14),
                (-1, -1, 14),
            ] {
                let (a, b) = (ci + di, cj + dj);
                if a < 0 || b < 0 || a >= w || b as usize >= p.height {
                    continue;
                }
                let nk = b as usize * p.width + a as usize;
                if !p.valid[nk] {
                    continue;
                }
                if di != 0
                    && dj != 0
                    && (!p.valid[cj as usize * p.width + a as usize]
                        || !p.valid[b as usize * p.width + ci as usize])
                {
                    continue;
                }
                let nd = d + step + p.penalty[nk];
                if nd < dist[nk] {
                    dist[nk] = nd;
                    parent[nk] = k as u32;
                    heap.push(Reverse((nd, nk)));
                }
            }
        }
        if reached.len() < 2 {
            return;
        }
        let res = p.frame.resolution();
        let center = |k: usize| {
            p.frame.grid_frame_to_world(
                ((k % p.width) as f64 + 0.5) * res,
                ((k / p.width) as f64 + 0.5) * res,
            )
        };
        let mut goal = reached[reached.len() - 1];
        for _ in 0..100 {
            let k = reached[self.rng.random_range(1..reached.len())];
            let (gx, gy) = center(k);
            goal = k;
            if math::hypot(gx - pose.x, gy - pose.y) >= self.config.min_goal_distance {
                break;
            }
        }
        let mut cells = vec![goal];
        let mut k = goal;
        while k != start && parent[k] != u32::MAX {
            k = parent[k] as usize;
            cells.push(k);
        }
        cells.reverse();
        // Every third cell is plenty for pure pursuit; keep the goal.
        let mut path: Vec<(f64, f64)> = cells.iter().step_by(3).map(|&k| center(k)).collect();
        if cells.len() % 3 != 1 {
            path.push(center(goal));
        }
        let length: f64 = path
            .windows(2)
            .map(|s| math::hypot(s[1].0 - s[0].0, s[1].1 - s[0].1))
            .sum();
        // Ticks of 0.1 s allowed before giving up on this goal: three times the
        // straight driving time, plus turning.
        self.budget = 100 + (30.0 * length / self.config.v_max.max(0.05)) as u32;
        self.path = path;
    }

    /// The command `(v, ω)` for the robot at `pose`.
    pub fn command(&mut self, pose: &Pose2) -> (f64, f64) {
        if self.budget == 0 {
            self.path.clear();
        }
        self.budget = self.budget.saturating_sub(1);
        if self.path.is_empty() || self.next >= self.path.len() {
            self.plan_from(pose);
            if self.path.is_empty() {
                return (0.0, 0.0);
            }
        }
        let dist = |q: (f64, f64)| math::hypot(q.0 - pose.x, q.1 - pose.y);
        while self.next + 1 < self.path.len() && dist(self.path[self.next]) < self.config.lookahead
        {
            self.next += 1;
        }
        let target = self.path[self.next];
        if self.next + 1 == self.path.len() && dist(target) < 0.15 {
            self.path.clear();
            return (0.0, 0.0);
        }
        let e = wrap_angle(math::atan2(target.1 - pose.y, target.0 - pose.x) - pose.theta);
        let w_max = self.config.w_max.max(0.1);
        if e.abs() > 0.7 {
            return (0.0, w_max.copysign(e));
        }
        let v = self.config.v_max * math::cos(e).max(0.0).powi(2);
        let w = (2.5 * e).clamp(-w_max, w_max);
        (v, w)
    }
}
