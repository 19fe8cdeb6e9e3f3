#!/usr/bin/env bash
# Installs Intel Open Image Denoise for `cargo build --features oidn` from the
# PyPI wheel `pyoidn` (which ships libOpenImageDenoise.so 2.5 and its CPU
# device), into scripts/.venv, and prints the environment the build needs:
#
#   eval "$(scripts/setup_oidn.sh)"
#   cargo build --release --features oidn
#   cargo test --release --features oidn --test denoise
#
# Progress goes to stderr; stdout holds only `export` lines, so `eval` works.
set -euo pipefail

SCRIPTS="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
VENV="$SCRIPTS/.venv"
# The version the measurements in README.md were taken with.
PYOIDN="pyoidn==2.5.1.0"

if [[ ! -x "$VENV/bin/python" ]]; then
    echo "creating $VENV" >&2
    python3 -m venv "$VENV"
fi
if ! "$VENV/bin/python" -m pip show --quiet pyoidn >/dev/null 2>&1; then
    echo "installing $PYOIDN into $VENV" >&2
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check "$PYOIDN" >&2
fi

# The wheel's own copy of the library (not a system one that may be older).
SO="$(find "$VENV" -path '*pyoidn*' -name 'libOpenImageDenoise.so*' -print | sort | head -n 1)"
if [[ -z "$SO" ]]; then
    echo "error: no libOpenImageDenoise.so* inside the pyoidn wheel in $VENV" >&2
    exit 1
fi
LIB="$(dirname "$SO")"
# The linker looks for the unversioned name (-lOpenImageDenoise); wheels store
# files, not symlinks, and some ship only the versioned ones.
if [[ ! -e "$LIB/libOpenImageDenoise.so" ]]; then
    VERSIONED="$(find "$LIB" -maxdepth 1 -name 'libOpenImageDenoise.so.*' -print | sort | head -n 1)"
    ln -s "$(basename "$VERSIONED")" "$LIB/libOpenImageDenoise.so"
    echo "linked $LIB/libOpenImageDenoise.so -> $(basename "$VERSIONED")" >&2
fi
if [[ "$(basename "$LIB")" != "lib" ]]; then
    echo "error: $SO is not in a lib/ folder; the oidn crate expects \$OIDN_DIR/lib" >&2
    exit 1
fi

# oidn's build script links $OIDN_DIR/lib; the loader needs the same folder
# at run time (the library loads its CPU device module from there too).
echo "export OIDN_DIR=\"$(dirname "$LIB")\""
echo "export LD_LIBRARY_PATH=\"$LIB\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}\""
echo "ready: cargo build --release --features oidn" >&2
