//! The Monte Carlo localization scenario: the world (map, robot, lidar, wheel
//! odometry, explorer) and the filters' parameters, named after ROS amcl's.

use crate::grid::explorer::ExplorerConfig;
use crate::grid::lidar::Lidar;
use crate::grid::robot::ROBOT_ODOMETRY_NOISE;
use crate::noise::stream_seed;
use serde::{Deserialize, Serialize};
use slamlab_core::Pose2;
use slamlab_core::grid::Costmap;
use slamlab_core::odometry::{OdometryModel, OdometryNoise};
use slamlab_core::particle::{
    BeamModel, ClusterBins, KldSampling, LikelihoodFieldModel, LocalizationMap, MclConfig,
    MeasurementModel, RecoveringMcl, Recovery, RecoveryAlphas, Resampler, ScanAggregation,
};
use std::sync::Arc;

/// How the particles start.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InitMode {
    /// Uniformly over the free cells: global localization.
    #[default]
    Global,
    /// A Gaussian around the true start pose (`initial_cov_*`): tracking.
    Tracking,
}

impl InitMode {
    /// The CLI / URL name.
    pub fn name(self) -> &'static str {
        match self {
            InitMode::Global => "global",
            InitMode::Tracking => "tracking",
        }
    }
}

/// amcl's `laser_model_type`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LaserModelType {
    /// The beam model (ray casting).
    Beam,
    /// The likelihood field (amcl's default).
    #[default]
    LikelihoodField,
}

/// The localization estimators the runner knows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LocalizationEstimator {
    /// Plain Monte Carlo localization (thesis `000` Algorithm 8).
    #[default]
    Mcl,
    /// Augmented MCL (thesis Algorithm 9).
    Amcl,
    /// Costmap MCL (thesis Algorithm 10).
    Cmcl,
    /// Augmented costmap MCL (thesis Algorithm 11).
    Acmcl,
}

impl LocalizationEstimator {
    /// Every estimator.
    pub const ALL: [LocalizationEstimator; 4] = [
        LocalizationEstimator::Mcl,
        LocalizationEstimator::Amcl,
        LocalizationEstimator::Cmcl,
        LocalizationEstimator::Acmcl,
    ];

    /// The recovery it uses.
    pub fn recovery(self) -> Recovery {
        match self {
            LocalizationEstimator::Mcl => Recovery::None,
            LocalizationEstimator::Amcl => Recovery::Augmented,
            LocalizationEstimator::Cmcl => Recovery::Costmap,
            LocalizationEstimator::Acmcl => Recovery::AugmentedCostmap,
        }
    }

    /// The CLI / JSON name.
    pub fn name(self) -> &'static str {
        self.recovery().name()
    }

    /// Parses a name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|e| e.name() == name)
    }
}

/// Everything a Monte Carlo localization run needs besides the map itself.
/// Filter parameters carry ROS 1 amcl's names and defaults, except
/// `resample_interval` (1: resample every update, as thesis Algorithm 8; amcl
/// uses 2), `odom_model_type` (`diff-corrected`, Probabilistic Robotics' form;
/// ROS 1 amcl's default is `diff`), and the scan aggregation: by default SLAM
/// Lab multiplies the beams' likelihoods (Probabilistic Robotics,
/// `laser_likelihood_aggregation = product`) where amcl adds their cubes
/// (`amcl`, the `amcl-ros1` and `nav2` presets). The plain product of 30 beams
/// is so sharp that global localization with 5,000 particles on the maze locks
/// onto a wrong place in about half the seeds, so it is raised to
/// `laser_likelihood_exponent` (default 0.05; 10 of 10 seeds converge,
/// docs/kidnap-tables.md).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MclScenario {
    /// The map's name (`maze`, `office`) or file, for labelling.
    pub map: String,
    /// Master seed; every random stream is derived from it.
    pub seed: u64,
    /// Simulation step, seconds.
    pub dt: f64,
    /// The filters to run, side by side on the same robot and scans.
    pub estimators: Vec<LocalizationEstimator>,
    /// How the particles start.
    pub init: InitMode,
    /// Initial variance in x, m² (tracking; amcl `initial_cov_xx`).
    pub initial_cov_xx: f64,
    /// Initial variance in y, m² (amcl `initial_cov_yy`).
    pub initial_cov_yy: f64,
    /// Initial variance in heading, rad² (amcl `initial_cov_aa`).
    pub initial_cov_aa: f64,
    /// Fewest particles (KLD-sampling; plain MCL uses `max_particles`).
    pub min_particles: usize,
    /// Most particles; plain MCL's fixed count.
    pub max_particles: usize,
    /// `beam` or `likelihood_field`.
    pub laser_model_type: LaserModelType,
    /// Weight of the Gaussian hit component.
    pub laser_z_hit: f64,
    /// Weight of short readings (beam model).
    pub laser_z_short: f64,
    /// Weight of max-range readings (beam model).
    pub laser_z_max: f64,
    /// Weight of uniform noise.
    pub laser_z_rand: f64,
    /// Standard deviation of the hit Gaussian, metres.
    pub laser_sigma_hit: f64,
    /// Rate of short readings (beam model), 1/m.
    pub laser_lambda_short: f64,
    /// Cap of the distance field, metres (likelihood field).
    pub laser_likelihood_max_dist: f64,
    /// Beams used per update.
    pub laser_max_beams: usize,
    /// How the beams' likelihoods combine: `product` (Probabilistic Robotics,
    /// tempered by the exponent) or `amcl` (`1 + Σ p_k³`, ROS amcl).
    pub laser_likelihood_aggregation: ScanAggregation,
    /// Exponent applied to each scan's likelihood (1: the plain product over
    /// beams; default 0.05; see `MclConfig::likelihood_exponent`); the `amcl`
    /// aggregation ignores it.
    pub laser_likelihood_exponent: f64,
    /// amcl's `odom_model_type`: the noise sums as variances
    /// (`diff-corrected`, Nav2) or standard deviations (ROS 1 `diff`).
    pub odom_model_type: OdometryModel,
    /// Rotation noise from rotation.
    pub odom_alpha1: f64,
    /// Rotation noise from translation.
    pub odom_alpha2: f64,
    /// Translation noise from translation.
    pub odom_alpha3: f64,
    /// Translation noise from rotation.
    pub odom_alpha4: f64,
    /// Translation that triggers an update, metres.
    pub update_min_d: f64,
    /// Rotation that triggers an update, radians.
    pub update_min_a: f64,
    /// Resample every this many updates.
    pub resample_interval: u32,
    /// If set, resample only when `N_eff` is below this fraction of the count.
    pub resample_neff_fraction: Option<f64>,
    /// Resampling method.
    pub resampler: Resampler,
    /// KLD-sampling between `min_particles` and `max_particles`.
    pub kld_sampling: bool,
    /// KLD-sampling's error bound (amcl `kld_err`).
    pub kld_err: f64,
    /// KLD-sampling's quantile (amcl `kld_z`).
    pub kld_z: f64,
    /// Augmented MCL's long-term rate (amcl `recovery_alpha_slow`).
    pub recovery_alpha_slow: f64,
    /// Augmented MCL's short-term rate (amcl `recovery_alpha_fast`).
    pub recovery_alpha_fast: f64,
    /// A kidnap at this tick (the robot is teleported; the filters are not
    /// told).
    pub kidnap_at: Option<u64>,
    /// The kidnap takes the robot at least this far, metres.
    pub kidnap_distance: f64,
    /// Robot radius, metres.
    pub robot_radius: f64,
    /// The simulated lidar.
    pub lidar: Lidar,
    /// Noise of the simulated wheel odometry (per tick).
    pub odom_noise: OdometryNoise,
    /// The explorer.
    pub explorer: ExplorerConfig,
}

impl Default for MclScenario {
    fn default() -> Self {
        let beam = BeamModel::default();
        Self {
            map: "maze".to_owned(),
            seed: 1,
            dt: 0.1,
            estimators: vec![LocalizationEstimator::Mcl],
            init: InitMode::Global,
            initial_cov_xx: 0.25,
            initial_cov_yy: 0.25,
            initial_cov_aa: (std::f64::consts::PI / 12.0).powi(2),
            min_particles: 100,
            max_particles: 2000,
            laser_model_type: LaserModelType::LikelihoodField,
            laser_z_hit: beam.z_hit,
            laser_z_short: beam.z_short,
            laser_z_max: beam.z_max,
            laser_z_rand: beam.z_rand,
            laser_sigma_hit: beam.sigma_hit,
            laser_lambda_short: beam.lambda_short,
            laser_likelihood_max_dist: 2.0,
            laser_max_beams: 30,
            laser_likelihood_aggregation: ScanAggregation::Product,
            laser_likelihood_exponent: 0.05,
            odom_model_type: OdometryModel::DiffCorrected,
            odom_alpha1: 0.2,
            odom_alpha2: 0.2,
            odom_alpha3: 0.2,
            odom_alpha4: 0.2,
            update_min_d: 0.2,
            update_min_a: std::f64::consts::PI / 6.0,
            resample_interval: 1,
            resample_neff_fraction: None,
            resampler: Resampler::LowVariance,
            kld_sampling: false,
            kld_err: 0.01,
            kld_z: 0.99,
            recovery_alpha_slow: 0.001,
            recovery_alpha_fast: 0.1,
            kidnap_at: None,
            kidnap_distance: 3.0,
            robot_radius: 0.2,
            lidar: Lidar::default(),
            odom_noise: ROBOT_ODOMETRY_NOISE,
            explorer: ExplorerConfig::default(),
        }
    }
}

impl MclScenario {
    /// The measurement model the parameters describe.
    pub fn measurement_model(&self) -> MeasurementModel {
        match self.laser_model_type {
            LaserModelType::Beam => MeasurementModel::Beam(BeamModel {
                z_hit: self.laser_z_hit,
                z_short: self.laser_z_short,
                z_max: self.laser_z_max,
                z_rand: self.laser_z_rand,
                sigma_hit: self.laser_sigma_hit,
                lambda_short: self.laser_lambda_short,
            }),
            LaserModelType::LikelihoodField => {
                MeasurementModel::LikelihoodField(LikelihoodFieldModel {
                    z_hit: self.laser_z_hit,
                    z_rand: self.laser_z_rand,
                    sigma_hit: self.laser_sigma_hit,
                })
            }
        }
    }

    /// Augmented MCL's rates.
    pub fn recovery_alphas(&self) -> RecoveryAlphas {
        RecoveryAlphas {
            alpha_slow: self.recovery_alpha_slow,
            alpha_fast: self.recovery_alpha_fast,
        }
    }

    /// The filter of `estimator` with these parameters on `map`, its particles
    /// kept out of `collision`'s cells, its randomness from stream `stream` of
    /// the seed.
    pub fn filter(
        &self,
        estimator: LocalizationEstimator,
        map: Arc<LocalizationMap>,
        collision: Arc<Costmap>,
        stream: u64,
    ) -> RecoveringMcl {
        RecoveringMcl::new(
            estimator.recovery(),
            self.mcl_config(),
            self.recovery_alphas(),
            map,
            Some(collision),
            stream_seed(self.seed, stream),
        )
    }

    /// Starts `filter` tracking: its particles drawn around `start` with the
    /// initial covariance's standard deviations (`initial_cov_xx`, `_yy`,
    /// `_aa`; a variance that is not positive and finite: none).
    pub fn init_tracking(&self, filter: &mut RecoveringMcl, start: Pose2) {
        let sd = |v: f64| {
            if v > 0.0 && v.is_finite() {
                v.sqrt()
            } else {
                0.0
            }
        };
        filter.mcl_mut().init_tracking(
            start,
            [
                sd(self.initial_cov_xx),
                sd(self.initial_cov_yy),
                sd(self.initial_cov_aa),
            ],
        );
    }

    /// The configuration of a plain MCL filter.
    pub fn mcl_config(&self) -> MclConfig {
        MclConfig {
            particles: self.max_particles,
            odom: OdometryNoise {
                alpha1: self.odom_alpha1,
                alpha2: self.odom_alpha2,
                alpha3: self.odom_alpha3,
                alpha4: self.odom_alpha4,
            },
            odom_model: self.odom_model_type,
            model: self.measurement_model(),
            aggregation: self.laser_likelihood_aggregation,
            max_beams: self.laser_max_beams,
            update_min_d: self.update_min_d,
            update_min_a: self.update_min_a,
            resample_interval: self.resample_interval,
            neff_fraction: self.resample_neff_fraction,
            resampler: self.resampler,
            cluster: ClusterBins::default(),
            likelihood_exponent: self.laser_likelihood_exponent,
            kld: self.kld_sampling.then_some(KldSampling {
                err: self.kld_err,
                z: self.kld_z,
                min_particles: self.min_particles,
                max_particles: self.max_particles,
            }),
        }
    }
}

impl MclScenario {
    /// A preset's parameters by name (the lesson's presets, `preset=` in the URL and
    /// `--preset` on the command line, are listed in [`super::params::PRESETS`]). Every preset uses the recovery
    /// rates 0.001 / 0.1 (the thesis and the Nav2 documentation recommend them;
    /// both amcl versions default to 0, which disables recovery) and SLAM Lab's
    /// scan aggregation: the two amcl presets score scans as amcl does
    /// (`1 + Σ p_k³`, exponent 1); `amcl-ros1` samples motion with ROS 1's
    /// `diff` model, `nav2` with Nav2's (`diff-corrected`); the thesis preset
    /// keeps SLAM Lab's tempered product.
    pub fn preset(name: &str) -> Option<Self> {
        let base = Self::default();
        match name {
            "amcl-ros1" => Some(Self {
                kld_sampling: true,
                kld_err: 0.01,
                kld_z: 0.99,
                min_particles: 100,
                max_particles: 5000,
                laser_model_type: LaserModelType::LikelihoodField,
                laser_z_hit: 0.95,
                laser_z_short: 0.1,
                laser_z_max: 0.05,
                laser_z_rand: 0.05,
                laser_sigma_hit: 0.2,
                laser_lambda_short: 0.1,
                laser_likelihood_max_dist: 2.0,
                laser_max_beams: 30,
                laser_likelihood_aggregation: ScanAggregation::AmclCubes,
                laser_likelihood_exponent: 1.0,
                odom_model_type: OdometryModel::Diff,
                update_min_d: 0.2,
                update_min_a: std::f64::consts::PI / 6.0,
                resample_interval: 2,
                ..base
            }),
            "nav2" => Some(Self {
                kld_sampling: true,
                kld_err: 0.05,
                kld_z: 0.99,
                min_particles: 500,
                max_particles: 2000,
                laser_model_type: LaserModelType::LikelihoodField,
                laser_z_hit: 0.5,
                laser_z_short: 0.05,
                laser_z_max: 0.05,
                laser_z_rand: 0.5,
                laser_sigma_hit: 0.2,
                laser_lambda_short: 0.1,
                laser_likelihood_max_dist: 2.0,
                laser_max_beams: 60,
                laser_likelihood_aggregation: ScanAggregation::AmclCubes,
                laser_likelihood_exponent: 1.0,
                odom_model_type: OdometryModel::DiffCorrected,
                update_min_d: 0.25,
                update_min_a: 0.2,
                resample_interval: 1,
                ..base
            }),
            "thesis-table-5-1" => Some(Self {
                kld_sampling: false,
                max_particles: 1000,
                laser_model_type: LaserModelType::Beam,
                resample_interval: 1,
                ..base
            }),
            _ => None,
        }
    }
}
