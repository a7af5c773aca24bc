//! Presets: named scenarios that open exactly what a source shows ("thesis
//! Experiment 2") or a lesson's key comparison. A preset sets every parameter but
//! the seed; parameters given beside it (`?preset=thesis-exp2&landmarks=30`,
//! `--preset thesis-exp2 --landmarks 30`) apply on top, whatever their order.

use crate::io::landmark_data::DataSetKind;
use crate::params::Preset;
use crate::world::landmark_scenario::ekf_vs_ukf_scenario;
use crate::world::landmark_scenario::{Association, EstimatorKind, LandmarkScenario};

/// Every preset, in menu order.
pub static PRESETS: &[Preset<LandmarkScenario>] = &[
    Preset {
        id: "lesson",
        title: "EKF vs UKF (the lesson's start)",
        summary: "The teaching rings, a 120° 4 m sensor with 0.5 m / 10° noise, EKF-SLAM and UKF-SLAM side by side.",
        build: lesson,
    },
    Preset {
        id: "thesis-exp1",
        title: "Thesis Experiment 1",
        summary: "Xiang's thesis §3.4.3: 20 random landmarks, q = [0.1 m/s, 10°/s], v = [2 m, 10°], EKF and UKF.",
        build: |seed| ekf_vs_ukf_scenario(1.0, seed),
    },
    Preset {
        id: "thesis-exp2",
        title: "Thesis Experiment 2 (doubled control noise)",
        summary: "Experiment 1 with q doubled to [0.2 m/s, 20°/s]: where Xiang's thesis says the EKF may diverge.",
        build: |seed| ekf_vs_ukf_scenario(2.0, seed),
    },
    Preset {
        id: "ekf-vs-fej",
        title: "Why EKF-SLAM grows overconfident (EKF vs FEJ-EKF)",
        summary: "The same EKF linearized at its latest estimates and at its first ones: watch the NEES over a lap.",
        build: |seed| LandmarkScenario {
            estimators: vec![EstimatorKind::Ekf, EstimatorKind::FejEkf],
            ..lesson(seed)
        },
    },
    Preset {
        id: "precise-range",
        title: "Precise range, coarse bearing",
        summary: "0.1 m range noise with 10° bearing noise: a crescent-shaped likelihood no linearization follows.",
        build: |seed| LandmarkScenario {
            range_std: 0.1,
            ..lesson(seed)
        },
    },
    Preset {
        id: "mrclam",
        title: "UTIAS MRCLAM data: the noise measured against Vicon",
        summary: "EKF and UKF on an MRCLAM robot (open the data with data= or --data): odometry and camera noise as measured against the Vicon truth.",
        build: mrclam,
    },
    Preset {
        id: "freiburg",
        title: "Freiburg course data: the course's noise",
        summary: "EKF and UKF on the course's world.dat and sensor_data.dat (open them with data= or --data), with the noise of its exercises.",
        build: freiburg,
    },
    Preset {
        id: "victoria-park",
        title: "Victoria Park: trees without identities",
        summary: "EKF-SLAM with nearest-neighbour gating beside FastSLAM 2.0 with per-particle association on Victoria Park's trees (open the data with data= or --data).",
        build: victoria_park,
    },
];

/// The noise of the UTIAS MRCLAM data, measured against its Vicon truth over all
/// five robots of Dataset 6 ([`crate::world::recorded::mrclam::measure_noise`],
/// 1 s windows; the robust spreads, `1.4826 · MAD`): odometry 0.062 m/s and
/// 7.2°/s per step, camera 0.13 m and 0.48°. `docs/real-landmark-data.md` has
/// the numbers and how they were measured.
pub const MRCLAM_NOISE: [f64; 4] = [0.062, 7.2, 0.13, 0.48];

fn mrclam(seed: u64) -> LandmarkScenario {
    let [v, w_deg, range, bearing_deg] = MRCLAM_NOISE;
    LandmarkScenario {
        seed,
        v_std: v,
        w_std: w_deg.to_radians(),
        range_std: range,
        bearing_std: bearing_deg.to_radians(),
        // Every measurement: the camera's longest range in Dataset 6 is 8.6 m.
        max_range: 100.0,
        fov: 2.0 * std::f64::consts::PI,
        estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
        ..LandmarkScenario::default()
    }
}

/// The Freiburg course's noise: its FastSLAM exercise's odometry noise
/// `[0.005, 0.01, 0.005]` (rotation, translation, rotation: standard deviations)
/// and its EKF exercise's measurement noise `Q = 0.01 I` (0.1 m, 0.1 rad).
fn freiburg(seed: u64) -> LandmarkScenario {
    LandmarkScenario {
        seed,
        odometry_rot_std: 0.005,
        odometry_trans_std: 0.01,
        range_std: 0.1,
        bearing_std: 0.1,
        max_range: 100.0,
        fov: 2.0 * std::f64::consts::PI,
        estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
        ..LandmarkScenario::default()
    }
}

/// Victoria Park: unknown association, the car's speed and steering noise, the
/// laser's range and bearing noise (see `docs/real-landmark-data.md`).
fn victoria_park(seed: u64) -> LandmarkScenario {
    LandmarkScenario {
        seed,
        v_std: 0.5,
        steering_std: 3.0_f64.to_radians(),
        range_std: 0.5,
        bearing_std: 1.0_f64.to_radians(),
        association: Association::Unknown,
        max_range: 30.0,
        fov: std::f64::consts::PI,
        estimators: vec![EstimatorKind::Ekf, EstimatorKind::FastSlam2],
        ..LandmarkScenario::default()
    }
}

/// The lesson's start: the simulator's defaults with EKF-SLAM and UKF-SLAM.
fn lesson(seed: u64) -> LandmarkScenario {
    LandmarkScenario {
        seed,
        estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
        ..LandmarkScenario::default()
    }
}

/// The preset ids, for the parameter table.
pub const PRESET_IDS: &[&str] = &[
    "lesson",
    "thesis-exp1",
    "thesis-exp2",
    "ekf-vs-fej",
    "precise-range",
    "mrclam",
    "freiburg",
    "victoria-park",
];

/// The preset a recorded data set opens with (its noise, its estimators).
pub fn for_data(kind: DataSetKind) -> &'static str {
    match kind {
        DataSetKind::Mrclam => "mrclam",
        DataSetKind::Freiburg => "freiburg",
        DataSetKind::VictoriaPark => "victoria-park",
    }
}

/// The scenario of preset `id` with `seed`, or `None` for an unknown id.
pub fn scenario(id: &str, seed: u64) -> Option<LandmarkScenario> {
    find(id).map(|p| (p.build)(seed))
}

/// Looks a preset up by id.
pub fn find(id: &str) -> Option<&'static Preset<LandmarkScenario>> {
    PRESETS.iter().find(|p| p.id == id)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params;

    #[test]
    fn every_preset_is_listed_once_and_builds_a_checked_scenario() {
        let ids: Vec<&str> = PRESETS.iter().map(|p| p.id).collect();
        assert_eq!(ids, PRESET_IDS);
        for id in PRESET_IDS {
            let mut s = scenario(id, 42).unwrap_or_else(|| panic!("{id}"));
            assert_eq!(s.seed, 42, "{id} keeps the seed");
            assert!(params::sanitize(&mut s).is_empty(), "{id} is in range");
            assert!(find(id).is_some());
        }
        assert!(scenario("nope", 1).is_none());
    }

    #[test]
    fn the_thesis_presets_are_the_cli_experiments() {
        assert_eq!(
            scenario("thesis-exp1", 9),
            Some(ekf_vs_ukf_scenario(1.0, 9))
        );
        let exp2 = scenario("thesis-exp2", 9).unwrap_or_else(|| panic!("exp2"));
        assert!((exp2.v_std - 0.2).abs() < 1e-12 && (exp2.range_std - 2.0).abs() < 1e-12);
        assert_eq!(
            scenario("ekf-vs-fej", 1).map(|s| s.estimators),
            Some(vec![EstimatorKind::Ekf, EstimatorKind::FejEkf])
        );
    }
}
