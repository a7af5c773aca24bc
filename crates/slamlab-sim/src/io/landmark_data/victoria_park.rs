//! Victoria Park, Sydney (J. Guivant and E. Nebot, ACFR): a utility car driven
//! through a park for about 26 minutes, tree trunks detected in a 180° laser.
//! These are K. Leung's text conversions of the ACFR files:
//!
//! - `inputs.dat`: `time speed steering` (s, m/s, rad), the encoder's speed and
//!   the steering angle.
//! - `measurements.dat`: `time range bearing diameter` (s, m, rad, m); rows with
//!   the same time are one laser scan. The bearing runs from 0 (right) to π
//!   (left) across the sweep: π/2 is straight ahead. Trees carry no identity.
//! - `gps.dat`: `time x y` (s, m): fixes in a frame of their own, often missing.
//!
//! Times are seconds after the first GPS fix. `inputs.dat` and `measurements.dat`
//! are required; without `gps.dat` the run has no reference.

use super::table::{check_range, check_time_order, numeric_rows};
use super::{DataError, DataFile, find};

/// The car's inputs.
pub const INPUTS: &str = "inputs.dat";
/// The tree detections.
pub const MEASUREMENTS: &str = "measurements.dat";
/// The GPS fixes.
pub const GPS: &str = "gps.dat";
/// The three file names.
pub const FILES: [&str; 3] = [INPUTS, MEASUREMENTS, GPS];

/// The car's speed and steering from `time` on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CarInput {
    /// Seconds.
    pub time: f64,
    /// The encoder's speed (on the rear left wheel), m/s.
    pub speed: f64,
    /// Steering angle, radians (positive to the left).
    pub steering: f64,
}

/// One tree in a scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeDetection {
    /// Range from the laser, metres.
    pub range: f64,
    /// Bearing in the laser's sweep, radians: 0 right, π/2 ahead, π left.
    pub bearing: f64,
    /// The trunk's estimated diameter, metres.
    pub diameter: f64,
}

/// The trees of one laser scan.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeScan {
    /// Seconds.
    pub time: f64,
    /// The detections, in the file's order.
    pub trees: Vec<TreeDetection>,
}

/// A GPS fix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpsFix {
    /// Seconds.
    pub time: f64,
    /// Metres, in the GPS's own frame.
    pub x: f64,
    /// Metres, in the GPS's own frame.
    pub y: f64,
}

/// The three files as read.
#[derive(Clone, Debug, PartialEq)]
pub struct VictoriaParkData {
    /// The car's inputs, in time order.
    pub inputs: Vec<CarInput>,
    /// The laser scans with trees, in time order.
    pub scans: Vec<TreeScan>,
    /// The GPS fixes, in time order (empty when `gps.dat` was not given).
    pub gps: Vec<GpsFix>,
}

impl VictoriaParkData {
    /// The number of tree detections.
    pub fn detection_count(&self) -> usize {
        self.scans.iter().map(|s| s.trees.len()).sum()
    }
}

/// Reads the files (other files are ignored).
pub fn read(files: &[DataFile]) -> Result<VictoriaParkData, DataError> {
    let required = |name: &str| {
        find(files, name).ok_or_else(|| {
            DataError::set(format!(
                "{name} is missing: Victoria Park is {INPUTS} and {MEASUREMENTS} (with \
                 {GPS} for the reference)"
            ))
        })
    };
    let inputs_file = required(INPUTS)?;
    let measurements_file = required(MEASUREMENTS)?;

    let rows = numeric_rows(inputs_file, ["time", "speed", "steering"])?;
    check_time_order(inputs_file, rows.iter().map(|(l, r)| (*l, r[0])))?;
    if rows.is_empty() {
        return Err(DataError::file(&inputs_file.name, "has no inputs"));
    }
    let inputs = rows
        .into_iter()
        .map(|(_, [time, speed, steering])| CarInput {
            time,
            speed,
            steering,
        })
        .collect();

    let rows = numeric_rows(measurements_file, ["time", "range", "bearing", "diameter"])?;
    check_time_order(measurements_file, rows.iter().map(|(l, r)| (*l, r[0])))?;
    let mut scans: Vec<TreeScan> = Vec::new();
    for (line, [time, range, bearing, diameter]) in rows {
        check_range(measurements_file, line, range)?;
        let tree = TreeDetection {
            range,
            bearing,
            diameter,
        };
        match scans.last_mut() {
            Some(scan) if scan.time == time => scan.trees.push(tree),
            _ => scans.push(TreeScan {
                time,
                trees: vec![tree],
            }),
        }
    }

    let gps = match find(files, GPS) {
        Some(file) => {
            let rows = numeric_rows(file, ["time", "x", "y"])?;
            check_time_order(file, rows.iter().map(|(l, r)| (*l, r[0])))?;
            rows.into_iter()
                .map(|(_, [time, x, y])| GpsFix { time, x, y })
                .collect()
        }
        None => Vec::new(),
    };
    Ok(VictoriaParkData { inputs, scans, gps })
}
