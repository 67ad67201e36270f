#!/usr/bin/env python3
"""Independent numpy/scipy baseline of the stochastic energy-Casimir pipeline.

This script is the *independent* Python implementation used for two things:

  (a) cross-checking the numbers produced by the Rust engine (`verify`), and
  (b) the side-by-side speed baseline (``--bench N``).

It was written from the conventions, pipeline and contract (docs/architecture.md
§1, §2, §4) and the paper only, without
reading the Rust code.  Conventions (docs/architecture.md §1):

  * structure constants  [e_a, e_b] = c^k_ab e_k, stored as ``c[a, b, k]``;
  * (ad*_xi mu)_b = c^k_ab xi^a mu_k, i.e. ad*_xi is the matrix
    ``(ad*_xi)[b, k] = sum_a c[a, b, k] xi[a]``;
  * Stratonovich SDE  d mu = ad*_{Dh(mu)} mu dt + sum_i ad*_{sigma_i} mu o dW^i.

Pipeline per spec (docs/architecture.md §2, steps 1-8 without the exact level):

  1. equilibrium residual  ad*_{Dh(mu_e)} mu_e            -> not_an_equilibrium
  2. noise residuals       ad*_{sigma_i} mu_e              -> noise_incompatible
  3. multipliers: Dh + sum lambda_j DC_j + sum nu_j DF_j = 0 (affine family
     = particular solution + null space, parameter t)
  4. P0(t) = D2h + sum lambda_j D2C_j + sum nu_j D2F_j, G = [DC | DF] at mu_e,
     Z = orthonormal basis of ker G^T, R(t) = Z^T P0(t) Z.  Free t: maximise
     lambda_min(+-R(t)) (concave) for definiteness, then minimise Sigma^2(t)
     over the definite region.  P = P0 + m Y Y^T (Y = orthonormal basis of
     range G) with m from the Schur complement.
  5. A = Jacobian of the drift, B_i = ad*_{sigma_i}, Atilde = A + 1/2 sum B_i^2,
     Q = sym(P Atilde + Atilde^T P) + sum B_i^T P B_i, drift residual
     sym(P A + A^T P).
  6. Sigma^2 = max(0, largest generalized eigenvalue of (Q, P)) (of (-Q, -P)
     when P < 0), T = ln(eps/delta)/Sigma^2.
  7. No definite P: eigenvalue of A with Re > 1e-9 ||A|| -> linearly_unstable,
     else inconclusive.

Two Sigma^2 values are reported:

  * ``sigma2_P``: for the concrete P printed (finite Schur multiple m);
  * ``sigma2``  : the sharpest value over the Casimir freedom, i.e. the limit
    m -> infinity of the Finsler term (Q does not depend on m when every
    conserved quantity is preserved by the linearised drift and the noise,
    and then the limit is the generalized eigenproblem restricted to
    ker G^T: (Z^T Q Z, Z^T P0 Z)), minimised over the multiplier family t.
    When Q does depend on m (a first integral not commuting with the noise)
    ``sigma2`` falls back to ``sigma2_P``.
  In every fixture the two coincide because Z^T P0 Y = 0 there.

Sympy is used only up front (parsing, exact Casimir / first-integral checks,
differentiation, lambdify).  ``--bench N`` times N repetitions of steps 1-7
(``certify``) on the prepared data, i.e. everything after parsing.

Usage:  python3 numpy_pipeline.py SPEC.json [SPEC.json ...] [--bench N] [--pretty]
"""

import subprocess
import sys

try:
    import numpy as np
    import scipy.linalg
    import scipy.optimize
    import sympy
except ImportError:  # install our own dependencies
    subprocess.check_call([sys.executable, "-m", "pip", "install", "--quiet",
                           "numpy", "scipy", "sympy"])
    import numpy as np
    import scipy.linalg
    import scipy.optimize
    import sympy

import argparse
import json
import math
import time
from dataclasses import dataclass, field

from sympy.parsing.sympy_parser import (parse_expr, standard_transformations,
                                        convert_xor, rationalize)

_TRANSFORMS = standard_transformations + (convert_xor, rationalize)

# --------------------------------------------------------------------------
# Lie algebras
# --------------------------------------------------------------------------


def _eps(a, b, k):
    return int(sympy.LeviCivita(a, b, k))


def so3_constants():
    c = [[[sympy.Integer(_eps(a, b, k)) for k in range(3)] for b in range(3)]
         for a in range(3)]
    return c


def se3_constants():
    """so(3) ⋉ R^3: [(xi,u),(eta,v)] = (xi x eta, xi x v - eta x u)."""
    n = 6
    c = [[[sympy.Integer(0)] * n for _ in range(n)] for _ in range(n)]
    for a in range(3):
        for b in range(3):
            for k in range(3):
                e = _eps(a, b, k)
                c[a][b][k] = sympy.Integer(e)
                c[a][3 + b][3 + k] = sympy.Integer(e)     # [xi, v] = xi x v
                c[3 + b][a][3 + k] = sympy.Integer(-e)    # antisymmetry
    return c


BUILTINS = {
    "so3": dict(coordinates=["Pi1", "Pi2", "Pi3"], constants=so3_constants,
                casimirs=["(Pi1^2 + Pi2^2 + Pi3^2)/2"]),
    "se3": dict(coordinates=["Pi1", "Pi2", "Pi3", "Gamma1", "Gamma2", "Gamma3"],
                constants=se3_constants,
                casimirs=["(Gamma1^2 + Gamma2^2 + Gamma3^2)/2",
                          "Pi1*Gamma1 + Pi2*Gamma2 + Pi3*Gamma3"]),
}


class SpecError(Exception):
    pass


def to_rational(v, local=None, where="?"):
    """Numbers or strings -> exact sympy expression (decimals become rationals)."""
    if isinstance(v, bool):
        raise SpecError(f"{where}: boolean is not a number")
    if isinstance(v, int):
        return sympy.Integer(v)
    if isinstance(v, float):
        return sympy.Rational(repr(float(v)))
    if isinstance(v, str):
        try:
            return parse_expr(v, local_dict=dict(local or {}),
                              transformations=_TRANSFORMS, evaluate=True)
        except Exception as exc:  # noqa: BLE001
            raise SpecError(f"{where}: cannot parse {v!r}: {exc}") from exc
    raise SpecError(f"{where}: expected number or string, got {type(v).__name__}")


def custom_constants(alg):
    coords = alg["coordinates"]
    n = len(coords)
    c = [[[sympy.Integer(0)] * n for _ in range(n)] for _ in range(n)]
    seen = {}
    for i, row in enumerate(alg["structure_constants"]):
        a, b, k, val = row
        val = to_rational(val, where=f"algebra.structure_constants[{i}][3]")
        if a == b and val != 0:
            raise SpecError(f"algebra.structure_constants[{i}]: c^{k}_{a}{a} must be 0")
        for (x, y, s) in ((a, b, 1), (b, a, -1)):
            key = (x, y, k)
            if key in seen and seen[key] != s * val:
                raise SpecError(f"algebra.structure_constants[{i}]: inconsistent with antisymmetry")
            seen[key] = s * val
            c[x][y][k] = s * val
    # Jacobi: [[e_a,e_b],e_d] + cyclic = 0
    for a in range(n):
        for b in range(n):
            for d in range(n):
                for m in range(n):
                    s = sum(c[a][b][k] * c[k][d][m] + c[b][d][k] * c[k][a][m]
                            + c[d][a][k] * c[k][b][m] for k in range(n))
                    if sympy.simplify(s) != 0:
                        raise SpecError(f"algebra.structure_constants: Jacobi fails for ({a},{b},{d})")
    return c


def discover_casimirs(c, mus):
    """Linear and quadratic polynomial Casimirs by exact linear algebra.

    C(mu) is a Casimir iff ad*_{DC(mu)} mu = 0 identically in mu."""
    n = len(mus)
    found = []
    for deg in (1, 2):
        monos = sorted(sympy.itermonomials(mus, deg, deg), key=sympy.default_sort_key)
        coeffs = sympy.symbols(f"k0:{len(monos)}")
        C = sum(k * m for k, m in zip(coeffs, monos))
        dC = [sympy.diff(C, x) for x in mus]
        eqs = []
        for b in range(n):
            expr = sympy.expand(sum(c[a][b][k] * dC[a] * mus[k]
                                    for a in range(n) for k in range(n)))
            eqs += sympy.Poly(expr, *mus).coeffs() if expr != 0 else []
        if eqs:
            Mat, _ = sympy.linear_eq_to_matrix(eqs, coeffs)
            basis = Mat.nullspace()
        else:
            basis = [sympy.eye(len(coeffs))[:, i] for i in range(len(coeffs))]
        for v in basis:
            found.append(sympy.expand(sum(v[i] * monos[i] for i in range(len(monos)))))
    return found


# --------------------------------------------------------------------------
# Preparation (untimed): parse, check, differentiate, lambdify
# --------------------------------------------------------------------------


@dataclass
class Prepared:
    name: str
    spec: dict
    coords: list
    n: int
    c: np.ndarray                     # c[a, b, k]
    ders: object                      # lambdified: mu -> flat list of all derivatives
    m_cas: int
    m_fi: int
    mu_e: np.ndarray
    sigmas: list
    eps_delta: tuple = None
    checks: dict = field(default_factory=dict)
    casimir_exprs: list = field(default_factory=list)
    first_integral_exprs: list = field(default_factory=list)


def _bracket(c, df, dg, mus):
    """{F, G}(mu) up to sign: <mu, [DF, DG]> = c^k_ab dF_a dG_b mu_k."""
    n = len(mus)
    return sympy.expand(sum(c[a][b][k] * df[a] * dg[b] * mus[k]
                            for a in range(n) for b in range(n) for k in range(n)
                            if c[a][b][k] != 0))


def prepare(spec):
    name = spec.get("name", "?")
    alg = spec.get("algebra")
    if isinstance(alg, str):
        if alg not in BUILTINS:
            raise SpecError(f"algebra: unknown builtin {alg!r}")
        bi = BUILTINS[alg]
        coords, c_sym, default_cas = bi["coordinates"], bi["constants"](), bi["casimirs"]
    elif isinstance(alg, dict):
        coords, c_sym, default_cas = alg["coordinates"], custom_constants(alg), None
    else:
        raise SpecError("algebra: expected a builtin name or an object")
    n = len(coords)
    mus = sympy.symbols(coords, real=True)
    cdict = dict(zip(coords, mus))

    params = {}
    for pname, pval in (spec.get("parameters") or {}).items():
        params[pname] = to_rational(pval, params, where=f"parameters.{pname}")
    local = dict(params)
    local.update(cdict)

    def ex(s, where):
        return sympy.sympify(to_rational(s, local, where=where))

    h = ex(spec["hamiltonian"], "hamiltonian")
    if spec.get("casimirs") is not None:
        cas = [ex(s, f"casimirs[{i}]") for i, s in enumerate(spec["casimirs"])]
        cas_source = "spec"
    elif default_cas is not None:
        cas = [ex(s, "builtin casimir") for s in default_cas]
        cas_source = "builtin"
    else:
        cas = discover_casimirs(c_sym, list(mus))
        cas_source = "discovered (degree <= 2)"
    fis = [ex(s, f"first_integrals[{i}]") for i, s in enumerate(spec.get("first_integrals") or [])]

    mu_e = [ex(v, f"equilibrium[{i}]") for i, v in enumerate(spec["equilibrium"])]
    if len(mu_e) != n:
        raise SpecError(f"equilibrium: expected {n} components, got {len(mu_e)}")
    sig = []
    for i, s in enumerate(spec.get("noise") or []):
        if len(s) != n:
            raise SpecError(f"noise[{i}]: expected {n} components")
        sig.append([ex(v, f"noise[{i}][{j}]") for j, v in enumerate(s)])

    # exact checks (docs/architecture.md §2, step 1)
    grad = lambda f: [sympy.diff(f, x) for x in mus]  # noqa: E731
    dh = grad(h)
    checks = {"casimir_source": cas_source, "casimirs": [], "first_integrals": []}
    for C in cas:
        dC = grad(C)
        is_cas = all(sympy.expand(sum(c_sym[a][b][k] * dC[a] * mus[k]
                                      for a in range(n) for k in range(n))) == 0
                     for b in range(n))
        noise_comm = [_bracket(c_sym, dC, s, mus) == 0 for s in sig]
        checks["casimirs"].append({"expr": str(C), "is_casimir": bool(is_cas),
                                   "commutes_with_noise": noise_comm})
    for F in fis:
        dF = grad(F)
        checks["first_integrals"].append({
            "expr": str(F), "commutes_with_h": bool(_bracket(c_sym, dF, dh, mus) == 0),
            "commutes_with_noise": [_bracket(c_sym, dF, s, mus) == 0 for s in sig]})

    # one lambdified function returning every derivative needed, flattened
    flat = list(dh) + [sympy.diff(h, x, y) for x in mus for y in mus]
    for K in cas + fis:
        flat += grad(K) + [sympy.diff(K, x, y) for x in mus for y in mus]
    ders = sympy.lambdify(list(mus), flat, "math")

    c_num = np.array([[[float(c_sym[a][b][k]) for k in range(n)] for b in range(n)]
                      for a in range(n)])
    st = spec.get("stopping")
    eps_delta = (float(ex(st["epsilon"], "stopping.epsilon")),
                 float(ex(st["delta"], "stopping.delta"))) if st else None
    return Prepared(name=name, spec=spec, coords=coords, n=n, c=c_num, ders=ders,
                    m_cas=len(cas), m_fi=len(fis),
                    mu_e=np.array([float(v) for v in mu_e]),
                    sigmas=[np.array([float(v) for v in s]) for s in sig],
                    eps_delta=eps_delta, checks=checks,
                    casimir_exprs=cas, first_integral_exprs=fis)


# --------------------------------------------------------------------------
# The timed part: steps 1-7
# --------------------------------------------------------------------------


def _gen_max(Q, P, s):
    """Largest generalized eigenvalue of (s Q, s P), s P > 0."""
    if Q.shape[0] == 0:
        return 0.0
    return float(scipy.linalg.eigh(s * Q, s * P, eigvals_only=True)[-1])


def _lmin(M):
    return float(np.linalg.eigvalsh(M)[0]) if M.shape[0] else math.inf


def certify(pp):
    n, c, mu = pp.n, pp.c, pp.mu_e
    out = {"name": pp.name, "level": "numerical"}
    vals = np.asarray(pp.ders(*mu), dtype=float)
    nn = n * n
    dh, Hh = vals[:n], vals[n:n + nn].reshape(n, n)
    m = pp.m_cas + pp.m_fi
    blk = vals[n + nn:].reshape(m, n + nn) if m else np.zeros((0, n + nn))
    G = blk[:, :n].T                                   # n x m gradients
    Hs = blk[:, n:].reshape(m, n, n)                   # Hessians of C_j, F_j

    def adstar(xi):                                    # (ad*_xi)[b, k]
        return np.tensordot(xi, c, axes=(0, 0))

    scale = max(1.0, float(np.abs(c).max()) * np.linalg.norm(dh) * np.linalg.norm(mu))
    tol = 1e-12 * scale

    # 1. equilibrium
    ad_dh = adstar(dh)
    res_eq = ad_dh @ mu
    out["equilibrium_residual"] = float(np.linalg.norm(res_eq))
    if out["equilibrium_residual"] > tol:
        out.update(verdict="not_an_equilibrium", residual_vector=res_eq.tolist(),
                   sigma2=None, T=None, P=None, Q=None, multipliers=None,
                   max_real_eig=None)
        return out

    # 2. noise
    Bs = [adstar(s) for s in pp.sigmas]
    nres = [float(np.linalg.norm(B @ mu)) for B in Bs]
    out["noise_residuals"] = nres
    if any(r > 1e-12 * max(1.0, float(np.abs(c).max()) * np.linalg.norm(s) * np.linalg.norm(mu))
           for r, s in zip(nres, pp.sigmas)):
        L = np.tensordot(c, mu, axes=(2, 0)).T         # L[b, a] = c^k_ab mu_k
        _, sv, vt = np.linalg.svd(L)
        rk = int((sv > 1e-10 * max(1.0, sv[0] if sv.size else 0)).sum())
        out.update(verdict="noise_incompatible", isotropy_basis=vt[rk:].tolist(),
                   sigma2=None, T=None, P=None, Q=None, multipliers=None,
                   max_real_eig=None)
        return out

    # 5 (needed for both branches). linearisation
    A = np.einsum("abk,am,k->bm", c, Hh, mu) + ad_dh
    At = A + 0.5 * sum((B @ B for B in Bs), np.zeros((n, n)))
    eigA = np.linalg.eigvals(A)
    imax = int(np.argmax(eigA.real))
    out["max_real_eig"] = [float(eigA[imax].real), float(eigA[imax].imag)]

    def Qof(P):
        Q = P @ At + At.T @ P + sum((B.T @ P @ B for B in Bs), np.zeros((n, n)))
        return 0.5 * (Q + Q.T)

    # 3. multipliers
    if m:
        U, sv, vt = np.linalg.svd(G)
        rk = int((sv > 1e-10 * max(1.0, sv[0])).sum())
        x_p = np.linalg.lstsq(G, -dh, rcond=None)[0]
        mres = float(np.linalg.norm(G @ x_p + dh))
        Nul = vt[rk:].T                                # m x r family directions
        Y, Z = U[:, :rk], U[:, rk:]
    else:
        x_p, Nul, rk = np.zeros(0), np.zeros((0, 0)), 0
        mres = float(np.linalg.norm(dh))
        Y, Z = np.zeros((n, 0)), np.eye(n)
    out["multiplier_residual"] = mres
    sign, t_best, P0 = 0, None, None
    if mres <= 1e-9 * max(1.0, np.linalg.norm(dh)):
        Pp = Hh + np.tensordot(x_p, Hs, axes=(0, 0))
        Pk = [np.tensordot(Nul[:, k], Hs, axes=(0, 0)) for k in range(Nul.shape[1])]
        Rp, Rk = Z.T @ Pp @ Z, [Z.T @ X @ Z for X in Pk]
        ptol = 1e-10 * max(1.0, np.linalg.norm(Pp, 2))

        def Rof(t):
            return Rp + sum((ti * Ri for ti, Ri in zip(t, Rk)), np.zeros_like(Rp))

        r = len(Pk)
        out["multipliers"] = {"lambda": x_p[:pp.m_cas].tolist(), "nu": x_p[pp.m_cas:].tolist(),
                              "family_dimension": r, "t": [0.0] * r,
                              "family_directions": Nul.T.tolist()}
        # 4. definiteness of R(t), both signs
        for s in (1, -1):
            if r == 0:
                t, val = np.zeros(0), _lmin(s * Rp)
            else:
                step = max(1.0, float(np.linalg.norm(x_p)))
                simplex = np.vstack([np.zeros(r), step * np.eye(r)])
                res = scipy.optimize.minimize(lambda t: -_lmin(s * Rof(t)), np.zeros(r),
                                              method="Nelder-Mead",
                                              options=dict(initial_simplex=simplex,
                                                           xatol=1e-10, fatol=1e-13,
                                                           maxiter=400 * r))
                t, val = res.x, -res.fun
            if val > ptol:
                sign, t_best = s, t
                out["lambda_min_restricted"] = s * val
                break
        if sign:
            # Q is linear in P: Q(P0(t)) = Qp + sum t_k Qk
            Qp, Qk = Z.T @ Qof(Pp) @ Z, [Z.T @ Qof(X) @ Z for X in Pk]
            QYY = Qof(Y @ Y.T)
            m_indep = bool(np.linalg.norm(QYY) <= 1e-9 * max(1.0, np.linalg.norm(Qof(Pp))))

            # generalized eigenvalues below this are rounding noise -> 0
            s2_tol = 1e-10 * max(1.0, sum(float(np.linalg.norm(B, 2)) ** 2 for B in Bs))

            def s2(t):
                Rt = Rof(t)
                if _lmin(sign * Rt) <= ptol:
                    return math.inf
                Qt = Qp + sum((ti * Qi for ti, Qi in zip(t, Qk)), np.zeros_like(Qp))
                v = _gen_max(Qt, Rt, sign)
                return v if v > s2_tol else 0.0

            if r and m_indep:                           # minimise Sigma^2 over the family
                t0 = t_best
                step = max(1e-3, 0.1 * float(np.linalg.norm(t0)) + 1e-2)
                res = scipy.optimize.minimize(s2, t0, method="Nelder-Mead",
                                              options=dict(initial_simplex=np.vstack([t0, t0 + step * np.eye(r)]),
                                                           xatol=1e-12, fatol=1e-15, maxiter=400 * r))
                if res.fun < s2(t0) - s2_tol:       # keep t0 unless clearly better
                    t_best = res.x
            lam = x_p + (Nul @ t_best if r else 0.0)
            P0 = Pp + sum((ti * Xi for ti, Xi in zip(t_best, Pk)), np.zeros((n, n)))
            out["multipliers"] = {"lambda": lam[:pp.m_cas].tolist(),
                                  "nu": lam[pp.m_cas:].tolist(),
                                  "family_dimension": r,
                                  "t": [float(x) for x in t_best],
                                  "family_directions": Nul.T.tolist()}
            # Finsler / Schur: P = P0 + mfac Y Y^T
            if rk:
                R = Z.T @ P0 @ Z
                C = Z.T @ P0 @ Y
                S = Y.T @ P0 @ Y
                Schur = S - C.T @ np.linalg.solve(R, C) if R.shape[0] else S
                m0 = -_lmin(sign * Schur)
                mfac = sign * (max(m0, 0.0) + max(1.0, float(np.linalg.norm(P0, 2))))
            else:
                mfac = 0.0
            P = P0 + mfac * (Y @ Y.T)
            Q = Qof(P)
            out["finsler_m"] = float(mfac)
            out["P"], out["Q"] = P.tolist(), Q.tolist()
            out["drift_residual"] = float(np.linalg.norm(0.5 * (P @ A + A.T @ P + (P @ A + A.T @ P).T)))
            out["Q_depends_on_finsler_m"] = not m_indep
            # 6. Sigma^2
            v = _gen_max(Q, P, sign)
            out["sigma2_P"] = v if v > s2_tol else 0.0
            out["sigma2"] = s2(t_best) if m_indep else out["sigma2_P"]
            out["definiteness"] = "positive" if sign > 0 else "negative"
            out["verdict"] = "stable"
            if pp.eps_delta:
                e, d = pp.eps_delta
                out["T"] = math.log(e / d) / out["sigma2"] if out["sigma2"] > 0 else "inf"
            else:
                out["T"] = None
            return out
    # 7. no definite P
    out.update(sigma2=None, T=None, P=None, Q=None)
    out.setdefault("multipliers", None)
    nA = float(np.linalg.norm(A, 2))
    if eigA[imax].real > 1e-9 * nA:
        out["verdict"] = "linearly_unstable"
        out["unstable_eigenvalue"] = out["max_real_eig"]
    else:
        out["verdict"] = "inconclusive"
    return out


# --------------------------------------------------------------------------


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("specs", nargs="+")
    ap.add_argument("--bench", type=int, default=0,
                    help="time N repetitions of steps 1-7 per spec")
    ap.add_argument("--pretty", action="store_true")
    ap.add_argument("--summary", action="store_true",
                    help="print only name, verdict, sigma2, T, max_real_eig")
    args = ap.parse_args(argv)
    status = 0
    for path in args.specs:
        try:
            with open(path) as fh:
                spec = json.load(fh)
            pp = prepare(spec)
        except (SpecError, KeyError, json.JSONDecodeError) as exc:
            print(json.dumps({"file": path, "error": str(exc)}))
            status = 2
            continue
        cert = certify(pp)
        cert["checks"] = pp.checks
        keys = ["name", "verdict", "sigma2", "T", "P", "Q", "multipliers", "max_real_eig"]
        if args.summary:
            line = {k: cert.get(k) for k in keys if k not in ("P", "Q")}
        else:
            line = {k: cert.get(k) for k in keys}
            line.update({k: v for k, v in cert.items() if k not in line})
        print(json.dumps(line, indent=2 if args.pretty else None))
        if args.bench:
            certify(pp)                                  # warm-up
            t0 = time.perf_counter()
            for _ in range(args.bench):
                certify(pp)
            dt = time.perf_counter() - t0
            print(json.dumps({"name": pp.name, "bench_reps": args.bench,
                              "us_per_certificate": 1e6 * dt / args.bench}))
    return status


if __name__ == "__main__":
    sys.exit(main())
