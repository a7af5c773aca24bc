//! Recorded landmark worlds: a data set read by [`crate::io::landmark_data`]
//! turned into the steps a landmark session replays instead of simulating, next
//! to the simulated world of [`crate::world::landmarks`].
//!
//! A recorded world is a list of [`RecordedStep`]s in time order. Each moves the
//! robot (a velocity held for a time step, an odometry reading, the car's input:
//! [`StepMotion`]) and then brings the measurements made at its time (rows with
//! the same time are one update). It holds what the data knows beside: the true
//! landmarks (MRCLAM's Vicon survey, the Freiburg course's `world.dat`), the true
//! path ([`TruthTrack`], MRCLAM's Vicon, interpolated, with its gaps kept as
//! gaps), other robots' Vicon tracks, and an independent reference (Victoria
//! Park's GPS, in a frame of its own).
//!
//! - [`mrclam`]: one robot of a UTIAS MRCLAM data set, and the noise measured
//!   from its residuals against Vicon ([`mrclam::measure_noise`]).
//! - [`freiburg`]: the course's steps.
//! - [`victoria_park`]: the car's inputs and the trees, and the GPS.

pub mod freiburg;
pub mod mrclam;
#[cfg(test)]
pub(crate) mod tests;
pub mod victoria_park;

use crate::io::landmark_data::{DataSetKind, LandmarkData};
use crate::world::landmarks::{Landmark, LandmarkWorld};
use nalgebra::{Matrix2, Vector2};
use slamlab_core::motion::{CarGeometry, CarStep, OdometryStep, RecordedMotion};
use slamlab_core::range_bearing::RangeBearing;
use slamlab_core::{Control, MotionModel, Pose2, wrap_angle};

/// Vicon poses farther apart than this are not interpolated between: the truth
/// has a gap there (six missed frames at Vicon's 60 Hz).
pub const MAX_TRUTH_GAP: f64 = 0.1;

/// Where a recorded world comes from: its name, its source and how to cite it,
/// for the lesson's Sources and the command line's output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DataSource {
    /// The data set's title.
    pub title: &'static str,
    /// Where the files come from.
    pub source: &'static str,
    /// How to cite it.
    pub citation: &'static str,
}

/// The source of each data set.
pub fn data_source(kind: DataSetKind) -> DataSource {
    match kind {
        DataSetKind::Mrclam => DataSource {
            title: "UTIAS Multi-Robot Cooperative Localization and Mapping data set",
            source: "University of Toronto Institute for Aerospace Studies; the files as UTIAS \
                     distributes them (MRCLAM_DatasetN)",
            citation: "K. Y. K. Leung, Y. Halpern, T. D. Barfoot and H. H. T. Liu, \"The UTIAS \
                       multi-robot cooperative localization and mapping dataset\", International \
                       Journal of Robotics Research 30(8):969-974, 2011",
        },
        DataSetKind::Freiburg => DataSource {
            title: "Freiburg Robot Mapping course, EKF-SLAM data (world.dat, sensor_data.dat)",
            source: "C. Stachniss, Robot Mapping course, University of Freiburg: the input of \
                     its EKF-SLAM, UKF-SLAM and FastSLAM exercises",
            citation: "C. Stachniss, \"Robot Mapping\", lecture and exercises, University of \
                       Freiburg, WS 2013/14",
        },
        DataSetKind::VictoriaPark => DataSource {
            title: "Victoria Park, Sydney (ACFR): tree detections, car inputs and GPS",
            source: "J. Guivant and E. Nebot, Australian Centre for Field Robotics; the text \
                     files of K. Leung's conversion (RFS-SLAM)",
            citation: "J. Guivant and E. Nebot, \"Optimization of the simultaneous localization \
                       and map-building algorithm for real-time implementation\", IEEE \
                       Transactions on Robotics and Automation 17(3):242-257, 2001",
        },
    }
}

/// How one step moves the robot, as the data gives it. The noise the filters
/// assume comes from the scenario ([`StepMotion::recorded`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepMotion {
    /// A forward speed and turn rate held for `dt` seconds (MRCLAM's odometry),
    /// moved by the scenario's [`MotionModel`].
    Velocity {
        /// The command.
        control: Control,
        /// How long it is held, seconds.
        dt: f64,
    },
    /// An odometry reading `(δrot1, δtrans, δrot2)` (the Freiburg course).
    Odometry {
        /// First rotation, radians.
        rot1: f64,
        /// Translation, metres.
        trans: f64,
        /// Second rotation, radians.
        rot2: f64,
    },
    /// The car's encoder speed and steering held for `dt` seconds (Victoria Park).
    Car {
        /// The encoder's speed, m/s.
        speed: f64,
        /// Steering angle, radians.
        steering: f64,
        /// How long they are held, seconds.
        dt: f64,
    },
}

/// The noise the filters assume on recorded motions that are not velocities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordedNoise {
    /// Standard deviation of each odometry rotation, radians.
    pub odometry_rot_std: f64,
    /// Standard deviation of an odometry translation, metres.
    pub odometry_trans_std: f64,
    /// Standard deviation of the car's speed, m/s.
    pub speed_std: f64,
    /// Standard deviation of the car's steering angle, radians.
    pub steering_std: f64,
}

impl StepMotion {
    /// The motion as a filter predicts with it: `None` for a velocity (it goes
    /// through the scenario's motion model), else the recorded motion with `noise`.
    pub fn recorded(&self, noise: &RecordedNoise) -> Option<RecordedMotion> {
        match *self {
            StepMotion::Velocity { .. } => None,
            StepMotion::Odometry { rot1, trans, rot2 } => {
                Some(RecordedMotion::Odometry(OdometryStep {
                    rot1,
                    trans,
                    rot2,
                    rot_std: noise.odometry_rot_std,
                    trans_std: noise.odometry_trans_std,
                }))
            }
            StepMotion::Car {
                speed,
                steering,
                dt,
            } => Some(RecordedMotion::Car(CarStep {
                speed,
                steering,
                dt,
                car: CarGeometry::VICTORIA_PARK,
                speed_std: noise.speed_std,
                steering_std: noise.steering_std,
            })),
        }
    }

    /// Moves `pose` without noise (dead reckoning); a motion the model refuses
    /// (a steering too sharp for the car) leaves it where it is.
    pub fn apply(&self, pose: &Pose2, model: MotionModel, noise: &RecordedNoise) -> Pose2 {
        match (self, self.recorded(noise)) {
            (StepMotion::Velocity { control, dt }, _) => model.predict(pose, control, *dt),
            (_, Some(motion)) => motion.apply(pose, &[0.0; 3]).unwrap_or(*pose),
            (_, None) => *pose,
        }
    }

    /// The step's duration, seconds (`None` for an odometry reading).
    pub fn dt(&self) -> Option<f64> {
        match self {
            StepMotion::Velocity { dt, .. } | StepMotion::Car { dt, .. } => Some(*dt),
            StepMotion::Odometry { .. } => None,
        }
    }
}

/// What a measurement of the data saw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sighting {
    /// A landmark with this id (known association).
    Landmark(usize),
    /// Another robot (MRCLAM): shown, never used by the filters.
    Robot(u32),
    /// A landmark without identity (Victoria Park's trees): the filters associate it.
    Unlabelled,
}

/// One measurement of a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordedObservation {
    /// What it saw.
    pub sighting: Sighting,
    /// Range and bearing from the robot's (or the laser's) pose.
    pub measurement: RangeBearing,
}

/// One step of a recorded world: a motion, then the measurements at its time.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordedStep {
    /// Seconds since the world's start.
    pub time: f64,
    /// How the robot moved to this time.
    pub motion: StepMotion,
    /// What it measured at this time (empty for most odometry steps).
    pub observations: Vec<RecordedObservation>,
}

/// A true path sampled at times (Vicon), interpolated between samples at most
/// [`MAX_TRUTH_GAP`] apart; elsewhere the truth is unknown.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TruthTrack {
    /// `(time, pose)` in time order, seconds since the world's start.
    pub samples: Vec<(f64, Pose2)>,
}

impl TruthTrack {
    /// The true pose at `time`: linear in position and in the wrapped heading
    /// difference between the samples around it, `None` in a gap or outside the track.
    pub fn at(&self, time: f64) -> Option<Pose2> {
        let i = self.samples.partition_point(|(t, _)| *t < time);
        let (t1, p1) = *self.samples.get(i)?;
        if t1 == time {
            return Some(p1);
        }
        let (t0, p0) = *self.samples.get(i.checked_sub(1)?)?;
        if t1 - t0 > MAX_TRUTH_GAP {
            return None;
        }
        let s = (time - t0) / (t1 - t0);
        Some(Pose2 {
            x: p0.x + s * (p1.x - p0.x),
            y: p0.y + s * (p1.y - p0.y),
            theta: wrap_angle(p0.theta + s * wrap_angle(p1.theta - p0.theta)),
        })
    }

    /// The track split at its gaps, each piece up to `until` (for drawing).
    pub fn pieces(&self, until: f64) -> Vec<&[(f64, Pose2)]> {
        let end = self.samples.partition_point(|(t, _)| *t <= until);
        let samples = &self.samples[..end];
        let mut pieces = Vec::new();
        let mut start = 0;
        for i in 1..samples.len() {
            if samples[i].0 - samples[i - 1].0 > MAX_TRUTH_GAP {
                pieces.push(&samples[start..i]);
                start = i;
            }
        }
        if start < samples.len() {
            pieces.push(&samples[start..]);
        }
        pieces
    }

    /// The gaps: `(from, to)` times between samples more than [`MAX_TRUTH_GAP`] apart.
    pub fn gaps(&self) -> Vec<(f64, f64)> {
        self.samples
            .windows(2)
            .filter(|w| w[1].0 - w[0].0 > MAX_TRUTH_GAP)
            .map(|w| (w[0].0, w[1].0))
            .collect()
    }
}

/// Another robot of the data set, shown greyed (MRCLAM).
#[derive(Clone, Debug, PartialEq)]
pub struct OtherRobot {
    /// Its number.
    pub number: u32,
    /// Its Vicon track.
    pub truth: TruthTrack,
}

/// A data set as a world a landmark session replays.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordedWorld {
    /// Which data set.
    pub kind: DataSetKind,
    /// What the lesson calls it: "MRCLAM_Dataset6, robot 1".
    pub name: String,
    /// The robot's number (MRCLAM), else 0.
    pub robot: u32,
    /// The data's own time of the world's start (Unix seconds for MRCLAM).
    pub start_time: f64,
    /// Where the robot starts: its Vicon pose at the start (MRCLAM), else the origin.
    pub start: Pose2,
    /// The steps, in time order.
    pub steps: Vec<RecordedStep>,
    /// The true landmarks (empty when the data has none), with the covariance a
    /// given map enters the filters with (localization).
    pub landmarks: Vec<(Landmark, Matrix2<f64>)>,
    /// The robot's true path, if the data has one.
    pub truth: Option<TruthTrack>,
    /// Other robots, shown and not used.
    pub others: Vec<OtherRobot>,
    /// An independent reference for the path in a frame of its own (Victoria
    /// Park's GPS): `(time, position)`.
    pub reference: Vec<(f64, Vector2<f64>)>,
    /// True when the data names what each measurement saw (MRCLAM, Freiburg).
    pub known_association: bool,
    /// What the reader or the conversion had to skip or accept, for the user.
    pub notices: Vec<String>,
}

impl RecordedWorld {
    /// The world of `data`: for MRCLAM, the robot numbered `robot` (refused, with
    /// the robots there are, when it is not in the files).
    pub fn from_data(data: &LandmarkData, robot: u32) -> Result<Self, String> {
        match data {
            LandmarkData::Mrclam(d) => mrclam::world(d, robot),
            LandmarkData::Freiburg(d) => Ok(freiburg::world(d)),
            LandmarkData::VictoriaPark(d) => Ok(victoria_park::world(d)),
        }
    }

    /// Its source and citation.
    pub fn source(&self) -> DataSource {
        data_source(self.kind)
    }

    /// The time of its last step, seconds.
    pub fn duration(&self) -> f64 {
        self.steps.last().map_or(0.0, |s| s.time)
    }

    /// The true landmarks as a landmark world (for drawing and the landmark
    /// error), sized to hold them, the truth and the reference.
    pub fn landmark_world(&self) -> LandmarkWorld {
        let mut extent = 1.0_f64;
        let points = self.landmarks.iter().map(|(l, _)| l.position).chain(
            self.truth
                .iter()
                .flat_map(|t| t.samples.iter().map(|(_, p)| p.translation())),
        );
        for p in points {
            extent = extent.max(p[0].abs()).max(p[1].abs());
        }
        LandmarkWorld {
            size: 2.0 * extent,
            landmarks: self.landmarks.iter().map(|(l, _)| *l).collect(),
        }
    }

    /// The true pose at `time` (seconds since the start), if the data knows it.
    pub fn truth_at(&self, time: f64) -> Option<Pose2> {
        self.truth.as_ref().and_then(|t| t.at(time))
    }
}
