"""Cost of calling the engine from Python against the Rust engine itself, in
one script, against the speed targets below:

* ``certify`` of the rigid body from Python (spec text in, certificate
  object out, the JSON parsed by ``json.loads``) against the Rust end-to-end
  ``certify`` (spec text in, certificate JSON out) timed by
  ``target/release/examples/bench_certify`` in the same run; the target is
  at most 2x;
* a 10^4-point sweep (the rigid body over a 100 x 100 grid of inertias) by
  ``energy_casimir.sweep`` against ``verify sweep`` (the release binary,
  lines to a file, process start included) on the same grid, same machine,
  same thread count, best of three each; the target is the CLI's rate
  within 20%.

Run from the repository root, with the release wheel installed into the
Python that runs it (``./test.sh`` installs a dev-profile wheel, slower)::

    python/wheel.sh --release dist && pip install dist/energy_casimir-*.whl
    cargo build --release -p verify --example bench_certify --bin verify
    python bench/python_side_by_side.py [--reps 3000] [--grid 100]
"""

import argparse
import json
import os
import subprocess
import tempfile
import time

import energy_casimir as ec

SPEC = "fixtures/rigid-body-major-axis.json"
GRID = ("I2", "I3")


def certify_python(text, reps):
    for _ in range(min(reps, 200)):  # warm-up
        ec.certify(text)
    t = time.perf_counter()
    for _ in range(reps):
        ec.certify(text)
    return (time.perf_counter() - t) / reps * 1e6


def certify_rust(reps):
    out = subprocess.check_output(["target/release/examples/bench_certify", SPEC, str(reps)], text=True)
    return json.loads(out.strip().splitlines()[-1])["us_end_to_end"]


def sweep_params(count):
    return {name: f"1/10:6:{count}" for name in GRID}


def sweep_python(count, numeric):
    t = time.perf_counter()
    cols = ec.sweep(SPEC, params=sweep_params(count), numeric=numeric)
    elapsed = time.perf_counter() - t
    return elapsed, len(cols["index"])


def best_of(runs, f):
    """The fastest of `runs` calls of f() -> (seconds, points)."""
    return min((f() for _ in range(runs)), key=lambda r: r[0])


def sweep_cli(count, numeric):
    with tempfile.TemporaryDirectory() as d:
        args = ["target/release/verify", "sweep", SPEC]
        for name, r in sweep_params(count).items():
            args += ["--param", f"{name}={r}"]
        if numeric:
            args.append("--numeric")
        args += ["-o", os.path.join(d, "lines.jsonl")]
        t = time.perf_counter()
        subprocess.run(args, check=True, stderr=subprocess.DEVNULL)
        elapsed = time.perf_counter() - t
        with open(os.path.join(d, "lines.jsonl")) as f:
            points = sum(1 for _ in f)
    return elapsed, points


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=3000)
    ap.add_argument("--grid", type=int, default=100)
    ap.add_argument("--runs", type=int, default=3, help="sweeps timed each way (the best is kept)")
    a = ap.parse_args()
    with open(SPEC) as f:
        text = f.read()
    py = certify_python(text, a.reps)
    rust = certify_rust(a.reps)
    print(f"certify {SPEC}: python {py:.1f} us, rust end-to-end {rust:.1f} us, ratio {py / rust:.2f} (target <= 2)")
    threads = os.environ.get("RAYON_NUM_THREADS", "all cores")
    # The first engine call in a process starts its thread pool: a one-time
    # cost, like the CLI's process start, which every CLI run pays.
    ec.sweep(SPEC, params=sweep_params(10), numeric=True)
    for numeric in (True, False):
        level = "numeric" if numeric else "exact"
        tp, n_py = best_of(a.runs, lambda: sweep_python(a.grid, numeric))
        tc, n_cli = best_of(a.runs, lambda: sweep_cli(a.grid, numeric))
        assert n_py == n_cli == a.grid**2, (n_py, n_cli)
        print(
            f"sweep {a.grid}x{a.grid} ({level}, threads: {threads}): python {n_py / tp:,.0f} points/s, "
            f"CLI {n_cli / tc:,.0f} points/s, python/CLI rate {(n_py / tp) / (n_cli / tc):.2f} (target >= 0.8)"
        )


if __name__ == "__main__":
    main()
