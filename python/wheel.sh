#!/usr/bin/env bash
# Build the Python package's abi3 wheel and its sdist with maturin.
#
#   python/wheel.sh [--release] [OUTDIR]      (OUTDIR: target/wheels)
#
# Without --release the wheel is built in the dev profile, on the build
# `cargo test` made (./test.sh installs it and runs the Python tests against
# it); with --release it is the wheel to distribute: a release build of the
# engine (minutes on two cores), stripped of symbols and line tables (4.3 MB
# instead of 16 MB). The two differ only in the cargo profile and the strip.
# Needs maturin on PATH (./test.sh installs it in target/python-venv) and
# the Rust toolchain; the wheel itself needs neither.
set -euo pipefail
profile=(--profile dev)
if [ "${1:-}" = "--release" ]; then
  profile=(--release --strip)
  shift
fi
# OUTDIR is relative to where the script is called from; the default is
# the repository's target/wheels.
out="${1:-$(dirname "$0")/../target/wheels}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"
cd "$(dirname "$0")/.."
# One wheel and one sdist in OUTDIR: older builds of this version go first,
# so `pip install OUTDIR/*.whl` takes the one just built.
rm -f "$out"/energy_casimir-*.whl "$out"/energy_casimir-*.tar.gz
maturin build --quiet -m python/Cargo.toml "${profile[@]}" --out "$out"
maturin sdist -m python/Cargo.toml --out "$out"
ls "$out"/energy_casimir-*.whl "$out"/energy_casimir-*.tar.gz
