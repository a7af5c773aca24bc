//! The Monte Carlo localization run as files: the true pose and each filter's
//! estimate at the end of every tick, with the covariance of its particle cloud,
//! as File > Export trajectories and `slamlab run kidnap --trajectory-out DIR`
//! write them.

use super::run::MclRun;
use crate::metrics::{NamedTrajectory, Trajectory, TrajectoryRole};

/// The truth and each filter's estimates, stamped at the end of their ticks
/// (`k · dt` for tick `k`, from 1; for a replayed log the scan's time since the
/// log's first scan). A filter's trajectory starts at its first estimate (a
/// global localization has none before its first update). A log without truth
/// has no truth trajectory.
pub fn trajectories(run: &MclRun) -> Vec<NamedTrajectory> {
    let stamp = |k: usize| run.tick_time(k);
    let truth = run.truth_ticks();
    let mut all = Vec::new();
    if run.has_truth() {
        all.push(NamedTrajectory::new(
            "truth",
            TrajectoryRole::Truth,
            Trajectory::new((0..truth.len()).map(stamp).collect(), truth.to_vec()),
        ));
    }
    for f in run.filters() {
        let mut t = Trajectory::default();
        for (k, e) in f.estimates.iter().enumerate() {
            if let Some((pose, covariance)) = e {
                t.push(stamp(k), *pose, Some(*covariance));
            }
        }
        all.push(NamedTrajectory::new(f.name, TrajectoryRole::Estimate, t));
    }
    all
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::BuiltinMap;
    use crate::kidnap::scenario::{InitMode, MclScenario};
    use crate::metrics::{Alignment, EvaluationSettings, evaluate};

    /// An exported estimate scored against the exported truth has the errors the
    /// lesson plots, tick by tick.
    #[test]
    fn exported_estimates_have_the_lessons_errors() {
        let scenario = MclScenario {
            init: InitMode::Tracking,
            max_particles: 300,
            min_particles: 300,
            ..MclScenario::default()
        };
        let grid = BuiltinMap::Maze.load().unwrap();
        let mut run = MclRun::new(scenario, grid).unwrap();
        run.run_ticks(60);
        let all = trajectories(&run);
        let truth = &all[0].trajectory;
        assert_eq!(truth.len(), 60);
        for (f, exported) in run.filters().iter().zip(&all[1..]) {
            let e = evaluate(
                truth,
                &exported.trajectory,
                &EvaluationSettings {
                    alignment: Alignment::None,
                    ..EvaluationSettings::default()
                },
            )
            .unwrap();
            let offset = truth.len() - exported.trajectory.len();
            for (k, err) in e.ape.translation_m.iter().enumerate() {
                let lesson = f.ticks[k + offset].position;
                assert!(
                    (err - lesson).abs() < 1e-12,
                    "{}: tick {k}: {err} against {lesson}",
                    f.name
                );
            }
        }
    }
}
