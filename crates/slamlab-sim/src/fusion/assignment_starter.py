#!/usr/bin/env python3
"""Starter code for a SLAM Lab sensor-fusion assignment.

Reads the sensor files of this folder (odometry.csv, imu.csv, slam_pose.csv:
one CSV per sensor, the time t_s first, each column's unit in its name) and
writes a correctly formatted, deliberately naive estimate: dead reckoning from
the wheel odometry alone, one pose every 0.1 s. Grade its output
(`slamlab grade ASSIGNMENT --student ID --estimate estimate.tum`) to see where
the odometry alone stands; then replace `estimate()` with your filter: predict
with the odometry (and the IMU's yaw rate), correct with the SLAM poses.

Standard library and numpy only.  Usage:  python3 starter.py [OUT]
  (OUT defaults to estimate.tum)
"""

import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def read_csv(name):
    """(column names, a numpy array of the rows), or None when the file is not
    in this folder (a sensor the assignment does not hand out)."""
    path = os.path.join(HERE, name)
    if not os.path.exists(path):
        return None
    with open(path) as f:
        header = f.readline().strip().split(",")
    rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return header, rows


def arc(x, y, th, v, w, dt):
    """The pose after driving at speed v and yaw rate w for dt seconds along an
    exact arc (a straight line when w*dt is tiny)."""
    phi = w * dt
    if abs(phi) < 1e-4:
        a = 1.0 - phi * phi / 6.0
        b = phi * (0.5 - phi * phi / 24.0)
    else:
        a = math.sin(phi) / phi
        b = (1.0 - math.cos(phi)) / phi
    d = v * dt
    c, s = math.cos(th), math.sin(th)
    x += d * (c * a - s * b)
    y += d * (s * a + c * b)
    th = math.atan2(math.sin(th + phi), math.cos(th + phi))
    return x, y, th


def estimate():
    """[(t, x, y, theta)]: dead reckoning from the odometry, every 0.1 s from
    t = 0 to the end of the drive (the last odometry reading's time)."""
    _header, odo = read_csv("odometry.csv")
    # The other sensors, for your filter:
    _imu = read_csv("imu.csv")          # t, gyro z, accel x, accel y
    _slam = read_csv("slam_pose.csv")   # t, x, y, theta
    end = odo[-1, 0]
    steps = int(round(end * 10.0))
    x = y = th = 0.0
    held = None          # (t, v, w) of the last reading applied
    k = 0
    rows = []
    for i in range(steps + 1):
        t = i / 10.0
        while k < len(odo) and odo[k, 0] <= t:
            if held is not None:
                x, y, th = arc(x, y, th, held[1], held[2], odo[k, 0] - held[0])
            held = (odo[k, 0], odo[k, 1], odo[k, 2])
            k += 1
        if held is None:
            rows.append((t, x, y, th))
        else:
            rows.append((t, *arc(x, y, th, held[1], held[2], t - held[0])))
    return rows


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
