#!/usr/bin/env python3
"""The matrix-free eigenvalue of a non-zonal Zeitlin state side by side with numpy/scipy.

The state is the degree-3 Rossby–Haurwitz-type vorticity

    W_e = 1.0 T_{3,1} + 0.6 T_{3,-2} - 0.2 T_{3,0}

in quflow's real spherical-harmonic basis (``quflow.shr2mat``), which is zonal
about no axis. Its linearised drift on su(N) is

    A X = ([P_e, X] + [Delta^{-1} X, W_e]) / hbar,   hbar = 2 / sqrt(N^2 - 1),

with ``Delta = -sum_a [S_a, [S_a, .]]`` (Hoppe–Yau) and ``P_e = Delta^{-1} W_e``
(trace-free). For each N the script

1. **engine**: writes the spec, forces the matrix-free path
   (``"settings": {"dense_max_n": 2}``, and ``matrix_free_max_n`` above
   N = 256), times one ``verify certify`` (wall clock) and reads
   ``matrix_free.eigenvalue`` and ``matrix_free.backward_error``;
2. **dense numpy reference** (N <= ``--dense-max``, default 32, at most 48;
   ``--dense-64`` allows 64): the Laplacian from the spin matrices as a sparse
   N^2 x N^2 operator, its inverse on su(N) in orthonormal real coordinates
   (dimension N^2 - 1), ``A`` assembled densely, ``numpy.linalg.eigvals``; the
   rightmost eigenvalue is compared with the engine's. The matrix-free
   operator of step 3 is checked against this dense matrix on a random
   vector;
3. **what a user would otherwise do at large N** (``--arpack-ns``, default the
   N >= 64 of the list): ``scipy.sparse.linalg.eigs(LinearOperator, k=4,
   which='LR', ncv=40)`` on gl(N) (the complexification of u(N), so the same
   eigenvalues, plus 0 from the identity), each product applied with numpy
   matrix products; the Poisson solve diagonalises the Laplacian once per
   diagonal (Delta maps each diagonal of a matrix to itself, as a symmetric
   tridiagonal matrix, the same for diagonals m and -m), O(N^3) per solve.
   A wall-clock cap (``--cap``, default 300 s) is enforced inside the matvec:
   if it is hit, or ``maxiter`` is exhausted, that is reported as such, with
   any eigenvalues ARPACK had converged. Returned eigenvalues come with the
   residual ``|A v - lambda v| / |v|``.

It prints a markdown table and, with ``--json OUT``, writes every number.
Run from the repository root (``target/release/verify`` must exist: ``cargo
build --release -p verify``; ``--verify PATH`` otherwise):

    python3 bench/zeitlin/nonzonal_side_by_side.py            # N = 16 32 64 128 256
    python3 bench/zeitlin/nonzonal_side_by_side.py --quick    # N = 16 32 64
    python3 bench/zeitlin/nonzonal_side_by_side.py --ns 16 32 48 --dense-max 48 --json out.json
    python3 bench/zeitlin/nonzonal_side_by_side.py --threads 1 --ns 64 128 256   # BLAS on one thread

Threads: by default nothing is pinned. numpy's BLAS and the engine (rayon)
use what the machine gives; ``OMP_NUM_THREADS``/``OPENBLAS_NUM_THREADS`` and
the load average are recorded. ``--threads K`` pins numpy's BLAS (not the
engine) to K threads: on a loaded 2-core machine, ARPACK with 2 OpenBLAS
threads was measured about 20 times slower than with 1 (18.6 against 0.88 ms
per matvec at N = 64). If quflow is importable (here or by
``--quflow-python``, default ``/tmp/qfvenv/bin/python`` if present), W_e is
also compared with ``quflow.shr2mat`` at the dense N.

Provenance: ``spin_matrices``, ``ad``, ``su_basis`` and ``rel`` come from
``su_numpy.py`` beside this script, shared with ``dense_side_by_side.py``. The
non-zonal basis (``laplacian_blocks``, ``harmonic``) generalises that
script's m = 0 construction to every diagonal m, following quflow's
``compute_basis``/``shr2mat`` conventions.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time


def _blas_threads_from_argv():
    """--threads K pins numpy's BLAS (OPENBLAS/OMP/MKL_NUM_THREADS) before numpy is imported.

    Default: nothing is pinned (the machine's default). The engine's rayon pool
    is never pinned by this script.
    """
    for i, a in enumerate(sys.argv):
        if a.startswith("--threads"):
            k = a.split("=", 1)[1] if "=" in a else sys.argv[i + 1]
            for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
                os.environ[var] = k


_blas_threads_from_argv()
import numpy as np  # noqa: E402
import scipy  # noqa: E402
import scipy.linalg as sla  # noqa: E402
import scipy.sparse as sps  # noqa: E402
import scipy.sparse.linalg as spla  # noqa: E402

HARMONICS = [[3, 1, 1.0], [3, -2, 0.6], [3, 0, -0.2]]
REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


# --------------------------------------------------------------------------
# Copied from bench/zeitlin/dense_side_by_side.py
# --------------------------------------------------------------------------

from su_numpy import ad, rel, spin_matrices, su_basis  # noqa: E402  (beside this script)


# --------------------------------------------------------------------------
# The Laplacian, diagonal by diagonal, and quflow's real harmonics
# --------------------------------------------------------------------------

def laplacian(n):
    """Delta = -sum_a ad_{S_a}^2 on column-major vec, sparse N^2 x N^2."""
    return -sum(ad(sa) @ ad(sa) for sa in spin_matrices(n))


def laplacian_blocks(n, lap=None):
    """Delta restricted to each diagonal m = 0..N-1, diagonalised.

    Returns (blocks, checks): blocks[m] = (eigenvalues, eigenvectors) with the
    order l = m..N-1 (eigenvalue -l(l+1)), block entry j <-> X[j, j+m]; the
    same matrix acts on X[j+m, j] (checked). The blocks are extracted from
    the spin-matrix Laplacian, not written down from a formula.
    """
    lap = laplacian(n) if lap is None else lap
    lap = lap.tocsr()
    blocks, eig_err, lower_diff, imag, kept = [], 0.0, 0.0, 0.0, 0.0
    for m in range(n):
        j = np.arange(n - m)
        up = j + (j + m) * n  # X[j, j+m], column-major
        lo = (j + m) + j * n  # X[j+m, j]
        b_up = lap[up][:, up].toarray()
        b_lo = lap[lo][:, lo].toarray()
        kept += np.abs(b_up).sum() + (np.abs(b_lo).sum() if m else 0.0)
        imag = max(imag, float(np.abs(b_up.imag).max()))
        lower_diff = max(lower_diff, float(np.abs(b_up - b_lo).max()))
        w, v = np.linalg.eigh(b_up.real)
        w, v = w[::-1], v[:, ::-1]  # l = m, m+1, ..., N-1
        ls = np.arange(m, n)
        eig_err = max(eig_err, float(np.abs(w + ls * (ls + 1)).max() / (n * (n - 1))))
        blocks.append((w, np.ascontiguousarray(v)))
    # Delta maps every diagonal to itself: nothing outside the blocks.
    leak = float(abs(lap).sum() - kept)
    return blocks, {"block_eigenvalue_error": eig_err, "lower_vs_upper_block": lower_diff,
                    "block_imag": imag, "off_diagonal_leak": leak}


def harmonic(n, blocks, l, m):
    """quflow's T_lm (shr2mat/elmr2mat): b = sqrt(N) * eigenvector of block |m| for
    -l(l+1), signed so its last entry has the sign (-1)^|m| (compute_basis's
    adjust_basis_orientation_), then sgn = (-1)^|m|, and
    T_l0 = i diag(b); T_lm = i sgn b/sqrt2 on both m-th diagonals (m > 0);
    T_l,-m = sgn b/sqrt2 upper, -sgn b/sqrt2 lower."""
    am = abs(m)
    b = blocks[am][1][:, l - am] * np.sqrt(n)
    want = 1.0 if am % 2 == 0 else -1.0
    if np.sign(b[-1]) != want:
        b = -b
    t = np.zeros((n, n), dtype=complex)
    j = np.arange(n - am)
    if am == 0:
        t[j, j] = 1j * b
        return t
    c = (1.0 if am % 2 == 0 else -1.0) * b / np.sqrt(2)
    if m > 0:
        t[j, j + am] = 1j * c
        t[j + am, j] = 1j * c
    else:
        t[j, j + am] = c
        t[j + am, j] = -c
    return t


def equilibrium(n, blocks):
    return sum(v * harmonic(n, blocks, l, m) for l, m, v in HARMONICS)


class PoissonSolver:
    """X -> Delta^{-1} X (pseudo-inverse: the identity part is dropped), diagonal by diagonal.

    For each m, the upper and lower m-th diagonals are stacked as two columns
    and solved with the block's eigendecomposition: O(sum (N-m)^2) = O(N^3).
    """

    def __init__(self, n, blocks):
        self.n = n
        self.parts = []
        for m, (w, v) in enumerate(blocks):
            inv = np.where(np.abs(w) > 0.5, 1.0 / np.where(w == 0, 1.0, w), 0.0)  # l = 0 -> 0
            j = np.arange(n - m)
            self.parts.append((m, j * n + j + m, (j + m) * n + j, v, v.T.copy(), inv))

    def __call__(self, x):
        xf = x.reshape(-1)
        out = np.zeros(self.n * self.n, dtype=x.dtype)
        for m, up, lo, v, vt, inv in self.parts:
            z = np.stack([xf[up], xf[lo]], axis=1) if m else xf[up][:, None]
            y = v @ ((vt @ z) * inv[:, None])
            out[up] = y[:, 0]
            if m:
                out[lo] = y[:, 1]
        return out.reshape(self.n, self.n)


def drift_operator(n, we, pe, solve):
    hbar = 2 / np.sqrt(n * n - 1)

    def apply(x):
        y = solve(x)
        return (pe @ x - x @ pe + y @ we - we @ y) / hbar

    return apply


# --------------------------------------------------------------------------
# 1. The engine
# --------------------------------------------------------------------------

def run_engine(verify, n, workdir):
    settings = {"dense_max_n": 2}
    if n > 256:
        settings["matrix_free_max_n"] = max(512, n)
    spec = {"name": f"rh-{n}", "zeitlin": {"N": n, "equilibrium": {"harmonics": HARMONICS}, "noise": []},
            "settings": settings}
    spec_path = os.path.join(workdir, f"spec-n{n}.json")
    cert_path = os.path.join(workdir, f"cert-n{n}.json")
    with open(spec_path, "w") as fh:
        json.dump(spec, fh)
    load = os.getloadavg()[0]
    t = time.perf_counter()
    proc = subprocess.run([verify, "certify", spec_path, "-o", cert_path], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True)
    dt = time.perf_counter() - t
    if not os.path.exists(cert_path):
        raise SystemExit(f"N = {n}: verify certify wrote no certificate (exit {proc.returncode}): "
                         f"{proc.stderr.strip()[-800:]}")
    with open(cert_path) as fh:
        cert = json.load(fh)
    mf = cert.get("matrix_free") or {}
    ev = mf.get("eigenvalue")
    return {"seconds": dt, "load1_before": load, "exit": proc.returncode, "verdict": cert.get("verdict"),
            "level": cert.get("level"), "growth_rate": cert.get("growth_rate"),
            "eigenvalue": complex(ev[0], ev[1]) if ev else None, "backward_error": mf.get("backward_error"),
            "dimension": mf.get("dimension"), "reason": cert.get("reason"), "stdout": proc.stdout.strip()}


# --------------------------------------------------------------------------
# 2. The dense reference
# --------------------------------------------------------------------------

def rightmost(ev):
    """The eigenvalue of largest real part; of a conjugate pair, the one with Im >= 0."""
    top = ev.real.max()
    cand = ev[np.abs(ev.real - top) <= 1e-9 * max(1.0, abs(top))]
    return complex(cand[np.argmax(cand.imag)])


def dense_reference(n):
    out = {}
    t0 = time.perf_counter()
    lap = laplacian(n)
    blocks, out["checks"] = laplacian_blocks(n, lap)
    we = equilibrium(n, blocks)
    v, _ = su_basis(n)
    vh = v.conj().T.tocsr()

    def coords(op):
        return (vh @ op @ v).real / n

    def to_mat(x):
        return (v @ x).reshape(n, n, order="F")

    def from_mat(w):
        return (vh @ w.reshape(-1, order="F")).real / n

    lap_c = coords(lap).toarray()
    lap_c = (lap_c + lap_c.T) / 2
    # -Delta is positive definite on su(N) (its kernel, the identity, is left out).
    g = sla.cho_solve(sla.cho_factor(-lap_c), np.eye(n * n - 1))  # G = -Delta^{-1}
    x_we = from_mat(we)
    out["we_trace"] = float(abs(np.trace(we)))
    out["we_in_su"] = float(np.linalg.norm(to_mat(x_we) - we) / np.linalg.norm(we))
    pe = to_mat(-g @ x_we)
    out["poisson_residual"] = float(np.linalg.norm((lap @ pe.reshape(-1, order="F")).reshape(n, n, order="F") - we)
                                    / np.linalg.norm(we))
    out["pe_vs_minus_we_over_12"] = float(np.linalg.norm(pe + we / 12) / np.linalg.norm(pe))  # every l = 3
    hbar = 2 / np.sqrt(n * n - 1)
    a = (coords(ad(pe)).toarray() + coords(ad(we)).toarray() @ g) / hbar
    out["t_assembly"] = time.perf_counter() - t0
    out["load1_before_eigvals"] = os.getloadavg()[0]
    t1 = time.perf_counter()
    ev = np.linalg.eigvals(a)
    out["t_eigvals"] = time.perf_counter() - t1
    order = np.argsort(-ev.real)
    out["eigenvalue"] = rightmost(ev)
    out["top_by_real_part"] = [complex(z) for z in ev[order[:8]]]
    out["max_abs_imag"] = float(np.abs(ev.imag).max())
    out["max_abs"] = float(np.abs(ev).max())
    # The matrix-free operator of part 3 against this dense matrix.
    solve = PoissonSolver(n, blocks)
    op = drift_operator(n, we, solve(we), solve)
    x = np.random.default_rng(1).standard_normal(n * n - 1)
    dense_ax = to_mat(a @ x)
    out["matvec_vs_dense"] = float(np.linalg.norm(op(to_mat(x)) - dense_ax) / np.linalg.norm(dense_ax))
    out["pe_poisson_solver_vs_dense"] = float(np.linalg.norm(solve(we) - pe) / np.linalg.norm(pe))
    out["we"] = we
    return out


# --------------------------------------------------------------------------
# 3. ARPACK on a LinearOperator
# --------------------------------------------------------------------------

class Capped(Exception):
    pass


def arpack(n, ncv, maxiter, cap, tol, k=4):
    out = {"ncv": ncv, "maxiter": maxiter, "cap_s": cap, "tol": tol, "k": k}
    t0 = time.perf_counter()
    blocks, out["checks"] = laplacian_blocks(n)
    we = equilibrium(n, blocks)
    solve = PoissonSolver(n, blocks)
    pe = solve(we)
    apply = drift_operator(n, we, pe, solve)
    out["t_setup"] = time.perf_counter() - t0
    # One matvec outside the timing, to report its cost.
    x0 = np.random.default_rng(0).standard_normal((n, n)) + 1j * np.random.default_rng(1).standard_normal((n, n))
    t = time.perf_counter()
    apply(x0)
    out["t_matvec"] = time.perf_counter() - t

    count = [0]
    start = [0.0]

    def mv(x):
        if time.perf_counter() - start[0] > cap:
            raise Capped()
        count[0] += 1
        return apply(x.reshape(n, n)).reshape(-1)

    op = spla.LinearOperator((n * n, n * n), matvec=mv, dtype=complex)
    out["load1_before"] = os.getloadavg()[0]
    start[0] = time.perf_counter()
    vals, vecs = None, None
    try:
        vals, vecs = spla.eigs(op, k=k, which="LR", ncv=ncv, maxiter=maxiter, tol=tol, v0=x0.reshape(-1))
        out["status"] = "converged"
    except spla.ArpackNoConvergence as e:
        vals, vecs = e.eigenvalues, e.eigenvectors
        out["status"] = f"did not converge in maxiter = {maxiter} ({len(vals)} of {k} converged)"
    except Capped:
        out["status"] = f"capped at {cap:.0f} s (no eigenvalue returned)"
    out["seconds"] = time.perf_counter() - start[0]
    out["matvecs"] = count[0]
    out["eigenvalues"], out["residuals"] = [], []
    if vals is not None and len(vals):
        for lam, vec in zip(vals, vecs.T):
            r = np.linalg.norm(apply(vec.reshape(n, n)).reshape(-1) - lam * vec) / np.linalg.norm(vec)
            out["eigenvalues"].append(complex(lam))
            out["residuals"].append(float(r))
        i = max(range(len(vals)), key=lambda q: (round(vals[q].real, 12), vals[q].imag))
        out["eigenvalue"], out["residual"] = out["eigenvalues"][i], out["residuals"][i]
    return out


# --------------------------------------------------------------------------
# quflow cross-check of W_e
# --------------------------------------------------------------------------

QUFLOW_CODE = r"""
import json, sys
import numpy as np
import quflow as qf
job = json.load(sys.stdin)
res = {}
for n in job["ns"]:
    omega = np.zeros(n * n)
    for l, m, v in job["harmonics"]:
        omega[qf.utils.elm2ind(l, m)] = v
    w = qf.shr2mat(omega, N=n)
    res[str(n)] = [w.real.tolist(), w.imag.tolist()]
print(json.dumps(res))
"""


def quflow_we(ns, python):
    job = json.dumps({"ns": ns, "harmonics": HARMONICS})
    try:
        import quflow  # noqa: F401
        python = sys.executable
    except ImportError:
        if not python or not os.path.exists(python):
            return None, "quflow not importable and no --quflow-python interpreter"
    proc = subprocess.run([python, "-c", QUFLOW_CODE], input=job, capture_output=True, text=True)
    if proc.returncode != 0:
        return None, f"quflow via {python} failed: {proc.stderr.strip()[-400:]}"
    res = json.loads(proc.stdout)
    return {int(k): np.array(v[0]) + 1j * np.array(v[1]) for k, v in res.items()}, python


# --------------------------------------------------------------------------

def fmt_c(z, digits=10):
    if z is None:
        return "-"
    return f"{z.real:.{digits}e} {'+' if z.imag >= 0 else '-'} {abs(z.imag):.{digits - 4}e}i"


def blas_info():
    try:
        cfg = np.show_config(mode="dicts")
        b = cfg["Build Dependencies"]["blas"]
        return f"{b.get('name')} {b.get('version')}"
    except Exception as e:  # noqa: BLE001
        return f"unknown ({e})"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="N = 16 32 64 only")
    ap.add_argument("--ns", type=int, nargs="+", help="N values for the engine (default 16 32 64 128 256)")
    ap.add_argument("--dense-max", type=int, default=32, help="largest N for the dense reference (at most 48)")
    ap.add_argument("--dense-64", action="store_true", help="allow the dense reference at N = 64 (4095^2, minutes)")
    ap.add_argument("--arpack-ns", type=int, nargs="*", help="N values for ARPACK (default: the N >= 64 of --ns)")
    ap.add_argument("--ncv", type=int, default=40)
    ap.add_argument("--maxiter", type=int, default=2000, help="ARPACK restarts")
    ap.add_argument("--tol", type=float, default=0.0, help="ARPACK tol (0: machine precision, scipy's default)")
    ap.add_argument("--cap", type=float, default=300.0, help="wall-clock cap per ARPACK run, seconds")
    ap.add_argument("--verify", default=os.path.join(REPO, "target", "release", "verify"))
    ap.add_argument("--quflow-python", default="/tmp/qfvenv/bin/python")
    ap.add_argument("--threads", help="pin numpy's BLAS to this many threads (default: not pinned); measured "
                                      "here: under load, multi-threaded OpenBLAS made ARPACK about 20x slower")
    ap.add_argument("--json", help="also write all measurements here")
    args = ap.parse_args()

    ns = args.ns or ([16, 32, 64] if args.quick else [16, 32, 64, 128, 256])
    dense_max = 64 if args.dense_64 else min(args.dense_max, 48)
    dense_ns = [n for n in ns if n <= dense_max]
    arpack_ns = args.arpack_ns if args.arpack_ns is not None else [n for n in ns if n >= 64]
    if not os.path.exists(args.verify):
        raise SystemExit(f"{args.verify} is missing: build it with `cargo build --release -p verify` first")

    env = {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                          "RAYON_NUM_THREADS")}
    report = {"harmonics": HARMONICS, "numpy": np.__version__, "scipy": scipy.__version__, "blas": blas_info(),
              "python": sys.version.split()[0], "cores": os.cpu_count(), "env": env,
              "load_start": os.getloadavg(), "engine": {}, "dense": {}, "arpack": {}}
    np.linalg.eigvals(np.random.default_rng(0).standard_normal((64, 64)))  # start the BLAS pool untimed

    with tempfile.TemporaryDirectory() as work:
        for n in ns:
            e = run_engine(args.verify, n, work)
            report["engine"][n] = e
            print(f"engine N = {n}: {e['seconds']:.3f} s, {e['verdict']} ({e['level']}), eigenvalue "
                  f"{fmt_c(e['eigenvalue'])}, backward error {e['backward_error']}", file=sys.stderr)

    for n in dense_ns:
        d = dense_reference(n)
        report["dense"][n] = d
        print(f"dense N = {n}: assembly {d['t_assembly']:.2f} s, eigvals {d['t_eigvals']:.2f} s, rightmost "
              f"{fmt_c(d['eigenvalue'])}; checks {d['checks']}, Delta P_e - W_e {d['poisson_residual']:.1e}, "
              f"P_e + W_e/12 {d['pe_vs_minus_we_over_12']:.1e}, matvec vs dense {d['matvec_vs_dense']:.1e}, "
              f"block solver P_e vs dense {d['pe_poisson_solver_vs_dense']:.1e}; top by Re "
              f"{[fmt_c(z, 6) for z in d['top_by_real_part'][:6]]}; max |Im| {d['max_abs_imag']:.3g}",
              file=sys.stderr)

    qf, qf_note = ({}, "skipped") if not dense_ns else quflow_we(dense_ns, args.quflow_python)
    report["quflow_we_check"] = {}
    if qf:
        for n in dense_ns:
            diff = float(np.abs(qf[n] - report["dense"][n]["we"]).max() / np.abs(qf[n]).max())
            report["quflow_we_check"][n] = diff
        qf_note = f"W_e vs quflow.shr2mat ({qf_note}): max rel. entry difference " + ", ".join(
            f"N = {n}: {d:.1e}" for n, d in report["quflow_we_check"].items())
    else:
        qf_note = f"W_e not checked against quflow: {qf_note}"
    print(qf_note, file=sys.stderr)
    for n in dense_ns:
        del report["dense"][n]["we"]

    for n in arpack_ns:
        r = arpack(n, args.ncv, args.maxiter, args.cap, args.tol)
        report["arpack"][n] = r
        print(f"ARPACK N = {n}: setup {r['t_setup']:.2f} s, matvec {r['t_matvec'] * 1e3:.1f} ms, eigs "
              f"{r['seconds']:.1f} s, {r['matvecs']} matvecs, {r['status']}; eigenvalues "
              f"{[fmt_c(z, 6) for z in r['eigenvalues']]}, residuals {[f'{x:.1e}' for x in r['residuals']]}",
              file=sys.stderr)
    report["load_end"] = os.getloadavg()

    print("| N | engine certify | engine eigenvalue | engine backward err. | dense eigvals (assembly) "
          "| dense rightmost | rel. diff Re (dense) | ARPACK eigs | ARPACK rightmost | residual "
          "| rel. diff Re (ARPACK) | ARPACK status |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |")
    for n in sorted(set(ns) | set(dense_ns) | set(arpack_ns)):
        e, d, r = report["engine"].get(n), report["dense"].get(n), report["arpack"].get(n)
        ez = e["eigenvalue"] if e else None
        cells = [str(n),
                 f"{e['seconds']:.3f} s" if e else "-", fmt_c(ez),
                 f"{e['backward_error']:.1e}" if e and e["backward_error"] is not None else "-"]
        if d:
            cells += [f"{d['t_eigvals']:.2f} s ({d['t_assembly']:.2f} s)", fmt_c(d["eigenvalue"]),
                      f"{rel(ez.real, d['eigenvalue'].real):.1e}" if ez else "-"]
        else:
            cells += ["-", "-", "-"]
        if r:
            lam = r.get("eigenvalue")
            cells += [f"{r['seconds']:.1f} s ({r['matvecs']} matvecs)", fmt_c(lam),
                      f"{r['residual']:.1e}" if lam is not None else "-",
                      f"{rel(ez.real, lam.real):.1e}" if (lam is not None and ez) else "-", r["status"]]
        else:
            cells += ["-", "-", "-", "-", "-"]
        print("| " + " | ".join(cells) + " |")
    print()
    print(qf_note)
    print(f"numpy {np.__version__} ({report['blas']}), scipy {scipy.__version__}, python {report['python']}; "
          f"{os.cpu_count()} cores; BLAS threads " + (f"pinned to {args.threads} (--threads)" if args.threads
                                                        else "not pinned") + ": " + ", ".join(f"{k}={v}" for k, v in env.items())
          + f"; load average (1, 5, 15 min) start {' '.join(f'{x:.2f}' for x in report['load_start'])}, end "
          f"{' '.join(f'{x:.2f}' for x in report['load_end'])}; engine one run per N (wall clock); ARPACK "
          f"k = 4, which = 'LR', ncv = {args.ncv}, maxiter = {args.maxiter}, tol = {args.tol}, cap {args.cap:.0f} s")
    if args.json:
        def enc(o):
            if isinstance(o, complex):
                return [o.real, o.imag]
            if isinstance(o, np.ndarray):
                return o.tolist()
            return float(o)
        with open(args.json, "w") as fh:
            json.dump(report, fh, indent=1, default=enc)


if __name__ == "__main__":
    main()
