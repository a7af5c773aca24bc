//! The visual-odometry run as files: the true top-view path of the camera, the
//! wheel odometry, the visual odometry scaled by the wheels' distances and the
//! unit-scale visual odometry (its scale its own: score it with `--align sim2`),
//! one pose per frame, as File > Export trajectories and
//! `slamlab run visual-odometry --trajectory-out DIR` write them.

use super::odometry::{TopPose, VoRun};
use super::world::FRAME_DT;
use crate::metrics::{NamedTrajectory, Trajectory, TrajectoryRole};
use slamlab_core::Pose2;

/// The four top-view paths, frame `k` at `k · FRAME_DT` seconds.
pub fn trajectories(run: &VoRun) -> Vec<NamedTrajectory> {
    let path = |poses: &[TopPose]| {
        Trajectory::new(
            (0..poses.len()).map(|k| k as f64 * FRAME_DT).collect(),
            poses
                .iter()
                .map(|p| Pose2::new(p.x, p.y, p.theta))
                .collect(),
        )
    };
    vec![
        NamedTrajectory::new("truth", TrajectoryRole::Truth, path(&run.truth)),
        NamedTrajectory::new(
            "wheel-odometry",
            TrajectoryRole::Odometry,
            path(&run.wheel_odometry),
        ),
        NamedTrajectory::new(
            "visual-odometry",
            TrajectoryRole::Estimate,
            path(&run.visual_odometry),
        ),
        NamedTrajectory::new(
            "visual-odometry-unit-scale",
            TrajectoryRole::Estimate,
            path(&run.visual_odometry_unit_scale),
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::{Alignment, EvaluationSettings, evaluate};
    use crate::visual_odometry::{VoSettings, run_visual_odometry};

    /// The exported scaled estimate, scored without alignment, has the lesson's
    /// trajectory RMSE.
    #[test]
    fn exported_paths_score_as_the_lesson_does() {
        let run = run_visual_odometry(VoSettings::default());
        let all = trajectories(&run);
        let e = evaluate(
            &all[0].trajectory,
            &all[2].trajectory,
            &EvaluationSettings {
                alignment: Alignment::None,
                ..EvaluationSettings::default()
            },
        )
        .unwrap();
        assert!(
            (e.ape.translation.rmse - run.trajectory_rmse.visual_odometry).abs() < 1e-9,
            "{} against {}",
            e.ape.translation.rmse,
            run.trajectory_rmse.visual_odometry
        );
    }
}
