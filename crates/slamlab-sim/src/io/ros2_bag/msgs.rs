//! The ROS 2 messages the laser lessons read and write, field by field as their
//! `.msg` files define them (ROS 2 Humble to Kilted; the layouts have not
//! changed since Foxy): `sensor_msgs/msg/LaserScan`, `nav_msgs/msg/Odometry`,
//! `tf2_msgs/msg/TFMessage` and `geometry_msgs/msg/PoseStamped`, with the
//! `builtin_interfaces/msg/Time` and `std_msgs/msg/Header` inside them.
//!
//! Decoding keeps what the lessons use and skips the rest (intensities,
//! covariances) after checking it is there.

use super::cdr::{CdrError, CdrReader, CdrWriter};
use slamlab_core::{Pose2, math};

/// The most beams a LaserScan may have (the CARMEN reader's cap as well).
pub const MAX_BEAMS: usize = 100_000;
/// The longest frame id read, bytes.
pub const MAX_FRAME_ID: usize = 1024;
/// The most transforms one TFMessage may hold.
pub const MAX_TRANSFORMS: usize = 10_000;

/// The ROS type names, as a bag's schema records name them.
pub const LASER_SCAN: &str = "sensor_msgs/msg/LaserScan";
/// `nav_msgs/msg/Odometry`.
pub const ODOMETRY: &str = "nav_msgs/msg/Odometry";
/// `tf2_msgs/msg/TFMessage`.
pub const TF_MESSAGE: &str = "tf2_msgs/msg/TFMessage";
/// `geometry_msgs/msg/PoseStamped`.
pub const POSE_STAMPED: &str = "geometry_msgs/msg/PoseStamped";

/// `builtin_interfaces/msg/Time`: seconds and nanoseconds since the epoch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds, 0 to 999,999,999.
    pub nanosec: u32,
}

impl Time {
    /// Nanoseconds since the epoch.
    pub fn nanos(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    /// The time of `nanos` nanoseconds since the epoch (seconds saturated to `i32`).
    pub fn from_nanos(nanos: i64) -> Self {
        let sec = nanos.div_euclid(1_000_000_000);
        Self {
            sec: sec.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32,
            nanosec: nanos.rem_euclid(1_000_000_000) as u32,
        }
    }

    /// The time nearest to `seconds` (a CARMEN timestamp), to the nanosecond.
    pub fn from_seconds(seconds: f64) -> Self {
        let sec = seconds.floor();
        // `seconds - sec` is exact (Sterbenz); the nanoseconds round it.
        let mut nanos = ((seconds - sec) * 1e9).round() as i64;
        let mut sec = sec as i64;
        if nanos >= 1_000_000_000 {
            sec += 1;
            nanos -= 1_000_000_000;
        }
        Self::from_nanos(sec * 1_000_000_000 + nanos)
    }

    /// Seconds, as a CARMEN timestamp.
    pub fn seconds(self) -> f64 {
        f64::from(self.sec) + f64::from(self.nanosec) * 1e-9
    }

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            sec: r.i32("stamp.sec")?,
            nanosec: r.u32("stamp.nanosec")?,
        })
    }

    fn write(self, w: &mut CdrWriter) {
        w.i32(self.sec);
        w.u32(self.nanosec);
    }
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Header {
    /// When the data was taken.
    pub stamp: Time,
    /// The frame the data is expressed in.
    pub frame_id: String,
}

impl Header {
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            stamp: Time::read(r)?,
            frame_id: r.string("header.frame_id", MAX_FRAME_ID)?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.stamp.write(w);
        w.string(&self.frame_id);
    }
}

/// A 3D rigid transform: translation (metres) and unit quaternion `[x, y, z, w]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform3 {
    /// Translation, metres.
    pub translation: [f64; 3],
    /// Rotation as a quaternion `[x, y, z, w]`.
    pub rotation: [f64; 4],
}

impl Default for Transform3 {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform3 {
    /// No translation, no rotation.
    pub const IDENTITY: Self = Self {
        translation: [0.0; 3],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };

    /// The planar transform `(x, y, θ)` lifted to 3D: a rotation `θ` about z,
    /// `q = [0, 0, sin(θ/2), cos(θ/2)]`.
    pub fn from_pose2(p: Pose2) -> Self {
        let (s, c) = math::sin_cos(p.theta / 2.0);
        Self {
            translation: [p.x, p.y, 0.0],
            rotation: [0.0, 0.0, s, c],
        }
    }

    /// The rotation matrix of the (normalized) quaternion, rows first; `None`
    /// for a quaternion that is zero or not finite.
    pub fn rotation_matrix(&self) -> Option<[[f64; 3]; 3]> {
        let [x, y, z, w] = self.rotation;
        let n2 = x * x + y * y + z * z + w * w;
        if !(n2.is_finite() && n2 > 1e-12) {
            return None;
        }
        let s = 2.0 / n2;
        Some([
            [
                1.0 - s * (y * y + z * z),
                s * (x * y - w * z),
                s * (x * z + w * y),
            ],
            [
                s * (x * y + w * z),
                1.0 - s * (x * x + z * z),
                s * (y * z - w * x),
            ],
            [
                s * (x * z - w * y),
                s * (y * z + w * x),
                1.0 - s * (x * x + y * y),
            ],
        ])
    }

    /// The heading: the angle of the rotated x axis in the xy plane,
    /// `atan2(2(wz + xy), 1 − 2(y² + z²))` (the yaw of REP-103's z-y-x Euler
    /// angles); `None` for a quaternion that is zero or not finite.
    pub fn yaw(&self) -> Option<f64> {
        let m = self.rotation_matrix()?;
        Some(math::atan2(m[1][0], m[0][0]))
    }

    /// The planar pose: translation x, y and the yaw; `None` when not finite.
    pub fn to_pose2(&self) -> Option<Pose2> {
        let [x, y, _] = self.translation;
        let yaw = self.yaw()?;
        (x.is_finite() && y.is_finite()).then(|| Pose2::new(x, y, yaw))
    }

    /// `self ∘ other`: `other` first, then `self`.
    pub fn compose(&self, other: &Self) -> Self {
        let [ax, ay, az, aw] = self.rotation;
        let [bx, by, bz, bw] = other.rotation;
        let rotation = [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ];
        let t = other.translation;
        let m =
            self.rotation_matrix()
                .unwrap_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
        let mut translation = self.translation;
        for (i, out) in translation.iter_mut().enumerate() {
            *out += m[i][0] * t[0] + m[i][1] * t[1] + m[i][2] * t[2];
        }
        Self {
            translation,
            rotation,
        }
    }

    fn read_pose(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        // geometry_msgs/Pose: Point position, Quaternion orientation.
        Ok(Self {
            translation: r.f64_array::<3>("pose.position")?,
            rotation: r.f64_array::<4>("pose.orientation")?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        for v in self.translation.iter().chain(&self.rotation) {
            w.f64(*v);
        }
    }
}

/// `sensor_msgs/msg/LaserScan` without its intensities.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LaserScan {
    /// Stamp of the first beam and the laser's frame.
    pub header: Header,
    /// Angle of the first beam, radians.
    pub angle_min: f32,
    /// Angle of the last beam, radians.
    pub angle_max: f32,
    /// Angle between beams, radians (negative: clockwise).
    pub angle_increment: f32,
    /// Time between beams, seconds.
    pub time_increment: f32,
    /// Time between scans, seconds.
    pub scan_time: f32,
    /// Shortest valid range, metres.
    pub range_min: f32,
    /// Longest valid range, metres.
    pub range_max: f32,
    /// Ranges, metres (REP 117: `+inf` no return, `-inf` too close, NaN no measurement).
    pub ranges: Vec<f32>,
}

impl LaserScan {
    /// Decodes a serialized LaserScan (intensities checked and skipped).
    pub fn decode(bytes: &[u8]) -> Result<Self, CdrError> {
        let mut r = CdrReader::new(bytes)?;
        Ok(Self {
            header: Header::read(&mut r)?,
            angle_min: r.f32("angle_min")?,
            angle_max: r.f32("angle_max")?,
            angle_increment: r.f32("angle_increment")?,
            time_increment: r.f32("time_increment")?,
            scan_time: r.f32("scan_time")?,
            range_min: r.f32("range_min")?,
            range_max: r.f32("range_max")?,
            ranges: {
                let ranges = r.f32_sequence("ranges", MAX_BEAMS)?;
                r.skip_f32_sequence("intensities", MAX_BEAMS)?;
                ranges
            },
        })
    }

    /// Serializes it (with no intensities).
    pub fn encode(&self) -> Vec<u8> {
        let mut w = CdrWriter::new();
        self.header.write(&mut w);
        for v in [
            self.angle_min,
            self.angle_max,
            self.angle_increment,
            self.time_increment,
            self.scan_time,
            self.range_min,
            self.range_max,
        ] {
            w.f32(v);
        }
        w.f32_sequence(&self.ranges);
        w.f32_sequence(&[]);
        w.finish()
    }
}

/// `nav_msgs/msg/Odometry` without its covariances.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Odometry {
    /// Stamp and the odometry frame (`odom`).
    pub header: Header,
    /// The robot's frame (`base_link`, `base_footprint`).
    pub child_frame_id: String,
    /// The robot's pose in the odometry frame.
    pub pose: Transform3,
    /// Linear velocity in the child frame, m/s.
    pub linear: [f64; 3],
    /// Angular velocity in the child frame, rad/s.
    pub angular: [f64; 3],
}

impl Odometry {
    /// Decodes a serialized Odometry.
    pub fn decode(bytes: &[u8]) -> Result<Self, CdrError> {
        let mut r = CdrReader::new(bytes)?;
        let header = Header::read(&mut r)?;
        let child_frame_id = r.string("child_frame_id", MAX_FRAME_ID)?;
        let pose = Transform3::read_pose(&mut r)?;
        r.f64_array::<36>("pose.covariance")?;
        let linear = r.f64_array::<3>("twist.linear")?;
        let angular = r.f64_array::<3>("twist.angular")?;
        r.f64_array::<36>("twist.covariance")?;
        Ok(Self {
            header,
            child_frame_id,
            pose,
            linear,
            angular,
        })
    }

    /// Serializes it (covariances zero: unknown).
    pub fn encode(&self) -> Vec<u8> {
        let mut w = CdrWriter::new();
        self.header.write(&mut w);
        w.string(&self.child_frame_id);
        self.pose.write(&mut w);
        for _ in 0..36 {
            w.f64(0.0);
        }
        for v in self.linear.iter().chain(&self.angular) {
            w.f64(*v);
        }
        for _ in 0..36 {
            w.f64(0.0);
        }
        w.finish()
    }
}

/// `geometry_msgs/msg/TransformStamped`: `child_frame_id` in `header.frame_id`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TransformStamped {
    /// Stamp and the parent frame.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// The transform `parent_from_child`.
    pub transform: Transform3,
}

/// `tf2_msgs/msg/TFMessage`: a list of transforms.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TfMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}

/// Bytes of the smallest serialized TransformStamped: stamp (8), an empty
/// frame id (4), an empty child frame id (4), seven `float64` (56).
const MIN_TRANSFORM_BYTES: usize = 72;

impl TfMessage {
    /// Decodes a serialized TFMessage.
    pub fn decode(bytes: &[u8]) -> Result<Self, CdrError> {
        let mut r = CdrReader::new(bytes)?;
        let count = r.sequence_len("transforms", MIN_TRANSFORM_BYTES, MAX_TRANSFORMS)?;
        let mut transforms = Vec::with_capacity(count);
        for _ in 0..count {
            let header = Header::read(&mut r)?;
            let child_frame_id = r.string("child_frame_id", MAX_FRAME_ID)?;
            let transform = Transform3 {
                translation: r.f64_array::<3>("transform.translation")?,
                rotation: r.f64_array::<4>("transform.rotation")?,
            };
            transforms.push(TransformStamped {
                header,
                child_frame_id,
                transform,
            });
        }
        Ok(Self { transforms })
    }

    /// Serializes it.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = CdrWriter::new();
        w.sequence_len(self.transforms.len());
        for t in &self.transforms {
            t.header.write(&mut w);
            w.string(&t.child_frame_id);
            t.transform.write(&mut w);
        }
        w.finish()
    }
}

/// `geometry_msgs/msg/PoseStamped`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseStamped {
    /// Stamp and frame.
    pub header: Header,
    /// The pose.
    pub pose: Transform3,
}

impl PoseStamped {
    /// Decodes a serialized PoseStamped.
    pub fn decode(bytes: &[u8]) -> Result<Self, CdrError> {
        let mut r = CdrReader::new(bytes)?;
        Ok(Self {
            header: Header::read(&mut r)?,
            pose: Transform3::read_pose(&mut r)?,
        })
    }

    /// Serializes it.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = CdrWriter::new();
        self.header.write(&mut w);
        self.pose.write(&mut w);
        w.finish()
    }
}

/// The `ros2msg` schema of a type SLAM Lab writes: its `.msg` text and, after
/// `=` lines, every type it uses (the concatenation rosbag2 stores; comments
/// left out). `None` for a type SLAM Lab does not write.
pub fn schema_text(type_name: &str) -> Option<String> {
    const SEP: &str =
        "================================================================================\n";
    let deps: &[(&str, &str)] = match type_name {
        LASER_SCAN => &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
        ],
        ODOMETRY => &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
            ("geometry_msgs/PoseWithCovariance", POSE_WITH_COVARIANCE),
            ("geometry_msgs/Pose", POSE),
            ("geometry_msgs/Point", POINT),
            ("geometry_msgs/Quaternion", QUATERNION),
            ("geometry_msgs/TwistWithCovariance", TWIST_WITH_COVARIANCE),
            ("geometry_msgs/Twist", TWIST),
            ("geometry_msgs/Vector3", VECTOR3),
        ],
        TF_MESSAGE => &[
            ("geometry_msgs/TransformStamped", TRANSFORM_STAMPED),
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
            ("geometry_msgs/Transform", TRANSFORM),
            ("geometry_msgs/Vector3", VECTOR3),
            ("geometry_msgs/Quaternion", QUATERNION),
        ],
        POSE_STAMPED => &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
            ("geometry_msgs/Pose", POSE),
            ("geometry_msgs/Point", POINT),
            ("geometry_msgs/Quaternion", QUATERNION),
        ],
        _ => return None,
    };
    let main = match type_name {
        LASER_SCAN => LASER_SCAN_MSG,
        ODOMETRY => ODOMETRY_MSG,
        TF_MESSAGE => TF_MESSAGE_MSG,
        _ => POSE_STAMPED_MSG,
    };
    let mut text = main.to_owned();
    for (name, body) in deps {
        text.push_str(SEP);
        text.push_str("MSG: ");
        text.push_str(name);
        text.push('\n');
        text.push_str(body);
    }
    Some(text)
}

const LASER_SCAN_MSG: &str = "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities\n";
const ODOMETRY_MSG: &str = "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n";
const TF_MESSAGE_MSG: &str = "geometry_msgs/TransformStamped[] transforms\n";
const POSE_STAMPED_MSG: &str = "std_msgs/Header header\ngeometry_msgs/Pose pose\n";
const HEADER: &str = "builtin_interfaces/Time stamp\nstring frame_id\n";
const TIME: &str = "int32 sec\nuint32 nanosec\n";
const POSE_WITH_COVARIANCE: &str = "geometry_msgs/Pose pose\nfloat64[36] covariance\n";
const POSE: &str = "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n";
const POINT: &str = "float64 x\nfloat64 y\nfloat64 z\n";
const QUATERNION: &str = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n";
const TWIST_WITH_COVARIANCE: &str = "geometry_msgs/Twist twist\nfloat64[36] covariance\n";
const TWIST: &str = "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n";
const VECTOR3: &str = "float64 x\nfloat64 y\nfloat64 z\n";
const TRANSFORM_STAMPED: &str =
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n";
const TRANSFORM: &str = "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n";
