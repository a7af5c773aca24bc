"""Reads a ROS 2 bag with PyPI's `rosbags` (the ROS ecosystem's reader, not SLAM
Lab's) and prints what it finds as JSON: every topic with its type and message
count, and the first and last message of /scan, /odom and /ground_truth decoded
with the Humble typestore (numbers as Python's shortest round-trip strings, so
that they parse back to the same bits).

usage: read_bag.py BAG.mcap
"""

import json
import sys

from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

ts = get_typestore(Stores.ROS2_HUMBLE)
out = {'topics': {}, 'first': {}, 'last': {}}
with Reader(sys.argv[1]) as reader:
    for topic, info in reader.topics.items():
        out['topics'][topic] = [info.msgtype, info.msgcount]
    wanted = [c for c in reader.connections if c.topic in ('/scan', '/odom', '/ground_truth')]
    counted = {}
    for conn, _timestamp, raw in reader.messages(connections=wanted):
        msg = ts.deserialize_cdr(raw, conn.msgtype)
        counted[conn.topic] = counted.get(conn.topic, 0) + 1
        if conn.topic == '/scan':
            v = {
                'sec': msg.header.stamp.sec,
                'nanosec': msg.header.stamp.nanosec,
                'frame_id': msg.header.frame_id,
                'angle_min': repr(float(msg.angle_min)),
                'angle_increment': repr(float(msg.angle_increment)),
                'range_max': repr(float(msg.range_max)),
                'ranges': len(msg.ranges),
                'range_0': repr(float(msg.ranges[0])),
            }
        elif conn.topic == '/odom':
            p = msg.pose.pose
            v = {
                'child_frame_id': msg.child_frame_id,
                'x': repr(p.position.x),
                'y': repr(p.position.y),
                'qz': repr(p.orientation.z),
                'qw': repr(p.orientation.w),
            }
        else:
            v = {'x': repr(msg.pose.position.x), 'y': repr(msg.pose.position.y), 'frame_id': msg.header.frame_id}
        out['first'].setdefault(conn.topic, v)
        out['last'][conn.topic] = v
    out['decoded'] = counted
print(json.dumps(out))
