#!/usr/bin/env python3
"""Starter code for a SLAM Lab two-view assignment (the essential matrix with
RANSAC).

Reads the intrinsics (K.txt) and the pixel matches (matches.csv: u1,v1,u2,v2)
of this folder and writes a correctly formatted, deliberately naive relative
pose: no rotation, the camera moved straight ahead (R = I, t = (0, 0, -1):
camera b's centre -R^T t = (0, 0, 1) in camera a's frame).
Grade its output (`slamlab grade ASSIGNMENT --student ID --estimate pose.txt`)
to see where that stands; then replace `estimate()` with RANSAC around the
eight-point algorithm: normalize the pixels with K^-1, fit E to 8 random
matches (the smallest singular vector of the 8 x 9 system, then singular
values forced to (1, 1, 0)), count the matches within a pixel or two of their
epipolar lines, keep the best E, refit it to its inliers, and decompose it
into the one (R, t) of four that puts the points in front of both cameras.

Standard library and numpy only.  Usage:  python3 starter.py [OUT]
  (OUT defaults to pose.txt)
"""

import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def read_k():
    """K as a 3 x 3 numpy array (pixels)."""
    rows = []
    with open(os.path.join(HERE, "K.txt")) as f:
        for line in f:
            line = line.split("#")[0].strip()
            if line:
                rows.append([float(v) for v in line.split()])
    return np.array(rows)


def read_matches():
    """The matches as an n x 4 numpy array: u1, v1, u2, v2 (pixels)."""
    rows = []
    with open(os.path.join(HERE, "matches.csv")) as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith(("#", "u")):
                rows.append([float(v) for v in line.split(",")])
    return np.array(rows)


def estimate(k, matches):
    """(R, t) with X_b = R X_a + t. Naive: no rotation, straight ahead."""
    return np.eye(3), np.array([0.0, 0.0, -1.0])


def write_pose(out, r, t):
    """R row by row, then t (its direction: any positive length)."""
    with open(out, "w") as f:
        f.write("# X_b = R X_a + t: R row by row, then t\n")
        for row in r:
            f.write(" ".join(repr(float(v)) for v in row) + "\n")
        f.write(" ".join(repr(float(v)) for v in t) + "\n")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "pose.txt"
    k, matches = read_k(), read_matches()
    print(f"K: fx {k[0, 0]:.1f} px, {len(matches)} matches")
    r, t = estimate(k, matches)
    write_pose(out, r, t)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
