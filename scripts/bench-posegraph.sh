#!/usr/bin/env bash
# Times gtsam 4.3.0's Levenberg-Marquardt and SLAM Lab's on the same machine in the
# same run: M3500, intel and city10000 from ../shared/data/posegraphs.
#
# gtsam is a benchmark dependency only: it goes into a throwaway virtualenv in a
# temporary directory (python3 -m venv; pip install gtsam==4.3.0), removed at exit.
#
# gtsam: readG2o, a prior on the first pose (variances 1e-6, 1e-6, 1e-8, as in the
# data folder's README), default LevenbergMarquardtParams; time = median of 3 runs of
# optimize(). SLAM Lab: the release CLI, first vertex fixed, LM; time = median of 3
# runs of `time_ms` (structure analysis + iterations, file reading excluded) with
# --target-cost = 2 × gtsam's final error × (1 + 1e-4): the time to reach gtsam's
# final cost (SLAM Lab's cost is twice gtsam's error) within 0.01 %.
#
# Usage: scripts/bench-posegraph.sh [DATA_DIR]
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/.." && pwd)"
DATA="${1:-$ROOT/../shared/data/posegraphs}"
DATASETS=(M3500.g2o intel.g2o city10000.g2o)

for f in "${DATASETS[@]}"; do
  [[ -f "$DATA/$f" ]] || { echo "missing $DATA/$f" >&2; exit 1; }
done

TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT

echo "building the release CLI…" >&2
(cd "$ROOT" && cargo build --release -q -p slamlab-cli)
SLAMLAB="$ROOT/target/release/slamlab"

echo "installing gtsam 4.3.0 into a throwaway virtualenv ($TMP/venv)…" >&2
python3 -m venv "$TMP/venv"
"$TMP/venv/bin/pip" install -q gtsam==4.3.0 >&2

cat > "$TMP/gtsam_lm.py" <<'PY'
import json, statistics, sys, time
import gtsam

path = sys.argv[1]
graph, initial = gtsam.readG2o(path, False)
k0 = min(initial.keys())
g = gtsam.NonlinearFactorGraph(graph)
g.add(gtsam.PriorFactorPose2(k0, initial.atPose2(k0),
                             gtsam.noiseModel.Diagonal.Variances([1e-6, 1e-6, 1e-8])))
times = []
for _ in range(3):
    opt = gtsam.LevenbergMarquardtOptimizer(g, initial, gtsam.LevenbergMarquardtParams())
    t0 = time.perf_counter()
    result = opt.optimize()
    times.append((time.perf_counter() - t0) * 1e3)
print(json.dumps({
    "initial_error": graph.error(initial),
    "final_error": graph.error(result),
    "iterations": opt.iterations(),
    "time_ms": statistics.median(times),
}))
PY

echo "machine: $(uname -m), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "date: $(date -u +%Y-%m-%dT%H:%MZ)"
printf '%-14s | %-28s | %-44s | %s\n' "dataset" "gtsam LM: final cost (x2), it, ms" "SLAM Lab LM: cost at target, steps, ms" "ratio"
for f in "${DATASETS[@]}"; do
  G="$("$TMP/venv/bin/python" "$TMP/gtsam_lm.py" "$DATA/$f")"
  read -r GCOST GIT GMS < <(python3 -c "import json,sys; d=json.loads(sys.argv[1]); print(2*d['final_error'], d['iterations'], d['time_ms'])" "$G")
  TARGET="$(python3 -c "print($GCOST * (1 + 1e-4))")"
  RUNS=()
  for _ in 1 2 3; do
    RUNS+=("$("$SLAMLAB" graph optimize "$DATA/$f" --solver lm --target-cost "$TARGET" --json)")
  done
  read -r OCOST OIT OMS < <(python3 - "${RUNS[@]}" <<'PY'
import json, statistics, sys
runs = [json.loads(r) for r in sys.argv[1:]]
print(runs[0]["final_cost"], runs[0]["iterations"], statistics.median(r["time_ms"] for r in runs))
PY
)
  printf '%-14s | %12.6g, %2d it, %7.1f ms | %12.6g, %2d steps, %7.1f ms            | %.2f\n' \
    "$f" "$GCOST" "$GIT" "$GMS" "$OCOST" "$OIT" "$OMS" "$(python3 -c "print($OMS / $GMS)")"
done

# MITb: SLAM Lab's pose-pose error is thesis Eq. 4.5 (g2o's), gtsam's is the SE(2)
# logarithm; at MITb's large residuals the two costs differ. Evaluate each cost at
# the other's optimum.
if [[ -f "$DATA/MITb.g2o" ]]; then
  "$SLAMLAB" graph optimize "$DATA/MITb.g2o" --solver lm --out "$TMP/mitb_slamlab.g2o" --json > "$TMP/mitb.json" 2>/dev/null
  cat > "$TMP/cross.py" <<'PY'
import json, sys
import gtsam
data, ours_path, gtsam_out = sys.argv[1:4]
graph, initial = gtsam.readG2o(data, False)
k0 = min(initial.keys())
g = gtsam.NonlinearFactorGraph(graph)
g.add(gtsam.PriorFactorPose2(k0, initial.atPose2(k0), gtsam.noiseModel.Diagonal.Variances([1e-6, 1e-6, 1e-8])))
result = gtsam.LevenbergMarquardtOptimizer(g, initial, gtsam.LevenbergMarquardtParams()).optimize()
gtsam.writeG2o(graph, result, gtsam_out)
_, ours = gtsam.readG2o(ours_path, False)
print(json.dumps({"gtsam_error_at_gtsam_optimum": graph.error(result),
                  "gtsam_error_at_slamlab_optimum": graph.error(ours)}))
PY
  X="$("$TMP/venv/bin/python" "$TMP/cross.py" "$DATA/MITb.g2o" "$TMP/mitb_slamlab.g2o" "$TMP/mitb_gtsam.g2o")"
  OURS_AT_GTSAM="$("$SLAMLAB" graph optimize "$TMP/mitb_gtsam.g2o" --max-iterations 1 --json 2>/dev/null | python3 -c "import json,sys; print(json.load(sys.stdin)['initial_cost'])")"
  python3 - "$X" "$TMP/mitb.json" "$OURS_AT_GTSAM" <<'PY'
import json, sys
x = json.loads(sys.argv[1]); ours = json.load(open(sys.argv[2])); at_gtsam = float(sys.argv[3])
print("MITb, each cost at each optimum (SLAM Lab cost = Σ eᵀΩe with Eq. 4.5; gtsam cost = 2 × graph.error):")
print(f"  at SLAM Lab's optimum: SLAM Lab cost {ours['final_cost']:.4f}, gtsam cost {2 * x['gtsam_error_at_slamlab_optimum']:.4f}")
print(f"  at gtsam's optimum:    SLAM Lab cost {at_gtsam:.4f}, gtsam cost {2 * x['gtsam_error_at_gtsam_optimum']:.4f}")
PY
fi
