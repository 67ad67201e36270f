#!/usr/bin/env bash
# Simulation throughput, side by side in one run: the engine's Lie–Heun
# scheme (coadjoint-orbit preserving, all cores) against a vectorised numpy
# Stratonovich Heun (bench/numpy_heun.py, one core) on the same specs, with
# the Casimir drift of each. Also the peak memory of a 10^6-path run that
# keeps only statistics.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -c 'import numpy, sympy' 2>/dev/null || python3 -m pip install --quiet numpy sympy
cargo build --quiet --release -p simulate --example throughput
paths=${PATHS:-100000}
steps=${STEPS:-1000}
printf '%-24s %22s %22s %9s %14s %14s\n' spec "rust lie-heun (steps/s)" "numpy heun (steps/s)" "ratio" "rust drift" "numpy drift"
for spec in fixtures/rigid-body-major-axis.json fixtures/heavy-top-asymmetric.json; do
  rust=$(./target/release/examples/throughput "$spec" "$paths" "$steps")
  numpy=$(python3 bench/numpy_heun.py "$spec" "$paths" "$((steps / 5))")
  python3 - "$rust" "$numpy" <<'PY'
import json, sys
r, n = json.loads(sys.argv[1]), json.loads(sys.argv[2])
name = r["spec"]
print(f"{name:<24} {r['path_steps_per_second']:>22.3e} {n['path_steps_per_second']:>22.3e} {r['path_steps_per_second'] / n['path_steps_per_second']:>8.1f}x {r['casimir_drift']:>14.1e} {n['casimir_drift']:>14.1e}")
PY
done
echo "peak memory of 10^6 paths x 100 steps (statistics only):"
/usr/bin/time -v ./target/release/examples/throughput fixtures/rigid-body-major-axis.json 1000000 100 2>&1 | grep -E 'path_steps|Maximum resident' | sed 's/^\s*/  /'
