//! FastSLAM 1.0 and 2.0: a Rao-Blackwellized particle filter for landmark SLAM
//! (slides `001`, "FastSLAM"; Montemerlo et al. 2002 and 2003; Probabilistic
//! Robotics Tables 13.1 and 13.3).
//!
//! Each particle carries one robot pose and one small EKF (2-vector mean, 2x2
//! covariance) per landmark: given the robot's path, the landmarks are independent
//! (slides, "Key Insight"), so `M` landmarks cost `M` 2x2 filters instead of one
//! `(3 + 2M)²` covariance.
//!
//! - **FastSLAM 1.0** samples each particle's new pose from the motion model with
//!   the control noise (slides, "Prediction Step"), updates the observed
//!   landmark's EKF at that pose and multiplies the particle's weight by the
//!   innovation likelihood `N(ν; 0, H Σ Hᵀ + Q)` (slides, "Measurement Update").
//!   A landmark seen for the first time is placed with the inverse observation
//!   model, `Σ = G_z Q G_zᵀ`, and the particle weighted with the constant `p₀`.
//! - **FastSLAM 2.0** samples the pose from the proposal that already includes
//!   the measurement (slides, "FastSLAM 2.0"): the motion prediction
//!   `N(g(x, u), V M Vᵀ)` corrected by the observation as a Kalman update of the
//!   pose with `S = H_x Σ_x H_xᵀ + H_m Σ_m H_mᵀ + Q`; the weight is the
//!   normalizer of that proposal, `N(ν; 0, S)` (Montemerlo et al. 2003, Eq. 19).
//!   SLAM Lab writes the pose update in covariance form, which is the same as the
//!   paper's information form `Σ = (H_xᵀ Q_j⁻¹ H_x + R⁻¹)⁻¹` but also works when
//!   the motion noise `R` is singular (two control noises drive three pose
//!   components). With several observations in one step the proposal is refined
//!   by each in turn; the pose is drawn as `μ + L ε` with one standard-normal `ε`
//!   per particle and step, so each measurement moves the draw towards where it
//!   says the robot is. Each landmark is updated at the draw of its own
//!   measurement; at the end of the step ([`FastSlam::resample`], or the next
//!   prediction) the step's landmark updates are re-derived at the final draw, so
//!   the particle is exactly "one pose from the full proposal, every landmark
//!   updated at it". This costs one extra 2x2 update per measurement.
//!
//! **Maximum-likelihood association** (unknown ids; Montemerlo et al. 2003,
//! Sec. 4; Probabilistic Robotics Table 13.2, lines 11-18): each particle
//! scores every landmark of its own map, `π_j = N(ν_j; 0, S_j)`, and takes
//! `ĉ = argmax{π_1, …, π_N, p₀}`: the landmark if its `π_j` beats the
//! new-landmark likelihood `p₀`, else a new landmark; the particle's weight is
//! multiplied by that maximum. The gate does not decide by itself: it sets
//! `p₀` (the likelihood of a measurement at squared distance `gate` under `Q`,
//! see [`association::new_landmark_log_likelihood`]), so a landmark is matched
//! when `d² < gate − ln(det S_j / det Q)`, a little inside the gate for an
//! uncertain landmark. Gating on `d²` alone would match a landmark just inside
//! the gate with a weight below the `p₀` a new landmark would have given.
//!
//! Weights are kept as logarithms ([`super::normalize_log_weights`]). If every
//! weight underflows to zero (or the lesson forces them to zero), the set falls
//! back to uniform weights and says so in its report. Landmark filters are
//! shared between particles until one of them changes (copy on write: a particle's
//! map is an `Arc` of a vector of `Arc`s), so resampling copies pointers, not maps.

use super::resample::{Resampler, resample_indices};
use super::weights::{WeightError, effective_sample_size, normalize_log_weights};
use crate::association::{
    self, AssociationDecision, AssociationMode, DEFAULT_GATE, log_gaussian, mahalanobis_squared,
};
use crate::belief::{ParticleBelief, PoseBelief};
use crate::geometry::{Pose2, wrap_angle};
use crate::math;
use crate::motion::{Control, MotionModel, RecordedMotion};
use crate::range_bearing::{self, MIN_RANGE, RangeBearing};
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use thiserror::Error;

/// The largest particle set a filter accepts (checked before allocating).
pub const MAX_PARTICLES: usize = 100_000;

/// Which FastSLAM.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum FastSlamVersion {
    /// Poses sampled from the motion model (Montemerlo et al. 2002).
    #[serde(rename = "1")]
    V1,
    /// Poses sampled from the measurement-informed proposal (Montemerlo et al. 2003).
    #[default]
    #[serde(rename = "2")]
    V2,
}

impl FastSlamVersion {
    /// The estimator name used in URLs and JSON ("fastslam1", "fastslam2").
    pub fn name(self) -> &'static str {
        match self {
            FastSlamVersion::V1 => "fastslam1",
            FastSlamVersion::V2 => "fastslam2",
        }
    }

    /// `1` or `2`.
    pub fn number(self) -> u8 {
        match self {
            FastSlamVersion::V1 => 1,
            FastSlamVersion::V2 => 2,
        }
    }

    /// The version for `1` or `2`.
    pub fn from_number(n: u8) -> Option<Self> {
        match n {
            1 => Some(FastSlamVersion::V1),
            2 => Some(FastSlamVersion::V2),
            _ => None,
        }
    }
}

/// The noise the filter assumes (standard deviations, as the simulator's scenario
/// gives them).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FastSlamNoise {
    /// Executed forward speed, m/s.
    pub v_std: f64,
    /// Executed turn rate, rad/s.
    pub w_std: f64,
    /// Range, metres.
    pub range_std: f64,
    /// Bearing, radians.
    pub bearing_std: f64,
}

impl Default for FastSlamNoise {
    fn default() -> Self {
        Self {
            v_std: 0.1,
            w_std: std::f64::consts::PI / 18.0,
            range_std: 0.5,
            bearing_std: std::f64::consts::PI / 18.0,
        }
    }
}

/// When [`FastSlam::resample`] actually resamples.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum ResamplePolicy {
    /// Every time it is called (once per filter step): the slides' particle filter.
    EveryStep,
    /// Only when `N_eff < threshold · M` (slides, "Adaptive resampling", with
    /// threshold ½). `threshold` is in `[0, 1]`; 0 never resamples.
    WhenNeffBelow {
        /// The fraction of the particle count.
        threshold: f64,
    },
}

impl Default for ResamplePolicy {
    fn default() -> Self {
        ResamplePolicy::WhenNeffBelow { threshold: 0.5 }
    }
}

/// Everything a FastSLAM filter is configured with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FastSlamConfig {
    /// 1.0 or 2.0.
    pub version: FastSlamVersion,
    /// Number of particles `M`, `1..=MAX_PARTICLES`.
    pub particles: usize,
    /// The motion model particles move with.
    pub motion_model: MotionModel,
    /// The noise it assumes.
    pub noise: FastSlamNoise,
    /// Known ids or per-particle maximum likelihood.
    pub association: AssociationMode,
    /// Resampling method.
    pub resampler: Resampler,
    /// When to resample.
    pub resample: ResamplePolicy,
    /// Seed of the filter's own random generator.
    pub seed: u64,
}

impl Default for FastSlamConfig {
    fn default() -> Self {
        Self {
            version: FastSlamVersion::V2,
            particles: 100,
            motion_model: MotionModel::ExactArc,
            noise: FastSlamNoise::default(),
            association: AssociationMode::KnownIds,
            resampler: Resampler::LowVariance,
            resample: ResamplePolicy::default(),
            seed: 1,
        }
    }
}

/// Why a FastSLAM filter could not be built or a phase could not run. The filter
/// is unchanged after an error.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum FastSlamError {
    /// A particle filter needs particles.
    #[error("FastSLAM needs at least one particle (got 0)")]
    NoParticles,
    /// More particles than [`MAX_PARTICLES`].
    #[error("{count} particles is more than the {MAX_PARTICLES} FastSLAM accepts")]
    TooManyParticles {
        /// The requested count.
        count: usize,
    },
    /// A noise standard deviation or the gate is not finite and positive.
    #[error("parameter {name} = {value} is not allowed (it must be finite and positive)")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// The adaptive-resampling threshold is outside `[0, 1]` or NaN.
    #[error("the resampling threshold {value} must be a fraction of the particle count in [0, 1]")]
    ThresholdOutOfRange {
        /// The rejected value.
        value: f64,
    },
    /// A control or time step is NaN, infinite, or (time step) negative.
    #[error(
        "control (v = {v}, w = {w}) must be finite and the time step dt = {dt} finite and not negative"
    )]
    InvalidControl {
        /// Forward speed.
        v: f64,
        /// Turn rate.
        w: f64,
        /// Time step.
        dt: f64,
    },
    /// A recorded motion (odometry reading, car input) cannot move the particles.
    #[error("{0}")]
    InvalidMotion(String),
    /// A landmark given with the map is already in it, or not a position and a covariance.
    #[error("landmark {id} cannot be added to the map: {why}")]
    InvalidLandmark {
        /// The landmark's id.
        id: usize,
        /// Why.
        why: &'static str,
    },
    /// A measurement is NaN or infinite.
    #[error("measurement (range {range}, bearing {bearing}) must be finite")]
    InvalidMeasurement {
        /// Range.
        range: f64,
        /// Bearing.
        bearing: f64,
    },
}

/// One measurement with the id the sensor reports. With
/// [`AssociationMode::MaximumLikelihood`] the id is ignored.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LandmarkObservation {
    /// The sensor's landmark id.
    pub id: usize,
    /// `[range, bearing]`.
    pub z: RangeBearing,
}

/// One landmark's EKF inside one particle.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LandmarkEkf {
    /// The sensor's id (known association) or the particle's own label (maximum
    /// likelihood: 0, 1, 2, … in order of discovery).
    pub id: usize,
    /// Mean position, metres.
    pub mean: Vector2<f64>,
    /// 2x2 covariance.
    pub covariance: Matrix2<f64>,
    /// How many measurements it has absorbed.
    pub observations: u32,
}

/// A particle's map: shared until written (copy on write at two levels).
type SharedMap = Arc<Vec<Arc<LandmarkEkf>>>;

/// A landmark update of this step, kept so FastSLAM 2.0 can re-derive it at a new
/// pose draw.
#[derive(Clone, Debug)]
struct Replay {
    slot: usize,
    z: RangeBearing,
    /// The filter before this step's first update of it; `None` for a landmark
    /// this step created.
    prior: Option<Arc<LandmarkEkf>>,
}

/// FastSLAM 2.0's proposal for the current step.
#[derive(Clone, Debug)]
struct Proposal {
    mean: Vector3<f64>,
    covariance: Matrix3<f64>,
    /// The standard-normal draw of this step.
    noise: Vector3<f64>,
    replays: Vec<Replay>,
}

#[derive(Clone, Debug)]
struct Particle {
    pose: Pose2,
    /// Log weight, up to a constant shared by all particles.
    log_weight: f64,
    map: SharedMap,
    /// The next label for a landmark this particle starts (maximum likelihood).
    next_id: usize,
    proposal: Option<Proposal>,
}

/// A particle as the lesson draws it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleView {
    /// Its pose.
    pub pose: Pose2,
    /// Its normalized weight.
    pub weight: f64,
    /// How many landmarks its map has.
    pub landmarks: usize,
}

/// What a prediction did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticlePredictReport {
    /// The control used.
    pub control: Control,
    /// The root-mean-square distance of the particles from their weighted mean
    /// position after the move, metres.
    pub spread: f64,
}

/// What one measurement update did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleUpdateReport {
    /// The particle with the largest weight after the update.
    pub best_particle: usize,
    /// How much that particle's log weight changed (the log likelihood of the
    /// measurement under it).
    pub best_log_weight_change: f64,
    /// That particle's association decision (`None` when it could not use the
    /// measurement, e.g. a landmark on top of it).
    pub decision: Option<AssociationDecision>,
    /// How many particles started a new landmark with this measurement.
    pub new_landmark_particles: usize,
    /// `N_eff` after the update.
    pub n_eff: f64,
    /// True when every weight had underflowed to zero and the set was reset to
    /// uniform weights.
    pub recovered: bool,
}

/// What a resampling call did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResampleReport {
    /// `N_eff` before resampling.
    pub n_eff_before: f64,
    /// The `N_eff` below which the policy resamples (`threshold · M`; `M` plus one
    /// for [`ResamplePolicy::EveryStep`]).
    pub n_eff_threshold: f64,
    /// Whether it resampled.
    pub resampled: bool,
    /// How many different particles survived (the particle count when it did not
    /// resample).
    pub distinct_survivors: usize,
    /// True when every weight was zero and the set was resampled uniformly.
    pub recovered: bool,
}

/// A FastSLAM 1.0 or 2.0 filter, phase by phase: [`predict`](Self::predict) (sample),
/// [`update`](Self::update) once per measurement (weight), [`resample`](Self::resample).
#[derive(Clone, Debug)]
pub struct FastSlam {
    config: FastSlamConfig,
    particles: Vec<Particle>,
    /// Normalized weights, kept in step with the log weights.
    weights: Vec<f64>,
    rng: ChaCha8Rng,
    control_covariance: Matrix2<f64>,
    measurement_covariance: Matrix2<f64>,
    /// `ln p₀`, the weight factor of a new landmark.
    new_landmark_log_likelihood: f64,
    recoveries: u64,
    last_notice: Option<String>,
    indices: Vec<usize>,
}

fn check_count(count: usize) -> Result<(), FastSlamError> {
    match count {
        0 => Err(FastSlamError::NoParticles),
        c if c > MAX_PARTICLES => Err(FastSlamError::TooManyParticles { count: c }),
        _ => Ok(()),
    }
}

fn check_policy(policy: ResamplePolicy) -> Result<(), FastSlamError> {
    match policy {
        ResamplePolicy::EveryStep => Ok(()),
        ResamplePolicy::WhenNeffBelow { threshold } if (0.0..=1.0).contains(&threshold) => Ok(()),
        ResamplePolicy::WhenNeffBelow { threshold } => {
            Err(FastSlamError::ThresholdOutOfRange { value: threshold })
        }
    }
}

impl FastSlam {
    /// A filter whose particles all start at `start` (the map's origin) with
    /// empty maps and equal weights.
    pub fn new(config: FastSlamConfig, start: Pose2) -> Result<Self, FastSlamError> {
        check_count(config.particles)?;
        check_policy(config.resample)?;
        let n = config.noise;
        for (name, value) in [
            ("v_std", n.v_std),
            ("w_std", n.w_std),
            ("range_std", n.range_std),
            ("bearing_std", n.bearing_std),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(FastSlamError::InvalidParameter { name, value });
            }
        }
        let gate = match config.association {
            AssociationMode::KnownIds => DEFAULT_GATE,
            AssociationMode::MaximumLikelihood { gate } => gate,
        };
        if !(gate.is_finite() && gate > 0.0) {
            return Err(FastSlamError::InvalidParameter {
                name: "gate",
                value: gate,
            });
        }
        if !start.is_finite() {
            return Err(FastSlamError::InvalidParameter {
                name: "start pose",
                value: f64::NAN,
            });
        }
        let measurement_covariance =
            Matrix2::new(n.range_std.powi(2), 0.0, 0.0, n.bearing_std.powi(2));
        let particle = Particle {
            pose: start,
            log_weight: 0.0,
            map: Arc::new(Vec::new()),
            next_id: 0,
            proposal: None,
        };
        Ok(Self {
            particles: vec![particle; config.particles],
            weights: vec![1.0 / config.particles as f64; config.particles],
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            control_covariance: Matrix2::new(n.v_std.powi(2), 0.0, 0.0, n.w_std.powi(2)),
            measurement_covariance,
            new_landmark_log_likelihood: association::new_landmark_log_likelihood(
                gate,
                &measurement_covariance,
            ),
            recoveries: 0,
            last_notice: None,
            indices: Vec::new(),
            config,
        })
    }

    /// The configuration (the particle count follows [`set_particle_count`](Self::set_particle_count)).
    pub fn config(&self) -> &FastSlamConfig {
        &self.config
    }

    /// "fastslam1" or "fastslam2".
    pub fn name(&self) -> &'static str {
        self.config.version.name()
    }

    /// Switches the resampling method (takes effect at the next resampling).
    pub fn set_resampler(&mut self, resampler: Resampler) {
        self.config.resampler = resampler;
    }

    /// Switches when to resample. A threshold outside `[0, 1]` is refused.
    pub fn set_resample_policy(&mut self, policy: ResamplePolicy) -> Result<(), FastSlamError> {
        check_policy(policy)?;
        self.config.resample = policy;
        Ok(())
    }

    /// Changes the number of particles by drawing `count` from the current set
    /// with the configured resampler (so the distribution is kept); the new set
    /// has equal weights. 0 or more than [`MAX_PARTICLES`] is refused.
    pub fn set_particle_count(&mut self, count: usize) -> Result<(), FastSlamError> {
        check_count(count)?;
        self.draw(count);
        self.config.particles = count;
        Ok(())
    }

    /// Prediction (sampling): moves every particle by `control` for `dt` seconds.
    ///
    /// FastSLAM 1.0 draws each particle's executed control `u + N(0, M)` and moves
    /// it with the motion model (slides, "Prediction Step"). FastSLAM 2.0 starts
    /// the proposal `N(g(x, u), V M Vᵀ)` (`V = ∂g/∂u`) and draws the pose from it;
    /// the measurements of this step then refine it. A robot told to stop
    /// (`v = w = 0`) gets no noise, as in the simulator.
    pub fn predict(
        &mut self,
        control: &Control,
        dt: f64,
    ) -> Result<ParticlePredictReport, FastSlamError> {
        if !control.is_finite() || !dt.is_finite() || dt < 0.0 {
            return Err(FastSlamError::InvalidControl {
                v: control.v,
                w: control.w,
                dt,
            });
        }
        let moving = *control != Control::default();
        let model = self.config.motion_model;
        let (v_std, w_std) = (self.config.noise.v_std, self.config.noise.w_std);
        for p in &mut self.particles {
            finish_step(p, &self.measurement_covariance);
            match self.config.version {
                FastSlamVersion::V1 => {
                    let executed = if moving {
                        Control::new(
                            control.v + v_std * normal(&mut self.rng),
                            control.w + w_std * normal(&mut self.rng),
                        )
                    } else {
                        *control
                    };
                    p.pose = model.predict(&p.pose, &executed, dt);
                    p.proposal = None;
                }
                FastSlamVersion::V2 => {
                    let step = model.step(&p.pose, control, dt);
                    let covariance = if moving {
                        step.jacobian_control
                            * self.control_covariance
                            * step.jacobian_control.transpose()
                    } else {
                        Matrix3::zeros()
                    };
                    let proposal = Proposal::new(step.pose.to_vector(), covariance, &mut self.rng);
                    p.pose = proposal.draw();
                    p.proposal = Some(proposal);
                }
            }
        }
        let spread = self.spread();
        Ok(ParticlePredictReport {
            control: *control,
            spread,
        })
    }

    /// Prediction with a motion as a data set records it ([`RecordedMotion`]): the
    /// same sampling as [`predict`](Self::predict) with the motion's model and
    /// input noise. FastSLAM 1.0 draws each particle's input `u + N(0, diag(σ²))`
    /// and moves it by `x ⊕ δ(u)`; FastSLAM 2.0 starts the proposal
    /// `N(x ⊕ δ(u), G diag(σ²) Gᵀ)`. A robot standing still gets no noise.
    pub fn predict_recorded(
        &mut self,
        motion: &RecordedMotion,
    ) -> Result<ParticlePredictReport, FastSlamError> {
        motion
            .validate()
            .map_err(|e| FastSlamError::InvalidMotion(e.to_string()))?;
        let k = motion.input_dim();
        let std = motion.input_std();
        let moving = !motion.is_still();
        for p in &mut self.particles {
            finish_step(p, &self.measurement_covariance);
            match self.config.version {
                FastSlamVersion::V1 => {
                    let mut noise = [0.0; 3];
                    if moving {
                        for i in 0..k {
                            noise[i] = std[i] * normal(&mut self.rng);
                        }
                    }
                    // A failed move (a draw beyond the car's steering limit) keeps the pose.
                    if let Ok(pose) = motion.apply(&p.pose, &noise) {
                        p.pose = pose;
                    }
                    p.proposal = None;
                }
                FastSlamVersion::V2 => {
                    let step = motion
                        .step(&p.pose)
                        .map_err(|e| FastSlamError::InvalidMotion(e.to_string()))?;
                    let g = step.jacobian_input;
                    let covariance = g * step.input_covariance * g.transpose();
                    let proposal = Proposal::new(step.pose.to_vector(), covariance, &mut self.rng);
                    p.pose = proposal.draw();
                    p.proposal = Some(proposal);
                }
            }
        }
        let spread = self.spread();
        Ok(ParticlePredictReport {
            control: motion.velocity().unwrap_or_default(),
            spread,
        })
    }

    /// Adds landmark `id` at `position` with `covariance` to every particle's map:
    /// a map given before the run (localization with a known map). Refused when a
    /// particle has `id` already, or the numbers are not a position and a
    /// covariance. With maximum-likelihood association the particles' own labels
    /// continue above `id`.
    pub fn insert_landmark(
        &mut self,
        id: usize,
        position: Vector2<f64>,
        covariance: Matrix2<f64>,
    ) -> Result<(), FastSlamError> {
        let finite = position
            .iter()
            .chain(covariance.iter())
            .all(|v| v.is_finite());
        let psd = covariance[(0, 1)] == covariance[(1, 0)]
            && covariance[(0, 0)] >= 0.0
            && covariance[(1, 1)] >= 0.0
            && covariance[(0, 0)] * covariance[(1, 1)] >= covariance[(0, 1)].powi(2);
        if !(finite && psd) {
            return Err(FastSlamError::InvalidLandmark {
                id,
                why: "its position or covariance is not finite, or the covariance not symmetric positive semi-definite",
            });
        }
        if self
            .particles
            .iter()
            .any(|p| p.map.iter().any(|l| l.id == id))
        {
            return Err(FastSlamError::InvalidLandmark {
                id,
                why: "it is already in the map",
            });
        }
        let landmark = Arc::new(LandmarkEkf {
            id,
            mean: position,
            covariance,
            observations: 0,
        });
        for p in &mut self.particles {
            Arc::make_mut(&mut p.map).push(Arc::clone(&landmark));
            p.next_id = p.next_id.max(id.saturating_add(1));
        }
        Ok(())
    }

    /// Measurement update (importance weighting) with one measurement: every
    /// particle associates it (by id, or by maximum likelihood in its own map),
    /// updates or creates that landmark's EKF and multiplies its weight by the
    /// measurement's likelihood (see the module documentation for 1.0 and 2.0).
    pub fn update(
        &mut self,
        observation: &LandmarkObservation,
    ) -> Result<ParticleUpdateReport, FastSlamError> {
        let z = observation.z;
        // A negative range is a legitimate noisy reading of a landmark close by
        // (Gaussian range noise); only a first sighting needs a positive one.
        if !z.is_finite() {
            return Err(FastSlamError::InvalidMeasurement {
                range: z.range,
                bearing: z.bearing,
            });
        }
        let ctx = Context {
            version: self.config.version,
            association: self.config.association,
            q: self.measurement_covariance,
            new_log: self.new_landmark_log_likelihood,
        };
        let mut outcomes = Vec::with_capacity(self.particles.len());
        for p in &mut self.particles {
            let (delta, decision) = ctx.update_particle(p, observation.id, &z);
            let delta = if delta.is_nan() {
                f64::NEG_INFINITY
            } else {
                delta
            };
            p.log_weight += delta;
            outcomes.push((delta, decision));
        }
        let recovered = self.renormalize("update");
        let best = self.best_particle();
        let (best_log_weight_change, decision) = outcomes.get(best).copied().unwrap_or((0.0, None));
        Ok(ParticleUpdateReport {
            best_particle: best,
            best_log_weight_change,
            decision,
            new_landmark_particles: outcomes
                .iter()
                .filter(|(_, d)| d.is_some_and(|d| d.is_new()))
                .count(),
            n_eff: self.effective_sample_size(),
            recovered,
        })
    }

    /// Resampling: when the policy says so, draws `M` particles with the
    /// configured resampler (thesis `000` Sec. 2.3); survivors share their maps
    /// with their parents, and every weight becomes `1/M`.
    pub fn resample(&mut self) -> ResampleReport {
        for p in &mut self.particles {
            finish_step(p, &self.measurement_covariance);
        }
        let m = self.particles.len();
        let n_eff_before = self.effective_sample_size();
        let n_eff_threshold = match self.config.resample {
            ResamplePolicy::EveryStep => m as f64 + 1.0,
            ResamplePolicy::WhenNeffBelow { threshold } => threshold * m as f64,
        };
        let all_zero = !(self.weights.iter().sum::<f64>() > 0.0);
        if !(n_eff_before < n_eff_threshold) && !all_zero {
            return ResampleReport {
                n_eff_before,
                n_eff_threshold,
                resampled: false,
                distinct_survivors: m,
                recovered: false,
            };
        }
        if all_zero {
            self.note_recovery("resample");
        }
        let distinct_survivors = self.draw(m);
        ResampleReport {
            n_eff_before,
            n_eff_threshold,
            resampled: true,
            distinct_survivors,
            recovered: all_zero,
        }
    }

    /// Draws `count` particles by the current weights; returns how many distinct
    /// parents survived.
    fn draw(&mut self, count: usize) -> usize {
        for p in &mut self.particles {
            finish_step(p, &self.measurement_covariance);
        }
        let mut indices = std::mem::take(&mut self.indices);
        resample_indices(
            self.config.resampler,
            &self.weights,
            count,
            &mut self.rng,
            &mut indices,
        );
        let survivors = indices
            .iter()
            .enumerate()
            .filter(|(k, i)| *k == 0 || indices[k - 1] != **i)
            .count();
        let particles: Vec<Particle> = indices
            .iter()
            .filter_map(|&i| self.particles.get(i))
            .map(|p| Particle {
                log_weight: 0.0,
                // A resampled particle starts a new step: no proposal to refine
                // (updates before the next prediction keep its pose fixed).
                proposal: None,
                ..p.clone()
            })
            .collect();
        self.particles = particles;
        self.weights = vec![1.0 / self.particles.len().max(1) as f64; self.particles.len()];
        self.indices = indices;
        survivors
    }

    /// Normalizes the log weights; when they are all zero, resets them to uniform
    /// and notes it. Returns true on a reset.
    fn renormalize(&mut self, phase: &str) -> bool {
        let logs: Vec<f64> = self.particles.iter().map(|p| p.log_weight).collect();
        match normalize_log_weights(&logs, &mut self.weights) {
            Ok(_) => {
                // Keep the largest log weight at 0 so sums stay bounded.
                let max = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                for p in &mut self.particles {
                    p.log_weight -= max;
                }
                false
            }
            Err(WeightError::Empty) => false,
            Err(WeightError::AllZero | WeightError::NotANumber { .. }) => {
                for p in &mut self.particles {
                    p.log_weight = 0.0;
                }
                let m = self.particles.len().max(1);
                self.weights = vec![1.0 / m as f64; self.particles.len()];
                self.note_recovery(phase);
                true
            }
        }
    }

    fn note_recovery(&mut self, phase: &str) {
        self.recoveries += 1;
        self.last_notice = Some(format!(
            "every particle's weight was zero at this {phase} (the measurements contradict them all); \
             the weights were reset to uniform ({} time(s) so far)",
            self.recoveries
        ));
    }

    /// Teaching fault: sets every particle's weight to zero, as a measurement that
    /// contradicts them all would. The next update or resampling recovers.
    pub fn force_all_weights_zero(&mut self) {
        for p in &mut self.particles {
            p.log_weight = f64::NEG_INFINITY;
        }
        self.weights.iter_mut().for_each(|w| *w = 0.0);
    }

    /// How many times the set fell back to uniform weights.
    pub fn recoveries(&self) -> u64 {
        self.recoveries
    }

    /// The latest note about a fallback to uniform weights, for the lesson to show.
    pub fn last_notice(&self) -> Option<&str> {
        self.last_notice.as_deref()
    }

    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.particles.len()
    }

    /// Every particle's pose, normalized weight and map size.
    pub fn particles(&self) -> impl ExactSizeIterator<Item = ParticleView> + '_ {
        self.particles
            .iter()
            .zip(&self.weights)
            .map(|(p, &weight)| ParticleView {
                pose: p.pose,
                weight,
                landmarks: p.map.len(),
            })
    }

    /// The normalized weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// `N_eff = 1 / Σ wᵢ²` of the current weights (slides, "Adaptive resampling").
    pub fn effective_sample_size(&self) -> f64 {
        effective_sample_size(&self.weights)
    }

    /// The index of the particle with the largest weight (the first on a tie).
    pub fn best_particle(&self) -> usize {
        let mut best = 0;
        for (i, &w) in self.weights.iter().enumerate() {
            if w > self.weights[best] {
                best = i;
            }
        }
        best
    }

    /// The best particle's pose.
    pub fn best_pose(&self) -> Pose2 {
        self.particles
            .get(self.best_particle())
            .map_or(Pose2::IDENTITY, |p| p.pose)
    }

    /// The particles' weighted RMS distance from their mean position, metres:
    /// `√(Σ wᵢ ‖pᵢ − p̄‖²)` (what a prediction report calls the spread).
    fn spread(&self) -> f64 {
        let mean = self.mean_pose();
        (self
            .particles
            .iter()
            .zip(&self.weights)
            .map(|(p, w)| w * (p.pose.translation() - mean.translation()).norm_squared())
            .sum::<f64>())
        .sqrt()
    }

    /// The weighted mean pose (circular mean of the headings).
    pub fn mean_pose(&self) -> Pose2 {
        let (mut x, mut y, mut s, mut c) = (0.0, 0.0, 0.0, 0.0);
        for (p, &w) in self.particles.iter().zip(&self.weights) {
            x += w * p.pose.x;
            y += w * p.pose.y;
            let (sn, cs) = math::sin_cos(p.pose.theta);
            s += w * sn;
            c += w * cs;
        }
        Pose2::new(x, y, math::atan2(s, c))
    }

    /// The landmarks of particle `index` (empty for an index out of range).
    pub fn landmarks_of(&self, index: usize) -> impl Iterator<Item = &LandmarkEkf> + '_ {
        self.particles
            .get(index)
            .into_iter()
            .flat_map(|p| p.map.iter().map(|l| &**l))
    }

    /// The best particle's landmarks: id, mean and 2x2 covariance (the lesson
    /// draws their ellipses). In the middle of a FastSLAM 2.0 step, the landmarks
    /// measured earlier in the step are as updated at that measurement's draw.
    pub fn best_landmarks(&self) -> Vec<LandmarkEkf> {
        self.landmarks_of(self.best_particle()).copied().collect()
    }

    /// Every particle's landmark means (the lesson draws them faintly).
    pub fn landmark_means(&self) -> Vec<Vector2<f64>> {
        self.particles
            .iter()
            .flat_map(|p| p.map.iter().map(|l| l.mean))
            .collect()
    }

    /// `(distinct, total)`: how many landmark EKFs exist in memory against how
    /// many the particles hold (they differ by what copy on write shares).
    pub fn landmark_filter_sharing(&self) -> (usize, usize) {
        let mut pointers: Vec<*const LandmarkEkf> = self
            .particles
            .iter()
            .flat_map(|p| p.map.iter().map(Arc::as_ptr))
            .collect();
        let total = pointers.len();
        pointers.sort_unstable();
        pointers.dedup();
        (pointers.len(), total)
    }
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    crate::random::standard_normal(rng)
}

impl Proposal {
    /// The Gaussian `N(mean, covariance)` with this step's standard-normal draw
    /// `ε` from `rng`.
    fn new(mean: Vector3<f64>, covariance: Matrix3<f64>, rng: &mut ChaCha8Rng) -> Self {
        let noise = Vector3::new(normal(rng), normal(rng), normal(rng));
        Proposal {
            mean,
            covariance,
            noise,
            replays: Vec::new(),
        }
    }

    /// `μ + L ε` with `L Lᵀ = Σ`.
    fn draw(&self) -> Pose2 {
        let x = self.mean + psd_cholesky3(&self.covariance) * self.noise;
        Pose2::new(x[0], x[1], wrap_angle(x[2]))
    }
}

/// The lower Cholesky factor of a positive semi-definite 3x3 matrix; a pivot at
/// or below `1e-12` of the largest diagonal entry (a direction without
/// uncertainty) gets a zero column.
fn psd_cholesky3(a: &Matrix3<f64>) -> Matrix3<f64> {
    let scale = a.diagonal().max().max(0.0);
    let mut l = Matrix3::zeros();
    if !(scale > 0.0) || !scale.is_finite() {
        return l;
    }
    for j in 0..3 {
        let d = a[(j, j)] - (0..j).map(|k| l[(j, k)] * l[(j, k)]).sum::<f64>();
        if !(d > 1e-12 * scale) {
            continue;
        }
        let ljj = d.sqrt();
        l[(j, j)] = ljj;
        for i in (j + 1)..3 {
            l[(i, j)] = (a[(i, j)] - (0..j).map(|k| l[(i, k)] * l[(j, k)]).sum::<f64>()) / ljj;
        }
    }
    l
}

/// The 2x2 EKF update of a landmark at a known pose (slides, "Measurement
/// Update"): `K = Σ Hᵀ S⁻¹`, `μ += K ν`, and the covariance in Joseph form
/// `(I − K H) Σ (I − K H)ᵀ + K Q Kᵀ` (the slides' `(I − K H) Σ`, written so it
/// stays symmetric and positive definite). Returns the updated filter and
/// `ln N(ν; 0, S)`, or `None` when the model cannot be evaluated.
fn ekf_update(
    pose: &Pose2,
    landmark: &LandmarkEkf,
    z: &RangeBearing,
    q: &Matrix2<f64>,
) -> Option<(LandmarkEkf, f64)> {
    let p = range_bearing::predict(pose, &landmark.mean).ok()?;
    let h = p.jacobian_landmark;
    let s = h * landmark.covariance * h.transpose() + q;
    let s_inv = s.try_inverse()?;
    let nu = z.difference(&p.measurement);
    let k = landmark.covariance * h.transpose() * s_inv;
    let i_kh = Matrix2::identity() - k * h;
    let mut cov = i_kh * landmark.covariance * i_kh.transpose() + k * q * k.transpose();
    let off = 0.5 * (cov[(0, 1)] + cov[(1, 0)]);
    cov[(0, 1)] = off;
    cov[(1, 0)] = off;
    let updated = LandmarkEkf {
        id: landmark.id,
        mean: landmark.mean + k * nu,
        covariance: cov,
        observations: landmark.observations.saturating_add(1),
    };
    if !updated
        .mean
        .iter()
        .chain(updated.covariance.iter())
        .all(|v| v.is_finite())
    {
        return None;
    }
    Some((updated, log_gaussian(&nu, &s)?))
}

/// A new landmark from the inverse observation model (slides, "Measurement
/// Update": `μ = h⁻¹(y, x)`, `Σ = G Q Gᵀ` with `G = ∂h⁻¹/∂y`).
fn initialize(pose: &Pose2, z: &RangeBearing, id: usize, q: &Matrix2<f64>) -> Option<LandmarkEkf> {
    if !(z.range > MIN_RANGE) {
        return None;
    }
    let inv = range_bearing::inverse(pose, z).ok()?;
    let g = inv.jacobian_measurement;
    Some(LandmarkEkf {
        id,
        mean: inv.landmark,
        covariance: g * q * g.transpose(),
        observations: 1,
    })
}

/// What every particle's update needs.
#[derive(Clone, Copy)]
struct Context {
    version: FastSlamVersion,
    association: AssociationMode,
    q: Matrix2<f64>,
    new_log: f64,
}

/// Which landmark a measurement goes to.
enum Choice {
    Existing { slot: usize, d2: f64 },
    New { nearest: Option<(usize, f64)> },
}

impl Context {
    /// Innovation and its covariance for the landmark in `slot` seen from the pose
    /// mean `pose` with pose covariance `pose_cov` (zero for FastSLAM 1.0).
    fn innovation(
        &self,
        pose: &Pose2,
        pose_cov: &Matrix3<f64>,
        landmark: &LandmarkEkf,
        z: &RangeBearing,
    ) -> Option<(Vector2<f64>, Matrix2<f64>, range_bearing::Prediction)> {
        let p = range_bearing::predict(pose, &landmark.mean).ok()?;
        let hx = p.jacobian_pose;
        let hm = p.jacobian_landmark;
        let s = hx * pose_cov * hx.transpose() + hm * landmark.covariance * hm.transpose() + self.q;
        Some((z.difference(&p.measurement), s, p))
    }

    fn choose(
        &self,
        map: &[Arc<LandmarkEkf>],
        id: usize,
        pose: &Pose2,
        pose_cov: &Matrix3<f64>,
        z: &RangeBearing,
    ) -> Choice {
        match self.association {
            AssociationMode::KnownIds => match map.iter().position(|l| l.id == id) {
                Some(slot) => Choice::Existing { slot, d2: 0.0 },
                None => Choice::New { nearest: None },
            },
            AssociationMode::MaximumLikelihood { .. } => {
                // ĉ = argmax{π_1, …, π_N, p₀} (Montemerlo et al. 2003;
                // Probabilistic Robotics Table 13.2): the gate enters through p₀.
                let mut best: Option<(usize, f64, f64)> = None;
                for (slot, l) in map.iter().enumerate() {
                    let Some((nu, s, _)) = self.innovation(pose, pose_cov, l, z) else {
                        continue;
                    };
                    let (Some(d2), Some(ll)) =
                        (mahalanobis_squared(&nu, &s), log_gaussian(&nu, &s))
                    else {
                        continue;
                    };
                    if best.is_none_or(|(_, _, b)| ll > b) {
                        best = Some((slot, d2, ll));
                    }
                }
                match best {
                    Some((slot, d2, ll)) if ll >= self.new_log => Choice::Existing { slot, d2 },
                    _ => Choice::New {
                        nearest: best.and_then(|(slot, d2, _)| map.get(slot).map(|l| (l.id, d2))),
                    },
                }
            }
        }
    }

    /// One particle's update; returns its log weight change and decision.
    fn update_particle(
        &self,
        p: &mut Particle,
        id: usize,
        z: &RangeBearing,
    ) -> (f64, Option<AssociationDecision>) {
        let known = matches!(self.association, AssociationMode::KnownIds);
        match self.version {
            FastSlamVersion::V1 => match self.choose(&p.map, id, &p.pose, &Matrix3::zeros(), z) {
                Choice::Existing { slot, d2 } => {
                    let Some((updated, ll)) = ekf_update(&p.pose, &p.map[slot], z, &self.q) else {
                        return (0.0, None);
                    };
                    let landmark_id = updated.id;
                    *Arc::make_mut(&mut Arc::make_mut(&mut p.map)[slot]) = updated;
                    (
                        ll,
                        Some(AssociationDecision::Matched {
                            id: landmark_id,
                            mahalanobis_squared: d2,
                        }),
                    )
                }
                Choice::New { nearest } => {
                    let new_id = if known { id } else { p.next_id };
                    let Some(landmark) = initialize(&p.pose, z, new_id, &self.q) else {
                        return (0.0, None);
                    };
                    Arc::make_mut(&mut p.map).push(Arc::new(landmark));
                    if !known {
                        p.next_id += 1;
                    }
                    (
                        self.new_log,
                        Some(AssociationDecision::New {
                            id: new_id,
                            nearest,
                        }),
                    )
                }
            },
            FastSlamVersion::V2 => self.update_particle_v2(p, id, z, known),
        }
    }

    fn update_particle_v2(
        &self,
        p: &mut Particle,
        id: usize,
        z: &RangeBearing,
        known: bool,
    ) -> (f64, Option<AssociationDecision>) {
        let mut proposal = p.proposal.take().unwrap_or_else(|| Proposal {
            mean: p.pose.to_vector(),
            covariance: Matrix3::zeros(),
            noise: Vector3::zeros(),
            replays: Vec::new(),
        });
        let mean_pose = Pose2::new(proposal.mean[0], proposal.mean[1], proposal.mean[2]);
        let outcome = match self.choose(&p.map, id, &mean_pose, &proposal.covariance, z) {
            Choice::Existing { slot, d2 } => {
                match self.innovation(&mean_pose, &proposal.covariance, &p.map[slot], z) {
                    Some((nu, s, pred)) => match (s.try_inverse(), log_gaussian(&nu, &s)) {
                        (Some(s_inv), Some(ll)) => {
                            // The pose part of the Kalman update: the proposal
                            // N(μ + Kx ν, Σ − Kx S Kxᵀ) with Kx = Σ Hxᵀ S⁻¹.
                            let kx = proposal.covariance * pred.jacobian_pose.transpose() * s_inv;
                            let mut mean = proposal.mean + kx * nu;
                            mean[2] = wrap_angle(mean[2]);
                            let mut cov = proposal.covariance - kx * s * kx.transpose();
                            cov = 0.5 * (cov + cov.transpose());
                            if mean.iter().chain(cov.iter()).all(|v| v.is_finite()) {
                                proposal.mean = mean;
                                proposal.covariance = cov;
                            }
                            proposal.replays.push(Replay {
                                slot,
                                z: *z,
                                prior: Some(p.map[slot].clone()),
                            });
                            let landmark_id = p.map[slot].id;
                            (
                                ll,
                                Some(AssociationDecision::Matched {
                                    id: landmark_id,
                                    mahalanobis_squared: d2,
                                }),
                            )
                        }
                        _ => (0.0, None),
                    },
                    None => (0.0, None),
                }
            }
            Choice::New { nearest } => {
                let new_id = if known { id } else { p.next_id };
                match initialize(&p.pose, z, new_id, &self.q) {
                    Some(landmark) => {
                        let slot = p.map.len();
                        Arc::make_mut(&mut p.map).push(Arc::new(landmark));
                        if !known {
                            p.next_id += 1;
                        }
                        proposal.replays.push(Replay {
                            slot,
                            z: *z,
                            prior: None,
                        });
                        (
                            self.new_log,
                            Some(AssociationDecision::New {
                                id: new_id,
                                nearest,
                            }),
                        )
                    }
                    None => (0.0, None),
                }
            }
        };
        // Draw the pose from the refined proposal (the same ε all step) and update
        // this measurement's landmark at it. The landmarks updated earlier this
        // step were updated at earlier draws; `finish_step` re-derives them at
        // the final one.
        p.pose = proposal.draw();
        if let (Some(AssociationDecision::Matched { .. }), Some(last)) =
            (outcome.1, proposal.replays.last())
            && let Some(current) = p.map.get(last.slot)
            && let Some((next, _)) = ekf_update(&p.pose, current, z, &self.q)
        {
            *Arc::make_mut(&mut Arc::make_mut(&mut p.map)[last.slot]) = next;
        }
        p.proposal = Some(proposal);
        outcome
    }
}

/// Ends a FastSLAM 2.0 step for one particle: re-derives every landmark update
/// of the step at the particle's final pose draw (from each landmark's filter
/// before the step, in order), so the particle is exactly "one pose from the full
/// proposal, every landmark updated at it". Only landmarks updated before the
/// last draw change; nothing happens after a single measurement.
fn finish_step(p: &mut Particle, q: &Matrix2<f64>) {
    let Some(proposal) = p.proposal.as_mut() else {
        return;
    };
    let replays = std::mem::take(&mut proposal.replays);
    if replays.len() < 2 {
        return;
    }
    let map = Arc::make_mut(&mut p.map);
    for (k, r) in replays.iter().enumerate() {
        let first = replays[..k].iter().all(|e| e.slot != r.slot);
        let Some(current) = map.get(r.slot) else {
            continue;
        };
        let from: LandmarkEkf = match (first, &r.prior) {
            (true, Some(prior)) => **prior,
            (false, _) => **current,
            (true, None) => {
                if let Some(l) = initialize(&p.pose, &r.z, current.id, q) {
                    *Arc::make_mut(&mut map[r.slot]) = l;
                }
                continue;
            }
        };
        let next = ekf_update(&p.pose, &from, &r.z, q).map_or(from, |(l, _)| l);
        *Arc::make_mut(&mut map[r.slot]) = next;
    }
}

impl PoseBelief for FastSlam {
    /// The weighted mean pose ([`FastSlam::mean_pose`]).
    fn robot_pose(&self) -> Pose2 {
        self.mean_pose()
    }

    /// The weighted covariance of the particle poses around the mean, heading
    /// differences wrapped.
    fn robot_covariance(&self) -> Matrix3<f64> {
        let mean = self.mean_pose();
        let mut cov = Matrix3::zeros();
        for (p, &w) in self.particles.iter().zip(&self.weights) {
            let d = Vector3::new(
                p.pose.x - mean.x,
                p.pose.y - mean.y,
                wrap_angle(p.pose.theta - mean.theta),
            );
            cov += w * d * d.transpose();
        }
        cov
    }
}

impl ParticleBelief for FastSlam {
    fn particle_count(&self) -> usize {
        self.particles.len()
    }

    fn particle_pose(&self, index: usize) -> Option<Pose2> {
        self.particles.get(index).map(|p| p.pose)
    }

    fn particle_weight(&self, index: usize) -> f64 {
        self.weights.get(index).copied().unwrap_or(0.0)
    }

    fn n_eff(&self) -> f64 {
        self.effective_sample_size()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix2x3;

    fn config(version: FastSlamVersion, particles: usize) -> FastSlamConfig {
        FastSlamConfig {
            version,
            particles,
            ..FastSlamConfig::default()
        }
    }

    #[test]
    fn recorded_motions_spread_the_particles_as_g_m_gt() {
        // One step from a certain pose: the cloud's covariance is the linearized
        // G diag(σ²) Gᵀ to sampling error (10,000 particles: a few per cent).
        use crate::motion::{CarGeometry, CarStep, OdometryStep};
        let motions = [
            RecordedMotion::Odometry(OdometryStep {
                rot1: 0.1,
                trans: 0.5,
                rot2: -0.05,
                rot_std: 0.02,
                trans_std: 0.05,
            }),
            RecordedMotion::Car(CarStep {
                speed: 3.0,
                steering: 0.1,
                dt: 0.1,
                car: CarGeometry::VICTORIA_PARK,
                speed_std: 0.5,
                steering_std: 0.02,
            }),
        ];
        let start = Pose2::new(1.0, -2.0, 0.7);
        for version in [FastSlamVersion::V1, FastSlamVersion::V2] {
            for motion in motions {
                let mut f = FastSlam::new(config(version, 10_000), start).unwrap();
                f.predict_recorded(&motion).unwrap();
                let step = motion.step(&start).unwrap();
                let expected =
                    step.jacobian_input * step.input_covariance * step.jacobian_input.transpose();
                let got = f.robot_covariance();
                for i in 0..3 {
                    let rel = (got[(i, i)] - expected[(i, i)]).abs() / expected[(i, i)];
                    assert!(
                        rel < 0.05,
                        "{version:?} {motion:?} [{i}]: {got} vs {expected}"
                    );
                }
                let offset = (f.mean_pose().translation() - step.pose.translation()).norm();
                assert!(offset < 0.01, "{version:?} {motion:?}: {offset}");
            }
        }
    }

    #[test]
    fn a_given_map_is_in_every_particle_and_matched_by_id() {
        let mut f = FastSlam::new(config(FastSlamVersion::V2, 50), Pose2::IDENTITY).unwrap();
        let tiny = Matrix2::new(1e-8, 0.0, 0.0, 1e-8);
        f.insert_landmark(6, Vector2::new(3.0, 1.0), tiny).unwrap();
        f.insert_landmark(7, Vector2::new(-1.0, 4.0), tiny).unwrap();
        assert!(matches!(
            f.insert_landmark(7, Vector2::new(0.0, 0.0), tiny),
            Err(FastSlamError::InvalidLandmark { id: 7, .. })
        ));
        assert!(
            f.insert_landmark(8, Vector2::new(0.0, f64::INFINITY), tiny)
                .is_err()
        );
        assert_eq!(f.landmark_filter_sharing(), (2, 100));
        let z = crate::range_bearing::predict(&Pose2::IDENTITY, &Vector2::new(3.0, 1.0))
            .unwrap()
            .measurement;
        let report = f.update(&LandmarkObservation { id: 6, z }).unwrap();
        assert_eq!(report.new_landmark_particles, 0, "landmark 6 is known");
        assert!(f.best_landmarks().iter().all(|l| l.id == 6 || l.id == 7));
    }

    #[test]
    fn bad_parameters_are_refused_with_a_clear_error() {
        let start = Pose2::IDENTITY;
        assert_eq!(
            FastSlam::new(config(FastSlamVersion::V1, 0), start).unwrap_err(),
            FastSlamError::NoParticles
        );
        assert!(matches!(
            FastSlam::new(config(FastSlamVersion::V1, MAX_PARTICLES + 1), start),
            Err(FastSlamError::TooManyParticles { .. })
        ));
        for threshold in [-0.1, 1.5, f64::NAN] {
            let c = FastSlamConfig {
                resample: ResamplePolicy::WhenNeffBelow { threshold },
                ..config(FastSlamVersion::V2, 10)
            };
            let e = FastSlam::new(c, start).unwrap_err();
            assert!(e.to_string().contains("[0, 1]"), "{e}");
        }
        let mut noisy = config(FastSlamVersion::V2, 10);
        noisy.noise.range_std = f64::NAN;
        assert!(matches!(
            FastSlam::new(noisy, start),
            Err(FastSlamError::InvalidParameter {
                name: "range_std",
                ..
            })
        ));
        let mut f = FastSlam::new(config(FastSlamVersion::V2, 10), start).unwrap();
        assert!(f.set_particle_count(0).is_err());
        assert!(
            f.set_resample_policy(ResamplePolicy::WhenNeffBelow { threshold: 2.0 })
                .is_err()
        );
        assert!(f.predict(&Control::new(f64::NAN, 0.0), 0.1).is_err());
        assert!(f.predict(&Control::new(1.0, 0.0), -0.1).is_err());
        let bad = LandmarkObservation {
            id: 0,
            z: RangeBearing {
                range: f64::NAN,
                bearing: 0.0,
            },
        };
        assert!(f.update(&bad).is_err());
        assert_eq!(f.particle_count(), 10);
        f.set_particle_count(25).unwrap();
        assert_eq!(f.particle_count(), 25);
        assert!((f.weights().iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_new_landmark_is_placed_by_the_inverse_model_with_g_q_gt() {
        for version in [FastSlamVersion::V1, FastSlamVersion::V2] {
            let mut f = FastSlam::new(config(version, 3), Pose2::new(1.0, 2.0, 0.5)).unwrap();
            let z = RangeBearing::new(2.0, 0.3);
            let r = f.update(&LandmarkObservation { id: 4, z }).unwrap();
            assert_eq!(r.new_landmark_particles, 3);
            assert!(matches!(
                r.decision,
                Some(AssociationDecision::New { id: 4, .. })
            ));
            let l = f.best_landmarks()[0];
            let angle: f64 = 0.8;
            assert!(
                (l.mean - Vector2::new(1.0 + 2.0 * math::cos(angle), 2.0 + 2.0 * math::sin(angle)))
                    .norm()
                    < 1e-12
            );
            let g = Matrix2::new(
                math::cos(angle),
                -2.0 * math::sin(angle),
                math::sin(angle),
                2.0 * math::cos(angle),
            );
            let expected = g * f.measurement_covariance * g.transpose();
            assert!((l.covariance - expected).norm() < 1e-12);
        }
    }

    #[test]
    fn fastslam1_landmark_update_matches_the_slides_ekf_and_weight() {
        let mut f = FastSlam::new(config(FastSlamVersion::V1, 1), Pose2::IDENTITY).unwrap();
        let z0 = RangeBearing::new(3.0, 0.2);
        f.update(&LandmarkObservation { id: 0, z: z0 }).unwrap();
        let prior = f.best_landmarks()[0];
        let z1 = RangeBearing::new(3.3, 0.15);
        let r = f.update(&LandmarkObservation { id: 0, z: z1 }).unwrap();
        // Hand-written slides form: K = Σ Hᵀ (H Σ Hᵀ + Q)⁻¹, μ + K ν, (I − K H) Σ.
        let p = range_bearing::predict(&Pose2::IDENTITY, &prior.mean).unwrap();
        let h = p.jacobian_landmark;
        let q = f.measurement_covariance;
        let s = h * prior.covariance * h.transpose() + q;
        let k = prior.covariance * h.transpose() * s.try_inverse().unwrap();
        let nu = z1.difference(&p.measurement);
        let mean = prior.mean + k * nu;
        let cov = (Matrix2::identity() - k * h) * prior.covariance;
        let after = f.best_landmarks()[0];
        assert!((after.mean - mean).norm() < 1e-12);
        assert!((after.covariance - cov).norm() < 1e-12);
        let d2 = (nu.transpose() * s.try_inverse().unwrap() * nu)[(0, 0)];
        let ll = -0.5 * d2 - math::ln(2.0 * std::f64::consts::PI) - 0.5 * math::ln(s.determinant());
        assert!((r.best_log_weight_change - ll).abs() < 1e-12);
        assert_eq!(after.observations, 2);
    }

    #[test]
    fn fastslam2_proposal_is_the_kalman_pose_update_and_the_weight_its_normalizer() {
        // One particle, a known landmark, then a prediction and one observation.
        let mut f = FastSlam::new(config(FastSlamVersion::V2, 1), Pose2::IDENTITY).unwrap();
        f.update(&LandmarkObservation {
            id: 0,
            z: RangeBearing::new(3.0, 0.4),
        })
        .unwrap();
        let landmark = f.best_landmarks()[0];
        let u = Control::new(1.0, 0.3);
        f.predict(&u, 0.5).unwrap();
        let prop = f.particles[0].proposal.clone().unwrap();
        let step = MotionModel::ExactArc.step(&Pose2::IDENTITY, &u, 0.5);
        let r0 = step.jacobian_control * f.control_covariance * step.jacobian_control.transpose();
        assert!((prop.mean - step.pose.to_vector()).norm() < 1e-12);
        assert!((prop.covariance - r0).norm() < 1e-15);
        let z = RangeBearing::new(2.6, 0.1);
        let rep = f.update(&LandmarkObservation { id: 0, z }).unwrap();
        // Montemerlo et al. 2003 information form (R is rank 2 here, so regularize
        // it by 1e-9 before inverting and compare to 1e-7).
        let pred = range_bearing::predict(&step.pose, &landmark.mean).unwrap();
        let hx: Matrix2x3<f64> = pred.jacobian_pose;
        let hm = pred.jacobian_landmark;
        let qj = f.measurement_covariance + hm * landmark.covariance * hm.transpose();
        let s = hx * r0 * hx.transpose() + qj;
        let nu = z.difference(&pred.measurement);
        let expected_ll = log_gaussian(&nu, &s).unwrap();
        assert!((rep.best_log_weight_change - expected_ll).abs() < 1e-12);
        let reg = r0 + Matrix3::identity() * 1e-9;
        let info = hx.transpose() * qj.try_inverse().unwrap() * hx + reg.try_inverse().unwrap();
        let cov = info.try_inverse().unwrap();
        let mean = step.pose.to_vector() + cov * hx.transpose() * qj.try_inverse().unwrap() * nu;
        let after = f.particles[0].proposal.clone().unwrap();
        assert!(
            (after.covariance - cov).norm() < 1e-7,
            "{} vs {}",
            after.covariance,
            cov
        );
        assert!(
            (after.mean - mean).norm() < 1e-6,
            "{} vs {}",
            after.mean,
            mean
        );
        // The pose is μ + L ε and the landmark was updated at that pose.
        let x = after.draw();
        assert!((f.particles[0].pose.to_vector() - x.to_vector()).norm() < 1e-12);
        let (expected_landmark, _) =
            ekf_update(&x, &landmark, &z, &f.measurement_covariance).unwrap();
        assert!((f.best_landmarks()[0].mean - expected_landmark.mean).norm() < 1e-12);
    }

    #[test]
    fn fastslam2_ends_a_step_with_every_landmark_updated_at_the_final_draw() {
        let mut f = FastSlam::new(config(FastSlamVersion::V2, 4), Pose2::IDENTITY).unwrap();
        let first = [
            RangeBearing::new(3.0, 0.4),
            RangeBearing::new(2.5, -0.3),
            RangeBearing::new(4.0, 0.0),
        ];
        for (id, z) in first.iter().enumerate() {
            f.update(&LandmarkObservation { id, z: *z }).unwrap();
        }
        f.resample();
        let priors: Vec<Vec<LandmarkEkf>> = (0..4)
            .map(|i| f.landmarks_of(i).copied().collect())
            .collect();
        f.predict(&Control::new(1.0, 0.2), 0.3).unwrap();
        let second = [
            RangeBearing::new(2.7, 0.35),
            RangeBearing::new(2.3, -0.45),
            RangeBearing::new(3.8, -0.1),
        ];
        for (id, z) in second.iter().enumerate() {
            f.update(&LandmarkObservation { id, z: *z }).unwrap();
        }
        // Before the end of the step, the first landmark was updated at an
        // earlier draw; after it, all three are updated at the final pose.
        let poses: Vec<Pose2> = f.particles().map(|p| p.pose).collect();
        let before = f.best_landmarks()[0];
        let (at_final, _) = ekf_update(
            &poses[f.best_particle()],
            &priors[f.best_particle()][0],
            &second[0],
            &f.measurement_covariance,
        )
        .unwrap();
        assert!(
            (before.mean - at_final.mean).norm() > 1e-6,
            "the first update was at another draw"
        );
        f.resample_policy_free_finish();
        for i in 0..4 {
            let after: Vec<LandmarkEkf> = f.landmarks_of(i).copied().collect();
            for (k, z) in second.iter().enumerate() {
                let (expected, _) =
                    ekf_update(&poses[i], &priors[i][k], z, &f.measurement_covariance).unwrap();
                assert!(
                    (after[k].mean - expected.mean).norm() < 1e-12,
                    "particle {i} landmark {k}"
                );
                assert!((after[k].covariance - expected.covariance).norm() < 1e-12);
            }
        }
    }

    #[test]
    fn psd_cholesky_handles_rank_deficient_matrices() {
        let b = nalgebra::Matrix3x2::new(1.0, 0.2, 0.5, -0.3, 0.0, 1.0);
        let a = b * b.transpose();
        let l = psd_cholesky3(&a);
        assert!((l * l.transpose() - a).norm() < 1e-12);
        assert_eq!(psd_cholesky3(&Matrix3::zeros()), Matrix3::zeros());
    }

    impl FastSlam {
        /// Ends the step without resampling (tests only).
        fn resample_policy_free_finish(&mut self) {
            for p in &mut self.particles {
                finish_step(p, &self.measurement_covariance);
            }
        }
    }

    fn run_steps(f: &mut FastSlam, steps: usize, force_zero: bool) {
        // A robot on a circle among four landmarks it always sees (no truth needed:
        // the measurements are made up from the commanded path).
        let landmarks = [
            Vector2::new(2.0, 0.0),
            Vector2::new(0.0, 2.0),
            Vector2::new(-2.0, 0.0),
            Vector2::new(0.0, -2.0),
        ];
        let u = Control::new(0.5, 0.5);
        let mut truth = Pose2::new(0.0, -1.0, 0.0);
        for _ in 0..steps {
            truth = MotionModel::ExactArc.predict(&truth, &u, 0.1);
            if force_zero {
                f.force_all_weights_zero();
            }
            f.predict(&u, 0.1).unwrap();
            for (id, l) in landmarks.iter().enumerate() {
                let z = range_bearing::predict(&truth, l).unwrap().measurement;
                f.update(&LandmarkObservation { id, z }).unwrap();
            }
            f.resample();
        }
    }

    #[test]
    fn no_nan_after_ten_thousand_steps_with_every_weight_forced_to_zero() {
        for version in [FastSlamVersion::V1, FastSlamVersion::V2] {
            let mut f = FastSlam::new(config(version, 8), Pose2::new(0.0, -1.0, 0.0)).unwrap();
            run_steps(&mut f, 10_000, true);
            assert!(
                f.particles()
                    .all(|p| p.pose.is_finite() && p.weight.is_finite())
            );
            assert!(
                f.landmark_means()
                    .iter()
                    .all(|m| m.iter().all(|v| v.is_finite()))
            );
            assert!((f.weights().iter().sum::<f64>() - 1.0).abs() < 1e-9);
            let n_eff = f.effective_sample_size();
            assert!((1.0..=8.0 + 1e-9).contains(&n_eff), "{n_eff}");
            // Every step's first update found all weights zero and recovered.
            assert_eq!(f.recoveries(), 10_000, "{version:?}");
            assert!(f.last_notice().is_some_and(|n| n.contains("uniform")));
        }
    }

    #[test]
    fn resampling_shares_maps_and_an_update_copies_only_the_changed_landmark() {
        let mut f = FastSlam::new(
            FastSlamConfig {
                resample: ResamplePolicy::EveryStep,
                noise: FastSlamNoise {
                    v_std: 0.3,
                    w_std: 0.3,
                    range_std: 0.05,
                    bearing_std: 0.05,
                },
                ..config(FastSlamVersion::V1, 20)
            },
            Pose2::new(0.0, -1.0, 0.0),
        )
        .unwrap();
        run_steps(&mut f, 5, false);
        // Resampled at the end of the step: many particles are copies, and copies
        // share their whole map (the outer Arc) and every landmark filter.
        let idx: Vec<usize> = (0..20).collect();
        let shared_pairs = idx
            .iter()
            .flat_map(|&i| idx.iter().map(move |&j| (i, j)))
            .filter(|(i, j)| i < j && Arc::ptr_eq(&f.particles[*i].map, &f.particles[*j].map))
            .count();
        assert!(shared_pairs > 0);
        let (distinct, total) = f.landmark_filter_sharing();
        assert_eq!(total, 20 * 4);
        assert!(distinct < total, "{distinct} of {total}");
        // Find a map shared by two particles; update one with landmark 1 only.
        let (a, b) = idx
            .iter()
            .flat_map(|&i| idx.iter().map(move |&j| (i, j)))
            .find(|(i, j)| i < j && Arc::ptr_eq(&f.particles[*i].map, &f.particles[*j].map))
            .unwrap();
        let strong_before = Arc::strong_count(&f.particles[a].map[0]);
        let ctx = Context {
            version: FastSlamVersion::V1,
            association: AssociationMode::KnownIds,
            q: f.measurement_covariance,
            new_log: f.new_landmark_log_likelihood,
        };
        let mut pa = f.particles[a].clone();
        let (ll, decision) = ctx.update_particle(&mut pa, 1, &RangeBearing::new(2.0, 0.5));
        assert!(ll.is_finite());
        assert_eq!(decision.map(|d| d.id()), Some(1));
        let pb = &f.particles[b];
        assert!(
            !Arc::ptr_eq(&pa.map, &pb.map),
            "the outer vector was copied"
        );
        for slot in [0, 2, 3] {
            assert!(
                Arc::ptr_eq(&pa.map[slot], &pb.map[slot]),
                "slot {slot} still shared"
            );
        }
        assert!(
            !Arc::ptr_eq(&pa.map[1], &pb.map[1]),
            "the updated landmark is its own"
        );
        assert_eq!(Arc::strong_count(&pa.map[0]), strong_before + 1);
    }

    #[test]
    fn adaptive_resampling_waits_for_n_eff_to_drop() {
        let mut f = FastSlam::new(
            FastSlamConfig {
                resample: ResamplePolicy::WhenNeffBelow { threshold: 0.5 },
                noise: FastSlamNoise {
                    v_std: 0.5,
                    w_std: 0.1,
                    range_std: 0.05,
                    bearing_std: 0.05,
                },
                ..config(FastSlamVersion::V1, 50)
            },
            Pose2::IDENTITY,
        )
        .unwrap();
        // Uniform weights: N_eff = M, no resampling.
        let r = f.resample();
        assert!(!r.resampled);
        assert!((r.n_eff_before - 50.0).abs() < 1e-9);
        assert!((r.n_eff_threshold - 25.0).abs() < 1e-12);
        f.update(&LandmarkObservation {
            id: 0,
            z: RangeBearing::new(2.0, 0.0),
        })
        .unwrap();
        for _ in 0..3 {
            f.predict(&Control::new(1.0, 0.0), 1.0).unwrap();
            f.update(&LandmarkObservation {
                id: 0,
                z: RangeBearing::new(1.0, 0.0),
            })
            .unwrap();
        }
        let r = f.resample();
        assert!(r.n_eff_before < 25.0, "{r:?}");
        assert!(r.resampled && r.distinct_survivors < 50);
        assert!((f.effective_sample_size() - 50.0).abs() < 1e-9);
    }

    #[test]
    fn a_match_just_inside_the_gate_that_is_less_likely_than_p0_starts_a_new_landmark() {
        // One particle, no motion. The first sighting places the landmark with
        // Σ = G Q Gᵀ, so a second sighting from the same pose has S = 2 Q
        // (det S = 4 det Q). An innovation with d² = gate − 0.5 is inside the
        // gate, but ln N(ν; 0, S) = −½ d² − ln 2π − ½ ln det S is below
        // ln p₀ = −½ gate − ln 2π − ½ ln det Q by ½ ln 4 − 0.25 = 0.443:
        // ĉ = argmax{π, p₀} is a new landmark, weighted p₀.
        let cfg = FastSlamConfig {
            association: AssociationMode::maximum_likelihood(),
            ..config(FastSlamVersion::V1, 1)
        };
        let noise = cfg.noise;
        let mut f = FastSlam::new(cfg, Pose2::IDENTITY).unwrap();
        let first = RangeBearing::new(3.0, 0.5);
        f.update(&LandmarkObservation { id: 0, z: first }).unwrap();
        let d2_inside = DEFAULT_GATE - 0.5;
        let dr = (d2_inside * 2.0 * noise.range_std * noise.range_std).sqrt();
        let r = f
            .update(&LandmarkObservation {
                id: 0,
                z: RangeBearing::new(3.0 + dr, 0.5),
            })
            .unwrap();
        let q_det = noise.range_std.powi(2) * noise.bearing_std.powi(2);
        let ln_p0 =
            -0.5 * DEFAULT_GATE - math::ln(2.0 * std::f64::consts::PI) - 0.5 * math::ln(q_det);
        let ln_match =
            -0.5 * d2_inside - math::ln(2.0 * std::f64::consts::PI) - 0.5 * math::ln(4.0 * q_det);
        assert!((ln_p0 - ln_match - (0.5 * math::ln(4.0) - 0.25)).abs() < 1e-12);
        match r.decision {
            Some(AssociationDecision::New {
                id: 1,
                nearest: Some((0, d2)),
            }) => assert!((d2 - d2_inside).abs() < 1e-6, "{d2}"),
            other => panic!("{other:?}"),
        }
        assert!(
            (r.best_log_weight_change - ln_p0).abs() < 1e-9,
            "{} vs {ln_p0}",
            r.best_log_weight_change
        );
        // Closer in, where π beats p₀ (d² = gate − 2, ln π − ln p₀ = 0.307):
        // matched, weighted π.
        let mut f = FastSlam::new(
            FastSlamConfig {
                association: AssociationMode::maximum_likelihood(),
                ..config(FastSlamVersion::V1, 1)
            },
            Pose2::IDENTITY,
        )
        .unwrap();
        f.update(&LandmarkObservation { id: 0, z: first }).unwrap();
        let d2_close = DEFAULT_GATE - 2.0;
        let dr = (d2_close * 2.0 * noise.range_std * noise.range_std).sqrt();
        let r = f
            .update(&LandmarkObservation {
                id: 0,
                z: RangeBearing::new(3.0 + dr, 0.5),
            })
            .unwrap();
        let ln_close =
            -0.5 * d2_close - math::ln(2.0 * std::f64::consts::PI) - 0.5 * math::ln(4.0 * q_det);
        assert!(ln_close > ln_p0);
        assert!(
            matches!(r.decision, Some(AssociationDecision::Matched { id: 0, .. })),
            "{r:?}"
        );
        assert!((r.best_log_weight_change - ln_close).abs() < 1e-6, "{r:?}");
    }

    #[test]
    fn maximum_likelihood_association_keeps_hypotheses_per_particle() {
        let mut f = FastSlam::new(
            FastSlamConfig {
                association: AssociationMode::maximum_likelihood(),
                ..config(FastSlamVersion::V1, 5)
            },
            Pose2::IDENTITY,
        )
        .unwrap();
        // Two landmarks far apart: two new ones; a repeat of the first matches it.
        let first = RangeBearing::new(3.0, 0.5);
        let r = f.update(&LandmarkObservation { id: 99, z: first }).unwrap();
        assert!(matches!(
            r.decision,
            Some(AssociationDecision::New {
                id: 0,
                nearest: None
            })
        ));
        let r = f
            .update(&LandmarkObservation {
                id: 99,
                z: RangeBearing::new(3.0, -0.5),
            })
            .unwrap();
        assert!(
            matches!(r.decision, Some(AssociationDecision::New { id: 1, nearest: Some((_, d2)) }) if d2 > DEFAULT_GATE)
        );
        let r = f
            .update(&LandmarkObservation {
                id: 99,
                z: RangeBearing::new(3.05, 0.48),
            })
            .unwrap();
        match r.decision {
            Some(AssociationDecision::Matched {
                id: 0,
                mahalanobis_squared,
            }) => {
                assert!(mahalanobis_squared < 1.0)
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(f.best_landmarks().len(), 2);
    }
}
