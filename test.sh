#!/usr/bin/env bash
# The tests: every Rust test of the workspace, then the Python package's
# (its wheel built with maturin and installed in a virtual environment under
# target/, then pytest). Installs what it needs from PyPI. Every test
# binary and pytest run even when an earlier one fails, so one run reports
# every failure; the exit status is non-zero if any failed.
set -euo pipefail
cd "$(dirname "$0")"
rust_status=0
cargo test --workspace --release --no-fail-fast || rust_status=$?

echo "== Python package: wheel (maturin), install, pytest"
target="${CARGO_TARGET_DIR:-target}"
venv="$target/pyenv"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv" 2>/dev/null || {
    apt-get update -qq && apt-get install -y -qq python3-venv python3-pip
    python3 -m venv "$venv"
  }
fi
"$venv/bin/pip" install -q --disable-pip-version-check "maturin>=1.5,<2" "pytest>=7" "numpy>=1.20" "pyarrow>=12" "ray>=2.9" "matplotlib>=3.5" "pandas>=1.5" "polars>=0.20" "mypy>=1.5"
rm -rf "$target/wheels"
"$venv/bin/maturin" build --release -q -m crates/python/Cargo.toml -o "$target/wheels"
"$venv/bin/pip" install -q --disable-pip-version-check --force-reinstall --no-deps "$target"/wheels/rtpipe-*.whl
python_status=0
RTPIPE_BIN="$PWD/$target/release/rtpipe" "$venv/bin/python" -m pytest -q -p no:cacheprovider crates/python/tests || python_status=$?
if [ "$rust_status" -ne 0 ] || [ "$python_status" -ne 0 ]; then
  echo "FAILED: cargo test exit $rust_status (its failing tests are listed above), pytest exit $python_status" >&2
  exit 1
fi
