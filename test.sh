#!/usr/bin/env bash
# The tests: every Rust test of the workspace, then the Python package's
# (its wheel built with maturin and installed in a virtual environment under
# target/, then pytest). Installs what it needs from PyPI. Every test
# binary and pytest run even when an earlier one fails, so one run reports
# every failure; the exit status is non-zero if any failed.
# RTPIPE_PORTABLE_WHEEL=1 builds and tests the manylinux2014 wheel instead
# of the build host's (docs/guide/python.md, "The portable wheel").
set -euo pipefail
cd "$(dirname "$0")"
target="${CARGO_TARGET_DIR:-target}"
case "$target" in /*) ;; *) target="$PWD/$target" ;; esac
# The tests' temporary files in a directory of their own, so that what a
# run leaves behind is seen (and not mixed with other runs' in /tmp): a
# passing test removes its scratch directory, a failing one keeps it
# (docs/contributing.md).
export TMPDIR="$target/test-tmp"
rm -rf "$TMPDIR"
mkdir -p "$TMPDIR"
rust_status=0
cargo test --workspace --release --no-fail-fast || rust_status=$?
left=$(find "$TMPDIR" -mindepth 1 -maxdepth 1 -name 'rtpipe-*' | sort)
if [ -n "$left" ]; then
  echo "the tests left these in $TMPDIR:" >&2
  echo "$left" >&2
  # A failing test keeps its directory on purpose; a passing run leaves none.
  if [ "$rust_status" -eq 0 ]; then rust_status=1; fi
fi

echo "== Python package: wheel (maturin), install, pytest"
venv="$target/pyenv"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv" 2>/dev/null || {
    apt-get update -qq && apt-get install -y -qq python3-venv python3-pip
    python3 -m venv "$venv"
  }
fi
# Absolute paths, whether CARGO_TARGET_DIR is relative or not.
target_abs=$(cd "$target" && pwd)
"$venv/bin/pip" install -q --disable-pip-version-check "maturin>=1.5,<2" "pytest>=7" "numpy>=1.20" "pyarrow>=12" "ray>=2.9" "matplotlib>=3.5" "polars>=1" "pandas>=2" "mypy>=1.5"
rm -rf "$target/wheels"
if [ "${RTPIPE_PORTABLE_WHEEL:-0}" = 1 ]; then
  # The manylinux2014 wheel (glibc 2.17+), linked by zig: a second
  # compile of the whole workspace (its own target tree), so opt-in.
  "$venv/bin/pip" install -q --disable-pip-version-check "ziglang" "auditwheel"
  PATH="$target_abs/pyenv/bin:$PATH" "$venv/bin/maturin" build --release -q -m crates/python/Cargo.toml \
    --compatibility manylinux2014 --zig -o "$target/wheels"
  "$venv/bin/auditwheel" show "$target"/wheels/rtpipe-*.whl
else
  # The build host's glibc tag: the tests' compile, reused.
  "$venv/bin/maturin" build --release -q -m crates/python/Cargo.toml -o "$target/wheels"
fi
wheel=$(ls "$target_abs"/wheels/rtpipe-*.whl)
"$venv/bin/pip" install -q --disable-pip-version-check --force-reinstall --no-deps "$wheel"
python_status=0
RTPIPE_BIN="$target_abs/release/rtpipe" RTPIPE_WHEEL="$wheel" \
  "$venv/bin/python" -m pytest -q -p no:cacheprovider -o tmp_path_retention_policy=failed \
  crates/python/tests || python_status=$?
if [ "$rust_status" -ne 0 ] || [ "$python_status" -ne 0 ]; then
  echo "FAILED: cargo test exit $rust_status (its failing tests are listed above), pytest exit $python_status" >&2
  exit 1
fi
