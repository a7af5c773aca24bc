//! Recovery from localization failure on top of [`Mcl`]:
//!
//! - **AMCL**, Augmented MCL (thesis `000` Algorithm 9; Probabilistic Robotics
//!   Table 8.3): short- and long-term averages `w_fast`, `w_slow` of the
//!   average likelihood `w_avg`; at resampling each particle is replaced by a
//!   uniform random pose over the free cells with probability
//!   `max(0, 1 − w_fast / w_slow)`. As ROS amcl: `w_avg = Σ wᵢ p(z | xᵢ)` with
//!   the prior weights `wᵢ` (the table's plain mean assumes they are uniform,
//!   which holds only when the filter resamples at every update); injection
//!   follows `w_fast < w_slow` whatever the rates (with `α_slow = 0` the long
//!   average stays at its first value); both averages restart from the next
//!   `w_avg` after an update that injected.
//! - **CMCL**, Costmap MCL (thesis Algorithm 10): after the motion step, a
//!   particle whose straight path from its previous pose enters an invalid cell
//!   of the costmap (the map inflated by the robot radius, thesis Sec. 5.1.3;
//!   checked every half cell) is regenerated uniformly over the valid cells,
//!   before weighting.
//! - **ACMCL** (thesis Algorithm 11): both. Regenerated particles are left out
//!   of `w_avg`. Erratum (seeds README): the listing updates `w_slow` and
//!   `w_fast` inside the particle loop; they are updated once per filter step,
//!   after the loop, from the average weight of the valid particles.
//!   Departure from the listing: Algorithm 11 sets the regenerated particles
//!   apart as `X_c`, unweighted and not resampled, and returns `⟨X_t, X_c⟩`,
//!   which leaves the next set's size (`M + |X_c|`?) and the weights of `X_c`
//!   undefined. Here, as in CMCL (Algorithm 10, line 8) and in amcl, on which
//!   the thesis built it, every particle of the set is weighted by the scan
//!   and takes part in resampling, so the set stays `M` particles with
//!   normalized weights; a regenerated particle that lands near the truth
//!   survives resampling by its weight, as any other.
//!
//! `w_slow` and `w_fast` are kept as logarithms (a likelihood over 30 beams is
//! far below the smallest `f64`); the exponential smoothing
//! `w ← w + α (w_avg − w)` is done with log-sum-exp.

use super::mcl::{LocalizationMap, Mcl, MclConfig, ParticleFlag};
use super::{PredictReport, ResampleReport, Scan, WeightReport};
use crate::belief::{ParticleBelief, PoseBelief};
use crate::geometry::Pose2;
use crate::grid::{Costmap, FreeCells};
use crate::math;
use nalgebra::Matrix3;
use rand::Rng;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Which recovery a filter uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Recovery {
    /// None: plain MCL (thesis Algorithm 8).
    #[default]
    None,
    /// Random-particle injection (AMCL, thesis Algorithm 9).
    Augmented,
    /// Costmap regeneration (CMCL, thesis Algorithm 10).
    Costmap,
    /// Both (ACMCL, thesis Algorithm 11).
    AugmentedCostmap,
}

impl Recovery {
    /// The estimator's name: `mcl`, `amcl`, `cmcl`, `acmcl`.
    pub fn name(self) -> &'static str {
        match self {
            Recovery::None => "mcl",
            Recovery::Augmented => "amcl",
            Recovery::Costmap => "cmcl",
            Recovery::AugmentedCostmap => "acmcl",
        }
    }

    /// Parses a name as written by [`Recovery::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        [
            Recovery::None,
            Recovery::Augmented,
            Recovery::Costmap,
            Recovery::AugmentedCostmap,
        ]
        .into_iter()
        .find(|r| r.name() == name)
    }

    /// Whether it injects random particles (Augmented MCL's `w_slow`/`w_fast`).
    pub fn injects(self) -> bool {
        matches!(self, Recovery::Augmented | Recovery::AugmentedCostmap)
    }

    fn regenerates(self) -> bool {
        matches!(self, Recovery::Costmap | Recovery::AugmentedCostmap)
    }
}

/// The smoothing rates of Augmented MCL (amcl `recovery_alpha_slow`,
/// `recovery_alpha_fast`; 0.001 and 0.1 as both the thesis and the Nav2
/// documentation recommend; ROS amcl's defaults 0 disable injection).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecoveryAlphas {
    /// Rate of the long-term average, `0 < α_slow ≪ α_fast`.
    pub alpha_slow: f64,
    /// Rate of the short-term average.
    pub alpha_fast: f64,
}

impl Default for RecoveryAlphas {
    fn default() -> Self {
        Self {
            alpha_slow: 0.001,
            alpha_fast: 0.1,
        }
    }
}

/// What recovery did in the latest update.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RecoveryReport {
    /// `ln w_avg` of the latest weighting (valid particles only for ACMCL).
    pub log_w_avg: Option<f64>,
    /// `ln w_slow`.
    pub log_w_slow: Option<f64>,
    /// `ln w_fast`.
    pub log_w_fast: Option<f64>,
    /// `max(0, 1 − w_fast / w_slow)`.
    pub injection_probability: f64,
    /// Particles injected at the latest resampling.
    pub injected: usize,
    /// Particles regenerated at the latest prediction.
    pub regenerated: usize,
}

/// MCL with an optional recovery (AMCL, CMCL, ACMCL). Owns its random stream
/// through the inner [`Mcl`].
#[derive(Clone, Debug)]
pub struct RecoveringMcl {
    kind: Recovery,
    mcl: Mcl,
    alphas: RecoveryAlphas,
    log_w_slow: Option<f64>,
    log_w_fast: Option<f64>,
    costmap: Option<Arc<Costmap>>,
    valid_cells: Option<Arc<FreeCells>>,
    report: RecoveryReport,
    notices: Vec<String>,
}

/// `ln w_avg` with `w_avg = Σ wᵢ p(z | xᵢ) / Σ wᵢ` from pairs `(ln wᵢ, ln p(z | xᵢ))`
/// of prior (normalized) weight and scan likelihood: the likelihood of the scan
/// under the predicted belief, as amcl's `pf_update_sensor` sums it before
/// normalizing. With uniform prior weights (resampling at every update) it is
/// the plain mean of Probabilistic Robotics Table 8.3, line 8; with
/// `resample_interval > 1` or selective resampling the prior weights matter.
/// ACMCL passes only its valid particles (renormalized over them). `None` if no
/// pair has weight and likelihood.
fn log_weighted_average(pairs: impl Iterator<Item = (f64, f64)>) -> Option<f64> {
    let pairs: Vec<(f64, f64)> = pairs.collect();
    let top = pairs
        .iter()
        .map(|&(w, l)| w + l)
        .fold(f64::NEG_INFINITY, f64::max);
    let top_w = pairs
        .iter()
        .map(|&(w, _)| w)
        .fold(f64::NEG_INFINITY, f64::max);
    if !top.is_finite() || !top_w.is_finite() {
        return None;
    }
    let num: f64 = pairs.iter().map(|&(w, l)| math::exp(w + l - top)).sum();
    let den: f64 = pairs.iter().map(|&(w, _)| math::exp(w - top_w)).sum();
    Some(top + math::ln(num) - top_w - math::ln(den))
}

/// `ln((1 − α) e^a + α e^b)`.
fn log_smooth(a: f64, b: f64, alpha: f64) -> f64 {
    if alpha >= 1.0 {
        return b;
    }
    let x = math::ln(1.0 - alpha) + a;
    let y = if alpha > 0.0 {
        math::ln(alpha) + b
    } else {
        f64::NEG_INFINITY
    };
    let m = x.max(y);
    if m == f64::NEG_INFINITY {
        return m;
    }
    m + math::ln(math::exp(x - m) + math::exp(y - m))
}

impl RecoveringMcl {
    /// A filter of kind `kind`. `costmap` is the map inflated by the robot
    /// radius (needed by CMCL and ACMCL; without one, or if it has no valid
    /// cell, they regenerate over the free cells, with a notice).
    pub fn new(
        kind: Recovery,
        config: MclConfig,
        alphas: RecoveryAlphas,
        map: Arc<LocalizationMap>,
        costmap: Option<Arc<Costmap>>,
        seed: u64,
    ) -> Self {
        let mcl = Mcl::new(config, map, seed);
        let mut notices = Vec::new();
        let mut alphas = alphas;
        for (name, a) in [
            ("recovery_alpha_slow", &mut alphas.alpha_slow),
            ("recovery_alpha_fast", &mut alphas.alpha_fast),
        ] {
            if !(0.0..=1.0).contains(a) {
                let c = if *a > 1.0 { 1.0 } else { 0.0 };
                notices.push(format!("{name} {a} clamped to {c}"));
                *a = c;
            }
        }
        let valid_cells = if kind.regenerates() {
            match &costmap {
                Some(c) if c.valid_count() > 0 => Some(Arc::new(c.valid_cells())),
                Some(_) => {
                    notices.push(
                        "the robot radius leaves no valid cell in the costmap: particles are regenerated over the free cells".to_owned(),
                    );
                    None
                }
                None => {
                    notices.push(
                        "no costmap given: particles are regenerated over the free cells"
                            .to_owned(),
                    );
                    None
                }
            }
        } else {
            None
        };
        Self {
            kind,
            mcl,
            alphas,
            log_w_slow: None,
            log_w_fast: None,
            costmap: if kind.regenerates() { costmap } else { None },
            valid_cells,
            report: RecoveryReport::default(),
            notices,
        }
    }

    /// The kind of recovery.
    pub fn kind(&self) -> Recovery {
        self.kind
    }

    /// The inner MCL (particles, estimate, N_eff for drawing).
    pub fn mcl(&self) -> &Mcl {
        &self.mcl
    }

    /// The inner MCL, mutable (initialization buttons).
    pub fn mcl_mut(&mut self) -> &mut Mcl {
        &mut self.mcl
    }

    /// What recovery did in the latest update.
    pub fn report(&self) -> &RecoveryReport {
        &self.report
    }

    /// Messages about clamped parameters and fallbacks.
    pub fn notices(&self) -> Vec<String> {
        self.mcl
            .notices()
            .iter()
            .chain(&self.notices)
            .cloned()
            .collect()
    }

    /// See [`Mcl::update_due`].
    pub fn update_due(&self, odom: Pose2) -> bool {
        self.mcl.update_due(odom)
    }

    /// Phase 1: the motion update, then (CMCL, ACMCL) regeneration of the
    /// particles whose motion entered an invalid cell.
    pub fn predict(&mut self, odom: Pose2) -> PredictReport {
        let before: Vec<Pose2> = if self.kind.regenerates() {
            self.mcl.particles().iter().map(|p| p.pose).collect()
        } else {
            Vec::new()
        };
        let report = self.mcl.predict(odom);
        self.report.regenerated = 0;
        self.report.injected = 0;
        if self.kind.regenerates() {
            let map = Arc::clone(self.mcl.map());
            let costmap = self.costmap.clone();
            let cells = self.valid_cells.clone();
            let (particles, rng) = self.mcl.particles_and_rng();
            let mut regenerated = 0;
            for (p, b) in particles.iter_mut().zip(&before) {
                let ok = match &costmap {
                    Some(c) if cells.is_some() => c.is_path_valid(b.x, b.y, p.pose.x, p.pose.y),
                    _ => map.grid().is_free_at(p.pose.x, p.pose.y),
                };
                if !ok {
                    let fresh = match &cells {
                        Some(c) => c.sample(rng),
                        None => map.free_cells().sample(rng),
                    };
                    if let Some(pose) = fresh {
                        p.pose = pose;
                        p.flag = ParticleFlag::Regenerated;
                        regenerated += 1;
                    }
                }
            }
            self.report.regenerated = regenerated;
        }
        report
    }

    /// Phase 2: weighting; for AMCL and ACMCL also the update of `w_slow` and
    /// `w_fast` from the average likelihood (ACMCL: of the particles not
    /// regenerated).
    pub fn weight(&mut self, scan: &Scan) -> WeightReport {
        let mut ll = Vec::new();
        let beams = self.mcl.weighting_log_likelihoods(scan, &mut ll);
        if self.kind.injects() {
            let skip_regenerated = self.kind == Recovery::AugmentedCostmap;
            if let Some(log_avg) = log_weighted_average(
                self.mcl
                    .particles()
                    .iter()
                    .zip(&ll)
                    .filter(|(p, _)| !(skip_regenerated && p.flag == ParticleFlag::Regenerated))
                    .map(|(p, &l)| (p.log_weight, l)),
            ) {
                self.log_w_slow = Some(match self.log_w_slow {
                    Some(s) => log_smooth(s, log_avg, self.alphas.alpha_slow),
                    None => log_avg,
                });
                self.log_w_fast = Some(match self.log_w_fast {
                    Some(f) => log_smooth(f, log_avg, self.alphas.alpha_fast),
                    None => log_avg,
                });
                self.report.log_w_avg = Some(log_avg);
            }
            self.report.log_w_slow = self.log_w_slow;
            self.report.log_w_fast = self.log_w_fast;
            // amcl injects whenever w_fast < w_slow, whatever the rates: with
            // α_slow = 0, w_slow stays at the first w_avg and w_fast falling
            // below it injects (with both 0 they never part).
            self.report.injection_probability = match (self.log_w_slow, self.log_w_fast) {
                (Some(s), Some(f)) => (1.0 - math::exp(f - s)).max(0.0),
                _ => 0.0,
            };
        }
        self.mcl.apply_log_likelihoods(&ll, scan, beams)
    }

    /// Phase 3: resampling; for AMCL and ACMCL each new particle is replaced by
    /// a uniform random pose with the injection probability.
    pub fn resample(&mut self) -> ResampleReport {
        let report = self.mcl.resample();
        self.report.injected = 0;
        let p = self.report.injection_probability;
        if self.kind.injects() && report.resampled && p > 0.0 {
            let map = Arc::clone(self.mcl.map());
            let (particles, rng) = self.mcl.particles_and_rng();
            let mut injected = 0;
            for particle in particles.iter_mut() {
                if rng.random::<f64>() < p
                    && let Some(pose) = map.free_cells().sample(rng)
                {
                    particle.pose = pose;
                    particle.flag = ParticleFlag::Injected;
                    injected += 1;
                }
            }
            self.report.injected = injected;
            // ROS amcl: restart both averages after injecting.
            self.log_w_slow = None;
            self.log_w_fast = None;
        }
        report
    }

    /// The fraction of particles injected or regenerated in the latest update.
    pub fn randomized_fraction(&self) -> f64 {
        let n = self.mcl.count().max(1);
        (self.report.injected + self.report.regenerated) as f64 / n as f64
    }
}

impl PoseBelief for RecoveringMcl {
    fn robot_pose(&self) -> Pose2 {
        self.mcl.robot_pose()
    }

    fn robot_covariance(&self) -> Matrix3<f64> {
        self.mcl.robot_covariance()
    }
}

impl ParticleBelief for RecoveringMcl {
    fn particle_count(&self) -> usize {
        self.mcl.particle_count()
    }

    fn particle_pose(&self, index: usize) -> Option<Pose2> {
        self.mcl.particle_pose(index)
    }

    fn particle_weight(&self, index: usize) -> f64 {
        self.mcl.particle_weight(index)
    }

    fn n_eff(&self) -> f64 {
        ParticleBelief::n_eff(&self.mcl)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::particle::mcl::tests::room;

    /// 60 readings all around from `pose`.
    fn scan_from(map: &LocalizationMap, pose: Pose2) -> Scan {
        crate::particle::mcl::tests::scan_from(map, pose, 60)
    }

    #[test]
    fn w_avg_weights_each_likelihood_by_the_prior_weight() {
        // amcl pf_update_sensor: w_avg = Σ wᵢ p(z | xᵢ) with the weights from
        // before the scan (not resampled since), not the plain mean.
        let map = room();
        let truth = Pose2::new(1.2, 2.5, 0.4);
        let config = MclConfig {
            particles: 200,
            likelihood_exponent: 0.05,
            ..Default::default()
        };
        let mut f = RecoveringMcl::new(
            Recovery::Augmented,
            config,
            RecoveryAlphas::default(),
            map.clone(),
            None,
            3,
        );
        f.mcl_mut().init_tracking(truth, [0.5, 0.5, 0.5]);
        let scan = scan_from(&map, truth);
        let mut ll = Vec::new();
        f.mcl.clone().weighting_log_likelihoods(&scan, &mut ll);
        // Prior weight 0.9 on the least likely particle, the rest shared.
        let worst = (0..ll.len())
            .min_by(|&a, &b| ll[a].total_cmp(&ll[b]))
            .unwrap();
        let rest = 0.1 / 199.0;
        for (i, p) in f.mcl_mut().particles_mut().iter_mut().enumerate() {
            p.weight = if i == worst { 0.9 } else { rest };
            p.log_weight = math::ln(p.weight);
        }
        let top = ll.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let weighted: f64 = f
            .mcl()
            .particles()
            .iter()
            .zip(&ll)
            .map(|(p, &l)| p.weight * math::exp(l - top))
            .sum();
        let expected = top + math::ln(weighted);
        let plain = top + math::ln(ll.iter().map(|&l| math::exp(l - top)).sum::<f64>() / 200.0);
        f.weight(&scan);
        let got = f.report().log_w_avg.unwrap();
        assert!((got - expected).abs() < 1e-9, "{got} vs {expected}");
        // The plain mean would be far off (the heavy particle is the worst).
        assert!(plain - expected > 1.0, "plain {plain} weighted {expected}");
        // Uniform weights: the plain mean.
        let mut g = RecoveringMcl::new(
            Recovery::Augmented,
            f.mcl().config().clone(),
            RecoveryAlphas::default(),
            map.clone(),
            None,
            3,
        );
        g.mcl_mut().init_tracking(truth, [0.5, 0.5, 0.5]);
        g.weight(&scan);
        assert!((g.report().log_w_avg.unwrap() - plain).abs() < 1e-9);
    }

    #[test]
    fn injection_with_alpha_slow_zero_follows_w_fast() {
        // amcl: w_slow stays at the first w_avg when α_slow = 0; a scan that
        // contradicts the cloud pulls w_fast below it, and the filter injects.
        let map = room();
        let truth = Pose2::new(1.2, 2.5, 0.4);
        let elsewhere = Pose2::new(3.0, 3.2, -2.0);
        let run = |alphas: RecoveryAlphas| {
            let mut f = RecoveringMcl::new(
                Recovery::Augmented,
                MclConfig {
                    particles: 300,
                    likelihood_exponent: 0.05,
                    ..Default::default()
                },
                alphas,
                map.clone(),
                None,
                5,
            );
            f.mcl_mut().init_tracking(truth, [0.05, 0.05, 0.05]);
            f.weight(&scan_from(&map, truth));
            let first = f.report().log_w_slow.unwrap();
            f.weight(&scan_from(&map, elsewhere));
            let r = *f.report();
            let resampled = f.resample();
            (first, r, resampled, f.report().injected)
        };
        let (first, r, resampled, injected) = run(RecoveryAlphas {
            alpha_slow: 0.0,
            alpha_fast: 0.5,
        });
        assert_eq!(r.log_w_slow, Some(first));
        // w_fast = 0.5 w_avg1 + 0.5 w_avg2 with w_avg2 ≪ w_avg1: about half.
        assert!(r.log_w_fast.unwrap() < first - 0.6, "{r:?}");
        let ratio = math::exp(r.log_w_avg.unwrap() - first);
        assert!(
            (r.injection_probability - (0.5 - 0.5 * ratio)).abs() < 1e-9,
            "{r:?}"
        );
        assert!(r.injection_probability > 0.49, "{r:?}");
        assert!(resampled.resampled);
        assert!(injected > 100, "{injected}");
        // Both rates 0: the averages never part, nothing is injected.
        let (_, r0, _, injected0) = run(RecoveryAlphas {
            alpha_slow: 0.0,
            alpha_fast: 0.0,
        });
        assert_eq!(r0.injection_probability, 0.0);
        assert_eq!(injected0, 0);
    }

    #[test]
    fn log_smoothing_is_the_exponential_smoother() {
        let (a, b, alpha) = (0.3_f64, 0.9_f64, 0.1);
        let direct = (1.0 - alpha) * a + alpha * b;
        assert!((math::exp(log_smooth(math::ln(a), math::ln(b), alpha)) - direct).abs() < 1e-12);
        // Far below the smallest double.
        let s = log_smooth(-2000.0, -2001.0, 0.5);
        let expected = -2000.0 + math::ln(0.5 + 0.5 * math::exp(-1.0));
        assert!((s - expected).abs() < 1e-9);
        assert_eq!(
            Recovery::from_name("acmcl"),
            Some(Recovery::AugmentedCostmap)
        );
    }
}
