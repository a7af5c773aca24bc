#!/usr/bin/env bash
# Fuzzes every reader SLAM Lab gives user input to, in process, with many more
# inputs than ./test.sh (which runs 10,000 per reader):
#
#   scripts/fuzz.sh              1,000,000 mutated inputs per reader
#   scripts/fuzz.sh 50000        another count
#   SLAMLAB_FUZZ_SEED=7 scripts/fuzz.sh   another input stream (the default is 2026)
#
# Readers: ROS map YAML, PGM/PNG images, the two together (load_map), g2o, TORO and
# iSAM pose graphs, any pose-graph file (format detection), CARMEN logs, ROS 2 bags
# (MCAP) and their CDR messages, scenario JSON
# (slamlab-sim), URL query strings applied to every lesson's parameters (slamlab-app).
# Seeds are the built-in maps and ../shared/data (when it is beside the repository).
# The tests are built in the release profile (the readers run ~10x faster than in the
# test profile); each prints its inputs, accepted/refused counts, time and peak
# allocation. A failing input is saved to the temporary directory (the message says
# where). docs/robustness.md records the counts and the date of the last full run.
#
# Adding a reader: see the documentation of crates/slamlab-fuzz (src/lib.rs), then add
# its test name to FILTERS below.
set -euo pipefail

repo_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo_root"
if ! command -v cargo >/dev/null && [[ -x "$HOME/.cargo/bin/cargo" ]]; then
	export PATH="$HOME/.cargo/bin:$PATH"
fi

export SLAMLAB_FUZZ_INPUTS="${1:-1000000}"
# Every fuzz test's name ends like this.
FILTERS=(survive_mutations survives_mutations survive_mutations_together)

started=$SECONDS
echo "==> Fuzzing every reader with $SLAMLAB_FUZZ_INPUTS inputs (seed ${SLAMLAB_FUZZ_SEED:-2026})"
for crate in slamlab-sim slamlab-app; do
	# --nocapture: the per-reader counts are the result. One test thread per core. (With
	# one thread libtest prints "test NAME ... " before a count on the same line.)
	cargo test --release -p "$crate" --lib -- "${FILTERS[@]}" --nocapture 2>&1 |
		grep -E '(^|\.\.\. )fuzz |test result|panicked|FAILED|failed' || true
	[[ "${PIPESTATUS[0]}" == 0 ]] || {
		echo "scripts/fuzz.sh: $crate's fuzz tests failed (above)" >&2
		exit 1
	}
done
echo "==> Done in $((SECONDS - started)) s on $(nproc) cores, $(date -u +%Y-%m-%d)"
