//! Pose-graph files: g2o 2D (read and write), TORO 2D (read) and the iSAM-style
//! `ODOMETRY`/`LANDMARK` format of the Victoria Park data set (read).
//!
//! Parsers take the file's text, so the browser can hand over the bytes of a
//! dropped file; the CLI does the reading. Every refusal names the line and what is
//! wrong with it.
//!
//! * g2o: `VERTEX_SE2 id x y θ`, `VERTEX_XY id x y`,
//!   `EDGE_SE2 i j dx dy dθ I11 I12 I13 I22 I23 I33` (upper triangle of the
//!   information matrix, row by row), `EDGE_SE2_XY i j x y I11 I12 I22`,
//!   `EDGE_PRIOR_SE2 i x y θ I11 … I33`, `FIX id…`, `#` comments.
//! * TORO: `VERTEX2 id x y θ`, `EDGE2 i j dx dy dθ Ixx Ixy Iyy Iθθ Ixθ Iyθ`
//!   (information in TORO's order).
//! * iSAM: `ODOMETRY i j dx dy dθ c11 c12 c13 c22 c23 c33` (a covariance) and
//!   `LANDMARK pose lm lx ly v1 v2 v3` (the landmark in the robot frame). There are
//!   no vertex lines: the initial poses chain the odometry from the identity, and
//!   each landmark starts where its first sighting puts it.

use nalgebra::{Matrix2, Matrix3, Vector2};
use slamlab_core::Pose2;
use slamlab_core::graph::{EdgeKind, PoseGraph, VertexId, VertexState};
use slamlab_core::math;
use std::collections::HashMap;
use std::fmt::Write as _;
use thiserror::Error;

/// The largest file the readers accept, in bytes (32 MiB; the largest standard 2D
/// data sets are under 5 MB). Larger input is refused before it is parsed.
pub const MAX_FILE_BYTES: usize = 32 * 1024 * 1024;

/// A pose-graph file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GraphFormat {
    /// g2o 2D.
    G2o,
    /// TORO 2D (`VERTEX2`/`EDGE2`).
    Toro,
    /// iSAM-style `ODOMETRY`/`LANDMARK` (Victoria Park).
    Isam,
}

impl GraphFormat {
    /// Guesses the format from a file name's extension: `.g2o`, `.graph`/`.toro`.
    pub fn from_extension(path: &str) -> Option<Self> {
        let lower = path.to_ascii_lowercase();
        if lower.ends_with(".g2o") {
            Some(GraphFormat::G2o)
        } else if lower.ends_with(".graph") || lower.ends_with(".toro") {
            Some(GraphFormat::Toro)
        } else {
            None
        }
    }
}

/// Why a file was refused.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum GraphFileError {
    /// Larger than [`MAX_FILE_BYTES`].
    #[error("the file has {size} bytes, more than the {limit} bytes SLAM Lab reads")]
    TooLarge {
        /// Its size.
        size: usize,
        /// The limit.
        limit: usize,
    },
    /// A malformed or inconsistent entry.
    #[error("line {line}: {message}")]
    Line {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// Not one of the formats.
    #[error(
        "this is not a pose-graph file SLAM Lab reads: no line starts with VERTEX_SE2, VERTEX_XY, EDGE_SE2 (g2o), VERTEX2, EDGE2 (TORO) or ODOMETRY, LANDMARK (iSAM){}",
        .first_line.as_ref().map(|(n, t)| format!("; line {n} starts with '{t}'")).unwrap_or_default()
    )]
    UnknownFormat {
        /// The first non-comment line and its first word.
        first_line: Option<(usize, String)>,
    },
    /// The graph is too small to optimise.
    #[error("{0}")]
    TooSmall(String),
    /// The graph cannot be written in the requested format.
    #[error("{0}")]
    Unwritable(String),
}

fn line_error(line: usize, message: impl Into<String>) -> GraphFileError {
    GraphFileError::Line {
        line,
        message: message.into(),
    }
}

/// The numbers after a line's tag.
struct Fields<'a> {
    line: usize,
    tag: &'a str,
    words: Vec<&'a str>,
}

impl Fields<'_> {
    fn expect_len(&self, n: usize, layout: &str) -> Result<(), GraphFileError> {
        if self.words.len() != n {
            return Err(line_error(
                self.line,
                format!(
                    "{} needs {n} numbers ({layout}), found {}",
                    self.tag,
                    self.words.len()
                ),
            ));
        }
        Ok(())
    }

    fn id(&self, k: usize) -> Result<VertexId, GraphFileError> {
        self.words[k].parse::<VertexId>().map_err(|_| {
            line_error(
                self.line,
                format!(
                    "{}: '{}' is not a vertex id (a whole number ≥ 0)",
                    self.tag, self.words[k]
                ),
            )
        })
    }

    fn num(&self, k: usize) -> Result<f64, GraphFileError> {
        let v = self.words[k].parse::<f64>().map_err(|_| {
            line_error(
                self.line,
                format!("{}: '{}' is not a number", self.tag, self.words[k]),
            )
        })?;
        if !v.is_finite() {
            return Err(line_error(
                self.line,
                format!("{}: '{}' is not a finite number", self.tag, self.words[k]),
            ));
        }
        Ok(v)
    }

    fn nums(&self, from: usize, count: usize) -> Result<Vec<f64>, GraphFileError> {
        (from..from + count).map(|k| self.num(k)).collect()
    }

    /// Adds the pose vertex of a `VERTEX_SE2`/`VERTEX2` line: `id x y θ`.
    fn add_pose_to(&self, graph: &mut PoseGraph) -> Result<(), GraphFileError> {
        self.expect_len(4, "id x y theta")?;
        let v = self.nums(1, 3)?;
        graph
            .add_pose(self.id(0)?, file_pose(v[0], v[1], v[2]))
            .map(|_| ())
            .map_err(|e| line_error(self.line, e.to_string()))
    }

    /// The pose-pose edge of an `EDGE_SE2`/`EDGE2` line: `i j dx dy dθ` and six
    /// numbers of information, in the order `information` reads (`layout`
    /// names all eleven fields for the message of a short line).
    fn between(
        &self,
        layout: &str,
        information: impl Fn(&[f64]) -> Matrix3<f64>,
    ) -> Result<(usize, PendingEdge), GraphFileError> {
        self.expect_len(11, layout)?;
        let v = self.nums(2, 9)?;
        let z = file_pose(v[0], v[1], v[2]);
        let edge = PendingEdge::Between(self.id(0)?, self.id(1)?, z, information(&v[3..]));
        Ok((self.line, edge))
    }

    /// The refusal of a tag the format does not have (`format` as "a g2o 2D").
    fn unknown_tag(&self, format: &str, known: &str) -> GraphFileError {
        line_error(
            self.line,
            format!(
                "'{}' is not {format} entry SLAM Lab reads ({known})",
                self.tag
            ),
        )
    }
}

/// Splits the text into (line number, tag, numbers), skipping blank lines and
/// `#` comments.
fn lines(text: &str) -> impl Iterator<Item = Fields<'_>> {
    text.lines().enumerate().filter_map(|(i, raw)| {
        let content = raw.split('#').next().unwrap_or("").trim();
        let mut words = content.split_whitespace();
        let tag = words.next()?;
        Some(Fields {
            line: i + 1,
            tag,
            words: words.collect(),
        })
    })
}

/// Detects the format from the first tag in the text.
pub fn detect_format(text: &str) -> Result<GraphFormat, GraphFileError> {
    let Some(f) = lines(text).next() else {
        return Err(GraphFileError::UnknownFormat { first_line: None });
    };
    match f.tag {
        "VERTEX_SE2" | "VERTEX_XY" | "EDGE_SE2" | "EDGE_SE2_XY" | "FIX" | "EDGE_PRIOR_SE2" => {
            Ok(GraphFormat::G2o)
        }
        "VERTEX2" | "EDGE2" => Ok(GraphFormat::Toro),
        "ODOMETRY" | "LANDMARK" => Ok(GraphFormat::Isam),
        other => Err(GraphFileError::UnknownFormat {
            first_line: Some((f.line, other.chars().take(40).collect())),
        }),
    }
}

/// Reads a pose graph in any of the three formats (detected from the content).
pub fn read_graph(text: &str) -> Result<PoseGraph, GraphFileError> {
    check_size(text)?;
    match detect_format(text)? {
        GraphFormat::G2o => read_g2o(text),
        GraphFormat::Toro => read_toro(text),
        GraphFormat::Isam => read_isam(text),
    }
}

fn check_size(text: &str) -> Result<(), GraphFileError> {
    if text.len() > MAX_FILE_BYTES {
        return Err(GraphFileError::TooLarge {
            size: text.len(),
            limit: MAX_FILE_BYTES,
        });
    }
    Ok(())
}

/// The symmetric matrix of an upper triangle given row by row.
fn upper3(v: &[f64]) -> Matrix3<f64> {
    Matrix3::new(v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5])
}

fn upper2(v: &[f64]) -> Matrix2<f64> {
    Matrix2::new(v[0], v[1], v[1], v[2])
}

/// The information matrix of a TORO edge: `Ixx Ixy Iyy Iθθ Ixθ Iyθ`.
pub fn toro_information(v: &[f64; 6]) -> Matrix3<f64> {
    let [xx, xy, yy, tt, xt, yt] = *v;
    Matrix3::new(xx, xy, xt, xy, yy, yt, xt, yt, tt)
}

fn refuse_small(graph: &PoseGraph) -> Result<(), GraphFileError> {
    if graph.vertices().len() < 2 {
        return Err(GraphFileError::TooSmall(format!(
            "the file holds {} vertex{}: a graph to optimise needs at least two vertices and an edge",
            graph.vertices().len(),
            if graph.vertices().len() == 1 {
                ""
            } else {
                "es"
            }
        )));
    }
    if graph.edges().is_empty() {
        return Err(GraphFileError::TooSmall(
            "the file holds no edges: there is nothing to optimise".to_owned(),
        ));
    }
    Ok(())
}

/// An edge read from a file, kept until every vertex is known.
enum PendingEdge {
    Between(VertexId, VertexId, Pose2, Matrix3<f64>),
    Point(VertexId, VertexId, Vector2<f64>, Matrix2<f64>),
    Prior(VertexId, Pose2, Matrix3<f64>),
}

/// Adds the edges read from a file, in file order, once every vertex is known.
fn add_pending(
    graph: &mut PoseGraph,
    pending: Vec<(usize, PendingEdge)>,
) -> Result<(), GraphFileError> {
    for (line, edge) in pending {
        add_pending_edge(graph, line, edge)?;
    }
    Ok(())
}

fn add_pending_edge(
    graph: &mut PoseGraph,
    line: usize,
    edge: PendingEdge,
) -> Result<(), GraphFileError> {
    let idx = |id: VertexId, name: &str| {
        graph.index_of(id).ok_or_else(|| {
            line_error(
                line,
                format!("{name} refers to vertex {id}, which the file does not define"),
            )
        })
    };
    let kind = match edge {
        PendingEdge::Between(a, b, z, info) => EdgeKind::PosePose {
            from: idx(a, "edge")?,
            to: idx(b, "edge")?,
            measurement: z,
            information: info,
        },
        PendingEdge::Point(a, b, z, info) => EdgeKind::PosePoint {
            pose: idx(a, "edge")?,
            point: idx(b, "edge")?,
            measurement: z,
            information: info,
        },
        PendingEdge::Prior(a, z, info) => EdgeKind::PosePrior {
            pose: idx(a, "prior")?,
            measurement: z,
            information: info,
        },
    };
    graph
        .add_edge(kind)
        .map(|_| ())
        .map_err(|e| line_error(line, e.to_string()))
}

/// Reads g2o 2D text.
pub fn read_g2o(text: &str) -> Result<PoseGraph, GraphFileError> {
    check_size(text)?;
    let mut graph = PoseGraph::new();
    let mut pending = Vec::new();
    let mut fixed = Vec::new();
    for f in lines(text) {
        match f.tag {
            "VERTEX_SE2" => f.add_pose_to(&mut graph)?,
            "VERTEX_XY" => {
                f.expect_len(3, "id x y")?;
                let v = f.nums(1, 2)?;
                graph
                    .add_point(f.id(0)?, Vector2::new(v[0], v[1]))
                    .map_err(|e| line_error(f.line, e.to_string()))?;
            }
            "EDGE_SE2" => {
                pending.push(f.between("i j dx dy dtheta I11 I12 I13 I22 I23 I33", upper3)?)
            }
            "EDGE_SE2_XY" => {
                f.expect_len(7, "i j x y I11 I12 I22")?;
                let v = f.nums(2, 5)?;
                pending.push((
                    f.line,
                    PendingEdge::Point(
                        f.id(0)?,
                        f.id(1)?,
                        Vector2::new(v[0], v[1]),
                        upper2(&v[2..]),
                    ),
                ));
            }
            "EDGE_PRIOR_SE2" => {
                f.expect_len(10, "i x y theta I11 I12 I13 I22 I23 I33")?;
                let v = f.nums(1, 9)?;
                pending.push((
                    f.line,
                    PendingEdge::Prior(f.id(0)?, file_pose(v[0], v[1], v[2]), upper3(&v[3..])),
                ));
            }
            "FIX" => {
                if f.words.is_empty() {
                    return Err(line_error(f.line, "FIX needs at least one vertex id"));
                }
                for k in 0..f.words.len() {
                    fixed.push((f.line, f.id(k)?));
                }
            }
            _ => {
                return Err(f.unknown_tag(
                    "a g2o 2D",
                    "VERTEX_SE2, VERTEX_XY, EDGE_SE2, EDGE_SE2_XY, EDGE_PRIOR_SE2, FIX",
                ));
            }
        }
    }
    add_pending(&mut graph, pending)?;
    for (line, id) in fixed {
        graph.set_fixed(id, true).map_err(|_| {
            line_error(
                line,
                format!("FIX names vertex {id}, which the file does not define"),
            )
        })?;
    }
    refuse_small(&graph)?;
    Ok(graph)
}

/// Reads TORO 2D text (`VERTEX2`, `EDGE2` with information in TORO's order).
pub fn read_toro(text: &str) -> Result<PoseGraph, GraphFileError> {
    check_size(text)?;
    let mut graph = PoseGraph::new();
    let mut pending = Vec::new();
    for f in lines(text) {
        match f.tag {
            "VERTEX2" => f.add_pose_to(&mut graph)?,
            "EDGE2" => {
                pending.push(f.between("i j dx dy dtheta Ixx Ixy Iyy Itt Ixt Iyt", |v| {
                    toro_information(&[v[0], v[1], v[2], v[3], v[4], v[5]])
                })?)
            }
            _ => return Err(f.unknown_tag("a TORO 2D", "VERTEX2, EDGE2")),
        }
    }
    add_pending(&mut graph, pending)?;
    refuse_small(&graph)?;
    Ok(graph)
}

/// The first id SLAM Lab gives landmarks of an iSAM file: the smallest power of ten
/// above every pose id (poses 0..6968 put landmark 5 at vertex 10005), because the
/// file numbers poses and landmarks separately.
pub fn isam_landmark_base(max_pose_id: VertexId) -> VertexId {
    let mut base: VertexId = 10;
    while base <= max_pose_id && base < VertexId::MAX / 10 {
        base *= 10;
    }
    base
}

/// Reads the iSAM-style format of victoria_park.txt.
///
/// `ODOMETRY` carries a covariance `c11 c12 c13 c22 c23 c33`; its inverse is the
/// edge's information. `LANDMARK pose lm lx ly v1 v2 v3` becomes a range-bearing
/// edge the way gtsam's `load2D` reads it (so that costs compare with gtsam's):
/// range `‖(lx, ly)‖`, bearing `atan2(ly, lx)`, and, when `v1 ≈ v3`, standard
/// deviations `σ_r = √v1`, `σ_φ = √(v1 / 10)` (gtsam takes the x-y variance as
/// describing a sighting 10 m away); otherwise `σ_r = σ_φ = 1`.
pub fn read_isam(text: &str) -> Result<PoseGraph, GraphFileError> {
    check_size(text)?;
    struct Odo {
        line: usize,
        i: VertexId,
        j: VertexId,
        z: Pose2,
        info: Matrix3<f64>,
    }
    struct Sighting {
        line: usize,
        pose: VertexId,
        lm: VertexId,
        local: Vector2<f64>,
        v: [f64; 3],
    }
    let mut odometry = Vec::new();
    let mut sightings = Vec::new();
    for f in lines(text) {
        match f.tag {
            "ODOMETRY" => {
                f.expect_len(11, "i j dx dy dtheta c11 c12 c13 c22 c23 c33")?;
                let v = f.nums(2, 9)?;
                let cov = upper3(&v[3..]);
                let info = cov
                    .try_inverse()
                    .filter(|m| m.iter().all(|x| x.is_finite()))
                    .ok_or_else(|| {
                        line_error(
                            f.line,
                            "ODOMETRY: the covariance is singular and has no information matrix",
                        )
                    })?;
                odometry.push(Odo {
                    line: f.line,
                    i: f.id(0)?,
                    j: f.id(1)?,
                    z: file_pose(v[0], v[1], v[2]),
                    info: 0.5 * (info + info.transpose()),
                });
            }
            "LANDMARK" => {
                f.expect_len(7, "pose landmark lx ly v1 v2 v3")?;
                let v = f.nums(2, 5)?;
                sightings.push(Sighting {
                    line: f.line,
                    pose: f.id(0)?,
                    lm: f.id(1)?,
                    local: Vector2::new(v[0], v[1]),
                    v: [v[2], v[3], v[4]],
                });
            }
            _ => return Err(f.unknown_tag("an iSAM", "ODOMETRY, LANDMARK")),
        }
    }
    let mut graph = PoseGraph::new();
    // Chain the odometry from the identity at the first pose.
    let mut poses: HashMap<VertexId, Pose2> = HashMap::new();
    for o in &odometry {
        if poses.is_empty() {
            poses.insert(o.i, Pose2::IDENTITY);
            graph
                .add_pose(o.i, Pose2::IDENTITY)
                .map_err(|e| line_error(o.line, e.to_string()))?;
        }
        let Some(from) = poses.get(&o.i).copied() else {
            return Err(line_error(
                o.line,
                format!(
                    "ODOMETRY starts at pose {}, which no earlier ODOMETRY line reaches (the initial estimate chains odometry)",
                    o.i
                ),
            ));
        };
        if let std::collections::hash_map::Entry::Vacant(slot) = poses.entry(o.j) {
            let to = from.compose(&o.z);
            slot.insert(to);
            graph
                .add_pose(o.j, to)
                .map_err(|e| line_error(o.line, e.to_string()))?;
        }
    }
    let max_pose = poses.keys().copied().max().unwrap_or(0);
    let base = isam_landmark_base(max_pose);
    for s in &sightings {
        let Some(pose) = poses.get(&s.pose).copied() else {
            return Err(line_error(
                s.line,
                format!(
                    "LANDMARK is seen from pose {}, which no ODOMETRY line defines",
                    s.pose
                ),
            ));
        };
        let id = base.saturating_add(s.lm);
        if graph.index_of(id).is_none() {
            graph
                .add_point(id, pose.transform_point(&s.local))
                .map_err(|e| line_error(s.line, e.to_string()))?;
        }
    }
    for o in &odometry {
        let (Some(from), Some(to)) = (graph.index_of(o.i), graph.index_of(o.j)) else {
            return Err(line_error(o.line, "ODOMETRY refers to an undefined pose"));
        };
        graph
            .add_edge(EdgeKind::PosePose {
                from,
                to,
                measurement: o.z,
                information: o.info,
            })
            .map_err(|e| line_error(o.line, e.to_string()))?;
    }
    for s in &sightings {
        let (Some(pose), Some(point)) = (graph.index_of(s.pose), graph.index_of(base + s.lm))
        else {
            return Err(line_error(s.line, "LANDMARK refers to an undefined vertex"));
        };
        let [v1, _, v3] = s.v;
        let (range_std, bearing_std) = if (v1 - v3).abs() < 1e-4 && v1 > 0.0 {
            (v1.sqrt(), (v1 / 10.0).sqrt())
        } else {
            (1.0, 1.0)
        };
        graph
            .add_edge(EdgeKind::RangeBearing {
                pose,
                point,
                range: math::hypot(s.local[0], s.local[1]),
                bearing: math::atan2(s.local[1], s.local[0]),
                information: Matrix2::new(
                    1.0 / (range_std * range_std),
                    0.0,
                    0.0,
                    1.0 / (bearing_std * bearing_std),
                ),
            })
            .map_err(|e| line_error(s.line, e.to_string()))?;
    }
    refuse_small(&graph)?;
    Ok(graph)
}

/// A number in the shortest text that reads back to the same `f64`, in exponent
/// form when plain digits would be long (denormals, large information values).
fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || (1e-4..1e15).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A pose read from a file: the heading is kept exactly when it already lies in
/// (-π, π] (so that write-then-read is exact), and wrapped otherwise.
fn file_pose(x: f64, y: f64, theta: f64) -> Pose2 {
    if theta > -std::f64::consts::PI && theta <= std::f64::consts::PI {
        Pose2 { x, y, theta }
    } else {
        Pose2::new(x, y, theta)
    }
}

/// `x y θ` of a pose, as [`write_g2o`] writes it.
fn pose_text(p: &Pose2) -> String {
    format!("{} {} {}", num(p.x), num(p.y), num(p.theta))
}

/// The upper triangle of a 3x3 information matrix, row by row (g2o's order).
fn upper3_text(m: &Matrix3<f64>) -> String {
    format!(
        "{} {} {} {} {} {}",
        num(m[(0, 0)]),
        num(m[(0, 1)]),
        num(m[(0, 2)]),
        num(m[(1, 1)]),
        num(m[(1, 2)]),
        num(m[(2, 2)])
    )
}

/// Writes a graph as g2o 2D text. Numbers are written in Rust's shortest form that
/// reads back to the same `f64`, so write-then-read gives the same graph. Range-
/// bearing edges and point priors have no g2o 2D tag and are refused.
pub fn write_g2o(graph: &PoseGraph) -> Result<String, GraphFileError> {
    let mut out = String::new();
    let v = graph.vertices();
    for vertex in v {
        match vertex.state {
            VertexState::Pose(p) => {
                let _ = writeln!(out, "VERTEX_SE2 {} {}", vertex.id, pose_text(&p));
            }
            VertexState::Point(p) => {
                let _ = writeln!(out, "VERTEX_XY {} {} {}", vertex.id, num(p[0]), num(p[1]));
            }
        }
    }
    for vertex in v.iter().filter(|v| v.fixed) {
        let _ = writeln!(out, "FIX {}", vertex.id);
    }
    for e in graph.edges() {
        match *e {
            EdgeKind::PosePose {
                from,
                to,
                measurement: z,
                information: m,
            } => {
                let _ = writeln!(
                    out,
                    "EDGE_SE2 {} {} {} {}",
                    v[from].id,
                    v[to].id,
                    pose_text(&z),
                    upper3_text(&m)
                );
            }
            EdgeKind::PosePoint {
                pose,
                point,
                measurement: z,
                information: m,
            } => {
                let _ = writeln!(
                    out,
                    "EDGE_SE2_XY {} {} {} {} {} {} {}",
                    v[pose].id,
                    v[point].id,
                    num(z[0]),
                    num(z[1]),
                    num(m[(0, 0)]),
                    num(m[(0, 1)]),
                    num(m[(1, 1)])
                );
            }
            EdgeKind::PosePrior {
                pose,
                measurement: z,
                information: m,
            } => {
                let _ = writeln!(
                    out,
                    "EDGE_PRIOR_SE2 {} {} {}",
                    v[pose].id,
                    pose_text(&z),
                    upper3_text(&m)
                );
            }
            EdgeKind::RangeBearing { .. } | EdgeKind::PointPrior { .. } => {
                return Err(GraphFileError::Unwritable(format!(
                    "the graph has {} edges, which g2o 2D has no entry for",
                    e.name()
                )));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod score_tests {
    //! `metrics::graph` on graphs written to g2o and read back.
    use super::{read_graph, write_g2o};
    use crate::metrics::graph::*;
    use nalgebra::Matrix3;
    use slamlab_core::graph::SolverKind;
    use slamlab_core::graph::{EdgeKind, OptimizerSettings, PoseGraph, RobustKernel, graph_cost};
    use slamlab_core::{Pose2, math};

    /// 120 poses twice around a circle of radius 5 m, odometry with a
    /// deterministic "noise" of phase `phase`, loop closures between the laps.
    fn noisy_circle(phase: f64) -> PoseGraph {
        let n = 120;
        let truth: Vec<Pose2> = (0..n)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 60.0;
                let (s, c) = math::sin_cos(a);
                Pose2::new(5.0 * s, 5.0 * (1.0 - c), a)
            })
            .collect();
        let noise = |k: usize, scale: f64| {
            let k = k as f64 + phase;
            Pose2::new(
                scale * math::sin(1.7 * k),
                scale * math::cos(2.3 * k),
                0.5 * scale * math::sin(3.1 * k),
            )
        };
        let information = Matrix3::from_diagonal(&nalgebra::Vector3::new(400.0, 400.0, 1000.0));
        let mut graph = PoseGraph::new();
        let mut guess = truth[0];
        let mut edges = Vec::new();
        for k in 0..n {
            if k > 0 {
                let z = truth[k - 1].between(&truth[k]).compose(&noise(k, 0.1));
                guess = guess.compose(&z);
                edges.push((k - 1, k, z));
            }
            graph.add_pose(k as u64, guess).expect("a new id");
        }
        for j in (0..60).step_by(7) {
            let z = truth[j]
                .between(&truth[j + 60])
                .compose(&noise(j + 500, 0.05));
            edges.push((j, j + 60, z));
        }
        for (from, to, measurement) in edges {
            graph
                .add_edge(EdgeKind::PosePose {
                    from,
                    to,
                    measurement,
                    information,
                })
                .expect("known vertices");
        }
        graph.set_fixed(0, true).expect("vertex 0");
        graph
    }

    fn problem() -> PoseGraph {
        noisy_circle(0.0)
    }

    fn gn() -> OptimizerSettings {
        OptimizerSettings {
            solver: SolverKind::GaussNewton,
            ..OptimizerSettings::default()
        }
    }

    fn round_trip(graph: &PoseGraph) -> PoseGraph {
        let text = write_g2o(graph).unwrap_or_default();
        read_graph(&text).unwrap_or_default()
    }

    #[test]
    fn the_solvers_own_result_read_back_scores_its_own_final_cost() {
        let problem = problem();
        let solution = reference_solution(&problem, gn(), 100).expect("solves");
        assert!(solution.converged);
        assert!(solution.cost < 0.5 * solution.initial_cost);
        let score = score_graph(&problem, &round_trip(&solution.graph), solution.cost)
            .expect("the same graph");
        assert!((score.cost - solution.cost).abs() <= 1e-9 * solution.cost);
        assert!((score.cost_ratio.unwrap_or(0.0) - 1.0).abs() <= 1e-9);
        assert!(score.cost_difference.abs() <= 1e-9 * solution.cost);
        assert_eq!(score.initial_cost, solution.initial_cost);
    }

    #[test]
    fn the_unoptimized_problem_scores_its_initial_cost() {
        let problem = problem();
        let solution = reference_solution(&problem, gn(), 100).expect("solves");
        let score = score_graph(&problem, &round_trip(&problem), solution.cost).expect("same");
        assert_eq!(score.cost, score.initial_cost);
        assert_eq!(score.cost, graph_cost(&problem, &RobustKernel::None));
        assert!(score.cost_ratio.unwrap_or(0.0) > 3.0, "{score:?}");
    }

    #[test]
    fn another_graph_is_refused_with_what_differs() {
        let problem = problem();
        let text = write_g2o(&problem).unwrap_or_default();
        // A vertex left out (and its edges).
        let without: String = text
            .lines()
            .filter(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                !(f.first() == Some(&"VERTEX_SE2") && f.get(1) == Some(&"57"))
                    && !(f.first() == Some(&"EDGE_SE2")
                        && (f.get(1) == Some(&"57") || f.get(2) == Some(&"57")))
            })
            .map(|l| format!("{l}\n"))
            .collect();
        let file = read_graph(&without).expect("reads");
        let why = score_graph(&problem, &file, 1.0).unwrap_err();
        assert!(why.contains("vertex 57 of the problem is missing"), "{why}");
        // Another student's noise: every vertex there, a measurement moved.
        let other = noisy_circle(0.4);
        let why = score_graph(&problem, &other, 1.0).unwrap_err();
        assert!(why.contains("another graph"), "{why}");
        // An edge dropped.
        let mut lines: Vec<&str> = text.lines().collect();
        let last_edge = lines.iter().rposition(|l| l.starts_with("EDGE_SE2"));
        if let Some(k) = last_edge {
            lines.remove(k);
        }
        let file = read_graph(&lines.join("\n")).expect("reads");
        let why = score_graph(&problem, &file, 1.0).unwrap_err();
        assert!(why.contains("edges, the problem"), "{why}");
    }

    #[test]
    fn rounded_measurements_and_reordered_edges_are_the_same_graph() {
        let problem = problem();
        let text = write_g2o(&problem).unwrap_or_default();
        // Every number to six decimals, the edges in reverse order.
        let rounded: Vec<String> = text
            .lines()
            .map(|l| {
                l.split_whitespace()
                    .map(|w| match w.parse::<f64>() {
                        Ok(v) if w.contains('.') || w.contains('e') => format!("{v:.6}"),
                        _ => w.to_owned(),
                    })
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .collect();
        let (mut edges, others): (Vec<String>, Vec<String>) =
            rounded.into_iter().partition(|l| l.starts_with("EDGE"));
        edges.reverse();
        let file = read_graph(&[others, edges].concat().join("\n")).expect("reads");
        let score = score_graph(&problem, &file, 1.0).expect("the same graph");
        // Six decimals move the states by at most 5e-7: the cost barely.
        assert!((score.cost - score.initial_cost).abs() < 1e-3 * score.initial_cost);
    }

    #[test]
    fn graph_poses_are_stamped_with_their_ids() {
        let problem = problem();
        let t = graph_poses(&problem);
        assert_eq!(t.len(), 120);
        assert_eq!(t.stamps()[0], 0.0);
        assert_eq!(t.stamps()[119], 119.0);
    }
}
