//! The Freiburg "Robot Mapping" course's EKF-SLAM data (C. Stachniss): the
//! input of its EKF-SLAM, UKF-SLAM and FastSLAM homework.
//!
//! - `world.dat`: one landmark a line, `id x y` (metres).
//! - `sensor_data.dat`: steps; each is one line `ODOMETRY r1 t r2` (the odometry
//!   motion model: rotate `r1`, translate `t`, rotate `r2`; radians and metres)
//!   followed by zero or more lines `SENSOR id range bearing` (metres, radians;
//!   the landmark's id: known correspondences).
//!
//! Quirks accepted, as the course's own code does: a negative range (the file has
//! one, -0.035 m) and bearings slightly beyond ±π. Both are counted
//! ([`FreiburgData::negative_ranges`], [`FreiburgData::bearings_beyond_pi`]).
//! `sensor_data.dat` is required; without `world.dat` the run has no true landmarks.

use super::table::{number, records, text, whole};
use super::{DataError, DataFile, find};
use std::f64::consts::PI;

/// The step file.
pub const SENSOR_DATA: &str = "sensor_data.dat";
/// The landmark file.
pub const WORLD: &str = "world.dat";
/// Both file names.
pub const FILES: [&str; 2] = [SENSOR_DATA, WORLD];
/// The largest landmark id accepted.
pub const MAX_ID: u32 = 1_000_000;

/// A landmark of `world.dat`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldLandmark {
    /// Its id (the `SENSOR` lines' id).
    pub id: u32,
    /// Position, metres.
    pub x: f64,
    /// Position, metres.
    pub y: f64,
}

/// The odometry of one step (Probabilistic Robotics Sec. 5.4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometryReading {
    /// First rotation, radians.
    pub rot1: f64,
    /// Translation, metres.
    pub trans: f64,
    /// Second rotation, radians.
    pub rot2: f64,
}

/// One `SENSOR` line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorReading {
    /// The landmark's id.
    pub id: u32,
    /// Range, metres (may be slightly negative: see the module).
    pub range: f64,
    /// Bearing, radians (may lie slightly beyond ±π).
    pub bearing: f64,
}

/// One step: an odometry reading and the sensor readings after it.
#[derive(Clone, Debug, PartialEq)]
pub struct FreiburgStep {
    /// The step's `ODOMETRY` line's number.
    pub line: usize,
    /// The motion.
    pub odometry: OdometryReading,
    /// The landmarks seen after it.
    pub sensors: Vec<SensorReading>,
}

/// The two files as read.
#[derive(Clone, Debug, PartialEq)]
pub struct FreiburgData {
    /// `world.dat`'s landmarks (empty when it was not given).
    pub world: Vec<WorldLandmark>,
    /// The steps of `sensor_data.dat`.
    pub steps: Vec<FreiburgStep>,
    /// `SENSOR` lines with a negative range.
    pub negative_ranges: usize,
    /// `SENSOR` lines with a bearing beyond ±π.
    pub bearings_beyond_pi: usize,
}

impl FreiburgData {
    /// The number of `SENSOR` lines.
    pub fn sensor_count(&self) -> usize {
        self.steps.iter().map(|s| s.sensors.len()).sum()
    }
}

/// Reads the course's files (other files are ignored).
pub fn read(files: &[DataFile]) -> Result<FreiburgData, DataError> {
    let sensor_file = find(files, SENSOR_DATA).ok_or_else(|| {
        DataError::set(format!(
            "{SENSOR_DATA} is missing: the Freiburg course's data is {SENSOR_DATA} \
             (with {WORLD} for the true landmarks)"
        ))
    })?;
    let world = find(files, WORLD).map(read_world).transpose()?;
    let mut data = read_sensor_data(sensor_file)?;
    data.world = world.unwrap_or_default();
    Ok(data)
}

fn read_world(file: &DataFile) -> Result<Vec<WorldLandmark>, DataError> {
    let mut world: Vec<WorldLandmark> = Vec::new();
    for (line, fields) in records(text(file)?) {
        if fields.len() != 3 {
            return Err(DataError::line(
                &file.name,
                line,
                format!("{} fields, expected 3: id, x, y", fields.len()),
            ));
        }
        let id = whole(
            file,
            line,
            "id",
            number(file, line, "id", fields[0])?,
            MAX_ID,
        )?;
        if world.iter().any(|l| l.id == id) {
            return Err(DataError::line(
                &file.name,
                line,
                format!("landmark {id} is listed twice"),
            ));
        }
        world.push(WorldLandmark {
            id,
            x: number(file, line, "x", fields[1])?,
            y: number(file, line, "y", fields[2])?,
        });
    }
    Ok(world)
}

fn read_sensor_data(file: &DataFile) -> Result<FreiburgData, DataError> {
    let mut data = FreiburgData {
        world: Vec::new(),
        steps: Vec::new(),
        negative_ranges: 0,
        bearings_beyond_pi: 0,
    };
    for (line, fields) in records(text(file)?) {
        let values = |names: [&str; 3]| -> Result<[f64; 3], DataError> {
            if fields.len() != 4 {
                return Err(DataError::line(
                    &file.name,
                    line,
                    format!(
                        "{} has {} numbers, expected 3: {}",
                        fields[0],
                        fields.len() - 1,
                        names.join(", ")
                    ),
                ));
            }
            Ok([
                number(file, line, names[0], fields[1])?,
                number(file, line, names[1], fields[2])?,
                number(file, line, names[2], fields[3])?,
            ])
        };
        match fields[0] {
            "ODOMETRY" => {
                let [rot1, trans, rot2] = values(["r1", "t", "r2"])?;
                data.steps.push(FreiburgStep {
                    line,
                    odometry: OdometryReading { rot1, trans, rot2 },
                    sensors: Vec::new(),
                });
            }
            "SENSOR" => {
                let [id, range, bearing] = values(["id", "range", "bearing"])?;
                let id = whole(file, line, "id", id, MAX_ID)?;
                let Some(step) = data.steps.last_mut() else {
                    return Err(DataError::line(
                        &file.name,
                        line,
                        "a SENSOR line before the first ODOMETRY line: every step starts \
                         with its odometry",
                    ));
                };
                step.sensors.push(SensorReading { id, range, bearing });
                data.negative_ranges += usize::from(range < 0.0);
                data.bearings_beyond_pi += usize::from(bearing.abs() > PI);
            }
            other => {
                return Err(DataError::line(
                    &file.name,
                    line,
                    format!(
                        "'{}' is not a record of {SENSOR_DATA} (ODOMETRY or SENSOR)",
                        super::table::shorten(other)
                    ),
                ));
            }
        }
    }
    if data.steps.is_empty() {
        return Err(DataError::file(&file.name, "has no ODOMETRY line"));
    }
    Ok(data)
}
