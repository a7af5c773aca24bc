#!/usr/bin/env bash
# Builds SLAM Lab for the browser and serves it on this machine:
#
#   web/serve.sh                 -> http://127.0.0.1:8765/index.html?lesson=landmark-slam&seed=7
#   PORT=9000 web/serve.sh       another port
#   SLAMLAB_NO_BUILD=1 web/serve.sh   serve the web/dist that is already there
#
# Stop it with Ctrl-C. Only this computer can connect (127.0.0.1). To publish the app,
# copy web/dist/ to any static web host instead; nothing needs to run on the server.
set -euo pipefail

repo_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo_root"
port="${PORT:-8765}"

die() {
	printf 'web/serve.sh: error: %s\n' "$*" >&2
	exit 1
}

[[ "$port" =~ ^[0-9]+$ ]] && ((port > 0 && port < 65536)) || die "PORT must be a port number, not '$port'"

# 1. Refuse early, before a long build, if something already listens on the port (an old
#    web/serve.sh, for example): http.server would otherwise fail after the build.
if ! python3 - "$port" <<'PY'; then
import socket, sys
s = socket.socket()
s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as http.server does
try:
    s.bind(("127.0.0.1", int(sys.argv[1])))
except OSError:
    sys.exit(1)
PY
	die "port $port on 127.0.0.1 is already in use (an old web/serve.sh?). Stop that, or choose another port: PORT=8766 web/serve.sh"
fi

if [[ "${SLAMLAB_NO_BUILD:-0}" != 1 ]]; then
	# 2. Install whatever the web build still needs (quick when everything is there).
	scripts/install-deps.sh --web
	# 3. Build web/dist.
	web/build.sh
fi
[[ -f web/dist/index.html ]] || die "web/dist is not built: run web/build.sh"

# 4. Serve it. Python's http.server sends .wasm as application/wasm, which browsers need.
base="http://127.0.0.1:$port"
cat <<MSG

SLAM Lab is served from web/dist at $base/ (Ctrl-C to stop). Open:
  $base/index.html?lesson=landmark-slam&seed=7
  $base/lecture.html    (an example lecture page with two embedded apps)

MSG
exec python3 -m http.server "$port" --bind 127.0.0.1 --directory web/dist
