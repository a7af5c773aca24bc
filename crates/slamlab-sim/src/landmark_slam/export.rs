//! The landmark lesson's run as files: every path (the truth, dead reckoning,
//! each estimator's with its robot-pose covariance) and each estimator's
//! landmarks with their covariances, as File > Export trajectories in the app and
//! `slamlab run landmark-slam --trajectory-out DIR` write them.

use crate::io::trajectory::LandmarkRow;
use crate::metrics::{NamedTrajectory, Trajectory, TrajectoryRole};
use crate::world::landmark_session::LandmarkSession;
use nalgebra::Matrix3;
use slamlab_core::Pose2;

/// The truth, dead reckoning and every estimator's path so far, each pose at
/// its tick's time (the start at 0). An estimator's covariance at the start is
/// the zero matrix (it knows where it starts), then its robot-pose covariance
/// after every tick. A recorded world's truth is its own track (MRCLAM's Vicon
/// samples, gaps and all); a world without one has no truth file.
pub fn trajectories(session: &LandmarkSession) -> Vec<NamedTrajectory> {
    let times = session.tick_times();
    let path = |poses: &[Pose2]| {
        let n = poses.len().min(times.len());
        Trajectory::new(times[..n].to_vec(), poses[..n].to_vec())
    };
    let truth = match session.recorded_world() {
        None => Some(path(session.truth_path())),
        Some(world) => world.truth.as_ref().map(|t| {
            Trajectory::new(
                t.samples.iter().map(|(time, _)| *time).collect(),
                t.samples.iter().map(|(_, pose)| *pose).collect(),
            )
        }),
    };
    let mut all: Vec<NamedTrajectory> = truth
        .map(|t| NamedTrajectory::new("truth", TrajectoryRole::Truth, t))
        .into_iter()
        .collect();
    all.push(NamedTrajectory::new(
        "dead-reckoning",
        TrajectoryRole::Odometry,
        path(session.dead_reckoning_path()),
    ));
    for run in session.filters() {
        let records = run.records();
        let covariances: Vec<Matrix3<f64>> = records.covariances.clone();
        all.push(NamedTrajectory::new(
            run.kind.name(),
            TrajectoryRole::Estimate,
            path(&records.path).with_covariances(covariances),
        ));
    }
    all
}

/// Each estimator's landmarks now (id, mean, 2x2 covariance), and the true map.
pub fn landmarks(session: &LandmarkSession) -> Vec<(String, Vec<LandmarkRow>)> {
    let mut all = vec![(
        "truth".to_owned(),
        session
            .world()
            .landmarks
            .iter()
            .map(|l| LandmarkRow {
                id: l.id as u64,
                x: l.position.x,
                y: l.position.y,
                covariance: None,
            })
            .collect(),
    )];
    for run in session.filters() {
        let rows = run
            .filter()
            .landmarks()
            .iter()
            .map(|l| LandmarkRow {
                id: l.id as u64,
                x: l.mean.x,
                y: l.mean.y,
                covariance: Some(l.covariance),
            })
            .collect();
        all.push((run.kind.name().to_owned(), rows));
    }
    all
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::trajectory::{export_files, read_landmarks, read_trajectory};
    use crate::metrics::{Alignment, EvaluationSettings, evaluate};
    use crate::world::landmark_scenario::{EstimatorKind, LandmarkScenario};

    /// Exported, read back and evaluated against the exported truth without
    /// alignment, each estimator's NEES is the lesson's, tick by tick, and its
    /// position error is the lesson's error plot.
    #[test]
    fn exported_estimates_score_as_the_lesson_scores_them() {
        let mut session = LandmarkSession::new(LandmarkScenario {
            estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
            seed: 11,
            ..LandmarkScenario::default()
        });
        session.run_ticks(120);
        let files = export_files(
            "landmark-slam",
            &trajectories(&session),
            &landmarks(&session),
        );
        let file = |name: &str| {
            files
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, b)| b.clone())
                .unwrap_or_else(|| {
                    panic!(
                        "no {name} in {:?}",
                        files.iter().map(|f| &f.0).collect::<Vec<_>>()
                    )
                })
        };
        let truth = read_trajectory("truth.csv", &file("truth.csv"))
            .unwrap()
            .trajectory;
        assert_eq!(truth.len(), 121);
        for run in session.filters() {
            let name = run.kind.name();
            let est = read_trajectory("est.csv", &file(&format!("{name}.csv")))
                .unwrap()
                .trajectory;
            let e = evaluate(
                &truth,
                &est,
                &EvaluationSettings {
                    alignment: Alignment::None,
                    ..EvaluationSettings::default()
                },
            )
            .unwrap();
            let lesson_nees: Vec<Option<f64>> = std::iter::once(None)
                .chain(run.records().history.iter().map(|m| m.nees))
                .collect();
            assert_eq!(e.nees.unwrap().values, lesson_nees, "{name}");
            let lesson_errors: Vec<f64> = std::iter::once(0.0)
                .chain(run.records().history.iter().map(|m| m.position_error))
                .collect();
            for (a, b) in e.ape.translation_m.iter().zip(&lesson_errors) {
                assert!((a - b).abs() < 1e-12, "{name}: {a} against {b}");
            }
            // The TUM file gives the same poses to 1e-9.
            let tum = read_trajectory("est.tum", &file(&format!("{name}.tum")))
                .unwrap()
                .trajectory;
            for (a, b) in tum.poses().iter().zip(est.poses()) {
                assert!((a.x - b.x).abs() < 1e-9 && (a.y - b.y).abs() < 1e-9);
                assert!(slamlab_core::wrap_angle(a.theta - b.theta).abs() < 1e-9);
            }
            let rows = read_landmarks(&file(&format!("{name}-landmarks.csv"))).unwrap();
            assert_eq!(rows.len(), run.filter().landmarks().len());
        }
        let readme = String::from_utf8(file("README.txt")).unwrap();
        assert!(
            readme.contains("ekf: an estimate, 121 poses, with covariances"),
            "{readme}"
        );
    }
}
