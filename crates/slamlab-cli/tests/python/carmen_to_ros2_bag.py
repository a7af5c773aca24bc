"""Converts a CARMEN log (plain or bzip2) into a ROS 2 bag in MCAP with the ROS
ecosystem's own tool, PyPI's `rosbags` (its rosbag2 writer, MCAP storage, zstd
chunks, and its Humble typestore for the message types), as an oracle that SLAM
Lab's reader did not write.

Every FLASER line becomes a sensor_msgs/msg/LaserScan on /scan (frame `laser`)
and, at the same stamp, a nav_msgs/msg/Odometry on /odom (`odom` -> `base_link`)
with the line's odometry pose; /tf_static holds `base_link -> laser` (identity).
The beam layout is SLAM Lab's reading of a FLASER record: n beams from -90°,
180°/n apart; range_max 50 m (SLAM Lab's default for FLASER), range_min 0.

usage: carmen_to_ros2_bag.py LOG OUT_DIR MAX_SCANS [big-endian]   (MAX_SCANS 0: every scan)
With `big-endian`, every message is serialized in big-endian CDR.
prints: {"scans": N, "bag": "OUT_DIR/OUT_DIR.mcap"}
"""

import bz2
import json
import math
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode
from rosbags.typesys import Stores, get_typestore

src, dst, max_scans = sys.argv[1], Path(sys.argv[2]), int(sys.argv[3])
little_endian = not (len(sys.argv) > 4 and sys.argv[4] == 'big-endian')
ts = get_typestore(Stores.ROS2_HUMBLE)
T = ts.types
Time = T['builtin_interfaces/msg/Time']
Header = T['std_msgs/msg/Header']
LaserScan = T['sensor_msgs/msg/LaserScan']
Odometry = T['nav_msgs/msg/Odometry']
TFMessage = T['tf2_msgs/msg/TFMessage']
TransformStamped = T['geometry_msgs/msg/TransformStamped']
Transform = T['geometry_msgs/msg/Transform']
Vector3 = T['geometry_msgs/msg/Vector3']
Quaternion = T['geometry_msgs/msg/Quaternion']
Pose = T['geometry_msgs/msg/Pose']
Point = T['geometry_msgs/msg/Point']
PoseWithCovariance = T['geometry_msgs/msg/PoseWithCovariance']
Twist = T['geometry_msgs/msg/Twist']
TwistWithCovariance = T['geometry_msgs/msg/TwistWithCovariance']


def stamp(t):
    sec = math.floor(t)
    nanosec = round((t - sec) * 1e9)
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return Time(sec=sec, nanosec=nanosec)


def quaternion(theta):
    return Quaternion(x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2))


opener = bz2.open if src.endswith('.bz2') else open
scans = 0
writer = Writer(dst, version=9, storage_plugin=StoragePlugin.MCAP)
writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
with opener(src, 'rt') as log, writer as w:
    scan_conn = w.add_connection('/scan', LaserScan.__msgtype__, typestore=ts)
    odom_conn = w.add_connection('/odom', Odometry.__msgtype__, typestore=ts)
    static_conn = w.add_connection('/tf_static', TFMessage.__msgtype__, typestore=ts)
    for line in log:
        f = line.split()
        if not f or f[0] != 'FLASER':
            continue
        n = int(f[1])
        ranges = np.array([float(r) for r in f[2:2 + n]], dtype=np.float32)
        ox, oy, oth = (float(v) for v in f[2 + n + 3:2 + n + 6])
        t = float(f[2 + n + 6])
        st = stamp(t)
        ns = st.sec * 1_000_000_000 + st.nanosec
        if scans == 0:
            mount = TransformStamped(
                header=Header(stamp=st, frame_id='base_link'),
                child_frame_id='laser',
                transform=Transform(
                    translation=Vector3(x=0.0, y=0.0, z=0.0), rotation=quaternion(0.0)
                ),
            )
            w.write(static_conn, ns, ts.serialize_cdr(TFMessage(transforms=[mount]), TFMessage.__msgtype__, little_endian=little_endian))
        angle_min = -math.pi / 2
        increment = math.pi / n
        scan = LaserScan(
            header=Header(stamp=st, frame_id='laser'),
            angle_min=angle_min,
            angle_max=angle_min + (n - 1) * increment,
            angle_increment=increment,
            time_increment=0.0,
            scan_time=0.0,
            range_min=0.0,
            range_max=50.0,
            ranges=ranges,
            intensities=np.array([], dtype=np.float32),
        )
        w.write(scan_conn, ns, ts.serialize_cdr(scan, LaserScan.__msgtype__, little_endian=little_endian))
        odom = Odometry(
            header=Header(stamp=st, frame_id='odom'),
            child_frame_id='base_link',
            pose=PoseWithCovariance(
                pose=Pose(position=Point(x=ox, y=oy, z=0.0), orientation=quaternion(oth)),
                covariance=np.zeros(36, dtype=np.float64),
            ),
            twist=TwistWithCovariance(
                twist=Twist(linear=Vector3(x=0.0, y=0.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=0.0)),
                covariance=np.zeros(36, dtype=np.float64),
            ),
        )
        w.write(odom_conn, ns, ts.serialize_cdr(odom, Odometry.__msgtype__, little_endian=little_endian))
        scans += 1
        if max_scans and scans >= max_scans:
            break

print(json.dumps({'scans': scans, 'bag': str(dst / (dst.name + '.mcap'))}))
