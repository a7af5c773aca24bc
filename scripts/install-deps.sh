#!/usr/bin/env bash
# Installs what SLAM Lab's builds and tests need on a Debian 12 (bookworm) machine.
# Safe to run again and again: it installs only what is missing, and skips apt entirely
# when every package is already there. Non-interactive (for CI); as root, or through
# sudo when it is available.
#
#   scripts/install-deps.sh              everything (what ./test.sh needs)
#   scripts/install-deps.sh --web        the WebAssembly build: rustup's wasm32 target and
#                                        rust-src (tried first), else Debian's rustc-web toolchain; the wasm-bindgen
#                                        CLI, web/node_modules
#   scripts/install-deps.sh --browser    Chromium for the headless browser tests
#   scripts/install-deps.sh --desktop    Xvfb, ImageMagick, xdotool, Mesa: run the native app
#                                        without a screen (scripts/desktop-smoke.sh, UI tests)
#   scripts/install-deps.sh --rust       rustfmt and clippy (for ./test.sh's lint step)
# Flags can be combined. Assumed present (the base image): rustup's stable Rust with
# cargo, node 20 with npm, python3.
set -euo pipefail

repo_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo_root"

say() { printf '==> %s\n' "$*"; }
die() {
	printf 'install-deps.sh: error: %s\n' "$*" >&2
	exit 1
}

# --- Which parts?
want_web=0 want_browser=0 want_desktop=0 want_rust=0
if (($# == 0)); then
	want_web=1 want_browser=1 want_desktop=1 want_rust=1
fi
for arg in "$@"; do
	case "$arg" in
	--web) want_web=1 ;;
	--browser) want_browser=1 ;;
	--desktop) want_desktop=1 ;;
	--rust) want_rust=1 ;;
	--all) want_web=1 want_browser=1 want_desktop=1 want_rust=1 ;;
	-h | --help)
		sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
		exit 0
		;;
	*) die "unknown option '$arg' (try --help)" ;;
	esac
done

# Does rustup have the wasm32 target? Then Debian's wasm toolchain is not needed
# (web/build.sh prefers rustup's).
rustup_has_wasm32() {
	command -v rustup >/dev/null && rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown
}

# --- 0. The wasm32 target from rustup, when rustup can fetch it (it could not on some
# machines); otherwise Debian's rustc-web below.
if ((want_web)) && ! rustup_has_wasm32 && [[ "${SLAMLAB_WASM_TOOLCHAIN:-}" != debian ]] && command -v rustup >/dev/null; then
	say "rustup target add wasm32-unknown-unknown"
	if ! timeout 600 rustup target add wasm32-unknown-unknown; then
		say "rustup could not add the wasm32 target; using Debian's rustc-web instead"
	fi
fi
# The standard library's sources: web/build.sh then compiles std for the browser with the
# web profile's size settings (0.27 MB smaller than the prebuilt std; docs/web-build.md).
# Without them the build links rustup's prebuilt std and still works.
if ((want_web)) && rustup_has_wasm32 && [[ "${SLAMLAB_WASM_TOOLCHAIN:-}" != debian ]] &&
	[[ ! -f "$(rustc --print sysroot)/lib/rustlib/src/rust/library/sysroot/Cargo.toml" ]]; then
	say "rustup component add rust-src"
	if ! timeout 600 rustup component add rust-src; then
		say "rustup could not add rust-src; the web build links the prebuilt standard library"
	fi
fi

# --- 1. Debian packages.
packages=()
if ((want_web)) && { ! rustup_has_wasm32 || [[ "${SLAMLAB_WASM_TOOLCHAIN:-}" == debian ]]; }; then
	# rustc/cargo 1.96 for the web (/usr/bin), the standard library's sources (built
	# with -Zbuild-std, since this toolchain has no prebuilt wasm32 std) and the linker.
	packages+=(rustc-web cargo-web rust-web-src rust-web-llvm lld-22)
fi
if ((want_browser)); then
	packages+=(chromium)
fi
if ((want_desktop)); then
	# A virtual X server, screenshots (import), synthetic input, and Mesa's software
	# OpenGL (llvmpipe) that wgpu renders with when there is no GPU.
	packages+=(xvfb imagemagick xdotool libegl1 libegl-mesa0 libgl1-mesa-dri libxkbcommon-x11-0)
fi

missing=()
for package in "${packages[@]}"; do
	if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q 'install ok installed'; then
		missing+=("$package")
	fi
done

if ((${#missing[@]} == 0)); then
	((${#packages[@]} == 0)) || say "Debian packages: all ${#packages[@]} present"
else
	command -v apt-get >/dev/null ||
		die "missing packages (${missing[*]}) and no apt-get: this script knows Debian 12 only; install their equivalents by hand"
	if ((EUID == 0)); then
		as_root=(env DEBIAN_FRONTEND=noninteractive)
	elif command -v sudo >/dev/null; then
		as_root=(sudo env DEBIAN_FRONTEND=noninteractive)
	else
		die "missing packages (${missing[*]}): run this script as root, or install sudo"
	fi
	say "apt-get install ${missing[*]}"
	"${as_root[@]}" apt-get update -q
	"${as_root[@]}" apt-get install -y -q "${missing[@]}"
fi

# --- 2. rustfmt and clippy (normally part of rustup's default profile).
if ((want_rust)); then
	if cargo fmt --version >/dev/null 2>&1 && cargo clippy --version >/dev/null 2>&1; then
		say "rustfmt and clippy: present"
	else
		command -v rustup >/dev/null || die "cargo fmt / cargo clippy are missing and there is no rustup to add them"
		say "rustup component add rustfmt clippy"
		rustup component add rustfmt clippy
	fi
fi

if ((want_web)); then
	# --- 3. The wasm-bindgen CLI, exactly the version of the wasm-bindgen crate in
	# Cargo.lock, into .tools/ (web/build.sh checks this too).
	bindgen_version="$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/"/, "", $3); print $3; exit }' Cargo.lock)"
	[[ -n "$bindgen_version" ]] || die "could not find the wasm-bindgen version in Cargo.lock"
	installed_version="$(.tools/bin/wasm-bindgen --version 2>/dev/null | awk '{ print $2 }' || true)"
	if [[ "$installed_version" == "$bindgen_version" ]]; then
		say "wasm-bindgen CLI $bindgen_version: present"
	else
		say "cargo install wasm-bindgen-cli $bindgen_version into .tools/ (takes ~2 min)"
		# No --locked: the CLI's own lock file pins a crate that no longer builds here.
		cargo install wasm-bindgen-cli --version "$bindgen_version" --root "$repo_root/.tools" --force
	fi

	# --- 4. Node modules from web/package-lock.json: playwright-core (drives the system
	# Chromium; it downloads no browser) and binaryen (the wasm-opt -Oz that web/build.sh runs).
	if [[ -f web/node_modules/.package-lock.json && web/node_modules/.package-lock.json -nt web/package-lock.json ]]; then
		say "web/node_modules: up to date"
	else
		command -v npm >/dev/null || die "npm is not installed"
		say "npm ci in web/"
		if [[ -f web/package-lock.json ]]; then
			(cd web && npm ci --no-audit --no-fund)
		else
			(cd web && npm install --no-audit --no-fund)
		fi
	fi
fi

say "dependencies ready"
