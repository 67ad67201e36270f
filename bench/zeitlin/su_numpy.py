"""su(N) in numpy, shared by the Zeitlin side-by-side scripts of this folder.

The spin-(N-1)/2 matrices, `ad` on column-major `vec`, an orthonormal basis
of su(N) for `Re tr(A B^*)/N`, and a relative difference. Importing this
module sets no thread count: each script pins its libraries' threads
before it imports numpy, then imports this.
"""

import numpy as np
import scipy.sparse as sps


def spin_matrices(n):
    """Hermitian S_1, S_2, S_3 of the spin-(N-1)/2 representation, as in tests/zeitlin.rs."""
    s = (n - 1) / 2
    mj = s - np.arange(n)
    sp = np.zeros((n, n))
    for j in range(1, n):
        sp[j - 1, j] = np.sqrt(s * (s + 1) - mj[j] * (mj[j] + 1))
    return [(sp + sp.T) / 2 + 0j, -0.5j * (sp - sp.T), np.diag(mj) + 0j]


def ad(a):
    """w -> [a, w] on column-major vec(w): kron(I, a) - kron(a^T, I)."""
    a = sps.csr_matrix(a)
    eye = sps.identity(a.shape[0], format="csr")
    return (sps.kron(eye, a) - sps.kron(a.T, eye)).tocsr()


def su_basis(n):
    """Orthonormal basis of su(N) for Re tr(A B^*)/N, as columns of vec(E_a).

    Ordered by diagonal m = 1..N-1 (pairs (j, j+m), real then imaginary part)
    and then the N-1 trace-free diagonal elements (Helmert vectors, deliberately
    not the u_l of the quantisation), so that each block m is a contiguous
    slice of the coordinates.
    """
    rows, cols, vals, slices = [], [], [], {}
    col = 0
    r = np.sqrt(n / 2)
    idx = lambda i, j: i + j * n  # noqa: E731  (column-major vec)
    for m in range(1, n):
        start = col
        for j in range(n - m):
            k = j + m
            rows += [idx(j, k), idx(k, j)]
            cols += [col, col]
            vals += [r, -r]
            rows += [idx(j, k), idx(k, j)]
            cols += [col + 1, col + 1]
            vals += [1j * r, 1j * r]
            col += 2
        slices[m] = slice(start, col)
    start = col
    for q in range(1, n):
        h = np.zeros(n)
        h[:q] = 1.0
        h[q] = -q
        h /= np.sqrt(q * (q + 1))
        for i in range(q + 1):
            rows.append(idx(i, i))
            cols.append(col)
            vals.append(1j * np.sqrt(n) * h[i])
        col += 1
    slices[0] = slice(start, col)
    v = sps.csc_matrix((np.array(vals, dtype=complex), (rows, cols)), shape=(n * n, n * n - 1))
    return v, slices


def dense_sigma2(n, cert, eigh_reps):
    import scipy.linalg as sla
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


def rel(a, b):
    return abs(a - b) / max(abs(a), abs(b), 1e-300)
