#!/usr/bin/env python3
"""Starter code for a SLAM Lab localization assignment.

Reads the map and the CARMEN log of this folder and writes a correctly
formatted, deliberately naive estimate: the wheel odometry as it is, one pose
per scan, ignoring the map and every scan. Grade its output
(`slamlab grade ASSIGNMENT --student ID --estimate estimate.tum`) to see
where odometry stands; then replace
`estimate()` with your particle filter: move the particles by each odometry
increment, weigh them by how well the scan fits the map, resample.

Standard library and numpy only.  Usage:  python3 starter.py [OUT]
  (OUT defaults to estimate.tum)
"""

import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def read_map():
    """(occupancy as a numpy array of 0 free, 1 occupied, -1 unknown, row 0 at
    the bottom; resolution in m; origin (x, y, theta))."""
    meta = {}
    with open(os.path.join(HERE, "map.yaml")) as f:
        for line in f:
            if ":" in line:
                key, value = line.split(":", 1)
                meta[key.strip()] = value.strip()
    with open(os.path.join(HERE, meta.get("image", "map.pgm")), "rb") as f:
        data = f.read()
    # Binary PGM (P5): magic, width, height, maxval, then the pixels.
    fields, pos = [], 0
    while len(fields) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            while data[pos:pos + 1] not in (b"\n", b""):
                pos += 1
            continue
        start = pos
        while not data[pos:pos + 1].isspace():
            pos += 1
        fields.append(data[start:pos])
    width, height, maxval = int(fields[1]), int(fields[2]), int(fields[3])
    pixels = np.frombuffer(data[pos + 1:pos + 1 + width * height], dtype=np.uint8)
    pixels = pixels.reshape(height, width)[::-1].astype(float) / maxval
    occupied = (1.0 - pixels) > float(meta.get("occupied_thresh", 0.65))
    free = (1.0 - pixels) < float(meta.get("free_thresh", 0.196))
    grid = np.where(occupied, 1, np.where(free, 0, -1))
    origin = [float(v) for v in meta["origin"].strip("[]").split(",")]
    return grid, float(meta["resolution"]), origin


def read_log():
    """(params, [(t, odometry (x, y, theta), ranges as a numpy array)])."""
    params, scans = {}, []
    with open(os.path.join(HERE, "robot.log")) as f:
        for line in f:
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            if fields[0] == "PARAM":
                params[fields[1]] = fields[2]
            elif fields[0] == "FLASER":
                n = int(fields[1])
                ranges = np.array([float(v) for v in fields[2:2 + n]])
                odom = tuple(float(v) for v in fields[5 + n:8 + n])
                scans.append((float(fields[8 + n]), odom, ranges))
    return params, scans


def estimate():
    """[(t, x, y, theta)]: the odometry pose at every scan."""
    _params, scans = read_log()
    return [(t, *odom) for t, odom, _ranges in scans]


def write_tum(path, rows):
    """TUM: t x y z qx qy qz qw, a rotation about z."""
    with open(path, "w") as f:
        f.write("# t x y z qx qy qz qw\n")
        for t, x, y, th in rows:
            f.write("%.6f %.9f %.9f 0 0 0 %.12f %.12f\n"
                    % (t, x, y, math.sin(th / 2.0), math.cos(th / 2.0)))


def main(argv):
    out = argv[0] if argv else "estimate.tum"
    rows = estimate()
    write_tum(out, rows)
    print("wrote %d poses to %s" % (len(rows), out))


if __name__ == "__main__":
    main(sys.argv[1:])
