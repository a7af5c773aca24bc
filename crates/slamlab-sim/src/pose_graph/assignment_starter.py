#!/usr/bin/env python3
"""Starter code for a SLAM Lab pose-graph assignment.

Reads problem.g2o of this folder and writes a correctly formatted,
deliberately naive answer: the initial guess back unchanged, every vertex
where the file put it. Grade its output
(`slamlab grade ASSIGNMENT --student ID --estimate estimate.g2o`) to see where
the initial guess stands; then replace `optimize()` with your least-squares
solver: linearize every edge's error e = t2v(z^-1 (x_i^-1 x_j)) around the
current poses, build H = sum J^T Omega J and b = sum J^T Omega e, hold the
fixed pose, solve H dx = -b, update, repeat until the cost stops falling.

Standard library and numpy only.  Usage:  python3 starter.py [OUT]
  (OUT defaults to estimate.g2o)
"""

import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def read_g2o(path):
    """(poses: {id: numpy array [x, y, theta]}, fixed: set of ids,
    edges: [(i, j, z as numpy array [dx, dy, dtheta], Omega as 3x3 numpy array)])."""
    poses, fixed, edges = {}, set(), []
    with open(path) as f:
        for line in f:
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            tag, values = fields[0], fields[1:]
            if tag == "VERTEX_SE2":
                poses[int(values[0])] = np.array([float(v) for v in values[1:4]])
            elif tag == "FIX":
                fixed.update(int(v) for v in values)
            elif tag == "EDGE_SE2":
                i, j = int(values[0]), int(values[1])
                z = np.array([float(v) for v in values[2:5]])
                a = [float(v) for v in values[5:11]]
                omega = np.array([[a[0], a[1], a[2]],
                                  [a[1], a[3], a[4]],
                                  [a[2], a[4], a[5]]])
                edges.append((i, j, z, omega))
    return poses, fixed, edges


def write_g2o(path, poses, fixed, edges):
    """Writes the graph: every pose (repr: the shortest text that reads back to
    the same number), the fixed ids, every edge as it was."""
    with open(path, "w") as f:
        for i in sorted(poses):
            x, y, theta = (float(v) for v in poses[i])
            f.write(f"VERTEX_SE2 {i} {x!r} {y!r} {theta!r}\n")
        for i in sorted(fixed):
            f.write(f"FIX {i}\n")
        for i, j, z, o in edges:
            numbers = [z[0], z[1], z[2], o[0, 0], o[0, 1], o[0, 2], o[1, 1], o[1, 2], o[2, 2]]
            f.write(f"EDGE_SE2 {i} {j} " + " ".join(repr(float(v)) for v in numbers) + "\n")


def cost(poses, edges):
    """F = sum over edges of e^T Omega e, e = t2v(z^-1 (x_i^-1 x_j))."""
    total = 0.0
    for i, j, z, omega in edges:
        xi, xj = poses[i], poses[j]
        c, s = np.cos(xi[2]), np.sin(xi[2])
        # x_i^-1 x_j, then z^-1 of that.
        d = np.array([c * (xj[0] - xi[0]) + s * (xj[1] - xi[1]),
                      -s * (xj[0] - xi[0]) + c * (xj[1] - xi[1]),
                      xj[2] - xi[2]])
        cz, sz = np.cos(z[2]), np.sin(z[2])
        e = np.array([cz * (d[0] - z[0]) + sz * (d[1] - z[1]),
                      -sz * (d[0] - z[0]) + cz * (d[1] - z[1]),
                      d[2] - z[2]])
        e[2] = (e[2] + np.pi) % (2 * np.pi) - np.pi
        total += e @ omega @ e
    return total


def optimize(poses, fixed, edges):
    """The naive answer: the initial guess unchanged. Write your solver here."""
    return poses


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "estimate.g2o"
    poses, fixed, edges = read_g2o(os.path.join(HERE, "problem.g2o"))
    print(f"{len(poses)} poses, {len(edges)} edges; initial cost {cost(poses, edges):.6e}")
    poses = optimize(poses, fixed, edges)
    print(f"final cost {cost(poses, edges):.6e}")
    write_g2o(out, poses, fixed, edges)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
