//! The SLAM pose taken from the landmark lesson's EKF-SLAM on the same drive,
//! instead of the white-noise-and-drift model.

use super::log::{Arrival, SLAM, SensorLog};
use crate::world::landmark_scenario::{ControllerKind, EstimatorKind, LandmarkScenario};
use crate::world::landmark_session::LandmarkSession;
use crate::world::landmarks::LandmarkLayout;
use nalgebra::Matrix3;
use slamlab_core::geometry::Pose2;
use slamlab_core::kalman::fusion::Reading;
use slamlab_core::math;
use slamlab_core::motion::Control;

/// The smallest standard deviations given to an EKF-SLAM pose, metres and
/// radians: at the start EKF-SLAM knows the robot's pose exactly (zero covariance),
/// which the fusion filter would refuse as noise that is not positive.
const POSE_STD_FLOOR: [f64; 3] = [0.001, 0.001, 0.001];

/// Replaces `log`'s SLAM readings with EKF-SLAM's robot pose (estimate and
/// covariance) from a [`LandmarkSession`] driven with the same commands.
///
/// The session runs the landmark lesson's EKF-SLAM (thesis `000` Sec. 3.2) at its
/// 0.1 s tick among 30 seeded random landmarks in a 12 m world, with the lesson's
/// sensor (120°, 4 m, 0.5 m and 10° noise) and executed-command noise of
/// 0.005 m/s and 0.6 °/s. Its commands are the drive's true speed and yaw rate
/// averaged over each tick. The session's robot starts elsewhere in its world, so
/// the SLAM error is carried over in the robot's frame: the reported pose is
/// `truth ∘ (session_truth⁻¹ ∘ session_estimate)`, its covariance rotated alike.
/// A pose is taken every `1 / rate` seconds, stamped at the tick's end and arriving
/// after the scenario's latency.
pub(crate) fn replace_slam_with_landmark_ekf(
    log: &mut SensorLog,
    seed: u64,
    rate: f64,
    latency: f64,
) {
    let dt = 0.1;
    let mut session = LandmarkSession::new(LandmarkScenario {
        seed,
        dt,
        world_size: 12.0,
        landmarks: 30,
        layout: LandmarkLayout::Random,
        v_std: 0.005,
        w_std: 0.6_f64.to_radians(),
        controller: ControllerKind::Manual,
        estimators: vec![EstimatorKind::Ekf],
        ..LandmarkScenario::default()
    });
    let ticks = (log.duration() / dt).floor() as usize;
    let every = ((1.0 / rate) / dt).round().max(1.0) as usize;
    let per_tick = (dt / log.truth_dt).round().max(1.0) as usize;
    let mut poses = Vec::new();
    let mut arrivals = Vec::new();
    for k in 0..=ticks {
        let t = k as f64 * dt;
        if k > 0 {
            // The true commands averaged over the tick that ends at t.
            let samples = &log.truth[(k - 1) * per_tick..(k * per_tick).min(log.truth.len())];
            let n = samples.len().max(1) as f64;
            let v = samples.iter().map(|s| s.v).sum::<f64>() / n;
            let w = samples.iter().map(|s| s.w).sum::<f64>() / n;
            session.set_teleop(Control::new(v, w));
            session.step_tick();
        }
        if k % every != 0 {
            continue;
        }
        let Some(run) = session.filters().first().cloned() else {
            return;
        };
        let estimate = run.filter().robot_pose();
        let covariance = run.filter().robot_covariance();
        let session_truth = session.truth();
        let truth = log.truth_at(t);
        let reported = truth.compose(&session_truth.between(&estimate));
        // From the session's world into the drive's: a rotation by the headings' difference.
        let (s, c) = math::sin_cos(truth.theta - session_truth.theta);
        let rot = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        let mut cov = rot * covariance * rot.transpose();
        for i in 0..3 {
            cov[(i, i)] = cov[(i, i)].max(POSE_STD_FLOOR[i].powi(2));
        }
        poses.push((t, reported));
        let reading = Reading::Pose {
            pose: Pose2::new(reported.x, reported.y, reported.theta),
            covariance: cov,
        };
        arrivals.push(Arrival::new(SLAM, t, t + latency, reading));
    }
    log.measurements.retain(|a| a.measurement.sensor != SLAM);
    log.measurements.extend(arrivals);
    log.measurements.sort_by(|a, b| {
        a.arrival
            .total_cmp(&b.arrival)
            .then(a.measurement.stamp.total_cmp(&b.measurement.stamp))
    });
    log.slam_poses = poses;
    log.relocalizations.clear();
}
