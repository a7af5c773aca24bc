//! The landmark filters on real data (`slamlab experiment real-data`): each robot
//! of a data set, each estimator and each mode (SLAM, or localization with the
//! landmark map given), scored against the truth with the trajectory metrics
//! ([`crate::metrics`]) as evo scores them: the absolute trajectory error without
//! alignment (MRCLAM's frame is the Vicon frame, where every run starts), the
//! average NEES and the share of the time it spends inside its 95 % band.
//! Dead reckoning (`dead-reckoning`) is the EKF's prediction alone: the path the
//! odometry gives, with the covariance the motion noise grows.

use crate::io::landmark_data::LandmarkData;
use crate::metrics::{
    Alignment, EvaluationSettings, Similarity, Trajectory, evaluate, landmark_errors,
};
use crate::world::landmark_scenario::{EstimatorKind, LandmarkScenario, MapMode};
use crate::world::landmark_session::LandmarkSession;
use crate::world::recorded::{RecordedWorld, StepMotion};
use nalgebra::Matrix3;
use serde::Serialize;
use slamlab_core::belief::PoseBelief;
use slamlab_core::kalman::{EkfSlam, LandmarkSlam};
use std::sync::Arc;

/// An estimator of the experiment: a landmark filter, or dead reckoning.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RealEstimator {
    /// The odometry alone (the EKF's prediction without updates).
    DeadReckoning,
    /// A landmark filter of the lesson.
    Filter(EstimatorKind),
}

impl RealEstimator {
    /// Its name on the command line and in the rows.
    pub fn name(self) -> &'static str {
        match self {
            RealEstimator::DeadReckoning => "dead-reckoning",
            RealEstimator::Filter(kind) => kind.name(),
        }
    }

    /// Looks one up by name (`ideal-ekf` is not among them: it needs a truth
    /// the data does not give the filters).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "dead-reckoning" => Some(RealEstimator::DeadReckoning),
            "ideal-ekf" => None,
            other => EstimatorKind::from_name(other).map(RealEstimator::Filter),
        }
    }
}

/// One row of the experiment: a robot, an estimator and a mode.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RealDataRow {
    /// The robot (MRCLAM), else 0.
    pub robot: u32,
    /// The estimator's name.
    pub estimator: String,
    /// `slam`, `localization`, or `none` for dead reckoning.
    pub mode: String,
    /// The absolute trajectory error's RMSE against the truth without alignment,
    /// metres (evo's `evo_ape` translation RMSE with `--t_max_diff 0.01`).
    pub trajectory_rmse: Option<f64>,
    /// The RMS distance of the final landmarks from the surveyed ones (by id),
    /// metres; `None` for dead reckoning.
    pub landmark_rmse: Option<f64>,
    /// The average robot-pose NEES over the pairs (3 is consistent).
    pub anees: Option<f64>,
    /// The share of the pairs whose NEES lies inside the 95 % band of one value
    /// (χ²₃: 0.216 to 9.35): the share of the time, the truth being sampled evenly.
    pub in_band: Option<f64>,
    /// The pairs of estimate and truth poses the scores are over.
    pub pairs: usize,
    /// The share of the truth's time span the estimate covers.
    pub coverage: f64,
    /// Landmarks in the final map.
    pub landmarks: usize,
    /// The path against the data's GPS (Victoria Park), after the rigid
    /// alignment that carries it onto the fixes: not an error against a truth
    /// (the GPS has metres of its own error and gaps) but how well the path's
    /// shape agrees with an independent sensor. `None` without a GPS.
    pub gps: Option<GpsFit>,
    /// The filter's last error, if a phase failed.
    pub error: Option<String>,
}

/// The robot's estimated path as a trajectory: its pose and covariance after
/// every tick, at the tick's time.
#[derive(Clone, Debug)]
struct Track {
    trajectory: Trajectory,
}

/// Runs one robot of `data` in `mode` with `estimators` (the filters side by
/// side in one session, dead reckoning beside it) on `base`'s noise, and scores
/// every estimator.
pub fn run_robot(
    data: &LandmarkData,
    robot: u32,
    mode: MapMode,
    estimators: &[RealEstimator],
    base: &LandmarkScenario,
) -> Result<Vec<RealDataRow>, String> {
    let world = Arc::new(RecordedWorld::from_data(data, robot)?);
    let filters: Vec<EstimatorKind> = estimators
        .iter()
        .filter_map(|e| match e {
            RealEstimator::Filter(kind) => Some(*kind),
            RealEstimator::DeadReckoning => None,
        })
        .collect();
    let mut rows = Vec::new();
    if !filters.is_empty() {
        let scenario = LandmarkScenario {
            estimators: filters.clone(),
            mode,
            robot,
            ..base.clone()
        };
        let (session, tracks) = run_session(scenario, world.clone());
        if session.filters().len() < filters.len() {
            return Err(format!(
                "not every estimator could start: {}",
                session.notices().join("; ")
            ));
        }
        for (run, track) in session.filters().iter().zip(&tracks) {
            let map: Vec<(u64, [f64; 2])> = run
                .filter()
                .landmarks()
                .iter()
                .map(|l| (l.id as u64, [l.mean[0], l.mean[1]]))
                .collect();
            rows.push(score(
                &world,
                RealEstimator::Filter(run.kind).name(),
                mode.name(),
                &track.trajectory,
                Some(&map),
                run.last_error.clone(),
            ));
        }
    }
    if estimators.contains(&RealEstimator::DeadReckoning) {
        let track = dead_reckoning(&world, base)?;
        rows.insert(
            0,
            score(
                &world,
                "dead-reckoning",
                "none",
                &track.trajectory,
                None,
                None,
            ),
        );
    }
    Ok(rows)
}

/// Runs a session to the end of its world, keeping each filter's poses and
/// covariances tick by tick.
fn run_session(
    scenario: LandmarkScenario,
    world: Arc<RecordedWorld>,
) -> (LandmarkSession, Vec<Track>) {
    let start = world.start;
    let mut session = LandmarkSession::recorded(scenario, world);
    let mut tracks: Vec<Track> = session
        .filters()
        .iter()
        .map(|run| Track {
            trajectory: Trajectory::new(vec![0.0], vec![start])
                .with_covariances(vec![run.filter().robot_covariance()]),
        })
        .collect();
    while !session.is_finished() {
        session.step_tick();
        let time = session.time();
        for (track, run) in tracks.iter_mut().zip(session.filters()) {
            track.trajectory.push(
                time,
                run.filter().robot_pose(),
                Some(run.filter().robot_covariance()),
            );
        }
    }
    (session, tracks)
}

/// The odometry alone: an EKF predicting every step and never updating, so its
/// mean is the dead-reckoning path and its covariance what the motion noise grows.
fn dead_reckoning(world: &RecordedWorld, scenario: &LandmarkScenario) -> Result<Track, String> {
    let mut ekf = EkfSlam::new(scenario.filter_config(), world.start).map_err(|e| e.to_string())?;
    let noise = scenario.recorded_noise();
    let mut trajectory =
        Trajectory::new(vec![0.0], vec![world.start]).with_covariances(vec![Matrix3::zeros()]);
    for step in &world.steps {
        let predicted = match (step.motion, step.motion.recorded(&noise)) {
            (StepMotion::Velocity { control, dt }, _) => ekf.predict(&control, dt),
            (_, Some(motion)) => ekf.predict_recorded(&motion),
            (_, None) => continue,
        };
        predicted.map_err(|e| e.to_string())?;
        trajectory.push(step.time, ekf.robot_pose(), Some(ekf.robot_covariance()));
    }
    Ok(Track { trajectory })
}

/// One estimator's row: its trajectory against the truth without alignment, its
/// final map against the surveyed landmarks.
fn score(
    world: &RecordedWorld,
    estimator: &str,
    mode: &str,
    estimate: &Trajectory,
    map: Option<&[(u64, [f64; 2])]>,
    error: Option<String>,
) -> RealDataRow {
    let truth = world.truth.as_ref().map(|t| {
        Trajectory::new(
            t.samples.iter().map(|(time, _)| *time).collect(),
            t.samples.iter().map(|(_, pose)| *pose).collect(),
        )
    });
    let settings = EvaluationSettings {
        alignment: Alignment::None,
        ..EvaluationSettings::default()
    };
    let evaluation = truth
        .as_ref()
        .and_then(|truth| evaluate(truth, estimate, &settings).ok());
    let surveyed: Vec<(u64, [f64; 2])> = world
        .landmarks
        .iter()
        .map(|(l, _)| (l.id as u64, [l.position[0], l.position[1]]))
        .collect();
    let landmark_rmse = map.and_then(|map| {
        let errors = landmark_errors(map, &surveyed, &Similarity::IDENTITY);
        (!errors.is_empty()).then(|| {
            (errors.iter().map(|e| e.error_m * e.error_m).sum::<f64>() / errors.len() as f64).sqrt()
        })
    });
    RealDataRow {
        robot: world.robot,
        estimator: estimator.to_owned(),
        mode: mode.to_owned(),
        trajectory_rmse: evaluation.as_ref().map(|e| e.ape.translation.rmse),
        landmark_rmse,
        anees: evaluation.as_ref().and_then(|e| e.nees.as_ref()?.anees),
        in_band: evaluation
            .as_ref()
            .and_then(|e| e.nees.as_ref()?.share_in_band),
        pairs: evaluation.as_ref().map_or(0, |e| e.pairing.pairs),
        coverage: evaluation.as_ref().map_or(0.0, |e| e.pairing.coverage),
        landmarks: map.map_or(0, <[_]>::len),
        gps: gps_fit(world, estimate),
        error,
    }
}

/// The scenario's parameters that do not reach a replay of any data set: the
/// simulated world's (its landmarks, layout and size), the scripted robot's
/// (controller, speed, turn rate, tick length: the data has its own steps) and
/// the simulated car's wheel base (Victoria Park's car is the data's).
const SIMULATION_ONLY: [&str; 8] = [
    "controller",
    "v",
    "w-deg",
    "dt",
    "landmarks",
    "layout",
    "world-size",
    "wheel-base",
];

/// The parameters a run of `slamlab experiment real-data` used, as
/// [`crate::landmark_slam::summary::parameters_json`] prints them, but only
/// those that reach the replay of `kind`: the data set's motion noise (MRCLAM's
/// `(v, ω)` noise and velocity model, the Freiburg odometry's `(δrot1, δtrans,
/// δrot2)` noise, Victoria Park's speed and steering noise), the camera's or
/// laser's noise and reach, the association and its gates, and the filters'
/// own settings for the filters that ran. `estimator`, `mode` and `robot` are
/// the lists the experiment ran, not the base scenario's single values.
pub fn parameters_used(
    base: &LandmarkScenario,
    kind: crate::io::landmark_data::DataSetKind,
    estimators: &[RealEstimator],
    modes: &[MapMode],
    robots: &[u32],
) -> serde_json::Map<String, serde_json::Value> {
    use crate::io::landmark_data::DataSetKind;
    use crate::world::landmark_scenario::Association;
    let motion: &[&str] = match kind {
        DataSetKind::Mrclam => &["v-std", "w-std-deg", "motion"],
        DataSetKind::Freiburg => &["odometry-rot-std", "odometry-trans-std"],
        DataSetKind::VictoriaPark => &["v-std", "steering-std-deg"],
    };
    let other_motion = [
        "v-std",
        "w-std-deg",
        "motion",
        "odometry-rot-std",
        "odometry-trans-std",
        "steering-std-deg",
    ];
    let runs = |f: fn(EstimatorKind) -> bool| {
        estimators
            .iter()
            .any(|e| matches!(e, RealEstimator::Filter(k) if f(*k)))
    };
    let ukf = runs(|k| k == EstimatorKind::Ukf);
    let particles = runs(|k| matches!(k, EstimatorKind::FastSlam1 | EstimatorKind::FastSlam2));
    let unknown = base.association == Association::Unknown;
    let mut used = crate::landmark_slam::summary::parameters_json(base);
    used.retain(|name, _| {
        let name = name.as_str();
        !SIMULATION_ONLY.contains(&name)
            && (motion.contains(&name) || !other_motion.contains(&name))
            && (ukf || !name.starts_with("ukf-"))
            && (particles
                || !matches!(
                    name,
                    "particles" | "fastslam-resampler" | "resample-threshold" | "seed"
                ))
            && (unknown || !matches!(name, "gate" | "new-landmark-threshold"))
    });
    let list = |items: Vec<String>| serde_json::Value::String(items.join(","));
    used.insert(
        "estimator".to_owned(),
        list(estimators.iter().map(|e| e.name().to_owned()).collect()),
    );
    used.insert(
        "mode".to_owned(),
        list(modes.iter().map(|m| m.name().to_owned()).collect()),
    );
    match kind {
        DataSetKind::Mrclam => {
            used.insert(
                "robot".to_owned(),
                list(robots.iter().map(u32::to_string).collect()),
            );
        }
        DataSetKind::Freiburg | DataSetKind::VictoriaPark => {
            used.remove("robot");
        }
    }
    used
}

/// How far apart two paired times of the path and the GPS may be, seconds:
/// Victoria Park's steps come at about 40 Hz (inputs) with laser scans between,
/// so every fix inside the run has a step within about 13 ms.
pub const GPS_MAX_DIFF: f64 = 0.05;

/// An estimated path carried onto a data set's GPS fixes (Victoria Park) by
/// the rigid transform that fits them best (Umeyama's method over the fixes
/// paired with the path's poses in time, [`crate::metrics::umeyama`]), and the
/// distance that remains: the GPS alignment RMSE
/// `sqrt(1/N Σ |g_i - (R p_i + t)|²)` over the `N` pairs.
///
/// The GPS is no truth: its fixes are off by metres under the trees and it
/// drops out, so the RMSE bounds how well the path's shape agrees with an
/// independent sensor (and includes the GPS's own error), and the transform is
/// where the GPS's frame sits against the estimate's (for EKF-SLAM's whole
/// Victoria Park run: 2.3° and (-1.6, -0.6) m, `docs/real-landmark-data.md`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct GpsFit {
    /// The RMS distance between the fixes and the aligned path, metres.
    pub rmse: f64,
    /// The fixes paired with a pose of the path (within [`GPS_MAX_DIFF`]).
    pub pairs: usize,
    /// The fixes the data has.
    pub fixes: usize,
    /// The rotation that carries the path into the GPS's frame, degrees.
    pub rotation_deg: f64,
    /// The translation that carries the path into the GPS's frame, metres.
    pub translation_m: [f64; 2],
    /// The transform itself (estimate to GPS).
    #[serde(skip)]
    pub similarity: Similarity,
}

impl GpsFit {
    /// A GPS fix in the estimate's frame (the alignment undone:
    /// `Rᵀ (g - t)`), for drawing it over the estimate.
    pub fn to_estimate_frame(&self, fix: [f64; 2]) -> [f64; 2] {
        let (s, c) = slamlab_core::math::sin_cos(self.similarity.rotation);
        let [tx, ty] = self.similarity.translation;
        let (dx, dy) = (fix[0] - tx, fix[1] - ty);
        let k = 1.0 / self.similarity.scale;
        [k * (c * dx + s * dy), k * (-s * dx + c * dy)]
    }
}

/// The path `estimate` against the GPS of `world` ([`GpsFit`]); `None`
/// without a GPS or with fewer than two distinct paired positions.
pub fn gps_fit(world: &RecordedWorld, estimate: &Trajectory) -> Option<GpsFit> {
    let evaluation = reference_alignment(world, estimate, GPS_MAX_DIFF)?;
    Some(GpsFit {
        rmse: evaluation.ape.translation.rmse,
        pairs: evaluation.pairing.pairs,
        fixes: world.reference.len(),
        rotation_deg: evaluation.alignment.rotation_deg,
        translation_m: evaluation.alignment.translation_m,
        similarity: evaluation.similarity,
    })
}

/// The estimated path against a recorded world's reference (Victoria Park's GPS,
/// in a frame of its own): the rigid transform that best carries the path onto
/// the fixes (Umeyama's method over the pairs within `max_diff` seconds) and the
/// RMS distance that remains, over the fixes within the path's time span. `None`
/// without a reference or a pair.
pub fn reference_alignment(
    world: &RecordedWorld,
    estimate: &Trajectory,
    max_diff: f64,
) -> Option<crate::metrics::Evaluation> {
    // Only the fixes within the path's time span: a path still being driven
    // (the lesson's) is then the longer of the two, and each fix finds its step
    // (evo pairs from the shorter trajectory, which would otherwise be the path,
    // pairing one fix with every step near it).
    let start = estimate.stamps().first()? - max_diff;
    let end = estimate.stamps().last()? + max_diff;
    let fixes: Vec<&(f64, nalgebra::Vector2<f64>)> = world
        .reference
        .iter()
        .filter(|(t, _)| (start..=end).contains(t))
        .collect();
    if fixes.is_empty() {
        return None;
    }
    let reference = Trajectory::new(
        fixes.iter().map(|(t, _)| *t).collect(),
        fixes
            .iter()
            .map(|(_, p)| slamlab_core::Pose2::new(p[0], p[1], 0.0))
            .collect(),
    );
    let settings = EvaluationSettings {
        alignment: Alignment::Se2,
        max_diff,
        ..EvaluationSettings::default()
    };
    evaluate(&reference, estimate, &settings).ok()
}

#[cfg(test)]
mod tests;
