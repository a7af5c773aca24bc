//! Recorded worlds: the truth's interpolation and gaps, how each data set's rows
//! become steps, and the noise measured from MRCLAM Dataset 6.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // a failing test stops

use super::*;
use crate::io::landmark_data::{DataFile, read_landmark_data, read_path};
use slamlab_core::Pose2;

/// A data set under `../shared/data/landmarks/`, or `None` with a message.
pub(crate) fn shared(path: &str) -> Option<LandmarkData> {
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

fn mrclam6() -> Option<crate::io::landmark_data::MrclamData> {
    match shared("mrclam/MRCLAM_Dataset6.zip")? {
        LandmarkData::Mrclam(d) => Some(d),
        _ => panic!("not MRCLAM"),
    }
}

#[test]
fn the_truth_is_interpolated_and_its_gaps_stay_gaps() {
    let track = TruthTrack {
        samples: vec![
            (0.0, Pose2::new(0.0, 0.0, 3.1)),
            (0.02, Pose2::new(0.02, 0.0, -3.1)),
            (0.04, Pose2::new(0.04, 0.01, -3.1)),
            // A 0.5 s gap.
            (0.54, Pose2::new(0.5, 0.01, 0.0)),
            (0.56, Pose2::new(0.52, 0.01, 0.0)),
        ],
    };
    // Heading interpolated across ±π the short way.
    let mid = track.at(0.01).unwrap();
    assert!((mid.x - 0.01).abs() < 1e-15);
    assert!(
        (mid.theta.abs() - std::f64::consts::PI).abs() < 1e-12,
        "{mid:?}"
    );
    assert_eq!(track.at(0.04), Some(Pose2::new(0.04, 0.01, -3.1)));
    assert_eq!(track.at(0.3), None, "in the gap");
    assert_eq!(track.at(-0.01), None, "before the track");
    assert_eq!(track.at(0.6), None, "after the track");
    assert!((track.at(0.55).unwrap().x - 0.51).abs() < 1e-12);
    assert_eq!(track.gaps(), [(0.04, 0.54)]);
    let pieces = track.pieces(0.55);
    assert_eq!(pieces.len(), 2);
    assert_eq!((pieces[0].len(), pieces[1].len()), (3, 1));
}

fn small_mrclam() -> Vec<DataFile> {
    let file = |name: &str, text: &str| DataFile::new(name, text.as_bytes().to_vec());
    vec![
        file("Barcodes.dat", "1 72\n2 5\n6 14\n7 90\n"),
        file(
            "Landmark_Groundtruth.dat",
            "6 1.0 2.0 0.001 0.002\n7 -1.5 0.5 0.001 0.001\n",
        ),
        file(
            "Robot1_Odometry.dat",
            "100.00 0.1 0.0\n100.01 0.1 0.0\n100.01 0.2 0.1\n100.02 0.2 0.1\n101.00 0.0 0.0\n",
        ),
        file(
            "Robot1_Measurement.dat",
            "99.9 14 1.0 0.0\n100.01 14 3.787 -0.257\n100.01 5 2.5 0.1\n100.01 43 1.0 0.0\n\
             100.015 90 6.0 0.0\n",
        ),
        file(
            "Robot1_Groundtruth.dat",
            "99.99 0.0 0.0 0.0\n100.02 0.003 0.0 0.001\n",
        ),
        file("Robot2_Odometry.dat", "100.0 0.0 0.0\n"),
        file("Robot2_Measurement.dat", ""),
        file("Robot2_Groundtruth.dat", "100.0 1.0 1.0 0.0\n"),
    ]
}

#[test]
fn mrclam_rows_become_odometry_steps_and_camera_images() {
    let data = read_landmark_data(small_mrclam()).unwrap();
    let world = RecordedWorld::from_data(&data, 1).unwrap();
    assert_eq!(world.name, "MRCLAM, robot 1");
    assert_eq!(world.start_time, 100.0);
    assert!(
        (world.start.x - 0.001).abs() < 1e-12,
        "Vicon at the first odometry row"
    );
    let summary: Vec<(f64, usize)> = world
        .steps
        .iter()
        .map(|s| ((s.time * 1000.0).round() / 1000.0, s.observations.len()))
        .collect();
    // The image at 100.01 (the two odometry rows of that time only change the
    // command: no time passes), the image at 100.015, odometry at 100.02 and 101.0.
    assert_eq!(summary, [(0.01, 2), (0.015, 1), (0.02, 0), (1.0, 0)]);
    // The image at 100.01 comes first (the robot moved 0.01 s at 0.1 m/s), and
    // the command of 100.01 (0.2, 0.1) drives from there.
    assert_eq!(
        world.steps[0].motion,
        StepMotion::Velocity {
            control: Control::new(0.1, 0.0),
            dt: world.steps[0].time,
        }
    );
    assert!(matches!(
        world.steps[1].motion,
        StepMotion::Velocity { control, .. } if control == Control::new(0.2, 0.1)
    ));
    assert_eq!(
        world.steps[0].observations[0].sighting,
        Sighting::Landmark(6)
    );
    assert_eq!(world.steps[0].observations[1].sighting, Sighting::Robot(2));
    assert_eq!(
        world.steps[1].observations[0].sighting,
        Sighting::Landmark(7)
    );
    assert_eq!(
        world.notices,
        [
            "1 measurement of barcode 43 (not in Barcodes.dat: misreads) skipped",
            "1 measurements before the first odometry row skipped"
        ]
    );
    assert_eq!(world.others.len(), 1);
    assert_eq!(world.others[0].number, 2);
    assert_eq!(world.landmarks.len(), 2);
    assert_eq!(world.landmarks[0].1, Matrix2::new(1e-6, 0.0, 0.0, 4e-6));
    let e = RecordedWorld::from_data(&data, 3).unwrap_err();
    assert_eq!(e, "robot 3 is not in MRCLAM: its files hold robots 1, 2");
}

#[test]
fn mrclam_dataset6_robot1_steps_and_sightings() {
    let Some(data) = mrclam6() else {
        return;
    };
    let world = RecordedWorld::from_data(&LandmarkData::Mrclam(data.clone()), 1).unwrap();
    let observations: Vec<&RecordedObservation> =
        world.steps.iter().flat_map(|s| &s.observations).collect();
    let landmarks = observations
        .iter()
        .filter(|o| matches!(o.sighting, Sighting::Landmark(_)))
        .count();
    let robots = observations
        .iter()
        .filter(|o| matches!(o.sighting, Sighting::Robot(_)))
        .count();
    let images = world
        .steps
        .iter()
        .filter(|s| !s.observations.is_empty())
        .count();
    println!(
        "robot 1: {} steps, {images} images, {landmarks} landmark and {robots} robot sightings, notices {:?}",
        world.steps.len(),
        world.notices
    );
    assert_eq!(landmarks + robots + 1, 1942, "one unknown barcode skipped");
    assert_eq!(robots, 407);
    assert_eq!(images, 1234);
    let gaps = world.truth.as_ref().unwrap().gaps();
    println!("robot 1's Vicon gaps: {gaps:?}");
    assert!(
        (world.duration() - 887.947).abs() < 1e-3,
        "{}",
        world.duration()
    );
}

#[test]
fn mrclam_dataset6_noise_measured_against_vicon() {
    let Some(data) = mrclam6() else {
        return;
    };
    let noise = mrclam::measure_noise(&data, &[1, 2, 3, 4, 5], 1.0);
    println!("{noise:#?}");
    println!(
        "v_std {:.4} m/s, w_std {:.4} rad/s ({:.2} deg/s), range {:.4} m, bearing {:.5} rad ({:.3} deg)",
        noise.v_std(),
        noise.w_std(),
        noise.w_std().to_degrees(),
        noise.range.robust_std,
        noise.bearing.robust_std,
        noise.bearing.robust_std.to_degrees()
    );
    for r in 1..=5 {
        let n = mrclam::measure_noise(&data, &[r], 1.0);
        println!(
            "robot {r}: v_std {:.4}, w_std {:.4}, range {:.4} ({:.4}), bearing {:.5} ({:.5}), along mean {:.4}, heading mean {:.4}",
            n.v_std(),
            n.w_std(),
            n.range.robust_std,
            n.range.std,
            n.bearing.robust_std,
            n.bearing.std,
            n.along.mean,
            n.heading.mean
        );
    }
}
