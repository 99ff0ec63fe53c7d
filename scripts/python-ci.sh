#!/usr/bin/env bash
# The Python package's part of CI (issue 20), also runnable alone after `cargo build --release -p
# plie-cli`: lint the extension crate, make a venv, install maturin, pytest, numpy and Ray from the
# package registry, build and install the package (release, once), run python/tests.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

echo "== python: venv and tools"
command -v python3 >/dev/null || { echo "ci: python3 not found" >&2; exit 1; }
venv=${PLIE_VENV:-$root/target/python-ci-venv}
python3 -m venv "$venv"
export PATH="$venv/bin:$PATH"   # maturin's PEP 517 hook calls `maturin`
"$venv/bin/pip" install -q --upgrade pip
"$venv/bin/pip" install -q maturin pytest numpy
if ! "$venv/bin/pip" install -q ray; then
    echo "ci: notice: could not install Ray; the farm tests will be skipped"
fi

echo "== python: the extension crate (fmt, clippy)"
export PYO3_PYTHON="$venv/bin/python"
(cd crates/plie-py && cargo fmt -- --check && CARGO_TARGET_DIR="$root/target" cargo clippy --locked --all-targets -- -D warnings)

echo "== python: build and install the package (maturin, release)"
CARGO_TARGET_DIR="$root/target" "$venv/bin/pip" install -q --no-build-isolation ./python

echo "== python: pytest"
test -x "$root/target/release/plie" || cargo build --release --locked -p plie-cli
cd python/tests
PLIE_BIN="$root/target/release/plie" "$venv/bin/python" -m pytest -q -p no:cacheprovider .
