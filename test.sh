#!/usr/bin/env bash
# The README's test command: the Rust test suite, then the Python package's.
#
# The Python part builds the extension (python/, PyO3 + maturin, abi3; the
# dev profile) into a private virtual environment under target/python-venv,
# installing maturin, pytest, numpy and matplotlib (for
# examples/rigid_body.py) there from PyPI when they are missing, and runs the pytest suite (python/tests) and the
# package's doc examples from the repository root (they read fixtures/).
# Between the two, tests/browser/report.sh opens `verify report`'s page in
# headless Chromium (BROWSER_TESTS=0 skips it).
# Arguments go to `cargo test --workspace`.
# PYTHON_TESTS=0 skips the Python part.
set -euo pipefail
cd "$(dirname "$0")"
# Each part's end is stamped with the seconds since the start (stderr), so a
# log shows where the time goes.
part() { echo "-- test.sh: $* [${SECONDS} s]" >&2; }
cargo test --workspace "$@"
part "cargo test --workspace done"
# `verify report` in headless Chromium (installed from Debian's packages
# when missing): no console error, no fetch, every section rendered.
# BROWSER_TESTS=0 skips it.
if [ "${BROWSER_TESTS:-1}" != "0" ]; then
  tests/browser/report.sh
  part "browser test done"
fi
if [ "${PYTHON_TESTS:-1}" = "0" ]; then
  exit 0
fi
venv="$PWD/target/python-venv"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
if ! "$venv/bin/python" -c 'import maturin, pytest, numpy, matplotlib' 2>/dev/null; then
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "maturin>=1.9,<2" "pytest>=7" numpy matplotlib
fi
# The extension is a member of the workspace, built in the dev profile: on
# the engine's crates `cargo test` built, so only the binding crate compiles.
part "Python environment ready"
VIRTUAL_ENV="$venv" PATH="$venv/bin:$PATH" maturin develop --quiet -m python/Cargo.toml
part "extension built (maturin, dev profile)"
"$venv/bin/python" -m pytest -q -p no:cacheprovider python/tests --doctest-modules --pyargs energy_casimir
part "pytest done"
