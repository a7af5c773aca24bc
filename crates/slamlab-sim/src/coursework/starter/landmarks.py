#!/usr/bin/env python3
"""Starter code for a SLAM Lab landmark-SLAM assignment.

Reads the inputs of this folder and writes a correctly formatted, deliberately
naive estimate: dead reckoning, the commands integrated along the exact arc from
the start pose, ignoring every measurement. Grade its output
(`slamlab grade ASSIGNMENT --student ID --estimate estimate.tum`) to see
where dead reckoning stands; then replace
`estimate()` with your filter: predict with each step's control, correct with
that step's measurements.

Standard library and numpy only.  Usage:  python3 starter.py [--odometry] [OUT]
  (default: the velocity model on controls.csv; --odometry: the odometry model
  on sensor_data.dat; OUT defaults to estimate.tum)
"""

import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def read_start():
    with open(os.path.join(HERE, "start_pose.txt")) as f:
        x, y, th = (float(v) for v in f.read().split())
    return np.array([x, y, th])


def read_run():
    """{'dt': seconds, 'steps': count} from run.txt."""
    info = {}
    with open(os.path.join(HERE, "run.txt")) as f:
        for line in f:
            key, value = line.split()
            info[key] = float(value)
    return info


def read_controls():
    """[(t, v, w)] from controls.csv: the command over (t - dt, t]."""
    rows = []
    with open(os.path.join(HERE, "controls.csv")) as f:
        next(f)  # header t,v,w
        for line in f:
            t, v, w = (float(c) for c in line.split(","))
            rows.append((t, v, w))
    return rows


def read_measurements():
    """{t: [(id, range, bearing)]} from measurements.csv (ids from 1)."""
    by_time = {}
    with open(os.path.join(HERE, "measurements.csv")) as f:
        next(f)  # header t,id,range,bearing
        for line in f:
            t, i, r, b = line.split(",")
            by_time.setdefault(float(t), []).append((int(i), float(r), float(b)))
    return by_time


def read_sensor_data():
    """[(odometry (r1, t, r2), [(id, range, bearing)])], the Freiburg format."""
    steps = []
    with open(os.path.join(HERE, "sensor_data.dat")) as f:
        for line in f:
            fields = line.split()
            if not fields:
                continue
            if fields[0] == "ODOMETRY":
                steps.append(([float(v) for v in fields[1:4]], []))
            elif fields[0] == "SENSOR" and steps:
                steps[-1][1].append((int(fields[1]), float(fields[2]), float(fields[3])))
    return steps


def wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def exact_arc(pose, v, w, dt):
    x, y, th = pose
    if abs(w) < 1e-9:
        return np.array([x + v * dt * math.cos(th), y + v * dt * math.sin(th), th])
    r = v / w
    return np.array([
        x + r * (math.sin(th + w * dt) - math.sin(th)),
        y + r * (math.cos(th) - math.cos(th + w * dt)),
        wrap(th + w * dt),
    ])


def odometry_step(pose, r1, t, r2):
    x, y, th = pose
    return np.array([x + t * math.cos(th + r1), y + t * math.sin(th + r1), wrap(th + r1 + r2)])


def estimate(use_odometry):
    """[(t, x, y, theta)]: one pose at t = 0 and one after every step."""
    pose = read_start()
    if use_odometry:
        steps = read_sensor_data()
        dt = read_run()["dt"]
        out = [(0.0, *pose)]
        for k, ((r1, t, r2), _seen) in enumerate(steps, start=1):
            pose = odometry_step(pose, r1, t, r2)
            out.append((k * dt, *pose))
        return out
    out = [(0.0, *pose)]
    prev_t = 0.0
    for t, v, w in read_controls():
        pose = exact_arc(pose, v, w, t - prev_t)
        out.append((t, *pose))
        prev_t = t
    return out


def write_tum(path, rows):
    """TUM: t x y z qx qy qz qw, a rotation about z."""
    with open(path, "w") as f:
        f.write("# t x y z qx qy qz qw\n")
        for t, x, y, th in rows:
            f.write("%.9f %.9f %.9f 0 0 0 %.12f %.12f\n"
                    % (t, x, y, math.sin(th / 2.0), math.cos(th / 2.0)))


def main(argv):
    use_odometry = "--odometry" in argv
    rest = [a for a in argv if a != "--odometry"]
    out = rest[0] if rest else "estimate.tum"
    rows = estimate(use_odometry)
    write_tum(out, rows)
    print("wrote %d poses to %s" % (len(rows), out))


if __name__ == "__main__":
    main(sys.argv[1:])
