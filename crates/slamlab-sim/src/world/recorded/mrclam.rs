//! One robot of a UTIAS MRCLAM data set as a recorded world, and the noise of
//! its odometry and camera measured against the Vicon truth.
//!
//! The robot's odometry rows drive the prediction at their own rate (about
//! 100 Hz in the files): each row is a step that holds the previous row's
//! `(v, w)` until its time, then takes its own. The measurement rows with one
//! time (one camera image) are one step with one update per landmark seen. Rows
//! of other robots' barcodes become [`Sighting::Robot`] (shown, not used);
//! barcodes missing from `Barcodes.dat` (misreads) are counted and skipped. Times
//! are seconds after the robot's first odometry row, where the run starts at its
//! Vicon pose.

use super::{
    OtherRobot, RecordedObservation, RecordedStep, RecordedWorld, Sighting, StepMotion, TruthTrack,
};
use crate::io::landmark_data::DataSetKind;
use crate::io::landmark_data::mrclam::{MrclamData, MrclamRobot, Subject, TimedPose};
use crate::world::landmarks::Landmark;
use nalgebra::{Matrix2, Vector2};
use slamlab_core::range_bearing::{self, RangeBearing};
use slamlab_core::{Control, MotionModel, Pose2, wrap_angle};

/// The world of robot `number` of `data`.
pub fn world(data: &MrclamData, number: u32) -> Result<RecordedWorld, String> {
    let Some(robot) = data.robot(number) else {
        let there: Vec<String> = data.robots.iter().map(|r| r.number.to_string()).collect();
        return Err(format!(
            "robot {number} is not in {}: its files hold robot{} {}",
            data.name,
            if there.len() == 1 { "" } else { "s" },
            there.join(", ")
        ));
    };
    let Some(first) = robot.odometry.first() else {
        return Err(format!(
            "robot {number} of {} has no odometry rows",
            data.name
        ));
    };
    let t0 = first.time;
    let mut notices = Vec::new();
    let truth = track(&robot.groundtruth, t0);
    let start = match truth
        .as_ref()
        .and_then(|t| t.at(0.0).or(t.samples.first().map(|s| s.1)))
    {
        Some(pose) => pose,
        None => {
            notices.push(format!(
                "robot {number} has no Vicon truth: the run starts at the origin, and the error \
                 plots stay empty"
            ));
            Pose2::IDENTITY
        }
    };
    let (steps, skipped_unknown, skipped_early) = steps(data, robot);
    if skipped_unknown > 0 {
        let mut codes: Vec<u32> = robot
            .measurements
            .iter()
            .filter(|m| data.subject(m.barcode) == Subject::Unknown)
            .map(|m| m.barcode)
            .collect();
        codes.sort_unstable();
        codes.dedup();
        let codes: Vec<String> = codes.iter().map(u32::to_string).collect();
        notices.push(format!(
            "{skipped_unknown} measurement{} of barcode{} {} (not in Barcodes.dat: misreads) skipped",
            if skipped_unknown == 1 { "" } else { "s" },
            if codes.len() == 1 { "" } else { "s" },
            codes.join(", ")
        ));
    }
    if skipped_early > 0 {
        notices.push(format!(
            "{skipped_early} measurements before the first odometry row skipped"
        ));
    }
    let landmarks = data
        .landmarks
        .iter()
        .map(|l| {
            (
                Landmark {
                    id: l.subject as usize,
                    position: Vector2::new(l.x, l.y),
                },
                Matrix2::new(l.x_std * l.x_std, 0.0, 0.0, l.y_std * l.y_std),
            )
        })
        .collect();
    let others = data
        .robots
        .iter()
        .filter(|r| r.number != number)
        .filter_map(|r| {
            track(&r.groundtruth, t0).map(|truth| OtherRobot {
                number: r.number,
                truth,
            })
        })
        .collect();
    Ok(RecordedWorld {
        kind: DataSetKind::Mrclam,
        name: format!("{}, robot {number}", data.name),
        robot: number,
        start_time: t0,
        start,
        steps,
        landmarks,
        truth,
        others,
        reference: Vec::new(),
        known_association: true,
        notices,
    })
}

/// A Vicon file as a track in seconds after `t0`; `None` when empty.
fn track(poses: &[TimedPose], t0: f64) -> Option<TruthTrack> {
    (!poses.is_empty()).then(|| TruthTrack {
        samples: poses.iter().map(|p| (p.time - t0, p.pose)).collect(),
    })
}

/// The robot's steps, the count of unknown barcodes and of measurements before
/// the first odometry row.
fn steps(data: &MrclamData, robot: &MrclamRobot) -> (Vec<RecordedStep>, usize, usize) {
    let odometry = &robot.odometry;
    let t0 = odometry.first().map_or(0.0, |o| o.time);
    let mut command = odometry
        .first()
        .map_or(Control::default(), |o| Control::new(o.v, o.w));
    let mut last = t0;
    let mut steps = Vec::with_capacity(odometry.len() + robot.measurements.len());
    let mut skipped_unknown = 0;
    let measurements = &robot.measurements;
    let skipped_early = measurements.partition_point(|m| m.time < t0);
    let (mut o, mut m) = (1, skipped_early);
    while o < odometry.len() || m < measurements.len() {
        let next_odometry = odometry.get(o).map(|r| r.time);
        let next_measurement = measurements.get(m).map(|r| r.time);
        // At equal times the image is taken first, then the new command applies.
        let image = match (next_odometry, next_measurement) {
            (Some(to), Some(tm)) => tm <= to,
            (None, Some(_)) => true,
            _ => false,
        };
        if image {
            let time = measurements[m].time;
            let mut observations = Vec::new();
            while let Some(row) = measurements.get(m).filter(|r| r.time == time) {
                let sighting = match data.subject(row.barcode) {
                    Subject::Landmark(s) => Some(Sighting::Landmark(s as usize)),
                    Subject::Robot(n) => Some(Sighting::Robot(n)),
                    Subject::Unknown => None,
                };
                match sighting {
                    Some(sighting) => observations.push(RecordedObservation {
                        sighting,
                        measurement: RangeBearing::new(row.range, row.bearing),
                    }),
                    None => skipped_unknown += 1,
                }
                m += 1;
            }
            steps.push(RecordedStep {
                time: time - t0,
                motion: StepMotion::Velocity {
                    control: command,
                    dt: time - last,
                },
                observations,
            });
            last = time;
        } else {
            let row = odometry[o];
            // Rows that share a time: the last one's command holds.
            if row.time > last {
                steps.push(RecordedStep {
                    time: row.time - t0,
                    motion: StepMotion::Velocity {
                        control: command,
                        dt: row.time - last,
                    },
                    observations: Vec::new(),
                });
                last = row.time;
            }
            command = Control::new(row.v, row.w);
            o += 1;
        }
    }
    (steps, skipped_unknown, skipped_early)
}

/// Mean and spread of a set of residuals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResidualStats {
    /// How many residuals.
    pub count: usize,
    /// Their mean (the bias).
    pub mean: f64,
    /// Their standard deviation about the mean.
    pub std: f64,
    /// The robust spread `1.4826 · median |r − median r|` (a Gaussian's σ, not
    /// inflated by the few gross errors).
    pub robust_std: f64,
}

impl ResidualStats {
    fn of(mut values: Vec<f64>) -> Self {
        let count = values.len();
        if count == 0 {
            return Self {
                count,
                mean: f64::NAN,
                std: f64::NAN,
                robust_std: f64::NAN,
            };
        }
        let mean = values.iter().sum::<f64>() / count as f64;
        let std =
            (values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / count as f64).sqrt();
        values.sort_by(f64::total_cmp);
        let median = values[count / 2];
        let mut deviations: Vec<f64> = values.iter().map(|v| (v - median).abs()).collect();
        deviations.sort_by(f64::total_cmp);
        Self {
            count,
            mean,
            std,
            robust_std: 1.4826 * deviations[count / 2],
        }
    }
}

/// The noise of one or more robots' odometry and camera, measured against Vicon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasuredNoise {
    /// Range residuals `z − h(x_Vicon, m_Vicon)`, metres, over the landmark sightings
    /// at times the truth is known.
    pub range: ResidualStats,
    /// Bearing residuals, radians (wrapped).
    pub bearing: ResidualStats,
    /// The window over which odometry is compared with Vicon, seconds.
    pub window: f64,
    /// The mean odometry time step, seconds.
    pub mean_dt: f64,
    /// Along-track error of the odometry over each window (Vicon minus odometry,
    /// in the robot's frame at the window's start), metres.
    pub along: ResidualStats,
    /// Heading error over each window, radians.
    pub heading: ResidualStats,
}

impl MeasuredNoise {
    /// The filters' `v_std`: white noise on every odometry step that gives the
    /// window's along-track spread, `σ_v = σ_along / √(T · Δt)` (over `T / Δt`
    /// steps of `Δt` the variance adds up to `σ_v² Δt² · T / Δt`).
    pub fn v_std(&self) -> f64 {
        self.along.robust_std / (self.window * self.mean_dt).sqrt()
    }

    /// The filters' `w_std`, likewise from the heading spread over the window.
    pub fn w_std(&self) -> f64 {
        self.heading.robust_std / (self.window * self.mean_dt).sqrt()
    }
}

/// Measures the noise of the robots numbered `robots` of `data` (all of them
/// pooled): each landmark sighting's range and bearing against the ones Vicon
/// predicts (the robot's interpolated Vicon pose, the landmark's surveyed
/// position), and the odometry integrated over windows of `window` seconds
/// (exact arc, from the Vicon pose at the window's start) against the Vicon pose
/// at its end.
pub fn measure_noise(data: &MrclamData, robots: &[u32], window: f64) -> MeasuredNoise {
    let (mut range, mut bearing, mut along, mut heading) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut dt_sum, mut dt_count) = (0.0, 0usize);
    for robot in robots.iter().filter_map(|&n| data.robot(n)) {
        let Some(truth) = track(&robot.groundtruth, 0.0) else {
            continue;
        };
        for row in &robot.measurements {
            let Subject::Landmark(subject) = data.subject(row.barcode) else {
                continue;
            };
            let (Some(pose), Some(landmark)) = (
                truth.at(row.time),
                data.landmarks.iter().find(|l| l.subject == subject),
            ) else {
                continue;
            };
            if let Ok(p) = range_bearing::predict(&pose, &Vector2::new(landmark.x, landmark.y)) {
                range.push(row.range - p.measurement.range);
                bearing.push(wrap_angle(row.bearing - p.measurement.bearing));
            }
        }
        let odometry = &robot.odometry;
        for w in odometry.windows(2) {
            dt_sum += w[1].time - w[0].time;
            dt_count += 1;
        }
        // Consecutive windows [t_k, t_k + T], each from the Vicon pose at its start.
        let mut k = 0;
        while k < odometry.len() {
            let start_time = odometry[k].time;
            let end_time = start_time + window;
            let mut j = k;
            let mut pose = truth.at(start_time);
            while j + 1 < odometry.len() && odometry[j + 1].time <= end_time {
                let dt = odometry[j + 1].time - odometry[j].time;
                let control = Control::new(odometry[j].v, odometry[j].w);
                pose = pose.map(|p| MotionModel::ExactArc.predict(&p, &control, dt));
                j += 1;
            }
            let (Some(start), Some(predicted), Some(end)) =
                (truth.at(start_time), pose, truth.at(odometry[j].time))
            else {
                k = j.max(k + 1);
                continue;
            };
            if odometry[j].time - start_time > 0.5 * window {
                // Vicon minus odometry in the frame of the window's start.
                let e = end.translation() - predicted.translation();
                let (s, c) = slamlab_core::math::sin_cos(start.theta);
                along.push(c * e[0] + s * e[1]);
                heading.push(wrap_angle(end.theta - predicted.theta));
            }
            k = j.max(k + 1);
        }
    }
    MeasuredNoise {
        range: ResidualStats::of(range),
        bearing: ResidualStats::of(bearing),
        window,
        mean_dt: if dt_count > 0 {
            dt_sum / dt_count as f64
        } else {
            f64::NAN
        },
        along: ResidualStats::of(along),
        heading: ResidualStats::of(heading),
    }
}
