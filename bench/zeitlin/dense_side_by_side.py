#!/usr/bin/env python3
"""The zonal Zeitlin certificate side by side with a dense numpy/scipy construction.

What a researcher without the engine would do, in the same run as the engine:

1. write a spec (equilibrium ``z + 0.3*z^3``, noise ``0.1*z^2``,
   ``casimir_momentum: false`` so that Sigma^2 > 0) and time
   ``verify certify`` on it (wall clock, best of ``--reps``);
2. in numpy, from the model alone (no block formulas): the Hoppe–Yau
   Laplacian ``Delta = -sum_a [S_a, [S_a, .]]`` from the spin matrices, its
   inverse on su(N), quflow's quantisation of omega(z) and xi(z), the Hessian
   ``P`` of ``L = eps H + tr Phi(-iW)/N + beta J`` at the engine's
   ``(eps, beta, free curvature)`` and the generator form
   ``Q = P A~ + A~^T P + B^T P B`` of the linearised SDE, all dense in the
   real coordinates of su(N) (dimension N^2 - 1); then
   ``scipy.linalg.eigh(Q, P)``, whose largest eigenvalue is Sigma^2;
3. quflow's isospectral midpoint step (``quflow.isomp``) at N = 64, 128, 256,
   if quflow can be imported (here or by ``--quflow-python``);

and prints two markdown tables. Run from the repository root:

    python3 bench/zeitlin/dense_side_by_side.py            # N = 16, 32, 64
    python3 bench/zeitlin/dense_side_by_side.py --quick    # N = 16, 32 only
    python3 bench/zeitlin/dense_side_by_side.py --json out.json

It needs numpy and scipy, and ``target/release/verify`` (``--verify PATH``
otherwise; it does not build it). quflow is not on PyPI: install it from a
checkout of its source (``pip install --no-deps PATH``, plus its
dependencies numba, ducc0, h5py, appdirs, tqdm, matplotlib) into this
interpreter or into a venv named by ``--quflow-python`` (default
``/tmp/qfvenv/bin/python`` if it exists). Without it the quflow parts are
skipped and the reason is printed. N = 64 needs about 1.7 GB of memory and
about 1.5 minutes on one thread. Every side runs on one thread unless
``--threads`` says otherwise (see ``_threads_from_argv``).

Normalisation. Coordinates are taken in an orthonormal basis ``E_a`` of
su(N) for quflow's inner product ``<A, B> = Re tr(A B^*)/N``, so the quadratic
form ``x^T P x`` is exactly the second variation ``d^2 L[w, w]`` and
``x^T Q x`` is the generator applied to it. The engine's blocks are
``(2/N)(eps G + D_c)``; the factors differ, and ``lambda_max(Q, P)`` does not
depend on them.

Why each piece is built the way it is:

* ``A~ = A + (1/2) sum B_i^2`` is the Ito drift of the Stratonovich SDE
  ``dw = A w dt + sum B_i w o dB^i``; the generator of ``w^T P w`` is then
  ``w^T (P A~ + A~^T P + sum B_i^T P B_i) w``. For a ``P`` conserved by the
  drift this is the form in docs/zeitlin.md; the script checks
  ``P A + A^T P = 0`` instead of assuming it.
* The Casimir's second variation at a diagonal ``W_e`` is the
  Daleckii–Krein sum ``sum_jk Phi'[omega_j, omega_k] |w_jk|^2 / N`` (divided
  differences; ``Phi''`` on the diagonal, where the engine's free curvature
  is used). ``Phi'`` at the nodes comes from criticality,
  ``Phi'(omega_j) = eps pi_j - beta tau_j``, with ``pi`` from the dense
  inverse Laplacian and ``J(W) = <W, i diag(tau)>``, ``tau_j = j - (N-1)/2``.
* ``B`` and the ad-operators of diagonal matrices are kept sparse: they have
  two entries per column, and a researcher would not multiply by them
  densely. ``P``, ``G``, ``A`` and ``Q`` are dense.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time


def _threads_from_argv():
    """Fix the thread count of every side before numpy is imported (OpenBLAS reads it once).

    Default 1: the engine (rayon), OpenBLAS and numba then run alike, and the
    numbers survive another job on the same 2 cores. Multi-threaded OpenBLAS
    and numba pools spin, and under such a load were measured 100 to 500
    times slower here. --threads 0 leaves every library at its default.
    """
    k = "1"
    for i, a in enumerate(sys.argv):
        if a.startswith("--threads"):
            k = a.split("=", 1)[1] if "=" in a else sys.argv[i + 1]
    if k != "0":
        for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS",
                    "RAYON_NUM_THREADS"):
            os.environ[var] = k


_threads_from_argv()
import numpy as np  # noqa: E402

EQUILIBRIUM = "z + 0.3*z^3"
NOISE = "0.1*z^2"
REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def profile(expr):
    """The spec's expression in z as a numpy function (one source of truth for both sides)."""
    code = compile(expr.replace("^", "**"), expr, "eval")
    return lambda z: eval(code, {"__builtins__": {}}, {"z": z})


def best_of(reps, f):
    best, out = float("inf"), None
    for _ in range(reps):
        t = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t)
    return best, out


def legendre_coefficients(f, lmax, nodes):
    """a_l = 1/2 int f(z) sqrt(2l+1) P_l(z) dz, l = 0..lmax, by Gauss–Legendre."""
    from numpy.polynomial import legendre

    z, w = legendre.leggauss(nodes)
    fz = f(z)
    return np.array([0.5 * np.sum(w * fz * legendre.legval(z, np.eye(lmax + 1)[l])) * np.sqrt(2 * l + 1)
                     for l in range(lmax + 1)])


# --------------------------------------------------------------------------
# The engine
# --------------------------------------------------------------------------

def run_engine(verify, n, reps, workdir):
    spec = {
        "name": f"zeitlin-dense-bench-n{n}",
        "description": "bench/zeitlin/dense_side_by_side.py: the monotone zonal state with the energy forced in",
        "zeitlin": {"N": n, "equilibrium": EQUILIBRIUM, "noise": [NOISE]},
        "stopping": {"epsilon": 0.1, "delta": 0.001},
        "settings": {"casimir_momentum": False},
    }
    spec_path = os.path.join(workdir, f"spec-n{n}.json")
    cert_path = os.path.join(workdir, f"cert-n{n}.json")
    with open(spec_path, "w") as fh:
        json.dump(spec, fh)

    def once():
        subprocess.run([verify, "certify", spec_path, "-o", cert_path], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)

    t, _ = best_of(reps, once)
    with open(cert_path) as fh:
        return t, json.load(fh)


# --------------------------------------------------------------------------
# The dense construction
# --------------------------------------------------------------------------

from su_numpy import ad, rel, spin_matrices, su_basis  # noqa: E402  (beside this script)


def dense_sigma2(n, cert, eigh_reps):
    import scipy.linalg as sla
    import scipy.sparse as sps

    out = {}
    t0 = time.perf_counter()

    # --- Laplacian on su(N), from the spin matrices -------------------------
    s = spin_matrices(n)
    lap = -sum(ad(sa) @ ad(sa) for sa in s)  # N^2 x N^2 on vec(W), sparse
    v, slices = su_basis(n)
    vh = v.conj().T.tocsr()

    def coords(op):
        """An operator on vec(W) that preserves su(N), in the orthonormal coordinates."""
        return (vh @ op @ v).real / n

    def to_vec(x):
        return v @ x

    def from_vec(wvec):
        return (vh @ wvec).real / n

    gram = coords(sps.identity(n * n))
    out["basis_orthonormality"] = float(abs(gram - sps.identity(n * n - 1)).max())
    lap_c = coords(lap).toarray()
    out["laplacian_asymmetry"] = float(np.abs(lap_c - lap_c.T).max() / np.abs(lap_c).max())
    lap_c = (lap_c + lap_c.T) / 2
    # Delta has kernel = multiples of the identity, which is not in su(N): on
    # su(N) its pseudo-inverse is the inverse, and -Delta is positive definite.
    t_inv = time.perf_counter()
    g = sla.cho_solve(sla.cho_factor(-lap_c), np.eye(n * n - 1))  # G = -Delta^{-1}
    g = (g + g.T) / 2
    out["t_laplacian_inverse"] = time.perf_counter() - t_inv

    # --- quflow's quantisation of the zonal profiles ------------------------
    dd = np.array([i + i * n for i in range(n)])
    lap0 = lap[dd][:, dd].toarray().real  # Delta on diagonal matrices
    # Delta maps diagonals to diagonals: nothing leaks off it.
    out["m0_leak"] = float(abs(lap[:, dd]).sum() - abs(lap[dd][:, dd]).sum())
    ev, u = np.linalg.eigh(lap0)
    ev, u = ev[::-1], u[:, ::-1]  # l = 0, 1, ..., N-1
    u = u * np.sign(u[-1, :])  # quflow's shr2mat: last entry positive
    ls = np.arange(n)
    out["m0_eigenvalue_error"] = float(np.abs(ev + ls * (ls + 1)).max() / (n * (n - 1)))
    nodes = 2 * n + 32
    a_om = legendre_coefficients(profile(EQUILIBRIUM), n - 1, nodes)
    a_xi = legendre_coefficients(profile(NOISE), n - 1, nodes)
    omega = np.sqrt(n) * u[:, 1:] @ a_om[1:]  # W_e = sum_{l>=1} a_l T_l0, T_l0 = i sqrt(N) diag(u_l)
    xi = np.sqrt(n) * u[:, 1:] @ a_xi[1:]
    out["a_omega"], out["a_xi"], out["omega"], out["xi"] = a_om, a_xi, omega, xi
    ce = np.array(cert["model"]["equilibrium_coefficients"])  # l = 1, 2, ...
    cn = np.array(cert["model"]["noise_coefficients"][0])
    k = min(len(ce), n - 1)
    out["coefficients_vs_cert"] = float(max(np.abs(a_om[1:1 + k] - ce[:k]).max(),
                                            np.abs(a_xi[1:1 + min(len(cn), n - 1)] - cn[:n - 1]).max()))

    # --- equilibrium stream function ----------------------------------------
    we = np.diag(1j * omega)
    x_we = from_vec(we.reshape(-1, order="F"))
    x_pe = -g @ x_we  # P_e = Delta^{-1} W_e
    pe = to_vec(x_pe).reshape(n, n, order="F")
    out["pe_offdiag"] = float(np.abs(pe - np.diag(np.diag(pe))).max() / np.abs(pe).max())
    pi = np.diag(pe).imag
    out["pi"] = pi
    out["poisson_residual"] = float(np.abs(lap @ pe.reshape(-1, order="F") - we.reshape(-1, order="F")).max()
                                    / np.abs(omega).max())

    # --- drift, noise ---------------------------------------------------------
    hbar = 2 / np.sqrt(n * n - 1)
    # A w = ([P_e, w] + [Delta^{-1} w, W_e]) / hbar = (ad_{P_e} + ad_{W_e} G) w / hbar
    ad_pe = coords(ad(np.diag(1j * pi)))
    ad_we = coords(ad(we))
    a = (ad_pe.toarray() + ad_we @ g) / hbar
    b = coords(ad(np.diag(1j * xi))) / hbar  # sparse
    b2 = (b @ b).tocsr()

    # --- Hessian of L = eps H + tr Phi(-iW)/N + beta J --------------------------
    form = cert["form"]
    eps, beta, phi2 = form["energy_coefficient"], form["momentum_coefficient"], form["free_curvature"]
    tau = np.arange(n) - (n - 1) / 2
    dphi = eps * pi - beta * tau  # Phi'(omega_j), from dL = 0 at W_e
    num = dphi[:, None] - dphi[None, :]
    den = omega[:, None] - omega[None, :]
    kdd = np.where(np.eye(n, dtype=bool), phi2, num / np.where(den == 0, 1.0, den))
    if np.any((den == 0) & ~np.eye(n, dtype=bool)):
        raise SystemExit("repeated eigenvalues of W_e: c_jk is free there; not handled by this script")
    cas = coords(sps.diags(kdd.reshape(-1, order="F")))
    p = eps * g + cas.toarray()
    p = (p + p.T) / 2

    # --- generator form ---------------------------------------------------------
    pa = p @ a  # the one dense O(n^3) product
    # The scale: |P A| is dominated by the Casimir–momentum part, whose
    # antisymmetric bulk is exact by structure; what must cancel is the
    # symmetric part of the energy's G A (against the Casimir's). So the
    # residual is measured against |(G A + A^T G) X| on random probes X.
    probes = np.random.default_rng(0).standard_normal((n * n - 1, 8))
    sym_ga = g @ (a @ probes) + a.T @ (g @ probes)
    out["drift_residual"] = float(np.linalg.norm((pa + pa.T) @ probes) / np.linalg.norm(sym_ga))
    # Its effect on the dense Sigma^2: |delta lambda| <= |PA + A^T P|_2 / lambda_min(P)
    # (Frobenius norm here, an upper bound); divided by lambda_min(P) below.
    out["drift_residual_abs"] = float(np.linalg.norm(pa + pa.T))
    pb2 = (b2.T @ p).T  # P B^2 (P symmetric)
    pb = (b.T @ p).T
    q = pa + pa.T + 0.5 * (pb2 + pb2.T) + b.T @ pb
    q = (q + q.T) / 2
    out["t_assembly"] = time.perf_counter() - t0

    # P is definite with the sign of eps (or of the Casimir part if eps = 0).
    sign = np.sign(eps) if eps != 0 else 1.0
    ps, qs = sign * p, sign * q
    # P, Q are block diagonal in m; measure it rather than assume it.
    # (Directly on the off-block entries: |P|^2 - sum |P_m|^2 would cancel.)
    block_of = np.empty(n * n - 1, dtype=np.int32)
    for m, sl in slices.items():
        block_of[sl] = m
    off = block_of[:, None] != block_of[None, :]
    out["p_off_block"] = float(np.abs(ps[off]).max() / np.abs(ps).max())
    out["q_off_block"] = float(np.abs(qs[off]).max() / np.abs(qs).max())
    del off

    # --- the generalized eigenproblem -------------------------------------------
    dim = n * n - 1
    out["t_eigh"], ev_all = best_of(eigh_reps, lambda: sla.eigh(qs, ps, eigvals_only=True))
    out["t_eigh_top"], ev_top = best_of(
        eigh_reps, lambda: sla.eigh(qs, ps, eigvals_only=True, subset_by_index=[dim - 1, dim - 1]))
    out["sigma2_all"], out["sigma2_top"] = float(ev_all[-1]), float(ev_top[-1])

    # --- per block: lambda_max(Q_m, P_m) and conditioning ------------------------
    blocks, pmin, pmax = {}, np.inf, 0.0
    for m, sl in slices.items():
        pe_m = np.linalg.eigvalsh(ps[sl, sl])
        pmin, pmax = min(pmin, pe_m[0]), max(pmax, pe_m[-1])
        lam = sla.eigh(qs[sl, sl], ps[sl, sl], eigvals_only=True)
        blocks[m] = {"lambda_max": float(lam[-1]), "cond_p": float(pe_m[-1] / pe_m[0]), "p_min": float(pe_m[0])}
    out["blocks"], out["cond_p"], out["p_min"] = blocks, float(pmax / pmin), float(pmin)
    out["dense_error_bound"] = out["drift_residual_abs"] / pmin / out["sigma2_all"]
    return out


# --------------------------------------------------------------------------
# quflow (here, or in another interpreter through --quflow-worker)
# --------------------------------------------------------------------------

def quflow_worker(job):
    """Cross-check the quantisation and the Poisson solve, and time isomp."""
    import quflow as qf

    res = {"version": getattr(qf, "__version__", "?"), "check": {}, "timing": {}}
    for n_str, c in job["check"].items():
        n = int(n_str)
        shr = np.zeros(n * n)
        for l, al in enumerate(c["a_omega"]):
            if l >= 1:
                shr[l * l + l] = al  # elm2ind(l, 0)
        w = qf.shr2mat(shr, N=n)
        # quflow's own forward transform of omega(z) on its grid (z = cos theta).
        theta, _ = qf.sphgrid(n)
        f = profile(EQUILIBRIUM)(np.cos(theta))
        a_qf = qf.fun2shr(f)[[l * l + l for l in range(n)]]
        p = np.array(qf.solve_poisson(w.copy()))  # solve_poisson returns a cached buffer
        res["check"][n_str] = {
            "omega": np.diag(w).imag.tolist(),
            "offdiag": float(np.abs(w - np.diag(np.diag(w))).max()),
            "a_fun2shr": a_qf.tolist(),
            "pi": np.diag(p).imag.tolist(),
            "hbar": float(qf.geometry.hbar(n)),
        }
    # quflow's own profiling protocol (profiling/run_profiling.py in its
    # source): a random state with l < 10, no circulation or angular
    # momentum, dt = 0.01 hbar, exactly 10 fixed-point iterations a step. A
    # steady zonal state would converge at once and understate the cost.
    # Also its default (tolerance 'auto'), with the iterations it took.
    rs = np.random.RandomState(42)
    omega0 = rs.randn(100)
    omega0[0:4] = 0.0
    for n in job["timing_ns"]:
        w0 = qf.shr2mat(omega0, N=n)
        dt = 0.01 * qf.geometry.hbar(n)
        qf.isomp(w0.copy(), dt, steps=2)  # numba compilation, outside the timing
        steps = max(4, int(job["step_budget"] * (64 / n) ** 2))
        t_fixed, _ = best_of(job["reps"], lambda: qf.isomp(w0.copy(), dt, steps=steps, minit=10, maxit=10))
        stats = {"iterations": 0.0}  # (isomp fills a non-empty dict only)
        t_auto, _ = best_of(job["reps"], lambda: qf.isomp(w0.copy(), dt, steps=steps, stats=stats))
        t_poisson, _ = best_of(job["reps"], lambda: [qf.solve_poisson(w0) for _ in range(steps)])
        res["timing"][str(n)] = {"fixed10": t_fixed / steps, "auto": t_auto / steps, "steps": steps,
                                 "iterations": stats.get("iterations"), "poisson": t_poisson / steps}
    return res


def run_quflow(job, python):
    try:
        import quflow  # noqa: F401
        return quflow_worker(job), sys.executable
    except ImportError as e:
        here = f"not importable by {sys.executable} ({e})"
    if not python or not os.path.exists(python):
        return {"error": here + "; no --quflow-python interpreter (quflow is not on PyPI: "
                                "install it from a checkout of its source)"}, None
    proc = subprocess.run([python, os.path.abspath(__file__), "--quflow-worker"], input=json.dumps(job),
                          capture_output=True, text=True)
    if proc.returncode != 0:
        return {"error": f"{python} --quflow-worker failed: {proc.stderr.strip()[-800:]}"}, python
    return json.loads(proc.stdout), python


# --------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="skip N = 64 (dimension 4095)")
    ap.add_argument("--ns", type=int, nargs="+", help="N values (default 16 32 64)")
    ap.add_argument("--reps", type=int, default=3, help="best of REPS for verify certify and quflow")
    ap.add_argument("--eigh-reps", type=int, default=3, help="best of this many for scipy eigh")
    ap.add_argument("--verify", default=os.path.join(REPO, "target", "release", "verify"))
    ap.add_argument("--quflow-python", default="/tmp/qfvenv/bin/python",
                    help="interpreter with quflow installed, used if this one lacks it")
    ap.add_argument("--quflow-ns", type=int, nargs="+", default=[64, 128, 256])
    ap.add_argument("--quflow-step-budget", type=int, default=64, help="isomp steps timed at N = 64 (fewer above)")
    ap.add_argument("--no-quflow", action="store_true")
    ap.add_argument("--threads", default="1", help="threads for the engine (rayon), OpenBLAS and numba, passed on "
                                                   "to the subprocesses; 0: each library's default (all cores)")
    ap.add_argument("--json", help="also write all measurements here")
    ap.add_argument("--quflow-worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()

    if args.quflow_worker:
        print(json.dumps(quflow_worker(json.load(sys.stdin))))
        return

    ns = args.ns or ([16, 32] if args.quick else [16, 32, 64])
    if not os.path.exists(args.verify):
        raise SystemExit(f"{args.verify} is missing: build it with `cargo build --release -p verify` first")
    # Start OpenBLAS's thread pool outside any timing.
    import scipy.linalg as sla

    sla.eigh(np.eye(64) * 2, np.eye(64), eigvals_only=True)
    load0 = os.getloadavg()
    rows, report = [], {"load_start": load0, "ns": {}}
    with tempfile.TemporaryDirectory() as work:
        for n in ns:
            t_engine, cert = run_engine(args.verify, n, args.reps, work)
            if cert.get("sigma2") is None:
                raise SystemExit(f"N = {n}: the engine reports no Sigma^2 ({cert['verdict']}: {cert['reason']})")
            d = dense_sigma2(n, cert, args.eigh_reps)
            s_eng = cert["sigma2"]
            eng_blocks = {b["m"]: b["lambda_max"] for b in cert.get("blocks", [])}
            # Against Sigma^2, not per block: the last block (one entry) has
            # lambda_max = 0 exactly in the engine and ~1e-49 here.
            block_diff = max((abs(eng_blocks[m] - d["blocks"][m]["lambda_max"]) / s_eng for m in eng_blocks),
                             default=float("nan"))
            m_top = max(eng_blocks, key=eng_blocks.get) if eng_blocks else None
            rows.append((n, n * n - 1, t_engine, d["t_assembly"], d["t_eigh"], d["t_eigh_top"], s_eng,
                         d["sigma2_all"], rel(s_eng, d["sigma2_all"]), block_diff))
            report["ns"][n] = {
                "engine_s": t_engine, "form": cert["form"], "verdict": cert["verdict"], "level": cert["level"],
                "sigma2_engine": s_eng, "sigma2_upper_engine": cert.get("sigma2_upper"), "m_top": m_top,
                **{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in d.items()},
            }
            r = report["ns"][n]
            print(f"N = {n}: {cert['verdict']} ({cert['level']}), eps {cert['form']['energy_coefficient']:+g}, "
                  f"beta {cert['form']['momentum_coefficient']:.6g}, free curvature "
                  f"{cert['form']['free_curvature']:.4g}, attained {cert['form']['attained']}", file=sys.stderr)
            print(f"  checks: basis {r['basis_orthonormality']:.1e}, Delta_0 eigenvalues vs -l(l+1) "
                  f"{r['m0_eigenvalue_error']:.1e}, a_l vs certificate {r['coefficients_vs_cert']:.1e}, "
                  f"Delta P_e - W_e {r['poisson_residual']:.1e}, drift |(PA + A^T P)X|/|(GA + A^T G)X| "
                  f"{r['drift_residual']:.1e}, off-block P {r['p_off_block']:.1e} Q {r['q_off_block']:.1e}",
                  file=sys.stderr)
            print(f"  cond(P) {r['cond_p']:.2e} (min eig {r['p_min']:.3e}); block m = {m_top}: cond "
                  f"{r['blocks'][m_top]['cond_p']:.2e}, lambda_max dense {r['blocks'][m_top]['lambda_max']:.12e}, "
                  f"engine {eng_blocks[m_top]:.12e}; eigh all {r['sigma2_all']:.12e}, top-only "
                  f"{r['sigma2_top']:.12e}; Delta^-1 {r['t_laplacian_inverse']:.2f} s of the assembly",
                  file=sys.stderr)
            # Newer engines also record a proved upper bound on Sigma^2.
            up = cert.get("sigma2_upper")
            up_text = "none" if up is None else f"{up:.12e} (>= scipy: {up >= r['sigma2_all']})"
            print(f"  engine sigma2_upper {up_text}; dense rounding bound from the drift residual "
                  f"{r['dense_error_bound']:.1e} of Sigma^2", file=sys.stderr)

    qf_rows, qf_note = [], None
    if not args.no_quflow:
        job = {"check": {str(n): {"a_omega": report["ns"][n]["a_omega"]} for n in ns},
               "timing_ns": args.quflow_ns, "reps": args.reps, "step_budget": args.quflow_step_budget}
        qres, interp = run_quflow(job, args.quflow_python)
        report["quflow"] = qres
        if "error" in qres:
            qf_note = "quflow: " + qres["error"]
        else:
            qf_note = f"quflow {qres['version']} ({interp})"
            for n in ns:
                c, r = qres["check"][str(n)], report["ns"][n]
                om_diff = np.abs(np.array(c["omega"]) - np.array(r["omega"])).max() / np.abs(r["omega"]).max()
                pi_diff = np.abs(np.array(c["pi"]) - np.array(r["pi"])).max() / np.abs(r["pi"]).max()
                a_diff = np.abs(np.array(c["a_fun2shr"]) - np.array(r["a_omega"]))[1:].max()
                print(f"  quflow N = {n}: shr2mat diagonal vs numpy {om_diff:.1e} (off-diagonal "
                      f"{c['offdiag']:.1e}), fun2shr a_l vs Gauss–Legendre {a_diff:.1e}, solve_poisson pi vs "
                      f"dense inverse {pi_diff:.1e}, hbar {c['hbar']:.15g} vs {2 / np.sqrt(n * n - 1):.15g}",
                      file=sys.stderr)
            for n_str, t in qres["timing"].items():
                qf_rows.append((int(n_str), t["fixed10"], t["auto"], t["iterations"], t["poisson"], t["steps"]))
    load1 = os.getloadavg()
    report["load_end"] = load1

    print("| N | dimension | engine certify | numpy assembly | scipy eigh (all) | scipy eigh (top) "
          "| Sigma^2 engine | Sigma^2 scipy | rel. diff | max_m diff / Sigma^2 |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for n, dim, te, ta, tg, tt, se, sd, rd, bd in rows:
        print(f"| {n} | {dim} | {te * 1e3:.1f} ms | {ta:.2f} s | {tg:.2f} s | {tt:.2f} s | {se:.10e} | {sd:.10e} "
              f"| {rd:.1e} | {bd:.1e} |")
    print()
    if qf_rows:
        print("| N | quflow isomp per step (10 iterations) | per step (tol auto) | iterations per step (auto) "
              "| solve_poisson | steps timed |")
        print("| ---: | ---: | ---: | ---: | ---: | ---: |")
        for n, t10, ta, it, tp, steps in qf_rows:
            print(f"| {n} | {t10 * 1e3:.3f} ms | {ta * 1e3:.3f} ms | {it:.2f} | {tp * 1e3:.3f} ms | {steps} |")
        print()
    if qf_note:
        print(qf_note)
    print(f"load average (1, 5, 15 min): start {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}, "
          f"end {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f}; {os.cpu_count()} cores; engine best of {args.reps}, "
          f"eigh best of {args.eigh_reps}, assembly once; threads "
          f"{os.environ.get('OPENBLAS_NUM_THREADS', 'library defaults')}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(report, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
