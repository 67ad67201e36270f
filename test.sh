#!/usr/bin/env bash
# The README's test command: the Rust test suite, then the Python package's.
#
# The Python part builds the package's abi3 wheel and sdist
# (python/wheel.sh: maturin, the dev profile, with maturin in
# target/python-venv), installs the wheel into a new virtual environment
# (target/python-wheel-venv) whose PATH has no Rust toolchain, with its
# quflow and xarray extras (h5py, xarray), pytest, matplotlib (for the
# gallery, examples/*.py),
# jupytext (the gallery read as notebooks) and scipy (the quflow tests'
# independent harmonics) from PyPI, and runs the pytest
# suite (python/tests) and the package's doc examples against it, from the
# repository root (they read fixtures/).
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
# The build tools (maturin) live in one virtual environment; the package is
# tested as a user gets it: its wheel, installed into a new virtual
# environment whose PATH has no Rust toolchain.
tools="$PWD/target/python-venv"
if [ ! -x "$tools/bin/python" ]; then
  python3 -m venv "$tools"
fi
if ! "$tools/bin/python" -c 'import maturin' 2>/dev/null; then
  "$tools/bin/python" -m pip install --quiet --disable-pip-version-check "maturin>=1.9,<2"
fi
part "Python build tools ready"
# The wheel and the sdist (python/wheel.sh), in the dev profile: the
# extension is a member of the workspace, so only the binding crate
# compiles, on the engine's crates `cargo test` built.
PATH="$tools/bin:$PATH" python/wheel.sh target/wheels
part "wheel and sdist built (maturin, dev profile)"
# The sdist must carry the engine's crates the wheel is built from.
"$tools/bin/python" - <<'PY'
import glob, sys, tarfile
sdist, = glob.glob("target/wheels/energy_casimir-*.tar.gz")
names = tarfile.open(sdist).getnames()
for need in ("/pyproject.toml", "/python/src/lib.rs", "/crates/spec/src/lib.rs", "/crates/fluid/src/lib.rs"):
    if not any(n.endswith(need) for n in names):
        sys.exit(f"{sdist} has no {need}")
PY
wheel_env="$PWD/target/python-wheel-venv"
python3 -m venv --clear "$wheel_env"
no_rust_path="$wheel_env/bin:/usr/local/bin:/usr/bin:/bin"
if PATH="$no_rust_path" command -v cargo >/dev/null || PATH="$no_rust_path" command -v rustc >/dev/null; then
  echo "test.sh: the wheel's environment must have no Rust toolchain on its PATH" >&2
  exit 1
fi
PATH="$no_rust_path" "$wheel_env/bin/python" -m pip install --quiet --disable-pip-version-check \
  "$(ls target/wheels/energy_casimir-*.whl)[quflow,xarray]" "pytest>=7" matplotlib scipy jupytext
part "wheel installed into a new environment without Rust"
# From the repository root (the tests read fixtures/), against the installed
# package: python/pysrc is not on the path, and the check below says so.
PATH="$no_rust_path" "$wheel_env/bin/python" -c \
  'import energy_casimir, sys; sys.exit(0 if "site-packages" in energy_casimir.__file__ else f"tests would import {energy_casimir.__file__}")'
PATH="$no_rust_path" "$wheel_env/bin/python" -m pytest -q -p no:cacheprovider python/tests --doctest-modules --pyargs energy_casimir
part "pytest done (the installed wheel)"
