//! A growable occupancy probability grid built from lidar scans: the map the
//! lidar lessons make (occupancy-grid mapping, grid FastSLAM, submaps).
//!
//! Cell `(i, j)` covers the square `[i r, (i+1) r) x [j r, (j+1) r)` of the
//! world (`r` the resolution); `i` and `j` may be negative, and the grid grows
//! in whole tiles of [`TILE`] x [`TILE`] cells wherever a scan reaches, so its
//! extent need not be known in advance.
//!
//! Each cell holds its log odds `l = ln(p / (1 − p))`, or nothing while it has
//! never been observed. Both textbook update rules are one addition in log-odds
//! space followed by a clamp; [`UpdateRule`] says which numbers are added and
//! where the clamp sits:
//!
//! - **Log odds with clamping** (Probabilistic Robotics Table 9.1/9.2, the
//!   slides' form): `l ← clamp(l + l_occ)` for a hit, `l ← clamp(l + l_free)` for
//!   a miss (the prior `l₀ = 0`, p = 0.5), clamped to `[l_min, l_max]`.
//! - **Cartographer's probability grid** (thesis `000` Eq. 5.3-5.4):
//!   `M_new = clamp(odds⁻¹(odds(M_old) · odds(p_hit)))`, clamped to
//!   `[p_min, p_max]`. Multiplying odds is adding log odds, so this is the
//!   same step with `l_occ = ln odds(p_hit)`, `l_free = ln odds(p_miss)` and
//!   the clamp at `ln odds(p_min)` and `ln odds(p_max)`; a never-seen cell
//!   (odds 1) becomes exactly `p_hit` or `p_miss`, as in Cartographer.
//!
//! One scan updates each cell at most once ([`ProbabilityGrid::insert_scan`]):
//! the *hit* set is the cells holding a beam's end point; the *miss* set is the
//! cells the beams cross on their way there, minus the hit set. A beam that
//! returned nothing (max range) marks free space up to a configurable distance
//! and hits nothing. Cells are stamped during a scan as Cartographer stamps
//! them (its `kUpdateMarker`): a large offset on the stored value, replaced by
//! the updated value when the scan is done.
//!
//! Tiles are shared copy-on-write (`Arc`): a clone of the grid shares every
//! tile until one of them writes to it, which copies that tile alone. Grid
//! FastSLAM's particles and Cartographer's submaps rely on that.
//!
//! Beside its log odds each cell keeps its entry in the scan matchers' table
//! of probabilities ([`table_entry`]): a matcher reads hundreds of thousands
//! of cells per scan and never writes one, so the conversion from log odds to
//! a table entry is made once when a scan writes the cell instead of at every
//! read (Cartographer's grids likewise keep a 16-bit value per cell and a
//! table that turns it into a probability). It costs 2 bytes a cell.

use super::floor_to_i64;
use crate::geometry::Pose2;
use crate::laser::Scan;
use crate::math;
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// The next tile revision, shared by every grid in the process: a revision
/// names one content of one tile, so a view that shows one grid of several
/// (grid FastSLAM's particles, a mean map) can tell two grids' tiles apart
/// even when both took the same number of scans.
static NEXT_REVISION: AtomicU64 = AtomicU64::new(1);

/// A revision no grid has used.
fn new_revision() -> u64 {
    NEXT_REVISION.fetch_add(1, Ordering::Relaxed)
}

/// Cells per tile side.
pub const TILE: usize = 32;
const TILE_CELLS: usize = TILE * TILE;
/// log2 of [`TILE`].
const TILE_SHIFT: u32 = 5;
/// The offset that stamps a cell as updated during one scan; log odds stay
/// far below it (the clamps are checked to be within ±50).
const UPDATE_MARK: f32 = 1.0e4;
/// The largest clamp magnitude accepted, in log odds (p within 1e-22 of 0 or 1).
const MAX_LOG_ODDS: f64 = 50.0;
/// The largest grid, in tiles (a tile is 6 KiB): 6 GiB of cells is refused.
const MAX_TILES: usize = 1 << 20;

/// Entries of the matchers' probability table for observed cells: log odds in
/// `[−TABLE_LOG_ODDS, TABLE_LOG_ODDS]` at equal steps (`scan::scan_to_map`'s
/// `ProbabilityLookup` holds the probabilities).
pub const TABLE_ENTRIES: usize = 4096;
/// The table entry of a cell never observed (one past the observed ones).
pub const UNKNOWN_ENTRY: u16 = TABLE_ENTRIES as u16;
/// The log odds the table spans on either side of 0.
pub const TABLE_LOG_ODDS: f64 = 16.0;

/// The table entry of log odds `l` (NaN: never observed): the nearest of
/// [`TABLE_ENTRIES`] equal steps over `[−16, 16]`, clamped to the ends.
#[inline]
pub fn table_entry(l: f32) -> u16 {
    if l.is_nan() {
        return UNKNOWN_ENTRY;
    }
    let last = (TABLE_ENTRIES - 1) as f64;
    let t = (f64::from(l) + TABLE_LOG_ODDS) / (2.0 * TABLE_LOG_ODDS) * last;
    (t + 0.5).clamp(0.0, last) as u16
}

/// The log odds that table entry `k` stands for (`k` below [`TABLE_ENTRIES`]).
pub fn table_log_odds(k: usize) -> f64 {
    -TABLE_LOG_ODDS + 2.0 * TABLE_LOG_ODDS * k as f64 / (TABLE_ENTRIES - 1) as f64
}

/// `ln(p / (1 − p))`.
pub fn log_odds(p: f64) -> f64 {
    math::ln(p / (1.0 - p))
}

/// The probability whose log odds is `l`: `1 / (1 + e^{−l})`.
pub fn probability(l: f64) -> f64 {
    1.0 / (1.0 + math::exp(-l))
}

/// How a scan changes the cells it touches.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "rule", rename_all = "kebab-case")]
pub enum UpdateRule {
    /// Probabilistic Robotics Table 9.2: add `l_occ` on a hit and `l_free` on a
    /// miss, clamp to `[l_min, l_max]` (log odds).
    LogOdds {
        /// Added on a hit (positive).
        l_occ: f64,
        /// Added on a miss (negative).
        l_free: f64,
        /// Lower clamp.
        l_min: f64,
        /// Upper clamp.
        l_max: f64,
    },
    /// Thesis `000` Eq. 5.3-5.4 (Cartographer): multiply the odds by
    /// `odds(p_hit)` or `odds(p_miss)`, clamp the probability to
    /// `[p_min, p_max]`.
    Odds {
        /// Probability of a hit cell (above 0.5).
        p_hit: f64,
        /// Probability of a miss cell (below 0.5).
        p_miss: f64,
        /// Lower clamp.
        p_min: f64,
        /// Upper clamp.
        p_max: f64,
    },
}

impl Default for UpdateRule {
    fn default() -> Self {
        Self::LOG_ODDS
    }
}

impl UpdateRule {
    /// The slides' numbers: `l_occ = 0.85`, `l_free = −0.4` (p = 0.7 and 0.4),
    /// clamped to `[−2, 3.5]` (p in [0.12, 0.97]).
    pub const LOG_ODDS: Self = Self::LogOdds {
        l_occ: 0.85,
        l_free: -0.4,
        l_min: -2.0,
        l_max: 3.5,
    };
    /// Cartographer's 2-D defaults: `hit_probability 0.55`,
    /// `miss_probability 0.49`, clamped to `[0.1, 0.9]`.
    pub const CARTOGRAPHER: Self = Self::Odds {
        p_hit: 0.55,
        p_miss: 0.49,
        p_min: 0.1,
        p_max: 0.9,
    };

    /// The rule's name as the URL and the CLI spell it.
    pub fn name(&self) -> &'static str {
        match self {
            Self::LogOdds { .. } => "log-odds",
            Self::Odds { .. } => "odds",
        }
    }

    /// The rule as four log-odds numbers `(hit, miss, min, max)`, or a message
    /// saying what is wrong with it (a hit that does not raise the odds, a
    /// miss that does not lower them, clamps in the wrong order or not
    /// finite, probabilities outside (0, 1)).
    pub fn log_odds_steps(&self) -> Result<LogOddsSteps, String> {
        let steps = match *self {
            Self::LogOdds {
                l_occ,
                l_free,
                l_min,
                l_max,
            } => LogOddsSteps {
                hit: l_occ,
                miss: l_free,
                min: l_min,
                max: l_max,
            },
            Self::Odds {
                p_hit,
                p_miss,
                p_min,
                p_max,
            } => {
                for (name, p) in [
                    ("p_hit", p_hit),
                    ("p_miss", p_miss),
                    ("p_min", p_min),
                    ("p_max", p_max),
                ] {
                    if !(p > 0.0 && p < 1.0) {
                        return Err(format!("{name} = {p} is not a probability in (0, 1)"));
                    }
                }
                LogOddsSteps {
                    hit: log_odds(p_hit),
                    miss: log_odds(p_miss),
                    min: log_odds(p_min),
                    max: log_odds(p_max),
                }
            }
        };
        if !(steps.hit > 0.0) {
            return Err(format!(
                "a hit must raise the odds of occupancy (its log odds {:.3} is not positive)",
                steps.hit
            ));
        }
        if !(steps.miss < 0.0) {
            return Err(format!(
                "a miss must lower the odds of occupancy (its log odds {:.3} is not negative)",
                steps.miss
            ));
        }
        if !(steps.min < 0.0
            && steps.max > 0.0
            && steps.min.abs() <= MAX_LOG_ODDS
            && steps.max <= MAX_LOG_ODDS)
        {
            return Err(format!(
                "the clamp [{:.3}, {:.3}] (log odds) must contain 0 and lie within ±{MAX_LOG_ODDS}",
                steps.min, steps.max
            ));
        }
        Ok(steps)
    }
}

/// An update rule as log-odds steps (see [`UpdateRule::log_odds_steps`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogOddsSteps {
    /// Added on a hit.
    pub hit: f64,
    /// Added on a miss.
    pub miss: f64,
    /// Lower clamp.
    pub min: f64,
    /// Upper clamp.
    pub max: f64,
}

impl LogOddsSteps {
    /// One update of a cell holding `old` (`None`: never seen, log odds 0).
    pub fn apply(&self, old: Option<f64>, hit: bool) -> f64 {
        let step = if hit { self.hit } else { self.miss };
        (old.unwrap_or(0.0) + step).clamp(self.min, self.max)
    }
}

/// How scans are inserted.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct InsertParams {
    /// The update rule.
    pub rule: UpdateRule,
    /// A beam that returned nothing (max range) marks free space up to this
    /// distance from the sensor, metres (0: such beams change nothing).
    /// Cartographer's `missing_data_ray_length`.
    pub max_range_free: f64,
}

impl Default for InsertParams {
    fn default() -> Self {
        Self {
            rule: UpdateRule::default(),
            max_range_free: 5.0,
        }
    }
}

/// What one scan did to the grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct InsertReport {
    /// Cells updated as hits.
    pub hits: usize,
    /// Cells updated as misses.
    pub misses: usize,
    /// Cells never seen before this scan.
    pub new_cells: usize,
}

/// A segment of a beam in cell units, `(from, to, include_last_cell)`.
type FreeSegment = ((f64, f64), (f64, f64), bool);

/// One cell of a beam's update ([`ProbabilityGrid::explain_beam`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BeamCell {
    /// The cell `(i, j)`.
    pub cell: (i64, i64),
    /// Whether this is the beam's end-point cell (the last in the list).
    pub end: bool,
    /// Whether the scan updates it as a hit (some beam ends in it) rather
    /// than as a miss.
    pub hit: bool,
    /// Its log odds before the scan (`None`: never observed, p = 0.5).
    pub before: Option<f64>,
    /// Its log odds after the scan.
    pub after: f64,
    /// Whether this beam is the one that updates it (once per scan: an
    /// earlier beam, or a hit of another beam, may have taken it).
    pub updated_here: bool,
}

/// What one beam of a scan does to the grid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BeamUpdate {
    /// The beam's index in the scan.
    pub beam: usize,
    /// The sensor's position, metres.
    pub origin: (f64, f64),
    /// The cells it crosses in order from the sensor, then its end-point cell
    /// (absent for a beam with no usable end point).
    pub cells: Vec<BeamCell>,
}

/// The index of cell `(i, j)` within its tile (row-major from the bottom).
#[inline]
fn local_index(i: i64, j: i64) -> usize {
    ((j & (TILE as i64 - 1)) as usize) * TILE + (i & (TILE as i64 - 1)) as usize
}

/// One tile of cells: log odds, NaN where never observed, and each cell's
/// [`table_entry`].
#[derive(Clone, Debug, PartialEq)]
struct Tile {
    cells: [f32; TILE_CELLS],
    entries: [u16; TILE_CELLS],
}

impl Tile {
    fn unknown() -> Self {
        Self {
            cells: [f32::NAN; TILE_CELLS],
            entries: [UNKNOWN_ENTRY; TILE_CELLS],
        }
    }

    /// Sets cell `local` to log odds `l` (and its table entry with it).
    #[inline]
    fn set(&mut self, local: usize, l: f32) {
        self.cells[local] = l;
        self.entries[local] = table_entry(l);
    }
}

/// The growable grid. See the module documentation.
#[derive(Clone, Debug)]
pub struct ProbabilityGrid {
    resolution: f64,
    /// Tile coordinates of the lower-left tile held.
    tile_origin: (i64, i64),
    /// Tiles held per row and column.
    tiles_wide: usize,
    tiles_high: usize,
    /// `tiles_wide x tiles_high` tiles, row-major from the bottom; `None`
    /// where no scan has reached.
    tiles: Vec<Option<Arc<Tile>>>,
    /// A revision per tile slot, new whenever the tile changes (for a view
    /// that redraws only what changed); unique across grids.
    revisions: Vec<u64>,
    /// The cells stamped during the scan being inserted, with the value each
    /// gets when the stamp comes off.
    stamped: Vec<(usize, usize, f32)>,
    /// The cells of one beam during an insertion (kept for its capacity).
    scratch: Vec<(i64, i64)>,
}

impl ProbabilityGrid {
    /// An empty grid of `resolution` metres per cell (a non-positive or
    /// non-finite resolution becomes 0.05 m).
    pub fn new(resolution: f64) -> Self {
        let resolution = if resolution.is_finite() && resolution > 1e-4 {
            resolution
        } else {
            0.05
        };
        Self {
            resolution,
            tile_origin: (0, 0),
            tiles_wide: 0,
            tiles_high: 0,
            tiles: Vec::new(),
            revisions: Vec::new(),
            stamped: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// Metres per cell.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// The cell holding the world point `(x, y)`.
    pub fn cell_of(&self, x: f64, y: f64) -> (i64, i64) {
        (
            floor_to_i64(x / self.resolution),
            floor_to_i64(y / self.resolution),
        )
    }

    /// The centre of cell `(i, j)` in the world, metres.
    pub fn cell_center(&self, i: i64, j: i64) -> (f64, f64) {
        (
            (i as f64 + 0.5) * self.resolution,
            (j as f64 + 0.5) * self.resolution,
        )
    }

    /// The slot of the tile holding cell `(i, j)` and the cell's index in it,
    /// if that tile lies within the held rectangle.
    #[inline]
    fn locate(&self, i: i64, j: i64) -> Option<(usize, usize)> {
        let (ti, tj) = (i >> TILE_SHIFT, j >> TILE_SHIFT);
        let (di, dj) = (ti - self.tile_origin.0, tj - self.tile_origin.1);
        if di < 0 || dj < 0 || di >= self.tiles_wide as i64 || dj >= self.tiles_high as i64 {
            return None;
        }
        let slot = dj as usize * self.tiles_wide + di as usize;
        Some((slot, local_index(i, j)))
    }

    /// The log odds of cell `(i, j)`, or `None` if it was never observed.
    #[inline]
    pub fn log_odds_at(&self, i: i64, j: i64) -> Option<f64> {
        let (slot, local) = self.locate(i, j)?;
        let v = self.tiles[slot].as_ref()?.cells[local];
        (!v.is_nan()).then_some(v as f64)
    }

    /// The [`table_entry`] of the `len` cells `(i, j)`, `(i + 1, j)`, … in one
    /// row, [`UNKNOWN_ENTRY`] where never observed, when they lie in one tile
    /// column (a matcher reading a small window of cells finds them in one
    /// place); `None` when the run crosses a tile boundary or is longer than a
    /// tile.
    #[inline]
    pub fn entries_in_row(&self, i: i64, j: i64, len: usize) -> Option<&[u16]> {
        static UNKNOWN: [u16; TILE] = [UNKNOWN_ENTRY; TILE];
        if len == 0 || len > TILE || i >> TILE_SHIFT != (i + len as i64 - 1) >> TILE_SHIFT {
            return None;
        }
        let Some((slot, local)) = self.locate(i, j) else {
            return Some(&UNKNOWN[..len]);
        };
        match &self.tiles[slot] {
            Some(tile) => tile.entries.get(local..local + len),
            None => Some(&UNKNOWN[..len]),
        }
    }

    /// The [`table_entry`] of every cell of the tile that holds the whole
    /// `side` x `side` window of cells with its lower-left cell at `(i, j)`,
    /// and the index in it of cell `(i, j)` (row `r` of the window starts
    /// [`TILE`] `* r` entries later); `None` when the window crosses a tile
    /// boundary. A tile never reached reads as all [`UNKNOWN_ENTRY`]. A
    /// matcher reading a small window around each point finds it in one tile
    /// most of the time, with one look-up instead of one per row.
    #[inline]
    pub fn entries_window(
        &self,
        i: i64,
        j: i64,
        side: usize,
    ) -> Option<(&[u16; TILE_CELLS], usize)> {
        static UNKNOWN: [u16; TILE_CELLS] = [UNKNOWN_ENTRY; TILE_CELLS];
        let last = side as i64 - 1;
        if side == 0
            || side > TILE
            || i >> TILE_SHIFT != (i + last) >> TILE_SHIFT
            || j >> TILE_SHIFT != (j + last) >> TILE_SHIFT
        {
            return None;
        }
        let Some((slot, local)) = self.locate(i, j) else {
            return Some((&UNKNOWN, local_index(i, j)));
        };
        Some(match &self.tiles[slot] {
            Some(tile) => (&tile.entries, local),
            None => (&UNKNOWN, local),
        })
    }

    /// The [`table_entry`] of cell `(i, j)` ([`UNKNOWN_ENTRY`] if never
    /// observed).
    #[inline]
    pub fn entry_at(&self, i: i64, j: i64) -> u16 {
        match self.locate(i, j) {
            Some((slot, local)) => self.tiles[slot]
                .as_ref()
                .map_or(UNKNOWN_ENTRY, |tile| tile.entries[local]),
            None => UNKNOWN_ENTRY,
        }
    }

    /// The occupancy probability of cell `(i, j)`, or `None` if never observed.
    #[inline]
    pub fn probability_at(&self, i: i64, j: i64) -> Option<f64> {
        self.log_odds_at(i, j).map(probability)
    }

    /// Grows the held rectangle of tiles to include the tile of cell `(i, j)`.
    /// Returns false (and changes nothing) if the grid would exceed its cap.
    fn ensure_cell(&mut self, i: i64, j: i64) -> bool {
        if self.locate(i, j).is_some() {
            return true;
        }
        let (ti, tj) = (i >> TILE_SHIFT, j >> TILE_SHIFT);
        let (x0, y0, x1, y1) = if self.tiles_wide == 0 {
            (ti, tj, ti + 1, tj + 1)
        } else {
            let (ox, oy) = self.tile_origin;
            // Grow by a margin so that a robot driving on does not re-lay the
            // grid at every new tile.
            let margin = 2;
            (
                if ti < ox { ti - margin } else { ox },
                if tj < oy { tj - margin } else { oy },
                if ti >= ox + self.tiles_wide as i64 {
                    ti + 1 + margin
                } else {
                    ox + self.tiles_wide as i64
                },
                if tj >= oy + self.tiles_high as i64 {
                    tj + 1 + margin
                } else {
                    oy + self.tiles_high as i64
                },
            )
        };
        let (w, h) = ((x1 - x0) as usize, (y1 - y0) as usize);
        if w.saturating_mul(h) > MAX_TILES {
            return false;
        }
        let mut tiles = vec![None; w * h];
        let mut revisions = vec![0; w * h];
        for dj in 0..self.tiles_high {
            for di in 0..self.tiles_wide {
                let old = dj * self.tiles_wide + di;
                let nx = (self.tile_origin.0 + di as i64 - x0) as usize;
                let ny = (self.tile_origin.1 + dj as i64 - y0) as usize;
                tiles[ny * w + nx] = self.tiles[old].take();
                revisions[ny * w + nx] = self.revisions[old];
            }
        }
        // Cells stamped earlier in this scan move with their tiles.
        for stamp in &mut self.stamped {
            let (di, dj) = (stamp.0 % self.tiles_wide, stamp.0 / self.tiles_wide);
            let nx = (self.tile_origin.0 + di as i64 - x0) as usize;
            let ny = (self.tile_origin.1 + dj as i64 - y0) as usize;
            stamp.0 = ny * w + nx;
        }
        self.tiles = tiles;
        self.revisions = revisions;
        self.tile_origin = (x0, y0);
        self.tiles_wide = w;
        self.tiles_high = h;
        true
    }

    /// Updates each of `cells` once in the scan being inserted (a stamped
    /// cell is left alone), in order. Returns how many were updated and how
    /// many of those were new. Consecutive cells in one tile (a ray crosses a
    /// tile in a run of cells) share one look-up of the tile and one
    /// copy-on-write check.
    fn update_cells(
        &mut self,
        cells: &[(i64, i64)],
        steps: &LogOddsSteps,
        hit: bool,
    ) -> (usize, usize) {
        let (mut updated, mut new) = (0, 0);
        let mut rest = cells;
        while let Some(&(i, j)) = rest.first() {
            let tile_of = |&(a, b): &(i64, i64)| (a >> TILE_SHIFT, b >> TILE_SHIFT);
            let run = rest
                .iter()
                .take_while(|c| tile_of(c) == tile_of(&(i, j)))
                .count();
            let (run_cells, next) = rest.split_at(run);
            rest = next;
            if !self.ensure_cell(i, j) {
                continue;
            }
            let Some((slot, _)) = self.locate(i, j) else {
                continue;
            };
            let tile =
                Arc::make_mut(self.tiles[slot].get_or_insert_with(|| Arc::new(Tile::unknown())));
            for &(i, j) in run_cells {
                let local = local_index(i, j);
                let old = tile.cells[local];
                if old > UPDATE_MARK / 2.0 {
                    continue;
                }
                let was_new = old.is_nan();
                let value = steps.apply((!was_new).then_some(old as f64), hit);
                tile.cells[local] = value as f32 + UPDATE_MARK;
                self.stamped.push((slot, local, value as f32));
                updated += 1;
                new += usize::from(was_new);
            }
        }
        (updated, new)
    }

    /// Inserts one scan taken from `world_from_sensor` (Cartographer's
    /// `ProbabilityGridRangeDataInserter2D`): every end point's cell once as a
    /// hit, then every cell the beams cross (and, for max-range beams, the
    /// cells up to `params.max_range_free`) once as a miss, skipping the hit
    /// cells. An invalid rule changes nothing and is reported as an error.
    pub fn insert_scan(
        &mut self,
        world_from_sensor: &Pose2,
        scan: &Scan,
        params: &InsertParams,
    ) -> Result<InsertReport, String> {
        let reports = Self::insert_scan_into_all(&mut [self], world_from_sensor, scan, params)?;
        Ok(reports.first().copied().unwrap_or_default())
    }

    /// [`insert_scan`](Self::insert_scan) into several grids at once, as
    /// Cartographer inserts each scan into both active submaps: the beams'
    /// cells are traced once and each grid is updated with them exactly as its
    /// own `insert_scan` would update it (cells depend only on the resolution).
    /// One report per grid, in order. Grids whose resolution differs from the
    /// first one's get their own `insert_scan`.
    pub fn insert_scan_into_all(
        grids: &mut [&mut ProbabilityGrid],
        world_from_sensor: &Pose2,
        scan: &Scan,
        params: &InsertParams,
    ) -> Result<Vec<InsertReport>, String> {
        let steps = params.rule.log_odds_steps()?;
        if !world_from_sensor.is_finite() {
            return Err("the scan's pose is not finite".to_owned());
        }
        let Some(resolution) = grids.first().map(|g| g.resolution) else {
            return Ok(Vec::new());
        };
        if grids.iter().any(|g| g.resolution != resolution) {
            return grids
                .iter_mut()
                .map(|g| {
                    Self::insert_scan_into_all(&mut [&mut **g], world_from_sensor, scan, params)
                })
                .map(|r| r.map(|v| v.first().copied().unwrap_or_default()))
                .collect();
        }
        let mut reports = vec![InsertReport::default(); grids.len()];
        let n = scan.len();
        let mut cells = std::mem::take(&mut grids[0].scratch);
        // Hits first, so that the misses skip them.
        cells.clear();
        cells.extend((0..n).filter_map(|k| grids[0].hit_cell(world_from_sensor, scan, k)));
        for (grid, report) in grids.iter_mut().zip(&mut reports) {
            let (updated, new) = grid.update_cells(&cells, &steps, true);
            report.hits += updated;
            report.new_cells += new;
        }
        for k in 0..n {
            let Some((from, to, include_end)) =
                grids[0].free_segment(world_from_sensor, scan, k, params)
            else {
                continue;
            };
            cells.clear();
            segment_cells(from, to, include_end, |i, j| cells.push((i, j)));
            for (grid, report) in grids.iter_mut().zip(&mut reports) {
                let (updated, new) = grid.update_cells(&cells, &steps, false);
                report.misses += updated;
                report.new_cells += new;
            }
        }
        grids[0].scratch = cells;
        for grid in grids.iter_mut() {
            grid.finish_scan();
        }
        Ok(reports)
    }

    /// The cell of beam `k`'s end point, if the beam has one.
    fn hit_cell(&self, world_from_sensor: &Pose2, scan: &Scan, k: usize) -> Option<(i64, i64)> {
        if !scan.is_end_point(k) {
            return None;
        }
        let (x, y) = beam_end(world_from_sensor, scan.angles[k], scan.ranges[k]);
        Some(self.cell_of(x, y))
    }

    /// The segment beam `k` marks as free, in cell units, and whether its
    /// last cell is included: up to (not into) its end point's cell, or, for
    /// a max-range beam, up to `params.max_range_free` (last cell included);
    /// `None` for a beam that marks nothing.
    fn free_segment(
        &self,
        world_from_sensor: &Pose2,
        scan: &Scan,
        k: usize,
        params: &InsertParams,
    ) -> Option<FreeSegment> {
        let free_length = if params.max_range_free.is_finite() {
            params.max_range_free.clamp(0.0, scan.range_max.max(0.0))
        } else {
            0.0
        };
        let (length, include_end) = if scan.is_end_point(k) {
            (scan.ranges[k], false)
        } else if scan.is_max_range(k) && free_length > 0.0 {
            (free_length, true)
        } else {
            return None;
        };
        let r = self.resolution;
        let (x, y) = beam_end(world_from_sensor, scan.angles[k], length);
        let origin = (world_from_sensor.x / r, world_from_sensor.y / r);
        Some((origin, (x / r, y / r), include_end))
    }

    /// The cells beam `k` marks as free, in order from the sensor.
    fn crossed_cells(
        &self,
        world_from_sensor: &Pose2,
        scan: &Scan,
        k: usize,
        params: &InsertParams,
    ) -> Vec<(i64, i64)> {
        let mut cells = Vec::new();
        if let Some((from, to, include_end)) = self.free_segment(world_from_sensor, scan, k, params)
        {
            segment_cells(from, to, include_end, |i, j| cells.push((i, j)));
        }
        cells
    }

    /// What inserting `scan` at `world_from_sensor` does to the cells of beam
    /// `beam`, without changing the grid: every cell it crosses, in order from
    /// the sensor, then its end point's cell, each with its log odds before and
    /// after the scan and whether this beam is the one that updates it (a cell
    /// changes once per scan: a crossed cell that holds another beam's end point
    /// is a hit, not a miss, and a cell an earlier beam crossed was updated by
    /// that beam). The lesson steps through a scan's beams with it.
    pub fn explain_beam(
        &self,
        world_from_sensor: &Pose2,
        scan: &Scan,
        beam: usize,
        params: &InsertParams,
    ) -> Result<BeamUpdate, String> {
        let steps = params.rule.log_odds_steps()?;
        if !world_from_sensor.is_finite() {
            return Err("the scan's pose is not finite".to_owned());
        }
        if beam >= scan.len() {
            return Err(format!("beam {beam} of a scan of {} beams", scan.len()));
        }
        let hits: std::collections::HashSet<(i64, i64)> = (0..scan.len())
            .filter_map(|k| self.hit_cell(world_from_sensor, scan, k))
            .collect();
        let earlier: std::collections::HashSet<(i64, i64)> = (0..beam)
            .flat_map(|k| self.crossed_cells(world_from_sensor, scan, k, params))
            .collect();
        let earlier_hits: std::collections::HashSet<(i64, i64)> = (0..beam)
            .filter_map(|k| self.hit_cell(world_from_sensor, scan, k))
            .collect();
        let crossed = self.crossed_cells(world_from_sensor, scan, beam, params);
        let hit = self.hit_cell(world_from_sensor, scan, beam);
        let mut seen_here = std::collections::HashSet::new();
        let mut cells = Vec::with_capacity(crossed.len() + 1);
        for (cell, end) in crossed
            .into_iter()
            .map(|c| (c, false))
            .chain(hit.map(|c| (c, true)))
        {
            let is_hit = hits.contains(&cell);
            let before = self.log_odds_at(cell.0, cell.1);
            let first_time_here = seen_here.insert(cell);
            // Hits are inserted before every miss: a hit cell is this beam's
            // to update only if it is this beam's end point and no earlier
            // beam ended in it.
            let updated_here = first_time_here
                && if is_hit {
                    end && !earlier_hits.contains(&cell)
                } else {
                    !earlier.contains(&cell)
                };
            cells.push(BeamCell {
                cell,
                end,
                hit: is_hit,
                before,
                after: steps.apply(before, is_hit),
                updated_here,
            });
        }
        Ok(BeamUpdate {
            beam,
            origin: (world_from_sensor.x, world_from_sensor.y),
            cells,
        })
    }

    /// Removes the stamps of the scan just inserted and raises the revision of
    /// every tile it changed.
    fn finish_scan(&mut self) {
        let revision = new_revision();
        // Stamps come ray by ray, so runs of them share a tile: one
        // copy-on-write check per run instead of one per cell.
        let mut k = 0;
        while k < self.stamped.len() {
            let slot = self.stamped[k].0;
            let run = self.stamped[k..]
                .iter()
                .take_while(|(s, _, _)| *s == slot)
                .count();
            if let Some(tile) = self.tiles[slot].as_mut() {
                let tile = Arc::make_mut(tile);
                for &(_, local, value) in &self.stamped[k..k + run] {
                    tile.set(local, value);
                }
            }
            self.revisions[slot] = revision;
            k += run;
        }
        self.stamped.clear();
    }

    /// The cells observed at least once.
    pub fn known_cells(&self) -> usize {
        self.tiles
            .iter()
            .flatten()
            .map(|t| t.cells.iter().filter(|v| !v.is_nan()).count())
            .sum()
    }

    /// The bounding box of the observed cells, `(i_min, j_min, i_max, j_max)`
    /// inclusive, or `None` for an empty grid.
    pub fn known_bounds(&self) -> Option<(i64, i64, i64, i64)> {
        let mut b: Option<(i64, i64, i64, i64)> = None;
        for (i0, j0, tile) in self.tiles() {
            for (local, v) in tile.iter().enumerate() {
                if v.is_nan() {
                    continue;
                }
                let (i, j) = (i0 + (local % TILE) as i64, j0 + (local / TILE) as i64);
                b = Some(match b {
                    None => (i, j, i, j),
                    Some((a, c, d, e)) => (a.min(i), c.min(j), d.max(i), e.max(j)),
                });
            }
        }
        b
    }

    /// Every tile held: its lower-left cell and its cells' log odds (row-major
    /// from the bottom, NaN where unknown).
    pub fn tiles(&self) -> impl Iterator<Item = (i64, i64, &[f32; TILE_CELLS])> {
        self.tiles.iter().enumerate().filter_map(|(slot, t)| {
            let t = t.as_ref()?;
            let (ti, tj) = self.slot_tile(slot);
            Some((ti * TILE as i64, tj * TILE as i64, &t.cells))
        })
    }

    /// Tile coordinates of a slot.
    fn slot_tile(&self, slot: usize) -> (i64, i64) {
        (
            self.tile_origin.0 + (slot % self.tiles_wide) as i64,
            self.tile_origin.1 + (slot / self.tiles_wide) as i64,
        )
    }

    /// Every tile held with its revision: `(tile_i, tile_j, revision)`, tile
    /// coordinates in tiles. A view redraws a tile when its revision changed.
    pub fn tile_revisions(&self) -> impl Iterator<Item = (i64, i64, u64)> + '_ {
        self.tiles.iter().enumerate().filter_map(|(slot, t)| {
            t.as_ref()?;
            let (ti, tj) = self.slot_tile(slot);
            Some((ti, tj, self.revisions[slot]))
        })
    }

    /// The cells of tile `(ti, tj)` (tile coordinates), if held.
    pub fn tile_cells(&self, ti: i64, tj: i64) -> Option<&[f32; TILE_CELLS]> {
        let (slot, _) = self.locate(ti * TILE as i64, tj * TILE as i64)?;
        self.tiles[slot].as_ref().map(|t| &t.cells)
    }

    /// Bytes a tile of cells occupies: its log odds and table entries.
    pub const TILE_BYTES: usize = std::mem::size_of::<Tile>();

    /// Bytes of cell storage in tiles this grid holds (shared tiles counted in
    /// full).
    pub fn memory_bytes(&self) -> usize {
        self.tiles.iter().flatten().count() * std::mem::size_of::<Tile>()
            + self.tiles.len() * (std::mem::size_of::<Option<Arc<Tile>>>() + 8)
    }

    /// Bytes of cell storage held by a set of grids that may share tiles
    /// (grid FastSLAM's particles): each tile allocation counted once, plus
    /// every grid's own table of tile slots. This is what the set really
    /// occupies, where summing [`memory_bytes`](Self::memory_bytes) would
    /// count a shared tile once per grid.
    pub fn distinct_memory_bytes<'a>(
        grids: impl IntoIterator<Item = &'a ProbabilityGrid>,
    ) -> usize {
        let mut seen: std::collections::HashSet<*const Tile> = std::collections::HashSet::new();
        let mut slots = 0;
        for grid in grids {
            slots += grid.tiles.len() * (std::mem::size_of::<Option<Arc<Tile>>>() + 8);
            seen.extend(grid.tiles.iter().flatten().map(Arc::as_ptr));
        }
        seen.len() * std::mem::size_of::<Tile>() + slots
    }

    /// Tiles this grid shares with `other` (the same allocation), for
    /// copy-on-write accounting.
    pub fn shared_tiles_with(&self, other: &ProbabilityGrid) -> usize {
        let theirs: std::collections::HashSet<*const Tile> =
            other.tiles.iter().flatten().map(Arc::as_ptr).collect();
        self.tiles
            .iter()
            .flatten()
            .filter(|t| theirs.contains(&Arc::as_ptr(t)))
            .count()
    }

    /// The weighted mean of several grids of one resolution (grid FastSLAM's
    /// particles weighted by their weights): each cell's occupancy
    /// probability averaged over the grids that observed it, their weights
    /// renormalized over those grids; unknown where none did. Grids of
    /// another resolution than the first, and weights that are not finite and
    /// positive, are left out. `None` when nothing is left.
    pub fn weighted_mean<'a>(
        grids: impl IntoIterator<Item = (&'a ProbabilityGrid, f64)>,
    ) -> Option<ProbabilityGrid> {
        use std::collections::BTreeMap;
        // Per tile: Σ w·p and Σ w over the grids that know each cell.
        type Sums = (Box<[f64; TILE_CELLS]>, Box<[f64; TILE_CELLS]>);
        let mut sums: BTreeMap<(i64, i64), Sums> = BTreeMap::new();
        let mut resolution = None;
        for (grid, w) in grids {
            if !(w.is_finite() && w > 0.0) {
                continue;
            }
            let r = *resolution.get_or_insert(grid.resolution);
            if grid.resolution != r {
                continue;
            }
            for (slot, tile) in grid.tiles.iter().enumerate() {
                let Some(tile) = tile else { continue };
                let (wp, ws) = sums
                    .entry(grid.slot_tile(slot))
                    .or_insert_with(|| (Box::new([0.0; TILE_CELLS]), Box::new([0.0; TILE_CELLS])));
                for (k, &l) in tile.cells.iter().enumerate() {
                    if !l.is_nan() {
                        wp[k] += w * probability(f64::from(l));
                        ws[k] += w;
                    }
                }
            }
        }
        let resolution = resolution?;
        let mut mean = ProbabilityGrid::new(resolution);
        let revision = new_revision();
        for ((ti, tj), (wp, ws)) in sums {
            let (i, j) = (ti * TILE as i64, tj * TILE as i64);
            if !mean.ensure_cell(i, j) {
                continue;
            }
            let Some((slot, _)) = mean.locate(i, j) else {
                continue;
            };
            let mut tile = Tile::unknown();
            for k in 0..TILE_CELLS {
                if ws[k] > 0.0 {
                    let p = (wp[k] / ws[k]).clamp(1e-9, 1.0 - 1e-9);
                    tile.set(k, log_odds(p) as f32);
                }
            }
            mean.tiles[slot] = Some(Arc::new(tile));
            mean.revisions[slot] = revision;
        }
        Some(mean)
    }

    /// The probability grid as a three-state occupancy grid over its observed
    /// bounds: occupied above `occupied_above`, free below `free_below`,
    /// unknown between and where never observed (ROS map_server's
    /// `occupied_thresh` and `free_thresh`). `None` for an empty grid.
    pub fn to_occupancy_grid(
        &self,
        occupied_above: f64,
        free_below: f64,
    ) -> Option<super::OccupancyGrid> {
        let (i0, j0, i1, j1) = self.known_bounds()?;
        let (w, h) = ((i1 - i0 + 1) as usize, (j1 - j0 + 1) as usize);
        let mut cells = vec![super::Cell::Unknown; w * h];
        for j in 0..h {
            for i in 0..w {
                if let Some(p) = self.probability_at(i0 + i as i64, j0 + j as i64) {
                    cells[j * w + i] = if p > occupied_above {
                        super::Cell::Occupied
                    } else if p < free_below {
                        super::Cell::Free
                    } else {
                        super::Cell::Unknown
                    };
                }
            }
        }
        let origin = Pose2::new(
            i0 as f64 * self.resolution,
            j0 as f64 * self.resolution,
            0.0,
        );
        super::OccupancyGrid::new(w, h, self.resolution, origin, cells).ok()
    }
}

/// The world point `length` metres along the beam at `angle` (sensor frame).
#[inline]
fn beam_end(world_from_sensor: &Pose2, angle: f64, length: f64) -> (f64, f64) {
    let (s, c) = math::sin_cos(world_from_sensor.theta + angle);
    (
        world_from_sensor.x + length * c,
        world_from_sensor.y + length * s,
    )
}

/// Visits the cells the segment from `p0` to `p1` (in cell units) passes
/// through, in order, from the cell of `p0` to the cell of `p1` (that last one
/// only if `include_end`): an exact 4-connected traversal (Amanatides and Woo
/// 1987). It visits `|Δi| + |Δj| + 1` cells and always ends in the cell of `p1`,
/// whatever the rounding near corners.
pub fn segment_cells(
    p0: (f64, f64),
    p1: (f64, f64),
    include_end: bool,
    mut visit: impl FnMut(i64, i64),
) {
    let (mut i, mut j) = (floor_to_i64(p0.0), floor_to_i64(p0.1));
    let (ie, je) = (floor_to_i64(p1.0), floor_to_i64(p1.1));
    let (dx, dy) = (p1.0 - p0.0, p1.1 - p0.1);
    let step_i: i64 = if dx > 0.0 { 1 } else { -1 };
    let step_j: i64 = if dy > 0.0 { 1 } else { -1 };
    let delta_i = if dx != 0.0 {
        1.0 / dx.abs()
    } else {
        f64::INFINITY
    };
    let delta_j = if dy != 0.0 {
        1.0 / dy.abs()
    } else {
        f64::INFINITY
    };
    let mut next_i = if dx > 0.0 {
        (i as f64 + 1.0 - p0.0) * delta_i
    } else if dx < 0.0 {
        (p0.0 - i as f64) * delta_i
    } else {
        f64::INFINITY
    };
    let mut next_j = if dy > 0.0 {
        (j as f64 + 1.0 - p0.1) * delta_j
    } else if dy < 0.0 {
        (p0.1 - j as f64) * delta_j
    } else {
        f64::INFINITY
    };
    let steps = (ie - i).unsigned_abs() + (je - j).unsigned_abs();
    for _ in 0..steps {
        visit(i, j);
        // Step along the axis whose boundary comes first, unless that axis is
        // already done (rounding near a corner).
        if (next_i < next_j && i != ie) || j == je {
            i += step_i;
            next_i += delta_i;
        } else {
            j += step_j;
            next_j += delta_j;
        }
    }
    if include_end {
        visit(i, j);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_beam(range: f64, angle: f64, range_max: f64) -> Scan {
        Scan {
            angles: vec![angle],
            ranges: vec![range],
            range_min: 0.0,
            range_max,
        }
    }

    /// The log-odds rule, beams that return nothing marking nothing.
    fn log_odds_without_free_run() -> InsertParams {
        InsertParams {
            rule: UpdateRule::LOG_ODDS,
            max_range_free: 0.0,
        }
    }

    #[test]
    fn the_weighted_mean_averages_probabilities_over_the_grids_that_know_a_cell() {
        let params = log_odds_without_free_run();
        // Grid a: one beam of 0.5 m along +x (cell 5 hit, 0..=4 free).
        // Grid b: one beam of 0.3 m (cell 3 hit, 0..=2 free), and a beam along
        // +y that only b knows.
        let pose = Pose2::new(0.05, 0.05, 0.0);
        let mut a = ProbabilityGrid::new(0.1);
        a.insert_scan(&pose, &one_beam(0.5, 0.0, 10.0), &params)
            .unwrap();
        let mut b = ProbabilityGrid::new(0.1);
        b.insert_scan(&pose, &one_beam(0.3, 0.0, 10.0), &params)
            .unwrap();
        b.insert_scan(
            &pose,
            &one_beam(0.4, std::f64::consts::FRAC_PI_2, 10.0),
            &params,
        )
        .unwrap();
        let (wa, wb) = (0.75, 0.25);
        let mean = ProbabilityGrid::weighted_mean([(&a, wa), (&b, wb)]).unwrap();
        let (p_hit, p_free) = (probability(0.85), probability(-0.4));
        let p = |i, j| mean.probability_at(i, j).unwrap();
        // Cell 3: free in a, hit in b; cell 5: hit in a, unknown in b.
        assert!((p(3, 0) - (wa * p_free + wb * p_hit)).abs() < 1e-6);
        assert!((p(5, 0) - p_hit).abs() < 1e-6);
        assert!((p(1, 0) - p_free).abs() < 1e-6);
        assert!((p(0, 4) - p_hit).abs() < 1e-6, "only b knows (0, 4)");
        assert_eq!(mean.log_odds_at(6, 0), None);
        assert_eq!(mean.known_cells(), 6 + 4);
        // Weights that are not positive leave their grid out; none left: None.
        let only_a = ProbabilityGrid::weighted_mean([(&a, 1.0), (&b, 0.0)]).unwrap();
        assert!((only_a.probability_at(3, 0).unwrap() - p_free).abs() < 1e-6);
        assert!(ProbabilityGrid::weighted_mean([(&a, f64::NAN)]).is_none());
    }

    /// Inserting into several grids at once leaves each exactly as its own
    /// `insert_scan` would (every cell's log-odds to the bit, the reports
    /// equal): two grids with different histories at one resolution, and a
    /// third at another resolution (its own insertion).
    #[test]
    fn inserting_into_several_grids_at_once_equals_one_by_one() {
        let params = InsertParams {
            rule: UpdateRule::CARTOGRAPHER,
            max_range_free: 3.0,
        };
        // The ICP tests' room, seen to 2.5 m (so many beams are max-range
        // readings), every 37th range NaN.
        let scan_at = |pose: Pose2| {
            let mut scan = crate::laser::test_room::ray_cast(
                &crate::laser::test_room::room(),
                pose,
                360,
                2.5,
                None,
            );
            for k in (0..scan.len()).step_by(37) {
                scan.ranges[k] = f64::NAN;
            }
            scan
        };
        let mut a = ProbabilityGrid::new(0.05);
        let mut b = ProbabilityGrid::new(0.05);
        let mut c = ProbabilityGrid::new(0.1);
        a.insert_scan(
            &Pose2::new(0.3, 0.1, 0.2),
            &scan_at(Pose2::new(0.3, 0.1, 0.2)),
            &params,
        )
        .unwrap();
        b.insert_scan(
            &Pose2::new(-0.4, 0.2, -0.3),
            &scan_at(Pose2::new(-0.4, 0.2, -0.3)),
            &params,
        )
        .unwrap();
        let pose = Pose2::new(0.123, -0.456, 0.789);
        let scan = scan_at(pose);
        let (mut a1, mut b1, mut c1) = (a.clone(), b.clone(), c.clone());
        let expected = [
            a1.insert_scan(&pose, &scan, &params).unwrap(),
            b1.insert_scan(&pose, &scan, &params).unwrap(),
            c1.insert_scan(&pose, &scan, &params).unwrap(),
        ];
        let got =
            ProbabilityGrid::insert_scan_into_all(&mut [&mut a, &mut b], &pose, &scan, &params)
                .unwrap();
        assert_eq!(got, expected[..2]);
        let alone =
            ProbabilityGrid::insert_scan_into_all(&mut [&mut c], &pose, &scan, &params).unwrap();
        assert_eq!(alone, expected[2..]);
        for (together, one_by_one) in [(&a, &a1), (&b, &b1), (&c, &c1)] {
            assert_eq!(together.known_cells(), one_by_one.known_cells());
            let (i0, j0, i1, j1) = one_by_one.known_bounds().unwrap();
            for j in j0 - 1..=j1 + 1 {
                for i in i0 - 1..=i1 + 1 {
                    assert_eq!(
                        together.log_odds_at(i, j).map(f64::to_bits),
                        one_by_one.log_odds_at(i, j).map(f64::to_bits),
                        "cell ({i}, {j})"
                    );
                }
            }
        }
        // Mixed resolutions: each grid gets its own insertion.
        let (mut a2, mut c2) = (a1.clone(), c1.clone());
        let mixed =
            ProbabilityGrid::insert_scan_into_all(&mut [&mut a2, &mut c2], &pose, &scan, &params)
                .unwrap();
        assert_eq!(
            mixed,
            vec![
                a1.insert_scan(&pose, &scan, &params).unwrap(),
                c1.insert_scan(&pose, &scan, &params).unwrap()
            ]
        );
        assert_eq!(a2.known_cells(), a1.known_cells());
        assert_eq!(c2.known_cells(), c1.known_cells());
    }

    #[test]
    fn a_row_in_one_tile_reads_the_same_entries_as_one_by_one() {
        let params = log_odds_without_free_run();
        let mut g = ProbabilityGrid::new(0.1);
        g.insert_scan(
            &Pose2::new(0.05, 0.05, 0.0),
            &one_beam(2.0, 0.0, 10.0),
            &params,
        )
        .unwrap();
        for (i, j, len) in [
            (0, 0, 5),
            (27, 0, 5),
            (-40, 3, 5),
            (100, 100, 3),
            (32, 0, 32),
        ] {
            let row = g.entries_in_row(i, j, len).unwrap();
            assert_eq!(row.len(), len);
            for (k, &entry) in row.iter().enumerate() {
                assert_eq!(entry, g.entry_at(i + k as i64, j), "({i}, {j}) + {k}");
            }
        }
        // The beam's cells are known, the rest of the row not.
        assert_eq!(g.entries_in_row(0, 0, 5).unwrap()[0], table_entry(-0.4));
        assert_eq!(g.entries_in_row(27, 0, 5).unwrap()[4], UNKNOWN_ENTRY);
        // A window in one tile holds the same entries, row by row.
        for (i, j) in [(0, 0), (27, 2), (-40, 3), (100, 100)] {
            let (entries, base) = g.entries_window(i, j, 5).unwrap();
            for (r, c) in (0..5).flat_map(|r| (0..5).map(move |c| (r, c))) {
                assert_eq!(
                    entries[base + r * TILE + c],
                    g.entry_at(i + c as i64, j + r as i64),
                    "({i}, {j}) + ({c}, {r})"
                );
            }
        }
        assert!(g.entries_window(30, 0, 5).is_none());
        assert!(g.entries_window(0, 30, 5).is_none());
        assert!(g.entries_window(0, 0, 33).is_none());
        // A run across a tile boundary, or longer than a tile: read cell by cell.
        assert!(g.entries_in_row(30, 0, 5).is_none());
        assert!(g.entries_in_row(-2, 0, 5).is_none());
        assert!(g.entries_in_row(0, 0, 33).is_none());
    }

    /// Every cell's table entry is the entry of its log odds, after scans from
    /// several poses (hits, misses, a grid that grew in every direction, cells
    /// updated many times up to the clamp) and in a weighted mean of grids.
    #[test]
    fn every_cell_keeps_the_table_entry_of_its_log_odds() {
        let params = InsertParams {
            rule: UpdateRule::LOG_ODDS,
            max_range_free: 3.0,
        };
        let beams = 90;
        let scan = Scan {
            angles: (0..beams)
                .map(|k| {
                    -std::f64::consts::PI + 2.0 * std::f64::consts::PI * k as f64 / beams as f64
                })
                .collect(),
            ranges: (0..beams)
                .map(|k| {
                    if k % 7 == 0 {
                        10.0
                    } else {
                        1.0 + 0.05 * (k % 13) as f64
                    }
                })
                .collect(),
            range_min: 0.0,
            range_max: 10.0,
        };
        let mut a = ProbabilityGrid::new(0.1);
        let mut b = ProbabilityGrid::new(0.1);
        for step in 0..40 {
            let pose = Pose2::new(
                -2.0 + 0.1 * step as f64,
                0.03 * step as f64,
                0.05 * step as f64,
            );
            a.insert_scan(&pose, &scan, &params).unwrap();
            if step % 3 == 0 {
                b.insert_scan(&pose, &scan, &params).unwrap();
            }
        }
        let mean = ProbabilityGrid::weighted_mean([(&a, 0.7), (&b, 0.3)]).unwrap();
        for grid in [&a, &b, &mean] {
            let mut known = 0;
            // `tiles` gives each tile's lower-left cell.
            for (ti, tj, cells) in grid.tiles() {
                for (k, &l) in cells.iter().enumerate() {
                    let (i, j) = (ti + (k % TILE) as i64, tj + (k / TILE) as i64);
                    assert_eq!(grid.entry_at(i, j), table_entry(l), "cell ({i}, {j})");
                    known += usize::from(!l.is_nan());
                }
            }
            assert!(known > 500, "{known} known cells");
        }
        // Entries at the clamp and in between are distinct table entries.
        assert_eq!(table_entry(f32::NAN), UNKNOWN_ENTRY);
        assert_eq!(table_entry(-100.0), 0);
        assert_eq!(table_entry(100.0), (TABLE_ENTRIES - 1) as u16);
        assert_eq!(table_entry(0.0), 2048);
        assert!((table_log_odds(2048) - 0.0039).abs() < 1e-4);
    }

    #[test]
    fn tile_revisions_tell_two_grids_apart_after_the_same_number_of_scans() {
        let params = log_odds_without_free_run();
        let pose = Pose2::new(0.05, 0.05, 0.0);
        let mut a = ProbabilityGrid::new(0.1);
        a.insert_scan(&pose, &one_beam(0.5, 0.0, 10.0), &params)
            .unwrap();
        let mut b = a.clone();
        let rev = |g: &ProbabilityGrid| g.tile_revisions().map(|(_, _, r)| r).collect::<Vec<_>>();
        assert_eq!(rev(&a), rev(&b), "a copy shows the same tiles");
        a.insert_scan(&pose, &one_beam(0.3, 0.0, 10.0), &params)
            .unwrap();
        b.insert_scan(&pose, &one_beam(0.2, 0.0, 10.0), &params)
            .unwrap();
        assert_ne!(rev(&a), rev(&b), "different contents, different revisions");
    }

    #[test]
    fn log_odds_and_probability_invert_each_other() {
        for p in [0.01, 0.1, 0.49, 0.5, 0.55, 0.9, 0.999] {
            assert!((probability(log_odds(p)) - p).abs() < 1e-12);
        }
        assert_eq!(log_odds(0.5), 0.0);
    }

    #[test]
    fn one_beam_with_log_odds_matches_hand_computed_cells() {
        // Sensor at the centre of cell (0, 0), beam along +x, 0.5 m at 0.1 m
        // cells: end point at x = 0.55, cell 5. Misses: cells 0..=4.
        let mut g = ProbabilityGrid::new(0.1);
        let pose = Pose2::new(0.05, 0.05, 0.0);
        let params = InsertParams {
            rule: UpdateRule::LOG_ODDS,
            max_range_free: 0.0,
        };
        let report = g
            .insert_scan(&pose, &one_beam(0.5, 0.0, 10.0), &params)
            .unwrap();
        assert_eq!(report.hits, 1);
        assert_eq!(report.misses, 5);
        assert_eq!(report.new_cells, 6);
        let l = |g: &ProbabilityGrid, i| g.log_odds_at(i, 0).unwrap();
        assert!((l(&g, 5) - 0.85).abs() < 1e-6);
        for i in 0..5 {
            assert!((l(&g, i) + 0.4).abs() < 1e-6, "cell {i}: {}", l(&g, i));
        }
        assert_eq!(g.log_odds_at(6, 0), None);
        assert_eq!(g.log_odds_at(0, 1), None);
        // Five more scans: hits clamp at l_max = 3.5 (0.85 · 5 = 4.25), misses
        // at l_min = −2 (−0.4 · 6 = −2.4).
        for _ in 0..5 {
            g.insert_scan(&pose, &one_beam(0.5, 0.0, 10.0), &params)
                .unwrap();
        }
        assert!((l(&g, 5) - 3.5).abs() < 1e-6);
        assert!((l(&g, 0) + 2.0).abs() < 1e-6);
        assert!((g.probability_at(5, 0).unwrap() - probability(3.5)).abs() < 1e-6);
    }

    #[test]
    fn one_beam_with_odds_matches_eq_5_4_by_hand() {
        let mut g = ProbabilityGrid::new(0.1);
        let pose = Pose2::new(0.05, 0.05, 0.0);
        let params = InsertParams {
            rule: UpdateRule::CARTOGRAPHER,
            max_range_free: 0.0,
        };
        let odds = |p: f64| p / (1.0 - p);
        let inv = |o: f64| o / (1.0 + o);
        let (mut hit, mut miss) = (0.5_f64, 0.5_f64);
        for scan in 0..40 {
            g.insert_scan(&pose, &one_beam(0.3, 0.0, 10.0), &params)
                .unwrap();
            // Eq. 5.4 in probability space, then the clamp.
            hit = inv(odds(hit) * odds(0.55)).clamp(0.1, 0.9);
            miss = inv(odds(miss) * odds(0.49)).clamp(0.1, 0.9);
            let got_hit = g.probability_at(3, 0).unwrap();
            let got_miss = g.probability_at(1, 0).unwrap();
            assert!(
                (got_hit - hit).abs() < 1e-5,
                "scan {scan}: {got_hit} vs {hit}"
            );
            assert!(
                (got_miss - miss).abs() < 1e-5,
                "scan {scan}: {got_miss} vs {miss}"
            );
        }
        // A never-seen cell becomes exactly p_hit after one hit.
        let mut fresh = ProbabilityGrid::new(0.1);
        fresh
            .insert_scan(&pose, &one_beam(0.3, 0.0, 10.0), &params)
            .unwrap();
        assert!((fresh.probability_at(3, 0).unwrap() - 0.55).abs() < 1e-6);
        assert!((fresh.probability_at(0, 0).unwrap() - 0.49).abs() < 1e-6);
        // After 40 hits the clamp holds it at p_max.
        assert!((hit - 0.9).abs() < 1e-12);
    }

    /// From the middle of cell (0, 0) of a 0.1 m grid, 90 beams ending in cell
    /// 5 and one beam beyond, ending in cell 10; log odds, no free space for
    /// max-range beams.
    fn ninety_beams_and_one_beyond() -> (Pose2, Scan, InsertParams) {
        let mut angles = vec![0.0; 90];
        let mut ranges = vec![0.52; 90];
        angles.push(0.0);
        ranges.push(1.02);
        let scan = Scan {
            angles,
            ranges,
            range_min: 0.0,
            range_max: 10.0,
        };
        let params = InsertParams {
            rule: UpdateRule::LOG_ODDS,
            max_range_free: 0.0,
        };
        (Pose2::new(0.05, 0.05, 0.0), scan, params)
    }

    #[test]
    fn a_cell_is_updated_once_per_scan_and_hits_win_over_misses() {
        // 90 beams all ending in the same cell, and one beam that crosses that
        // cell on its way further out.
        let mut g = ProbabilityGrid::new(0.1);
        let (pose, scan, params) = ninety_beams_and_one_beyond();
        let report = g.insert_scan(&pose, &scan, &params).unwrap();
        assert_eq!(report.hits, 2, "cells 5 and 10");
        assert_eq!(report.misses, 9, "cells 0-4 and 6-9");
        assert!((g.log_odds_at(5, 0).unwrap() - 0.85).abs() < 1e-6);
        assert!((g.log_odds_at(10, 0).unwrap() - 0.85).abs() < 1e-6);
        assert!((g.log_odds_at(2, 0).unwrap() + 0.4).abs() < 1e-6);
        assert!((g.log_odds_at(7, 0).unwrap() + 0.4).abs() < 1e-6);
        // No stamp is left behind.
        for (_, _, cells) in g.tiles() {
            assert!(cells.iter().all(|v| v.is_nan() || v.abs() < 60.0));
        }
    }

    #[test]
    fn a_beam_explained_names_its_cells_values_and_who_updates_them() {
        // The scan of the test above: beam 90 crosses cell 5, where the first
        // 90 beams end, so cell 5 is a hit there, not a miss, and it is beam
        // 0's to update; cells 0-4 were crossed by beam 0 already.
        let mut g = ProbabilityGrid::new(0.1);
        let (pose, scan, params) = ninety_beams_and_one_beyond();
        // A first scan so that "before" is not empty: cell 3 at -0.4.
        g.insert_scan(&pose, &one_beam(0.32, 0.0, 10.0), &params)
            .unwrap();
        let first = g.explain_beam(&pose, &scan, 0, &params).unwrap();
        let cells: Vec<(i64, i64)> = first.cells.iter().map(|c| c.cell).collect();
        assert_eq!(cells, [(0, 0), (1, 0), (2, 0), (3, 0), (4, 0), (5, 0)]);
        assert!(first.cells.iter().all(|c| c.updated_here));
        // Cell 3 held the first scan's end point; in this scan it is crossed:
        // a miss, 0.85 - 0.4.
        let c3 = first.cells[3];
        assert_eq!((c3.hit, c3.end), (false, false));
        assert!((c3.before.unwrap() - 0.85).abs() < 1e-6);
        assert!((c3.after - 0.45).abs() < 1e-6);
        assert!(first.cells[5].end && first.cells[5].hit);
        let last = g.explain_beam(&pose, &scan, 90, &params).unwrap();
        let cells: Vec<(i64, i64)> = last.cells.iter().map(|c| c.cell).collect();
        assert_eq!(cells, (0..=10).map(|i| (i, 0)).collect::<Vec<_>>());
        let c5 = last.cells[5];
        assert!(c5.hit && !c5.end && !c5.updated_here, "{c5:?}");
        assert!((c5.after - 0.85).abs() < 1e-9, "a hit: 0 + l_occ");
        let c7 = last.cells[7];
        assert!(!c7.hit && c7.updated_here && c7.before.is_none());
        assert!((c7.after + 0.4).abs() < 1e-9);
        let c10 = last.cells[10];
        assert!(c10.end && c10.hit && c10.updated_here);
        assert!(!last.cells[2].updated_here, "beam 0 crossed cell 2 first");
        // Whatever the scan, the values explained are the values inserted.
        let mut after = g.clone();
        after.insert_scan(&pose, &scan, &params).unwrap();
        for beam in [0, 45, 90] {
            for c in g.explain_beam(&pose, &scan, beam, &params).unwrap().cells {
                let got = after.log_odds_at(c.cell.0, c.cell.1).unwrap();
                assert!((got - c.after).abs() < 1e-6, "beam {beam} {c:?}: {got}");
            }
        }
        assert!(g.explain_beam(&pose, &scan, 91, &params).is_err());
        assert!(
            g.explain_beam(&Pose2::new(f64::NAN, 0.0, 0.0), &scan, 0, &params)
                .is_err()
        );
    }

    #[test]
    fn a_grid_that_grows_during_a_scan_leaves_no_stamp_behind() {
        // The first beam ends in the first tile; the next ones reach tiles to
        // the west, south and north-east, so the grid is laid out again three
        // times while cells of the first tiles are stamped.
        let mut g = ProbabilityGrid::new(0.1);
        let pose = Pose2::new(0.05, 0.05, 0.0);
        let scan = Scan {
            angles: vec![0.0, std::f64::consts::PI, -std::f64::consts::FRAC_PI_2, 0.8],
            ranges: vec![1.0, 9.0, 12.0, 20.0],
            range_min: 0.0,
            range_max: 30.0,
        };
        let params = InsertParams {
            rule: UpdateRule::LOG_ODDS,
            max_range_free: 0.0,
        };
        let report = g.insert_scan(&pose, &scan, &params).unwrap();
        assert_eq!(report.hits, 4);
        for (_, _, cells) in g.tiles() {
            assert!(
                cells.iter().all(|v| v.is_nan() || v.abs() < 60.0),
                "a stamp survived the scan"
            );
        }
        // Every cell holds the value one update gives it.
        assert!((g.log_odds_at(10, 0).unwrap() - 0.85).abs() < 1e-6);
        assert!((g.log_odds_at(5, 0).unwrap() + 0.4).abs() < 1e-6);
        assert!((g.log_odds_at(-90, 0).unwrap() - 0.85).abs() < 1e-6);
        assert!((g.log_odds_at(-40, 0).unwrap() + 0.4).abs() < 1e-6);
        assert!((g.log_odds_at(0, -120).unwrap() - 0.85).abs() < 1e-6);
    }

    #[test]
    fn scans_from_a_wandering_sensor_match_a_cell_by_cell_reference() {
        // The grid against the plainest implementation of the rule: a map from
        // cell to log odds, the hit set and the miss set minus the hits, each
        // cell updated once per scan. The sensor wanders far, so the grid is
        // laid out again in the middle of many scans.
        use std::collections::{HashMap, HashSet};
        let params = InsertParams {
            rule: UpdateRule::LOG_ODDS,
            max_range_free: 3.0,
        };
        let steps = params.rule.log_odds_steps().unwrap();
        let mut g = ProbabilityGrid::new(0.1);
        let mut reference: HashMap<(i64, i64), f64> = HashMap::new();
        let mut state = 12345u64;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 0..40 {
            let pose = Pose2::new(
                -20.0 + 40.0 * uniform(),
                -20.0 + 40.0 * uniform(),
                6.0 * uniform(),
            );
            let n = 60;
            let angles: Vec<f64> = (0..n).map(|b| -3.1 + 6.2 * b as f64 / n as f64).collect();
            let ranges: Vec<f64> = (0..n)
                .map(|_| {
                    if uniform() < 0.1 {
                        8.0
                    } else {
                        0.3 + 7.0 * uniform()
                    }
                })
                .collect();
            let scan = Scan {
                angles,
                ranges,
                range_min: 0.0,
                range_max: 8.0,
            };
            g.insert_scan(&pose, &scan, &params).unwrap();
            let mut hits = HashSet::new();
            let mut misses = HashSet::new();
            for b in 0..n {
                if let Some(c) = g.hit_cell(&pose, &scan, b) {
                    hits.insert(c);
                }
                misses.extend(g.crossed_cells(&pose, &scan, b, &params));
            }
            for c in &hits {
                let old = reference.get(c).copied();
                reference.insert(*c, steps.apply(old, true));
            }
            for c in misses.difference(&hits) {
                let old = reference.get(c).copied();
                reference.insert(*c, steps.apply(old, false));
            }
            assert_eq!(g.known_cells(), reference.len(), "scan {k}");
        }
        for (&(i, j), &l) in &reference {
            let got = g.log_odds_at(i, j).unwrap();
            assert!((got - l).abs() < 1e-5, "cell ({i}, {j}): {got} against {l}");
        }
    }

    #[test]
    fn max_range_beams_mark_free_space_up_to_the_set_distance_and_no_hit() {
        let mut g = ProbabilityGrid::new(0.1);
        let pose = Pose2::new(0.05, 0.05, 0.0);
        let params = InsertParams {
            rule: UpdateRule::LOG_ODDS,
            max_range_free: 0.8,
        };
        let report = g
            .insert_scan(&pose, &one_beam(10.0, 0.0, 10.0), &params)
            .unwrap();
        assert_eq!(report.hits, 0);
        // From x = 0.05 to 0.85: cells 0..=8.
        assert_eq!(report.misses, 9);
        assert!(g.log_odds_at(8, 0).unwrap() < 0.0);
        assert_eq!(g.log_odds_at(9, 0), None);
        // With max_range_free = 0 the beam changes nothing.
        let mut g2 = ProbabilityGrid::new(0.1);
        let none = InsertParams {
            max_range_free: 0.0,
            ..params
        };
        let r2 = g2
            .insert_scan(&pose, &one_beam(10.0, 0.0, 10.0), &none)
            .unwrap();
        assert_eq!((r2.hits, r2.misses), (0, 0));
        // NaN and negative readings change nothing either.
        let r3 = g2
            .insert_scan(&pose, &one_beam(f64::NAN, 0.0, 10.0), &params)
            .unwrap();
        let r4 = g2
            .insert_scan(&pose, &one_beam(-1.0, 0.0, 10.0), &params)
            .unwrap();
        assert_eq!((r3.hits, r3.misses, r4.hits, r4.misses), (0, 0, 0, 0));
    }

    #[test]
    fn the_grid_grows_in_every_direction_and_keeps_what_it_had() {
        let mut g = ProbabilityGrid::new(0.05);
        let params = InsertParams::default();
        let pose = Pose2::new(0.0, 0.0, 0.0);
        g.insert_scan(&pose, &one_beam(1.0, 0.0, 10.0), &params)
            .unwrap();
        let before = g.log_odds_at(20, 0);
        assert!(before.is_some());
        for (angle, range) in [(3.0, 7.0), (-1.5, 9.0), (1.5, 8.0), (2.4, 6.0)] {
            g.insert_scan(&pose, &one_beam(range, angle, 10.0), &params)
                .unwrap();
        }
        assert_eq!(g.log_odds_at(20, 0), before);
        let (i0, j0, i1, j1) = g.known_bounds().unwrap();
        assert!(
            i0 < -100 && j0 < -150 && i1 >= 20 && j1 > 150,
            "{:?}",
            (i0, j0, i1, j1)
        );
        // The end point of the beam at 3.0 rad, 7 m.
        let (x, y) = (7.0 * math::cos(3.0), 7.0 * math::sin(3.0));
        let (i, j) = g.cell_of(x, y);
        assert!(g.log_odds_at(i, j).unwrap() > 0.0);
    }

    #[test]
    fn clones_share_tiles_until_they_write() {
        let mut parent = ProbabilityGrid::new(0.05);
        let params = InsertParams::default();
        for k in 0..8 {
            let a = k as f64 * 0.8;
            parent
                .insert_scan(&Pose2::IDENTITY, &one_beam(4.0, a, 10.0), &params)
                .unwrap();
        }
        let tiles = parent.tiles().count();
        assert!(tiles > 4);
        let mut child = parent.clone();
        assert_eq!(child.shared_tiles_with(&parent), tiles);
        // A write of one cell copies exactly one tile: a 1 cm beam from the
        // middle of a cell touches only that cell.
        let pose = Pose2::new(0.025, 0.025, 0.0);
        let tiny = one_beam(0.01, 0.0, 10.0);
        child
            .insert_scan(
                &pose,
                &tiny,
                &InsertParams {
                    max_range_free: 0.0,
                    ..params
                },
            )
            .unwrap();
        assert_eq!(child.shared_tiles_with(&parent), tiles - 1);
        assert_eq!(
            parent.log_odds_at(0, 0).is_some(),
            child.log_odds_at(0, 0).is_some()
        );
    }

    #[test]
    fn segment_traversal_visits_the_cells_between_and_ends_in_the_right_cell() {
        let mut seen = Vec::new();
        segment_cells((0.5, 0.5), (3.5, 1.5), true, |i, j| seen.push((i, j)));
        assert_eq!(seen.len(), 5);
        assert_eq!(seen.first(), Some(&(0, 0)));
        assert_eq!(seen.last(), Some(&(3, 1)));
        // Exactly through a corner, and backwards with negative cells.
        let mut corner = Vec::new();
        segment_cells((0.5, 0.5), (2.5, 2.5), false, |i, j| corner.push((i, j)));
        assert_eq!(corner.len(), 4);
        let mut back = Vec::new();
        segment_cells((0.2, 0.3), (-2.7, -1.1), true, |i, j| back.push((i, j)));
        assert_eq!(back.last(), Some(&(-3, -2)));
        assert_eq!(back.len(), 3 + 2 + 1);
        // Each step moves to a 4-neighbour.
        for w in back.windows(2) {
            assert_eq!((w[0].0 - w[1].0).abs() + (w[0].1 - w[1].1).abs(), 1);
        }
    }

    #[test]
    fn bad_rules_are_refused_with_a_reason() {
        let mut g = ProbabilityGrid::new(0.05);
        for rule in [
            UpdateRule::LogOdds {
                l_occ: -1.0,
                l_free: -0.4,
                l_min: -2.0,
                l_max: 2.0,
            },
            UpdateRule::Odds {
                p_hit: 0.55,
                p_miss: 0.6,
                p_min: 0.1,
                p_max: 0.9,
            },
            UpdateRule::Odds {
                p_hit: f64::NAN,
                p_miss: 0.4,
                p_min: 0.1,
                p_max: 0.9,
            },
        ] {
            let params = InsertParams {
                rule,
                max_range_free: 1.0,
            };
            let err = g.insert_scan(&Pose2::IDENTITY, &one_beam(1.0, 0.0, 5.0), &params);
            assert!(err.is_err());
        }
        assert_eq!(g.known_cells(), 0);
    }

    #[test]
    fn the_occupancy_grid_export_thresholds_probabilities() {
        let mut g = ProbabilityGrid::new(0.1);
        let pose = Pose2::new(0.05, 0.05, 0.0);
        let params = InsertParams {
            rule: UpdateRule::LOG_ODDS,
            max_range_free: 0.0,
        };
        for _ in 0..4 {
            g.insert_scan(&pose, &one_beam(0.5, 0.0, 10.0), &params)
                .unwrap();
        }
        let occ = g.to_occupancy_grid(0.65, 0.196).unwrap();
        assert_eq!((occ.width(), occ.height()), (6, 1));
        assert_eq!(occ.get(5, 0), Some(super::super::Cell::Occupied));
        assert_eq!(occ.get(0, 0), Some(super::super::Cell::Free));
        assert!((occ.origin().x - 0.0).abs() < 1e-12);
    }
}
