//! Trajectory and landmark files, the common language between SLAM Lab and a
//! student's own estimator.
//!
//! * **TUM** (`t x y z qx qy qz qw`, one pose a line, `#` comments): the format of
//!   the TUM RGB-D benchmark and of evo. A planar pose is written with `z = 0` and
//!   the quaternion of a rotation about z, `(0, 0, sin θ/2, cos θ/2)`; a pose read
//!   back keeps x, y and the yaw (`atan2(2(w z + x y), 1 − 2(y² + z²))`), and a
//!   notice says when a file has height or roll and pitch that the plane drops.
//! * **CSV** (`t,x,y,theta`, optionally followed by the upper triangle of the 3x3
//!   pose covariance `c_xx,c_xy,c_xtheta,c_yy,c_ytheta,c_thetatheta`, in m², m·rad
//!   and rad²): SLAM Lab's own, for an estimator with a covariance. A header line is
//!   written and, when present, read by its column names.
//! * **Landmark CSV** (`id,x,y`, optionally `c_xx,c_xy,c_yy`).
//!
//! Numbers are written with Rust's shortest round-trip formatting, so a file read
//! back gives the same bits. Every refusal names the line and what is wrong with
//! it; the readers never panic (they are in the fuzz harness) and refuse a file
//! over [`MAX_TRAJECTORY_BYTES`] before reading it.

use crate::metrics::Trajectory;
use nalgebra::{Matrix2, Matrix3};
use slamlab_core::Pose2;
use slamlab_core::math;
use std::fmt::Write as _;
use thiserror::Error;

/// The largest trajectory or landmark file the readers accept, in bytes (64 MiB:
/// a million poses in TUM format). Larger input is refused from its size.
pub const MAX_TRAJECTORY_BYTES: u64 = 64 * 1024 * 1024;

/// The most poses a file may hold.
pub const MAX_POSES: usize = 2_000_000;

/// Why a trajectory or landmark file was refused.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum TrajectoryFileError {
    /// Larger than [`MAX_TRAJECTORY_BYTES`].
    #[error(
        "the file has {size} bytes, more than the {limit} bytes SLAM Lab reads as a trajectory"
    )]
    TooLarge {
        /// Its size.
        size: u64,
        /// The limit.
        limit: u64,
    },
    /// Not text: a zip, gzip or other binary file where text belongs.
    #[error("this is not a text file but {0}; a trajectory is a TUM or CSV text file")]
    NotText(&'static str),
    /// No pose (or landmark) in it.
    #[error("the file holds no {0}")]
    Empty(&'static str),
    /// A malformed line.
    #[error("line {line}: {message}")]
    Line {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

/// A trajectory file's format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TrajectoryFormat {
    /// `t x y z qx qy qz qw`.
    Tum,
    /// `t,x,y,theta[,c_xx,c_xy,c_xtheta,c_yy,c_ytheta,c_thetatheta]`.
    Csv,
}

/// A trajectory read from a file, with what the reader had to say about it.
#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryFile {
    /// The poses (and covariances, from a CSV that has them).
    pub trajectory: Trajectory,
    /// The format it was read as.
    pub format: TrajectoryFormat,
    /// What the reader assumed or dropped ("z up to 0.31 m dropped").
    pub notices: Vec<String>,
}

/// One landmark estimate: its id, position and (when given) 2x2 covariance.
#[derive(Clone, Debug, PartialEq)]
pub struct LandmarkRow {
    /// The landmark's id.
    pub id: u64,
    /// Position, metres.
    pub x: f64,
    /// Position, metres.
    pub y: f64,
    /// Its covariance, m².
    pub covariance: Option<Matrix2<f64>>,
}

/// Refuses a file larger than [`MAX_TRAJECTORY_BYTES`] before it is read.
pub fn check_size(bytes: u64) -> Result<(), TrajectoryFileError> {
    if bytes > MAX_TRAJECTORY_BYTES {
        return Err(TrajectoryFileError::TooLarge {
            size: bytes,
            limit: MAX_TRAJECTORY_BYTES,
        });
    }
    Ok(())
}

/// What a binary file is, from its first bytes; `None` for text.
fn binary_kind(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06") {
        Some("a zip archive")
    } else if bytes.starts_with(&[0x1f, 0x8b]) {
        Some("a gzip file")
    } else if bytes.starts_with(b"BZh") {
        Some("a bzip2 file")
    } else if bytes.starts_with(b"\x89PNG") {
        Some("a PNG image")
    } else if bytes.iter().take(4096).any(|&b| b == 0) {
        Some("binary data")
    } else {
        None
    }
}

/// The file's text, or why it is not text.
fn text_of(bytes: &[u8]) -> Result<&str, TrajectoryFileError> {
    check_size(bytes.len() as u64)?;
    if let Some(kind) = binary_kind(bytes) {
        return Err(TrajectoryFileError::NotText(kind));
    }
    std::str::from_utf8(bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1;
        TrajectoryFileError::Line {
            line,
            message: "not UTF-8 text".to_owned(),
        }
    })
}

fn line_error(line: usize, message: impl Into<String>) -> TrajectoryFileError {
    TrajectoryFileError::Line {
        line,
        message: message.into(),
    }
}

/// The lines that carry data: 1-based number and text, comments and blank lines
/// skipped.
fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(k, l)| (k + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#') && !l.starts_with("//"))
}

/// A finite number, or a message naming the column.
fn number(field: &str, column: &str, line: usize) -> Result<f64, TrajectoryFileError> {
    match field.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(line_error(
            line,
            format!("{column} is {field}, not a finite number"),
        )),
        Err(_) => Err(line_error(
            line,
            format!("{column} '{field}' is not a number"),
        )),
    }
}

/// Guesses a trajectory file's format from its first data line: commas make a
/// CSV, eight numbers separated by spaces a TUM file.
pub fn detect_format(bytes: &[u8]) -> Result<TrajectoryFormat, TrajectoryFileError> {
    let text = text_of(bytes)?;
    let Some((line, first)) = data_lines(text).next() else {
        return Err(TrajectoryFileError::Empty("pose"));
    };
    if first.contains(',') {
        return Ok(TrajectoryFormat::Csv);
    }
    let fields = first.split_whitespace().count();
    if fields == 8 {
        Ok(TrajectoryFormat::Tum)
    } else {
        Err(line_error(
            line,
            format!(
                "{fields} fields separated by spaces: a TUM trajectory has 8 (t x y z qx qy qz qw), a CSV trajectory separates t,x,y,theta by commas"
            ),
        ))
    }
}

/// Reads a TUM or CSV trajectory, whichever the file is.
pub fn read_trajectory(name: &str, bytes: &[u8]) -> Result<TrajectoryFile, TrajectoryFileError> {
    match detect_format(bytes)? {
        TrajectoryFormat::Tum => read_tum(name, bytes),
        TrajectoryFormat::Csv => read_csv(bytes),
    }
}

/// Checks that time only goes forward: every stamp after the one before.
fn check_time(stamps: &[f64], line: usize, t: f64) -> Result<(), TrajectoryFileError> {
    if let Some(&previous) = stamps.last() {
        if t == previous {
            return Err(line_error(
                line,
                format!("the time {t} s repeats the line before's (every pose needs its own time)"),
            ));
        }
        if t < previous {
            return Err(line_error(
                line,
                format!(
                    "the time {t} s is before the line before's {previous} s (poses must be in time order)"
                ),
            ));
        }
    }
    Ok(())
}

/// Reads a TUM trajectory (`t x y z qx qy qz qw`).
pub fn read_tum(name: &str, bytes: &[u8]) -> Result<TrajectoryFile, TrajectoryFileError> {
    let text = text_of(bytes)?;
    let mut stamps = Vec::new();
    let mut poses = Vec::new();
    let (mut max_z, mut max_tilt) = (0.0_f64, 0.0_f64);
    let mut renormalized = 0usize;
    for (line, content) in data_lines(text) {
        let fields: Vec<&str> = content.split_whitespace().collect();
        if fields.len() != 8 {
            return Err(line_error(
                line,
                format!(
                    "{} fields; a TUM pose has 8: t x y z qx qy qz qw",
                    fields.len()
                ),
            ));
        }
        const COLUMNS: [&str; 8] = ["t", "x", "y", "z", "qx", "qy", "qz", "qw"];
        let mut v = [0.0; 8];
        for (k, field) in fields.iter().enumerate() {
            v[k] = number(field, COLUMNS[k], line)?;
        }
        let [t, x, y, z, qx, qy, qz, qw] = v;
        check_time(&stamps, line, t)?;
        let norm = (qx * qx + qy * qy + qz * qz + qw * qw).sqrt();
        if !(norm > 1e-9) {
            return Err(line_error(line, "the quaternion is zero"));
        }
        if (norm - 1.0).abs() > 1e-6 {
            renormalized += 1;
        }
        let (qx, qy, qz, qw) = (qx / norm, qy / norm, qz / norm, qw / norm);
        let theta = math::atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz));
        // How far the rotation's axis leaves the vertical: sin of the tilt.
        max_tilt = max_tilt.max(2.0 * (qx * qx + qy * qy).sqrt() * (qz * qz + qw * qw).sqrt());
        max_z = max_z.max(z.abs());
        if stamps.len() >= MAX_POSES {
            return Err(line_error(line, format!("more than {MAX_POSES} poses")));
        }
        stamps.push(t);
        poses.push(Pose2::new(x, y, theta));
    }
    if poses.is_empty() {
        return Err(TrajectoryFileError::Empty("pose"));
    }
    let mut notices = Vec::new();
    if max_z > 1e-6 {
        notices.push(format!(
            "{name}: heights up to {max_z:.3} m dropped (SLAM Lab's poses are planar)"
        ));
    }
    if max_tilt > 1e-6 {
        notices.push(format!(
            "{name}: roll and pitch up to {:.2}° dropped; the yaw is kept",
            math::asin(max_tilt.min(1.0)).to_degrees()
        ));
    }
    if renormalized > 0 {
        notices.push(format!(
            "{name}: {renormalized} quaternions were not of unit length and were normalized"
        ));
    }
    Ok(TrajectoryFile {
        trajectory: Trajectory::new(stamps, poses),
        format: TrajectoryFormat::Tum,
        notices,
    })
}

/// Writes a trajectory in TUM format, planar: `z = 0`, a rotation about z.
pub fn write_tum(trajectory: &Trajectory) -> String {
    let mut out = String::with_capacity(trajectory.len() * 64);
    out.push_str("# timestamp x y z qx qy qz qw\n");
    for (t, p) in trajectory.stamps().iter().zip(trajectory.poses()) {
        let (s, c) = math::sin_cos(0.5 * p.theta);
        let _ = writeln!(out, "{t} {} {} 0 0 0 {s} {c}", p.x, p.y);
    }
    out
}

/// The CSV trajectory's column names, in order (the last six only with a covariance).
pub const CSV_COLUMNS: [&str; 10] = [
    "t",
    "x",
    "y",
    "theta",
    "c_xx",
    "c_xy",
    "c_xtheta",
    "c_yy",
    "c_ytheta",
    "c_thetatheta",
];

/// Other names a CSV header may give a column (`time`, `yaw`, ...).
fn csv_column_index(name: &str) -> Option<usize> {
    let name = name.trim().trim_matches('"').to_ascii_lowercase();
    let canonical = match name.as_str() {
        "time" | "timestamp" | "stamp" | "t_s" | "time_s" => "t",
        "x_m" => "x",
        "y_m" => "y",
        "yaw" | "heading" | "th" | "theta_rad" | "yaw_rad" => "theta",
        other => other,
    };
    CSV_COLUMNS.iter().position(|c| *c == canonical)
}

/// Reads a CSV trajectory: 4 columns, or 10 with the covariance's upper triangle;
/// with a header line, by its column names (in any order).
pub fn read_csv(bytes: &[u8]) -> Result<TrajectoryFile, TrajectoryFileError> {
    let text = text_of(bytes)?;
    let mut lines = data_lines(text).peekable();
    // A header: the first line's first field is not a number.
    let mut order: Option<Vec<usize>> = None;
    if let Some(&(line, first)) = lines.peek() {
        let head = first.split(',').next().unwrap_or("").trim();
        if head.parse::<f64>().is_err() {
            let mut columns = Vec::new();
            for field in first.split(',') {
                let Some(k) = csv_column_index(field) else {
                    return Err(line_error(
                        line,
                        format!(
                            "unknown column '{}' in the header; the columns are {}",
                            field.trim(),
                            CSV_COLUMNS.join(",")
                        ),
                    ));
                };
                if columns.contains(&k) {
                    return Err(line_error(
                        line,
                        format!("the column '{}' appears twice", field.trim()),
                    ));
                }
                columns.push(k);
            }
            let has = |k: usize| columns.contains(&k);
            if !(0..4).all(has) {
                return Err(line_error(
                    line,
                    "the header needs the columns t, x, y and theta",
                ));
            }
            let cov = (4..10).filter(|&k| has(k)).count();
            if cov != 0 && cov != 6 {
                return Err(line_error(
                    line,
                    format!("the header has {cov} of the 6 covariance columns; give all 6 or none"),
                ));
            }
            order = Some(columns);
            lines.next();
        }
    }
    let mut stamps = Vec::new();
    let mut poses = Vec::new();
    let mut covariances: Vec<Matrix3<f64>> = Vec::new();
    let mut width = order.as_ref().map(Vec::len);
    for (line, content) in lines {
        let fields: Vec<&str> = content.split(',').collect();
        let expected = *width.get_or_insert(fields.len());
        if fields.len() != expected || !(expected == 4 || expected == 10) {
            return Err(line_error(
                line,
                format!(
                    "{} columns; a CSV trajectory has 4 (t,x,y,theta) or 10 (with c_xx,c_xy,c_xtheta,c_yy,c_ytheta,c_thetatheta){}",
                    fields.len(),
                    if fields.len() != expected && (expected == 4 || expected == 10) {
                        format!(", as its first line has {expected}")
                    } else {
                        String::new()
                    }
                ),
            ));
        }
        let mut v = [0.0; 10];
        for (k, field) in fields.iter().enumerate() {
            let column = order.as_ref().map_or(k, |o| o[k]);
            v[column] = number(field, CSV_COLUMNS[column], line)?;
        }
        check_time(&stamps, line, v[0])?;
        if stamps.len() >= MAX_POSES {
            return Err(line_error(line, format!("more than {MAX_POSES} poses")));
        }
        stamps.push(v[0]);
        poses.push(Pose2::new(v[1], v[2], v[3]));
        if expected == 10 {
            let p = Matrix3::new(v[4], v[5], v[6], v[5], v[7], v[8], v[6], v[8], v[9]);
            if !(v[4] >= 0.0 && v[7] >= 0.0 && v[9] >= 0.0) {
                return Err(line_error(
                    line,
                    "a variance (c_xx, c_yy or c_thetatheta) is negative",
                ));
            }
            covariances.push(p);
        }
    }
    if poses.is_empty() {
        return Err(TrajectoryFileError::Empty("pose"));
    }
    let mut trajectory = Trajectory::new(stamps, poses);
    if !covariances.is_empty() {
        trajectory = trajectory.with_covariances(covariances);
    }
    Ok(TrajectoryFile {
        trajectory,
        format: TrajectoryFormat::Csv,
        notices: Vec::new(),
    })
}

/// Writes a trajectory as CSV with a header, with the covariance's upper triangle
/// when the trajectory has covariances.
pub fn write_csv(trajectory: &Trajectory) -> String {
    let covariances = trajectory.covariances();
    let columns = if covariances.is_some() { 10 } else { 4 };
    let mut out = CSV_COLUMNS[..columns].join(",");
    out.push('\n');
    for (k, (t, p)) in trajectory
        .stamps()
        .iter()
        .zip(trajectory.poses())
        .enumerate()
    {
        let _ = write!(out, "{t},{},{},{}", p.x, p.y, p.theta);
        if let Some(c) = covariances.and_then(|c| c.get(k)) {
            let _ = write!(
                out,
                ",{},{},{},{},{},{}",
                c[(0, 0)],
                c[(0, 1)],
                c[(0, 2)],
                c[(1, 1)],
                c[(1, 2)],
                c[(2, 2)]
            );
        }
        out.push('\n');
    }
    out
}

/// Reads a landmark CSV: `id,x,y` or `id,x,y,c_xx,c_xy,c_yy`, with or without
/// a header line.
pub fn read_landmarks(bytes: &[u8]) -> Result<Vec<LandmarkRow>, TrajectoryFileError> {
    let text = text_of(bytes)?;
    let mut rows: Vec<LandmarkRow> = Vec::new();
    let mut width = None;
    for (line, content) in data_lines(text) {
        let fields: Vec<&str> = content.split(',').map(str::trim).collect();
        if rows.is_empty() && width.is_none() && fields[0].parse::<f64>().is_err() {
            if !fields.first().is_some_and(|f| f.eq_ignore_ascii_case("id")) {
                return Err(line_error(
                    line,
                    "a landmark CSV's header starts with id (id,x,y[,c_xx,c_xy,c_yy])",
                ));
            }
            width = Some(fields.len());
            continue;
        }
        let expected = *width.get_or_insert(fields.len());
        if fields.len() != expected || !(expected == 3 || expected == 6) {
            return Err(line_error(
                line,
                format!(
                    "{} columns; a landmark row has 3 (id,x,y) or 6 (id,x,y,c_xx,c_xy,c_yy)",
                    fields.len()
                ),
            ));
        }
        let id = fields[0].parse::<u64>().map_err(|_| {
            line_error(
                line,
                format!("the id '{}' is not a whole number", fields[0]),
            )
        })?;
        if rows.iter().any(|r| r.id == id) {
            return Err(line_error(
                line,
                format!("the landmark id {id} appears twice"),
            ));
        }
        if rows.len() >= MAX_POSES {
            return Err(line_error(line, format!("more than {MAX_POSES} landmarks")));
        }
        let x = number(fields[1], "x", line)?;
        let y = number(fields[2], "y", line)?;
        let covariance = if expected == 6 {
            let xx = number(fields[3], "c_xx", line)?;
            let xy = number(fields[4], "c_xy", line)?;
            let yy = number(fields[5], "c_yy", line)?;
            if !(xx >= 0.0 && yy >= 0.0) {
                return Err(line_error(line, "a variance (c_xx or c_yy) is negative"));
            }
            Some(Matrix2::new(xx, xy, xy, yy))
        } else {
            None
        };
        rows.push(LandmarkRow {
            id,
            x,
            y,
            covariance,
        });
    }
    if rows.is_empty() {
        return Err(TrajectoryFileError::Empty("landmark"));
    }
    Ok(rows)
}

/// Writes landmarks as CSV with a header; with covariances when every row has one.
pub fn write_landmarks(rows: &[LandmarkRow]) -> String {
    let with_cov = !rows.is_empty() && rows.iter().all(|r| r.covariance.is_some());
    let mut out = String::from(if with_cov {
        "id,x,y,c_xx,c_xy,c_yy\n"
    } else {
        "id,x,y\n"
    });
    for r in rows {
        let _ = write!(out, "{},{},{}", r.id, r.x, r.y);
        if let Some(c) = r.covariance.filter(|_| with_cov) {
            let _ = write!(out, ",{},{},{}", c[(0, 0)], c[(0, 1)], c[(1, 1)]);
        }
        out.push('\n');
    }
    out
}

/// A file name made of `name`: lower case, `[a-z0-9._-]` kept, anything else a
/// dash, never empty.
pub fn file_stem(name: &str) -> String {
    let stem: String = name
        .trim()
        .to_lowercase()
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '_' || c == '-' {
                c
            } else {
                '-'
            }
        })
        .collect();
    let stem = stem.trim_matches(|c| c == '-' || c == '.').to_owned();
    if stem.is_empty() {
        "trajectory".to_owned()
    } else {
        stem
    }
}

/// The files a lesson's trajectories export to: for each, `NAME.tum` and
/// `NAME.csv` (with the covariances when the estimator has them); for each
/// landmark map, `NAME-landmarks.csv`; and a `README.txt` saying what they are.
/// Names that would repeat get a number.
pub fn export_files(
    lesson: &str,
    trajectories: &[crate::metrics::NamedTrajectory],
    landmarks: &[(String, Vec<LandmarkRow>)],
) -> Vec<(String, Vec<u8>)> {
    let mut used: Vec<String> = Vec::new();
    let mut unique = |name: &str| {
        let stem = file_stem(name);
        let mut candidate = stem.clone();
        let mut k = 2;
        while used.contains(&candidate) {
            candidate = format!("{stem}-{k}");
            k += 1;
        }
        used.push(candidate.clone());
        candidate
    };
    let mut files = Vec::new();
    let mut readme = format!(
        "SLAM Lab, lesson {lesson}: the trajectories of this run.\n\n\
         NAME.tum  t x y z qx qy qz qw (TUM format, as evo reads it; z = 0, a rotation about z)\n\
         NAME.csv  t,x,y,theta and, for an estimator with a covariance, the upper triangle of the 3x3\n          \
         covariance of (x, y, theta): c_xx,c_xy,c_xtheta,c_yy,c_ytheta,c_thetatheta (m^2, m rad, rad^2)\n\
         NAME-landmarks.csv  id,x,y and, with covariances, c_xx,c_xy,c_yy\n\
         Times in seconds from the run's start; metres and radians; x forward, y left (ROS REP-103).\n\
         Score one against another: slamlab evaluate --estimate NAME.tum --reference truth.tum\n\n"
    );
    for t in trajectories {
        let stem = unique(&t.name);
        let role = match t.role {
            crate::metrics::TrajectoryRole::Truth => "the true path",
            crate::metrics::TrajectoryRole::Estimate => "an estimate",
            crate::metrics::TrajectoryRole::Odometry => "odometry alone (dead reckoning)",
        };
        let _ = writeln!(
            readme,
            "{stem}: {role}, {} poses{}",
            t.trajectory.len(),
            if t.trajectory.covariances().is_some() {
                ", with covariances"
            } else {
                ""
            }
        );
        files.push((format!("{stem}.tum"), write_tum(&t.trajectory).into_bytes()));
        files.push((format!("{stem}.csv"), write_csv(&t.trajectory).into_bytes()));
    }
    for (name, rows) in landmarks {
        let stem = unique(&format!("{name}-landmarks"));
        let _ = writeln!(
            readme,
            "{stem}: {}'s landmarks, {} of them",
            name,
            rows.len()
        );
        files.push((format!("{stem}.csv"), write_landmarks(rows).into_bytes()));
    }
    files.push(("README.txt".to_owned(), readme.into_bytes()));
    files
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Trajectory {
        let stamps = vec![0.0, 0.1, 0.2, 0.30000000000000004, 1e9 + 0.25];
        let poses = vec![
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(0.1, -0.02, 0.3),
            Pose2::new(1.0 / 3.0, 2.5e-7, 3.1),
            Pose2::new(-12.75, 4.0, -3.1),
            Pose2::new(1e6, -1e-300, -0.5),
        ];
        Trajectory::new(stamps, poses)
    }

    #[test]
    fn tum_files_read_back_to_the_same_poses() {
        let t = sample();
        let text = write_tum(&t);
        let back = read_trajectory("a.txt", text.as_bytes()).unwrap();
        assert_eq!(back.format, TrajectoryFormat::Tum);
        assert!(back.notices.is_empty(), "{:?}", back.notices);
        assert_eq!(back.trajectory.stamps(), t.stamps());
        for (a, b) in back.trajectory.poses().iter().zip(t.poses()) {
            assert_eq!((a.x, a.y), (b.x, b.y));
            assert!(
                slamlab_core::wrap_angle(a.theta - b.theta).abs() < 1e-9,
                "{a:?} {b:?}"
            );
        }
    }

    #[test]
    fn csv_files_with_covariances_read_back_to_the_same_bits() {
        let covariances: Vec<Matrix3<f64>> = (0..5)
            .map(|k| {
                let a = 0.01 * (k as f64 + 1.0) / 3.0;
                Matrix3::new(a, 1e-5, -2e-6, 1e-5, 2.0 * a, 3e-7, -2e-6, 3e-7, a / 7.0)
            })
            .collect();
        let t = sample().with_covariances(covariances.clone());
        let text = write_csv(&t);
        assert!(text.starts_with("t,x,y,theta,c_xx,c_xy,c_xtheta,c_yy,c_ytheta,c_thetatheta\n"));
        let back = read_trajectory("a.csv", text.as_bytes()).unwrap();
        assert_eq!(back.format, TrajectoryFormat::Csv);
        assert_eq!(back.trajectory, t);
        assert_eq!(back.trajectory.covariances(), Some(covariances.as_slice()));
        // Without covariances, and without a header.
        let plain = "0,1,2,0.5\n1,1.5,2,0.6\n";
        let back = read_trajectory("b.csv", plain.as_bytes()).unwrap();
        assert_eq!(back.trajectory.len(), 2);
        assert!(back.trajectory.covariances().is_none());
        // A header in another order, with other names.
        let named = "yaw,time,y,x\n0.5,0,2,1\n";
        let back = read_trajectory("c.csv", named.as_bytes()).unwrap();
        assert_eq!(back.trajectory.poses()[0], Pose2::new(1.0, 2.0, 0.5));
    }

    #[test]
    fn tilted_and_raised_poses_keep_their_yaw_with_a_notice() {
        // Yaw 0.7 about z after a roll of 0.2 about x: q = q_z(0.7) q_x(0.2).
        let (sz, cz) = math::sin_cos(0.35);
        let (sx, cx) = math::sin_cos(0.1);
        let (qw, qx, qy, qz) = (cz * cx, cz * sx, sz * sx, sz * cx);
        let text = format!("1.0 2 3 0.5 {qx} {qy} {qz} {qw}\n");
        let back = read_tum("lifted.txt", text.as_bytes()).unwrap();
        assert!((back.trajectory.poses()[0].theta - 0.7).abs() < 1e-12);
        assert_eq!(back.notices.len(), 2, "{:?}", back.notices);
        assert!(back.notices[0].contains("0.500 m"));
        assert!(back.notices[1].contains("11.46°"), "{}", back.notices[1]);
    }

    #[test]
    fn landmarks_read_back_to_the_same_bits() {
        let rows = vec![
            LandmarkRow {
                id: 3,
                x: 1.0 / 3.0,
                y: -2.0,
                covariance: Some(Matrix2::new(0.01, 1e-4, 1e-4, 0.02)),
            },
            LandmarkRow {
                id: 10,
                x: 5.5,
                y: 1e-9,
                covariance: Some(Matrix2::new(0.5, 0.0, 0.0, 0.25)),
            },
        ];
        let back = read_landmarks(write_landmarks(&rows).as_bytes()).unwrap();
        assert_eq!(back, rows);
        let plain = read_landmarks(b"1,2,3\n2,4,5\n").unwrap();
        assert_eq!(plain[1].id, 2);
        assert!(plain[1].covariance.is_none());
    }

    #[test]
    fn bad_files_are_refused_with_the_line() {
        let refuse = |text: &[u8]| read_trajectory("bad", text).unwrap_err().to_string();
        assert_eq!(
            refuse(b"0 1 2 0 0 0 0 1\n1 1 2 0 0 0 1\n"),
            "line 2: 7 fields; a TUM pose has 8: t x y z qx qy qz qw"
        );
        assert_eq!(
            refuse(b"0,1,2,0\n1,1,NaN,0\n"),
            "line 2: y is NaN, not a finite number"
        );
        assert_eq!(
            refuse(b"0,1,2,0\n0,1,2,0\n"),
            "line 2: the time 0 s repeats the line before's (every pose needs its own time)"
        );
        assert_eq!(
            refuse(b"# a comment\n1,1,2,0\n0.5,1,2,0\n"),
            "line 3: the time 0.5 s is before the line before's 1 s (poses must be in time order)"
        );
        assert!(refuse(b"0,1,2,0\n1,1,2,0,5\n").starts_with("line 2: 5 columns"));
        assert_eq!(
            refuse(b"PK\x03\x04rest of a zip"),
            "this is not a text file but a zip archive; a trajectory is a TUM or CSV text file"
        );
        assert_eq!(refuse(b"# nothing\n\n"), "the file holds no pose");
        assert!(refuse(b"t,x,y,speed\n").contains("unknown column 'speed'"));
        assert!(refuse(b"0 1 2 0 0 0 0 0\n").contains("quaternion is zero"));
        assert!(check_size(MAX_TRAJECTORY_BYTES + 1).is_err());
        assert!(
            check_size(2 << 30)
                .unwrap_err()
                .to_string()
                .contains("2147483648 bytes")
        );
        assert!(
            read_landmarks(b"1,2,3\n1,4,5\n")
                .unwrap_err()
                .to_string()
                .contains("appears twice")
        );
    }
}
