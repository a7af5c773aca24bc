#!/usr/bin/env bash
# Victoria Park's pose graph (../shared/data/posegraphs/victoria_park.txt, the same
# drive as the landmark lesson's three files, 6,969 poses and 151 trees) solved by
# gtsam 4.3.0 and by SLAM Lab, and the two solutions compared pose by pose and tree
# by tree. The landmark lesson draws SLAM Lab's solution as the reference map
# (docs/real-landmark-data.md).
#
# gtsam is an oracle only: it goes into a throwaway virtualenv in a temporary
# directory (python3.11 -m venv; pip install gtsam==4.3.0), removed at exit; without
# it (no network, no wheel) the script says so and exits 0.
#
# gtsam: load2D (covariances, the odometry-chained start), a prior on the first pose
# (variances 1e-6, 1e-6, 1e-8, as in the data folder's README), default
# LevenbergMarquardtParams. SLAM Lab: the release CLI, `slamlab graph optimize
# --solver lm --max-iterations 400`, first vertex fixed. Costs: SLAM Lab's Σ eᵀΩe
# is twice gtsam's graph.error; both are printed on gtsam's convention.
#
# Usage: scripts/victoria-park-gtsam.sh [DATA_DIR]
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/.." && pwd)"
DATA="${1:-${SLAMLAB_SHARED_DATA:-$ROOT/../shared/data}/posegraphs}"
FILE="$DATA/victoria_park.txt"
[[ -f "$FILE" ]] || { echo "skipped: $FILE not found (give the posegraphs folder as the argument)" >&2; exit 0; }

TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT

echo "building the release CLI…" >&2
(cd "$ROOT" && cargo build --release -q -p slamlab-cli)
SLAMLAB="$ROOT/target/release/slamlab"

PY="$(command -v python3.11 || command -v python3)"
echo "installing gtsam 4.3.0 into a throwaway virtualenv ($TMP/venv, $("$PY" --version))…" >&2
if ! "$PY" -m venv "$TMP/venv" || ! "$TMP/venv/bin/pip" install -q gtsam==4.3.0 >&2; then
  echo "skipped: gtsam 4.3.0 could not be installed (no network or no wheel for this Python)" >&2
  exit 0
fi

cat > "$TMP/gtsam_vp.py" <<'PY'
import json, sys, time
import gtsam
path, out = sys.argv[1:3]
graph, initial = gtsam.load2D(path)
g = gtsam.NonlinearFactorGraph(graph)
g.add(gtsam.PriorFactorPose2(0, initial.atPose2(0),
                             gtsam.noiseModel.Diagonal.Variances([1e-6, 1e-6, 1e-8])))
opt = gtsam.LevenbergMarquardtOptimizer(g, initial, gtsam.LevenbergMarquardtParams())
t0 = time.perf_counter()
result = opt.optimize()
ms = (time.perf_counter() - t0) * 1e3
poses, points = {}, {}
for k in result.keys():
    s = gtsam.Symbol(k)
    if s.chr() == 0:
        p = result.atPose2(k)
        poses[int(k)] = [p.x(), p.y(), p.theta()]
    else:
        p = result.atPoint2(k)
        points[int(s.index())] = [float(p[0]), float(p[1])]
json.dump({"initial_error": graph.error(initial), "final_error": graph.error(result),
           "iterations": opt.iterations(), "time_ms": ms, "poses": poses, "points": points},
          open(out, "w"))
PY

echo "machine: $(uname -m), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "date: $(date -u +%Y-%m-%dT%H:%MZ)"
"$TMP/venv/bin/python" "$TMP/gtsam_vp.py" "$FILE" "$TMP/gtsam.json"
/usr/bin/time -f '%e s wall, %U s CPU, %M kB resident' -o "$TMP/time.txt" \
  "$SLAMLAB" graph optimize "$FILE" --solver lm --max-iterations 400 --trajectory-out "$TMP/out" --json > "$TMP/slamlab.json"

python3 - "$TMP/gtsam.json" "$TMP/slamlab.json" "$TMP/out" "$TMP/time.txt" <<'PY'
import csv, json, math, sys
g = json.load(open(sys.argv[1])); s = json.load(open(sys.argv[2])); out = sys.argv[3]
# --trajectory-out writes each pose at the time of its vertex id, and the
# landmarks by vertex id (10000 + the file's landmark number).
poses = {int(float(r["t"])): [float(r["x"]), float(r["y"]), float(r["theta"])]
         for r in csv.DictReader(open(f"{out}/optimized.csv"))}
points = {int(r["id"]) - 10000: [float(r["x"]), float(r["y"])]
          for r in csv.DictReader(open(f"{out}/optimized-landmarks.csv"))}
def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))
dp = [math.hypot(poses[int(k)][0] - v[0], poses[int(k)][1] - v[1]) for k, v in g["poses"].items()]
dth = [abs(wrap(poses[int(k)][2] - v[2])) for k, v in g["poses"].items()]
dl = [math.hypot(points[int(k)][0] - v[0], points[int(k)][1] - v[1]) for k, v in g["points"].items()]
rms = lambda xs: math.sqrt(sum(x * x for x in xs) / len(xs))
print(f"gtsam 4.3.0 LM: error {g['initial_error']:.6e} -> {g['final_error']:.6f} in {g['iterations']} iterations, {g['time_ms']:.0f} ms")
print(f"SLAM Lab LM:    error {s['initial_cost'] / 2:.6e} -> {s['final_cost'] / 2:.6f} in {s['iterations']} steps, {s['time_ms']:.0f} ms "
      f"(whole CLI run: {open(sys.argv[4]).read().strip()})")
print(f"poses ({len(dp)}): position max {max(dp):.4f} m, RMS {rms(dp):.4f} m; heading max {math.degrees(max(dth)):.4f} deg")
print(f"trees ({len(dl)}): max {max(dl):.4f} m, RMS {rms(dl):.4f} m")
PY
