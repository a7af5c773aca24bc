//! The session's phases, checkpoints, step back and live changes.

use super::*;
use nalgebra::{DMatrix, DVector, Matrix3};
use slamlab_core::belief::LandmarkEstimate;
use std::f64::consts::PI;

/// Everything a filter shows (pose, covariance, landmarks, and its joint
/// Gaussian when it keeps one), to compare two runs to the last bit.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Shown {
    pose: Pose2,
    covariance: Matrix3<f64>,
    landmarks: Vec<LandmarkEstimate>,
    joint: Option<(DVector<f64>, DMatrix<f64>)>,
}

pub(super) fn shown(f: &dyn LandmarkSlam) -> Shown {
    Shown {
        pose: f.robot_pose(),
        covariance: f.robot_covariance(),
        landmarks: f.landmarks(),
        joint: f
            .gaussian()
            .map(|g| (g.mean().clone(), g.covariance().clone())),
    }
}

/// Asserts that two sessions have the same truth and the same first filter.
#[track_caller]
fn assert_same_truth_and_first_filter(a: &LandmarkSession, b: &LandmarkSession) {
    assert_eq!(a.truth(), b.truth());
    assert_eq!(
        shown(a.filters()[0].filter()),
        shown(b.filters()[0].filter())
    );
}

#[test]
fn phases_follow_predict_then_each_update() {
    let mut s = LandmarkSession::new(LandmarkScenario::default());
    let first = s.step_phase();
    assert_eq!(first, Phase::Predict);
    let n = s.observations().len();
    assert!(n > 0, "the teaching layout is in view at the start");
    for k in 1..=n {
        match s.step_phase() {
            Phase::Update { index, count, .. } => assert_eq!((index, count), (k, n)),
            Phase::Predict | Phase::Resample => panic!("expected update {k}"),
        }
    }
    assert!(!s.is_mid_tick());
    assert_eq!(s.filters()[0].history.len(), 1);
    assert_eq!(s.truth_path().len(), 2);
}

#[test]
fn same_seed_same_run_and_the_estimator_does_not_change_the_world() {
    let mut a = LandmarkSession::new(LandmarkScenario {
        seed: 4,
        ..Default::default()
    });
    let mut b = LandmarkSession::new(LandmarkScenario {
        seed: 4,
        ..Default::default()
    });
    a.run_ticks(50);
    b.run_ticks(50);
    assert_same_truth_and_first_filter(&a, &b);
    let mut c = LandmarkSession::new(LandmarkScenario {
        seed: 4,
        estimators: vec![],
        ..Default::default()
    });
    c.run_ticks(50);
    assert_eq!(
        a.truth(),
        c.truth(),
        "the world does not depend on the estimators"
    );
}

#[test]
fn one_phase_advances_every_filter_on_the_same_data() {
    let scenario = LandmarkScenario {
        estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
        ..Default::default()
    };
    let mut s = LandmarkSession::new(scenario);
    assert_eq!(s.filters().len(), 2);
    let before: Vec<_> = s
        .filters()
        .iter()
        .map(|f| f.filter().robot_covariance())
        .collect();
    assert_eq!(s.step_phase(), Phase::Predict);
    for (f, b) in s.filters().iter().zip(&before) {
        assert_ne!(
            f.filter().robot_covariance(),
            *b,
            "{} did not predict",
            f.kind.name()
        );
        assert!(f.last_predict.is_some());
    }
    s.step_phase();
    for f in s.filters() {
        assert_eq!(
            f.filter().landmark_ids().len(),
            1,
            "{} initialized the first landmark",
            f.kind.name()
        );
    }
    // The world is the same with one filter or two.
    let mut ekf_only = LandmarkSession::new(LandmarkScenario::default());
    s.run_ticks(30);
    ekf_only.run_ticks(30);
    assert_same_truth_and_first_filter(&s, &ekf_only);
}

#[test]
fn impossible_ukf_parameters_leave_a_notice_and_the_ekf_running() {
    let mut scenario = LandmarkScenario {
        estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
        ..Default::default()
    };
    scenario.ukf.alpha = 0.5;
    scenario.ukf.kappa = -9.0;
    let mut s = LandmarkSession::new(scenario);
    assert_eq!(s.filters().len(), 1);
    assert!(
        s.notices()
            .iter()
            .any(|n| n.contains("ukf could not start")),
        "{:?}",
        s.notices()
    );
    s.run_ticks(5);
}

#[test]
fn checkpoints_make_stepping_back_cheap_and_exact() {
    let scenario = LandmarkScenario {
        estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
        ..Default::default()
    };
    let snapshot = |s: &LandmarkSession| {
        (
            (s.tick(), s.phases_run(), s.next_phase(), s.truth()),
            s.truth_path().to_vec(),
            s.filters()
                .iter()
                .map(|r| {
                    (
                        shown(r.filter()),
                        r.history.clone(),
                        r.nis.clone(),
                        r.path.clone(),
                    )
                })
                .collect::<Vec<_>>(),
        )
    };
    let mut s = LandmarkSession::new(scenario.clone());
    s.run_ticks(130);
    s.step_phase();
    let phases = s.phases_run();
    // The latest checkpoint is at tick 100: a step back replays about 30 ticks.
    let replay = s.step_back_replay_length();
    assert!(replay > 0 && replay < phases / 3, "{replay} of {phases}");
    // Step back across the checkpoints at ticks 100 and 50, checking the state
    // against a straight run at three points.
    let targets = [phases - 1, phases * 2 / 3, phases / 4];
    for &target in &targets {
        while s.phases_run() > target {
            assert!(s.step_back());
        }
        let mut straight = LandmarkSession::new(scenario.clone());
        while straight.phases_run() < target {
            straight.step_phase();
        }
        assert_eq!(snapshot(&s), snapshot(&straight), "at phase {target}");
    }
    assert!(
        s.tick() < 100,
        "went back past a checkpoint: tick {}",
        s.tick()
    );
    // And forward again from there, exactly as the straight run goes.
    s.run_ticks(60);
    let mut straight = LandmarkSession::new(scenario);
    while straight.phases_run() < targets[2] {
        straight.step_phase();
    }
    straight.run_ticks(60);
    assert_eq!(snapshot(&s), snapshot(&straight));
}

/// The default scenario with the EKF alone.
fn ekf_only() -> LandmarkScenario {
    LandmarkScenario {
        estimators: vec![EstimatorKind::Ekf],
        ..Default::default()
    }
}

#[test]
fn taking_the_wheel_mid_run_keeps_the_run_and_step_back_replays_it() {
    let scenario = ekf_only();
    let mut s = LandmarkSession::new(scenario.clone());
    s.run_ticks(30);
    let landmarks = s.filters()[0].filter().landmark_ids().len();
    assert!(landmarks > 0);
    s.set_controller(ControllerKind::Manual);
    s.set_teleop(Control::new(0.4, -0.5));
    s.run_ticks(10);
    assert_eq!(s.tick(), 40, "the run goes on");
    assert_eq!(s.command(), Control::new(0.4, -0.5));
    assert!(s.filters()[0].filter().landmark_ids().len() >= landmarks);
    // Back to the circle: the scripted command again.
    s.set_controller(scenario.controller);
    s.run_ticks(5);
    assert_eq!(s.command(), Control::new(1.0, PI / 10.0));
    // Stepping back across the switches replays the commands exactly.
    let snapshot = |s: &LandmarkSession| (s.tick(), s.truth(), shown(s.filters()[0].filter()));
    let mut straight = LandmarkSession::new(scenario);
    straight.run_ticks(30);
    straight.set_controller(ControllerKind::Manual);
    straight.set_teleop(Control::new(0.4, -0.5));
    straight.run_ticks(10);
    while s.tick() > 40 {
        assert!(s.step_back());
    }
    assert!(!s.is_mid_tick());
    assert_eq!(snapshot(&s), snapshot(&straight));
    assert_eq!(
        s.controller(),
        ControllerKind::Circle {
            v: 1.0,
            w: PI / 10.0
        },
        "stepping back keeps today's driver"
    );
    // A circle without finite speeds is refused.
    s.set_controller(ControllerKind::Circle {
        v: f64::NAN,
        w: 0.0,
    });
    assert_eq!(
        s.controller(),
        ControllerKind::Circle {
            v: 1.0,
            w: PI / 10.0
        }
    );
}

#[test]
fn the_sensor_reach_changes_from_the_next_tick_and_replays_exactly() {
    let mut s = LandmarkSession::new(LandmarkScenario {
        seed: 5,
        ..Default::default()
    });
    let reach = |s: &LandmarkSession| (s.sensor().fov, s.sensor().max_range);
    let start = reach(&s);
    s.run_ticks(10);
    s.set_sensor_reach(2.0 * PI, 8.0);
    assert_eq!(
        reach(&s),
        start,
        "this tick's measurements are already taken"
    );
    assert_eq!(
        (s.scenario_now().fov, s.scenario_now().max_range),
        (2.0 * PI, 8.0)
    );
    assert_eq!(
        s.scenario().fov,
        start.0,
        "the run's scenario is where it started"
    );
    s.step_tick();
    assert_eq!(reach(&s), (2.0 * PI, 8.0));
    let truth = s.truth();
    let in_reach = s
        .world()
        .landmarks
        .iter()
        .filter(|l| (l.position - truth.translation()).norm() <= 8.0)
        .count();
    assert_eq!(s.observations().len(), in_reach, "all around, to 8 m");
    s.run_ticks(19);
    let at_30 = shown(s.filters()[0].filter());

    // Back to tick 8, before the change: the old reach. Forward again: the change
    // replays at tick 11 and the run is the same to the last bit.
    while s.tick() > 8 || s.is_mid_tick() {
        assert!(s.step_back());
    }
    assert_eq!(reach(&s), start);
    s.run_ticks(22);
    assert_eq!(s.tick(), 30);
    assert_eq!(shown(s.filters()[0].filter()), at_30);

    // Rewound and changed again: the new change replaces the later one.
    while s.tick() > 8 || s.is_mid_tick() {
        assert!(s.step_back());
    }
    s.set_sensor_reach(1.0, 3.0);
    s.run_ticks(12);
    assert_eq!(reach(&s), (1.0, 3.0));

    // Out-of-range values are clamped to the parameters' ranges; NaN changes nothing.
    s.set_sensor_reach(0.0, 1e9);
    s.step_tick();
    assert!((s.sensor().fov - 1_f64.to_radians()).abs() < 1e-12);
    assert_eq!(s.sensor().max_range, 100.0);
    s.set_sensor_reach(f64::NAN, 5.0);
    s.step_tick();
    assert_eq!(s.sensor().max_range, 100.0);
}

#[test]
fn stepping_back_restores_the_state_before_the_last_phase() {
    let scenario = LandmarkScenario {
        controller: crate::world::landmark_scenario::ControllerKind::Manual,
        estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
        ..Default::default()
    };
    let mut s = LandmarkSession::new(scenario);
    assert!(!s.step_back(), "nothing to undo at the start");
    s.set_teleop(Control::new(1.0, 0.3));
    s.run_ticks(7);
    s.set_teleop(Control::new(0.5, -0.6));
    s.run_ticks(3);
    s.step_phase();
    s.step_phase();
    let phases = s.phases_run();
    let before = (
        s.truth(),
        shown(s.filters()[1].filter()),
        s.next_phase(),
        s.filters()[0].history.len(),
    );
    s.step_phase();
    assert!(s.step_back());
    assert_eq!(s.phases_run(), phases);
    let after = (
        s.truth(),
        shown(s.filters()[1].filter()),
        s.next_phase(),
        s.filters()[0].history.len(),
    );
    assert_eq!(before, after);
    assert_eq!(
        s.teleop(),
        Control::new(0.5, -0.6),
        "the current drive command is kept"
    );
    // Back across a tick boundary, to the very start.
    while s.step_back() {}
    assert_eq!((s.tick(), s.phases_run()), (0, 0));
    assert_eq!(s.truth(), s.scenario().start_pose());
}

#[test]
fn a_stopped_manual_robot_stays_put() {
    let mut s = LandmarkSession::new(LandmarkScenario {
        controller: crate::world::landmark_scenario::ControllerKind::Manual,
        ..Default::default()
    });
    let start = s.truth();
    s.run_ticks(10);
    assert_eq!(s.truth(), start);
    s.set_teleop(Control::new(0.5, 0.0));
    s.set_teleop(Control::new(f64::NAN, 0.0));
    s.run_ticks(10);
    assert!(
        (s.truth().x - start.x - 0.5).abs() < 0.5,
        "moved about 0.5 m: {:?}",
        s.truth()
    );
}

#[test]
fn live_changes_are_recorded_once_and_replay_after_stepping_back() {
    let scenario = ekf_only();
    let mut s = LandmarkSession::new(scenario.clone());
    s.run_ticks(5);
    s.set_controller(ControllerKind::Manual);
    s.set_teleop(Control::new(0.5, 0.2));
    // The lesson hands the drive command before every step: the same one again
    // is no new event.
    s.set_teleop(Control::new(0.5, 0.2));
    s.set_controller(ControllerKind::Manual);
    s.run_ticks(5);
    s.set_sensor_reach(2.0 * PI, 6.0);
    s.mislabel_next_observation();
    s.mislabel_next_observation();
    s.run_ticks(5);
    assert_eq!(s.stepper().events().len(), 4);
    assert_eq!(s.mislabel_ticks(), vec![11]);
    let at_15 = (s.truth(), shown(s.filters()[0].filter()));

    // Back before the switch: the circle drives, as it did then.
    while s.tick() > 3 {
        assert!(s.step_back());
    }
    assert_eq!(s.controller(), scenario.controller);
    assert_eq!(s.teleop(), Control::default());
    assert_eq!(s.mislabel_ticks(), vec![11], "still to come");
    // Forward again (handed the drive command of that moment): every change
    // replays where it was made.
    s.set_teleop(Control::default());
    s.run_ticks(12);
    assert_eq!(s.controller(), ControllerKind::Manual);
    assert_eq!(s.sensor().max_range, 6.0);
    assert_eq!((s.truth(), shown(s.filters()[0].filter())), at_15);
    assert_eq!(s.stepper().events().len(), 4);
}
