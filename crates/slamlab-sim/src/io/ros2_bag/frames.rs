//! From a bag's messages to the laser lessons' input: the scan topic and the
//! odometry chosen, each scan posed by the odometry at its stamp, and the
//! laser's mounting read from the TF tree, all as ROS defines them.
//!
//! - **Beam angles** (sensor_msgs/LaserScan): beam `i` is at
//!   `angle_min + i · angle_increment` in the laser's frame, whatever
//!   `angle_max` says and whatever the increment's sign (negative: the beams
//!   run clockwise). A scan whose ranges reach more than one beam past
//!   `angle_max` contradicts itself and is refused. Each scan keeps its own
//!   beam count (an RPLidar's changes from turn to turn).
//! - **Ranges** (REP 117): `+inf` is "no return" (nothing within range: kept, it
//!   reads as free space up to the lesson's limit with no hit); NaN ("no
//!   measurement"), `-inf` ("too close") and readings below `range_min` are
//!   unusable (stored as NaN, which the lessons skip) and counted.
//! - **Odometry at the stamp**: the chosen `nav_msgs/Odometry` topic, or the
//!   moving transform `odom -> base` on `/tf` when the bag has no Odometry. A
//!   scan's pose is interpolated between the two odometry poses around its
//!   `header.stamp` (linearly in x and y, along the shorter arc in heading);
//!   a scan outside the odometry's time span is dropped and counted. Scans
//!   keep the order they were recorded in, even where their stamps go back
//!   (the Intel log's do 631 times).
//! - **Mounting** (REP 105, tf2): `base -> laser` is the chain of transforms
//!   from the odometry's child frame to the scan's `frame_id`, from
//!   `/tf_static` (or `/tf`, first value). Its yaw turns the beam angles; a
//!   laser mounted upside down (its z axis pointing down) mirrors them,
//!   `angle -> -angle`; its translation moves the scan's origin: a scan's pose
//!   is `odom_from_base ∘ (x, y, 0)`, the laser's position with the robot's
//!   heading. A scan plane tilted more than 25° from the floor is refused.

use super::msgs::{self, LaserScan, Transform3};
use super::{BagError, Logged, Ros2Bag};
use crate::io::laser_log::{LaserKind, LaserLog, LogOdometry, LogScan, TruePose};
use slamlab_core::particle::Scan;
use slamlab_core::{Pose2, geometry::wrap_angle, math};
use std::collections::BTreeMap;

/// The topics to read; `None` lets the bag choose (see [`Ros2Bag::laser_log`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TopicChoice {
    /// The LaserScan topic (`scan-topic=`).
    pub scan: Option<String>,
    /// The Odometry topic, or `tf` for the `odom -> base` transform on `/tf`
    /// (`odom-topic=`).
    pub odom: Option<String>,
}

/// Where the odometry came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum OdometrySource {
    /// A `nav_msgs/msg/Odometry` topic.
    Topic(String),
    /// A moving transform on `/tf`: parent and child frames.
    Tf {
        /// The odometry frame (`odom`).
        parent: String,
        /// The robot's frame (`base_link`, `base_footprint`).
        child: String,
    },
}

impl std::fmt::Display for OdometrySource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OdometrySource::Topic(t) => write!(f, "{t}"),
            OdometrySource::Tf { parent, child } => write!(f, "/tf {parent} -> {child}"),
        }
    }
}

/// A bag made into a laser log, with what was assumed on the way.
#[derive(Clone, Debug, PartialEq)]
pub struct BagLog {
    /// The scans (each with the odometry pose of the laser's position at its
    /// stamp) and the odometry records.
    pub log: LaserLog,
    /// The true pose at each scan, from a `/ground_truth` PoseStamped topic (a
    /// bag SLAM Lab simulated), for the metrics only.
    pub truth: Option<Vec<TruePose>>,
    /// The LaserScan topic read.
    pub scan_topic: String,
    /// The odometry read.
    pub odometry: OdometrySource,
    /// The other LaserScan topics, for a choice.
    pub other_scan_topics: Vec<String>,
    /// The other odometry sources (`tf` among them when it exists).
    pub other_odometry: Vec<String>,
    /// The laser's mounting on the robot, flattened: `(x, y, yaw)`.
    pub mount: Pose2,
    /// Whether the laser is mounted upside down (its beams mirrored).
    pub mirrored: bool,
    /// What the reader had to assume or drop, one sentence each.
    pub notices: Vec<String>,
}

/// The TF tree of a bag: each child frame's parent and transforms.
struct TfTree {
    /// Child -> (parent, transform) from `/tf_static` (the last one wins).
    fixed: BTreeMap<String, (String, Transform3)>,
    /// Child -> (parent, stamped transforms in stamp order) from `/tf`.
    moving: BTreeMap<String, (String, Vec<(i64, Transform3)>)>,
}

impl TfTree {
    fn new(bag: &Ros2Bag) -> Self {
        let mut fixed = BTreeMap::new();
        let mut moving: BTreeMap<String, (String, Vec<(i64, Transform3)>)> = BTreeMap::new();
        for t in &bag.transforms {
            let tr = &t.transform;
            let child = tr.child_frame_id.trim_start_matches('/').to_owned();
            let parent = tr.header.frame_id.trim_start_matches('/').to_owned();
            if t.is_static {
                fixed.insert(child, (parent, tr.transform));
            } else {
                let entry = moving
                    .entry(child)
                    .or_insert_with(|| (parent.clone(), Vec::new()));
                if entry.0 == parent {
                    entry.1.push((tr.header.stamp.nanos(), tr.transform));
                }
            }
        }
        for (_, series) in moving.values_mut() {
            series.sort_by_key(|(t, _)| *t);
        }
        Self { fixed, moving }
    }

    /// The parent of `frame` and whether that edge moves.
    fn parent(&self, frame: &str) -> Option<(&str, bool)> {
        if let Some((p, _)) = self.fixed.get(frame) {
            Some((p, false))
        } else {
            self.moving.get(frame).map(|(p, _)| (p.as_str(), true))
        }
    }

    /// The frames from `frame` up to the root: `[(child, parent, moving)]`.
    fn chain_up(&self, frame: &str) -> Vec<(String, String, bool)> {
        let mut out = Vec::new();
        let mut f = frame.to_owned();
        // A tree deeper than 64 frames (or with a cycle) stops here.
        while let Some((p, moving)) = self.parent(&f) {
            if out.len() >= 64 || out.iter().any(|(c, _, _)| *c == p) {
                break;
            }
            out.push((f.clone(), p.to_owned(), moving));
            f = p.to_owned();
        }
        out
    }

    /// `ancestor_from_frame` by the chain up from `frame`, with the frames of
    /// moving edges used (their first transform); `None` when `ancestor` is not
    /// above `frame`.
    fn lookup(&self, ancestor: &str, frame: &str) -> Option<(Transform3, Vec<String>)> {
        if ancestor == frame {
            return Some((Transform3::IDENTITY, Vec::new()));
        }
        let mut acc = Transform3::IDENTITY;
        let mut moving_used = Vec::new();
        for (child, parent, moving) in self.chain_up(frame) {
            let t = if moving {
                moving_used.push(format!("{parent} -> {child}"));
                self.moving.get(&child)?.1.first()?.1
            } else {
                self.fixed.get(&child)?.1
            };
            acc = t.compose(&acc);
            if parent == ancestor {
                return Some((acc, moving_used));
            }
        }
        None
    }
}

/// A pose series sorted by stamp (ns), interpolated at a stamp.
struct PoseSeries {
    stamps: Vec<i64>,
    poses: Vec<Pose2>,
}

impl PoseSeries {
    fn new(mut samples: Vec<(i64, Pose2)>) -> Self {
        samples.sort_by_key(|(t, _)| *t);
        let (stamps, poses) = samples.into_iter().unzip();
        Self { stamps, poses }
    }

    /// The pose at `t`: exactly a sample's pose at its own stamp, else linear
    /// between the two around `t` (heading along the shorter arc); `None`
    /// outside the span.
    fn at(&self, t: i64) -> Option<Pose2> {
        let k = self.stamps.partition_point(|&s| s < t);
        if self.stamps.get(k) == Some(&t) {
            return self.poses.get(k).copied();
        }
        if k == 0 || k >= self.stamps.len() {
            return None;
        }
        let (t0, t1) = (self.stamps[k - 1], self.stamps[k]);
        let (a, b) = (self.poses[k - 1], self.poses[k]);
        let f = (t - t0) as f64 / (t1 - t0) as f64;
        Some(Pose2::new(
            a.x + f * (b.x - a.x),
            a.y + f * (b.y - a.y),
            a.theta + f * wrap_angle(b.theta - a.theta),
        ))
    }
}

/// The topic to read among `candidates`: the one asked for, else `preferred`
/// if present, else the one with the most messages.
fn pick<'a>(candidates: &[(&'a str, usize)], preferred: &str) -> Option<&'a str> {
    if let Some((t, _)) = candidates.iter().find(|(t, _)| *t == preferred) {
        return Some(t);
    }
    candidates
        .iter()
        .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(a.0)))
        .map(|(t, _)| *t)
}

/// Degrees, for notices.
fn deg(rad: f64) -> f64 {
    rad * 180.0 / std::f64::consts::PI
}

impl Ros2Bag {
    /// The scans of one LaserScan topic with the odometry at their stamps: the
    /// lessons' input. With no choice, the scan topic is `/scan` if there is
    /// one, else the LaserScan topic with the most messages; the odometry is
    /// `/odom` if it is an Odometry topic, else the Odometry topic with the
    /// most messages, else the moving transform above the laser on `/tf`.
    pub fn laser_log(&self, choice: &TopicChoice) -> Result<BagLog, BagError> {
        let mut notices = Vec::new();
        // The scan topic.
        let scan_topics = self.topic_counts(msgs::LASER_SCAN);
        let scan_topic = match &choice.scan {
            Some(wanted) => wanted_topic(&scan_topics, wanted, msgs::LASER_SCAN, None)?,
            None => pick(&scan_topics, "/scan").ok_or_else(|| BagError::NoLaserTopic {
                topics: self.topic_list(),
            })?,
        };
        if scan_topics.len() > 1 && choice.scan.is_none() {
            notices.push(several_topics(
                &scan_topics,
                "LaserScan",
                &format!("mapping {scan_topic}"),
                "scan-topic",
            ));
        }
        let scans: &[Logged<LaserScan>] = self.scans.get(scan_topic).map_or(&[], Vec::as_slice);
        let Some(first) = scans.first() else {
            return Err(BagError::NoScans(format!("{scan_topic} has no messages")));
        };
        let laser_frame = first
            .message
            .header
            .frame_id
            .trim_start_matches('/')
            .to_owned();
        let tf = TfTree::new(self);

        // The odometry.
        let odom_topics = self.topic_counts(msgs::ODOMETRY);
        let tf_edge = odometry_edge(&tf, &laser_frame);
        let mut other_odometry: Vec<String> =
            odom_topics.iter().map(|(t, _)| (*t).to_owned()).collect();
        if tf_edge.is_some() {
            other_odometry.push("tf".to_owned());
        }
        let use_tf = match choice.odom.as_deref() {
            Some("tf") => true,
            Some(_) => false,
            None => odom_topics.is_empty(),
        };
        let (source, base_frame, series, odom_records) = if use_tf {
            let Some((parent, child)) = tf_edge else {
                return Err(BagError::NoOdometry { laser_frame });
            };
            if !parent.ends_with("odom") {
                notices.push(format!(
                    "no transform from a frame named odom above {laser_frame}: the moving transform {parent} -> {child} on /tf is taken as the odometry"
                ));
            }
            let samples: Vec<(i64, Pose2)> = tf
                .moving
                .get(&child)
                .map(|(_, s)| s.as_slice())
                .unwrap_or(&[])
                .iter()
                .filter_map(|(t, tr)| tr.to_pose2().map(|p| (*t, p)))
                .collect();
            let records = samples
                .iter()
                .map(|(t, p)| LogOdometry {
                    timestamp: *t as f64 * 1e-9,
                    pose: *p,
                    tv: 0.0,
                    rv: 0.0,
                })
                .collect();
            (
                OdometrySource::Tf {
                    parent,
                    child: child.clone(),
                },
                child,
                PoseSeries::new(samples),
                records,
            )
        } else {
            let topic = match &choice.odom {
                Some(wanted) => wanted_topic(
                    &odom_topics,
                    wanted,
                    msgs::ODOMETRY,
                    tf_edge.is_some().then_some("tf"),
                )?,
                None => pick(&odom_topics, "/odom").ok_or(BagError::NoOdometry {
                    laser_frame: laser_frame.clone(),
                })?,
            };
            if odom_topics.len() > 1 && choice.odom.is_none() {
                notices.push(several_topics(
                    &odom_topics,
                    "Odometry",
                    &format!("using {topic}"),
                    "odom-topic",
                ));
            }
            let messages = self.odometry.get(topic).map_or(&[][..], Vec::as_slice);
            let base = messages
                .first()
                .map(|m| m.message.child_frame_id.trim_start_matches('/').to_owned())
                .unwrap_or_default();
            let mut samples = Vec::with_capacity(messages.len());
            let mut records = Vec::with_capacity(messages.len());
            let mut unusable = 0usize;
            for m in messages {
                let stamp = stamp_or_log_time(m.message.header.stamp.nanos(), m.log_time);
                let Some(pose) = m.message.pose.to_pose2() else {
                    unusable += 1;
                    continue;
                };
                samples.push((stamp, pose));
                records.push(LogOdometry {
                    timestamp: stamp as f64 * 1e-9,
                    pose,
                    tv: m.message.linear[0],
                    rv: m.message.angular[2],
                });
            }
            if unusable > 0 {
                notices.push(format!(
                    "{unusable} odometry messages on {topic} with a pose that is not finite were skipped"
                ));
            }
            (
                OdometrySource::Topic(topic.to_owned()),
                base,
                PoseSeries::new(samples),
                records,
            )
        };
        other_odometry.retain(|s| match &source {
            OdometrySource::Topic(t) => s != t,
            OdometrySource::Tf { .. } => s != "tf",
        });
        if series.stamps.is_empty() {
            return Err(BagError::NoScans(format!(
                "the odometry ({source}) has no usable pose"
            )));
        }

        // The laser's mounting.
        let (mount3, mount_note) = if base_frame.is_empty() || laser_frame.is_empty() {
            (
                Transform3::IDENTITY,
                Some(format!(
                    "the odometry's child frame or the scan's frame is empty: the laser is taken to sit at the robot's centre, facing forward (frames {base_frame:?}, {laser_frame:?})"
                )),
            )
        } else {
            match tf.lookup(&base_frame, &laser_frame) {
                Some((t, moving)) => (
                    t,
                    (!moving.is_empty()).then(|| {
                        format!(
                            "the transforms {} move on /tf; their first values were taken as the laser's fixed mounting",
                            moving.join(", ")
                        )
                    }),
                ),
                None => (
                    Transform3::IDENTITY,
                    Some(format!(
                        "no transform from {base_frame} to {laser_frame} on /tf_static: the laser is taken to sit at the robot's centre, facing forward"
                    )),
                ),
            }
        };
        notices.extend(mount_note);
        let (mount, mirrored) = flatten_mount(&mount3, &base_frame, &laser_frame)?;
        if mirrored {
            notices.push(format!(
                "the laser is mounted upside down ({base_frame} -> {laser_frame} turns its z axis down): beam angles mirrored, angle -> -angle"
            ));
        }
        if mount.theta != 0.0 {
            notices.push(format!(
                "the laser is turned by {:.1}° on the robot: beam angles turned with it",
                deg(mount.theta)
            ));
        }
        let offset = Pose2::new(mount.x, mount.y, 0.0);
        let has_offset = mount.x != 0.0 || mount.y != 0.0;
        if has_offset {
            notices.push(format!(
                "the laser sits at ({:.3}, {:.3}) m from {base_frame}: each scan is posed at the laser's position with the robot's heading",
                mount.x, mount.y
            ));
        }

        // The scans.
        let mut stats = ScanStats::default();
        let mut out: Vec<(i64, LogScan)> = Vec::with_capacity(scans.len());
        let mut angle_cache: BTreeMap<(usize, u32, u32), Vec<f64>> = BTreeMap::new();
        for (i, m) in scans.iter().enumerate() {
            let index = i + 1;
            let s = &m.message;
            let bad = |message: String| BagError::BadScan {
                topic: scan_topic.to_owned(),
                index,
                message,
            };
            let stamp = stamp_or_log_time(s.header.stamp.nanos(), m.log_time);
            stats.zero_stamps += usize::from(s.header.stamp.nanos() == 0);
            let n = s.ranges.len();
            if n == 0 {
                stats.empty += 1;
                continue;
            }
            let (amin, amax, inc) = (
                f64::from(s.angle_min),
                f64::from(s.angle_max),
                f64::from(s.angle_increment),
            );
            if !(amin.is_finite() && amax.is_finite() && inc.is_finite()) {
                return Err(bad(format!(
                    "angle_min {amin}, angle_max {amax} or angle_increment {inc} is not finite"
                )));
            }
            if n > 1 && inc == 0.0 {
                return Err(bad(format!("{n} ranges with an angle_increment of 0")));
            }
            if n > 1 {
                // Beams past angle_max: more than one beam of tolerance (drivers
                // round the count either way).
                let span = (amax - amin) / inc;
                if span < -0.5 {
                    return Err(bad(format!(
                        "angle_increment {inc} leads away from angle_max: angle_min {amin}, angle_max {amax}"
                    )));
                }
                if (n - 1) as f64 > span + 1.0 + 1e-6 {
                    return Err(bad(format!(
                        "{n} ranges, but angle_min {amin:.6}, angle_max {amax:.6} and angle_increment {inc:.6} give {} beams: the ranges run past angle_max",
                        span.floor() as i64 + 1
                    )));
                }
            }
            let range_max = f64::from(s.range_max);
            if !(range_max.is_finite() && range_max > 0.0) {
                return Err(bad(format!(
                    "range_max {range_max} is not a positive number"
                )));
            }
            let range_min = f64::from(s.range_min);
            let range_min = if range_min.is_finite() && range_min >= 0.0 {
                range_min
            } else {
                0.0
            };
            stats.negative_increment |= inc < 0.0;
            stats.beams_min = stats.beams_min.min(n);
            stats.beams_max = stats.beams_max.max(n);
            if s.header.frame_id.trim_start_matches('/') != laser_frame {
                stats.other_frame += 1;
            }
            let Some(odometry) = series.at(stamp) else {
                stats.outside_odometry += 1;
                continue;
            };
            // ROS's angles, then the mounting (mirror, turn); one angle vector
            // per layout, shared by its scans.
            let angles = angle_cache
                .entry((n, s.angle_min.to_bits(), s.angle_increment.to_bits()))
                .or_insert_with(|| {
                    (0..n)
                        .map(|k| {
                            let a = amin + k as f64 * inc;
                            if mirrored || mount.theta != 0.0 {
                                wrap_angle(if mirrored { -a } else { a } + mount.theta)
                            } else {
                                a
                            }
                        })
                        .collect()
                })
                .clone();
            let ranges: Vec<f64> = s
                .ranges
                .iter()
                .map(|&r| {
                    let r = f64::from(r);
                    if r.is_nan() || r == f64::NEG_INFINITY || r < range_min {
                        stats.unusable += 1;
                        f64::NAN
                    } else {
                        r
                    }
                })
                .collect();
            out.push((
                stamp,
                LogScan {
                    timestamp: stamp as f64 * 1e-9,
                    kind: LaserKind::Robot,
                    scan: Scan {
                        angles,
                        ranges,
                        range_min,
                        range_max,
                    },
                    odometry: if has_offset {
                        odometry.compose(&offset)
                    } else {
                        odometry
                    },
                    laser_pose: None,
                    line: index,
                },
            ));
        }
        stats.notices(scan_topic, &source, &mut notices);
        let backwards = out.windows(2).filter(|w| w[1].0 < w[0].0).count();
        if backwards > 0 {
            notices.push(format!(
                "the stamps on {scan_topic} go backwards {backwards} times: the scans are kept in the order they were recorded"
            ));
        }
        if out.is_empty() {
            return Err(BagError::NoScans(format!(
                "none of the {} scans on {scan_topic} lies within the odometry's time span ({source})",
                scans.len()
            )));
        }
        let stamps: Vec<i64> = out.iter().map(|(t, _)| *t).collect();
        let truth = self.truth_at(&stamps, &mut notices);
        let log = LaserLog {
            scans: out.into_iter().map(|(_, s)| s).collect(),
            odometry: odom_records,
            unusable_readings: stats.unusable,
            ..LaserLog::default()
        };
        Ok(BagLog {
            log,
            truth,
            scan_topic: scan_topic.to_owned(),
            odometry: source,
            other_scan_topics: scan_topics
                .iter()
                .filter(|(t, _)| *t != scan_topic)
                .map(|(t, _)| (*t).to_owned())
                .collect(),
            other_odometry,
            mount,
            mirrored,
            notices,
        })
    }

    /// The true pose at each stamp from a `/ground_truth` PoseStamped topic;
    /// `None` when there is none or it does not cover every stamp.
    fn truth_at(&self, stamps: &[i64], notices: &mut Vec<String>) -> Option<Vec<TruePose>> {
        let poses = self.poses.get("/ground_truth")?;
        let series = PoseSeries::new(
            poses
                .iter()
                .filter_map(|m| {
                    let t = stamp_or_log_time(m.message.header.stamp.nanos(), m.log_time);
                    m.message.pose.to_pose2().map(|p| (t, p))
                })
                .collect(),
        );
        let truth: Option<Vec<TruePose>> = stamps
            .iter()
            .map(|&t| {
                series.at(t).map(|pose| TruePose {
                    timestamp: t as f64 * 1e-9,
                    pose,
                })
            })
            .collect();
        if truth.is_none() {
            notices
                .push("/ground_truth does not cover every scan: the run has no truth".to_owned());
        }
        truth
    }
}

/// The stamp, or the log time when the stamp is zero (a driver that leaves it unset).
fn stamp_or_log_time(stamp: i64, log_time: u64) -> i64 {
    if stamp == 0 {
        i64::try_from(log_time).unwrap_or(i64::MAX)
    } else {
        stamp
    }
}

/// The topic `wanted` among `topics` (of type `type_name`), or the error that
/// lists them (and `also`, another source that could be chosen: `tf`).
fn wanted_topic<'a>(
    topics: &[(&'a str, usize)],
    wanted: &str,
    type_name: &'static str,
    also: Option<&'a str>,
) -> Result<&'a str, BagError> {
    topics
        .iter()
        .find(|(t, _)| *t == wanted)
        .map(|(t, _)| *t)
        .ok_or_else(|| BagError::NoSuchTopic {
            wanted: wanted.to_owned(),
            type_name,
            available: list(topics.iter().map(|(t, _)| *t).chain(also)),
        })
}

/// The notice that the bag has several `kind` topics (`topics`) and what was
/// done (`doing`: which one is used), and the link key that chooses another.
fn several_topics(topics: &[(&str, usize)], kind: &str, doing: &str, key: &str) -> String {
    format!(
        "{} {kind} topics ({}): {doing}; choose another with {key}=",
        topics.len(),
        list(topics.iter().map(|(t, _)| *t))
    )
}

/// `a, b, c`, or `none`.
fn list<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let v: Vec<&str> = names.collect();
    if v.is_empty() {
        "none".to_owned()
    } else {
        v.join(", ")
    }
}

/// The moving edge on `/tf` above the laser taken as odometry: the first
/// whose parent is named `odom` (or ends with it), else the first moving edge.
fn odometry_edge(tf: &TfTree, laser_frame: &str) -> Option<(String, String)> {
    let chain = tf.chain_up(laser_frame);
    let moving: Vec<&(String, String, bool)> = chain.iter().filter(|(_, _, m)| *m).collect();
    moving
        .iter()
        .find(|(_, p, _)| p.ends_with("odom"))
        .or_else(|| moving.first())
        .map(|(c, p, _)| (p.clone(), c.clone()))
}

/// The mounting flattened onto the floor: `(x, y, yaw)` and whether the laser
/// is upside down. Refuses a scan plane tilted more than 25°.
fn flatten_mount(t: &Transform3, base: &str, laser: &str) -> Result<(Pose2, bool), BagError> {
    let Some(m) = t.rotation_matrix() else {
        return Err(BagError::Mounting(format!(
            "the transform {base} -> {laser} has a rotation that is zero or not finite"
        )));
    };
    let [x, y, _] = t.translation;
    if !(x.is_finite() && y.is_finite()) {
        return Err(BagError::Mounting(format!(
            "the transform {base} -> {laser} has a translation that is not finite"
        )));
    }
    // The laser's z axis in the base frame: m[.][2]; cos 25° = 0.906.
    let z = m[2][2];
    if z.abs() < 0.906 {
        let tilt = deg(math::acos(z.abs().min(1.0)));
        return Err(BagError::Mounting(format!(
            "the laser's scan plane is tilted {tilt:.0}° from the floor ({base} -> {laser}); SLAM Lab maps scans of a horizontal laser (tilt under 25°)"
        )));
    }
    let yaw = math::atan2(m[1][0], m[0][0]);
    Ok((Pose2::new(x, y, yaw), z < 0.0))
}

/// What the scan loop counted, turned into notices.
#[derive(Debug)]
struct ScanStats {
    unusable: usize,
    empty: usize,
    zero_stamps: usize,
    outside_odometry: usize,
    other_frame: usize,
    negative_increment: bool,
    beams_min: usize,
    beams_max: usize,
}

impl Default for ScanStats {
    fn default() -> Self {
        Self {
            unusable: 0,
            empty: 0,
            zero_stamps: 0,
            outside_odometry: 0,
            other_frame: 0,
            negative_increment: false,
            beams_min: usize::MAX,
            beams_max: 0,
        }
    }
}

impl ScanStats {
    fn notices(&self, topic: &str, source: &OdometrySource, notices: &mut Vec<String>) {
        if self.negative_increment {
            notices.push(format!(
                "{topic} has a negative angle_increment: its beams run clockwise, at angle_min + i·angle_increment as ROS defines them"
            ));
        }
        if self.beams_min < self.beams_max {
            notices.push(format!(
                "the beam count on {topic} changes from scan to scan ({} to {}): each scan keeps its own angles",
                self.beams_min, self.beams_max
            ));
        }
        if self.unusable > 0 {
            notices.push(format!(
                "{} readings are NaN, -inf or below range_min: skipped (REP 117); +inf reads as no return",
                self.unusable
            ));
        }
        for (count, what) in [
            (self.empty, "have no ranges: skipped".to_owned()),
            (
                self.zero_stamps,
                "have a zero header.stamp: the recorder's time was used".to_owned(),
            ),
            (
                self.outside_odometry,
                format!("lie outside the odometry's time span ({source}): dropped"),
            ),
            (
                self.other_frame,
                "name another frame than the first: the first one's mounting was used".to_owned(),
            ),
        ] {
            if count > 0 {
                notices.push(format!("{count} scans on {topic} {what}"));
            }
        }
    }
}
