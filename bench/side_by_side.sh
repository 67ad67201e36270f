#!/usr/bin/env bash
# Side-by-side speed of the certify pipeline: the Rust engine against the
# independent numpy/scipy implementation (bench/numpy_pipeline.py), same specs,
# same machine, same run. The numpy timing covers the pipeline after parsing
# (sympy parsing excluded), so the like-for-like Rust figure is `us_analyse`;
# `us_end_to_end` adds spec parsing and certificate building.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -c 'import numpy, scipy, sympy' 2>/dev/null || python3 -m pip install --quiet numpy scipy sympy
cargo build --quiet --release -p verify --example bench_certify
reps=${REPS:-5000}
printf '%-24s %12s %12s %12s %12s\n' spec "rust analyse" "rust e2e" "numpy" "speed-up"
for spec in fixtures/rigid-body-major-axis.json fixtures/heavy-top-asymmetric.json fixtures/lagrange-top-fast.json; do
  rust=$(./target/release/examples/bench_certify "$spec" "$reps")
  numpy=$(python3 bench/numpy_pipeline.py "$spec" --summary --bench $((reps / 5)) | tail -n 1)
  python3 - "$rust" "$numpy" <<'PY'
import json, sys
r, n = json.loads(sys.argv[1]), json.loads(sys.argv[2])
print(f"{r['name']:<24} {r['us_analyse']:>10.1f}us {r['us_end_to_end']:>10.1f}us {n['us_per_certificate']:>10.1f}us {n['us_per_certificate'] / r['us_analyse']:>10.1f}x")
PY
done
