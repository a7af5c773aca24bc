//! Victoria Park as a recorded world: the car's inputs drive the prediction at
//! their own rate (each row holds the previous row's speed and steering until
//! its time), each laser scan's trees are one step's measurements, without
//! identities. The pose the filters estimate is the laser's (Guivant and Nebot's
//! model, [`slamlab_core::motion::CarStep`]), and a tree's bearing is turned
//! from the laser's sweep (0 right, π/2 ahead, π left) into a bearing about the
//! heading by subtracting π/2. The car starts at the origin heading along x.
//! The world starts at the first input or scan, whichever comes first (0.852 s
//! after the first GPS fix, in the files' times), standing still; its times,
//! the GPS's included, count from there.

use super::{RecordedObservation, RecordedStep, RecordedWorld, Sighting, StepMotion};
use crate::io::landmark_data::DataSetKind;
use crate::io::landmark_data::victoria_park::VictoriaParkData;
use nalgebra::Vector2;
use slamlab_core::Pose2;
use slamlab_core::range_bearing::RangeBearing;
use std::f64::consts::FRAC_PI_2;

/// The world of the three files.
pub fn world(data: &VictoriaParkData) -> RecordedWorld {
    let start_time = match (data.inputs.first(), data.scans.first()) {
        (Some(i), Some(s)) => i.time.min(s.time),
        (Some(i), None) => i.time,
        (None, Some(s)) => s.time,
        (None, None) => 0.0,
    };
    let (mut speed, mut steering) = (0.0, 0.0);
    let mut last = start_time;
    let mut steps = Vec::with_capacity(data.inputs.len() + data.scans.len());
    let (mut i, mut s) = (0, 0);
    // The car driven at the held speed and steering until `time`, then `observations`.
    let car_step = |time: f64, last: f64, speed, steering, observations| RecordedStep {
        time: time - start_time,
        motion: StepMotion::Car {
            speed,
            steering,
            dt: time - last,
        },
        observations,
    };
    while i < data.inputs.len() || s < data.scans.len() {
        // At equal times the scan is taken first, then the new input applies.
        let scan = match (data.inputs.get(i), data.scans.get(s)) {
            (Some(input), Some(scan)) => scan.time <= input.time,
            (None, Some(_)) => true,
            _ => false,
        };
        if scan {
            let scan = &data.scans[s];
            let trees = scan
                .trees
                .iter()
                .map(|t| RecordedObservation {
                    sighting: Sighting::Unlabelled,
                    measurement: RangeBearing::new(t.range, t.bearing - FRAC_PI_2),
                })
                .collect();
            steps.push(car_step(scan.time, last, speed, steering, trees));
            last = scan.time;
            s += 1;
        } else {
            let input = data.inputs[i];
            if input.time > last || steps.is_empty() {
                steps.push(car_step(input.time, last, speed, steering, Vec::new()));
                last = input.time;
            }
            (speed, steering) = (input.speed, input.steering);
            i += 1;
        }
    }
    let mut notices = Vec::new();
    if data.gps.is_empty() {
        notices.push("no gps.dat: the path has no reference".to_owned());
    }
    RecordedWorld {
        kind: DataSetKind::VictoriaPark,
        name: "Victoria Park, Sydney".to_owned(),
        robot: 0,
        start_time,
        start: Pose2::IDENTITY,
        steps,
        landmarks: Vec::new(),
        truth: None,
        others: Vec::new(),
        reference: data
            .gps
            .iter()
            .map(|g| (g.time - start_time, Vector2::new(g.x, g.y)))
            .collect(),
        known_association: false,
        notices,
    }
}
