#!/usr/bin/env python3
"""Cross-check of hand-derived closed forms against the independent pipeline.

For each claim (a)-(d) we (1) redo the computation symbolically in sympy,
straight from the formulas of docs/architecture.md §2 (own code path: exact
multipliers, exact ker G^T basis, exact A, B, Q; Sigma^2 from the roots of
det(Z^T Q Z - s Z^T P0 Z) = 0), and (2) run numpy_pipeline.certify on random
parameter sets and compare with the claimed formula.  As extra independent
evidence, for each numeric case we also compute the second-moment (moment
Lyapunov) exponent of the linearised SDE, which must not exceed Sigma^2.

Usage: python3 check_closed_forms.py [--n 20] [--seed 1]
"""

import argparse
import math
import sys
import os

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy_pipeline as npl  # noqa: E402  (installs deps if needed)
import numpy as np  # noqa: E402
import sympy as sp  # noqa: E402

# --------------------------------------------------------------------------
# symbolic pipeline (independent of numpy_pipeline.certify)
# --------------------------------------------------------------------------


def sym_pipeline(c, mus, h, cons, mu_e, sigmas, extra_assume=None):
    """Return dict with multipliers family, R, Qz (restricted) and A, symbolically.

    c: nested list c[a][b][k]; cons: list of conserved quantities (Casimirs
    then first integrals); all exact sympy."""
    n = len(mus)
    sub = dict(zip(mus, mu_e))
    grad = lambda f: sp.Matrix([sp.diff(f, x) for x in mus])  # noqa: E731
    hess = lambda f: sp.hessian(f, mus)  # noqa: E731
    dh = grad(h).subs(sub)
    Hh = hess(h).subs(sub)
    G = sp.Matrix.hstack(*[grad(K).subs(sub) for K in cons]) if cons else sp.zeros(n, 0)

    def adstar(xi):
        return sp.Matrix(n, n, lambda b, k: sum(c[a][b][k] * xi[a] for a in range(n)))

    eq_res = sp.simplify(adstar(dh) * sp.Matrix(mu_e))
    Bs = [adstar(s) for s in sigmas]
    noise_res = [sp.simplify(B * sp.Matrix(mu_e)) for B in Bs]
    # multipliers: general solution of G x = -dh
    xs = sp.symbols(f"x0:{len(cons)}")
    sol = sp.linsolve((G, -dh), *xs)
    sol = list(sol)[0]
    free = sorted(set().union(*[sp.sympify(v).free_symbols for v in sol]) & set(xs),
                  key=str)
    P0 = Hh + sum((sol[j] * hess(K).subs(sub) for j, K in enumerate(cons)), sp.zeros(n, n))
    Z = sp.Matrix.hstack(*(G.T.nullspace())) if G.shape[1] else sp.eye(n)
    # drift Jacobian: f_b = c^k_ab dh_a mu_k
    f = sp.Matrix(n, 1, lambda b, _: sum(c[a][b][k] * sp.diff(h, mus[a]) * mus[k]
                                         for a in range(n) for k in range(n)))
    A = f.jacobian(mus).subs(sub)
    At = A + sum((B * B for B in Bs), sp.zeros(n, n)) / 2
    Q0 = P0 * At + At.T * P0 + sum((B.T * P0 * B for B in Bs), sp.zeros(n, n))
    drift = sp.simplify(P0 * A + A.T * P0)
    R = sp.simplify(Z.T * P0 * Z)
    Qz = sp.simplify(Z.T * Q0 * Z)
    # Q(G G^T) must vanish for the Finsler term to be irrelevant
    QG = sp.simplify(G * G.T * At + At.T * G * G.T
                     + sum((B.T * G * G.T * B for B in Bs), sp.zeros(n, n)))
    return dict(eq_res=eq_res, noise_res=noise_res, mult=sol, free=free, P0=P0,
                Z=Z, R=R, Qz=Qz, A=A, drift=drift, QG=QG)


def gen_eigs(Qz, R):
    s = sp.Symbol("s")
    poly = sp.factor(sp.expand((Qz - s * R).det()))
    return s, poly, sp.roots(sp.Poly(sp.numer(sp.together(poly)), s))


def moment_exponent(prep, cert):
    """Spectral abscissa of S -> At S + S At^T + sum B S B^T (second moments)."""
    n, c, mu = prep.n, prep.c, prep.mu_e
    vals = np.asarray(prep.ders(*mu), dtype=float)
    dh, Hh = vals[:n], vals[n:n + n * n].reshape(n, n)
    adstar = lambda xi: np.tensordot(xi, c, axes=(0, 0))  # noqa: E731
    A = np.einsum("abk,am,k->bm", c, Hh, mu) + adstar(dh)
    Bs = [adstar(s) for s in prep.sigmas]
    At = A + 0.5 * sum((B @ B for B in Bs), np.zeros((n, n)))
    I = np.eye(n)
    L = np.kron(At, I) + np.kron(I, At) + sum((np.kron(B, B) for B in Bs), np.zeros((n * n, n * n)))
    return float(np.linalg.eigvals(L).real.max())


def run(spec):
    pp = npl.prepare(spec)
    cert = npl.certify(pp)
    return pp, cert


# --------------------------------------------------------------------------

def rigid_spec(I1, I2, I3, sig):
    return {"name": "rb", "algebra": "so3",
            "parameters": {"I1": I1, "I2": I2, "I3": I3, "sigma": sig},
            "hamiltonian": "Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3)",
            "equilibrium": [1, 0, 0], "noise": [["sigma", 0, 0]]}


def heavy_spec(I1, I2, I3, mgl, p, sig, lagrange=False):
    s = {"name": "ht", "algebra": "se3",
         "parameters": {"I1": I1, "I2": I2, "I3": I3, "mgl": mgl, "p": p, "sigma": sig},
         "hamiltonian": "Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3) + mgl*Gamma3",
         "casimirs": ["(Gamma1^2 + Gamma2^2 + Gamma3^2)/2",
                      "Pi1*Gamma1 + Pi2*Gamma2 + Pi3*Gamma3"],
         "equilibrium": [0, 0, "p", 0, 0, 1], "noise": [[0, 0, "sigma", 0, 0, 0]]}
    if lagrange:
        s["first_integrals"] = ["Pi3"]
    return s


def so21_spec(I1, I2, I3, sig):
    return {"name": "so21", "algebra": {"coordinates": ["M1", "M2", "M3"],
                                        "structure_constants": [[0, 1, 2, -1], [1, 2, 0, 1], [2, 0, 1, 1]]},
            "parameters": {"I1": I1, "I2": I2, "I3": I3, "sigma": sig},
            "hamiltonian": "M1^2/(2*I1) + M2^2/(2*I2) + M3^2/(2*I3)",
            "casimirs": ["M1^2 + M2^2 - M3^2"],
            "equilibrium": [0, 0, 1], "noise": [[0, 0, "sigma"]]}


def rel(a, b):
    return abs(a - b) / max(1e-300, abs(b)) if b != 0 else abs(a)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    I1, I2, I3, sig, mgl, p = sp.symbols("I1 I2 I3 sigma mgl p", positive=True)
    worst = {}

    # ---------------------------------------------------------------- (a)
    print("=== (a) rigid body, mu_e = e1, noise sigma e1")
    P1, P2, P3 = mus = sp.symbols("Pi1 Pi2 Pi3", real=True)
    c3 = npl.so3_constants()
    h = P1**2 / (2 * I1) + P2**2 / (2 * I2) + P3**2 / (2 * I3)
    r = sym_pipeline(c3, list(mus), h, [(P1**2 + P2**2 + P3**2) / 2], [1, 0, 0], [[sig, 0, 0]])
    s, poly, roots = gen_eigs(r["Qz"], r["R"])
    print(" multipliers:", r["mult"], " drift residual zero:", r["drift"].is_zero_matrix,
          " Q(GG^T)=0:", r["QG"].is_zero_matrix)
    print(" R =", r["R"].tolist(), " Z^T Q Z =", r["Qz"].tolist())
    print(" det(ZQZ - s R) =", poly, " roots:", list(roots))
    claim_a = sig**2 * I1 * (I2 - I3) / (I3 * (I1 - I2))
    print(" claim in roots:", any(sp.simplify(rt - claim_a) == 0 for rt in roots))
    other = [rt for rt in roots if sp.simplify(rt - claim_a) != 0]
    print(" other root:", [sp.factor(o) for o in other],
          "; claim - other =", [sp.factor(claim_a - o) for o in other])
    errs = []
    for kind in ("major", "minor"):
        for _ in range(args.n):
            v = np.sort(rng.uniform(0.2, 5.0, 3))
            i1, i2, i3 = (v[2], v[1], v[0]) if kind == "major" else (v[0], v[1], v[2])
            sg = rng.uniform(0.05, 1.0)
            pp, ce = run(rigid_spec(i1, i2, i3, sg))
            cl = sg**2 * i1 * (i2 - i3) / (i3 * (i1 - i2))
            me = moment_exponent(pp, ce)
            errs.append(rel(ce["sigma2"], cl))
            assert ce["verdict"] == "stable", ce
            assert me <= ce["sigma2"] * (1 + 1e-9) + 1e-12
        print(f" {kind}: {args.n} random triples, max rel err vs claim = {max(errs[-args.n:]):.2e}")
    worst["a"] = max(errs)

    # ---------------------------------------------------------------- (b)
    print("=== (b) heavy top (se3), mu_e = (0,0,p,0,0,1), noise sigma e3")
    mus6 = sp.symbols("Pi1 Pi2 Pi3 Gamma1 Gamma2 Gamma3", real=True)
    Pi, Ga = mus6[:3], mus6[3:]
    c6 = npl.se3_constants()
    mglr = sp.Symbol("mgl", real=True)         # allow either sign of mgl
    hh = sum(Pi[i]**2 / (2 * [I1, I2, I3][i]) for i in range(3)) + mglr * Ga[2]
    cas = [sum(g**2 for g in Ga) / 2, sum(a * b for a, b in zip(Pi, Ga))]
    r = sym_pipeline(c6, list(mus6), hh, cas, [0, 0, p, 0, 0, 1], [[0, 0, sig, 0, 0, 0]])
    print(" equilibrium residual:", list(r["eq_res"]), " noise residual:", list(r["noise_res"][0]))
    print(" multipliers:", [sp.simplify(x) for x in r["mult"]],
          " drift residual zero:", r["drift"].is_zero_matrix, " Q(GG^T)=0:", r["QG"].is_zero_matrix)
    print(" R =", r["R"].tolist())
    # definiteness of R: it is block diagonal in (Pi_i, Gamma_i) pairs after reordering
    print(" leading minors of R:", [sp.factor(r["R"][:k, :k].det()) for k in range(1, 5)])
    s, poly, roots = gen_eigs(r["Qz"], r["R"])
    print(" det(ZQZ - s R) =", poly)
    print(" roots:", [sp.factor(x) for x in roots])
    claim_b = lambda i1, i2, i3, m, pp_, sg: (  # noqa: E731
        sg**2 * (abs(i1 - i2) / min(i1, i2)) * i3 * (pp_**2 - m * i3)
        / (pp_**2 * (i3 - max(i1, i2)) - m * i3**2))
    # symbolic comparison in the branch I1 > I2 (min = I2, max = I1)
    cb = sig**2 * ((I1 - I2) / I2) * I3 * (p**2 - mglr * I3) / (p**2 * (I3 - I1) - mglr * I3**2)
    print(" claim (I1>I2 branch) equals a root:", [sp.simplify(x - cb) == 0 for x in roots])
    errs, nstab, nfail, mism = [], 0, 0, []
    tries = 0
    while nstab < args.n and tries < 200 * args.n:
        tries += 1
        i1, i2, i3 = rng.uniform(0.3, 4.0, 3)
        m = rng.uniform(-2.0, 2.0)
        pv = rng.uniform(0.2, 6.0)
        sg = rng.uniform(0.05, 1.0)
        claimed_stable = all(pv**2 * (i3 - ii) / i3**2 > m for ii in (i1, i2))
        pp, ce = run(heavy_spec(i1, i2, i3, m, pv, sg))
        got_stable = ce["verdict"] == "stable"
        if got_stable != claimed_stable:
            mism.append((i1, i2, i3, m, pv, ce["verdict"]))
            continue
        if not got_stable:
            nfail += 1
            continue
        nstab += 1
        cl = claim_b(i1, i2, i3, m, pv, sg)
        e = rel(ce["sigma2"], cl)
        errs.append(e)
        me = moment_exponent(pp, ce)
        assert me <= ce["sigma2"] * (1 + 1e-8) + 1e-12, (me, ce["sigma2"])
        if e > 1e-8:
            print("  MISMATCH", dict(I1=i1, I2=i2, I3=i3, mgl=m, p=pv, sigma=sg),
                  "pipeline", ce["sigma2"], "claim", cl)
    print(f" {nstab} stable random sets (mgl in [-2,2]), {nfail} EC-not-stable sets agreed,"
          f" stability-criterion mismatches: {len(mism)}; max rel err Sigma^2 = {max(errs):.2e}")
    worst["b"] = max(errs)
    # mgl > 0 only, the physically upright case
    errs = []
    k = 0
    while k < args.n:
        i1, i2 = rng.uniform(0.3, 2.0, 2)
        i3 = max(i1, i2) + rng.uniform(0.1, 2.0)
        m = rng.uniform(0.1, 2.0)
        pmin2 = max(m * i3**2 / (i3 - ii) for ii in (i1, i2))
        pv = math.sqrt(pmin2 * rng.uniform(1.05, 4.0))
        sg = rng.uniform(0.05, 1.0)
        _, ce = run(heavy_spec(i1, i2, i3, m, pv, sg))
        assert ce["verdict"] == "stable"
        errs.append(rel(ce["sigma2"], claim_b(i1, i2, i3, m, pv, sg)))
        k += 1
    print(f" upright (mgl>0, I3>max) {args.n} sets: max rel err = {max(errs):.2e}")
    worst["b_upright"] = max(errs)
    # hanging top (mgl < 0) with a flat body I3 < min(I1, I2): stable iff p^2 < |mgl| I3^2/(Ii - I3)
    errs, k = [], 0
    while k < args.n:
        i3 = rng.uniform(0.3, 2.0)
        i1, i2 = i3 + rng.uniform(0.1, 2.0, 2)
        m = -rng.uniform(0.1, 2.0)
        pmax2 = min(-m * i3**2 / (ii - i3) for ii in (i1, i2))
        pv = math.sqrt(pmax2 * rng.uniform(0.05, 0.95))
        sg = rng.uniform(0.05, 1.0)
        _, ce = run(heavy_spec(i1, i2, i3, m, pv, sg))
        assert ce["verdict"] == "stable", ce["verdict"]
        errs.append(rel(ce["sigma2"], claim_b(i1, i2, i3, m, pv, sg)))
        _, ce = run(heavy_spec(i1, i2, i3, m, math.sqrt(pmax2 * rng.uniform(1.05, 3.0)), sg))
        assert ce["verdict"] != "stable", ce["verdict"]
        k += 1
    print(f" hanging (mgl<0, I3<min) {args.n} sets: max rel err = {max(errs):.2e}; "
          f"p^2 above the bound never certified stable")
    worst["b_hanging"] = max(errs)

    # ---------------------------------------------------------------- (c)
    print("=== (c) Lagrange top I1 = I2, first integral Pi3")
    hl = (Pi[0]**2 + Pi[1]**2) / (2 * I1) + Pi[2]**2 / (2 * I3) + mglr * Ga[2]
    r = sym_pipeline(c6, list(mus6), hl, cas + [Pi[2]], [0, 0, p, 0, 0, 1], [[0, 0, sig, 0, 0, 0]])
    print(" multiplier family:", [sp.simplify(x) for x in r["mult"]], " free:", r["free"])
    print(" R(t) =", r["R"].tolist())
    print(" Z^T Q Z identically zero (all t):", r["Qz"].is_zero_matrix,
          " drift residual zero:", r["drift"].is_zero_matrix, " Q(GG^T)=0:", r["QG"].is_zero_matrix)
    t = r["free"][0]
    # Z = (Pi1, Pi2, Gamma1, Gamma2) here: R(t) = two identical blocks on (Pi_i, Gamma_i)
    blk = r["R"].extract([0, 2], [0, 2])
    assert sp.simplify(blk - r["R"].extract([1, 3], [1, 3])).is_zero_matrix
    d2 = sp.expand(blk.det())
    tstar = sp.solve(sp.diff(d2, t), t)[0]
    print(" block (Pi_i, Gamma_i) =", blk.tolist(), "; det concave in t, max at t* =", sp.simplify(tstar),
          "; max det =", sp.factor(d2.subs(t, tstar)), " (>0 iff p^2 > 4 mgl I1)")
    lam = sp.Symbol("lam")
    cp = sp.factor((r["A"] - lam * sp.eye(6)).det())
    print(" charpoly(A) =", cp)
    # candidate eigenvalues: +-( i(p/I3 - p/(2 I1)) +- (1/2) sqrt(4 mgl/I1 - p^2/I1^2) )
    gr = sp.Rational(1, 2) * sp.sqrt(4 * mglr / I1 - p**2 / I1**2)
    cands = [s1 * (sp.I * (p / I3 - p / (2 * I1)) + s2 * gr) for s1 in (1, -1) for s2 in (1, -1)]
    quart = sp.cancel(cp / lam**2)
    print(" the 4 candidates  +-( i(p/I3 - p/(2I1)) +- (1/2)sqrt(4mgl/I1 - p^2/I1^2) ) are roots of charpoly/lam^2:",
          [sp.simplify(sp.expand(quart.subs(lam, e))) == 0 for e in cands],
          "(so for p^2 < 4 mgl I1 the real parts are exactly +-(1/2)sqrt(4mgl/I1 - p^2/I1^2))")
    # numeric
    errs_u, zs = [], []
    for _ in range(args.n):
        i1, i3 = rng.uniform(0.3, 3.0, 2)
        m = rng.uniform(0.1, 2.0)
        sg = rng.uniform(0.05, 1.0)
        pc = math.sqrt(4 * m * i1)
        pv = pc * rng.uniform(1.02, 3.0)
        _, ce = run(heavy_spec(i1, i1, i3, m, pv, sg, lagrange=True))
        assert ce["verdict"] == "stable", ce["verdict"]
        zs.append(ce["sigma2"])
        pv = pc * rng.uniform(0.05, 0.98)
        _, ce = run(heavy_spec(i1, i1, i3, m, pv, sg, lagrange=True))
        assert ce["verdict"] == "linearly_unstable", ce["verdict"]
        cl = 0.5 * math.sqrt(4 * m / i1 - pv**2 / i1**2)
        errs_u.append(rel(ce["max_real_eig"][0], cl))
    print(f" {args.n} stable sets: max Sigma^2 = {max(zs):.2e};"
          f" {args.n} unstable sets: max rel err of Re(eig) vs claim = {max(errs_u):.2e}")
    worst["c_sigma2"] = max(zs)
    worst["c_eig"] = max(errs_u)

    # ---------------------------------------------------------------- (d)
    print("=== (d) so(2,1) rigid body, mu_e = e3, noise sigma e3")
    M = sp.symbols("M1 M2 M3", real=True)
    spec = so21_spec(1, 2, 3, "3/10")
    c21 = npl.custom_constants(spec["algebra"])
    hs = M[0]**2 / (2 * I1) + M[1]**2 / (2 * I2) + M[2]**2 / (2 * I3)
    print(" discovered quadratic/linear Casimirs:", npl.discover_casimirs(c21, list(M)))
    r = sym_pipeline(c21, list(M), hs, [M[0]**2 + M[1]**2 - M[2]**2], [0, 0, 1], [[0, 0, sig]])
    s, poly, roots = gen_eigs(r["Qz"], r["R"])
    print(" R =", r["R"].tolist(), " ZQZ =", r["Qz"].tolist())
    print(" roots:", [sp.factor(x) for x in roots])
    q1, q2 = 1 / I1 + 1 / I3, 1 / I2 + 1 / I3
    print(" claim sigma^2(q1/q2 - 1) or sigma^2(q2/q1 - 1) are the roots:",
          [sp.simplify(x - sig**2 * (q1 / q2 - 1)) == 0 or sp.simplify(x - sig**2 * (q2 / q1 - 1)) == 0
           for x in roots])
    errs = []
    for _ in range(args.n):
        i1, i2, i3 = rng.uniform(0.2, 5.0, 3)
        sg = rng.uniform(0.05, 1.0)
        _, ce = run(so21_spec(i1, i2, i3, sg))
        a, b = 1 / i1 + 1 / i3, 1 / i2 + 1 / i3
        errs.append(rel(ce["sigma2"], sg**2 * (max(a, b) / min(a, b) - 1)))
    print(f" {args.n} random triples: max rel err = {max(errs):.2e}")
    worst["d"] = max(errs)
    print("=== worst:", worst)


if __name__ == "__main__":
    main()
