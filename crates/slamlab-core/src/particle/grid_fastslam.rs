//! Grid FastSLAM as gmapping does it (Grisetti, Stachniss, Burgard 2007,
//! "Improved techniques for grid mapping with Rao-Blackwellized particle
//! filters"; slides `001`, "Occupancy grid SLAM"): every particle carries a
//! pose, a path and its own occupancy grid, and the filter factors the SLAM
//! posterior as
//!
//! ```text
//! p(x_1:t, m | z_1:t, u_1:t) = p(x_1:t | z_1:t, u_1:t) · p(m | x_1:t, z_1:t)
//! ```
//!
//! (the path by particles, the map given each path by occupancy-grid mapping).
//! One update, when the robot has moved far enough (`linear_update`,
//! `angular_update`):
//!
//! 1. **Proposal.** With [`Proposal::Odometry`] each particle is moved by a
//!    sample of the motion model (gmapping's `drawFromMotion`, with its
//!    `srr`, `srt`, `str`, `stt`) and weighted by the scan's likelihood in its
//!    own map. With [`Proposal::ScanMatch`] (the improved proposal) each
//!    particle's odometry prediction is matched against its own map
//!    (the mapping lesson's scan-to-map matcher), the likelihood times the
//!    motion prior is evaluated at `K` poses around the match, a Gaussian is
//!    fitted to them and the new pose drawn from it. The slides' form:
//!
//!    ```text
//!    τ_j = p(z_t | x_j, m) · p(x_j | x_t−1, u_t)        (j = 1..K)
//!    η   = Σ_j τ_j
//!    μ   = (1/η) Σ_j τ_j x_j
//!    Σ   = (1/η) Σ_j τ_j (x_j − μ)(x_j − μ)ᵀ            (the slides print μ_j: a slip)
//!    x_t ~ N(μ, Σ),    w_t = w_t−1 · η                  ("Weighting" slide)
//!    ```
//!
//!    (Grisetti 2007's Eq. 14-16 and 19). A particle whose scan cannot be
//!    matched (no end points, nothing in its map that the scan touches) takes
//!    the odometry proposal for that update, and the report counts it.
//! 2. **Weights.** The log weights accumulate; the normalized weights are
//!    gmapping's smoothed ones, `w_i ∝ exp((ℓ_i − ℓ_max) / (ogain · M))`.
//! 3. **Adaptive resampling** (slides, "Resampling"): only when
//!    `N_eff = 1 / Σ w_i² < resample_threshold · M`, low variance. A copy
//!    shares its parent's map tiles (copy on write) and its path.
//! 4. **Map update.** Every particle inserts the scan at its pose.
//!
//! The likelihood `p(z | x, m)` is gmapping's `likelihoodAndScore`: each end
//! point looks for an occupied cell within `kernel_size` cells whose
//! neighbour one cell back along the beam is not occupied; a found cell at
//! distance `d` adds `−d² / lsigma` to the log likelihood, no cell adds
//! `−0.5 / lsigma`.

use super::resample::{Resampler, resample_indices};
use super::weights::effective_sample_size;
use crate::geometry::{Pose2, wrap_angle};
use crate::grid::{InsertParams, ProbabilityGrid};
use crate::math;
use crate::random::standard_normal;
use crate::scan::scan_to_map::{ProbabilityLookup, ScanToMapParams, match_scan_to_map};
use crate::scan::{Point2, PointTransform, Scan};
use nalgebra::{Matrix3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// The most particles grid FastSLAM accepts (each carries a map).
pub const MAX_GRID_PARTICLES: usize = 1000;

/// How particles are moved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Proposal {
    /// A sample of the odometry motion model, weighted by the scan likelihood.
    Odometry,
    /// The improved proposal: scan matching, then a Gaussian fitted around
    /// the match.
    #[default]
    ScanMatch,
}

impl Proposal {
    /// Both, in the order the lesson lists them.
    pub const ALL: [Proposal; 2] = [Proposal::Odometry, Proposal::ScanMatch];

    /// The name the URL and the CLI use.
    pub fn name(self) -> &'static str {
        match self {
            Proposal::Odometry => "odometry",
            Proposal::ScanMatch => "scan-match",
        }
    }

    /// The proposal a name spells, if any.
    pub fn from_name(name: &str) -> Option<Proposal> {
        Proposal::ALL.into_iter().find(|p| p.name() == name)
    }
}

/// Grid FastSLAM's parameters, with gmapping's names (its defaults unless
/// the comment says otherwise).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct GridFastSlamConfig {
    /// Particles `M` (`particles`).
    pub particles: usize,
    /// The proposal.
    pub proposal: Proposal,
    /// Resample when `N_eff < resample_threshold · M` (`resampleThreshold`).
    pub resample_threshold: f64,
    /// Translation noise per metre of translation (`srr`).
    pub srr: f64,
    /// Rotation noise per metre of translation, radians (`srt`).
    pub srt: f64,
    /// Translation noise per radian of rotation, metres (`str`).
    pub str: f64,
    /// Rotation noise per radian of rotation (`stt`).
    pub stt: f64,
    /// Half-width in x and y of the matcher's correlative search, metres
    /// (gmapping's `lstep`, its hill climber's first step; 0.1 m here).
    pub lstep: f64,
    /// Half-width in heading of the matcher's correlative search, radians
    /// (gmapping's `astep`; 5° here).
    pub astep: f64,
    /// The matcher's refinement iterations at most (`iterations`).
    pub iterations: usize,
    /// The likelihood's spread, m² (`lsigma`).
    pub lsigma: f64,
    /// Weight smoothing gain (`ogain`): weights are `exp(Δℓ / (ogain·M))`.
    pub ogain: f64,
    /// Cells searched around an end point, each way (`kernelSize`).
    pub kernel_size: usize,
    /// Half-width in x and y of the improved proposal's sample grid, metres
    /// (`llsamplerange`; 0.04 here, gmapping 0.01). With the steps below the
    /// grid is 5 × 5 × 7 poses (`K` = 175) reaching about 2.5 standard
    /// deviations of the likelihood's peak on a 5 cm grid, so the fitted
    /// Gaussian is not cut off (gmapping's ±1 cm grid is narrower than the
    /// peak: a ±2 cm grid already gave under half the true variance in x).
    pub llsamplerange: f64,
    /// Its step, metres (`llsamplestep`; 0.02 here, gmapping 0.01).
    pub llsamplestep: f64,
    /// Half-width in heading of the sample grid, radians (`lasamplerange`;
    /// 0.02 here, gmapping 0.005).
    pub lasamplerange: f64,
    /// Its step, radians (`lasamplestep`; 0.02/3 here, gmapping 0.005).
    pub lasamplestep: f64,
    /// Update after this much translation, metres (`linearUpdate`).
    pub linear_update: f64,
    /// Update after this much rotation, radians (`angularUpdate`).
    pub angular_update: f64,
    /// Metres per map cell (`delta`).
    pub delta: f64,
}

impl Default for GridFastSlamConfig {
    fn default() -> Self {
        Self {
            particles: 30,
            proposal: Proposal::ScanMatch,
            resample_threshold: 0.5,
            srr: 0.1,
            srt: 0.2,
            str: 0.1,
            stt: 0.2,
            lstep: 0.1,
            astep: 5f64.to_radians(),
            iterations: 10,
            lsigma: 0.075,
            ogain: 3.0,
            kernel_size: 1,
            llsamplerange: 0.04,
            llsamplestep: 0.02,
            lasamplerange: 0.02,
            lasamplestep: 0.02 / 3.0,
            linear_update: 1.0,
            angular_update: 0.5,
            delta: 0.05,
        }
    }
}

impl GridFastSlamConfig {
    /// The configuration with every value made usable, and a message for
    /// each value that had to change.
    pub fn sanitized(mut self) -> (Self, Vec<String>) {
        let mut notes = Vec::new();
        let defaults = Self::default();
        if self.particles == 0 {
            notes.push("particles 0 clamped to 1".to_owned());
            self.particles = 1;
        } else if self.particles > MAX_GRID_PARTICLES {
            notes.push(format!(
                "particles {} clamped to {MAX_GRID_PARTICLES} (each particle carries a map)",
                self.particles
            ));
            self.particles = MAX_GRID_PARTICLES;
        }
        if !(0.0..=1.0).contains(&self.resample_threshold) {
            notes.push(format!(
                "resample-threshold {} replaced by 0.5 (a fraction of the particles, 0 to 1)",
                self.resample_threshold
            ));
            self.resample_threshold = 0.5;
        }
        let mut non_negative = |name: &str, value: &mut f64, default: f64| {
            if !(value.is_finite() && *value >= 0.0) {
                notes.push(format!(
                    "{name} {value} replaced by {default} (it must be finite and not negative)"
                ));
                *value = default;
            }
        };
        non_negative("srr", &mut self.srr, defaults.srr);
        non_negative("srt", &mut self.srt, defaults.srt);
        non_negative("str", &mut self.str, defaults.str);
        non_negative("stt", &mut self.stt, defaults.stt);
        non_negative("lstep", &mut self.lstep, defaults.lstep);
        non_negative("astep", &mut self.astep, defaults.astep);
        non_negative(
            "llsamplerange",
            &mut self.llsamplerange,
            defaults.llsamplerange,
        );
        non_negative(
            "lasamplerange",
            &mut self.lasamplerange,
            defaults.lasamplerange,
        );
        non_negative(
            "linear-update",
            &mut self.linear_update,
            defaults.linear_update,
        );
        non_negative(
            "angular-update",
            &mut self.angular_update,
            defaults.angular_update,
        );
        let mut positive = |name: &str, value: &mut f64, default: f64, min: f64| {
            if !(value.is_finite() && *value >= min) {
                notes.push(format!(
                    "{name} {value} replaced by {default} (at least {min})"
                ));
                *value = default;
            }
        };
        positive("lsigma", &mut self.lsigma, defaults.lsigma, 1e-6);
        positive("ogain", &mut self.ogain, defaults.ogain, 1e-6);
        positive(
            "llsamplestep",
            &mut self.llsamplestep,
            defaults.llsamplestep,
            1e-4,
        );
        positive(
            "lasamplestep",
            &mut self.lasamplestep,
            defaults.lasamplestep,
            1e-4,
        );
        positive("delta", &mut self.delta, defaults.delta, 0.01);
        if self.delta > 1.0 {
            notes.push(format!("delta {} clamped to 1 m", self.delta));
            self.delta = 1.0;
        }
        if self.kernel_size > 5 {
            notes.push(format!("kernel-size {} clamped to 5", self.kernel_size));
            self.kernel_size = 5;
        }
        if self.iterations > 100 {
            notes.push(format!("iterations {} clamped to 100", self.iterations));
            self.iterations = 100;
        }
        // The sample grid has (2·range/step + 1)³ poses; keep it under 15³.
        for (name, range, step) in [
            ("llsamplerange", &mut self.llsamplerange, self.llsamplestep),
            ("lasamplerange", &mut self.lasamplerange, self.lasamplestep),
        ] {
            if *range > 7.0 * step {
                notes.push(format!(
                    "{name} {range} clamped to {} (7 steps each way)",
                    7.0 * step
                ));
                *range = 7.0 * step;
            }
        }
        (self, notes)
    }

    /// The scan-to-map matcher's settings for the improved proposal.
    pub fn matcher(&self) -> ScanToMapParams {
        ScanToMapParams {
            linear_search_window: self.lstep,
            angular_search_window: self.astep,
            max_iterations: self.iterations,
            ..ScanToMapParams::default()
        }
    }
}

/// One node of a particle's path. Paths are shared: a resampled copy
/// continues from its parent's node, so the paths of all particles form a
/// tree whose branches die with their particles.
#[derive(Debug)]
pub struct PathNode {
    /// The pose at this update.
    pub pose: Pose2,
    /// The index of the scan it was taken at.
    pub scan: usize,
    /// The node before, if any.
    pub parent: Option<Arc<PathNode>>,
}

impl Drop for PathNode {
    // Dropping a long path node by node instead of recursively, which would
    // overflow the stack after tens of thousands of updates.
    fn drop(&mut self) {
        let mut next = self.parent.take();
        while let Some(node) = next {
            match Arc::try_unwrap(node) {
                Ok(mut inner) => next = inner.parent.take(),
                Err(_) => break,
            }
        }
    }
}

impl PathNode {
    /// The path ending at this node, oldest first, as `(scan, pose)`.
    pub fn path(self: &Arc<Self>) -> Vec<(usize, Pose2)> {
        let mut out = Vec::new();
        let mut node = Some(self);
        while let Some(n) = node {
            out.push((n.scan, n.pose));
            node = n.parent.as_ref();
        }
        out.reverse();
        out
    }
}

/// One particle: a pose, its accumulated log weight since the last
/// resampling, its map and its path.
#[derive(Clone, Debug)]
pub struct GridParticle {
    /// The pose now.
    pub pose: Pose2,
    /// `ℓ`: the sum of the log weight factors since the last resampling.
    pub log_weight: f64,
    /// Its map.
    pub map: ProbabilityGrid,
    /// The last node of its path.
    pub path: Arc<PathNode>,
}

/// The Gaussian of the odometry motion model for one update, in the frame of
/// its mean: gmapping's `drawFromMotion` noise, with its conditioning
/// (`gaussianApproximation` adds 0.01 m² and 0.001 rad²).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotionPrior {
    /// The odometry prediction `x_t−1 ⊕ u_t`.
    pub mean: Pose2,
    /// Standard deviations along, across and in heading.
    pub std: [f64; 3],
}

impl MotionPrior {
    /// The prior of the move `delta` (robot frame) from `from`.
    pub fn new(config: &GridFastSlamConfig, from: Pose2, delta: Pose2) -> Self {
        let std = motion_std(config, delta);
        Self {
            mean: from.compose(&delta),
            std: [
                (std[0] * std[0] + 0.01).sqrt(),
                (std[1] * std[1] + 0.01).sqrt(),
                (std[2] * std[2] + 0.001).sqrt(),
            ],
        }
    }

    /// `log p(x | x_t−1, u_t)` up to a constant.
    pub fn log_density(&self, x: &Pose2) -> f64 {
        let e = self.mean.between(x);
        let v = [e.x, e.y, wrap_angle(e.theta)];
        -0.5 * v
            .iter()
            .zip(self.std)
            .map(|(v, s)| (v / s) * (v / s))
            .sum::<f64>()
    }
}

/// gmapping's `drawFromMotion` standard deviations for the move `delta`
/// (robot frame): along `srr|dx| + str|dθ| + 0.3·srr|dy|`, across
/// `srr|dy| + str|dθ| + 0.3·srr|dx|`, heading `stt|dθ| + srt·|(dx, dy)|`.
pub fn motion_std(config: &GridFastSlamConfig, delta: Pose2) -> [f64; 3] {
    let (dx, dy, dt) = (delta.x.abs(), delta.y.abs(), wrap_angle(delta.theta).abs());
    let sxy = 0.3 * config.srr;
    [
        config.srr * dx + config.str * dt + sxy * dy,
        config.srr * dy + config.str * dt + sxy * dx,
        config.stt * dt + config.srt * math::hypot(dx, dy),
    ]
}

/// A sample of the motion model: `from ∘ (delta + noise)`.
pub fn draw_from_motion<R: rand::Rng + ?Sized>(
    config: &GridFastSlamConfig,
    from: Pose2,
    delta: Pose2,
    rng: &mut R,
) -> Pose2 {
    let std = motion_std(config, delta);
    let noisy = Pose2::new(
        delta.x + std[0] * standard_normal(rng),
        delta.y + std[1] * standard_normal(rng),
        wrap_angle(delta.theta + std[2] * standard_normal(rng)),
    );
    let p = from.compose(&noisy);
    Pose2::new(p.x, p.y, wrap_angle(p.theta))
}

/// The scan's end points in the sensor frame, taken once per update and
/// read by every particle's likelihood ([`scan_log_likelihood`] finds the
/// point one cell back along each beam, gmapping's `freeDelta`, itself).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LikelihoodPoints {
    points: Vec<Point2>,
}

impl LikelihoodPoints {
    /// The end points of `scan`.
    pub fn new(scan: &Scan) -> Self {
        Self {
            points: scan.points(),
        }
    }

    /// End points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The end points, sensor frame.
    pub fn points(&self) -> &[Point2] {
        &self.points
    }
}

/// `log p(z | x, m)` by gmapping's `likelihoodAndScore` (module docs), and
/// how many end points found an occupied cell.
pub fn scan_log_likelihood(
    map: &ProbabilityGrid,
    points: &LikelihoodPoints,
    pose: &Pose2,
    config: &GridFastSlamConfig,
) -> (f64, usize) {
    let r = map.resolution();
    let free_delta = r * std::f64::consts::SQRT_2;
    let no_hit = -0.5 / config.lsigma;
    let k = config.kernel_size as i64;
    let occupied = |i: i64, j: i64| map.log_odds_at(i, j).is_some_and(|l| l > 0.0);
    let (mut l, mut found) = (0.0, 0);
    let transform = PointTransform::new(pose);
    for p in &points.points {
        let hit = transform.apply(*p);
        let range = math::hypot(p[0], p[1]);
        let back = if range > free_delta {
            (range - free_delta) / range
        } else {
            0.0
        };
        let free = transform.apply([p[0] * back, p[1] * back]);
        let (hi, hj) = map.cell_of(hit[0], hit[1]);
        let (fi, fj) = map.cell_of(free[0], free[1]);
        let (oi, oj) = (fi - hi, fj - hj);
        let mut best = f64::INFINITY;
        for dj in -k..=k {
            for di in -k..=k {
                let (i, j) = (hi + di, hj + dj);
                if occupied(i, j) && !occupied(i + oi, j + oj) {
                    let (cx, cy) = map.cell_center(i, j);
                    let d2 = (hit[0] - cx).powi(2) + (hit[1] - cy).powi(2);
                    best = best.min(d2);
                }
            }
        }
        if best.is_finite() {
            l -= best / config.lsigma;
            found += 1;
        } else {
            l += no_hit;
        }
    }
    (l, found)
}

/// The improved proposal of one particle: the Gaussian fitted to the
/// likelihood times the motion prior at the sample poses around the match.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProposalGaussian {
    /// `μ` (heading by circular mean).
    pub mean: Pose2,
    /// `Σ` over `(x, y, θ)`.
    pub covariance: Matrix3<f64>,
    /// `log η`, the particle's log weight factor.
    pub log_eta: f64,
    /// Poses evaluated (`K`).
    pub samples: usize,
}

/// Fits the improved proposal's Gaussian around `center` (the match): the
/// moments of `τ_j = p(z | x_j, m) · p(x_j | x_t−1, u_t)` over the sample
/// grid `center + (±llsamplerange, ±llsamplerange, ±lasamplerange)` at
/// `llsamplestep` and `lasamplestep` (gmapping's `ScanMatcher::likelihood`
/// with the odometry term). `None` if no sample has a finite weight.
pub fn fit_proposal(
    map: &ProbabilityGrid,
    points: &LikelihoodPoints,
    center: Pose2,
    prior: &MotionPrior,
    config: &GridFastSlamConfig,
) -> Option<ProposalGaussian> {
    let steps = |range: f64, step: f64| (range / step + 1e-9).floor() as i64;
    let (nl, na) = (
        steps(config.llsamplerange, config.llsamplestep),
        steps(config.lasamplerange, config.lasamplestep),
    );
    let mut samples: Vec<(Pose2, f64)> =
        Vec::with_capacity(((2 * nl + 1).pow(2) * (2 * na + 1)) as usize);
    for a in -na..=na {
        for b in -nl..=nl {
            for c in -nl..=nl {
                let x = Pose2::new(
                    center.x + c as f64 * config.llsamplestep,
                    center.y + b as f64 * config.llsamplestep,
                    wrap_angle(center.theta + a as f64 * config.lasamplestep),
                );
                let (l, _) = scan_log_likelihood(map, points, &x, config);
                samples.push((x, l + prior.log_density(&x)));
            }
        }
    }
    gaussian_of_weighted_poses(&samples)
}

/// The moments of poses with log weights (`log τ_j`): mean (circular in
/// heading), covariance, and `log Σ_j τ_j`. `None` if no weight is finite.
pub fn gaussian_of_weighted_poses(samples: &[(Pose2, f64)]) -> Option<ProposalGaussian> {
    let lmax = samples
        .iter()
        .map(|s| s.1)
        .filter(|l| l.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    if !lmax.is_finite() {
        return None;
    }
    let w: Vec<f64> = samples
        .iter()
        .map(|s| {
            if s.1.is_finite() {
                math::exp(s.1 - lmax)
            } else {
                0.0
            }
        })
        .collect();
    let eta: f64 = w.iter().sum();
    let (mut mx, mut my, mut s, mut c) = (0.0, 0.0, 0.0, 0.0);
    for ((p, _), w) in samples.iter().zip(&w) {
        mx += w * p.x;
        my += w * p.y;
        let (sn, cs) = math::sin_cos(p.theta);
        s += w * sn;
        c += w * cs;
    }
    let mean = Pose2::new(mx / eta, my / eta, math::atan2(s, c));
    let mut cov = Matrix3::zeros();
    for ((p, _), w) in samples.iter().zip(&w) {
        let d = Vector3::new(p.x - mean.x, p.y - mean.y, wrap_angle(p.theta - mean.theta));
        cov += *w * d * d.transpose();
    }
    cov /= eta;
    Some(ProposalGaussian {
        mean,
        covariance: cov,
        log_eta: math::ln(eta) + lmax,
        samples: samples.len(),
    })
}

/// A draw from `N(mean, covariance)` over `(x, y, θ)`; the mean itself when
/// the covariance has no Cholesky factor.
fn draw_gaussian<R: rand::Rng + ?Sized>(g: &ProposalGaussian, rng: &mut R) -> Pose2 {
    // A whisker on the diagonal keeps a covariance that one sample dominates
    // factorizable.
    let jitter = Matrix3::from_diagonal(&Vector3::new(1e-10, 1e-10, 1e-12));
    let Some(chol) = (g.covariance + jitter).cholesky() else {
        return g.mean;
    };
    let n = Vector3::new(
        standard_normal(rng),
        standard_normal(rng),
        standard_normal(rng),
    );
    let d = chol.l() * n;
    Pose2::new(
        g.mean.x + d[0],
        g.mean.y + d[1],
        wrap_angle(g.mean.theta + d[2]),
    )
}

/// What the proposal did to one particle in the last update.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleProposal {
    /// The odometry prediction `x_t−1 ⊕ u_t`.
    pub predicted: Pose2,
    /// The scan matcher's pose (improved proposal only).
    pub matched: Option<Pose2>,
    /// The fitted Gaussian (improved proposal only).
    pub gaussian: Option<ProposalGaussian>,
    /// The pose drawn.
    pub pose: Pose2,
    /// The log weight factor it got (`log η`, or the log likelihood).
    pub log_factor: f64,
    /// Whether it fell back to the odometry proposal.
    pub fell_back: bool,
}

/// What one update did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GridUpdateReport {
    /// The scan's index.
    pub scan: usize,
    /// Particles that fell back to the odometry proposal (nothing to match).
    pub fallbacks: usize,
    /// `N_eff` after weighting.
    pub neff: f64,
    /// Whether the particles were resampled.
    pub resampled: bool,
    /// Distinct particles that survived resampling (M if none).
    pub survivors: usize,
    /// Cells the scan updated in the best particle's map.
    pub inserted_cells: usize,
}

/// The filter. Cloning it is a checkpoint: maps and paths are shared until
/// written.
#[derive(Clone, Debug)]
pub struct GridFastSlam {
    config: GridFastSlamConfig,
    insert: InsertParams,
    particles: Vec<GridParticle>,
    /// Normalized (smoothed) weights, one per particle.
    weights: Vec<f64>,
    neff: f64,
    rng: ChaCha8Rng,
    lookup: Arc<ProbabilityLookup>,
    /// The odometry at the last update.
    last_odometry: Option<Pose2>,
    /// The last update's proposals, one per particle.
    proposals: Vec<ParticleProposal>,
    /// The odometry increment of the update whose proposals are under way.
    pending_delta: Option<Pose2>,
    updates: usize,
    resamplings: usize,
    fallbacks: usize,
    peak_memory: usize,
}

impl GridFastSlam {
    /// A filter with `config` (sanitized; the messages say what changed),
    /// inserting scans with `insert`, seeded with `seed`.
    pub fn new(config: GridFastSlamConfig, insert: InsertParams, seed: u64) -> (Self, Vec<String>) {
        let (config, notes) = config.sanitized();
        let m = config.particles;
        (
            Self {
                config,
                insert,
                particles: Vec::new(),
                weights: vec![1.0 / m as f64; m],
                neff: m as f64,
                rng: ChaCha8Rng::seed_from_u64(seed),
                lookup: Arc::new(ProbabilityLookup::default()),
                last_odometry: None,
                proposals: Vec::new(),
                pending_delta: None,
                updates: 0,
                resamplings: 0,
                fallbacks: 0,
                peak_memory: 0,
            },
            notes,
        )
    }

    /// The configuration (as sanitized).
    pub fn config(&self) -> &GridFastSlamConfig {
        &self.config
    }

    /// The particles (empty before the first scan).
    pub fn particles(&self) -> &[GridParticle] {
        &self.particles
    }

    /// The normalized weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// `N_eff` after the last weighting.
    pub fn neff(&self) -> f64 {
        self.neff
    }

    /// The heaviest particle's index (the first of equals).
    pub fn best_index(&self) -> usize {
        let mut best = 0;
        for (i, w) in self.weights.iter().enumerate() {
            if *w > self.weights[best] {
                best = i;
            }
        }
        best.min(self.particles.len().saturating_sub(1))
    }

    /// The heaviest particle.
    pub fn best(&self) -> Option<&GridParticle> {
        self.particles.get(self.best_index())
    }

    /// The last update's proposals.
    pub fn proposals(&self) -> &[ParticleProposal] {
        &self.proposals
    }

    /// Updates run (the first scan counts).
    pub fn updates(&self) -> usize {
        self.updates
    }

    /// Resamplings so far.
    pub fn resamplings(&self) -> usize {
        self.resamplings
    }

    /// Particle proposals that fell back to odometry so far.
    pub fn fallbacks(&self) -> usize {
        self.fallbacks
    }

    /// Bytes of map storage all particles hold now, each shared tile once.
    pub fn memory_bytes(&self) -> usize {
        ProbabilityGrid::distinct_memory_bytes(self.particles.iter().map(|p| &p.map))
    }

    /// The largest [`memory_bytes`](Self::memory_bytes) seen after an update.
    pub fn peak_memory_bytes(&self) -> usize {
        self.peak_memory
    }

    /// The odometry at the last update (`None` before the first scan).
    pub fn last_odometry(&self) -> Option<Pose2> {
        self.last_odometry
    }

    /// Whether [`resample_if_needed`](Self::resample_if_needed) would resample
    /// now: `N_eff < resample_threshold · M`.
    pub fn resample_due(&self) -> bool {
        self.neff < self.config.resample_threshold * self.particles.len() as f64
    }

    /// The particles' maps averaged cell by cell, each weighted by its
    /// particle's weight ([`ProbabilityGrid::weighted_mean`]); `None` before
    /// the first scan.
    pub fn mean_map(&self) -> Option<ProbabilityGrid> {
        ProbabilityGrid::weighted_mean(
            self.particles
                .iter()
                .zip(&self.weights)
                .map(|(p, w)| (&p.map, *w)),
        )
    }

    /// Whether the robot has moved far enough since the last update for the
    /// scan taken at `odometry` to be processed (always for the first scan).
    pub fn update_due(&self, odometry: &Pose2) -> bool {
        let Some(last) = self.last_odometry else {
            return true;
        };
        let d = last.between(odometry);
        math::hypot(d.x, d.y) >= self.config.linear_update
            || wrap_angle(d.theta).abs() >= self.config.angular_update
    }

    /// Processes scan number `index` taken at `odometry`: nothing (`None`)
    /// if the robot has not moved far enough since the last update, else a
    /// whole update (proposal, weights, resampling, maps).
    pub fn process(
        &mut self,
        index: usize,
        odometry: Pose2,
        scan: &Scan,
    ) -> Option<GridUpdateReport> {
        if !odometry.is_finite() || !self.update_due(&odometry) {
            return None;
        }
        if self.particles.is_empty() {
            return Some(self.initialize(index, odometry, scan));
        }
        let fallbacks = self.propose(odometry, scan);
        let neff = self.normalize();
        let (resampled, survivors) = self.resample_if_needed();
        let inserted_cells = self.update_maps(index, scan);
        Some(GridUpdateReport {
            scan: index,
            fallbacks,
            neff,
            resampled,
            survivors,
            inserted_cells,
        })
    }

    /// The first scan: one map from it at the first odometry pose, shared by
    /// every particle (its tiles are one allocation until a particle writes).
    pub fn initialize(&mut self, index: usize, odometry: Pose2, scan: &Scan) -> GridUpdateReport {
        let mut map = ProbabilityGrid::new(self.config.delta);
        let inserted = map
            .insert_scan(&odometry, scan, &self.insert)
            .map_or(0, |r| r.hits + r.misses);
        let path = Arc::new(PathNode {
            pose: odometry,
            scan: index,
            parent: None,
        });
        let m = self.config.particles;
        self.particles = (0..m)
            .map(|_| GridParticle {
                pose: odometry,
                log_weight: 0.0,
                map: map.clone(),
                path: Arc::clone(&path),
            })
            .collect();
        self.weights = vec![1.0 / m as f64; m];
        self.neff = m as f64;
        self.last_odometry = Some(odometry);
        self.proposals.clear();
        self.pending_delta = None;
        self.updates = 1;
        self.note_memory();
        GridUpdateReport {
            scan: index,
            fallbacks: 0,
            neff: m as f64,
            resampled: false,
            survivors: m,
            inserted_cells: inserted,
        }
    }

    /// Step 1: moves every particle by the proposal for the odometry
    /// `odometry` and the scan, and adds its log weight factor. Returns how
    /// many fell back to the odometry proposal.
    pub fn propose(&mut self, odometry: Pose2, scan: &Scan) -> usize {
        if !self.begin_proposals(odometry) {
            return 0;
        }
        let points = LikelihoodPoints::new(scan);
        let mut fallbacks = 0;
        while let Some(p) = self.propose_next(&points) {
            fallbacks += usize::from(p.fell_back);
        }
        fallbacks
    }

    /// Step 1 one particle at a time (the lesson shows each scan match):
    /// starts an update for the scan taken at `odometry`. Returns false (and
    /// changes nothing) before the first scan. Then
    /// [`propose_next`](Self::propose_next) moves the particles in order.
    pub fn begin_proposals(&mut self, odometry: Pose2) -> bool {
        let Some(last) = self.last_odometry else {
            return false;
        };
        self.last_odometry = Some(odometry);
        let delta = last.between(&odometry);
        self.pending_delta = Some(Pose2::new(delta.x, delta.y, wrap_angle(delta.theta)));
        self.proposals.clear();
        true
    }

    /// Moves the next particle (in index order) by its proposal for the scan
    /// whose end points are `points`, and returns what it did; `None` when
    /// every particle has moved (or no update was begun).
    pub fn propose_next(&mut self, points: &LikelihoodPoints) -> Option<&ParticleProposal> {
        let delta = self.pending_delta?;
        let i = self.proposals.len();
        let Some(p) = self.particles.get_mut(i) else {
            self.pending_delta = None;
            return None;
        };
        let prior = MotionPrior::new(&self.config, p.pose, delta);
        let improved = match self.config.proposal {
            Proposal::ScanMatch => improved_proposal(
                &p.map,
                &self.lookup,
                points,
                &prior,
                &self.config.matcher(),
                &self.config,
            ),
            Proposal::Odometry => None,
        };
        let proposal = match improved {
            Some((matched, gaussian)) => {
                let pose = draw_gaussian(&gaussian, &mut self.rng);
                ParticleProposal {
                    predicted: prior.mean,
                    matched: Some(matched),
                    gaussian: Some(gaussian),
                    pose,
                    log_factor: gaussian.log_eta,
                    fell_back: false,
                }
            }
            None => {
                let fell_back = self.config.proposal == Proposal::ScanMatch;
                let pose = draw_from_motion(&self.config, p.pose, delta, &mut self.rng);
                let (l, _) = scan_log_likelihood(&p.map, points, &pose, &self.config);
                ParticleProposal {
                    predicted: prior.mean,
                    matched: None,
                    gaussian: None,
                    pose,
                    log_factor: l,
                    fell_back,
                }
            }
        };
        p.pose = proposal.pose;
        if proposal.log_factor.is_finite() {
            p.log_weight += proposal.log_factor;
        }
        self.fallbacks += usize::from(proposal.fell_back);
        if i + 1 == self.particles.len() {
            self.pending_delta = None;
        }
        self.proposals.push(proposal);
        self.proposals.last()
    }

    /// Whether an update's proposals are under way (begun, not every particle
    /// moved yet).
    pub fn proposing(&self) -> bool {
        self.pending_delta.is_some()
    }

    /// Step 2: the normalized weights, gmapping's smoothing
    /// `w_i ∝ exp((ℓ_i − ℓ_max) / (ogain · M))`, and `N_eff = 1 / Σ w_i²`.
    pub fn normalize(&mut self) -> f64 {
        let m = self.particles.len().max(1);
        let gain = 1.0 / (self.config.ogain * m as f64);
        let lmax = self
            .particles
            .iter()
            .map(|p| p.log_weight)
            .filter(|l| l.is_finite())
            .fold(f64::NEG_INFINITY, f64::max);
        self.weights = self
            .particles
            .iter()
            .map(|p| {
                if lmax.is_finite() && p.log_weight.is_finite() {
                    math::exp(gain * (p.log_weight - lmax))
                } else {
                    1.0
                }
            })
            .collect();
        let total: f64 = self.weights.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            self.weights = vec![1.0 / m as f64; self.particles.len()];
        } else {
            for w in &mut self.weights {
                *w /= total;
            }
        }
        self.neff = effective_sample_size(&self.weights);
        self.neff
    }

    /// Step 3: low-variance resampling if `N_eff < resample_threshold · M`.
    /// Returns whether it resampled and how many distinct particles survived.
    pub fn resample_if_needed(&mut self) -> (bool, usize) {
        let m = self.particles.len();
        if !self.resample_due() {
            return (false, m);
        }
        let mut indices = Vec::with_capacity(m);
        resample_indices(
            Resampler::LowVariance,
            &self.weights,
            m,
            &mut self.rng,
            &mut indices,
        );
        let mut survivors = indices.clone();
        survivors.dedup();
        let old = std::mem::take(&mut self.particles);
        self.particles = indices
            .iter()
            .map(|&i| {
                let mut p = old[i.min(m - 1)].clone();
                p.log_weight = 0.0;
                p
            })
            .collect();
        self.weights = vec![1.0 / m as f64; m];
        self.resamplings += 1;
        (true, survivors.len())
    }

    /// Step 4: every particle inserts the scan at its pose and extends its
    /// path. Returns the cells the best particle's insertion updated.
    pub fn update_maps(&mut self, index: usize, scan: &Scan) -> usize {
        let best = self.best_index();
        let mut best_cells = 0;
        for (i, p) in self.particles.iter_mut().enumerate() {
            let cells = p
                .map
                .insert_scan(&p.pose, scan, &self.insert)
                .map_or(0, |r| r.hits + r.misses);
            if i == best {
                best_cells = cells;
            }
            p.path = Arc::new(PathNode {
                pose: p.pose,
                scan: index,
                parent: Some(Arc::clone(&p.path)),
            });
        }
        self.updates += 1;
        self.note_memory();
        best_cells
    }

    fn note_memory(&mut self) {
        self.peak_memory = self.peak_memory.max(self.memory_bytes());
    }
}

/// The improved proposal for one particle: the scan matched against its map
/// from the odometry prediction, then the Gaussian around the match. `None`
/// (fall back to odometry) when the scan has no end points, the match fails,
/// or no end point finds an occupied cell of the map at the match.
fn improved_proposal(
    map: &ProbabilityGrid,
    lookup: &ProbabilityLookup,
    points: &LikelihoodPoints,
    prior: &MotionPrior,
    matcher: &ScanToMapParams,
    config: &GridFastSlamConfig,
) -> Option<(Pose2, ProposalGaussian)> {
    if points.is_empty() {
        return None;
    }
    let (m, _) = match_scan_to_map(map, lookup, points.points(), prior.mean, matcher)?;
    if !m.pose.is_finite() {
        return None;
    }
    let (_, found) = scan_log_likelihood(map, points, &m.pose, config);
    if found == 0 {
        return None;
    }
    let g = fit_proposal(map, points, m.pose, prior, config)?;
    (g.mean.is_finite() && g.log_eta.is_finite() && g.covariance.iter().all(|v| v.is_finite()))
        .then_some((m.pose, g))
}

#[cfg(test)]
mod tests;
