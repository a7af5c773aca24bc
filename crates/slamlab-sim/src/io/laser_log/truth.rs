//! The truth companion of a simulated log (`<log>.truth`): the robot's true
//! pose at each scan, for metrics only (no estimator reads it).
//!
//! Format: UTF-8 text, `#` comment lines, then one line per scan
//! `timestamp x y theta` (seconds, metres, metres, radians; `%.6f`), in the
//! log's scan order.

use slamlab_core::Pose2;
use std::fmt::Write;

/// The true pose of the robot at one scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruePose {
    /// The scan's timestamp, seconds.
    pub timestamp: f64,
    /// The robot's true pose in the map frame.
    pub pose: Pose2,
}

/// Why a truth file cannot be read.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TruthError {
    /// A line that is not four finite numbers.
    #[error("truth file line {line}: {message}")]
    Malformed {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// Over the size cap.
    #[error("the truth file is {0} bytes, over the cap of {1} bytes")]
    TooLarge(u64, u64),
}

/// Writes the truth file.
pub fn write_truth(poses: &[TruePose]) -> String {
    let mut out = String::with_capacity(40 + poses.len() * 48);
    out.push_str("# SLAM Lab truth: timestamp x y theta (s, m, m, rad), one line per scan\n");
    for p in poses {
        let _ = writeln!(
            out,
            "{:.6} {:.6} {:.6} {:.6}",
            p.timestamp, p.pose.x, p.pose.y, p.pose.theta
        );
    }
    out
}

/// Reads a truth file.
pub fn read_truth(text: &str) -> Result<Vec<TruePose>, TruthError> {
    if text.len() as u64 > super::MAX_UNPACKED_BYTES {
        return Err(TruthError::TooLarge(
            text.len() as u64,
            super::MAX_UNPACKED_BYTES,
        ));
    }
    let mut out = Vec::new();
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let s = raw.trim();
        if s.is_empty() || s.starts_with('#') {
            continue;
        }
        let mut values = [0.0; 4];
        let mut fields = s.split_ascii_whitespace();
        for (k, name) in ["timestamp", "x", "y", "theta"].iter().enumerate() {
            let field = fields.next().ok_or_else(|| TruthError::Malformed {
                line,
                message: format!("missing {name}; expected `timestamp x y theta`"),
            })?;
            values[k] = match field.parse::<f64>() {
                Ok(v) if v.is_finite() => v,
                _ => {
                    return Err(TruthError::Malformed {
                        line,
                        message: format!("{name} {field:?} is not a finite number"),
                    });
                }
            };
        }
        if let Some(extra) = fields.next() {
            return Err(TruthError::Malformed {
                line,
                message: format!("unexpected field {extra:?} after theta"),
            });
        }
        out.push(TruePose {
            timestamp: values[0],
            pose: Pose2::new(values[1], values[2], values[3]),
        });
    }
    Ok(out)
}
