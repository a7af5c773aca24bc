//! A relative pose of two camera views as a student's two-view code writes it:
//! the rotation `R` and translation `t` with `X_b = R X_a + t` for a point in the
//! frames of view a and view b (the convention of the visual-odometry lesson and
//! of OpenCV's `recoverPose`).
//!
//! Two layouts, numbers separated by white space or commas over any number of
//! lines, `#` starting a comment:
//! - 12 numbers: `R` row by row, then `t` (`r11 r12 r13 r21 … r33 tx ty tz`);
//! - 7 numbers: `tx ty tz qx qy qz qw`, TUM's order without the time stamp, the
//!   quaternion Hamilton's (as ROS and Eigen write it) of the same `R`.
//!
//! A monocular `t` has no length: only its direction is scored.

use super::trajectory::check_size;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use slamlab_core::vision::RelativePose;
use std::fmt::Write as _;
use thiserror::Error;

/// How far `RᵀR` may be from the identity (largest entry) for 12 numbers to be
/// taken as a rotation: printed with six decimals, a rotation is within 1e-5.
pub const ROTATION_TOLERANCE: f64 = 1e-3;

/// Why a relative-pose file was refused.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum RelativePoseFileError {
    /// Too large, or not text.
    #[error("{0}")]
    File(String),
    /// A word that is not a number.
    #[error("line {line}: '{word}' is not a number")]
    NotANumber {
        /// 1-based line number.
        line: usize,
        /// The word.
        word: String,
    },
    /// A number that is NaN or infinite.
    #[error("line {line}: {word} is not a finite number")]
    NotFinite {
        /// 1-based line number.
        line: usize,
        /// The word.
        word: String,
    },
    /// Neither 12 nor 7 numbers.
    #[error(
        "the file has {0} numbers; a relative pose is 12 (R row by row, then t) or 7 (tx ty tz qx qy qz qw)"
    )]
    Count(usize),
    /// Twelve numbers whose first nine are no rotation.
    #[error(
        "R is not a rotation: R^T R differs from the identity by {deviation:.2e} and det R = {determinant:.4} (a rotation has 0 and 1)"
    )]
    NotARotation {
        /// The largest entry of `RᵀR − I`.
        deviation: f64,
        /// `det R`.
        determinant: f64,
    },
    /// A quaternion of length zero.
    #[error("the quaternion (qx qy qz qw) has length zero")]
    ZeroQuaternion,
    /// `t = 0`: no direction to score.
    #[error("t is zero: a relative pose's translation needs a direction")]
    ZeroTranslation,
}

/// A relative pose read from a file, with what the reader had to say.
#[derive(Clone, Debug, PartialEq)]
pub struct RelativePoseFile {
    /// `R` and `t`.
    pub pose: RelativePose,
    /// Things the reader assumed (a quaternion normalised).
    pub notices: Vec<String>,
}

/// Reads a relative pose (see the module's documentation for the layouts).
pub fn read_relative_pose(bytes: &[u8]) -> Result<RelativePoseFile, RelativePoseFileError> {
    check_size(bytes.len() as u64).map_err(|e| RelativePoseFileError::File(e.to_string()))?;
    let text = std::str::from_utf8(bytes).map_err(|_| {
        RelativePoseFileError::File(
            "this is not a text file; a relative pose is 12 or 7 numbers in text".to_owned(),
        )
    })?;
    let numbers = numbers(text)?;
    let mut notices = Vec::new();
    let (rotation, translation) = match numbers.as_slice() {
        [r @ .., tx, ty, tz] if r.len() == 9 => {
            let rotation = Matrix3::from_row_slice(r);
            let deviation = (rotation.transpose() * rotation - Matrix3::identity()).amax();
            let determinant = rotation.determinant();
            if deviation > ROTATION_TOLERANCE || (determinant - 1.0).abs() > ROTATION_TOLERANCE {
                return Err(RelativePoseFileError::NotARotation {
                    deviation,
                    determinant,
                });
            }
            (rotation, Vector3::new(*tx, *ty, *tz))
        }
        [tx, ty, tz, qx, qy, qz, qw] => {
            let q = Quaternion::new(*qw, *qx, *qy, *qz);
            let norm = q.norm();
            if !(norm > 1e-12) {
                return Err(RelativePoseFileError::ZeroQuaternion);
            }
            if (norm - 1.0).abs() > 1e-6 {
                notices.push(format!(
                    "the quaternion's length is {norm:.6}; it was normalised"
                ));
            }
            (
                UnitQuaternion::from_quaternion(q)
                    .to_rotation_matrix()
                    .into_inner(),
                Vector3::new(*tx, *ty, *tz),
            )
        }
        other => return Err(RelativePoseFileError::Count(other.len())),
    };
    if !(translation.norm() > 0.0) {
        return Err(RelativePoseFileError::ZeroTranslation);
    }
    Ok(RelativePoseFile {
        pose: RelativePose {
            rotation,
            translation,
        },
        notices,
    })
}

/// Every number of the file, in order; `#` comments and empty lines skipped.
fn numbers(text: &str) -> Result<Vec<f64>, RelativePoseFileError> {
    let mut all = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let content = line.split('#').next().unwrap_or("");
        for word in content
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|w| !w.is_empty())
        {
            let value: f64 = word
                .parse()
                .map_err(|_| RelativePoseFileError::NotANumber {
                    line: k + 1,
                    word: word.chars().take(40).collect(),
                })?;
            if !value.is_finite() {
                return Err(RelativePoseFileError::NotFinite {
                    line: k + 1,
                    word: word.to_owned(),
                });
            }
            all.push(value);
            // More than a relative pose holds: stop reading a large file early.
            if all.len() > 12 {
                return Err(RelativePoseFileError::Count(all.len()));
            }
        }
    }
    Ok(all)
}

/// Whether a file looks like a relative pose rather than a trajectory: text of
/// exactly 12 or 7 numbers.
pub fn is_relative_pose(bytes: &[u8]) -> bool {
    bytes.len() < 4096
        && std::str::from_utf8(bytes)
            .ok()
            .and_then(|t| numbers(t).ok())
            .is_some_and(|n| n.len() == 12 || n.len() == 7)
}

/// Writes a relative pose in the 12-number layout, `R` row by row on three
/// lines and `t` on the fourth, with a comment saying which is which.
pub fn write_relative_pose(pose: &RelativePose) -> String {
    let mut out = String::from(
        "# A relative pose of two views: X_b = R X_a + t. R row by row, then t (its direction).\n",
    );
    for row in 0..3 {
        let _ = writeln!(
            out,
            "{:.17} {:.17} {:.17}",
            pose.rotation[(row, 0)],
            pose.rotation[(row, 1)],
            pose.rotation[(row, 2)]
        );
    }
    let t = &pose.translation;
    let _ = writeln!(out, "{:.17} {:.17} {:.17}", t.x, t.y, t.z);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn pose() -> RelativePose {
        RelativePose {
            rotation: Rotation3::from_euler_angles(0.1, -0.2, 0.3).into_inner(),
            translation: Vector3::new(0.2, -0.1, 1.0),
        }
    }

    #[test]
    fn twelve_numbers_round_trip_to_the_bit() {
        let p = pose();
        let back = read_relative_pose(write_relative_pose(&p).as_bytes()).unwrap();
        assert_eq!(back.pose, p);
        assert!(back.notices.is_empty());
        assert!(is_relative_pose(write_relative_pose(&p).as_bytes()));
    }

    #[test]
    fn a_quaternion_gives_the_same_rotation() {
        let p = pose();
        let q = UnitQuaternion::from_matrix(&p.rotation);
        let text = format!(
            "# t then q\n{}, {}, {}, {}, {}, {}, {}\n",
            p.translation.x, p.translation.y, p.translation.z, q.i, q.j, q.k, q.w
        );
        let back = read_relative_pose(text.as_bytes()).unwrap();
        assert!((back.pose.rotation - p.rotation).amax() < 1e-12);
        assert_eq!(back.pose.translation, p.translation);
        // A quaternion written with few digits is normalised, and said so.
        let short = format!("0 0 1 {:.3} {:.3} {:.3} {:.3}", q.i, q.j, q.k, q.w);
        let back = read_relative_pose(short.as_bytes()).unwrap();
        assert_eq!(back.notices.len(), 1, "{:?}", back.notices);
        assert!((back.pose.rotation - p.rotation).amax() < 2e-3);
    }

    #[test]
    fn bad_files_are_refused_with_a_reason() {
        let said = |text: &str| read_relative_pose(text.as_bytes()).unwrap_err().to_string();
        assert!(said("1 0 0 0 1 0 0 0 1 0 0").contains("11 numbers"));
        assert!(said("1 0 0\n0 1 0\n0 0 x\n0 0 1").starts_with("line 3: 'x'"));
        assert!(said("1 0 0 0 1 0 0 0 1 NaN 0 1").contains("not a finite number"));
        assert!(said("1 0 0 0 1 0 0 0 -1 0 0 1").contains("det R = -1.0000"));
        assert!(said("2 0 0 0 1 0 0 0 1 0 0 1").contains("not a rotation"));
        assert!(said("1 0 0 0 1 0 0 0 1 0 0 0").contains("t is zero"));
        assert!(said("0 0 1 0 0 0 0").contains("length zero"));
        assert!(said(&"1 ".repeat(40)).contains("13 numbers"));
        assert!(read_relative_pose(b"PK\x03\x04\xff\xfe").is_err());
        // A TUM trajectory's line has eight numbers: not a relative pose.
        assert!(!is_relative_pose(b"0.0 1 2 0 0 0 0 1\n"));
    }
}
