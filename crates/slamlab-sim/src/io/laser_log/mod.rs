//! Laser logs: CARMEN log files read and written, and simulated logs with
//! their ground truth, so that a real recording (the Intel Research Lab log)
//! and a simulated run are the same input to the lidar lessons.
//!
//! # The CARMEN subset read
//!
//! One record a line, fields separated by white space, `#` starts a comment
//! line. Every message ends with `ipc_timestamp ipc_hostname logger_timestamp`;
//! SLAM Lab keeps `ipc_timestamp` (UNIX seconds) as the record's time.
//!
//! - `FLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta ipc_timestamp host logger_timestamp`
//!   (front laser) and `RLASER` (rear laser, same layout): `x y theta` is the
//!   laser's pose, `odom_*` the robot's odometry pose when the scan was taken.
//!   The beam angles are not in the record; see [`BeamLayout`].
//! - `ROBOTLASER1 laser_type start_angle fov angular_resolution max_range accuracy
//!   remission_mode n r_1 .. r_n m e_1 .. e_m laser_x laser_y laser_theta
//!   robot_x robot_y robot_theta tv rv forward_safety_dist side_safety_dist
//!   turn_axis ipc_timestamp host logger_timestamp` (CARMEN's
//!   `carmen_robot_laser_message`): angles `start_angle + k · angular_resolution`.
//! - `ODOM x y theta tv rv accel ipc_timestamp host logger_timestamp`.
//! - `PARAM name value ipc_timestamp host logger_timestamp`.
//!
//! Every other record (`SYNC`, `TRUEPOS`, `NMEA-GGA`, ...) is counted by name in
//! [`LaserLog::skipped`] and otherwise ignored.
//!
//! # Conventions
//!
//! - Units: metres, radians (CARMEN's own), seconds.
//! - Angles of `FLASER`/`RLASER`: `n` beams over the field of view `fov`, the
//!   first at `-fov/2`, `fov/n` apart (180 beams: -90°, -89°, ..., +89°, the
//!   convention of the Intel log and GMapping's CARMEN reader). `fov` is 180°
//!   unless a `PARAM` gives it (see [`BeamLayout::from_params`]); a `PARAM`
//!   resolution, if given, replaces `fov/n` as the spacing.
//! - Maximum range of `FLASER`/`RLASER`: [`DEFAULT_FLASER_MAX_RANGE`] (50 m)
//!   unless a `PARAM` gives it. The SICK scanners of the FLASER era report "no
//!   return" as a large code: in the Intel log every reading is either at most
//!   26.37 m or exactly 81.83 m (68,313 readings), so with 50 m the 81.83 m codes
//!   read as "nothing within range" and every real reading is kept.
//! - NaN and negative ranges: the line is kept, those beams are stored as NaN
//!   (the scan type ignores NaN readings) and counted in
//!   [`LaserLog::unusable_readings`]. `+inf` is kept and reads as "nothing
//!   within range".
//! - A beam count that changes mid-log (for one record type) is refused with
//!   the line number ([`LogError::BeamCountChanged`]): the lessons assume one
//!   sensor layout per log.
//!
//! # Caps
//!
//! [`MAX_INPUT_BYTES`] on the file as given (compressed or not), refused before
//! it is read or unpacked, and [`MAX_UNPACKED_BYTES`] on the unpacked text,
//! checked while decompressing.

mod compression;
mod truth;
mod write;

pub use compression::Compression;
pub use truth::{TruePose, TruthError, read_truth, write_truth};
pub use write::{WriteError, write_carmen};

use slamlab_core::Pose2;
use slamlab_core::particle::Scan;
use std::collections::BTreeMap;

/// The largest file accepted (compressed or plain), bytes: 256 MiB.
pub const MAX_INPUT_BYTES: u64 = 256 * 1024 * 1024;
/// The largest unpacked text accepted, bytes: 256 MiB (the Intel log unpacks
/// to 16.4 MB).
pub const MAX_UNPACKED_BYTES: u64 = 256 * 1024 * 1024;
/// Maximum range of `FLASER`/`RLASER` scans when no `PARAM` gives it, metres.
pub const DEFAULT_FLASER_MAX_RANGE: f64 = 50.0;
/// Field of view of `FLASER`/`RLASER` scans when no `PARAM` gives it, degrees.
pub const DEFAULT_FLASER_FOV_DEG: f64 = 180.0;
/// The most beams a record may declare (a guard against a corrupt count).
pub const MAX_BEAMS: usize = 100_000;

/// The size limits a read enforces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogLimits {
    /// Largest input, bytes.
    pub max_input_bytes: u64,
    /// Largest unpacked text, bytes.
    pub max_unpacked_bytes: u64,
}

impl Default for LogLimits {
    fn default() -> Self {
        Self {
            max_input_bytes: MAX_INPUT_BYTES,
            max_unpacked_bytes: MAX_UNPACKED_BYTES,
        }
    }
}

/// Why a log cannot be read.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum LogError {
    /// The file or its unpacked text is over a cap.
    #[error("{what} is {bytes} bytes, over the cap of {cap} bytes")]
    TooLarge {
        /// What was too large.
        what: &'static str,
        /// Its size (for unpacked text: where unpacking stopped), bytes.
        bytes: u64,
        /// The cap, bytes.
        cap: u64,
    },
    /// Packed in a format SLAM Lab does not unpack.
    #[error("the file is {0}-compressed; SLAM Lab reads plain, gzip and bzip2 logs")]
    UnsupportedCompression(&'static str),
    /// Compressed data that does not unpack (truncated or corrupt).
    #[error(
        "the {compression} data is truncated or corrupt ({message}) after {unpacked} unpacked bytes"
    )]
    Corrupt {
        /// `gzip` or `bzip2`.
        compression: &'static str,
        /// The decoder's message.
        message: String,
        /// Bytes unpacked before the failure.
        unpacked: u64,
    },
    /// A line that is not valid UTF-8 text.
    #[error("line {line}: not text (invalid UTF-8)")]
    NotText {
        /// 1-based line number.
        line: usize,
    },
    /// A record that does not have the layout its name promises.
    #[error("line {line}: malformed {record} record: {message}")]
    Malformed {
        /// 1-based line number.
        line: usize,
        /// The record name.
        record: String,
        /// What is wrong.
        message: String,
    },
    /// A laser record type whose beam count differs from its first record's.
    #[error(
        "line {line}: {record} has {found} beams where the first {record} (line {first_line}) had {expected}; SLAM Lab reads logs with one beam count per laser"
    )]
    BeamCountChanged {
        /// 1-based line number.
        line: usize,
        /// The record name.
        record: String,
        /// Beams in the first record of this type.
        expected: usize,
        /// The line of that first record.
        first_line: usize,
        /// Beams in this record.
        found: usize,
    },
    /// A `PARAM` the reader uses whose value is not a usable number.
    #[error("line {line}: PARAM {name} = {value:?} is not a positive number")]
    BadParam {
        /// 1-based line number.
        line: usize,
        /// The parameter.
        name: String,
        /// Its value.
        value: String,
    },
    /// No `FLASER`, `RLASER` or `ROBOTLASER1` record at all.
    #[error("the log has no laser record (FLASER, RLASER or ROBOTLASER1) in {lines} lines")]
    NoLaserRecord {
        /// Lines read.
        lines: usize,
    },
}

/// The laser record a scan came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum LaserKind {
    /// `FLASER`: the front laser.
    Front,
    /// `RLASER`: the rear laser.
    Rear,
    /// `ROBOTLASER1`: a laser with its own angles and range in the record.
    Robot,
}

impl LaserKind {
    /// The CARMEN record name.
    pub fn record(self) -> &'static str {
        match self {
            LaserKind::Front => "FLASER",
            LaserKind::Rear => "RLASER",
            LaserKind::Robot => "ROBOTLASER1",
        }
    }
}

/// One laser scan of a log.
#[derive(Clone, Debug, PartialEq)]
pub struct LogScan {
    /// `ipc_timestamp`, seconds.
    pub timestamp: f64,
    /// Which record it came from.
    pub kind: LaserKind,
    /// Angles and ranges in the sensor frame.
    pub scan: Scan,
    /// The robot's odometry pose when the scan was taken (`odom_x odom_y
    /// odom_theta` of `FLASER`, `robot_pose` of `ROBOTLASER1`).
    pub odometry: Pose2,
    /// The laser's pose in the odometry frame (`x y theta` of `FLASER`,
    /// `laser_pose` of `ROBOTLASER1`) when it differs from `odometry`; `None`
    /// when the laser sits at the robot's centre.
    pub laser_pose: Option<Pose2>,
    /// The 1-based line it was read from (0 for a scan not read from a file).
    pub line: usize,
}

impl LogScan {
    /// The laser's pose in the odometry frame.
    pub fn laser_pose(&self) -> Pose2 {
        self.laser_pose.unwrap_or(self.odometry)
    }
}

/// One `ODOM` record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogOdometry {
    /// `ipc_timestamp`, seconds.
    pub timestamp: f64,
    /// The odometry pose.
    pub pose: Pose2,
    /// Translational velocity, m/s.
    pub tv: f64,
    /// Rotational velocity, rad/s.
    pub rv: f64,
}

/// A laser log: scans, odometry, parameters and what was skipped.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LaserLog {
    /// The laser scans in file order.
    pub scans: Vec<LogScan>,
    /// The `ODOM` records in file order.
    pub odometry: Vec<LogOdometry>,
    /// `PARAM name value` (a later value replaces an earlier one).
    pub params: BTreeMap<String, String>,
    /// Records of other types, counted by name.
    pub skipped: BTreeMap<String, usize>,
    /// Comment lines.
    pub comments: usize,
    /// NaN or negative readings, stored as NaN.
    pub unusable_readings: usize,
    /// How the file was packed.
    pub compression: Option<Compression>,
}

/// The beam layout of `FLASER`/`RLASER` records (which carry only ranges).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeamLayout {
    /// Field of view, radians; the first beam is at `-fov/2`.
    pub fov: f64,
    /// Spacing between beams, radians; `None`: `fov / n`.
    pub resolution: Option<f64>,
    /// Maximum range, metres.
    pub max_range: f64,
}

/// `PARAM` names that give a front laser's field of view, degrees.
const FRONT_FOV: [&str; 2] = ["laser_front_laser_fov", "robot_front_laser_fov"];
/// `PARAM` names that give a front laser's angular resolution, degrees.
const FRONT_RESOLUTION: [&str; 2] = [
    "laser_front_laser_resolution",
    "robot_front_laser_resolution",
];
/// `PARAM` names that give a front laser's maximum range, metres.
const FRONT_MAX: [&str; 3] = [
    "robot_front_laser_max",
    "laser_front_laser_maxrange",
    "laser_front_laser_max_range",
];
const REAR_FOV: [&str; 2] = ["laser_rear_laser_fov", "robot_rear_laser_fov"];
const REAR_RESOLUTION: [&str; 2] = ["laser_rear_laser_resolution", "robot_rear_laser_resolution"];
const REAR_MAX: [&str; 3] = [
    "robot_rear_laser_max",
    "laser_rear_laser_maxrange",
    "laser_rear_laser_max_range",
];

impl BeamLayout {
    /// The `PARAM` names read for a laser: field of view (degrees), angular
    /// resolution (degrees), maximum range (metres).
    pub fn param_names(
        kind: LaserKind,
    ) -> (
        &'static [&'static str],
        &'static [&'static str],
        &'static [&'static str],
    ) {
        match kind {
            LaserKind::Rear => (&REAR_FOV, &REAR_RESOLUTION, &REAR_MAX),
            _ => (&FRONT_FOV, &FRONT_RESOLUTION, &FRONT_MAX),
        }
    }

    /// The layout the parameters give for a `FLASER` (front) or `RLASER`
    /// (rear) laser: the first of the names in [`BeamLayout::param_names`]
    /// present, else 180° and [`DEFAULT_FLASER_MAX_RANGE`].
    pub fn from_params(
        kind: LaserKind,
        params: &BTreeMap<String, String>,
        param_lines: &BTreeMap<String, usize>,
    ) -> Result<Self, LogError> {
        let (fov, res, max) = Self::param_names(kind);
        let lookup = |names: &[&str]| -> Result<Option<f64>, LogError> {
            for name in names {
                if let Some(value) = params.get(*name) {
                    return match value.trim().parse::<f64>() {
                        Ok(v) if v.is_finite() && v > 0.0 => Ok(Some(v)),
                        _ => Err(LogError::BadParam {
                            line: param_lines.get(*name).copied().unwrap_or(0),
                            name: (*name).to_string(),
                            value: value.clone(),
                        }),
                    };
                }
            }
            Ok(None)
        };
        let fov_deg = lookup(fov)?.unwrap_or(DEFAULT_FLASER_FOV_DEG);
        Ok(Self {
            fov: fov_deg.to_radians(),
            resolution: lookup(res)?.map(f64::to_radians),
            max_range: lookup(max)?.unwrap_or(DEFAULT_FLASER_MAX_RANGE),
        })
    }

    /// The angles of `n` beams.
    pub fn angles(&self, n: usize) -> Vec<f64> {
        let step = self.resolution.unwrap_or(self.fov / n.max(1) as f64);
        (0..n).map(|k| -self.fov / 2.0 + k as f64 * step).collect()
    }
}

/// A laser record before the parameters (read anywhere in the file) give
/// `FLASER`/`RLASER` their angles.
#[derive(Debug)]
struct RawScan {
    timestamp: f64,
    kind: LaserKind,
    ranges: Vec<f64>,
    /// `ROBOTLASER1`: `(start_angle, angular_resolution, max_range)`.
    own_layout: Option<(f64, f64, f64)>,
    odometry: Pose2,
    laser_pose: Pose2,
    line: usize,
}

/// The fields of one line, with the line number for messages.
struct Fields<'a> {
    tokens: Vec<&'a str>,
    next: usize,
    line: usize,
}

impl<'a> Fields<'a> {
    fn malformed(&self, message: impl Into<String>) -> LogError {
        LogError::Malformed {
            line: self.line,
            record: self.tokens.first().copied().unwrap_or("").to_string(),
            message: message.into(),
        }
    }

    fn token(&mut self, what: &str) -> Result<&'a str, LogError> {
        let t =
            self.tokens.get(self.next).copied().ok_or_else(|| {
                self.malformed(format!("missing {what} (field {})", self.next + 1))
            })?;
        self.next += 1;
        Ok(t)
    }

    fn number(&mut self, what: &str) -> Result<f64, LogError> {
        let t = self.token(what)?;
        match t.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.malformed(format!(
                "{what} {t:?} is not a finite number (field {})",
                self.next
            ))),
        }
    }

    fn count(&mut self, what: &str) -> Result<usize, LogError> {
        let t = self.token(what)?;
        match t.parse::<usize>() {
            Ok(n) if n <= MAX_BEAMS => Ok(n),
            Ok(n) => Err(self.malformed(format!("{what} {n} is over the limit of {MAX_BEAMS}"))),
            Err(_) => {
                Err(self.malformed(format!("{what} {t:?} is not a count (field {})", self.next)))
            }
        }
    }

    /// `n` ranges followed by at least `after` more fields; NaN and negative
    /// ranges become NaN and are counted.
    fn ranges(
        &mut self,
        n: usize,
        after: usize,
        unusable: &mut usize,
    ) -> Result<Vec<f64>, LogError> {
        let available = self.tokens.len().saturating_sub(self.next);
        if available < n + after {
            return Err(self.malformed(format!(
                "{n} readings announced, so at least {} fields must follow the count, but only {available} do",
                n + after
            )));
        }
        let mut out = Vec::with_capacity(n);
        for _ in 0..n {
            let t = self.token("reading")?;
            let v = t.parse::<f64>().map_err(|_| {
                self.malformed(format!(
                    "reading {t:?} is not a number (field {})",
                    self.next
                ))
            })?;
            if v.is_nan() || v < 0.0 {
                *unusable += 1;
                out.push(f64::NAN);
            } else {
                out.push(v);
            }
        }
        Ok(out)
    }

    fn pose(&mut self, what: &str) -> Result<Pose2, LogError> {
        let x = self.number(&format!("{what} x"))?;
        let y = self.number(&format!("{what} y"))?;
        let theta = self.number(&format!("{what} theta"))?;
        Ok(Pose2::new(x, y, theta))
    }

    /// `ipc_timestamp ipc_hostname logger_timestamp`: the first, checked.
    fn trailer(&mut self) -> Result<f64, LogError> {
        let t = self.number("ipc_timestamp")?;
        // The host name and logger time are not used; old logs may lack them.
        Ok(t)
    }
}

impl LaserLog {
    /// Reads a CARMEN log, plain or compressed (detected from the bytes), with
    /// the default [`LogLimits`].
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, LogError> {
        Self::from_bytes_with_limits(bytes, LogLimits::default())
    }

    /// Reads a CARMEN log within `limits`.
    pub fn from_bytes_with_limits(bytes: &[u8], limits: LogLimits) -> Result<Self, LogError> {
        check_input_size(bytes.len() as u64, limits)?;
        let (compression, text) = compression::unpack(bytes, limits.max_unpacked_bytes)?;
        let mut log = parse(&text)?;
        log.compression = Some(compression);
        Ok(log)
    }

    /// Reads a log file, refusing one over [`MAX_INPUT_BYTES`] before reading it.
    pub fn read_file(path: &std::path::Path) -> Result<Self, LogFileError> {
        let io = |e: std::io::Error| LogFileError::Io(path.display().to_string(), e.to_string());
        let len = std::fs::metadata(path).map_err(io)?.len();
        check_input_size(len, LogLimits::default())?;
        let bytes = std::fs::read(path).map_err(io)?;
        Ok(Self::from_bytes(&bytes)?)
    }

    /// The number of beams of the first scan (all scans of one record type
    /// have the same count).
    pub fn beams(&self) -> Option<usize> {
        self.scans.first().map(|s| s.scan.ranges.len())
    }

    /// The time span of the scans, seconds: `(first, last)`.
    pub fn time_span(&self) -> Option<(f64, f64)> {
        Some((self.scans.first()?.timestamp, self.scans.last()?.timestamp))
    }

    /// The number of scans of each record type.
    pub fn scan_counts(&self) -> BTreeMap<&'static str, usize> {
        let mut out = BTreeMap::new();
        for s in &self.scans {
            *out.entry(s.kind.record()).or_insert(0) += 1;
        }
        out
    }
}

/// Why a log file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum LogFileError {
    /// The file cannot be opened or read.
    #[error("cannot read {0}: {1}")]
    Io(String, String),
    /// The file is not a readable log.
    #[error(transparent)]
    Log(#[from] LogError),
}

/// Refuses an input over the cap before anything is read or unpacked.
pub fn check_input_size(bytes: u64, limits: LogLimits) -> Result<(), LogError> {
    if bytes > limits.max_input_bytes {
        return Err(LogError::TooLarge {
            what: "the file",
            bytes,
            cap: limits.max_input_bytes,
        });
    }
    Ok(())
}

/// Parses unpacked log text.
fn parse(text: &[u8]) -> Result<LaserLog, LogError> {
    let mut log = LaserLog::default();
    let mut raw = Vec::new();
    let mut param_lines = BTreeMap::new();
    // Per record type: (beam count, first line).
    let mut beam_counts: BTreeMap<LaserKind, (usize, usize)> = BTreeMap::new();
    let mut lines = 0;
    for (index, bytes) in text.split(|&b| b == b'\n').enumerate() {
        let line = index + 1;
        lines = line;
        let s = std::str::from_utf8(bytes).map_err(|_| LogError::NotText { line })?;
        let s = s.trim();
        if s.is_empty() {
            continue;
        }
        if s.starts_with('#') {
            log.comments += 1;
            continue;
        }
        let tokens: Vec<&str> = s.split_ascii_whitespace().collect();
        let name = tokens.first().copied().unwrap_or("");
        let mut f = Fields {
            tokens,
            next: 1,
            line,
        };
        match name {
            "FLASER" | "RLASER" => {
                let kind = if name == "FLASER" {
                    LaserKind::Front
                } else {
                    LaserKind::Rear
                };
                let n = f.count("num_readings")?;
                // Two poses and the timestamp follow the readings.
                let ranges = f.ranges(n, 7, &mut log.unusable_readings)?;
                let laser_pose = f.pose("laser pose")?;
                let odometry = f.pose("odometry")?;
                let timestamp = f.trailer()?;
                check_beams(&mut beam_counts, kind, n, line)?;
                raw.push(RawScan {
                    timestamp,
                    kind,
                    ranges,
                    own_layout: None,
                    odometry,
                    laser_pose,
                    line,
                });
            }
            "ROBOTLASER1" => {
                let _laser_type = f.token("laser_type")?;
                let start = f.number("start_angle")?;
                let _fov = f.number("field_of_view")?;
                let resolution = f.number("angular_resolution")?;
                let max_range = f.number("maximum_range")?;
                if !(max_range > 0.0) {
                    return Err(f.malformed(format!("maximum_range {max_range} is not positive")));
                }
                let _accuracy = f.number("accuracy")?;
                let _remission_mode = f.token("remission_mode")?;
                let n = f.count("num_readings")?;
                // The remission count, two poses, five numbers and the timestamp follow.
                let ranges = f.ranges(n, 13, &mut log.unusable_readings)?;
                let m = f.count("num_remissions")?;
                let available = f.tokens.len().saturating_sub(f.next);
                // Two poses, five numbers and the timestamp follow the remissions.
                if available < m + 12 {
                    return Err(f.malformed(format!(
                        "{m} remissions announced, so at least {} fields must follow their count, but only {available} do",
                        m + 12
                    )));
                }
                f.next += m;
                let laser_pose = f.pose("laser pose")?;
                let odometry = f.pose("robot pose")?;
                for what in [
                    "tv",
                    "rv",
                    "forward_safety_dist",
                    "side_safety_dist",
                    "turn_axis",
                ] {
                    f.number(what)?;
                }
                let timestamp = f.trailer()?;
                check_beams(&mut beam_counts, LaserKind::Robot, n, line)?;
                raw.push(RawScan {
                    timestamp,
                    kind: LaserKind::Robot,
                    ranges,
                    own_layout: Some((start, resolution, max_range)),
                    odometry,
                    laser_pose,
                    line,
                });
            }
            "ODOM" => {
                let pose = f.pose("pose")?;
                let tv = f.number("tv")?;
                let rv = f.number("rv")?;
                let _accel = f.number("accel")?;
                let timestamp = f.trailer()?;
                log.odometry.push(LogOdometry {
                    timestamp,
                    pose,
                    tv,
                    rv,
                });
            }
            "PARAM" => {
                let n = f.tokens.len();
                if n < 3 {
                    return Err(f.malformed("expected PARAM name value"));
                }
                let key = f.tokens[1].to_string();
                // With the three trailing fields, the value is everything between.
                let value = if n >= 6 {
                    f.tokens[2..n - 3].join(" ")
                } else {
                    f.tokens[2].to_string()
                };
                param_lines.insert(key.clone(), line);
                log.params.insert(key, value);
            }
            other => {
                *log.skipped.entry(other.to_string()).or_insert(0) += 1;
            }
        }
    }
    if raw.is_empty() {
        return Err(LogError::NoLaserRecord { lines });
    }
    let front = BeamLayout::from_params(LaserKind::Front, &log.params, &param_lines)?;
    let rear = BeamLayout::from_params(LaserKind::Rear, &log.params, &param_lines)?;
    // One angle vector per record type (the beam count is fixed per type).
    let mut angle_cache: BTreeMap<LaserKind, Vec<f64>> = BTreeMap::new();
    log.scans = raw
        .into_iter()
        .map(|r| {
            let n = r.ranges.len();
            let (angles, range_max) = match (r.kind, r.own_layout) {
                (_, Some((start, res, max))) => {
                    ((0..n).map(|k| start + k as f64 * res).collect(), max)
                }
                (LaserKind::Rear, None) => (
                    angle_cache
                        .entry(LaserKind::Rear)
                        .or_insert_with(|| rear.angles(n))
                        .clone(),
                    rear.max_range,
                ),
                (_, None) => (
                    angle_cache
                        .entry(LaserKind::Front)
                        .or_insert_with(|| front.angles(n))
                        .clone(),
                    front.max_range,
                ),
            };
            LogScan {
                timestamp: r.timestamp,
                kind: r.kind,
                scan: Scan {
                    angles,
                    ranges: r.ranges,
                    range_min: 0.0,
                    range_max,
                },
                odometry: r.odometry,
                laser_pose: (r.laser_pose != r.odometry).then_some(r.laser_pose),
                line: r.line,
            }
        })
        .collect();
    Ok(log)
}

fn check_beams(
    counts: &mut BTreeMap<LaserKind, (usize, usize)>,
    kind: LaserKind,
    n: usize,
    line: usize,
) -> Result<(), LogError> {
    let (expected, first_line) = *counts.entry(kind).or_insert((n, line));
    if expected != n {
        return Err(LogError::BeamCountChanged {
            line,
            record: kind.record().to_string(),
            expected,
            first_line,
            found: n,
        });
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests;
