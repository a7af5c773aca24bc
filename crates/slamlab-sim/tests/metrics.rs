//! The metrics on a lesson's own output: an EKF-SLAM run's path with covariances,
//! written to a file and read back, scores as the lesson scored it.

use slamlab_sim::io::trajectory::{read_trajectory, write_csv};
use slamlab_sim::metrics::{Alignment, EvaluationSettings, Trajectory, evaluate};
use slamlab_sim::world::landmark_scenario::{EstimatorKind, LandmarkScenario};
use slamlab_sim::world::landmark_session::LandmarkSession;

/// An estimate with covariances from EKF-SLAM: written to a CSV file, read back and
/// evaluated against the truth without alignment, its NEES is the lesson's, value
/// for value.
#[test]
fn nees_of_an_exported_ekf_equals_the_lessons() {
    let scenario = LandmarkScenario {
        estimators: vec![EstimatorKind::Ekf],
        seed: 4,
        ..LandmarkScenario::default()
    };
    let mut session = LandmarkSession::new(scenario);
    let (mut truth, mut est) = (Trajectory::default(), Trajectory::default());
    let mut lesson_nees = Vec::new();
    for _ in 0..150 {
        session.step_tick();
        let t = session.time();
        let f = &session.filters()[0];
        let filter = f.filter();
        truth.push(t, session.truth(), None);
        est.push(t, filter.robot_pose(), Some(filter.robot_covariance()));
        lesson_nees.push(f.latest().and_then(|m| m.nees));
    }
    let back = read_trajectory("ekf.csv", write_csv(&est).as_bytes())
        .unwrap()
        .trajectory;
    assert_eq!(back, est);
    let e = evaluate(
        &truth,
        &back,
        &EvaluationSettings {
            alignment: Alignment::None,
            ..EvaluationSettings::default()
        },
    )
    .unwrap();
    let nees = e.nees.unwrap();
    assert_eq!(nees.values, lesson_nees);
    assert!(nees.count > 100, "{}", nees.count);
    assert!(
        nees.anees.unwrap() > 0.5 && nees.anees.unwrap() < 10.0,
        "{:?}",
        nees.anees
    );
}
