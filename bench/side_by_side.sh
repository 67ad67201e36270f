#!/usr/bin/env bash
# Side-by-side speed of the certify pipeline: the Rust engine against the
# independent numpy/scipy implementation (bench/numpy_pipeline.py), same specs,
# same machine, same run. The numpy timing covers the pipeline after parsing
# (sympy parsing excluded) in floating point, so the like-for-like Rust figure
# is the numeric level in floating point (`us_analyse_numeric`:
# `generator::analyse_numeric`, what `verify sweep --numeric` runs); the
# exact-level analysis and the end-to-end certify (parsing, exact proofs,
# certificate JSON) are shown beside it.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -c 'import numpy, scipy, sympy' 2>/dev/null || python3 -m pip install --quiet numpy scipy sympy
cargo build --quiet --release -p verify --example bench_certify
reps=${REPS:-5000}
printf '%-34s %14s %12s %10s %10s %9s\n' spec "rust numeric" "rust exact" "rust e2e" "numpy" "speed-up"
for spec in fixtures/rigid-body-major-axis.json fixtures/heavy-top-asymmetric.json fixtures/lagrange-top-fast.json fixtures/lagrange-top-fluctuating-gravity.json; do
  rust=$(./target/release/examples/bench_certify "$spec" "$reps")
  numpy=$(python3 bench/numpy_pipeline.py "$spec" --summary --bench $((reps / 5)) | tail -n 1)
  python3 - "$rust" "$numpy" <<'PY'
import json, sys
r, n = json.loads(sys.argv[1]), json.loads(sys.argv[2])
print(f"{r['name']:<34} {r['us_analyse_numeric']:>12.1f}us {r['us_analyse']:>10.1f}us {r['us_end_to_end']:>8.1f}us {n['us_per_certificate']:>8.1f}us {n['us_per_certificate'] / r['us_analyse_numeric']:>8.1f}x")
PY
done
