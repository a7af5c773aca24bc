//! The mapping lesson's scenario and its parameter table (`lesson=mapping`):
//! where the scans come from (a simulated robot in a built-in or loaded map,
//! or a laser log), which poses build the map, and how scans change it.

use crate::grid::SimulatedRun;
use crate::grid::run_params::{map_param, seed_param, steps_param};
use crate::grid::{MappingInput, SimulatedLogConfig, log_input, simulate_log};
use crate::params::{Param, Scenario, choice_field, count_field, number_field};
use serde::{Deserialize, Serialize};
use slamlab_core::grid::{InsertParams, OccupancyGrid, UpdateRule};
use slamlab_core::particle::MAX_GRID_PARTICLES;
use slamlab_core::particle::{GridFastSlamConfig, Proposal};
use slamlab_core::scan::scan_to_map::ScanToMapParams;
use std::sync::Arc;

/// Where each scan's pose comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PoseSource {
    /// The simulator's true pose (simulation only): mapping with known poses.
    Truth,
    /// Wheel odometry alone: the smeared map that motivates SLAM.
    Odometry,
    /// Odometry corrected by point-to-point ICP against the previous scan.
    Icp,
    /// Odometry corrected by point-to-line ICP against the previous scan.
    Plicp,
    /// Odometry corrected by matching the scan against the map built so far
    /// (Cartographer's local SLAM).
    #[default]
    ScanToMap,
    /// Grid FastSLAM (gmapping): particles, each with its path and its own
    /// map; the pose is the heaviest particle's.
    #[serde(rename = "grid-fastslam")]
    GridFastSlam,
}

impl PoseSource {
    /// Every source, in menu order.
    pub const ALL: [PoseSource; 6] = [
        PoseSource::Truth,
        PoseSource::Odometry,
        PoseSource::Icp,
        PoseSource::Plicp,
        PoseSource::ScanToMap,
        PoseSource::GridFastSlam,
    ];
    /// The names the URL and the CLI use.
    pub const NAMES: &'static [&'static str] = &[
        "truth",
        "odometry",
        "icp",
        "plicp",
        "scan-to-map",
        "grid-fastslam",
    ];

    /// The name the URL and the CLI use.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    /// The source of a name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::NAMES
            .iter()
            .position(|n| *n == name)
            .map(|i| Self::ALL[i])
    }

    /// A label for legends and menus.
    pub fn label(self) -> &'static str {
        match self {
            PoseSource::Truth => "true poses",
            PoseSource::Odometry => "raw odometry",
            PoseSource::Icp => "ICP scan-to-scan (point-to-point)",
            PoseSource::Plicp => "ICP scan-to-scan (point-to-line)",
            PoseSource::ScanToMap => "scan-to-map matching",
            PoseSource::GridFastSlam => "grid FastSLAM (particles, gmapping)",
        }
    }
}

/// Which update rule builds the map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RuleKind {
    /// Probabilistic Robotics Table 9.2 (log odds, clamped).
    LogOdds,
    /// Thesis Eq. 5.3-5.4 (Cartographer's odds, clamped).
    #[default]
    Odds,
}

const RULES: &[&str] = &["log-odds", "odds"];

/// The mapping lesson's scenario.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MappingScenario {
    /// Seed of every random stream.
    pub seed: u64,
    /// Built-in map name (`maze`, `office`) or a map file's location.
    pub map: String,
    /// Scans to simulate.
    pub steps: usize,
    /// Where the poses come from.
    pub poses: PoseSource,
    /// Which update rule.
    pub rule: RuleKind,
    /// Grid resolution, metres per cell.
    pub resolution: f64,
    /// Free space marked along a max-range beam, metres.
    pub max_range_free: f64,
    /// Log-odds rule: added on a hit.
    pub l_occ: f64,
    /// Log-odds rule: added on a miss.
    pub l_free: f64,
    /// Log-odds rule: lower clamp.
    pub l_min: f64,
    /// Log-odds rule: upper clamp.
    pub l_max: f64,
    /// Odds rule: hit probability.
    pub hit_probability: f64,
    /// Odds rule: miss probability.
    pub miss_probability: f64,
    /// Odds rule: lower clamp.
    pub p_min: f64,
    /// Odds rule: upper clamp.
    pub p_max: f64,
    /// Scan-to-map: correlative search half-width in x and y, metres.
    pub linear_search_window: f64,
    /// Scan-to-map: correlative search half-width in heading, degrees.
    pub angular_search_window_deg: f64,
    /// Scan-to-map: pull towards the search's translation.
    pub translation_weight: f64,
    /// Scan-to-map: pull towards the search's heading.
    pub rotation_weight: f64,
    /// ICP: correspondences farther than this are rejected, metres.
    pub icp_max_distance: f64,
    /// ICP: the share of correspondences kept (trimming).
    pub icp_trim: f64,
    /// Simulated lidar: beams per scan (over 360°).
    pub beams: usize,
    /// Simulated lidar: maximum range, metres.
    pub lidar_range: f64,
    /// Simulated lidar: range noise standard deviation, metres.
    pub range_std: f64,
    /// Simulated odometry noise scale (1: the Monte Carlo lesson's α values).
    pub odometry_noise: f64,
    /// Grid FastSLAM: particles (gmapping's `particles`).
    pub particles: usize,
    /// Grid FastSLAM: the proposal.
    pub proposal: Proposal,
    /// Grid FastSLAM: resample when `N_eff` falls below this share of the
    /// particles (`resampleThreshold`).
    pub resample_threshold: f64,
    /// Grid FastSLAM: translation noise per metre of translation (`srr`).
    pub srr: f64,
    /// Grid FastSLAM: rotation noise per metre of translation (`srt`).
    pub srt: f64,
    /// Grid FastSLAM: translation noise per radian of rotation (`str`).
    pub str: f64,
    /// Grid FastSLAM: rotation noise per radian of rotation (`stt`).
    pub stt: f64,
    /// Grid FastSLAM: the matcher's search half-width in x and y, metres
    /// (`lstep`).
    pub lstep: f64,
    /// Grid FastSLAM: the matcher's search half-width in heading, radians
    /// (`astep`).
    pub astep: f64,
    /// Grid FastSLAM: the matcher's refinement iterations (`iterations`).
    pub iterations: usize,
    /// Grid FastSLAM: the scan likelihood's spread (`lsigma`).
    pub lsigma: f64,
    /// Grid FastSLAM: weight smoothing gain (`ogain`).
    pub ogain: f64,
    /// Grid FastSLAM: update after this much translation, metres
    /// (`linearUpdate`).
    pub linear_update: f64,
    /// Grid FastSLAM: update after this much rotation, radians
    /// (`angularUpdate`).
    pub angular_update: f64,
}

impl Default for MappingScenario {
    fn default() -> Self {
        let s2m = ScanToMapParams::default();
        let gm = GridFastSlamConfig::default();
        Self {
            seed: 1,
            map: "maze".to_owned(),
            steps: 1500,
            poses: PoseSource::ScanToMap,
            rule: RuleKind::Odds,
            resolution: 0.05,
            max_range_free: 5.0,
            l_occ: 0.85,
            l_free: -0.4,
            l_min: -2.0,
            l_max: 3.5,
            hit_probability: 0.55,
            miss_probability: 0.49,
            p_min: 0.1,
            p_max: 0.9,
            linear_search_window: s2m.linear_search_window,
            angular_search_window_deg: s2m.angular_search_window.to_degrees(),
            translation_weight: s2m.translation_weight,
            rotation_weight: s2m.rotation_weight,
            icp_max_distance: 0.5,
            icp_trim: 0.9,
            beams: 360,
            lidar_range: 12.0,
            range_std: 0.03,
            odometry_noise: 1.0,
            particles: gm.particles,
            proposal: gm.proposal,
            resample_threshold: gm.resample_threshold,
            srr: gm.srr,
            srt: gm.srt,
            str: gm.str,
            stt: gm.stt,
            lstep: gm.lstep,
            astep: gm.astep,
            iterations: gm.iterations,
            lsigma: gm.lsigma,
            ogain: gm.ogain,
            linear_update: gm.linear_update,
            angular_update: gm.angular_update,
        }
    }
}

impl MappingScenario {
    /// The update rule with this scenario's numbers.
    pub fn update_rule(&self) -> UpdateRule {
        match self.rule {
            RuleKind::LogOdds => UpdateRule::LogOdds {
                l_occ: self.l_occ,
                l_free: self.l_free,
                l_min: self.l_min,
                l_max: self.l_max,
            },
            RuleKind::Odds => UpdateRule::Odds {
                p_hit: self.hit_probability,
                p_miss: self.miss_probability,
                p_min: self.p_min,
                p_max: self.p_max,
            },
        }
    }

    /// How scans are inserted.
    pub fn insert_params(&self) -> InsertParams {
        InsertParams {
            rule: self.update_rule(),
            max_range_free: self.max_range_free,
        }
    }

    /// Grid FastSLAM's configuration: this scenario's gmapping parameters,
    /// its grid resolution as gmapping's `delta`, the rest gmapping's
    /// defaults.
    pub fn grid_fastslam_config(&self) -> GridFastSlamConfig {
        GridFastSlamConfig {
            particles: self.particles,
            proposal: self.proposal,
            resample_threshold: self.resample_threshold,
            srr: self.srr,
            srt: self.srt,
            str: self.str,
            stt: self.stt,
            lstep: self.lstep,
            astep: self.astep,
            iterations: self.iterations,
            lsigma: self.lsigma,
            ogain: self.ogain,
            linear_update: self.linear_update,
            angular_update: self.angular_update,
            delta: self.resolution,
            ..GridFastSlamConfig::default()
        }
    }

    /// The scan-to-map matcher's parameters.
    pub fn scan_to_map_params(&self) -> ScanToMapParams {
        ScanToMapParams {
            linear_search_window: self.linear_search_window,
            angular_search_window: self.angular_search_window_deg.to_radians(),
            translation_weight: self.translation_weight,
            rotation_weight: self.rotation_weight,
            ..ScanToMapParams::default()
        }
    }
}

/// Every parameter of the lesson, in the order `slamlab params --lesson
/// mapping` lists them. Cartographer's names where it has one.
pub static PARAMS: &[Param<MappingScenario>] = &[
    seed_param(),
    map_param(),
    steps_param(),
    choice_field!(
        "poses",
        "where each scan's pose comes from",
        PoseSource::NAMES,
        PoseSource::ALL,
        poses
    ),
    choice_field!(
        "rule",
        "map update: log-odds (Probabilistic Robotics Table 9.2) or odds (thesis Eq. 5.4)",
        RULES,
        [RuleKind::LogOdds, RuleKind::Odds],
        rule
    ),
    number_field!(
        "resolution",
        "m",
        "grid cell size (gmapping's delta)",
        (0.01, 0.5),
        resolution
    ),
    number_field!(
        "max-range-free",
        "m",
        "free space marked along a beam that returned nothing (missing_data_ray_length)",
        (0.0, 100.0),
        max_range_free
    ),
    number_field!(
        "l-occ",
        "",
        "log-odds rule: added to a hit cell",
        (0.01, 10.0),
        l_occ
    ),
    number_field!(
        "l-free",
        "",
        "log-odds rule: added to a crossed cell",
        (-10.0, -0.01),
        l_free
    ),
    number_field!(
        "l-min",
        "",
        "log-odds rule: lower clamp",
        (-40.0, -0.01),
        l_min
    ),
    number_field!(
        "l-max",
        "",
        "log-odds rule: upper clamp",
        (0.01, 40.0),
        l_max
    ),
    number_field!(
        "hit-probability",
        "",
        "odds rule: p_hit",
        (0.501, 0.999),
        hit_probability
    ),
    number_field!(
        "miss-probability",
        "",
        "odds rule: p_miss",
        (0.001, 0.499),
        miss_probability
    ),
    number_field!("p-min", "", "odds rule: lower clamp", (0.001, 0.499), p_min),
    number_field!("p-max", "", "odds rule: upper clamp", (0.501, 0.999), p_max),
    number_field!(
        "linear-search-window",
        "m",
        "scan-to-map: correlative search half-width in x and y",
        (0.0, 2.0),
        linear_search_window
    ),
    number_field!(
        "angular-search-window-deg",
        "°",
        "scan-to-map: correlative search half-width in heading",
        (0.0, 90.0),
        angular_search_window_deg
    ),
    number_field!(
        "translation-weight",
        "",
        "scan-to-map: pull towards the correlative search's position",
        (0.0, 1000.0),
        translation_weight
    ),
    number_field!(
        "rotation-weight",
        "",
        "scan-to-map: pull towards the correlative search's heading",
        (0.0, 1000.0),
        rotation_weight
    ),
    number_field!(
        "icp-max-distance",
        "m",
        "ICP: correspondences farther apart are rejected",
        (0.01, 10.0),
        icp_max_distance
    ),
    number_field!(
        "icp-trim",
        "",
        "ICP: share of the closest correspondences kept",
        (0.1, 1.0),
        icp_trim
    ),
    count_field!(
        "beams",
        "simulated lidar: beams over 360°",
        (8, 2048),
        beams
    ),
    number_field!(
        "lidar-range",
        "m",
        "simulated lidar: maximum range",
        (1.0, 80.0),
        lidar_range
    ),
    number_field!(
        "range-std",
        "m",
        "simulated lidar: range noise",
        (0.0, 1.0),
        range_std
    ),
    number_field!(
        "odometry-noise",
        "",
        "simulated odometry noise, times the Monte Carlo lesson's α values",
        (0.0, 20.0),
        odometry_noise
    ),
    count_field!(
        "particles",
        "grid FastSLAM: particles, each with its own map",
        (1, MAX_GRID_PARTICLES as u64),
        particles
    ),
    choice_field!(
        "proposal",
        "grid FastSLAM: odometry (the motion model) or scan-match (gmapping's improved proposal)",
        PROPOSALS,
        Proposal::ALL,
        proposal
    ),
    number_field!(
        "resample-threshold",
        "",
        "grid FastSLAM: resample when N_eff falls below this share of the particles",
        (0.0, 1.0),
        resample_threshold
    ),
    number_field!(
        "srr",
        "",
        "grid FastSLAM: translation noise per metre of translation",
        (0.0, 2.0),
        srr
    ),
    number_field!(
        "srt",
        "",
        "grid FastSLAM: rotation noise per metre of translation (rad/m)",
        (0.0, 2.0),
        srt
    ),
    number_field!(
        "str",
        "",
        "grid FastSLAM: translation noise per radian of rotation (m/rad)",
        (0.0, 2.0),
        str
    ),
    number_field!(
        "stt",
        "",
        "grid FastSLAM: rotation noise per radian of rotation",
        (0.0, 2.0),
        stt
    ),
    number_field!(
        "lstep",
        "m",
        "grid FastSLAM: the scan matcher's search half-width in x and y",
        (0.0, 2.0),
        lstep
    ),
    number_field!(
        "astep",
        "rad",
        "grid FastSLAM: the scan matcher's search half-width in heading",
        (0.0, 1.5),
        astep
    ),
    count_field!(
        "iterations",
        "grid FastSLAM: the scan matcher's refinement iterations",
        (1, 100),
        iterations
    ),
    number_field!(
        "lsigma",
        "",
        "grid FastSLAM: the scan likelihood's spread",
        (0.001, 10.0),
        lsigma
    ),
    number_field!(
        "ogain",
        "",
        "grid FastSLAM: weight smoothing gain (weights exp(Δℓ / (ogain · M)))",
        (0.1, 1000.0),
        ogain
    ),
    number_field!(
        "linear-update",
        "m",
        "grid FastSLAM: update after this much translation",
        (0.0, 20.0),
        linear_update
    ),
    number_field!(
        "angular-update",
        "rad",
        "grid FastSLAM: update after this much rotation",
        (0.0, 6.3),
        angular_update
    ),
];

/// The proposals' names, in [`Proposal`] order.
const PROPOSALS: &[&str] = &["odometry", "scan-match"];

impl SimulatedRun for MappingScenario {
    fn run(&self) -> (&str, usize) {
        (&self.map, self.steps)
    }
    fn run_mut(&mut self) -> (&mut u64, &mut String, &mut usize) {
        (&mut self.seed, &mut self.map, &mut self.steps)
    }
}

impl Scenario for MappingScenario {
    const LESSON: &'static str = "mapping";

    fn params() -> &'static [Param<Self>] {
        PARAMS
    }

    fn seed(&self) -> u64 {
        self.seed
    }
}

/// How the scenario's simulated robot records its log: its lidar and its
/// odometry noise (the default's alphas times `odometry-noise`).
pub fn simulated_log_config(scenario: &MappingScenario) -> SimulatedLogConfig {
    let mut config = SimulatedLogConfig::default();
    config.lidar.beams = scenario.beams;
    config.lidar.max_range = scenario.lidar_range;
    config.lidar.range_std = scenario.range_std;
    let k = scenario.odometry_noise.max(0.0);
    config.odom_noise.alpha1 *= k;
    config.odom_noise.alpha2 *= k;
    config.odom_noise.alpha3 *= k;
    config.odom_noise.alpha4 *= k;
    config
}

/// The simulated input of a scenario: the explorer drives the robot through
/// `map` for `scenario.steps` scans (0.1 s apart) with the scenario's lidar and
/// odometry noise. The true poses and the map travel beside the scans for the
/// metrics.
pub fn simulated_input(
    scenario: &MappingScenario,
    map: Arc<OccupancyGrid>,
    map_name: &str,
) -> Result<MappingInput, String> {
    let config = simulated_log_config(scenario);
    let (log, truth) =
        simulate_log(&map, scenario.steps, scenario.seed, &config).map_err(|e| e.to_string())?;
    let mut input = log_input(
        &log,
        &format!("simulated {map_name}, seed {}", scenario.seed),
    );
    input.truth = Some(truth.iter().map(|t| t.pose).collect());
    input.true_map = Some(map);
    Ok(input)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{apply_pairs, to_pairs};

    #[test]
    fn the_table_round_trips_and_refuses_nonsense() {
        let s = MappingScenario {
            poses: PoseSource::Plicp,
            rule: RuleKind::LogOdds,
            resolution: 0.1,
            ..MappingScenario::default()
        };
        let pairs = to_pairs(&s);
        let mut back = MappingScenario::default();
        let owned: Vec<(String, String)> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect();
        let issues = apply_pairs(
            &mut back,
            owned.iter().map(|(k, v)| (k.as_str(), v.as_str())),
            &[],
        );
        assert!(issues.is_empty(), "{issues:?}");
        assert_eq!(to_pairs(&back), pairs);
        let mut bad = MappingScenario::default();
        let issues = apply_pairs(
            &mut bad,
            [("poses", "teleport"), ("resolution", "NaN"), ("p-max", "3")],
            &[],
        );
        assert_eq!(issues.len(), 3, "{issues:?}");
        assert_eq!(bad.poses, PoseSource::ScanToMap);
        assert!(bad.p_max <= 0.999);
    }

    #[test]
    fn pose_source_names_round_trip() {
        for p in PoseSource::ALL {
            assert_eq!(PoseSource::from_name(p.name()), Some(p));
            // Scenario files spell it as the URL does.
            assert_eq!(
                serde_json::to_value(p).unwrap(),
                serde_json::Value::from(p.name())
            );
        }
    }
}
