#!/usr/bin/env python3
"""Starter code for a SLAM Lab ICP assignment.

Reads the two scans of this folder (scan_a.csv, scan_b.csv: x,y end points in
each scan's own frame) and writes a correctly formatted, deliberately naive
relative pose: the wheel odometry's (odometry.txt), unmatched.
Grade its output (`slamlab grade ASSIGNMENT --student ID --estimate pose.txt`)
to see where that stands; then replace `match()` with ICP: pair each point of
scan B (moved by the current guess) with its nearest point of scan A, solve
for the rigid motion that brings the pairs together, repeat until it stops
moving.

Standard library and numpy only.  Usage:  python3 starter.py [OUT]
  (OUT defaults to pose.txt)
"""

import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def read_points(name):
    """The scan's end points as an n x 2 numpy array (metres, its own frame)."""
    rows = []
    with open(os.path.join(HERE, name)) as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith(("#", "x")):
                rows.append([float(v) for v in line.split(",")])
    return np.array(rows)


def read_odometry():
    """(x, y, theta): scan B's pose in scan A's frame by the wheel odometry."""
    with open(os.path.join(HERE, "odometry.txt")) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                return tuple(float(v) for v in line.split()[:3])
    raise ValueError("odometry.txt has no numbers")


def match(a, b, guess):
    """(x, y, theta): the pose of scan B's frame in scan A's. Naive: the
    odometry's guess, unchanged."""
    return guess


def write_pose(out, x, y, theta):
    """R and t with X_b = R X_a + t: the inverse of B's pose in A's frame."""
    c, s = math.cos(-theta), math.sin(-theta)
    t = (-(c * x - s * y), -(s * x + c * y), 0.0)
    with open(out, "w") as f:
        f.write("# X_b = R X_a + t: R row by row, then t\n")
        f.write(f"{c!r} {-s!r} 0\n{s!r} {c!r} 0\n0 0 1\n")
        f.write(f"{t[0]!r} {t[1]!r} {t[2]!r}\n")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "pose.txt"
    a, b = read_points("scan_a.csv"), read_points("scan_b.csv")
    print(f"scan A: {len(a)} points, scan B: {len(b)} points")
    x, y, theta = match(a, b, read_odometry())
    write_pose(out, x, y, theta)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
