//! The Kalman filters with recorded motions (odometry readings, the ACFR car)
//! and with a map given before the run.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // a failing test stops

use super::ukf_slam::tests::config;
use super::*;
use crate::motion::recorded::tests::{car, odometry};
use nalgebra::{Matrix3, Vector3};

/// An EKF that has seen a landmark and moved, so its covariance has cross terms.
fn warmed_up<F: LandmarkSlam>(mut filter: F) -> F {
    filter.update(3, &RangeBearing::new(4.0, 0.4)).unwrap();
    for _ in 0..5 {
        filter.predict(&Control::new(1.0, 0.3), 0.1).unwrap();
    }
    filter.update(3, &RangeBearing::new(3.7, 0.1)).unwrap();
    filter
}

#[test]
fn the_ekf_propagates_f_p_ft_plus_g_m_gt() {
    for motion in [odometry(0.2, 0.5, -0.1), car(3.0, 0.1), car(-1.0, -0.3)] {
        let mut ekf = warmed_up(EkfSlam::new(config(), Pose2::new(1.0, 2.0, 0.3)).unwrap());
        let before = ekf.covariance().clone();
        let pose = ekf.robot_pose();
        ekf.predict_recorded(&motion).unwrap();
        let step = motion.step(&pose).unwrap();
        assert_eq!(ekf.robot_pose(), step.pose);
        let f = step.jacobian_pose;
        let g = step.jacobian_input;
        let expected_rr = f * before.fixed_view::<3, 3>(0, 0) * f.transpose()
            + g * step.input_covariance * g.transpose();
        assert!(
            (ekf.robot_covariance() - expected_rr).norm() < 1e-12,
            "{motion:?}"
        );
        let expected_rl = f * before.fixed_view::<3, 2>(0, 3);
        assert!(
            (ekf.covariance().fixed_view::<3, 2>(0, 3) - expected_rl).norm() < 1e-12,
            "{motion:?}"
        );
        assert_eq!(
            ekf.covariance().fixed_view::<2, 2>(3, 3),
            before.fixed_view::<2, 2>(3, 3),
            "the landmark block does not change"
        );
    }
}

/// The second-order mean shift `½ Σ σᵢ² ∂²f/∂uᵢ² + ½ P_θθ ∂²f/∂θ²` of a motion
/// (f is linear in x and y), by central differences.
fn second_order_shift(
    motion: &RecordedMotion,
    pose: &Pose2,
    heading_variance: f64,
) -> Vector3<f64> {
    let h = 1e-4;
    let at = |pose: &Pose2, noise: [f64; 3]| motion.apply(pose, &noise).unwrap().to_vector();
    let centre = at(pose, [0.0; 3]);
    let wrap = |mut v: Vector3<f64>| {
        v[2] = crate::geometry::wrap_angle(v[2]);
        v
    };
    let mut shift = Vector3::zeros();
    let std = motion.input_std();
    for i in 0..motion.input_dim() {
        let mut e = [0.0; 3];
        e[i] = h;
        let plus = wrap(at(pose, e) - centre);
        let minus = wrap(at(pose, e.map(|v| -v)) - centre);
        shift += (plus + minus) / (h * h) * std[i] * std[i] / 2.0;
    }
    let turned = |d: f64| Pose2 {
        theta: pose.theta + d,
        ..*pose
    };
    let plus = wrap(at(&turned(h), [0.0; 3]) - centre);
    let minus = wrap(at(&turned(-h), [0.0; 3]) - centre);
    shift + (plus + minus) / (h * h) * heading_variance / 2.0
}

#[test]
fn the_ukf_prediction_is_the_linearized_one_plus_the_second_order_shift() {
    // Small noise and short moves are nearly linear: the UKF's predicted mean is
    // the EKF's plus the second-order shift the EKF drops (d σ² / 2 for a step of
    // length d along a heading of variance σ², and the car's curvature in its
    // steering), and its covariance the EKF's formula on the UKF's own prior.
    for motion in [odometry(0.05, 0.1, 0.02), car(2.0, 0.05)] {
        let mut ukf = warmed_up(
            UkfSlam::new(
                config(),
                UnscentedParams::default(),
                Pose2::new(1.0, 2.0, 0.3),
            )
            .unwrap(),
        );
        let (prior_pose, prior) = (ukf.robot_pose(), ukf.robot_covariance());
        let step = motion.step(&prior_pose).unwrap();
        ukf.predict_recorded(&motion).unwrap();
        let linear = step.jacobian_pose * prior * step.jacobian_pose.transpose()
            + step.jacobian_input * step.input_covariance * step.jacobian_input.transpose();
        let shift = second_order_shift(&motion, &prior_pose, prior[(2, 2)]);
        let dp = ukf.robot_pose().to_vector() - step.pose.to_vector();
        let dc = (ukf.robot_covariance() - linear).norm();
        println!(
            "{motion:?}: mean shift {:.3e} m, second order {:.3e} m, covariance {dc:.3e} of {:.3e}",
            dp.norm(),
            shift.norm(),
            linear.norm()
        );
        assert!(shift.norm() > 1e-6);
        assert!(
            (dp - shift).norm() < 0.05 * shift.norm(),
            "{motion:?}: {dp} vs {shift}"
        );
        assert!(dc < 1e-3 * linear.norm(), "{motion:?}: {dc}");
    }
}

#[test]
fn standing_still_leaves_the_covariance_as_it_is() {
    let mut ekf = warmed_up(EkfSlam::new(config(), Pose2::IDENTITY).unwrap());
    let mut ukf =
        warmed_up(UkfSlam::new(config(), UnscentedParams::default(), Pose2::IDENTITY).unwrap());
    let (pe, pu) = (ekf.robot_covariance(), ukf.robot_covariance());
    ekf.predict_recorded(&car(0.0, 0.2)).unwrap();
    ukf.predict_recorded(&odometry(0.0, 0.0, 0.0)).unwrap();
    assert_eq!(ekf.robot_covariance(), pe);
    assert!((ukf.robot_covariance() - pu).norm() < 1e-15);
    let sharp = car(1.0, 1.4);
    assert!(matches!(
        ekf.predict_recorded(&sharp),
        Err(FilterError::InvalidMotion(_))
    ));
    assert!(matches!(
        ukf.predict_recorded(&sharp),
        Err(FilterError::InvalidMotion(_))
    ));
}

#[test]
fn a_given_map_localizes_the_robot_and_barely_moves() {
    let map = [(6, Vector2::new(3.0, 1.0)), (7, Vector2::new(-1.0, 4.0))];
    let tiny = Matrix2::new(1e-8, 0.0, 0.0, 1e-8);
    let mut filters: Vec<Box<dyn LandmarkSlam>> = vec![
        Box::new(EkfSlam::new(config(), Pose2::IDENTITY).unwrap()),
        Box::new(
            EkfSlam::with_linearization(config(), Pose2::IDENTITY, Linearization::FirstEstimates)
                .unwrap(),
        ),
        Box::new(UkfSlam::new(config(), UnscentedParams::default(), Pose2::IDENTITY).unwrap()),
    ];
    for filter in &mut filters {
        for (id, position) in map {
            filter.insert_landmark(id, position, tiny).unwrap();
        }
        assert_eq!(filter.landmark_ids(), [6, 7]);
        assert!(matches!(
            filter.insert_landmark(6, Vector2::new(0.0, 0.0), tiny),
            Err(FilterError::InvalidLandmark { id: 6, .. })
        ));
        assert!(
            filter
                .insert_landmark(8, Vector2::new(f64::NAN, 0.0), tiny)
                .is_err()
        );
        assert!(
            filter
                .insert_landmark(8, Vector2::new(0.0, 0.0), Matrix2::new(1.0, 2.0, 2.0, 1.0))
                .is_err()
        );
        // Drive without seeing anything, then see both landmarks where they are.
        for _ in 0..20 {
            filter.predict(&Control::new(0.5, 0.0), 0.1).unwrap();
        }
        let grown = filter.robot_covariance().trace();
        let truth = Pose2::new(1.0, 0.0, 0.0);
        for (id, position) in map {
            let z = crate::range_bearing::predict(&truth, &position)
                .unwrap()
                .measurement;
            filter.update(id, &z).unwrap();
        }
        assert!(
            filter.robot_covariance().trace() < 0.8 * grown,
            "{}: {} of {grown}",
            filter.name(),
            filter.robot_covariance().trace()
        );
        for l in filter.landmarks() {
            let given = map.iter().find(|(id, _)| *id == l.id).unwrap().1;
            assert!((l.mean - given).norm() < 1e-3, "{}: {l:?}", filter.name());
        }
    }
}

#[test]
fn fej_takes_the_recorded_motions_displacement_for_f() {
    // FEJ's F uses the displacement of the predicted poses, as for a velocity
    // command: with no update in between it equals the textbook F.
    let start = Pose2::new(0.5, -0.2, 1.0);
    let mut fej =
        EkfSlam::with_linearization(config(), start, Linearization::FirstEstimates).unwrap();
    let mut ekf = EkfSlam::new(config(), start).unwrap();
    for motion in [
        odometry(0.3, 0.4, -0.2),
        car(3.0, 0.2),
        odometry(-0.1, 0.2, 0.1),
    ] {
        fej.predict_recorded(&motion).unwrap();
        ekf.predict_recorded(&motion).unwrap();
    }
    assert!((fej.robot_covariance() - ekf.robot_covariance()).norm() < 1e-14);
    assert!(fej.robot_covariance() != Matrix3::zeros());
}
