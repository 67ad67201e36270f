"""Side-by-side with scipy on the matrices of one fluid x-mode.

Reads V.f64 and Q.f64 (row-major little-endian, n x n) written by
`verify/examples/fluid_mode.rs`, and solves the generalised symmetric
eigenproblem Q x = lambda V x with scipy.linalg.eigh: the top eigenvalue only
(subset_by_index, LAPACK ?sygvx) and the whole spectrum (?sygvd). Prints JSON.

    python3 bench/fluid_scipy.py DIR N [REPS]
"""
import json
import sys
import time

import numpy as np
import scipy.linalg


def best_of(reps, f):
    best, out = float("inf"), None
    for _ in range(reps):
        t = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t)
    return best, out


def main():
    d, n = sys.argv[1], int(sys.argv[2])
    reps = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    v = np.fromfile(f"{d}/V.f64", dtype="<f8").reshape(n, n)
    q = np.fromfile(f"{d}/Q.f64", dtype="<f8").reshape(n, n)
    t_top, top = best_of(reps, lambda: scipy.linalg.eigh(q, v, eigvals_only=True, subset_by_index=[n - 1, n - 1]))
    t_all, allv = best_of(reps, lambda: scipy.linalg.eigh(q, v, eigvals_only=True))
    print(json.dumps({
        "n": n,
        "scipy_top_ms": t_top * 1e3,
        "scipy_top": float(top[-1]),
        "scipy_all_ms": t_all * 1e3,
        "scipy_all_max": float(allv[-1]),
        "threads": __import__("os").environ.get("OMP_NUM_THREADS", "default"),
    }))


if __name__ == "__main__":
    main()
