#!/usr/bin/env bash
# Makes the pictures of the README and the lesson documents from the built site, in
# headless Chromium, with the browser tests' own machinery (web/tests/screenshots.mjs):
#
#   docs/images/slamlab.png               the README's picture (the whole app, 960 x 600)
#   docs/images/lesson-ID.png             each lesson as a lecture figure, 800 x 600, for its
#                                         document
#   docs/images/lesson-ID-small.png       the telling part of it, 240 x 180, for the README's
#                                         table
#
# Each lesson opens at a fixed URL with its seed and tick= (LESSON_SHOTS in
# web/tests/screenshots.mjs), so the same build gives the same pictures.
#
#   scripts/screenshots.sh                      build web/dist (web/build.sh), then shoot
#   SLAMLAB_NO_BUILD=1 scripts/screenshots.sh   shoot the web/dist that is there
#
# Look at every picture before committing it. web/test.sh makes one lesson's pictures in
# every run (the check "screenshots: ..."), so this script cannot break unnoticed.
# Needs what web/test.sh needs: scripts/install-deps.sh --web --browser.
set -euo pipefail

repo_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SLAMLAB_SCREENSHOTS="$repo_root/docs/images" SLAMLAB_ONLY="screenshots:" exec "$repo_root/web/test.sh"
