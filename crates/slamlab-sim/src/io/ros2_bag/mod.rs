//! ROS 2 bags in MCAP, read and written: a student's own robot recording
//! (`ros2 bag record /scan /odom /tf /tf_static`) becomes the laser lessons'
//! input, and a simulated run becomes a bag for ROS tools and Foxglove.
//!
//! - [`Ros2Bag::from_bytes`] reads the file with the `mcap` crate (chunks
//!   unpacked by pure-Rust zstd and LZ4 decoders: [`mcap_read`]) and decodes
//!   the messages the lessons use from CDR ([`cdr`], [`msgs`]):
//!   `sensor_msgs/msg/LaserScan`, `nav_msgs/msg/Odometry`,
//!   `tf2_msgs/msg/TFMessage` on `/tf` and `/tf_static`, and
//!   `geometry_msgs/msg/PoseStamped` (a simulated run's truth). Messages of
//!   other types are skipped and counted by type.
//! - [`Ros2Bag::laser_log`] turns the chosen scan and odometry topics into a
//!   [`LaserLog`](crate::io::laser_log::LaserLog), each scan with the odometry
//!   pose at its stamp, the laser's mounting from the TF tree ([`frames`]).
//! - [`write_bag`] writes a laser log (and its truth) as a bag ([`write`]).
//!
//! # Caps
//!
//! [`MAX_BAG_BYTES`] on the file, refused from its size before it is read
//! ([`Ros2Bag::read_file`]); [`MAX_CHUNK_BYTES`] on one chunk unpacked and
//! [`MAX_UNPACKED_BYTES`] on all of them, both checked from the chunk headers
//! before unpacking. Every length inside a message (a string, the ranges, the
//! transforms) is checked against the bytes that remain in it before anything
//! is allocated.

pub mod cdr;
pub mod frames;
pub mod mcap_read;
pub mod msgs;
pub mod write;

#[cfg(test)]
pub(crate) mod tests;

pub use frames::{BagLog, OdometrySource, TopicChoice};
pub use mcap_read::{ChannelInfo, McapHeader};
pub use write::{BagWriteError, BagWriteOptions, write_bag};

use cdr::CdrError;
use msgs::{LaserScan, Odometry, PoseStamped, TfMessage, TransformStamped};
use std::collections::BTreeMap;
use std::path::Path;

/// The largest bag read, bytes: 1 GiB. A recording with cameras is larger;
/// `ros2 bag record /scan /odom /tf /tf_static` (or `mcap filter`) makes one
/// of the topics the lessons need.
pub const MAX_BAG_BYTES: u64 = 1 << 30;
/// The largest chunk unpacked, bytes: 256 MiB (rosbag2 writes chunks of 768 KiB
/// by default, the `mcap` tools 4 MiB).
pub const MAX_CHUNK_BYTES: u64 = 256 << 20;
/// The most bytes unpacked from all chunks together: 4 GiB.
pub const MAX_UNPACKED_BYTES: u64 = 4 << 30;
/// The first bytes of every MCAP file.
pub const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// The size limits a read enforces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BagLimits {
    /// Largest file, bytes.
    pub max_input_bytes: u64,
    /// Largest chunk unpacked, bytes.
    pub max_chunk_bytes: u64,
    /// Most bytes unpacked from all chunks.
    pub max_unpacked_bytes: u64,
}

impl Default for BagLimits {
    fn default() -> Self {
        Self {
            max_input_bytes: MAX_BAG_BYTES,
            max_chunk_bytes: MAX_CHUNK_BYTES,
            max_unpacked_bytes: MAX_UNPACKED_BYTES,
        }
    }
}

/// Why a bag cannot be read or used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BagError {
    /// The file, a chunk or the unpacked data is over a cap.
    #[error(
        "{what} is {bytes} bytes, over the cap of {cap} bytes; record only the topics the lesson needs (ros2 bag record /scan /odom /tf /tf_static) or cut the bag with `mcap filter`"
    )]
    TooLarge {
        /// What was too large.
        what: &'static str,
        /// Its size, bytes.
        bytes: u64,
        /// The cap, bytes.
        cap: u64,
    },
    /// A ROS 1 bag.
    #[error(
        "this is a ROS 1 bag (#ROSBAG V2.0); SLAM Lab reads ROS 2 bags in MCAP: convert it with `pip install rosbags` and `rosbags-convert --src FILE.bag --dst DIR --dst-storage mcap`, then open DIR/DIR.mcap"
    )]
    Ros1Bag,
    /// A ROS 2 bag in the SQLite3 storage.
    #[error(
        "this is a ROS 2 bag in SQLite3 storage (.db3); SLAM Lab reads MCAP: convert it with `ros2 bag convert` (output storage_id: mcap) or `rosbags-convert --src BAG_DIR --dst DIR --dst-storage mcap`"
    )]
    Sqlite3Bag,
    /// Not an MCAP file at all.
    #[error("not an MCAP file (it does not start with the MCAP magic bytes)")]
    NotMcap,
    /// The file ends in the middle of a record.
    #[error(
        "the bag is truncated: it ends in the middle of a record after {records} records ({bytes} bytes); a recording that was cut off can be repaired with `mcap recover FILE -o FIXED.mcap`"
    )]
    Truncated {
        /// The file's size, bytes.
        bytes: u64,
        /// Records read before the end.
        records: usize,
    },
    /// A record the MCAP reader refuses.
    #[error("the MCAP file is damaged after {records} records: {message}")]
    Damaged {
        /// Records read before it.
        records: usize,
        /// What the reader said.
        message: String,
    },
    /// A chunk compressed with a format this build does not unpack.
    #[error(
        "a chunk is compressed with {0:?}; SLAM Lab unpacks zstd and lz4 chunks (or none): rewrite the bag with `mcap compress --compression zstd`"
    )]
    UnsupportedCompression(String),
    /// A chunk that does not unpack or fails its CRC.
    #[error("a {compression:?}-compressed chunk is corrupt: {message}")]
    CorruptChunk {
        /// The chunk's compression.
        compression: String,
        /// What is wrong.
        message: String,
    },
    /// A message of a type SLAM Lab reads that does not decode.
    #[error("message {index} on {topic} ({type_name}) does not decode: {error}")]
    Message {
        /// The topic.
        topic: String,
        /// 1-based index among that topic's messages.
        index: usize,
        /// Its type.
        type_name: String,
        /// What is wrong.
        error: CdrError,
    },
    /// No LaserScan topic.
    #[error("the bag has no sensor_msgs/msg/LaserScan topic (its topics: {topics})")]
    NoLaserTopic {
        /// The bag's topics and types, listed.
        topics: String,
    },
    /// A topic asked for that is not there (or not of the right type).
    #[error("the bag has no {type_name} topic {wanted:?} (it has: {available})")]
    NoSuchTopic {
        /// The topic asked for.
        wanted: String,
        /// The type it must have.
        type_name: &'static str,
        /// The topics of that type.
        available: String,
    },
    /// No odometry at all.
    #[error(
        "the bag has no odometry: no nav_msgs/msg/Odometry topic and no moving transform (odom -> base_link) on /tf above the laser's frame {laser_frame:?}"
    )]
    NoOdometry {
        /// The laser's frame.
        laser_frame: String,
    },
    /// A LaserScan that contradicts itself.
    #[error("message {index} on {topic}: {message}")]
    BadScan {
        /// The topic.
        topic: String,
        /// 1-based index among its messages.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// The laser's mounting cannot be flattened onto the floor.
    #[error("{0}")]
    Mounting(String),
    /// No scan left to map.
    #[error("{0}")]
    NoScans(String),
}

/// Why a bag file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum BagFileError {
    /// The file cannot be opened or read.
    #[error("cannot read {0}: {1}")]
    Io(String, String),
    /// The file is not a usable bag.
    #[error(transparent)]
    Bag(#[from] BagError),
}

/// One topic of a bag.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TopicInfo {
    /// The topic.
    pub topic: String,
    /// Its type (`sensor_msgs/msg/LaserScan`); empty without a schema.
    pub type_name: String,
    /// Its message encoding (`cdr`).
    pub encoding: String,
    /// Its messages.
    pub messages: usize,
}

/// A message with the time the recorder logged it (ns since the epoch).
#[derive(Clone, Debug, PartialEq)]
pub struct Logged<T> {
    /// The recorder's receive time, ns.
    pub log_time: u64,
    /// The message.
    pub message: T,
}

/// Appends `message`, received at `log_time`, to `topic`'s list.
fn push_logged<T>(
    lists: &mut BTreeMap<String, Vec<Logged<T>>>,
    topic: String,
    log_time: u64,
    message: T,
) {
    lists
        .entry(topic)
        .or_default()
        .push(Logged { log_time, message });
}

/// A transform from `/tf` or `/tf_static`.
#[derive(Clone, Debug, PartialEq)]
pub struct LoggedTransform {
    /// From `/tf_static` (fixed for the whole bag).
    pub is_static: bool,
    /// The transform.
    pub transform: TransformStamped,
}

/// A ROS 2 bag's messages of the types the laser lessons read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Ros2Bag {
    /// What the file says about itself.
    pub header: McapHeader,
    /// Every topic, by name.
    pub topics: Vec<TopicInfo>,
    /// LaserScan messages by topic, in file order.
    pub scans: BTreeMap<String, Vec<Logged<LaserScan>>>,
    /// Odometry messages by topic.
    pub odometry: BTreeMap<String, Vec<Logged<Odometry>>>,
    /// PoseStamped messages by topic.
    pub poses: BTreeMap<String, Vec<Logged<PoseStamped>>>,
    /// Every transform of `/tf` and `/tf_static` (or `NS/tf`, `NS/tf_static`).
    pub transforms: Vec<LoggedTransform>,
    /// Messages not read, counted by type (with the topic for a TFMessage
    /// that is not on a TF topic, the encoding for a type not in CDR).
    pub skipped: BTreeMap<String, usize>,
}

/// What the first bytes say a laser file is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BagKind {
    /// An MCAP file.
    Mcap,
    /// A ROS 1 bag (`#ROSBAG V2.0`).
    Ros1,
    /// An SQLite3 database (a ROS 2 `.db3` bag).
    Sqlite3,
    /// None of these (a CARMEN log, perhaps compressed).
    Other,
}

impl BagKind {
    /// Recognizes a bag from its first bytes, never from the file's name.
    pub fn detect(bytes: &[u8]) -> Self {
        if bytes.starts_with(MCAP_MAGIC) {
            BagKind::Mcap
        } else if bytes.starts_with(b"#ROSBAG V") {
            BagKind::Ros1
        } else if bytes.starts_with(b"SQLite format 3\0") {
            BagKind::Sqlite3
        } else {
            BagKind::Other
        }
    }
}

/// Refuses a bag over the cap before anything is read.
pub fn check_bag_size(bytes: u64, limits: &BagLimits) -> Result<(), BagError> {
    if bytes > limits.max_input_bytes {
        return Err(BagError::TooLarge {
            what: "the bag",
            bytes,
            cap: limits.max_input_bytes,
        });
    }
    Ok(())
}

/// Is `topic` a TF topic: `/tf` (`NS/tf`) dynamic, `/tf_static` static?
fn tf_topic(topic: &str) -> Option<bool> {
    if topic == "/tf" || topic == "tf" || topic.ends_with("/tf") {
        Some(false)
    } else if topic == "/tf_static" || topic == "tf_static" || topic.ends_with("/tf_static") {
        Some(true)
    } else {
        None
    }
}

impl Ros2Bag {
    /// Reads a bag with the default [`BagLimits`].
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, BagError> {
        Self::from_bytes_with_limits(bytes, &BagLimits::default())
    }

    /// Reads a bag within `limits`.
    pub fn from_bytes_with_limits(bytes: &[u8], limits: &BagLimits) -> Result<Self, BagError> {
        check_bag_size(bytes.len() as u64, limits)?;
        match BagKind::detect(bytes) {
            BagKind::Mcap => {}
            BagKind::Ros1 => return Err(BagError::Ros1Bag),
            BagKind::Sqlite3 => return Err(BagError::Sqlite3Bag),
            BagKind::Other => return Err(BagError::NotMcap),
        }
        let mut bag = Ros2Bag::default();
        let mut counts: BTreeMap<String, TopicInfo> = BTreeMap::new();
        let header = mcap_read::read_mcap(bytes, limits, |channel, log_time, data| {
            let info = counts
                .entry(channel.topic.clone())
                .or_insert_with(|| TopicInfo {
                    topic: channel.topic.clone(),
                    type_name: channel.type_name.clone(),
                    encoding: channel.message_encoding.clone(),
                    messages: 0,
                });
            info.messages += 1;
            let index = info.messages;
            bag.message(channel, index, log_time, data)
        })?;
        bag.header = header;
        bag.topics = counts.into_values().collect();
        Ok(bag)
    }

    /// Reads a bag file, refusing one over [`MAX_BAG_BYTES`] from its size
    /// before reading it.
    pub fn read_file(path: &Path) -> Result<Self, BagFileError> {
        let io = |e: std::io::Error| BagFileError::Io(path.display().to_string(), e.to_string());
        let len = std::fs::metadata(path).map_err(io)?.len();
        check_bag_size(len, &BagLimits::default())?;
        let bytes = std::fs::read(path).map_err(io)?;
        Ok(Self::from_bytes(&bytes)?)
    }

    /// Decodes one message of a type SLAM Lab reads; counts any other.
    fn message(
        &mut self,
        channel: &ChannelInfo,
        index: usize,
        log_time: u64,
        data: &[u8],
    ) -> Result<(), BagError> {
        let type_name = channel.type_name.as_str();
        let known = matches!(
            type_name,
            msgs::LASER_SCAN | msgs::ODOMETRY | msgs::TF_MESSAGE | msgs::POSE_STAMPED
        );
        if !known {
            let name = if type_name.is_empty() {
                format!("(no schema) on {}", channel.topic)
            } else {
                type_name.to_owned()
            };
            *self.skipped.entry(name).or_insert(0) += 1;
            return Ok(());
        }
        if channel.message_encoding != "cdr" {
            *self
                .skipped
                .entry(format!("{type_name} ({})", channel.message_encoding))
                .or_insert(0) += 1;
            return Ok(());
        }
        let error = |error: CdrError| BagError::Message {
            topic: channel.topic.clone(),
            index,
            type_name: type_name.to_owned(),
            error,
        };
        let topic = channel.topic.clone();
        match type_name {
            msgs::LASER_SCAN => {
                let message = LaserScan::decode(data).map_err(error)?;
                push_logged(&mut self.scans, topic, log_time, message);
            }
            msgs::ODOMETRY => {
                let message = Odometry::decode(data).map_err(error)?;
                push_logged(&mut self.odometry, topic, log_time, message);
            }
            msgs::POSE_STAMPED => {
                let message = PoseStamped::decode(data).map_err(error)?;
                push_logged(&mut self.poses, topic, log_time, message);
            }
            _ => {
                let Some(is_static) = tf_topic(&topic) else {
                    *self
                        .skipped
                        .entry(format!("{type_name} on {topic}"))
                        .or_insert(0) += 1;
                    return Ok(());
                };
                let message = TfMessage::decode(data).map_err(error)?;
                self.transforms
                    .extend(
                        message
                            .transforms
                            .into_iter()
                            .map(|transform| LoggedTransform {
                                is_static,
                                transform,
                            }),
                    );
            }
        }
        Ok(())
    }

    /// The topics of one type, by name, with their message counts.
    pub fn topic_counts(&self, type_name: &str) -> Vec<(&str, usize)> {
        self.topics
            .iter()
            .filter(|t| t.type_name == type_name)
            .map(|t| (t.topic.as_str(), t.messages))
            .collect()
    }

    /// Every topic as `name (type, N messages)`, for messages.
    pub fn topic_list(&self) -> String {
        if self.topics.is_empty() {
            return "none".to_owned();
        }
        self.topics
            .iter()
            .map(|t| {
                format!(
                    "{} ({}, {})",
                    t.topic,
                    if t.type_name.is_empty() {
                        "no schema"
                    } else {
                        &t.type_name
                    },
                    t.messages
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The number of messages skipped (of types not read).
    pub fn skipped_messages(&self) -> usize {
        self.skipped.values().sum()
    }
}
