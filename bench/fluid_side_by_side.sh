#!/usr/bin/env bash
# Side-by-side on one fluid x-mode: the engine's Lanczos estimate of Sigma^2
# (banded operators in vorticity coordinates) against scipy.linalg.eigh on the
# same dense V and Q (written by verify/examples/fluid_mode.rs), same machine,
# same run. Also the engine's whole certify run at ny = 1024 with its peak
# memory (GNU time), for the compressible fixture and the incompressible one.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -c 'import numpy, scipy' 2>/dev/null || python3 -m pip install --quiet numpy scipy
cargo build --quiet --release -p verify --example fluid_mode
cargo build --quiet --release -p verify
dir=$(mktemp -d)
printf '%-28s %5s %6s %12s %12s %12s %14s %12s\n' spec n m "rust lanczos" "rust check" "scipy top" "scipy all" "rel. diff"
for case in "fixtures/fluids/channel-sin-walls.json 1" "fixtures/fluids/channel-sin-walls.json 8" "fixtures/fluids/kolmogorov-periodic.json 1"; do
  set -- $case
  rust=$(./target/release/examples/fluid_mode "$1" "$2" "$dir" 20)
  n=$(python3 -c 'import json,sys; print(json.loads(sys.argv[1])["n"])' "$rust")
  py=$(python3 bench/fluid_scipy.py "$dir" "$n" 3)
  python3 - "$1" "$2" "$rust" "$py" <<'PY'
import json, os, sys
name, m, r, p = os.path.basename(sys.argv[1]).removesuffix(".json"), sys.argv[2], json.loads(sys.argv[3]), json.loads(sys.argv[4])
diff = abs(r["sigma2"] - p["scipy_top"]) / abs(p["scipy_top"])
print(f"{name:<28} {r['n']:>5} {m:>6} {r['lanczos_ms']:>10.2f}ms {r['dense_check_ms']:>10.1f}ms {p['scipy_top_ms']:>10.1f}ms {p['scipy_all_ms']:>12.1f}ms {diff:>12.2e}")
PY
done
rm -rf "$dir"
echo
echo "whole certify runs (wall time, peak resident memory):"
for spec in fixtures/fluids/compressible-uniform-noise.json fixtures/fluids/compressible-channel.json fixtures/fluids/channel-sin-walls.json; do
  /usr/bin/time -f "  $(basename "$spec" .json): %e s, %M KB" ./target/release/verify certify "$spec" -o /dev/null 2>&1 | grep -v '^  [A-Z]' | tail -n 1
done
