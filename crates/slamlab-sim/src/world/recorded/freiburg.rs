//! The Freiburg course's files as a recorded world: one step per `ODOMETRY`
//! line, moved by the odometry reading, with the `SENSOR` lines after it as its
//! measurements (known correspondences). The files have no times: SLAM Lab
//! plays one step every [`STEP_SECONDS`]. The robot starts at the origin, as
//! the course's filters do; `world.dat` gives the true landmarks; there is no
//! true path.

use super::{RecordedObservation, RecordedStep, RecordedWorld, Sighting, StepMotion};
use crate::io::landmark_data::DataSetKind;
use crate::io::landmark_data::freiburg::FreiburgData;
use crate::world::landmarks::Landmark;
use nalgebra::{Matrix2, Vector2};
use slamlab_core::Pose2;
use slamlab_core::range_bearing::RangeBearing;

/// The time one step of the course's data takes in the lesson, seconds.
pub const STEP_SECONDS: f64 = 0.1;

/// The world of the course's files.
pub fn world(data: &FreiburgData) -> RecordedWorld {
    let steps = data
        .steps
        .iter()
        .enumerate()
        .map(|(k, step)| RecordedStep {
            time: (k + 1) as f64 * STEP_SECONDS,
            motion: StepMotion::Odometry {
                rot1: step.odometry.rot1,
                trans: step.odometry.trans,
                rot2: step.odometry.rot2,
            },
            observations: step
                .sensors
                .iter()
                .map(|s| RecordedObservation {
                    sighting: Sighting::Landmark(s.id as usize),
                    measurement: RangeBearing::new(s.range, s.bearing),
                })
                .collect(),
        })
        .collect();
    let mut notices = Vec::new();
    if data.world.is_empty() {
        notices.push(
            "no world.dat: the true landmarks are not drawn and the landmark error is unknown"
                .to_owned(),
        );
    }
    if data.negative_ranges > 0 {
        notices.push(format!(
            "sensor_data.dat has {} negative range{} (kept, as the course's code keeps {})",
            data.negative_ranges,
            if data.negative_ranges == 1 { "" } else { "s" },
            if data.negative_ranges == 1 {
                "it"
            } else {
                "them"
            },
        ));
    }
    RecordedWorld {
        kind: DataSetKind::Freiburg,
        name: "Freiburg Robot Mapping course (world.dat, sensor_data.dat)".to_owned(),
        robot: 0,
        start_time: 0.0,
        start: Pose2::IDENTITY,
        steps,
        landmarks: data
            .world
            .iter()
            .map(|l| {
                (
                    Landmark {
                        id: l.id as usize,
                        position: Vector2::new(l.x, l.y),
                    },
                    Matrix2::zeros(),
                )
            })
            .collect(),
        truth: None,
        others: Vec::new(),
        reference: Vec::new(),
        known_association: true,
        notices,
    }
}
