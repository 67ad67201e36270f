#!/usr/bin/env bash
# Sweep throughput: the engine's `verify sweep` on the rigid body (numeric and
# exact level, 2 threads by default) against the independent numpy/scipy
# pipeline looping over the same grid (one core, bench/numpy_sweep.py), with
# the verdicts and Sigma^2 of the shared points compared. Peak memory of the
# engine is reported for 10^4 and 10^6 points (streamed output: it should not
# grow with the number of points).
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -c 'import numpy, scipy, sympy' 2>/dev/null || python3 -m pip install --quiet numpy scipy sympy
cargo build --quiet --release -p verify
out=$(mktemp -d)
spec=fixtures/rigid-body-major-axis.json
for n in 100 1000; do
  for level in --numeric ""; do
    [ "$n" = 1000 ] || [ -n "$level" ] || continue
    /usr/bin/time -f "peak_rss_kb %M" ./target/release/verify sweep $spec \
      --param I2=1/10:6:$n --param I3=1/10:6:$n $level -o "$out/rb.jsonl" 2>&1 | grep -E "points/s|peak_rss" | tr '\n' ' '
    echo "(grid ${n}x${n} ${level:-exact})"
  done
done
./target/release/verify sweep $spec --param I2=1/10:6:20 --param I3=1/10:6:20 -o "$out/small.jsonl" 2>/dev/null
python3 bench/numpy_sweep.py --count 20 --lines "$out/small.jsonl"
rm -rf "$out"
