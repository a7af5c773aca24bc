#!/usr/bin/env bash
# Browser tests for SLAM Lab's web build, in headless Chromium (no GPU, no display needed).
#
#   web/test.sh                  build web/dist (web/build.sh), then run web/tests/browser.test.mjs
#   SLAMLAB_NO_BUILD=1 web/test.sh   test the web/dist that is already there
#   SLAMLAB_ONLY=text web/test.sh    run only the checks whose name contains the text
#   SLAMLAB_LONG=1 web/test.sh       also map the whole Intel log in the Cartographer lesson
#   SLAMLAB_SCREENSHOTS=DIR web/test.sh   make every picture of the README and the lesson
#                                    documents into DIR (what scripts/screenshots.sh runs)
#
# Screenshots, metrics.json (time to first frame, wasm size) and result.json (every check
# and every console message) are written to web/test-output/. Look at the screenshots!
# The last line is "N passed, M failed"; the exit code is non-zero when anything failed.
# Needs: scripts/install-deps.sh --web --browser (Chromium, node modules, wasm toolchain).
set -euo pipefail

web_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$web_dir"

die() {
	printf 'web/test.sh: error: %s\n' "$*" >&2
	echo "0 passed, 1 failed"
	exit 1
}

chromium="${SLAMLAB_CHROMIUM:-/usr/bin/chromium}"
[[ -x "$chromium" ]] || die "no Chromium at $chromium: run scripts/install-deps.sh --browser (or set SLAMLAB_CHROMIUM)"
command -v node >/dev/null || die "node is not installed"

# 1. The test driver, playwright-core, from web/package-lock.json (no browser download:
#    it drives the system's Chromium).
if [[ ! -d node_modules/playwright-core ]]; then
	echo "==> npm ci (web/node_modules)"
	npm ci --no-audit --no-fund
fi

# 2. Build the site unless told not to (the repository's ./test.sh has just built it).
if [[ "${SLAMLAB_NO_BUILD:-0}" != 1 ]]; then
	./build.sh
fi
[[ -f dist/pkg/slamlab_app_bg.wasm ]] || die "web/dist is not built: run web/build.sh"

# 3. Run the tests. Old screenshots are removed so that none can be mistaken for new ones.
rm -rf test-output
mkdir -p test-output
echo "==> Browser tests (headless Chromium $("$chromium" --version 2>/dev/null | awk '{ print $2 }'))"
exec node tests/browser.test.mjs
