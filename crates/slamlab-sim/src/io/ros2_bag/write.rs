//! A laser log written as a ROS 2 bag in MCAP, readable by `ros2 bag info`,
//! `ros2 bag play` and Foxglove: per scan a `sensor_msgs/msg/LaserScan` on
//! `/scan`, a `nav_msgs/msg/Odometry` on `/odom` and the same pose as
//! `odom -> base_link` on `/tf`; `base_link -> laser` once on `/tf_static`
//! (identity: SLAM Lab's lidar sits at the robot's centre); and, for a
//! simulated run, the true pose as a `geometry_msgs/msg/PoseStamped` in `map`
//! on `/ground_truth`.
//!
//! The file follows rosbag2's MCAP storage: profile `ros2`, schemas in
//! `ros2msg` (the `.msg` text with its dependencies), messages in `cdr`, each
//! channel with its `offered_qos_profiles` (`/tf_static` transient-local, as
//! tf2 publishes it), uncompressed chunks with message indexes and a summary.

use super::msgs::{
    self, Header, LaserScan, Odometry, PoseStamped, TfMessage, Time, Transform3, TransformStamped,
};
use crate::io::laser_log::{LaserLog, LogScan, TruePose};
use std::collections::BTreeMap;
use std::io::Cursor;

/// Topic and frame names of a written bag.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BagWriteOptions {
    /// LaserScan topic.
    pub scan_topic: String,
    /// Odometry topic.
    pub odom_topic: String,
    /// Truth topic (PoseStamped).
    pub truth_topic: String,
    /// The odometry frame.
    pub odom_frame: String,
    /// The robot's frame.
    pub base_frame: String,
    /// The laser's frame.
    pub laser_frame: String,
    /// The frame of the truth (the simulated world's).
    pub truth_frame: String,
}

impl Default for BagWriteOptions {
    fn default() -> Self {
        Self {
            scan_topic: "/scan".to_owned(),
            odom_topic: "/odom".to_owned(),
            truth_topic: "/ground_truth".to_owned(),
            odom_frame: "odom".to_owned(),
            base_frame: "base_link".to_owned(),
            laser_frame: "laser".to_owned(),
            truth_frame: "map".to_owned(),
        }
    }
}

/// Why a log cannot be written as a bag.
#[derive(Debug, thiserror::Error)]
pub enum BagWriteError {
    /// A scan whose beams a LaserScan cannot express.
    #[error(
        "scan {index}: its beams are not evenly spaced (beam {beam} is {off:.3e} rad from angle_min + {beam}·angle_increment), which a LaserScan cannot express"
    )]
    UnevenBeams {
        /// 1-based scan index.
        index: usize,
        /// The first beam off the even layout.
        beam: usize,
        /// How far off, radians.
        off: f64,
    },
    /// Truth that does not match the scans.
    #[error("{truth} true poses for {scans} scans: one per scan is needed")]
    TruthLength {
        /// True poses given.
        truth: usize,
        /// Scans in the log.
        scans: usize,
    },
    /// The MCAP writer failed.
    #[error("writing the MCAP file: {0}")]
    Mcap(String),
}

/// `offered_qos_profiles` as rosbag2 records it (Humble's YAML): reliable,
/// keep-last; volatile for sensor topics, transient-local for `/tf_static`.
fn qos(transient_local: bool) -> String {
    let infinite = "\n    sec: 2147483647\n    nsec: 4294967295";
    format!(
        "- history: 1\n  depth: {}\n  reliability: 1\n  durability: {}\n  deadline:{infinite}\n  lifespan:{infinite}\n  liveliness: 1\n  liveliness_lease_duration:{infinite}\n  avoid_ros_namespace_conventions: false",
        if transient_local { 1 } else { 10 },
        if transient_local { 1 } else { 2 }
    )
}

/// The LaserScan of a log scan; refuses beams that are not evenly spaced.
fn laser_scan(
    index: usize,
    s: &LogScan,
    header: Header,
    scan_time: f32,
) -> Result<LaserScan, BagWriteError> {
    let a = &s.scan.angles;
    let n = a.len().min(s.scan.ranges.len());
    let (first, last) = (
        a.first().copied().unwrap_or(0.0),
        a.get(n.saturating_sub(1)).copied().unwrap_or(0.0),
    );
    let increment = if n > 1 {
        (last - first) / (n - 1) as f64
    } else {
        0.0
    };
    for (k, &angle) in a.iter().enumerate().take(n) {
        let off = (angle - (first + k as f64 * increment)).abs();
        if !(off <= 1e-6) {
            return Err(BagWriteError::UnevenBeams {
                index,
                beam: k,
                off,
            });
        }
    }
    Ok(LaserScan {
        header,
        angle_min: first as f32,
        angle_max: last as f32,
        angle_increment: increment as f32,
        time_increment: 0.0,
        scan_time,
        range_min: s.scan.range_min as f32,
        range_max: s.scan.range_max as f32,
        ranges: s.scan.ranges[..n].iter().map(|&r| r as f32).collect(),
    })
}

/// Writes `log` (and, for a simulated run, one true pose per scan) as a
/// ROS 2 bag in MCAP; returns the file's bytes.
pub fn write_bag(
    log: &LaserLog,
    truth: Option<&[TruePose]>,
    options: &BagWriteOptions,
) -> Result<Vec<u8>, BagWriteError> {
    if let Some(t) = truth
        && t.len() != log.scans.len()
    {
        return Err(BagWriteError::TruthLength {
            truth: t.len(),
            scans: log.scans.len(),
        });
    }
    let mcap_error = |e: mcap::McapError| BagWriteError::Mcap(e.to_string());
    let mut writer = mcap::WriteOptions::new()
        .profile("ros2")
        .library(format!(
            "slamlab {} (mcap-rust {})",
            env!("CARGO_PKG_VERSION"),
            mcap::VERSION
        ))
        .compression(None)
        .create(Cursor::new(Vec::new()))
        .map_err(mcap_error)?;
    let channel = |w: &mut mcap::Writer<Cursor<Vec<u8>>>,
                   topic: &str,
                   type_name: &str,
                   transient_local: bool|
     -> Result<u16, BagWriteError> {
        let schema = msgs::schema_text(type_name).unwrap_or_default();
        let schema_id = w
            .add_schema(type_name, "ros2msg", schema.as_bytes())
            .map_err(mcap_error)?;
        let metadata = BTreeMap::from([("offered_qos_profiles".to_owned(), qos(transient_local))]);
        w.add_channel(schema_id, topic, "cdr", &metadata)
            .map_err(mcap_error)
    };
    let scan_channel = channel(&mut writer, &options.scan_topic, msgs::LASER_SCAN, false)?;
    let odom_channel = channel(&mut writer, &options.odom_topic, msgs::ODOMETRY, false)?;
    let tf_channel = channel(&mut writer, "/tf", msgs::TF_MESSAGE, false)?;
    let tf_static_channel = channel(&mut writer, "/tf_static", msgs::TF_MESSAGE, true)?;
    let truth_channel = match truth {
        Some(_) => Some(channel(
            &mut writer,
            &options.truth_topic,
            msgs::POSE_STAMPED,
            false,
        )?),
        None => None,
    };
    let mut sequences: BTreeMap<u16, u32> = BTreeMap::new();
    let mut write = |w: &mut mcap::Writer<Cursor<Vec<u8>>>,
                     channel_id: u16,
                     stamp: Time,
                     data: &[u8]|
     -> Result<(), BagWriteError> {
        let sequence = sequences.entry(channel_id).or_insert(0);
        *sequence += 1;
        let time = u64::try_from(stamp.nanos()).unwrap_or(0);
        w.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id,
                sequence: *sequence,
                log_time: time,
                publish_time: time,
            },
            data,
        )
        .map_err(mcap_error)
    };
    let header = |stamp: Time, frame: &str| Header {
        stamp,
        frame_id: frame.to_owned(),
    };
    // The twist of each scan: the latest ODOM record at or before it.
    let mut odom_records = log.odometry.iter().peekable();
    let mut twist = (0.0, 0.0);
    for (k, s) in log.scans.iter().enumerate() {
        let stamp = Time::from_seconds(s.timestamp);
        if k == 0 {
            let mount = TfMessage {
                transforms: vec![TransformStamped {
                    header: header(stamp, &options.base_frame),
                    child_frame_id: options.laser_frame.clone(),
                    transform: Transform3::IDENTITY,
                }],
            };
            write(&mut writer, tf_static_channel, stamp, &mount.encode())?;
        }
        while let Some(o) = odom_records.next_if(|o| o.timestamp <= s.timestamp) {
            twist = (o.tv, o.rv);
        }
        let scan_time = log
            .scans
            .get(k + 1)
            .map_or(0.0, |next| (next.timestamp - s.timestamp) as f32);
        let scan = laser_scan(k + 1, s, header(stamp, &options.laser_frame), scan_time)?;
        write(&mut writer, scan_channel, stamp, &scan.encode())?;
        let pose = Transform3::from_pose2(s.odometry);
        let odometry = Odometry {
            header: header(stamp, &options.odom_frame),
            child_frame_id: options.base_frame.clone(),
            pose,
            linear: [twist.0, 0.0, 0.0],
            angular: [0.0, 0.0, twist.1],
        };
        write(&mut writer, odom_channel, stamp, &odometry.encode())?;
        let tf = TfMessage {
            transforms: vec![TransformStamped {
                header: header(stamp, &options.odom_frame),
                child_frame_id: options.base_frame.clone(),
                transform: pose,
            }],
        };
        write(&mut writer, tf_channel, stamp, &tf.encode())?;
        if let (Some(channel_id), Some(t)) = (truth_channel, truth.and_then(|t| t.get(k))) {
            let message = PoseStamped {
                header: header(stamp, &options.truth_frame),
                pose: Transform3::from_pose2(t.pose),
            };
            write(&mut writer, channel_id, stamp, &message.encode())?;
        }
    }
    writer.finish().map_err(mcap_error)?;
    Ok(writer.into_inner().into_inner())
}
