//! The UTIAS Multi-Robot Cooperative Localization and Mapping data set (Leung,
//! Halpern, Barfoot and Liu, IJRR 30(8), 2011): robots driving among barcoded
//! cylinders, with Vicon ground truth for every robot and landmark.
//!
//! One data set (`MRCLAM_DatasetN`) is these files, each with four `#` comment
//! lines and tab-separated fields padded with spaces:
//!
//! - `Barcodes.dat`: `subject barcode`. Subjects are the robots and the landmarks;
//!   the barcode-to-subject table differs between data sets, so everything is
//!   mapped through this file. One barcode names one subject.
//! - `Landmark_Groundtruth.dat`: `subject x y x_std y_std` (metres, Vicon). The
//!   subjects listed here are the landmarks; every other subject of
//!   `Barcodes.dat` is robot number `subject`.
//! - `RobotN_Odometry.dat`: `time v w` (s since the Unix epoch, m/s, rad/s).
//! - `RobotN_Measurement.dat`: `time barcode range bearing` (s, -, m, rad); rows
//!   with the same time are one camera image. The column is headed "Subject #"
//!   in the file but holds barcodes.
//! - `RobotN_Groundtruth.dat`: `time x y theta` (Vicon).
//!
//! `Barcodes.dat`, `Landmark_Groundtruth.dat` and, for each robot read, its
//! odometry and measurements are required; a robot's Vicon file may be missing
//! (the run then has no truth). Times must not go back; ranges must not be negative.

use super::table::{check_range, check_time_order, numeric_rows, whole};
use super::{DataError, DataFile, base_name, find};
use slamlab_core::Pose2;
use std::collections::BTreeMap;

/// The barcode table's file name.
pub const BARCODES: &str = "Barcodes.dat";
/// The landmarks' Vicon positions.
pub const LANDMARK_GROUNDTRUTH: &str = "Landmark_Groundtruth.dat";
/// The most robots a data set may have (robot numbers are 1 to this).
pub const MAX_ROBOTS: u32 = 99;
/// The largest barcode or subject number accepted.
pub const MAX_CODE: u32 = 9_999;

/// A landmark surveyed by the Vicon system.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurveyedLandmark {
    /// Its subject number.
    pub subject: u32,
    /// Position, metres.
    pub x: f64,
    /// Position, metres.
    pub y: f64,
    /// Standard deviation of `x` over the survey, metres.
    pub x_std: f64,
    /// Standard deviation of `y` over the survey, metres.
    pub y_std: f64,
}

/// One odometry record: the robot's forward speed and turn rate from `time` on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VelocityRow {
    /// Seconds since the Unix epoch.
    pub time: f64,
    /// Forward speed, m/s.
    pub v: f64,
    /// Turn rate, rad/s.
    pub w: f64,
}

/// One measurement record: range and bearing to whatever carries `barcode`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BarcodeRow {
    /// Seconds since the Unix epoch.
    pub time: f64,
    /// The barcode read (see [`MrclamData::barcodes`]).
    pub barcode: u32,
    /// Range, metres.
    pub range: f64,
    /// Bearing from the robot's heading, radians (counter-clockwise).
    pub bearing: f64,
}

/// A pose at a time (Vicon).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimedPose {
    /// Seconds since the Unix epoch.
    pub time: f64,
    /// The pose.
    pub pose: Pose2,
}

/// One robot's three files.
#[derive(Clone, Debug, PartialEq)]
pub struct MrclamRobot {
    /// The robot's number (its subject number).
    pub number: u32,
    /// Its odometry, in time order.
    pub odometry: Vec<VelocityRow>,
    /// Its measurements, in time order.
    pub measurements: Vec<BarcodeRow>,
    /// Its Vicon poses, in time order (empty when the file was not given).
    pub groundtruth: Vec<TimedPose>,
}

/// An MRCLAM data set as read.
#[derive(Clone, Debug, PartialEq)]
pub struct MrclamData {
    /// The data set's name: its folder's (`MRCLAM_Dataset6`), or "MRCLAM".
    pub name: String,
    /// Barcode to subject.
    pub barcodes: BTreeMap<u32, u32>,
    /// The landmarks, in the file's order.
    pub landmarks: Vec<SurveyedLandmark>,
    /// The robots whose files were given, by number.
    pub robots: Vec<MrclamRobot>,
}

/// What a barcode names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Subject {
    /// A landmark (its subject number).
    Landmark(u32),
    /// Another robot (its number).
    Robot(u32),
    /// A barcode not in `Barcodes.dat` (a misread).
    Unknown,
}

impl MrclamData {
    /// The robot numbered `number`, if its files were given.
    pub fn robot(&self, number: u32) -> Option<&MrclamRobot> {
        self.robots.iter().find(|r| r.number == number)
    }

    /// What `barcode` names.
    pub fn subject(&self, barcode: u32) -> Subject {
        match self.barcodes.get(&barcode) {
            None => Subject::Unknown,
            Some(&s) if self.landmarks.iter().any(|l| l.subject == s) => Subject::Landmark(s),
            Some(&s) => Subject::Robot(s),
        }
    }
}

/// The robot file names: `RobotN_Odometry.dat` and the like, `(N, kind)`.
fn robot_file(base: &str) -> Option<(u32, &str)> {
    let rest = base.strip_prefix("Robot")?.strip_suffix(".dat")?;
    let (number, kind) = rest.split_once('_')?;
    let number: u32 = number.parse().ok()?;
    ((1..=MAX_ROBOTS).contains(&number)
        && matches!(kind, "Odometry" | "Measurement" | "Groundtruth"))
    .then_some((number, kind))
}

/// True for the file names of an MRCLAM data set.
pub fn is_mrclam_file(base: &str) -> bool {
    base == BARCODES || base == LANDMARK_GROUNDTRUTH || robot_file(base).is_some()
}

/// Reads a data set from its files (other files are ignored).
pub fn read(files: &[DataFile]) -> Result<MrclamData, DataError> {
    let required = |name: &str| {
        find(files, name).ok_or_else(|| {
            DataError::set(format!(
                "{name} is missing: an MRCLAM data set needs {BARCODES}, \
                 {LANDMARK_GROUNDTRUTH} and each robot's RobotN_Odometry.dat and \
                 RobotN_Measurement.dat (RobotN_Groundtruth.dat for its truth)"
            ))
        })
    };
    let barcodes_file = required(BARCODES)?;
    let landmarks_file = required(LANDMARK_GROUNDTRUTH)?;
    let barcodes = read_barcodes(barcodes_file)?;
    let landmarks = read_landmarks(landmarks_file, &barcodes)?;

    let mut numbers: Vec<u32> = files
        .iter()
        .filter_map(|f| robot_file(f.base_name()).map(|(n, _)| n))
        .collect();
    numbers.sort_unstable();
    numbers.dedup();
    if numbers.is_empty() {
        return Err(DataError::set(
            "no robot's files: an MRCLAM data set needs RobotN_Odometry.dat and \
             RobotN_Measurement.dat for at least one robot N",
        ));
    }
    let mut robots = Vec::new();
    for number in numbers {
        let file = |kind: &str| find(files, &format!("Robot{number}_{kind}.dat"));
        let (Some(odometry), Some(measurements)) = (file("Odometry"), file("Measurement")) else {
            let missing = if file("Odometry").is_none() {
                "Odometry"
            } else {
                "Measurement"
            };
            return Err(DataError::set(format!(
                "Robot{number}_{missing}.dat is missing: robot {number} needs its \
                 odometry and its measurements"
            )));
        };
        if !barcodes.values().any(|&s| s == number) {
            return Err(DataError::file(
                &barcodes_file.name,
                format!("has no barcode for robot {number}, whose files are given"),
            ));
        }
        robots.push(MrclamRobot {
            number,
            odometry: read_odometry(odometry)?,
            measurements: read_measurements(measurements)?,
            groundtruth: file("Groundtruth")
                .map(read_groundtruth)
                .transpose()?
                .unwrap_or_default(),
        });
    }
    Ok(MrclamData {
        name: data_set_name(&barcodes_file.name),
        barcodes,
        landmarks,
        robots,
    })
}

/// `MRCLAM_Dataset6` from `…/MRCLAM_Dataset6/Barcodes.dat`, else "MRCLAM".
fn data_set_name(barcodes_path: &str) -> String {
    let folder = barcodes_path
        .strip_suffix(base_name(barcodes_path))
        .map(|f| f.trim_end_matches(['/', '\\']))
        .map(base_name)
        .unwrap_or_default();
    if folder.is_empty() || folder.to_ascii_lowercase().ends_with(".zip") {
        folder
            .strip_suffix(".zip")
            .filter(|f| !f.is_empty())
            .unwrap_or("MRCLAM")
            .to_owned()
    } else {
        folder.to_owned()
    }
}

/// `Barcodes.dat`: barcode to subject, one barcode per subject and one subject per barcode.
fn read_barcodes(file: &DataFile) -> Result<BTreeMap<u32, u32>, DataError> {
    let mut by_barcode: BTreeMap<u32, (u32, usize)> = BTreeMap::new();
    let mut by_subject: BTreeMap<u32, (u32, usize)> = BTreeMap::new();
    for (line, [subject, barcode]) in numeric_rows(file, ["subject", "barcode"])? {
        let subject = whole(file, line, "subject", subject, MAX_CODE)?;
        let barcode = whole(file, line, "barcode", barcode, MAX_CODE)?;
        if let Some(&(other, other_line)) = by_barcode.get(&barcode) {
            return Err(DataError::line(
                &file.name,
                line,
                format!(
                    "barcode {barcode} is given to subject {subject} and to subject {other} \
                     (line {other_line}): one barcode must name one subject"
                ),
            ));
        }
        if let Some(&(other, other_line)) = by_subject.get(&subject) {
            return Err(DataError::line(
                &file.name,
                line,
                format!(
                    "subject {subject} has barcode {barcode} and barcode {other} \
                     (line {other_line}): one subject carries one barcode"
                ),
            ));
        }
        by_barcode.insert(barcode, (subject, line));
        by_subject.insert(subject, (barcode, line));
    }
    if by_barcode.is_empty() {
        return Err(DataError::file(&file.name, "has no barcodes"));
    }
    Ok(by_barcode.into_iter().map(|(b, (s, _))| (b, s)).collect())
}

/// `Landmark_Groundtruth.dat`, each landmark a subject of `Barcodes.dat`.
fn read_landmarks(
    file: &DataFile,
    barcodes: &BTreeMap<u32, u32>,
) -> Result<Vec<SurveyedLandmark>, DataError> {
    let mut landmarks: Vec<SurveyedLandmark> = Vec::new();
    for (line, [subject, x, y, x_std, y_std]) in
        numeric_rows(file, ["subject", "x", "y", "x_std", "y_std"])?
    {
        let subject = whole(file, line, "subject", subject, MAX_CODE)?;
        if !barcodes.values().any(|&s| s == subject) {
            return Err(DataError::line(
                &file.name,
                line,
                format!("landmark {subject} has no barcode in {BARCODES}"),
            ));
        }
        if landmarks.iter().any(|l| l.subject == subject) {
            return Err(DataError::line(
                &file.name,
                line,
                format!("landmark {subject} is listed twice"),
            ));
        }
        if x_std < 0.0 || y_std < 0.0 {
            return Err(DataError::line(
                &file.name,
                line,
                "a standard deviation is negative",
            ));
        }
        landmarks.push(SurveyedLandmark {
            subject,
            x,
            y,
            x_std,
            y_std,
        });
    }
    if landmarks.is_empty() {
        return Err(DataError::file(&file.name, "has no landmarks"));
    }
    Ok(landmarks)
}

fn read_odometry(file: &DataFile) -> Result<Vec<VelocityRow>, DataError> {
    let rows = numeric_rows(file, ["time", "v", "w"])?;
    check_time_order(file, rows.iter().map(|(l, r)| (*l, r[0])))?;
    Ok(rows
        .into_iter()
        .map(|(_, [time, v, w])| VelocityRow { time, v, w })
        .collect())
}

fn read_measurements(file: &DataFile) -> Result<Vec<BarcodeRow>, DataError> {
    let rows = numeric_rows(file, ["time", "barcode", "range", "bearing"])?;
    check_time_order(file, rows.iter().map(|(l, r)| (*l, r[0])))?;
    rows.into_iter()
        .map(|(line, [time, barcode, range, bearing])| {
            check_range(file, line, range)?;
            Ok(BarcodeRow {
                time,
                barcode: whole(file, line, "barcode", barcode, MAX_CODE)?,
                range,
                bearing,
            })
        })
        .collect()
}

fn read_groundtruth(file: &DataFile) -> Result<Vec<TimedPose>, DataError> {
    let rows = numeric_rows(file, ["time", "x", "y", "theta"])?;
    check_time_order(file, rows.iter().map(|(l, r)| (*l, r[0])))?;
    Ok(rows
        .into_iter()
        .map(|(_, [time, x, y, theta])| TimedPose {
            time,
            // As the file gives it (Vicon's headings are in (-π, π] already).
            pose: Pose2 { x, y, theta },
        })
        .collect())
}
