//! One entry point for every laser file a lesson opens (file picker, drop,
//! `log=`, `--log`): a CARMEN log (plain, gzip or bzip2) or a ROS 2 bag in
//! MCAP, told apart by their first bytes, never by their names, and turned
//! into the lessons' [`MappingInput`].

use crate::grid::scans::{MappingInput, log_input};
use crate::io::laser_log::{LaserLog, LogError, MAX_INPUT_BYTES};
use crate::io::ros2_bag::{
    BagError, BagKind, BagLimits, BagLog, MAX_BAG_BYTES, Ros2Bag, TopicChoice, check_bag_size,
};
use std::path::Path;
use std::sync::Arc;

/// A laser file opened for a lesson.
#[derive(Clone, Debug)]
pub struct LaserFile {
    /// The scans with their odometry (and a simulated bag's truth).
    pub input: MappingInput,
    /// What the file is: `CARMEN log (bzip2)`, `ROS 2 bag, MCAP with zstd chunks`.
    pub format: String,
    /// What the reader assumed or dropped, one sentence each.
    pub notices: Vec<String>,
    /// For a bag: the topics read and the others to choose from.
    pub topics: Option<BagTopics>,
    /// For a bag: its messages, to read again with other topics
    /// ([`LaserFile::with_topics`]).
    pub bag: Option<Arc<Ros2Bag>>,
}

/// The topics a bag was read with and the choices it offers.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BagTopics {
    /// The LaserScan topic read.
    pub scan: String,
    /// The odometry read: an Odometry topic, or `tf`.
    pub odometry: String,
    /// Every LaserScan topic.
    pub scan_choices: Vec<String>,
    /// Every odometry source: the Odometry topics, and `tf` when the TF tree
    /// has a moving transform above the laser.
    pub odometry_choices: Vec<String>,
}

/// Why a laser file cannot be opened.
#[derive(Debug, PartialEq, thiserror::Error)]
pub enum LaserFileError {
    /// A CARMEN log that does not read.
    #[error(transparent)]
    Log(#[from] LogError),
    /// A bag that does not read or holds no usable scans.
    #[error(transparent)]
    Bag(#[from] BagError),
    /// The file cannot be read.
    #[error("cannot read {0}: {1}")]
    Io(String, String),
}

impl LaserFile {
    /// Opens a laser file's bytes: a bag (read with `choice`) or a CARMEN log.
    pub fn from_bytes(
        name: &str,
        bytes: &[u8],
        choice: &TopicChoice,
    ) -> Result<Self, LaserFileError> {
        Self::from_bytes_with_limits(name, bytes, choice, &BagLimits::default())
    }

    /// [`LaserFile::from_bytes`] with a bag's limits given.
    pub fn from_bytes_with_limits(
        name: &str,
        bytes: &[u8],
        choice: &TopicChoice,
        limits: &BagLimits,
    ) -> Result<Self, LaserFileError> {
        match BagKind::detect(bytes) {
            BagKind::Other => {
                let log = LaserLog::from_bytes(bytes)?;
                Ok(Self {
                    input: log_input(&log, name),
                    format: format!(
                        "CARMEN log ({})",
                        log.compression.map_or("plain", |c| c.name())
                    ),
                    notices: Vec::new(),
                    topics: None,
                    bag: None,
                })
            }
            _ => {
                let bag = Arc::new(Ros2Bag::from_bytes_with_limits(bytes, limits)?);
                Self::with_topics(name, bag, choice)
            }
        }
    }

    /// A bag already read, with (other) topics.
    pub fn with_topics(
        name: &str,
        bag: Arc<Ros2Bag>,
        choice: &TopicChoice,
    ) -> Result<Self, LaserFileError> {
        let log = bag.laser_log(choice)?;
        let topics = bag_topics(&log);
        let mut input = log_input(&log.log, name);
        input.truth = log
            .truth
            .as_ref()
            .map(|t| t.iter().map(|p| p.pose).collect());
        let chunks: Vec<String> = bag
            .header
            .chunks
            .keys()
            .map(|c| if c.is_empty() { "uncompressed" } else { c }.to_owned())
            .collect();
        let mut notices = log.notices;
        if bag.skipped_messages() > 0 {
            let types: Vec<String> = bag
                .skipped
                .iter()
                .map(|(t, n)| format!("{n} {t}"))
                .collect();
            notices.push(format!(
                "{} messages of types the lessons do not read were skipped: {}",
                bag.skipped_messages(),
                types.join(", ")
            ));
        }
        Ok(Self {
            input,
            format: if chunks.is_empty() {
                "ROS 2 bag, MCAP unchunked".to_owned()
            } else {
                format!("ROS 2 bag, MCAP with {} chunks", chunks.join(" and "))
            },
            notices,
            topics: Some(topics),
            bag: Some(bag),
        })
    }

    /// Reads a laser file, refusing one over its format's cap from its size
    /// before reading it ([`MAX_BAG_BYTES`] for a bag, [`MAX_INPUT_BYTES`] for
    /// a CARMEN log).
    pub fn read_file(path: &Path, choice: &TopicChoice) -> Result<Self, LaserFileError> {
        let io = |e: std::io::Error| LaserFileError::Io(path.display().to_string(), e.to_string());
        let len = std::fs::metadata(path).map_err(io)?.len();
        let mut first = [0u8; 16];
        let n = {
            use std::io::Read as _;
            let mut f = std::fs::File::open(path).map_err(io)?;
            f.read(&mut first).map_err(io)?
        };
        match BagKind::detect(&first[..n]) {
            BagKind::Other => {
                crate::io::laser_log::check_input_size(len, Default::default())?;
            }
            _ => check_bag_size(len, &BagLimits::default())?,
        }
        let bytes = std::fs::read(path).map_err(io)?;
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        Self::from_bytes(&name, &bytes, choice)
    }

    /// The input's name with the topics a bag was read with.
    pub fn describe(&self) -> String {
        match &self.topics {
            Some(t) => format!("{} ({}, odometry {})", self.input.name, t.scan, t.odometry),
            None => self.input.name.clone(),
        }
    }
}

/// The larger of the two caps, for a file whose kind is not known yet.
pub const MAX_LASER_FILE_BYTES: u64 = if MAX_BAG_BYTES > MAX_INPUT_BYTES {
    MAX_BAG_BYTES
} else {
    MAX_INPUT_BYTES
};

fn bag_topics(log: &BagLog) -> BagTopics {
    let odometry = match &log.odometry {
        crate::io::ros2_bag::OdometrySource::Topic(t) => t.clone(),
        crate::io::ros2_bag::OdometrySource::Tf { .. } => "tf".to_owned(),
    };
    let mut scan_choices = vec![log.scan_topic.clone()];
    scan_choices.extend(log.other_scan_topics.iter().cloned());
    scan_choices.sort();
    let mut odometry_choices = vec![odometry.clone()];
    odometry_choices.extend(log.other_odometry.iter().cloned());
    odometry_choices.sort();
    BagTopics {
        scan: log.scan_topic.clone(),
        odometry,
        scan_choices,
        odometry_choices,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{BuiltinMap, SimulatedLogConfig, simulate_log};
    use crate::io::laser_log::TruePose;
    use crate::io::laser_log::write_carmen;
    use crate::io::ros2_bag::msgs::{LASER_SCAN, ODOMETRY, POSE_STAMPED, TF_MESSAGE};
    use crate::io::ros2_bag::{BagWriteOptions, Ros2Bag, write_bag};

    #[test]
    fn a_carmen_log_and_a_bag_are_told_apart_by_their_bytes() {
        let map = BuiltinMap::Maze.load().unwrap();
        let (log, _) = simulate_log(&map, 5, 1, &SimulatedLogConfig::default()).unwrap();
        let text = write_carmen(&log).unwrap();
        let file =
            LaserFile::from_bytes("run.mcap", text.as_bytes(), &TopicChoice::default()).unwrap();
        assert_eq!(file.format, "CARMEN log (plain)");
        assert!(file.topics.is_none());
        assert_eq!(file.input.scans.len(), 5);
        let e = LaserFile::from_bytes("old.bag", b"#ROSBAG V2.0\n", &TopicChoice::default())
            .unwrap_err();
        assert!(e.to_string().starts_with("this is a ROS 1 bag"), "{e}");
    }

    // SLAM Lab's own bags, read back by the bag reader.

    fn small_simulated_log() -> (LaserLog, Vec<TruePose>) {
        let map = BuiltinMap::Maze.load().unwrap();
        simulate_log(&map, 60, 3, &SimulatedLogConfig::default()).unwrap()
    }

    #[test]
    fn a_bag_written_by_slam_lab_reads_back_to_the_same_run() {
        let (log, truth) = small_simulated_log();
        let bytes = write_bag(&log, Some(&truth), &BagWriteOptions::default()).unwrap();
        let bag = Ros2Bag::from_bytes(&bytes).unwrap();
        assert_eq!(bag.header.profile, "ros2");
        assert!(
            bag.header.library.starts_with("slamlab "),
            "{}",
            bag.header.library
        );
        assert!(bag.header.has_summary);
        let counts: Vec<(&str, &str, usize)> = bag
            .topics
            .iter()
            .map(|t| (t.topic.as_str(), t.type_name.as_str(), t.messages))
            .collect();
        assert_eq!(
            counts,
            [
                ("/ground_truth", POSE_STAMPED, 60),
                ("/odom", ODOMETRY, 60),
                ("/scan", LASER_SCAN, 60),
                ("/tf", TF_MESSAGE, 60),
                ("/tf_static", TF_MESSAGE, 1)
            ]
        );
        let back = bag.laser_log(&TopicChoice::default()).unwrap();
        assert!(back.notices.is_empty(), "{:?}", back.notices);
        assert_eq!(back.log.scans.len(), log.scans.len());
        for (a, b) in log.scans.iter().zip(&back.log.scans) {
            // Times to the nanosecond, ranges and angles to float32 as LaserScan
            // stores them, poses through the quaternion to 1e-15 rad.
            assert!((a.timestamp - b.timestamp).abs() < 1e-9);
            assert_eq!(a.scan.ranges.len(), b.scan.ranges.len());
            for (ra, rb) in a.scan.ranges.iter().zip(&b.scan.ranges) {
                assert_eq!(f64::from(*ra as f32).to_bits(), rb.to_bits());
            }
            for (k, ab) in b.scan.angles.iter().enumerate() {
                let expected = f64::from(a.scan.angles[0] as f32)
                    + k as f64
                        * f64::from(((a.scan.angles[359] - a.scan.angles[0]) / 359.0) as f32);
                assert_eq!(ab.to_bits(), expected.to_bits());
                assert!((ab - a.scan.angles[k]).abs() < 1e-5);
            }
            assert_eq!(b.scan.range_max, a.scan.range_max);
            assert_eq!((a.odometry.x, a.odometry.y), (b.odometry.x, b.odometry.y));
            assert!((a.odometry.theta - b.odometry.theta).abs() < 1e-15);
        }
        let back_truth = back.truth.unwrap();
        for (a, b) in truth.iter().zip(&back_truth) {
            assert_eq!((a.pose.x, a.pose.y), (b.pose.x, b.pose.y));
            assert!((a.pose.theta - b.pose.theta).abs() < 1e-15);
        }
        // The twist of each Odometry message is the ODOM record's.
        let odom = &bag.odometry["/odom"];
        assert_eq!(odom[10].message.linear[0], log.odometry[10].tv);
        assert_eq!(odom[10].message.angular[2], log.odometry[10].rv);
        // /tf_static's QoS is transient-local, as tf2 publishes it.
        assert!(qos_of(&bytes, "/tf_static").contains("durability: 1"));
    }

    /// The `offered_qos_profiles` of a topic in a written bag.
    fn qos_of(bytes: &[u8], topic: &str) -> String {
        let summary = mcap::Summary::read(bytes).unwrap().unwrap();
        summary
            .channels
            .values()
            .find(|c| c.topic == topic)
            .map(|c| c.metadata["offered_qos_profiles"].clone())
            .unwrap()
    }

    #[test]
    fn uneven_beams_are_refused_when_writing() {
        let (mut log, _) = small_simulated_log();
        log.scans[5].scan.angles[7] += 0.01;
        let e = write_bag(&log, None, &BagWriteOptions::default()).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("scan 6: its beams are not evenly spaced (beam 7"),
            "{e}"
        );
    }
}
