#!/usr/bin/env bash
# Smoke test of the native (desktop) SLAM Lab app, without a screen or a GPU:
# builds it, runs it on a virtual X server (Xvfb) with Mesa's software renderer, takes
# screenshots and checks that the window really shows something, presses the run key and
# checks that the picture changes, then the stepping keys, and that the app is still alive. Screenshots and the app's log go to
# target/desktop-smoke/. The last line is "N passed, M failed".
#
#   scripts/desktop-smoke.sh
#   SLAMLAB_DESKTOP_PROFILE=release scripts/desktop-smoke.sh   (default: the dev profile,
#                                        which reuses what `cargo test` has already built)
# Needs: scripts/install-deps.sh --desktop (xvfb, imagemagick, xdotool, Mesa).
set -euo pipefail

repo_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo_root"

profile="${SLAMLAB_DESKTOP_PROFILE:-dev}"
query="lesson=landmark-slam&seed=7"
out_dir="$repo_root/target/desktop-smoke"
passed=0
failed=0

pass() {
	passed=$((passed + 1))
	echo "ok     $*"
}
fail() {
	failed=$((failed + 1))
	echo "FAILED $*"
}
finish() {
	echo "screenshots and the app's log: $out_dir"
	echo "$passed passed, $failed failed"
	if ((failed > 0)); then exit 1; fi
	exit 0
}
die() {
	printf 'desktop-smoke.sh: error: %s\n' "$*" >&2
	fail "$*"
	finish
}

for tool in Xvfb import convert compare xdotool; do
	command -v "$tool" >/dev/null || die "$tool is missing: run scripts/install-deps.sh --desktop"
done

# --- 1. Build the native app.
echo "==> cargo build -p slamlab-app --profile $profile"
cargo build -p slamlab-app --profile "$profile"
profile_dir="$profile"
[[ "$profile" == dev ]] && profile_dir=debug
app="${CARGO_TARGET_DIR:-$repo_root/target}/$profile_dir/slamlab-app"
[[ -x "$app" ]] || die "the build produced no $app"

rm -rf "$out_dir"
mkdir -p "$out_dir"

# --- 2. A virtual X server on the first free display from :99 up.
display=""
for n in $(seq 99 140); do
	if [[ ! -e "/tmp/.X11-unix/X$n" && ! -e "/tmp/.X$n-lock" ]]; then
		display=":$n"
		break
	fi
done
[[ -n "$display" ]] || die "no free X display between :99 and :140"

xvfb_pid=""
app_pid=""
runtime_dir="$(mktemp -d)"
cleanup() {
	# Stop only what this script started.
	[[ -n "$app_pid" ]] && kill "$app_pid" 2>/dev/null || true
	[[ -n "$xvfb_pid" ]] && kill "$xvfb_pid" 2>/dev/null || true
	rm -rf "$runtime_dir"
}
trap cleanup EXIT

echo "==> Xvfb $display"
Xvfb "$display" -screen 0 1440x900x24 -nolisten tcp >"$out_dir/xvfb.log" 2>&1 &
xvfb_pid=$!
export DISPLAY="$display"
for _ in $(seq 50); do
	[[ -e "/tmp/.X11-unix/X${display#:}" ]] && break
	kill -0 "$xvfb_pid" 2>/dev/null || die "Xvfb did not start (see $out_dir/xvfb.log)"
	sleep 0.2
done

# --- 3. Start the app. wgpu picks Vulkan when a Vulkan driver (lavapipe) is installed,
# and otherwise OpenGL through EGL (llvmpipe); say GL outright when there is no Vulkan.
if [[ -z "${WGPU_BACKEND:-}" ]] && ! { ldconfig -p | grep -q 'libvulkan\.so\.1' && compgen -G '/usr/share/vulkan/icd.d/*.json' >/dev/null; }; then
	export WGPU_BACKEND=gl
fi
export XDG_RUNTIME_DIR="$runtime_dir" # silences "XDG_RUNTIME_DIR is invalid"
echo "==> $app \"$query\" (WGPU_BACKEND=${WGPU_BACKEND:-auto})"
RUST_LOG="${RUST_LOG:-warn}" timeout 120 "$app" "$query" >"$out_dir/app.log" 2>&1 &
app_pid=$!

# --- 4. Wait for the window.
window=""
for _ in $(seq 120); do
	window="$(xdotool search --name '^SLAM Lab' 2>/dev/null | head -n1 || true)"
	[[ -n "$window" ]] && break
	kill -0 "$app_pid" 2>/dev/null || break
	sleep 0.5
done
if [[ -n "$window" ]]; then
	pass "the app opened its window (X window $window)"
else
	tail -n 20 "$out_dir/app.log" >&2 || true
	die "the app's window did not appear (see $out_dir/app.log)"
fi

# How much is on a screenshot: distinct colours, and the share of pixels that differ
# from the most common colour. A blank window has one colour.
colours() { convert "$1" -format '%k' info:; }
non_background_share() {
	local total top
	total=$(convert "$1" -format '%[fx:w*h]' info:)
	top=$(convert "$1" -format '%c' histogram:info:- | sort -rn | awk -F: 'NR == 1 { print $1 + 0 }')
	awk -v t="$total" -v c="$top" 'BEGIN { printf "%.4f", (t - c) / t }'
}
is_drawn() { # file -> success when it has >= 16 colours and >= 0.1 % non-background pixels
	local k share
	k=$(colours "$1")
	share=$(non_background_share "$1")
	echo "$1: $k colours, $(awk -v s="$share" 'BEGIN { printf "%.2f", 100 * s }') % non-background"
	((k >= 16)) && awk -v s="$share" 'BEGIN { exit !(s >= 0.001) }'
}

# --- 5. Screenshots until the window shows something (the first frames take a moment
# with a software renderer): the whole screen for people, the window for the check.
drawn=0
for _ in $(seq 30); do
	sleep 1
	kill -0 "$app_pid" 2>/dev/null || break
	import -window root "$out_dir/screen-1-start.png" 2>>"$out_dir/import.log" || continue
	import -window "$window" "$out_dir/window-1-start.png" 2>>"$out_dir/import.log" || continue
	if report=$(is_drawn "$out_dir/window-1-start.png"); then
		drawn=1
		break
	fi
done
if ((drawn)); then
	pass "the window is drawn, not blank ($report)"
else
	fail "the window stayed blank or the app exited (${report:-no screenshot}; see $out_dir/app.log)"
fi

# --- 6. Click into the window (keyboard focus) and press Space (run): after two seconds
# the picture must have changed. xdotool without --window sends real (XTEST) input to the
# focused window; events sent to a window directly are flagged as synthetic and ignored.
xdotool windowfocus "$window" 2>/dev/null || true
xdotool mousemove --window "$window" 640 400 click 1 2>/dev/null || true
sleep 1
import -window "$window" "$out_dir/window-2-before-run.png" 2>>"$out_dir/import.log" || true
xdotool key space 2>/dev/null || true
sleep 3
import -window root "$out_dir/screen-3-running.png" 2>>"$out_dir/import.log" || true
import -window "$window" "$out_dir/window-3-running.png" 2>>"$out_dir/import.log" || true
# Pixels that differ by more than 6 % between the two screenshots (ImageMagick prints the
# count on stderr, and exits 1 when the images differ).
changed=$(compare -metric AE -fuzz 6% "$out_dir/window-2-before-run.png" "$out_dir/window-3-running.png" \
	"$out_dir/diff-run.png" 2>&1 >/dev/null || true)
changed=${changed%% *}
if [[ "$changed" =~ ^[0-9.e+]+$ ]] && awk -v c="$changed" 'BEGIN { exit !(c >= 500) }'; then
	pass "Space runs the simulation: $changed pixels changed in 3 s"
else
	fail "the window did not change after Space (changed pixels: ${changed:-?}; see $out_dir/window-3-running.png)"
fi

# --- 7. Pause, step a tick, step a phase, reset: the app must survive them.
xdotool key space n period r 2>/dev/null || true
sleep 1
import -window root "$out_dir/screen-4-after-keys.png" 2>>"$out_dir/import.log" || true
if kill -0 "$app_pid" 2>/dev/null && ! grep -q 'panicked' "$out_dir/app.log"; then
	pass "the app is still running after Space, n, . and r"
else
	tail -n 20 "$out_dir/app.log" >&2 || true
	fail "the app exited or panicked after the key presses (see $out_dir/app.log)"
fi

finish
