//! Writing a [`LaserLog`] as a CARMEN log: `PARAM`, `ODOM` and `FLASER`
//! lines that any CARMEN tool, and [`LaserLog::from_bytes`], read.
//!
//! `FLASER` carries no angles, so the writer states the layout in `PARAM`
//! lines the reader honours: `laser_front_laser_fov` (twice the first beam's
//! angle, so that the first beam is at `-fov/2`), `laser_front_laser_resolution`
//! (the spacing) in degrees, and `robot_front_laser_max` in metres.
//!
//! Printed precision: ranges to 1 mm (`%.3f`, as CARMEN writes them), poses to
//! 1 µm and 1 µrad (`%.6f`), times to 1 µs (`%.6f`), angles in the `PARAM`s to
//! 1e-9 degrees. Reading the output and writing it again gives the same text.

use super::{LaserLog, LogOdometry, LogScan};
use slamlab_core::Pose2;
use std::fmt::Write;

/// Why a log cannot be written as `FLASER` records.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum WriteError {
    /// Nothing to write.
    #[error("the log has no scans")]
    NoScans,
    /// Scans whose angles cannot be told by one `fov`/resolution pair.
    #[error("scan {index}: {message}; FLASER records need one evenly spaced beam layout")]
    UnevenLayout {
        /// Index of the scan in the log.
        index: usize,
        /// What differs.
        message: String,
    },
}

/// The scan layout written in the `PARAM`s: `(fov, resolution, max_range)`,
/// checked to describe every scan's angles to within the printed precision.
fn layout(log: &LaserLog) -> Result<(f64, f64, f64), WriteError> {
    let first = log.scans.first().ok_or(WriteError::NoScans)?;
    let a = &first.scan.angles;
    let n = a.len();
    let resolution = if n >= 2 {
        a[1] - a[0]
    } else {
        1f64.to_radians()
    };
    let fov = if n >= 1 { -2.0 * a[0] } else { 0.0 };
    let max = first.scan.range_max;
    for (index, s) in log.scans.iter().enumerate() {
        if s.scan.angles.len() != n || s.scan.ranges.len() != n {
            return Err(WriteError::UnevenLayout {
                index,
                message: format!("{} beams where the first scan has {n}", s.scan.ranges.len()),
            });
        }
        if s.scan.range_max != max {
            return Err(WriteError::UnevenLayout {
                index,
                message: format!(
                    "maximum range {} where the first scan has {max}",
                    s.scan.range_max
                ),
            });
        }
        for (k, &angle) in s.scan.angles.iter().enumerate() {
            let expected = -fov / 2.0 + k as f64 * resolution;
            if (angle - expected).abs() > 1e-9 {
                return Err(WriteError::UnevenLayout {
                    index,
                    message: format!("beam {k} at {angle} rad, expected {expected} rad"),
                });
            }
        }
    }
    Ok((fov, resolution, max))
}

/// Appends ` v` with `decimals` decimals, without a minus sign on a value
/// that prints as zero (`-0.000000` would not survive a second round trip
/// unchanged).
fn push_fixed(out: &mut String, v: f64, decimals: usize) {
    let start = out.len();
    let _ = write!(out, " {v:.decimals$}");
    if out[start..].starts_with(" -") && out[start + 2..].bytes().all(|b| b == b'0' || b == b'.') {
        out.remove(start + 1);
    }
}

fn pose_fields(out: &mut String, p: &Pose2) {
    for v in [p.x, p.y, p.theta] {
        push_fixed(out, v, 6);
    }
}

fn odom_line(out: &mut String, o: &LogOdometry) {
    out.push_str("ODOM");
    pose_fields(out, &o.pose);
    for v in [o.tv, o.rv, 0.0, o.timestamp] {
        push_fixed(out, v, 6);
    }
    out.push_str(" slamlab");
    push_fixed(out, o.timestamp, 6);
    out.push('\n');
}

fn laser_line(out: &mut String, s: &LogScan) {
    let _ = write!(out, "FLASER {}", s.scan.ranges.len());
    for r in &s.scan.ranges {
        if r.is_nan() {
            out.push_str(" nan");
        } else {
            push_fixed(out, *r, 3);
        }
    }
    pose_fields(out, &s.laser_pose());
    pose_fields(out, &s.odometry);
    push_fixed(out, s.timestamp, 6);
    out.push_str(" slamlab");
    push_fixed(out, s.timestamp, 6);
    out.push('\n');
}

/// Writes `log` as CARMEN text: a header, the `PARAM`s (the log's own, then the
/// beam layout), then `ODOM` and laser lines merged in time order (at equal
/// times `ODOM` first). Every scan is written as `FLASER` (the layout check
/// makes sure they share one beam layout), so `RLASER` and `ROBOTLASER1`
/// scans read back as front-laser scans.
pub fn write_carmen(log: &LaserLog) -> Result<String, WriteError> {
    let (fov, resolution, max) = layout(log)?;
    let beams = log.scans.first().map_or(0, |s| s.scan.ranges.len());
    let mut out = String::with_capacity(64 + log.scans.len() * (beams * 6 + 120));
    out.push_str("# CARMEN log written by SLAM Lab\n");
    out.push_str("# message_name [message contents] ipc_timestamp ipc_hostname logger_timestamp\n");
    out.push_str("# ODOM x y theta tv rv accel\n");
    out.push_str("# FLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta\n");
    let layout_names = [
        "laser_front_laser_fov",
        "laser_front_laser_resolution",
        "robot_front_laser_max",
    ];
    for (name, value) in &log.params {
        if !layout_names.contains(&name.as_str()) && !name.contains(char::is_whitespace) {
            let _ = writeln!(out, "PARAM {name} {value} 0.000000 slamlab 0.000000");
        }
    }
    let _ = writeln!(
        out,
        "PARAM laser_front_laser_fov {:.9} 0.000000 slamlab 0.000000",
        fov.to_degrees()
    );
    let _ = writeln!(
        out,
        "PARAM laser_front_laser_resolution {:.9} 0.000000 slamlab 0.000000",
        resolution.to_degrees()
    );
    let _ = writeln!(
        out,
        "PARAM robot_front_laser_max {max} 0.000000 slamlab 0.000000"
    );
    let (mut i, mut j) = (0, 0);
    while i < log.odometry.len() || j < log.scans.len() {
        let odom_next = match (log.odometry.get(i), log.scans.get(j)) {
            (Some(o), Some(s)) => o.timestamp <= s.timestamp,
            (Some(_), None) => true,
            _ => false,
        };
        if odom_next {
            odom_line(&mut out, &log.odometry[i]);
            i += 1;
        } else {
            laser_line(&mut out, &log.scans[j]);
            j += 1;
        }
    }
    Ok(out)
}
