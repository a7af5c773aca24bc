//! The filters on MRCLAM Dataset 6 against its Vicon truth, with the numbers
//! the docs report pinned.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // a failing test stops

use super::*;
use crate::io::landmark_data::read_path;
use crate::landmark_slam::presets;

/// A data set under `../shared/data/landmarks/`, or `None` with a message.
fn shared(path: &str) -> Option<LandmarkData> {
    let Some(data) = slamlab_fuzz::shared_data() else {
        println!("skipped: ../shared/data is absent (or set SLAMLAB_SHARED_DATA)");
        return None;
    };
    let full = data.join("landmarks").join(path);
    if !full.exists() {
        println!("skipped: ../shared/data/landmarks/{path} is absent");
        return None;
    }
    Some(read_path(&full).unwrap())
}

#[test]
#[ignore = "diagnosis: prints a robot's error, NIS and rejections over time"]
fn diagnose_a_robot() {
    let Some(data) = shared("mrclam/MRCLAM_Dataset6.zip") else {
        return;
    };
    let robot: u32 = std::env::var("ROBOT")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let gate: f64 = std::env::var("GATE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.0);
    let mode = if std::env::var("LOC").is_ok() {
        MapMode::Localization
    } else {
        MapMode::Slam
    };
    let world = Arc::new(RecordedWorld::from_data(&data, robot).unwrap());
    let scenario = LandmarkScenario {
        estimators: vec![EstimatorKind::Ekf],
        mode,
        outlier_gate: gate,
        ..presets::scenario("mrclam", 1).unwrap()
    };
    let mut session = LandmarkSession::recorded(scenario, world);
    let mut next = 0.0;
    let mut worst_nis = (0.0, 0.0, 0);
    while !session.is_finished() {
        session.step_tick();
        let run = &session.filters()[0];
        if let Some(s) = run.nis.last()
            && s.nis > worst_nis.1
            && s.tick == session.tick()
        {
            worst_nis = (session.time(), s.nis, s.id);
        }
        if session.time() >= next {
            let m = run.latest();
            println!(
                "t {:7.1} error {:6.3} nees {:9.1} worst NIS since {:?} rejected {} truth {:?}",
                session.time(),
                m.map_or(f64::NAN, |m| m.position_error),
                m.and_then(|m| m.nees).unwrap_or(f64::NAN),
                worst_nis,
                run.rejected,
                session.true_pose().is_some()
            );
            worst_nis = (0.0, 0.0, 0);
            next += 10.0;
        }
    }
}

#[test]
#[ignore = "exploration: Victoria Park's landmark counts and GPS fit for settings from the environment"]
fn explore_victoria_park() {
    let Some(data) = shared("victoria_park") else {
        return;
    };
    let env = |k: &str, d: f64| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let steps = env("STEPS", 8000.0) as usize;
    let world = Arc::new(RecordedWorld::from_data(&data, 0).unwrap());
    let estimators: Vec<EstimatorKind> = std::env::var("EST")
        .unwrap_or("ekf".into())
        .split(',')
        .filter_map(EstimatorKind::from_name)
        .collect();
    let scenario = LandmarkScenario {
        estimators,
        v_std: env("V", 0.5),
        steering_std: env("STEER", 3.0).to_radians(),
        range_std: env("R", 0.5),
        bearing_std: env("B", 1.0).to_radians(),
        gate: env("GATE", 13.8),
        max_range: env("MAXR", 100.0),
        fastslam: crate::world::landmark_scenario::FastSlamSettings {
            new_landmark_threshold: env("NEW", 13.8),
            particles: env("P", 100.0) as usize,
            ..Default::default()
        },
        ..presets::scenario("victoria-park", 1).unwrap()
    };
    let t = std::time::Instant::now();
    let mut session = LandmarkSession::recorded(scenario, world.clone());
    let mut tracks: Vec<Trajectory> = session
        .filters()
        .iter()
        .map(|_| Trajectory::new(vec![0.0], vec![world.start]))
        .collect();
    for _ in 0..steps {
        if session.is_finished() {
            break;
        }
        session.step_tick();
        for (track, run) in tracks.iter_mut().zip(session.filters()) {
            track.push(session.time(), run.filter().robot_pose(), None);
        }
    }
    let mut dr = Trajectory::new(vec![0.0], vec![world.start]);
    for (k, p) in session.dead_reckoning_path().iter().enumerate().skip(1) {
        dr.push(world.steps[k - 1].time, *p, None);
    }
    for span in [100.0, 300.0, 1e9] {
        let mut part = Trajectory::default();
        for (t, p) in dr.stamps().iter().zip(dr.poses()) {
            if *t <= span {
                part.push(*t, *p, None);
            }
        }
        let fit = reference_alignment(&world, &part, 0.05);
        println!(
            "dead reckoning to {span} s: GPS RMSE {:?} over {:?} pairs, rotation {:?}, translation {:?}",
            fit.as_ref().map(|f| f.ape.translation.rmse),
            fit.as_ref().map(|f| f.pairing.pairs),
            fit.as_ref().map(|f| f.alignment.rotation_deg),
            fit.as_ref().map(|f| f.alignment.translation_m),
        );
    }
    for (track, run) in tracks.iter().zip(session.filters()) {
        let fit = reference_alignment(&world, track, 0.05);
        println!(
            "{}: {} landmarks, {} ambiguous, GPS RMSE {:?} over {:?} pairs, rotation {:?}, {:.1} s, errors {:?}",
            run.kind.name(),
            run.filter().landmark_ids().len(),
            run.ambiguous,
            fit.as_ref().map(|f| f.ape.translation.rmse),
            fit.as_ref().map(|f| f.pairing.pairs),
            fit.as_ref().map(|f| f.alignment.rotation_deg),
            t.elapsed().as_secs_f64(),
            run.last_error
        );
    }
}
