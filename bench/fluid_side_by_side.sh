#!/usr/bin/env bash
# Side-by-side on one fluid x-mode: the engine's Lanczos estimate of Sigma^2
# (banded operators in vorticity coordinates) plus its verified bound as the
# analysis first proves it (the widest rung of the margin ladder, one banded
# check on walls and periodic grids) against scipy.linalg.eigh on the same
# dense V and Q (written by verify/examples/fluid_mode.rs), same machine, same
# run. "narrow" is what a mode that sets the overall bound pays on top (the
# ladder again from its first rung; "narrowed" the margin it then holds).
# "top/eng" and "all/eng" are scipy's top eigenvalue alone and its whole
# spectrum over the engine's Lanczos + verified bound; "all/+n" the same with
# the narrowing added. Also the engine's whole certify runs with their peak
# memory (GNU time).
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -c 'import numpy, scipy' 2>/dev/null || python3 -m pip install --quiet numpy scipy
cargo build --quiet --release -p verify --example fluid_mode
cargo build --quiet --release -p verify
dir=$(mktemp -d)
printf '%-22s %5s %3s %10s %10s %10s %9s %12s %12s %8s %8s %8s %9s\n' spec n m "lanczos" "verified" "narrow" narrowed "scipy top" "scipy all" "top/eng" "all/eng" "all/+n" "rel.diff"
for case in "bench/cubic-walls.json 1 1024" "bench/cubic-walls.json 8 1024" "bench/cubic-walls.json 1 2048" "bench/cubic-walls.json 1 4096" \
            "fixtures/fluids/channel-sin-walls.json 1 1024" "fixtures/fluids/channel-sin-walls.json 8 1024" \
            "fixtures/fluids/kolmogorov-periodic.json 1 256" "fixtures/fluids/kolmogorov-periodic.json 1 1024" \
            "fixtures/fluids/kolmogorov-periodic.json 8 1024" "fixtures/fluids/kolmogorov-periodic.json 1 4096"; do
  set -- $case
  rust=$(./target/release/examples/fluid_mode "$1" "$2" "$dir" 20 "$3")
  n=$(python3 -c 'import json,sys; print(json.loads(sys.argv[1])["n"])' "$rust")
  py=$(python3 bench/fluid_scipy.py "$dir" "$n" 2)
  python3 - "$1" "$2" "$rust" "$py" <<'PY'
import json, os, sys
name, m, r, p = os.path.basename(sys.argv[1]).removesuffix(".json"), sys.argv[2], json.loads(sys.argv[3]), json.loads(sys.argv[4])
diff = abs(r["sigma2"] - p["scipy_top"]) / abs(p["scipy_top"])
ours = r["lanczos_ms"] + r["check_ms"]
narrowed = f"{r['narrowed']:.1e}" if r["narrowed"] is not None else "none"
top, whole = p["scipy_top_ms"], p["scipy_all_ms"]
print(f"{name:<22} {r['n']:>5} {m:>3} {r['lanczos_ms']:>8.2f}ms {r['check_ms']:>8.1f}ms {r['narrow_ms']:>8.1f}ms {narrowed:>9} {top:>10.1f}ms {whole:>10.1f}ms {top / ours:>7.1f}x {whole / ours:>7.1f}x {whole / (ours + r['narrow_ms']):>7.1f}x {diff:>9.1e}")
PY
done
rm -rf "$dir"
echo
echo "whole certify runs (wall time, peak resident memory):"
for spec in fixtures/fluids/compressible-uniform-noise.json fixtures/fluids/compressible-channel.json fixtures/fluids/channel-sin-walls.json bench/cubic-walls.json bench/kolmogorov-4096.json bench/compressible-2048.json; do
  /usr/bin/time -f "  $(basename "$spec" .json): %e s, %M KB" ./target/release/verify certify "$spec" -o /dev/null 2>&1 | grep -v '^  [A-Z]' | tail -n 1
done
