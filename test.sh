#!/usr/bin/env bash
# SLAM Lab's one test command:   ./test.sh
#
# Runs every check, in this order, and stops at the first failure:
#   1. deps      scripts/install-deps.sh           (installs only what is missing)
#   2. fmt       cargo fmt --all -- --check        (code formatting)
#   3. clippy    cargo clippy --workspace --all-targets -- -D warnings
#   4. test      cargo test --workspace            (unit, integration and egui UI tests)
#   5. web-build web/build.sh                      (the WebAssembly site in web/dist)
#   6. web-test  web/test.sh                       (headless Chromium: starts, draws, runs)
#   7. desktop   scripts/desktop-smoke.sh          (the native app on a virtual screen)
# It works from a fresh clone of the repository on Debian 12 with rustup, node/npm and
# python3; a first run downloads and builds a lot (about 30 minutes on 2 cores).
#
# For quicker local runs, skip parts (everything runs by default):
#   SLAMLAB_SKIP_DEPS=1 SLAMLAB_SKIP_LINT=1 (fmt + clippy) SLAMLAB_SKIP_TEST=1
#   SLAMLAB_SKIP_WEB=1 (build + browser tests) SLAMLAB_SKIP_DESKTOP=1
# e.g.  SLAMLAB_SKIP_WEB=1 SLAMLAB_SKIP_DESKTOP=1 ./test.sh
set -euo pipefail

repo_root="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$repo_root"

# rustup's cargo, if the shell has not picked it up yet (fresh login shells in CI).
if ! command -v cargo >/dev/null && [[ -x "$HOME/.cargo/bin/cargo" ]]; then
	export PATH="$HOME/.cargo/bin:$PATH"
fi
# The egui UI tests render with wgpu; without a GPU they use Mesa's software OpenGL.
export WGPU_BACKEND="${WGPU_BACKEND:-gl}"
# A fresh clone gains nothing from incremental compilation, and its files take gigabytes.
if [[ -n "${CI:-}" ]]; then
	export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"
fi

started=$SECONDS
summary=()

print_summary() {
	echo
	echo "==================== SLAM Lab test summary ===================="
	local line
	for line in "${summary[@]}"; do echo "  $line"; done
	echo "  total: $((SECONDS - started)) s"
	# The build directory's size: the tests' binaries are the largest part of it.
	echo "  target: $(du -sh "${CARGO_TARGET_DIR:-$repo_root/target}" 2>/dev/null | cut -f1) used, $(df -h --output=avail . 2>/dev/null | tail -1 | tr -d ' ') free on this disk"
}

# What a step's output says about its tests (for the summary): cargo test's
# "test result: ok. N passed; M failed" lines, or the scripts' "N passed, M failed".
test_counts() {
	awk '
		/^test result: / { for (i = 1; i <= NF; i++) { if ($(i) ~ /^passed;?$/) p += $(i - 1); if ($(i) ~ /^failed;?$/) f += $(i - 1) }; cargo = 1 }
		/^[0-9]+ passed, [0-9]+ failed$/ { last = $0 }
		END { if (last != "") print last; else if (cargo) printf "%d passed, %d failed\n", p, f }
	' "$1"
}

# step NAME SKIP_VARIABLE COMMAND...: runs one step, records its time, stops on failure.
step() {
	local name="$1" skip_var="$2"
	shift 2
	if [[ "${!skip_var:-0}" == 1 ]]; then
		summary+=("$(printf '%-10s skipped (%s=1)' "$name" "$skip_var")")
		return
	fi
	printf '\n################ %s: %s\n' "$name" "$*"
	local step_started=$SECONDS status=0 log counts
	log="$(mktemp)"
	# tee keeps a copy of the output for the summary's test counts.
	"$@" 2>&1 | tee "$log" || status=${PIPESTATUS[0]}
	counts="$(test_counts "$log")"
	rm -f "$log"
	local took=$((SECONDS - step_started))
	if ((status != 0)); then
		summary+=("$(printf '%-10s FAILED after %s s (exit %s)%s' "$name" "$took" "$status" "${counts:+; $counts}")")
		print_summary
		echo
		echo "./test.sh stopped: step '$name' failed. To run just that step again:"
		echo "    $*"
		exit 1
	fi
	summary+=("$(printf '%-10s ok (%s s)%s' "$name" "$took" "${counts:+; $counts}")")
}

step deps SLAMLAB_SKIP_DEPS scripts/install-deps.sh
step fmt SLAMLAB_SKIP_LINT cargo fmt --all -- --check
step clippy SLAMLAB_SKIP_LINT cargo clippy --workspace --all-targets -- -D warnings
step test SLAMLAB_SKIP_TEST cargo test --workspace
step web-build SLAMLAB_SKIP_WEB web/build.sh
step web-test SLAMLAB_SKIP_WEB env SLAMLAB_NO_BUILD=1 web/test.sh
step desktop SLAMLAB_SKIP_DESKTOP scripts/desktop-smoke.sh

print_summary
echo
echo "All checks passed."
