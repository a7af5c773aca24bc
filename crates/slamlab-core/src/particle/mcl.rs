//! Monte Carlo localization on an occupancy grid: thesis `000` Algorithm 8,
//! Probabilistic Robotics Table 8.2, with ROS amcl's practical rules (update
//! thresholds, resample interval, cluster estimate).
//!
//! One filter update is three phases, callable one at a time so a lesson can
//! show each:
//!
//! 1. [`Mcl::predict`]: every particle is moved by a sample of the odometry
//!    motion model (Table 5.6) for the odometry since the last update.
//! 2. [`Mcl::weight`]: every particle's weight is multiplied by the scan's
//!    likelihood from its pose (beam model or likelihood field), in log space.
//! 3. [`Mcl::resample`]: particles are drawn in proportion to their weights
//!    (low-variance by default) every `resample_interval` updates, optionally
//!    only when `N_eff` falls below a fraction of the count.
//!
//! The filter owns its random number generator, so a clone is a checkpoint.

use super::cluster::{ClusterBins, PoseEstimate, heaviest_cluster};
use super::sensor::{
    BeamLikelihood, MeasurementModel, PreparedModel, Scan, ScanAggregation, beam_end_points,
};
use super::{
    Resampler, WeightError, effective_sample_size, log_sum_exp, normalize_log_weights,
    resample_indices,
};
use crate::geometry::{Pose2, wrap_angle};
use crate::grid::{DistanceField, FreeCells, OccupancyGrid};
use crate::math;
use crate::odometry::{OdometryModel, OdometryNoise, odometry_increment, sample_increment_with};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::sync::{Arc, Mutex};
use thiserror::Error;

/// The most particles a filter accepts (larger requests are clamped).
pub const MAX_PARTICLES: usize = 200_000;

/// A map prepared for localization: the grid, its distance field (capped at
/// amcl's `laser_likelihood_max_dist`) and its free cells. Shared between filters
/// with an [`Arc`].
#[derive(Debug)]
pub struct LocalizationMap {
    grid: OccupancyGrid,
    field: DistanceField,
    free: FreeCells,
    /// The measurement model last prepared on this map (see
    /// [`prepared_model`](Self::prepared_model)), so that the filters sharing
    /// the map tabulate it once instead of once each.
    prepared: Mutex<Option<Arc<PreparedModel>>>,
}

impl Clone for LocalizationMap {
    fn clone(&self) -> Self {
        Self {
            grid: self.grid.clone(),
            field: self.field.clone(),
            free: self.free.clone(),
            prepared: Mutex::new(None),
        }
    }
}

/// Why a map cannot be used for localization.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum MclError {
    /// No free cell: nowhere to put a particle (or a robot).
    #[error("the map has no free cell: there is nowhere for the robot to be")]
    NoFreeCell,
}

impl LocalizationMap {
    /// Prepares `grid`, with the distance field capped at `likelihood_max_dist`
    /// metres. Refuses a map with no free cell.
    pub fn new(grid: OccupancyGrid, likelihood_max_dist: f64) -> Result<Self, MclError> {
        let free = FreeCells::of(&grid);
        if free.is_empty() {
            return Err(MclError::NoFreeCell);
        }
        let field = DistanceField::new(&grid, likelihood_max_dist);
        Ok(Self {
            grid,
            field,
            free,
            prepared: Mutex::new(None),
        })
    }

    /// The occupancy grid.
    pub fn grid(&self) -> &OccupancyGrid {
        &self.grid
    }

    /// The distance field.
    pub fn field(&self) -> &DistanceField {
        &self.field
    }

    /// The free cells.
    pub fn free_cells(&self) -> &FreeCells {
        &self.free
    }

    /// `model` prepared on this map's distance field for scans of maximum range
    /// `range_max`, its beams combined by `aggregation` (the likelihood field's
    /// per-cell table). The map keeps the last one it prepared and hands it to
    /// every filter that asks for the same model, aggregation and range; a
    /// different request replaces it.
    pub fn prepared_model(
        &self,
        model: MeasurementModel,
        aggregation: ScanAggregation,
        range_max: f64,
    ) -> Arc<PreparedModel> {
        // A panic while the lock was held cannot leave the slot half written
        // (it holds an `Arc` or nothing), so a poisoned lock is still usable.
        let mut slot = self.prepared.lock().unwrap_or_else(|e| e.into_inner());
        match &*slot {
            Some(p)
                if *p.model() == model
                    && p.aggregation() == aggregation
                    && p.range_max() == range_max =>
            {
                Arc::clone(p)
            }
            _ => {
                let p = Arc::new(PreparedModel::new(
                    model,
                    aggregation,
                    &self.field,
                    range_max,
                ));
                *slot = Some(Arc::clone(&p));
                p
            }
        }
    }
}

/// Where a particle came from in the current update (for drawing; AMCL marks
/// injected particles, CMCL/ACMCL regenerated ones).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParticleFlag {
    /// Moved by the motion model (or drawn at initialization).
    #[default]
    Normal,
    /// Drawn uniformly at random in place of a resampled one (Augmented MCL).
    Injected,
    /// Redrawn because its motion entered an invalid cell (CMCL, ACMCL).
    Regenerated,
}

/// One particle: a pose hypothesis and its weight.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Particle {
    /// The pose hypothesis.
    pub pose: Pose2,
    /// Normalized weight (the weights sum to one).
    pub weight: f64,
    /// `ln` of the normalized weight (−∞ for weight zero).
    pub log_weight: f64,
    /// Where it came from in the current update.
    pub flag: ParticleFlag,
}

/// Parameters of plain MCL, named after ROS amcl's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MclConfig {
    /// Number of particles `M` (clamped to `1 ..= MAX_PARTICLES`).
    pub particles: usize,
    /// Odometry model noise (`odom_alpha1..4`).
    pub odom: OdometryNoise,
    /// Whether the odometry sums are variances or standard deviations
    /// (`odom_model_type`: `diff-corrected`, the default, or ROS 1's `diff`).
    #[serde(default)]
    pub odom_model: OdometryModel,
    /// Measurement model (`laser_model_type` and its `laser_z_*`).
    pub model: MeasurementModel,
    /// How the beams' likelihoods combine: the product (Probabilistic
    /// Robotics, tempered by `likelihood_exponent`) or amcl's `1 + Σ p_k³`.
    #[serde(default)]
    pub aggregation: ScanAggregation,
    /// Beams used per scan (`laser_max_beams`; 0: all).
    pub max_beams: usize,
    /// Translation that triggers an update, metres (`update_min_d`).
    pub update_min_d: f64,
    /// Rotation that triggers an update, radians (`update_min_a`).
    pub update_min_a: f64,
    /// Resample every this many updates (`resample_interval`; 1: every update).
    pub resample_interval: u32,
    /// If set, resample only when `N_eff < fraction x M` (selective resampling).
    pub neff_fraction: Option<f64>,
    /// The resampling method.
    pub resampler: Resampler,
    /// Bins for the cluster estimate.
    pub cluster: ClusterBins,
    /// Exponent `κ ∈ (0, 1]` applied to each scan likelihood, `p(z | x)^κ`
    /// (1: the plain product over beams). The beams of one scan are not
    /// independent, so their product is overconfident (Probabilistic Robotics
    /// Sec. 6.3.4 and 6.4 recommend subsampling beams or inflating the noise for
    /// this reason); `κ < 1` tempers it the same way for every beam. ROS amcl
    /// instead scores `1 + Σ p_k³` ([`ScanAggregation::AmclCubes`]), which is
    /// softer still; the exponent applies to the product only.
    pub likelihood_exponent: f64,
    /// KLD-sampling (Fox 2003; amcl `kld_err`, `kld_z`, `min_particles`,
    /// `max_particles`): if set, resampling draws particles until their count
    /// bounds the KL divergence of the binned estimate, between the limits;
    /// `particles` is then the count at the start.
    pub kld: Option<KldSampling>,
}

/// KLD-sampling's parameters (amcl names and defaults).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KldSampling {
    /// Maximum error between the true and the estimated distribution
    /// (`kld_err`, 0.01).
    pub err: f64,
    /// Upper standard normal quantile for `1 − δ` (`kld_z`; amcl's default 0.99
    /// is used as the quantile value itself, as amcl does).
    pub z: f64,
    /// Fewest particles (`min_particles`, 100).
    pub min_particles: usize,
    /// Most particles (`max_particles`, 5000).
    pub max_particles: usize,
}

impl Default for KldSampling {
    fn default() -> Self {
        Self {
            err: 0.01,
            z: 0.99,
            min_particles: 100,
            max_particles: 5000,
        }
    }
}

impl KldSampling {
    /// The particle count that bounds the error with `k` occupied bins (Fox
    /// 2003, Eq. 7; amcl `pf_resample_limit`), clamped to the limits.
    pub fn limit(&self, k: usize) -> usize {
        if k <= 1 {
            return self.max_particles;
        }
        let km1 = (k - 1) as f64;
        let b = 2.0 / (9.0 * km1);
        let x = 1.0 - b + b.sqrt() * self.z;
        let n = (km1 / (2.0 * self.err) * x * x * x).ceil();
        (n.min(self.max_particles as f64) as usize).clamp(self.min_particles, self.max_particles)
    }
}

impl Default for MclConfig {
    fn default() -> Self {
        Self {
            particles: 2000,
            odom: OdometryNoise::default(),
            odom_model: OdometryModel::default(),
            model: MeasurementModel::default(),
            aggregation: ScanAggregation::default(),
            max_beams: 30,
            update_min_d: 0.2,
            update_min_a: std::f64::consts::PI / 6.0,
            resample_interval: 1,
            neff_fraction: None,
            resampler: Resampler::LowVariance,
            cluster: ClusterBins::default(),
            likelihood_exponent: 1.0,
            kld: None,
        }
    }
}

impl MclConfig {
    /// The configuration with every value made usable, and a message for each
    /// value that had to change.
    pub fn sanitized(mut self) -> (Self, Vec<String>) {
        let mut notes = Vec::new();
        if self.particles == 0 {
            notes.push("particles 0 clamped to 1".to_owned());
            self.particles = 1;
        } else if self.particles > MAX_PARTICLES {
            notes.push(format!(
                "particles {} clamped to {MAX_PARTICLES}",
                self.particles
            ));
            self.particles = MAX_PARTICLES;
        }
        self.odom = self.odom.sanitized();
        if !(self.update_min_d >= 0.0) || !self.update_min_d.is_finite() {
            notes.push(format!(
                "update_min_d {} replaced by 0.2",
                self.update_min_d
            ));
            self.update_min_d = 0.2;
        }
        if !(self.update_min_a >= 0.0) || !self.update_min_a.is_finite() {
            notes.push(format!(
                "update_min_a {} replaced by π/6",
                self.update_min_a
            ));
            self.update_min_a = std::f64::consts::PI / 6.0;
        }
        if self.resample_interval == 0 {
            notes.push("resample_interval 0 clamped to 1".to_owned());
            self.resample_interval = 1;
        }
        if let Some(f) = self.neff_fraction
            && !(0.0..=1.0).contains(&f)
        {
            let c = if f > 1.0 { 1.0 } else { 0.0 };
            notes.push(format!("N_eff fraction {f} clamped to {c}"));
            self.neff_fraction = Some(c);
        }
        if let Some(k) = &mut self.kld {
            if k.min_particles > k.max_particles {
                notes.push(format!(
                    "min_particles {} above max_particles {}: swapped",
                    k.min_particles, k.max_particles
                ));
                std::mem::swap(&mut k.min_particles, &mut k.max_particles);
            }
            k.min_particles = k.min_particles.clamp(1, MAX_PARTICLES);
            k.max_particles = k.max_particles.clamp(1, MAX_PARTICLES);
            if !(k.err > 0.0 && k.err.is_finite()) {
                notes.push(format!("kld_err {} replaced by 0.01", k.err));
                k.err = 0.01;
            }
            if !k.z.is_finite() {
                notes.push(format!("kld_z {} replaced by 0.99", k.z));
                k.z = 0.99;
            }
        }
        if !(self.likelihood_exponent > 0.0 && self.likelihood_exponent <= 1.0) {
            notes.push(format!(
                "likelihood exponent {} replaced by 1",
                self.likelihood_exponent
            ));
            self.likelihood_exponent = 1.0;
        }
        let positive = |v: f64| v > 0.0 && v.is_finite();
        let non_negative = |v: f64| v >= 0.0 && v.is_finite();
        match &mut self.model {
            MeasurementModel::Beam(b) => {
                if !positive(b.sigma_hit) {
                    notes.push(format!("laser_sigma_hit {} replaced by 0.2", b.sigma_hit));
                    b.sigma_hit = 0.2;
                }
                for (name, v) in [
                    ("laser_z_hit", &mut b.z_hit),
                    ("laser_z_short", &mut b.z_short),
                    ("laser_z_max", &mut b.z_max),
                    ("laser_z_rand", &mut b.z_rand),
                    ("laser_lambda_short", &mut b.lambda_short),
                ] {
                    if !non_negative(*v) {
                        notes.push(format!("{name} {v} replaced by 0"));
                        *v = 0.0;
                    }
                }
            }
            MeasurementModel::LikelihoodField(lf) => {
                if !positive(lf.sigma_hit) {
                    notes.push(format!("laser_sigma_hit {} replaced by 0.2", lf.sigma_hit));
                    lf.sigma_hit = 0.2;
                }
                for (name, v) in [
                    ("laser_z_hit", &mut lf.z_hit),
                    ("laser_z_rand", &mut lf.z_rand),
                ] {
                    if !non_negative(*v) {
                        notes.push(format!("{name} {v} replaced by 0"));
                        *v = 0.0;
                    }
                }
            }
        }
        (self, notes)
    }
}

/// What [`Mcl::predict`] did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PredictReport {
    /// The odometry increment `(δrot1, δtrans, δrot2)` applied.
    pub increment: (f64, f64, f64),
    /// Whether this was the first odometry reading (nothing to apply yet).
    pub first: bool,
}

/// What [`Mcl::weight`] did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WeightReport {
    /// `ln Σᵢ p(z | xᵢ)`, the log of the sum of this scan's likelihoods
    /// (subtract `ln M` for the log of the average, which AMCL's `w_slow` and
    /// `w_fast` follow).
    pub log_likelihood_sum: f64,
    /// Beams used.
    pub beams: usize,
    /// The particle with the largest scan likelihood, and its log likelihood.
    pub best: (usize, f64),
    /// The particle with the smallest scan likelihood, and its log likelihood.
    pub worst: (usize, f64),
    /// Per-beam likelihoods of the best particle.
    pub best_beams: Vec<BeamLikelihood>,
    /// Per-beam likelihoods of a poor particle (the worst).
    pub poor_beams: Vec<BeamLikelihood>,
    /// `N_eff` after weighting.
    pub n_eff: f64,
    /// Set when the weights could not be updated (every likelihood zero): the
    /// previous weights were kept.
    pub note: Option<String>,
}

/// What [`Mcl::resample`] did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResampleReport {
    /// `N_eff` before resampling.
    pub n_eff_before: f64,
    /// Whether the particles were resampled.
    pub resampled: bool,
    /// How many distinct particles survived (all of them if not resampled).
    pub distinct_parents: usize,
}

/// Plain Monte Carlo localization (thesis `000` Algorithm 8; Probabilistic
/// Robotics Table 8.2).
#[derive(Clone, Debug)]
pub struct Mcl {
    config: MclConfig,
    map: Arc<LocalizationMap>,
    rng: ChaCha8Rng,
    particles: Vec<Particle>,
    /// The odometry pose of the last prediction.
    last_odom: Option<Pose2>,
    updates_since_resample: u32,
    estimate: Option<PoseEstimate>,
    n_eff: f64,
    prepared: Option<Arc<PreparedModel>>,
    notices: Vec<String>,
    scratch_log: Vec<f64>,
    scratch_w: Vec<f64>,
}

impl Mcl {
    /// A filter on `map` with its own random stream `seed`. The particles start
    /// uniformly over the free cells (global localization); call
    /// [`init_tracking`](Self::init_tracking) to start around a known pose.
    /// Values of `config` that had to be clamped are listed in
    /// [`notices`](Self::notices).
    pub fn new(config: MclConfig, map: Arc<LocalizationMap>, seed: u64) -> Self {
        let (config, notices) = config.sanitized();
        let mut mcl = Self {
            config,
            map,
            rng: ChaCha8Rng::seed_from_u64(seed),
            particles: Vec::new(),
            last_odom: None,
            updates_since_resample: 0,
            estimate: None,
            n_eff: 0.0,
            prepared: None,
            notices,
            scratch_log: Vec::new(),
            scratch_w: Vec::new(),
        };
        mcl.init_global();
        mcl
    }

    /// Scatters the particles uniformly over the free cells with uniform
    /// headings (global localization, Probabilistic Robotics Sec. 8.3).
    pub fn init_global(&mut self) {
        let m = self.config.particles;
        let w = 1.0 / m as f64;
        self.particles.clear();
        for _ in 0..m {
            // The map has at least one free cell (LocalizationMap::new).
            let pose = self
                .map
                .free
                .sample(&mut self.rng)
                .unwrap_or(Pose2::IDENTITY);
            self.particles.push(Particle {
                pose,
                weight: w,
                log_weight: math::ln(w),
                flag: ParticleFlag::Normal,
            });
        }
        self.after_reset();
    }

    /// Draws the particles from a Gaussian around `mean` with standard deviations
    /// `std = [σx, σy, σθ]` (position tracking; amcl's `initial_pose` and
    /// `initial_cov`).
    pub fn init_tracking(&mut self, mean: Pose2, std: [f64; 3]) {
        let m = self.config.particles;
        let w = 1.0 / m as f64;
        let s = std.map(|v| if v > 0.0 && v.is_finite() { v } else { 0.0 });
        self.particles.clear();
        for _ in 0..m {
            let n: [f64; 3] =
                std::array::from_fn(|_| crate::random::standard_normal(&mut self.rng));
            self.particles.push(Particle {
                pose: Pose2::new(
                    mean.x + s[0] * n[0],
                    mean.y + s[1] * n[1],
                    mean.theta + s[2] * n[2],
                ),
                weight: w,
                log_weight: math::ln(w),
                flag: ParticleFlag::Normal,
            });
        }
        self.after_reset();
    }

    fn after_reset(&mut self) {
        self.updates_since_resample = 0;
        self.n_eff = self.particles.len() as f64;
        self.refresh_estimate();
    }

    /// Whether the odometry has moved enough since the last update to run one
    /// (amcl: translation ≥ `update_min_d` or rotation ≥ `update_min_a`). The
    /// first reading always is.
    pub fn update_due(&self, odom: Pose2) -> bool {
        match self.last_odom {
            None => true,
            Some(last) => {
                math::hypot(odom.x - last.x, odom.y - last.y) >= self.config.update_min_d
                    || wrap_angle(odom.theta - last.theta).abs() >= self.config.update_min_a
            }
        }
    }

    /// Phase 1: moves every particle by a sample of the odometry motion model
    /// for the odometry from the last prediction to `odom` (Probabilistic
    /// Robotics Table 5.6). The first call only records `odom`.
    pub fn predict(&mut self, odom: Pose2) -> PredictReport {
        let Some(last) = self.last_odom.replace(odom) else {
            for p in &mut self.particles {
                p.flag = ParticleFlag::Normal;
            }
            return PredictReport {
                increment: (0.0, 0.0, 0.0),
                first: true,
            };
        };
        let (rot1, trans, rot2) = odometry_increment(last, odom);
        let noise = self.config.odom;
        let model = self.config.odom_model;
        for p in &mut self.particles {
            p.pose = sample_increment_with(model, p.pose, rot1, trans, rot2, &noise, &mut self.rng);
            p.flag = ParticleFlag::Normal;
        }
        PredictReport {
            increment: (rot1, trans, rot2),
            first: false,
        }
    }

    /// The scan log likelihood of every particle, into `out`.
    pub fn scan_log_likelihoods(&mut self, scan: &Scan, out: &mut Vec<f64>) -> usize {
        let rebuild = match &self.prepared {
            Some(p) => {
                p.range_max() != scan.range_max
                    || *p.model() != self.config.model
                    || p.aggregation() != self.config.aggregation
            }
            None => true,
        };
        let range_max = if scan.range_max > 0.0 && scan.range_max.is_finite() {
            scan.range_max
        } else {
            1.0
        };
        if rebuild {
            self.prepared = Some(self.map.prepared_model(
                self.config.model,
                self.config.aggregation,
                range_max,
            ));
        }
        let beams = scan.subsample(self.config.max_beams);
        let ends = beam_end_points(scan, &beams);
        out.clear();
        if let Some(model) = &self.prepared {
            let map = &*self.map;
            out.extend(self.particles.iter().map(|p| {
                model.scan_log_likelihood(&map.grid, &map.field, &p.pose, scan, &beams, &ends)
            }));
        }
        beams.len()
    }

    /// The log likelihoods that weight the particles: those of
    /// [`scan_log_likelihoods`](Self::scan_log_likelihoods), multiplied by
    /// `likelihood_exponent` for the product (amcl's sum of cubes is used as
    /// it is). Returns the number of beams used.
    pub fn weighting_log_likelihoods(&mut self, scan: &Scan, out: &mut Vec<f64>) -> usize {
        let beams = self.scan_log_likelihoods(scan, out);
        let kappa = self.config.likelihood_exponent;
        if kappa != 1.0 && self.config.aggregation == ScanAggregation::Product {
            for l in out.iter_mut() {
                *l *= kappa;
            }
        }
        beams
    }

    /// Phase 2: multiplies every weight by the likelihood of `scan` from the
    /// particle's pose (in log space, normalized with log-sum-exp).
    ///
    /// If every particle has likelihood zero (the scan contradicts them all) the
    /// weights are left as they were and the report carries a note; no weight
    /// ever becomes NaN.
    pub fn weight(&mut self, scan: &Scan) -> WeightReport {
        let mut ll = std::mem::take(&mut self.scratch_log);
        let beams = self.weighting_log_likelihoods(scan, &mut ll);
        let report = self.apply_log_likelihoods(&ll, scan, beams);
        self.scratch_log = ll;
        report
    }

    /// Multiplies the weights by `exp(ll[i])` and normalizes (the core of
    /// [`weight`](Self::weight), for filters that compute or adjust the
    /// likelihoods themselves).
    pub fn apply_log_likelihoods(&mut self, ll: &[f64], scan: &Scan, beams: usize) -> WeightReport {
        let n = self.particles.len().min(ll.len());
        let mut best = (0, f64::NEG_INFINITY);
        let mut worst = (0, f64::INFINITY);
        for (i, &l) in ll.iter().enumerate().take(n) {
            if l > best.1 {
                best = (i, l);
            }
            if l < worst.1 {
                worst = (i, l);
            }
        }
        let mut w = std::mem::take(&mut self.scratch_w);
        let mut note = None;
        let log_likelihood_sum = match log_sum_exp(&ll[..n]) {
            Ok(sum) => sum,
            Err(e) => {
                note = Some(format!("{e}; the weights are kept from before this scan"));
                f64::NEG_INFINITY
            }
        };
        if note.is_none() {
            let combined: Vec<f64> = self
                .particles
                .iter()
                .zip(ll)
                .map(|(p, l)| p.log_weight + l)
                .collect();
            match normalize_log_weights(&combined, &mut w) {
                Ok(total) => {
                    for ((p, &c), &wi) in self.particles.iter_mut().zip(&combined).zip(&w) {
                        p.log_weight = c - total;
                        p.weight = wi;
                    }
                }
                Err(e) => {
                    note = Some(format!(
                        "{e} (with the previous weights); the weights are kept from before this scan"
                    ));
                }
            }
        }
        self.scratch_w = w;
        self.n_eff = effective_sample_size(self.particles.iter().map(|p| &p.weight));
        self.refresh_estimate();
        let (best_beams, poor_beams) = if n > 0
            && let Some(model) = &self.prepared
        {
            let sub = scan.subsample(self.config.max_beams);
            let map = &*self.map;
            (
                model.explain(
                    &map.grid,
                    &map.field,
                    &self.particles[best.0].pose,
                    scan,
                    &sub,
                ),
                model.explain(
                    &map.grid,
                    &map.field,
                    &self.particles[worst.0].pose,
                    scan,
                    &sub,
                ),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        WeightReport {
            log_likelihood_sum,
            beams,
            best,
            worst,
            best_beams,
            poor_beams,
            n_eff: self.n_eff,
            note,
        }
    }

    /// Phase 3: draws a new particle set in proportion to the weights with the
    /// configured resampler (thesis Algorithm 7 by default), if this update is a
    /// resampling one (`resample_interval`, and `N_eff < fraction x M` when a
    /// fraction is set). Weights become uniform after resampling.
    pub fn resample(&mut self) -> ResampleReport {
        let n_eff_before = self.n_eff;
        self.updates_since_resample += 1;
        let m = self.particles.len();
        let interval_due = self.updates_since_resample >= self.config.resample_interval;
        let neff_due = match self.config.neff_fraction {
            Some(f) => n_eff_before < f * m as f64,
            None => true,
        };
        if !(interval_due && neff_due) || m == 0 {
            return ResampleReport {
                n_eff_before,
                resampled: false,
                distinct_parents: m,
            };
        }
        self.updates_since_resample = 0;
        let weights = self.weights();
        let mut idx = Vec::with_capacity(m);
        match self.config.kld {
            Some(kld) => self.kld_indices(&weights, &kld, &mut idx),
            None => resample_indices(self.config.resampler, &weights, m, &mut self.rng, &mut idx),
        }
        let m = idx.len();
        let mut distinct = 0;
        let mut last = usize::MAX;
        for &i in &idx {
            if i != last {
                distinct += 1;
                last = i;
            }
        }
        let w = 1.0 / m as f64;
        let lw = math::ln(w);
        let new: Vec<Particle> = idx
            .iter()
            .map(|&i| Particle {
                weight: w,
                log_weight: lw,
                ..self.particles[i]
            })
            .collect();
        self.particles = new;
        self.n_eff = m as f64;
        ResampleReport {
            n_eff_before,
            resampled: true,
            distinct_parents: distinct,
        }
    }

    /// KLD-sampling (Fox 2003, Table 1; amcl `pf_update_resample`): independent
    /// draws in proportion to the weights until the count reaches the bound for
    /// the number of occupied bins (amcl's 0.5 m / 10° bins), between the
    /// limits. Returns sorted indices.
    fn kld_indices(&mut self, weights: &[f64], kld: &KldSampling, out: &mut Vec<usize>) {
        let mut cumulative = Vec::with_capacity(weights.len());
        let mut total = 0.0;
        for &w in weights {
            total += if w > 0.0 && w.is_finite() { w } else { 0.0 };
            cumulative.push(total);
        }
        out.clear();
        if !(total > 0.0) || weights.is_empty() {
            out.extend(0..weights.len().min(kld.max_particles));
            return;
        }
        let cell = self.config.cluster.cell_size.max(1e-3);
        let angle = self.config.cluster.angle_bin.max(1e-3);
        let mut bins: Vec<(i64, i64, i64)> = Vec::new();
        let mut limit = kld.max_particles;
        while out.len() < kld.max_particles && (out.len() < limit || out.len() < kld.min_particles)
        {
            let r = self.rng.random::<f64>() * total;
            let i = cumulative
                .partition_point(|&c| c <= r)
                .min(weights.len() - 1);
            out.push(i);
            let p = self.particles[i].pose;
            let key = (
                crate::grid::floor_to_i64(p.x / cell),
                crate::grid::floor_to_i64(p.y / cell),
                crate::grid::floor_to_i64(p.theta / angle),
            );
            if let Err(pos) = bins.binary_search(&key) {
                bins.insert(pos, key);
                limit = kld.limit(bins.len());
            }
        }
        out.sort_unstable();
    }

    /// One full update if the odometry has moved enough (predict, weight,
    /// resample), else `None`.
    pub fn update(
        &mut self,
        odom: Pose2,
        scan: &Scan,
    ) -> Option<(PredictReport, WeightReport, ResampleReport)> {
        if !self.update_due(odom) {
            return None;
        }
        let p = self.predict(odom);
        let w = self.weight(scan);
        let r = self.resample();
        Some((p, w, r))
    }

    fn refresh_estimate(&mut self) {
        let poses: Vec<Pose2> = self.particles.iter().map(|p| p.pose).collect();
        let weights = self.weights();
        self.estimate = heaviest_cluster(&poses, &weights, &self.config.cluster);
    }

    /// The normalized weights.
    pub fn weights(&self) -> Vec<f64> {
        self.particles.iter().map(|p| p.weight).collect()
    }

    /// The particles (read-only, for drawing).
    pub fn particles(&self) -> &[Particle] {
        &self.particles
    }

    /// Mutable particles, for filters built on this one (AMCL injection,
    /// CMCL regeneration). Keep the weights normalized.
    pub fn particles_mut(&mut self) -> &mut Vec<Particle> {
        &mut self.particles
    }

    /// The particles and the random stream together, for filters built on this
    /// one that redraw particles.
    pub fn particles_and_rng(&mut self) -> (&mut Vec<Particle>, &mut ChaCha8Rng) {
        (&mut self.particles, &mut self.rng)
    }

    /// The filter's random stream, for filters built on this one.
    pub fn rng_mut(&mut self) -> &mut ChaCha8Rng {
        &mut self.rng
    }

    /// The heaviest cluster's mean and covariance, computed when the particles
    /// are weighted (and at initialization), as amcl reports its pose once per
    /// filter update: prediction and resampling leave it as it was. `None` if
    /// no particle has weight.
    pub fn estimate(&self) -> Option<&PoseEstimate> {
        self.estimate.as_ref()
    }

    /// Recomputes the estimate after the particles were changed from outside.
    pub fn recompute_estimate(&mut self) {
        self.n_eff = effective_sample_size(self.particles.iter().map(|p| &p.weight));
        self.refresh_estimate();
    }

    /// `N_eff = 1 / Σ wᵢ²` of the current weights.
    pub fn n_eff(&self) -> f64 {
        self.n_eff
    }

    /// Number of particles.
    pub fn count(&self) -> usize {
        self.particles.len()
    }

    /// The configuration in use (after clamping).
    pub fn config(&self) -> &MclConfig {
        &self.config
    }

    /// The map.
    pub fn map(&self) -> &Arc<LocalizationMap> {
        &self.map
    }

    /// Messages about clamped parameters.
    pub fn notices(&self) -> &[String] {
        &self.notices
    }

    /// The odometry pose of the last prediction, `None` before the first.
    pub fn last_odometry(&self) -> Option<Pose2> {
        self.last_odom
    }
}

/// Whether a [`WeightError`] means the scan contradicted every particle.
pub fn is_all_zero(e: &WeightError) -> bool {
    matches!(e, WeightError::AllZero)
}

impl crate::belief::PoseBelief for Mcl {
    /// The heaviest cluster's weighted mean, as amcl reports it (the origin for
    /// a cloud without weight).
    fn robot_pose(&self) -> Pose2 {
        self.estimate.as_ref().map_or(Pose2::IDENTITY, |e| e.pose)
    }

    /// The heaviest cluster's covariance; infinite variances for a cloud without
    /// weight (it says nothing about the pose).
    fn robot_covariance(&self) -> nalgebra::Matrix3<f64> {
        self.estimate.as_ref().map_or_else(
            || nalgebra::Matrix3::from_diagonal_element(f64::INFINITY),
            |e| e.covariance,
        )
    }
}

impl crate::belief::ParticleBelief for Mcl {
    fn particle_count(&self) -> usize {
        self.particles.len()
    }

    fn particle_pose(&self, index: usize) -> Option<Pose2> {
        self.particles.get(index).map(|p| p.pose)
    }

    fn particle_weight(&self, index: usize) -> f64 {
        self.particles.get(index).map_or(0.0, |p| p.weight)
    }

    fn n_eff(&self) -> f64 {
        self.n_eff
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::grid::Cell;
    use crate::particle::sensor::BeamModel;

    /// A 4 x 4 m room of 0.1 m cells with a wall all around and a pillar (also
    /// the recovery filters' test room).
    pub(crate) fn room() -> Arc<LocalizationMap> {
        let mut g = OccupancyGrid::filled(40, 40, 0.1, Pose2::IDENTITY, Cell::Free).unwrap();
        for k in 0..40 {
            g.set(k, 0, Cell::Occupied);
            g.set(k, 39, Cell::Occupied);
            g.set(0, k, Cell::Occupied);
            g.set(39, k, Cell::Occupied);
        }
        for i in 25..30 {
            for j in 8..12 {
                g.set(i, j, Cell::Occupied);
            }
        }
        Arc::new(LocalizationMap::new(g, 2.0).unwrap())
    }

    /// `beams` readings all around, raycast in `map` from `pose` (8 m range).
    pub(crate) fn scan_from(map: &LocalizationMap, pose: Pose2, beams: usize) -> Scan {
        let angles: Vec<f64> = (0..beams)
            .map(|k| -std::f64::consts::PI + std::f64::consts::TAU * k as f64 / beams as f64)
            .collect();
        let ranges = angles
            .iter()
            .map(|a| map.grid().raycast(pose.x, pose.y, pose.theta + a, 8.0))
            .collect();
        Scan {
            angles,
            ranges,
            range_min: 0.0,
            range_max: 8.0,
        }
    }

    #[test]
    fn weighting_favours_the_true_pose_and_resampling_resets_weights() {
        let map = room();
        let truth = Pose2::new(1.2, 2.5, 0.4);
        let mut mcl = Mcl::new(
            MclConfig {
                particles: 500,
                ..Default::default()
            },
            map.clone(),
            3,
        );
        mcl.init_tracking(truth, [0.3, 0.3, 0.3]);
        let scan = scan_from(&map, truth, 60);
        mcl.predict(Pose2::IDENTITY);
        let w = mcl.weight(&scan);
        assert!(w.note.is_none());
        assert_eq!(w.beams, 30);
        assert_eq!(w.best_beams.len(), 30);
        let best = mcl.particles()[w.best.0].pose;
        assert!(
            math::hypot(best.x - truth.x, best.y - truth.y) < 0.15,
            "{best:?}"
        );
        let sum: f64 = mcl.particles().iter().map(|p| p.weight).sum();
        assert!((sum - 1.0).abs() < 1e-12);
        assert!(mcl.n_eff() < 500.0);
        let e = mcl.estimate().unwrap();
        assert!(
            math::hypot(e.pose.x - truth.x, e.pose.y - truth.y) < 0.1,
            "{e:?}"
        );
        let r = mcl.resample();
        assert!(r.resampled && r.distinct_parents < 500);
        assert!((mcl.n_eff() - 500.0).abs() < 1e-9);
        assert!(mcl.particles().iter().all(|p| p.weight == 1.0 / 500.0));
    }

    #[test]
    fn filters_on_one_map_share_its_prepared_model() {
        let map = room();
        let model = MeasurementModel::default();
        let product = ScanAggregation::Product;
        let first = map.prepared_model(model, product, 8.0);
        assert!(Arc::ptr_eq(
            &first,
            &map.prepared_model(model, product, 8.0)
        ));
        let other_range = map.prepared_model(model, product, 5.0);
        assert!(!Arc::ptr_eq(&first, &other_range));
        assert_eq!(other_range.range_max(), 5.0);
    }

    #[test]
    fn a_scan_that_contradicts_every_particle_keeps_the_weights() {
        let map = room();
        let config = MclConfig {
            particles: 50,
            model: MeasurementModel::Beam(BeamModel {
                z_hit: 0.0,
                z_short: 0.0,
                z_max: 1.0,
                z_rand: 0.0,
                ..Default::default()
            }),
            ..Default::default()
        };
        let mut mcl = Mcl::new(config, map.clone(), 1);
        let before = mcl.weights();
        let scan = scan_from(&map, Pose2::new(2.0, 2.0, 0.0), 8);
        let w = mcl.weight(&scan);
        assert!(
            w.note.as_deref().is_some_and(|n| n.contains("weight zero")),
            "{w:?}"
        );
        assert_eq!(mcl.weights(), before);
        assert!(mcl.particles().iter().all(|p| p.weight.is_finite()));
        assert!(mcl.estimate().is_some());
    }

    #[test]
    fn kld_limit_follows_fox_and_stays_within_bounds() {
        let k = KldSampling {
            min_particles: 100,
            max_particles: 5000,
            ..Default::default()
        };
        // (k − 1)/(2ε) (1 − 2/(9(k−1)) + sqrt(2/(9(k−1))) z)³, ceiling.
        assert_eq!(k.limit(10), 651);
        assert_eq!(k.limit(50), 2936);
        assert_eq!(k.limit(2), 100);
        assert_eq!(k.limit(1), 5000);
        assert_eq!(k.limit(1000), 5000);
        // A tight cloud needs few particles, a spread one many.
        let map = room();
        let config = MclConfig {
            particles: 3000,
            kld: Some(KldSampling {
                min_particles: 50,
                max_particles: 3000,
                ..Default::default()
            }),
            ..Default::default()
        };
        let mut spread = Mcl::new(config.clone(), map.clone(), 4);
        spread.resample();
        let mut tight = Mcl::new(config, map, 4);
        tight.init_tracking(Pose2::new(2.0, 2.0, 0.0), [0.05, 0.05, 0.02]);
        tight.resample();
        // The tight cloud straddles bin edges at x = y = 2 m and θ = 0: 8 bins.
        assert!(tight.count() < 600, "{}", tight.count());
        assert!(spread.count() > 1000, "{}", spread.count());
        assert!((tight.weights().iter().sum::<f64>() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn thresholds_counts_and_selective_resampling() {
        let map = room();
        let (c, notes) = MclConfig {
            particles: 10_000_000,
            ..Default::default()
        }
        .sanitized();
        assert_eq!(c.particles, MAX_PARTICLES);
        assert_eq!(notes.len(), 1);
        let mut mcl = Mcl::new(
            MclConfig {
                particles: 0,
                neff_fraction: Some(0.5),
                ..Default::default()
            },
            map.clone(),
            2,
        );
        assert_eq!(mcl.count(), 1);
        assert_eq!(mcl.notices().len(), 1);
        assert!(mcl.update_due(Pose2::IDENTITY));
        mcl.predict(Pose2::IDENTITY);
        assert!(!mcl.update_due(Pose2::new(0.1, 0.0, 0.2)));
        assert!(mcl.update_due(Pose2::new(0.2, 0.0, 0.0)));
        assert!(mcl.update_due(Pose2::new(0.0, 0.0, 0.6)));
        // Uniform weights: N_eff = M, not below half of M: no resampling.
        let r = mcl.resample();
        assert!(!r.resampled);
    }
}
