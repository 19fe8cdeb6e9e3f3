#!/usr/bin/env bash
# Builds gradtrace with profile-guided optimisation (PGO): an instrumented build
# renders a training set of bundled scenes at low sample counts, and the final
# build lays out and inlines the code by that profile. Same images bit for bit
# (checked at the end: PGO changes no floating-point operation); faster by the
# figures in benches/README.md ("PGO build").
#
#   scripts/build_pgo.sh            -> target/pgo/release/gradtrace
#
# The release profile, in target dirs of their own (fat LTO and one codegen
# unit on top measured no faster). Needs rustup's llvm-tools (the compiler's
# own `llvm-profdata`), installed here when missing; exit status 3 when they
# cannot be had. Environment: RUSTFLAGS, as for cargo (default: the x86-64
# `rustflags` of .cargo/config.toml, which an explicit RUSTFLAGS replaces).
set -euo pipefail
cd "$(dirname "$0")/.."

# die MESSAGE [STATUS]: status 1 unless given (3: no llvm-tools to be had).
die() { echo "build_pgo.sh: $1" >&2; exit "${2:-1}"; }

sysroot=$(rustc --print sysroot)
host=$(rustc -vV | sed -n 's/^host: //p')
profdata="$sysroot/lib/rustlib/$host/bin/llvm-profdata"
if [ ! -x "$profdata" ]; then
    command -v rustup >/dev/null || die "llvm-profdata not found at $profdata and no rustup to install llvm-tools" 3
    rustup component add llvm-tools >&2 || die "rustup component add llvm-tools failed" 3
    [ -x "$profdata" ] || die "llvm-tools installed, but $profdata is missing" 3
fi

# RUSTFLAGS replaces .cargo/config.toml's rustflags (x86-64 only), so they are
# carried over.
if [ -z "${RUSTFLAGS+x}" ]; then
    RUSTFLAGS=""
    if [ "$(uname -m)" = x86_64 ]; then
        RUSTFLAGS=$(sed -n 's/^rustflags = \[\(.*\)\]/\1/p' .cargo/config.toml | tr -d '",')
    fi
fi
data=$PWD/target/pgo-profiles
rm -rf "$data"
mkdir -p "$data"

echo "== instrumented build" >&2
RUSTFLAGS="$RUSTFLAGS -Cprofile-generate=$data" \
    cargo build --release --bin gradtrace --target-dir target/pgo-instrumented
instrumented=target/pgo-instrumented/release/gradtrace
# The build's own build scripts were instrumented too: only the renders count.
rm -f "$data"/*.profraw

echo "== training renders" >&2
train=$(mktemp -d)
trap 'rm -rf "$train"' EXIT
export LLVM_PROFILE_FILE="$data/gradtrace-%p-%m.profraw"
run() { "$instrumented" "$@" --quiet --seed 1; }
# The reference path tracer on meshes, quads, spheres, glossy and bumped
# materials and environment light, its AOVs and gradients, the adaptive
# strategies and Cycles-style adaptive sampling: the paths users run.
run render scenes/cornell.toml --spp 8 --width 128 --height 128 --out "$train/cornell.exr"
run render scenes/bunny_env.toml --spp 16 --width 96 --height 96 --out "$train/bunny_env.exr"
run render scenes/spheres_table.toml --spp 8 --width 96 --height 64 --out "$train/spheres.exr"
run render scenes/glossy_teapot.toml --spp 8 --width 96 --height 72 --out "$train/teapot.exr"
run render scenes/objects_bumpy.toml --spp 8 --width 96 --height 72 --gradients --out "$train/bumpy.exr"
run render scenes/three_spheres_env.toml --spp 16 --width 96 --height 72 --strategy gradient --out "$train/adaptive.exr"
run render scenes/cornell.toml --noise-threshold 0.05 --spp 64 --width 96 --height 96 --out "$train/cycles.exr"
"$profdata" merge -o "$data/merged.profdata" "$data"/*.profraw
unset LLVM_PROFILE_FILE
# Named by its content: cargo sees the flag, not the file, so a new profile
# must change the flag to be built with.
profile="$data/merged-$(sha256sum "$data/merged.profdata" | cut -c1-16).profdata"
mv "$data/merged.profdata" "$profile"

echo "== optimised build" >&2
RUSTFLAGS="$RUSTFLAGS -Cprofile-use=$profile" \
    cargo build --release --bin gradtrace --target-dir target/pgo
built=target/pgo/release/gradtrace

# The profile may move code, never results: both builds must render the same bits.
check() { "$1" render scenes/cornell.toml --spp 4 --width 64 --height 64 --seed 7 --quiet --out "$2"; }
LLVM_PROFILE_FILE="$train/check.profraw" check "$instrumented" "$train/a.exr"
check "$built" "$train/b.exr"
"$built" diff "$train/a.exr" "$train/b.exr" --threshold 0 >/dev/null ||
    die "the PGO build renders other pixels than the instrumented one"
echo "$built"
