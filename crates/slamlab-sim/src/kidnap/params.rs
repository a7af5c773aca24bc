//! The Monte Carlo localization lesson's parameter table (`lesson=kidnap`): each
//! parameter once, named after ROS amcl's (`laser_z_hit` is `laser-z-hit`), with
//! its unit, range and help. The URL, share links, `slamlab params --lesson
//! kidnap` and the app's panel read it through [`crate::params`].

use super::scenario::{InitMode, LaserModelType, LocalizationEstimator, MclScenario};
use crate::params::{
    Param, ParamIssue, Preset, Scenario, choice_field, choose, choose_items, count_field,
    list_text, number_field,
};
use slamlab_core::odometry::OdometryModel;
use slamlab_core::particle::{Resampler, ScanAggregation};

const MAPS: &[&str] = &["maze", "office"];
const ESTIMATORS: &[&str] = &["mcl", "amcl", "cmcl", "acmcl"];
const INITS: &[&str] = &["global", "tracking"];
const LASER_MODELS: &[&str] = &["likelihood_field", "beam"];
const RESAMPLERS: &[&str] = &["low-variance", "multinomial", "stratified", "residual"];
const SWITCH: &[&str] = &["0", "1"];
const AGGREGATIONS: &[&str] = &["product", "amcl"];
const ODOM_MODELS: &[&str] = &["diff-corrected", "diff"];

/// Every parameter of the lesson, in the order `slamlab params --lesson kidnap` lists them.
pub static PARAMS: &[Param<MclScenario>] = &[
    Param::words(
        "preset",
        "start from a named setup; other parameters apply on top",
        &["amcl-ros1", "nav2", "thesis-table-5-1"],
        |_| None,
        crate::params::apply_preset::<MclScenario>,
    ),
    count_field!("seed", "seed of every random stream", (0, u64::MAX), seed),
    Param::words(
        "map",
        "built-in map (or drop a ROS map on the app's window)",
        MAPS,
        |s| Some(s.map.clone()),
        |s, v| choose(MAPS, v).map(|i| s.map = MAPS[i].to_owned()),
    ),
    Param::words(
        "estimator",
        "filters to run side by side, comma separated",
        ESTIMATORS,
        |s| Some(list_text(&s.estimators, |e| e.name())),
        |s, v| {
            choose_items(ESTIMATORS, v, LocalizationEstimator::from_name)
                .map(|list| s.estimators = list)
        },
    ),
    count_field!(
        "particles",
        "particles per filter (amcl max_particles)",
        (1, 200_000),
        max_particles
    ),
    count_field!(
        "min-particles",
        "fewest particles with KLD-sampling (amcl min_particles)",
        (1, 200_000),
        min_particles
    ),
    Param::words(
        "kld",
        "KLD-sampling: 1 adapts the particle count between min and max (Fox 2003)",
        SWITCH,
        |s| Some(SWITCH[usize::from(s.kld_sampling)].to_owned()),
        |s, v| choose(SWITCH, v).map(|i| s.kld_sampling = i == 1),
    ),
    number_field!(
        "kld-err",
        "",
        "KLD-sampling error bound (amcl kld_err)",
        (1e-4, 0.5),
        kld_err
    ),
    number_field!(
        "kld-z",
        "",
        "KLD-sampling quantile (amcl kld_z)",
        (0.5, 0.9999),
        kld_z
    ),
    choice_field!(
        "init",
        "global: particles everywhere; tracking: around the true start",
        INITS,
        [InitMode::Global, InitMode::Tracking],
        init
    ),
    number_field!("dt", "s", "simulation time step", (0.01, 1.0), dt),
    choice_field!(
        "laser-model-type",
        "measurement model: likelihood field (amcl's default) or beam model (Xiang's thesis §3.5.1)",
        LASER_MODELS,
        [LaserModelType::LikelihoodField, LaserModelType::Beam],
        laser_model_type
    ),
    count_field!(
        "laser-max-beams",
        "beams used per update",
        (1, 2000),
        laser_max_beams
    ),
    number_field!(
        "laser-z-hit",
        "",
        "weight of the hit Gaussian",
        (0.0, 1.0),
        laser_z_hit
    ),
    number_field!(
        "laser-z-short",
        "",
        "weight of short readings (beam model)",
        (0.0, 1.0),
        laser_z_short
    ),
    number_field!(
        "laser-z-max",
        "",
        "weight of max-range readings (beam model)",
        (0.0, 1.0),
        laser_z_max
    ),
    number_field!(
        "laser-z-rand",
        "",
        "weight of uniform noise",
        (0.0, 1.0),
        laser_z_rand
    ),
    number_field!(
        "laser-sigma-hit",
        "m",
        "hit Gaussian standard deviation",
        (0.005, 5.0),
        laser_sigma_hit
    ),
    number_field!(
        "laser-lambda-short",
        "1/m",
        "rate of short readings (beam model)",
        (0.001, 100.0),
        laser_lambda_short
    ),
    number_field!(
        "laser-likelihood-max-dist",
        "m",
        "distance field cap (likelihood field)",
        (0.05, 20.0),
        laser_likelihood_max_dist
    ),
    choice_field!(
        "laser-likelihood-aggregation",
        "how beams combine: product (Probabilistic Robotics, tempered by the exponent) or amcl (1 + sum of cubes, as ROS amcl)",
        AGGREGATIONS,
        [ScanAggregation::Product, ScanAggregation::AmclCubes],
        laser_likelihood_aggregation
    ),
    number_field!(
        "laser-likelihood-exponent",
        "",
        "exponent on each scan's likelihood (1: the plain product over beams; the amcl aggregation ignores it)",
        (0.001, 1.0),
        laser_likelihood_exponent
    ),
    choice_field!(
        "odom-model-type",
        "odometry noise sums as variances (diff-corrected, Nav2) or standard deviations (diff, ROS 1 amcl's default)",
        ODOM_MODELS,
        [OdometryModel::DiffCorrected, OdometryModel::Diff],
        odom_model_type
    ),
    number_field!(
        "odom-alpha1",
        "",
        "rotation noise from rotation",
        (0.0, 5.0),
        odom_alpha1
    ),
    number_field!(
        "odom-alpha2",
        "",
        "rotation noise from translation",
        (0.0, 5.0),
        odom_alpha2
    ),
    number_field!(
        "odom-alpha3",
        "",
        "translation noise from translation",
        (0.0, 5.0),
        odom_alpha3
    ),
    number_field!(
        "odom-alpha4",
        "",
        "translation noise from rotation",
        (0.0, 5.0),
        odom_alpha4
    ),
    number_field!(
        "update-min-d",
        "m",
        "translation that triggers a filter update",
        (0.0, 10.0),
        update_min_d
    ),
    Param::number(
        "update-min-a-deg",
        "deg",
        "rotation that triggers a filter update",
        (0.0, 360.0),
        |s| Some(s.update_min_a.to_degrees()),
        |s, v| {
            s.update_min_a = v.to_radians();
            Ok(())
        },
    ),
    choice_field!(
        "resampler",
        "resampling method",
        RESAMPLERS,
        [
            Resampler::LowVariance,
            Resampler::Multinomial,
            Resampler::Stratified,
            Resampler::Residual,
        ],
        resampler
    ),
    count_field!(
        "resample-interval",
        "resample every this many updates",
        (1, 100),
        resample_interval
    ),
    number_field!(
        "recovery-alpha-slow",
        "",
        "Augmented MCL's long-term averaging rate (amcl recovery_alpha_slow)",
        (0.0, 1.0),
        recovery_alpha_slow
    ),
    number_field!(
        "recovery-alpha-fast",
        "",
        "Augmented MCL's short-term averaging rate (amcl recovery_alpha_fast)",
        (0.0, 1.0),
        recovery_alpha_fast
    ),
    number_field!(
        "kidnap-distance",
        "m",
        "a kidnap moves the robot at least this far",
        (0.0, 500.0),
        kidnap_distance
    ),
    Param::words(
        "kidnap-at",
        "kidnap the robot at this tick (none: never)",
        &["none", "a tick number"],
        |s| {
            Some(
                s.kidnap_at
                    .map_or_else(|| "none".to_owned(), |t| t.to_string()),
            )
        },
        |s, v| match v {
            "none" | "" => {
                s.kidnap_at = None;
                Ok(())
            }
            _ => v
                .parse::<u64>()
                .map(|t| s.kidnap_at = Some(t))
                .map_err(|_| "a tick number (a whole number) or none".to_owned()),
        },
    ),
    number_field!(
        "robot-radius",
        "m",
        "robot radius (it cannot drive closer to a wall)",
        (0.01, 2.0),
        robot_radius
    ),
    count_field!(
        "lidar-beams",
        "lidar beams per scan",
        (1, 3600),
        lidar.beams
    ),
    Param::number(
        "lidar-fov-deg",
        "deg",
        "lidar field of view",
        (1.0, 360.0),
        |s| Some(s.lidar.fov.to_degrees()),
        |s, v| {
            s.lidar.fov = v.to_radians();
            Ok(())
        },
    ),
    number_field!(
        "lidar-max-range",
        "m",
        "lidar maximum range",
        (0.1, 100.0),
        lidar.max_range
    ),
    number_field!(
        "lidar-range-std",
        "m",
        "lidar range noise",
        (0.0, 5.0),
        lidar.range_std
    ),
    number_field!(
        "lidar-outlier-prob",
        "",
        "probability of a random lidar reading",
        (0.0, 1.0),
        lidar.outlier_prob
    ),
];

/// The parameters of preset `id` ([`MclScenario::preset`]) with `seed`.
fn named(id: &str, seed: u64) -> MclScenario {
    MclScenario {
        seed,
        ..MclScenario::preset(id).unwrap_or_default()
    }
}

/// The parameters of preset `id` with `seed`, run by AMCL alone (amcl's and
/// Nav2's defaults).
fn amcl(id: &str, seed: u64) -> MclScenario {
    MclScenario {
        estimators: vec![LocalizationEstimator::Amcl],
        ..named(id, seed)
    }
}

/// The presets: ROS 1 amcl's defaults, Nav2's, and the thesis's Table 5.1 runs
/// (each with Augmented MCL's recovery rates 0.001 / 0.1, see [`MclScenario::preset`]).
pub static PRESETS: &[Preset<MclScenario>] = &[
    Preset {
        id: "amcl-ros1",
        title: "ROS 1 amcl defaults (AMCL)",
        summary: "amcl's documented defaults: 100..5000 particles with KLD-sampling, likelihood field with 30 beams scored as amcl does (1 + sum of cubes), the diff odometry model, an update every 0.2 m or 30°, resampling every 2 updates.",
        build: |seed| amcl("amcl-ros1", seed),
    },
    Preset {
        id: "nav2",
        title: "Nav2 amcl defaults (AMCL)",
        summary: "Nav2's defaults: 500..2000 particles with KLD-sampling (kld_err 0.05), likelihood field with 60 beams scored as amcl does (1 + sum of cubes), an update every 0.25 m or 0.2 rad, resampling every update.",
        build: |seed| amcl("nav2", seed),
    },
    Preset {
        id: "thesis-table-5-1",
        title: "Table 5.1 of Xiang's thesis: AMCL vs ACMCL, 1000 particles, kidnapped at tick 300",
        summary: "AMCL beside ACMCL with 1000 particles each and the beam model, tracking from the start, kidnapped at least 3 m away at tick 300.",
        build: |seed| MclScenario {
            estimators: vec![LocalizationEstimator::Amcl, LocalizationEstimator::Acmcl],
            init: InitMode::Tracking,
            kidnap_at: Some(300),
            kidnap_distance: 3.0,
            ..named("thesis-table-5-1", seed)
        },
    },
];

impl Scenario for MclScenario {
    const LESSON: &'static str = "kidnap";

    fn params() -> &'static [Param<Self>] {
        PARAMS
    }

    fn presets() -> &'static [Preset<Self>] {
        PRESETS
    }

    fn seed(&self) -> u64 {
        self.seed
    }

    fn check(&mut self) -> Vec<ParamIssue> {
        let mut issues = Vec::new();
        if self.estimators.is_empty() {
            self.estimators = MclScenario::default().estimators;
        }
        if self.min_particles > self.max_particles {
            issues.push(ParamIssue::Clamped {
                name: "min-particles".to_owned(),
                value: self.min_particles.to_string(),
                used: format!("{} (not more than particles)", self.max_particles),
            });
            self.min_particles = self.max_particles;
        }
        issues
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::checks::*;
    use slamlab_core::odometry::OdometryModel;
    use slamlab_core::particle::ScanAggregation;

    #[test]
    fn presets_exist_and_differ() {
        for name in PRESETS.iter().map(|p| p.id) {
            let p = MclScenario::preset(name).unwrap();
            assert_ne!(p, MclScenario::default(), "{name}");
            assert_eq!(p.recovery_alpha_slow, 0.001);
            assert_eq!(p.recovery_alpha_fast, 0.1);
        }
        let nav2 = MclScenario::preset("nav2").unwrap();
        assert_eq!((nav2.min_particles, nav2.max_particles), (500, 2000));
        assert!(nav2.mcl_config().kld.is_some());
        assert!(MclScenario::preset("nope").is_none());
        for name in ["amcl-ros1", "nav2"] {
            let c = MclScenario::preset(name).unwrap().mcl_config();
            assert_eq!(c.aggregation, ScanAggregation::AmclCubes, "{name}");
        }
        assert_eq!(
            MclScenario::preset("amcl-ros1").unwrap().odom_model_type,
            OdometryModel::Diff
        );
        assert_eq!(nav2.odom_model_type, OdometryModel::DiffCorrected);
    }

    use crate::params::{apply_pairs, sanitize, set, to_pairs};

    #[test]
    fn every_parameter_round_trips_and_the_defaults_are_in_range() {
        let mut s = MclScenario::default();
        assert!(sanitize(&mut s).is_empty(), "{:?}", sanitize(&mut s));
        let pairs = to_pairs(&s);
        assert_eq!(
            pairs.len(),
            PARAMS.len() - 1,
            "every parameter but the preset has a value"
        );
        let mut copy = MclScenario {
            seed: 99,
            max_particles: 7,
            ..MclScenario::default()
        };
        assert_applies(&mut copy, &pairs);
        assert_eq!(to_pairs(&copy), pairs);
        assert_eq!((copy.seed, copy.max_particles), (s.seed, s.max_particles));
        assert!((copy.update_min_a - s.update_min_a).abs() < 1e-12);
        assert_round_trip(
            &mut s,
            &[
                ("estimator", "amcl,acmcl"),
                ("kidnap-at", "120"),
                ("resampler", "stratified"),
                ("lidar-fov-deg", "270"),
                ("kld", "1"),
                ("laser-likelihood-aggregation", "amcl"),
                ("odom-model-type", "diff"),
            ],
        );
        assert_eq!(
            s.estimators,
            vec![LocalizationEstimator::Amcl, LocalizationEstimator::Acmcl]
        );
        assert!((s.lidar.fov - 1.5 * std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn bad_values_get_messages_and_presets_keep_the_seed() {
        let mut s = MclScenario::default();
        for (k, v) in [("particles", "0"), ("particles", "10000000")] {
            assert!(
                matches!(set(&mut s, k, v), Some(ParamIssue::Clamped { .. })),
                "{k}={v}"
            );
        }
        assert_eq!(s.max_particles, 200_000);
        assert_unreadable(
            &mut s,
            &[
                ("map", "atlantis"),
                ("estimator", "ekf"),
                ("kidnap-at", "soon"),
                ("laser-sigma-hit", "NaN"),
            ],
        );
        let mut s = MclScenario {
            min_particles: 5000,
            max_particles: 100,
            ..MclScenario::default()
        };
        assert_eq!(sanitize(&mut s).len(), 1);
        assert_eq!(s.min_particles, 100);
        let mut s = MclScenario::default();
        assert!(apply_pairs(&mut s, [("seed", "4"), ("preset", "nav2")], &[]).is_empty());
        assert_eq!((s.seed, s.max_particles, s.laser_max_beams), (4, 2000, 60));
        for preset in PRESETS {
            let mut p = (preset.build)(1);
            assert!(sanitize(&mut p).is_empty(), "{} is in range", preset.id);
        }
    }
}
