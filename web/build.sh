#!/usr/bin/env bash
# Builds SLAM Lab for the browser into web/dist/, a static site that can be copied to
# any web server or static host (GitHub Pages, an S3 bucket, a university web space):
#
#   web/dist/index.html                 the app (full page; ?lesson=...&seed=...&embed=1)
#   web/dist/lecture.html               an example lecture page that embeds the app twice
#   web/dist/pkg/slamlab_app.js         wasm-bindgen's JavaScript glue
#   web/dist/pkg/slamlab_app_bg.wasm    the app itself (Rust compiled to WebAssembly)
#   web/dist/maps/                      the built-in maps as ROS map files (map=maps/office.yaml)
#
# Usage: web/build.sh            (from anywhere)
# Environment:
#   SLAMLAB_WASM_TOOLCHAIN=rustup|debian  force a toolchain (default: rustup if it has the
#                                         wasm32-unknown-unknown target, else Debian's rustc-web)
#   SLAMLAB_WASM_OPT=0                    skip binaryen's wasm-opt -Oz (from npm, web/node_modules),
#                                         which runs by default (6 to 7 min on 2 cores; -30 % raw)
#   SLAMLAB_WEB_PROFILE=release           build with the native release profile instead of `web`
#                                         (opt-level "z" with 3 for the estimators and solvers, fat
#                                         LTO, one codegen unit, no debug info: Cargo.toml's
#                                         [profile.web]; sizes and timings in docs/web-build.md)
#
# Needs: scripts/install-deps.sh --web (Debian: rustc-web, cargo-web, rust-web-src,
# rust-web-llvm, lld-22; the wasm-bindgen CLI is installed here on demand).
set -euo pipefail

repo_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo_root"

crate=slamlab-app
profile="${SLAMLAB_WEB_PROFILE:-web}"
[[ "$profile" =~ ^[a-z][a-z0-9_-]*$ ]] || { printf 'web/build.sh: error: SLAMLAB_WEB_PROFILE must be a cargo profile name, not %s\n' "$profile" >&2; exit 1; }
lib_name=slamlab_app # the crate's [lib] name: the wasm file and the JS glue are named after it
dist="$repo_root/web/dist"
tools_dir="$repo_root/.tools"
started=$SECONDS

say() { printf '\n==> %s\n' "$*"; }
die() {
	printf 'web/build.sh: error: %s\n' "$*" >&2
	exit 1
}

# --- 1. The wasm-bindgen CLI must be exactly the version of the wasm-bindgen crate in
# Cargo.lock: the JS glue it writes and the crate's generated code are one protocol.
bindgen_version="$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/"/, "", $3); print $3; exit }' Cargo.lock)"
[[ -n "$bindgen_version" ]] || die "could not find the wasm-bindgen version in Cargo.lock"
wasm_bindgen="$tools_dir/bin/wasm-bindgen"
installed_version="$("$wasm_bindgen" --version 2>/dev/null | awk '{ print $2 }' || true)"
if [[ "$installed_version" != "$bindgen_version" ]]; then
	say "Installing wasm-bindgen-cli $bindgen_version into .tools/ (was: ${installed_version:-none}; takes ~2 min)"
	# No --locked: the CLI's own lock file pins a crate that no longer builds here.
	cargo install wasm-bindgen-cli --version "$bindgen_version" --root "$tools_dir" --force
fi

# --- 2. Pick a Rust toolchain that can build for wasm32-unknown-unknown.
# (a) rustup with the wasm32 target installed (`rustup target add wasm32-unknown-unknown`).
#     It shares target/ with the native build (same compiler). With the rust-src component
#     it compiles the standard library itself, as (b) does; without, it links the prebuilt one.
# (b) Debian's rustc-web (rustup can't download targets on some machines): it ships the
#     standard library's *sources*, so cargo builds std itself (-Zbuild-std, unlocked on the
#     stable compiler by RUSTC_BOOTSTRAP=1). It uses its own target-web/ so the native
#     rustc and Debian's rustc don't keep rebuilding each other's build scripts.
toolchain="${SLAMLAB_WASM_TOOLCHAIN:-}"
if [[ -z "$toolchain" ]]; then
	if command -v rustup >/dev/null && rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown; then
		toolchain=rustup
	else
		toolchain=debian
	fi
fi

# WebAssembly SIMD (simd128): the text rasterizer (vello_cpu, through fearless_simd) then
# compiles its SIMD kernels instead of a much larger scalar fallback (docs/web-build.md).
# Every current browser runs it: Chrome and Edge 91+, Firefox 89+, Safari 16.4+. Added to
# any RUSTFLAGS already set; both toolchains below get it (with -Zbuild-std, std too).
# With --target, cargo gives RUSTFLAGS to the wasm code only, not to build scripts.
export RUSTFLAGS="${RUSTFLAGS:+$RUSTFLAGS }-C target-feature=+simd128"

# The -Zbuild-std arguments for the standard library sources in $1: std and panic_abort,
# with std's `optimize_for_size` feature where the sources have it (Rust 1.80 and later):
# compact sorting and formatting code in place of the fastest (docs/web-build.md).
build_std_args() {
	build_std=(-Zbuild-std=std,panic_abort)
	if grep -qs '^optimize_for_size' "$1/sysroot/Cargo.toml"; then
		build_std+=(-Zbuild-std-features=optimize_for_size)
	fi
}

case "$toolchain" in
rustup)
	target_dir="${CARGO_TARGET_DIR:-$repo_root/target}"
	# With rustup's rust-src component (scripts/install-deps.sh --web adds it) the standard
	# library is compiled here too, like the Debian toolchain below: with the web profile's
	# size settings and std's `optimize_for_size` (smaller sorting and formatting code),
	# 0.27 MB smaller than rustup's prebuilt std (docs/web-build.md). Without rust-src the
	# prebuilt std is linked: a working site, just a larger one.
	std_src="$(rustc --print sysroot)/lib/rustlib/src/rust/library"
	if [[ -f "$std_src/sysroot/Cargo.toml" ]]; then
		build_std_args "$std_src"
		say "Building $crate for wasm32 with rustup's $(rustc --version) and ${build_std[*]}"
		RUSTC_BOOTSTRAP=1 cargo build --lib -p "$crate" --profile "$profile" --target wasm32-unknown-unknown \
			--target-dir "$target_dir" "${build_std[@]}"
	else
		say "Building $crate for wasm32 with rustup's $(rustc --version) and its prebuilt std (no rust-src: 'rustup component add rust-src' makes the site 0.27 MB smaller)"
		cargo build --lib -p "$crate" --profile "$profile" --target wasm32-unknown-unknown --target-dir "$target_dir"
	fi
	;;
debian)
	[[ -x /usr/bin/rustc && -x /usr/bin/cargo && -d /usr/lib/rustlib/src/rust/library ]] ||
		die "no wasm toolchain: run scripts/install-deps.sh --web (Debian rustc-web, cargo-web, rust-web-src, rust-web-llvm, lld-22), or 'rustup target add wasm32-unknown-unknown'"
	/usr/bin/rustc --print target-list | grep -qx wasm32-unknown-unknown ||
		die "/usr/bin/rustc ($(/usr/bin/rustc --version)) has no wasm32 target: install Debian's rustc-web"
	target_dir="$repo_root/target-web"
	build_std_args /usr/lib/rustlib/src/rust/library
	say "Building $crate for wasm32 with Debian's $(/usr/bin/rustc --version) and ${build_std[*]}"
	# PATH=/usr/bin:/bin keeps rustup's proxies (~/.cargo/bin) out of the way;
	# CARGO_HOME is kept so the crates already downloaded for the native build are reused;
	# --lib: building the bin for wasm too would overwrite the cdylib with an empty wasm.
	env PATH=/usr/bin:/bin RUSTC=/usr/bin/rustc RUSTC_BOOTSTRAP=1 CARGO_HOME="${CARGO_HOME:-$HOME/.cargo}" \
		/usr/bin/cargo build --lib -p "$crate" --profile "$profile" --target wasm32-unknown-unknown \
		--target-dir "$target_dir" "${build_std[@]}"
	;;
*) die "SLAMLAB_WASM_TOOLCHAIN must be rustup or debian, not '$toolchain'" ;;
esac
wasm_in="$target_dir/wasm32-unknown-unknown/$profile/$lib_name.wasm"
[[ -f "$wasm_in" ]] || die "the build produced no $wasm_in"

# --- 3. wasm-bindgen turns the raw wasm into a module plus the JavaScript glue that
# loads it (`--target web`: a plain ES module, no bundler needed).
say "Running wasm-bindgen $bindgen_version"
rm -rf "$dist"
mkdir -p "$dist/pkg"
"$wasm_bindgen" --target web --no-typescript --out-dir "$dist/pkg" "$wasm_in"
wasm_out="$dist/pkg/${lib_name}_bg.wasm"

# --- 4. binaryen's optimiser, -Oz (by default; SLAMLAB_WASM_OPT=0 skips it). Only the npm
# build (web/node_modules): Debian's binaryen 108 writes a module that fails to load
# (WebAssembly.Table.set() ... invalid). The features are the ones rustc enables for
# wasm32-unknown-unknown, plus simd128 (above); wasm-opt must be told, since wasm-bindgen
# drops the target_features section.
if [[ "${SLAMLAB_WASM_OPT:-1}" != 0 ]]; then
	wasm_opt="$repo_root/web/node_modules/.bin/wasm-opt"
	if [[ ! -x "$wasm_opt" ]]; then
		say "npm's binaryen is missing: npm ci in web/"
		(cd web && npm ci --no-audit --no-fund)
	fi
	[[ -x "$wasm_opt" ]] || die "wasm-opt needs npm's binaryen: run 'npm ci' in web/ (scripts/install-deps.sh --web), or SLAMLAB_WASM_OPT=0"
	say "Optimising with wasm-opt -Oz ($("$wasm_opt" --version))"
	opt_started=$SECONDS
	before=$(stat -c %s "$wasm_out")
	"$wasm_opt" -Oz --enable-bulk-memory --enable-nontrapping-float-to-int --enable-sign-ext \
		--enable-mutable-globals --enable-reference-types --enable-multivalue --enable-simd \
		"$wasm_out" -o "$wasm_out.opt"
	mv "$wasm_out.opt" "$wasm_out"
	echo "wasm-opt: $before -> $(stat -c %s "$wasm_out") bytes in $((SECONDS - opt_started)) s"
fi

# --- 5. The pages. __BUILD_ID__ becomes a hash of the wasm, so after a new deployment
# browsers fetch the new files instead of reusing cached old ones.
build_id="$(sha256sum "$wasm_out" | cut -c1-12)"
for page in index.html lecture.html; do
	sed "s/__BUILD_ID__/$build_id/g" "web/$page" >"$dist/$page"
done
# The built-in maps as ROS map files beside the site: an example of a map an
# instructor hosts (index.html?lesson=kidnap&map=maps/office.yaml).
mkdir -p "$dist/maps"
cp assets/maps/*.yaml assets/maps/*.png "$dist/maps/"

# --- 6. Sizes: what a visitor downloads (servers usually send it gzip-compressed).
wasm_bytes=$(stat -c %s "$wasm_out")
wasm_gzip_bytes=$(gzip -9 -c "$wasm_out" | wc -c)
js_bytes=$(stat -c %s "$dist/pkg/$lib_name.js")
say "Built web/dist in $((SECONDS - started)) s ($toolchain toolchain, profile $profile, build id $build_id)"
printf '  %-28s %10s bytes raw  %10s bytes gzip -9\n' "pkg/${lib_name}_bg.wasm" "$wasm_bytes" "$wasm_gzip_bytes"
printf '  %-28s %10s bytes raw\n' "pkg/$lib_name.js" "$js_bytes"
echo "  Serve it with web/serve.sh, or copy web/dist/ to any static web host."
