#!/usr/bin/env python3
"""Starter code for a SLAM Lab grid-mapping assignment.

Reads the true poses (poses.csv), the scans (robot.log) and the map's grid
(map_spec.txt) of this folder and writes a correctly formatted, deliberately
naive map: every cell free, as if no scan had seen a wall. Grade its output
(`slamlab grade ASSIGNMENT --student ID --estimate map.zip`) to see where a
map that ignores the scans stands; then replace `build_map()` with occupancy
grid mapping: for every scan, at its pose, trace each beam through the grid,
lower the log-odds of the cells it crosses and raise the one it ends in.

Standard library and numpy only.  Usage:  python3 starter.py [OUT]
  (OUT defaults to map.zip; map.yaml and map.pgm are written beside it)
"""

import math
import os
import sys
import zipfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def read_spec():
    """(resolution, width, height, origin (x, y, theta))."""
    with open(os.path.join(HERE, "map_spec.txt")) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                v = line.split()
                return float(v[0]), int(v[1]), int(v[2]), tuple(float(a) for a in v[3:6])
    raise ValueError("map_spec.txt has no numbers")


def read_scans():
    """(params, [(t, true pose (x, y, theta), ranges as a numpy array)])."""
    params, scans = {}, []
    with open(os.path.join(HERE, "robot.log")) as f:
        for line in f:
            fields = line.split()
            if not fields:
                continue
            if fields[0] == "PARAM":
                params[fields[1]] = fields[2]
            elif fields[0] == "FLASER":
                n = int(fields[1])
                ranges = np.array([float(r) for r in fields[2:2 + n]])
                x, y, theta = (float(v) for v in fields[2 + n:5 + n])
                t = float(fields[8 + n])
                scans.append((t, (x, y, theta), ranges))
    return params, scans


def build_map(resolution, width, height, origin, params, scans):
    """The naive map: every cell free (0), none occupied (100), none unknown (-1).
    Rows from the bottom (row 0 at origin y). Write your mapping here."""
    return np.zeros((height, width), dtype=int)


def write_map(out, grid, resolution, origin):
    """map.yaml and map.pgm beside OUT, and both zipped into OUT."""
    folder = os.path.dirname(os.path.abspath(out))
    yaml_path, pgm_path = os.path.join(folder, "map.yaml"), os.path.join(folder, "map.pgm")
    height, width = grid.shape
    pixels = np.full((height, width), 205, dtype=np.uint8)
    pixels[grid == 0] = 254
    pixels[grid == 100] = 0
    with open(pgm_path, "wb") as f:
        f.write(f"P5\n{width} {height}\n255\n".encode())
        f.write(pixels[::-1].tobytes())  # the image's first row is the map's top
    with open(yaml_path, "w") as f:
        f.write("image: map.pgm\n")
        f.write(f"resolution: {resolution!r}\n")
        f.write(f"origin: [{origin[0]!r}, {origin[1]!r}, {origin[2]!r}]\n")
        f.write("negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        z.write(yaml_path, "map.yaml")
        z.write(pgm_path, "map.pgm")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "map.zip"
    resolution, width, height, origin = read_spec()
    params, scans = read_scans()
    print(f"{len(scans)} scans; a map of {width} x {height} cells of {resolution} m")
    grid = build_map(resolution, width, height, origin, params, scans)
    write_map(out, grid, resolution, origin)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
