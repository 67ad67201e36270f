#!/usr/bin/env python3
r"""Random study of the engine's certificates: how sharp, how sound.

Generates N random stochastic Lie-Poisson systems (dimension 3 to 8) as spec
files, certifies each one with one or more engine binaries ("before" and
"after" a change), checks each certificate with the same binary, and compares
against

  * the independent numpy/scipy pipeline ``bench/numpy_pipeline.py`` (verdict,
    linearisation spectrum, and its sharp infimum of Sigma^2 over the Casimir
    freedom when Q does not depend on M), and
  * exact rational arithmetic done here with ``fractions.Fraction``: every
    ``stable`` certificate's P must be exactly definite with the stated sign,
    and (extra) P is rebuilt from the recorded multipliers and M, Q from P,
    and ``S sP - sQ >= 0`` is decided exactly for the certified rational S.

What the reference adds to numpy_pipeline (each found by --self-test, which
compares a system with the same system in a random basis):

  * its spec is read exactly here (prepare_exact: derivatives at mu_e exact,
    rounded once) instead of by its sympy prepare, which takes up to 20 s on
    a dense 8-dimensional algebra and whose float equilibrium test rejects
    true equilibria with large coefficients (--reference-parse sympy to use it);
  * instability is decided on the 120-digit spectrum of the exact A (mpmath):
    numpy_pipeline's 1e-9 |A| test is passed by rounding alone for defective
    spectra (a nilpotent A in a random basis);
  * its Nelder-Mead over a multiplier family runs off to |t| ~ 1e20..1e120 in
    random bases, where its definiteness and Sigma^2 are rounding artefacts:
    for family dimension 1 and 2 the infimum is searched again on exact
    reduced matrices (refine_family_infimum), with the limit |t| -> infinity
    followed in 100-digit arithmetic when the search is pinned at the
    conditioning cut-off (hp_ray_limit); its "stable" counts only when a
    definite form is confirmed exactly (exact_confirm_reference);
  * two LinAlgError fallbacks (see numpy_pipeline()).
The Casimirs the reference gets are the unscaled ones (numpy_pipeline's rank
decision on the gradients is relative to 1e-10, which 10^+-6 factors defeat).
The infimum is "unknown" when Q depends on M, for a family of dimension > 2,
or for a 2-parameter family whose infimum is only approached at infinity.

Usage (see --help):

  python3 bench/random_study.py --count 2000 --seed 1 \
      --bin before=/work/verify-before --out /work/study-before.jsonl \
      --md /work/study-before.md

  # a later binary, reusing the numpy reference of the first run:
  python3 bench/random_study.py --count 2000 --seed 1 \
      --bin after=target/release/verify --reference-cache /work/study-before.jsonl \
      --out /work/study-after.jsonl --md /work/study-after.md --cases /work/study-cases-after

  # both binaries side by side in one table (the reference from the cache):
  python3 bench/random_study.py --count 2000 --seed 1 --bin before=/work/verify-before \
      --bin after=target/release/verify --reference-cache /work/study-before.jsonl \
      --out /work/study-both.jsonl --md /work/study-both.md --cases /work/study-cases-both

  # re-judge and re-tabulate an earlier run without running anything:
  python3 bench/random_study.py --report-only /work/study-before.jsonl

  python3 bench/random_study.py --only-generate DIR --count 50 --seed 3
  python3 bench/random_study.py --self-test

Conventions (docs/architecture.md §1): [e_a, e_b] = c^k_ab e_k,
(ad*_xi mu)_b = c^k_ab xi^a mu_k, d mu = ad*_{Dh(mu)} mu dt + sum_i ad*_{sigma_i} mu o dW^i.

Change of basis.  Take a new basis e'_a = sum_b T_ab e_b with T an integer
matrix, det T != 0.  Then
  [e'_a, e'_b] = T_ai T_bj c^k_ij e_k = T_ai T_bj c^k_ij (T^-1)_kl e'_l,
  so  c'^l_ab = sum T_ai T_bj c^k_ij (T^-1)_kl;
  dual coordinates  mu'_a = <mu, e'_a> = T_ab mu_b, i.e. mu' = T mu;
  algebra elements  xi = xi'^a e'_a = (T^T xi')^b e_b, i.e. xi' = T^-T xi
  (noise fields and Dh transform like this);
  functions         h'(mu') = h(T^-1 mu')  (Hamiltonian, Casimirs, first integrals).
With these, (ad*_{xi'} mu')' = T (ad*_xi mu), so equilibria and compatible
noise map to equilibria and compatible noise, P' = T^-T P T^-1 and
Q' = T^-T Q T^-1 (congruence), and every generalized eigenvalue, hence
Sigma^2, is unchanged.  The generator asserts the first identity on random
vectors for every transformed algebra, and re-parses every written spec with
the exact parser below to confirm (exactly) the equilibrium and the noise
compatibility in the new coordinates.  ``--self-test`` checks against the
numpy pipeline that the verdict and the infimum are basis independent.
"""

import argparse
import concurrent.futures as cf
import hashlib
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from fractions import Fraction as F

HERE = os.path.dirname(os.path.abspath(__file__))
sys.dont_write_bytecode = True      # no __pycache__ in bench/ when importing numpy_pipeline

# ==========================================================================
# Exact linear algebra over Fractions
# ==========================================================================


def mat_zero(r, c):
    return [[F(0)] * c for _ in range(r)]


def mat_eye(n):
    m = mat_zero(n, n)
    for i in range(n):
        m[i][i] = F(1)
    return m


def mat_mul(A, B):
    n, k, m = len(A), len(B), (len(B[0]) if B else 0)
    out = mat_zero(n, m)
    for i in range(n):
        Ai = A[i]
        oi = out[i]
        for t in range(k):
            a = Ai[t]
            if a:
                Bt = B[t]
                for j in range(m):
                    b = Bt[j]
                    if b:
                        oi[j] += a * b
    return out


def mat_T(A):
    return [list(r) for r in zip(*A)] if A else []


def mat_add(A, B, s=F(1)):
    return [[a + s * b for a, b in zip(ra, rb)] for ra, rb in zip(A, B)]


def mat_scale(A, s):
    return [[s * a for a in r] for r in A]


def mat_vec(A, v):
    return [sum((a * x for a, x in zip(r, v) if a and x), F(0)) for r in A]


def rref(A):
    """Reduced row echelon form (copy) and pivot columns."""
    M = [list(r) for r in A]
    rows = len(M)
    cols = len(M[0]) if rows else 0
    piv = []
    r = 0
    for c in range(cols):
        p = None
        for i in range(r, rows):
            if M[i][c] != 0:
                p = i
                break
        if p is None:
            continue
        M[r], M[p] = M[p], M[r]
        inv = 1 / M[r][c]
        M[r] = [x * inv for x in M[r]]
        for i in range(rows):
            if i != r and M[i][c] != 0:
                f = M[i][c]
                Mi, Mr = M[i], M[r]
                M[i] = [a - f * b for a, b in zip(Mi, Mr)]
        piv.append(c)
        r += 1
        if r == rows:
            break
    return M, piv


def nullspace(A, ncols=None):
    """Basis (list of vectors) of {x : A x = 0}."""
    if not A:
        n = ncols or 0
        return [[F(int(i == j)) for i in range(n)] for j in range(n)]
    n = len(A[0])
    R, piv = rref(A)
    free = [c for c in range(n) if c not in piv]
    basis = []
    for f in free:
        v = [F(0)] * n
        v[f] = F(1)
        for i, pc in enumerate(piv):
            v[pc] = -R[i][f]
        basis.append(v)
    return basis


def solve_affine(A, b):
    """Particular solution and null-space basis of A x = b, or (None, None)."""
    n = len(A[0]) if A else 0
    aug = [list(r) + [bi] for r, bi in zip(A, b)]
    R, piv = rref(aug)
    if n in piv:
        return None, None
    x = [F(0)] * n
    for i, pc in enumerate(piv):
        x[pc] = R[i][n]
    return x, nullspace(A, n)


def rank(A):
    if not A:
        return 0
    return len(rref(A)[1])


def det(A):
    n = len(A)
    M = [list(r) for r in A]
    d = F(1)
    for c in range(n):
        p = next((i for i in range(c, n) if M[i][c] != 0), None)
        if p is None:
            return F(0)
        if p != c:
            M[c], M[p] = M[p], M[c]
            d = -d
        d *= M[c][c]
        for i in range(c + 1, n):
            if M[i][c]:
                f = M[i][c] / M[c][c]
                M[i] = [a - f * b for a, b in zip(M[i], M[c])]
    return d


def inverse(A):
    n = len(A)
    aug = [list(r) + [F(int(i == j)) for j in range(n)] for i, r in enumerate(A)]
    R, piv = rref(aug)
    assert piv[:n] == list(range(n)), "singular matrix"
    return [r[n:] for r in R[:n]]


def is_pos_def(A):
    """Exact LDL^T without pivoting: every pivot > 0 <=> positive definite."""
    n = len(A)
    M = [list(r) for r in A]
    for c in range(n):
        if M[c][c] <= 0:
            return False
        inv = 1 / M[c][c]
        for i in range(c + 1, n):
            if M[i][c]:
                f = M[i][c] * inv
                Mc = M[c]
                Mi = M[i]
                for j in range(c + 1, n):
                    Mi[j] -= f * Mc[j]
    return True


def is_pos_semidef(A):
    """Exact test of A >= 0 (symmetric), handling singular A: symmetric
    elimination on a positive diagonal pivot; a zero diagonal forces a zero
    row and column; a negative diagonal is a certificate of indefiniteness."""
    M = [list(r) for r in A]
    idx = list(range(len(M)))
    while idx:
        if any(M[i][i] < 0 for i in idx):
            return False
        p = next((i for i in idx if M[i][i] > 0), None)
        if p is None:                     # zero diagonal: need the block to be zero
            return all(M[i][j] == 0 for i in idx for j in idx)
        for i in idx:                     # a zero diagonal entry needs a zero row
            if M[i][i] == 0 and any(M[i][j] != 0 for j in idx):
                return False
        idx.remove(p)
        inv = 1 / M[p][p]
        for i in idx:
            if M[i][p]:
                f = M[i][p] * inv
                for j in idx:
                    if M[p][j]:
                        M[i][j] -= f * M[p][j]
    return True


def fstr(x):
    x = F(x)
    return str(x.numerator) if x.denominator == 1 else f"{x.numerator}/{x.denominator}"


def fparse(s):
    if isinstance(s, bool):
        raise ValueError("boolean")
    if isinstance(s, int):
        return F(s)
    if isinstance(s, float):
        return F(repr(s))
    return F(str(s).strip())


# ==========================================================================
# Exact polynomials and an expression parser (the spec grammar: + - * / ^ ())
# ==========================================================================


class Poly:
    __slots__ = ("n", "t")

    def __init__(self, n, terms=None):
        self.n = n
        self.t = {k: v for k, v in (terms or {}).items() if v != 0}

    @staticmethod
    def const(n, c):
        return Poly(n, {(0,) * n: F(c)})

    @staticmethod
    def var(n, i, c=1):
        e = [0] * n
        e[i] = 1
        return Poly(n, {tuple(e): F(c)})

    def copy(self):
        return Poly(self.n, dict(self.t))

    def __add__(self, o):
        if not isinstance(o, Poly):
            o = Poly.const(self.n, o)
        t = dict(self.t)
        for k, v in o.t.items():
            t[k] = t.get(k, F(0)) + v
        return Poly(self.n, t)

    __radd__ = __add__

    def __neg__(self):
        return Poly(self.n, {k: -v for k, v in self.t.items()})

    def __sub__(self, o):
        return self + (-o if isinstance(o, Poly) else Poly.const(self.n, -F(o)))

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, Poly):
            o = F(o)
            return Poly(self.n, {k: v * o for k, v in self.t.items()})
        t = {}
        for k1, v1 in self.t.items():
            for k2, v2 in o.t.items():
                k = tuple(a + b for a, b in zip(k1, k2))
                t[k] = t.get(k, F(0)) + v1 * v2
        return Poly(self.n, t)

    __rmul__ = __mul__

    def __pow__(self, e):
        assert isinstance(e, int) and e >= 0
        r = Poly.const(self.n, 1)
        b = self
        while e:
            if e & 1:
                r = r * b
            b = b * b
            e >>= 1
        return r

    def is_zero(self):
        return not self.t

    def is_const(self):
        return all(sum(k) == 0 for k in self.t)

    def const_value(self):
        return self.t.get((0,) * self.n, F(0))

    def degree(self):
        return max((sum(k) for k in self.t), default=0)

    def diff(self, i):
        t = {}
        for k, v in self.t.items():
            if k[i]:
                kk = list(k)
                kk[i] -= 1
                kk = tuple(kk)
                t[kk] = t.get(kk, F(0)) + v * k[i]
        return Poly(self.n, t)

    def eval(self, x):
        s = F(0)
        for k, v in self.t.items():
            p = v
            for xi, e in zip(x, k):
                if e:
                    p *= xi ** e
            s += p
        return s

    def grad_at(self, x):
        return [self.diff(i).eval(x) for i in range(self.n)]

    def hess_at(self, x):
        d = [self.diff(i) for i in range(self.n)]
        return [[d[i].diff(j).eval(x) for j in range(self.n)] for i in range(self.n)]

    def linear_subst(self, L):
        """p(L y): old variable i becomes sum_j L[i][j] y_j (L is n x m)."""
        m = len(L[0])
        lin = [Poly(m, {tuple(int(j == q) for j in range(m)): L[i][q] for q in range(m) if L[i][q]})
               for i in range(self.n)]
        cache = {}

        def pw(i, e):
            if (i, e) not in cache:
                cache[(i, e)] = lin[i] ** e
            return cache[(i, e)]
        out = Poly(m)
        for k, v in self.t.items():
            term = Poly.const(m, v)
            for i, e in enumerate(k):
                if e:
                    term = term * pw(i, e)
            out = out + term
        return out

    def embed(self, n, offset):
        """Same polynomial, variables shifted into a ring of n variables."""
        t = {}
        for k, v in self.t.items():
            kk = [0] * n
            kk[offset:offset + self.n] = k
            t[tuple(kk)] = v
        return Poly(n, t)

    def to_str(self, names):
        if not self.t:
            return "0"
        keys = sorted(self.t, key=lambda k: (-sum(k), [-e for e in k]))
        out = []
        for k in keys:
            v = self.t[k]
            mono = "*".join((names[i] if e == 1 else f"{names[i]}^{e}") for i, e in enumerate(k) if e)
            a = abs(v)
            if mono:
                body = mono if a == 1 else f"{fstr(a)}*{mono}"
            else:
                body = fstr(a)
            if not out:
                out.append(("-" if v < 0 else "") + body)
            else:
                out.append((" - " if v < 0 else " + ") + body)
        return "".join(out)


_TOK = re.compile(r"\s*(?:(\d+\.?\d*(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?)|([A-Za-z_][A-Za-z_0-9]*)|(\S))")


class ParseError(Exception):
    pass


def parse_poly(text, names, params=None):
    """Exact parse of a spec expression into a Poly over the coordinates."""
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        return Poly.const(len(names), fparse(text))
    n = len(names)
    idx = {nm: i for i, nm in enumerate(names)}
    params = params or {}
    toks = []
    pos = 0
    s = str(text)
    while pos < len(s):
        m = _TOK.match(s, pos)
        if not m or m.end() == pos:
            if s[pos:].strip() == "":
                break
            raise ParseError(f"bad token at {pos} in {s!r}")
        pos = m.end()
        if m.group(1):
            toks.append(("num", F(m.group(1))))
        elif m.group(2):
            toks.append(("id", m.group(2)))
        elif m.group(3):
            toks.append(("op", m.group(3)))
    toks.append(("end", None))
    i = [0]

    def peek():
        return toks[i[0]]

    def take():
        t = toks[i[0]]
        i[0] += 1
        return t

    def expr():
        v = term()
        while peek() in (("op", "+"), ("op", "-")):
            op = take()[1]
            w = term()
            v = v + w if op == "+" else v - w
        return v

    def term():
        v = unary()
        while peek() in (("op", "*"), ("op", "/")):
            op = take()[1]
            w = unary()
            if op == "*":
                v = v * w
            else:
                if not w.is_const() or w.const_value() == 0:
                    raise ParseError("division by a non-constant or zero")
                v = v * (1 / w.const_value())
        return v

    def unary():
        if peek() == ("op", "-"):
            take()
            return -unary()
        if peek() == ("op", "+"):
            take()
            return unary()
        return power()

    def power():
        b = atom()
        if peek() == ("op", "^"):
            take()
            e = unary()
            if not e.is_const() or e.const_value().denominator != 1 or e.const_value() < 0:
                raise ParseError("exponent must be a non-negative integer")
            return b ** int(e.const_value())
        return b

    def atom():
        k, v = take()
        if k == "num":
            return Poly.const(n, v)
        if k == "id":
            if v in idx:
                return Poly.var(n, idx[v])
            if v in params:
                return Poly.const(n, params[v])
            raise ParseError(f"unknown identifier {v}")
        if (k, v) == ("op", "("):
            r = expr()
            if take() != ("op", ")"):
                raise ParseError("missing )")
            return r
        raise ParseError(f"unexpected {v!r}")
    r = expr()
    if peek()[0] != "end":
        raise ParseError(f"trailing input in {s!r}")
    return r


# ==========================================================================
# Lie algebras (exact): structure constants c[(a, b, k)] = c^k_ab
# ==========================================================================


class Algebra:
    def __init__(self, names, rows, casimirs=None, builtin=None, label=""):
        self.names = list(names)
        self.n = len(names)
        n = self.n
        self.c = [[[F(0)] * n for _ in range(n)] for _ in range(n)]
        for a, b, k, v in rows:
            v = F(v)
            self.c[a][b][k] = v
            self.c[b][a][k] = -v
        self.casimirs = casimirs or []     # list of Poly
        self.builtin = builtin
        self.label = label

    def rows(self):
        out = []
        for a in range(self.n):
            for b in range(a + 1, self.n):
                for k in range(self.n):
                    if self.c[a][b][k] != 0:
                        out.append((a, b, k, self.c[a][b][k]))
        return out

    def jacobi_ok(self):
        n, c = self.n, self.c
        for a in range(n):
            for b in range(a + 1, n):
                for d in range(b + 1, n):
                    for m in range(n):
                        s = F(0)
                        for k in range(n):
                            s += (c[a][b][k] * c[k][d][m] + c[b][d][k] * c[k][a][m]
                                  + c[d][a][k] * c[k][b][m])
                        if s != 0:
                            return False
        return True

    def adstar_matrix(self, xi):
        """(ad*_xi)[b][k] = sum_a c^k_ab xi^a, so (ad*_xi mu)_b = sum_k (.)[b][k] mu_k."""
        n, c = self.n, self.c
        return [[sum((c[a][b][k] * xi[a] for a in range(n) if xi[a]), F(0)) for k in range(n)]
                for b in range(n)]

    def adstar(self, xi, mu):
        return mat_vec(self.adstar_matrix(xi), mu)

    def iso_matrix(self, mu):
        """L[b][a] = sum_k c^k_ab mu_k: ad*_xi mu = L xi."""
        n, c = self.n, self.c
        return [[sum((c[a][b][k] * mu[k] for k in range(n) if mu[k]), F(0)) for a in range(n)]
                for b in range(n)]

    def isotropy(self, mu):
        return nullspace(self.iso_matrix(mu), self.n)

    def is_casimir(self, C):
        """ad*_{DC(mu)} mu = 0 identically."""
        n, c = self.n, self.c
        dC = [C.diff(i) for i in range(n)]
        for b in range(n):
            s = Poly(n)
            for a in range(n):
                if dC[a].is_zero():
                    continue
                for k in range(n):
                    if c[a][b][k]:
                        s = s + dC[a] * Poly.var(n, k, c[a][b][k])
            if not s.is_zero():
                return False
        return True

    def bracket(self, Fp, G):
        """{F, G}(mu) = <mu, [DF, DG]> (sign convention irrelevant for zero tests)."""
        n, c = self.n, self.c
        dF = [Fp.diff(i) for i in range(n)]
        dG = [G.diff(i) for i in range(n)]
        s = Poly(n)
        for a in range(n):
            if dF[a].is_zero():
                continue
            for b in range(n):
                if dG[b].is_zero():
                    continue
                for k in range(n):
                    if c[a][b][k]:
                        s = s + dF[a] * dG[b] * Poly.var(n, k, c[a][b][k])
        return s


def _p(n, terms):
    """Poly from {(i, j, ...) var-index tuple: coeff}."""
    t = {}
    for vs, v in terms.items():
        e = [0] * n
        for i in vs:
            e[i] += 1
        t[tuple(e)] = t.get(tuple(e), F(0)) + F(v)
    return Poly(n, t)


EPS = [(0, 1, 2), (1, 2, 0), (2, 0, 1)]


def block(kind):
    """A canonical algebra block: Algebra with its (complete) polynomial Casimirs."""
    if kind == "so3":
        return Algebra(["Pi1", "Pi2", "Pi3"], [(a, b, k, 1) for a, b, k in EPS],
                       [_p(3, {(0, 0): F(1, 2), (1, 1): F(1, 2), (2, 2): F(1, 2)})], "so3", "so3")
    if kind == "se3":
        rows = [(a, b, k, 1) for a, b, k in EPS] + [(a, 3 + b, 3 + k, 1) for a, b, k in EPS] \
            + [(b, 3 + a, 3 + k, -1) for a, b, k in EPS]
        return Algebra(["Pi1", "Pi2", "Pi3", "Gamma1", "Gamma2", "Gamma3"], rows,
                       [_p(6, {(3, 3): F(1, 2), (4, 4): F(1, 2), (5, 5): F(1, 2)}),
                        _p(6, {(0, 3): 1, (1, 4): 1, (2, 5): 1})], "se3", "se3")
    if kind == "sl2":
        return Algebra(["muH", "muE", "muF"], [(0, 1, 1, 2), (0, 2, 2, -2), (1, 2, 0, 1)],
                       [_p(3, {(0, 0): 1, (1, 2): 4})], "sl2", "sl2")
    if kind == "so21":
        return Algebra(["M1", "M2", "M3"], [(0, 1, 2, -1), (1, 2, 0, 1), (2, 0, 1, 1)],
                       [_p(3, {(0, 0): F(1, 2), (1, 1): F(1, 2), (2, 2): F(-1, 2)})], None, "so21")
    if kind == "se2":
        return Algebra(["M", "P1", "P2"], [(0, 1, 2, 1), (0, 2, 1, -1)],
                       [_p(3, {(1, 1): 1, (2, 2): 1})], "se2", "se2")
    if kind == "heis":
        return Algebra(["muX", "muY", "muZ"], [(0, 1, 2, 1)], [_p(3, {(2,): 1})], "heisenberg", "heis")
    if kind == "osc":       # oscillator algebra: [J,X]=Y, [J,Y]=-X, [X,Y]=Z
        return Algebra(["J", "X", "Y", "Z"], [(0, 1, 2, 1), (0, 2, 1, -1), (1, 2, 3, 1)],
                       [_p(4, {(3,): 1}), _p(4, {(1, 1): 1, (2, 2): 1, (0, 3): 2})], None, "osc")
    if kind == "n4":        # filiform: [e1,e2]=e3, [e1,e3]=e4
        return Algebra(["a1", "a2", "a3", "a4"], [(0, 1, 2, 1), (0, 2, 3, 1)],
                       [_p(4, {(3,): 1}), _p(4, {(2, 2): 1, (1, 3): -2})], None, "n4")
    if kind == "e11":       # Poincare 1+1: [e3,e1]=e1, [e3,e2]=-e2
        return Algebra(["p1", "p2", "b"], [(2, 0, 0, 1), (2, 1, 1, -1)], [_p(3, {(0, 1): 1})], None, "e11")
    if kind == "aff1":      # [e1,e2]=e2, no Casimir (open orbits)
        return Algebra(["s", "t"], [(0, 1, 1, 1)], [], None, "aff1")
    if kind == "h5":
        return Algebra(["x1", "y1", "x2", "y2", "z"], [(0, 1, 4, 1), (2, 3, 4, 1)], [_p(5, {(4,): 1})], None, "h5")
    if kind == "R":
        return Algebra(["r"], [], [_p(1, {(0,): 1})], None, "R")
    raise KeyError(kind)


BLOCK_DIM = {"so3": 3, "se3": 6, "sl2": 3, "so21": 3, "se2": 3, "heis": 3, "osc": 4, "n4": 4,
             "e11": 3, "aff1": 2, "h5": 5, "R": 1}

# Combinations (direct sums), dimension 3..8.  Weights favour the named
# algebras of the brief.
COMBOS = [
    (["so3"], 6), (["sl2"], 3), (["so21"], 3), (["se2"], 3), (["heis"], 3), (["e11"], 2),
    (["aff1", "R"], 1),
    (["osc"], 4), (["n4"], 2), (["so3", "R"], 4), (["se2", "R"], 2), (["heis", "R"], 1),
    (["sl2", "R"], 2), (["aff1", "aff1"], 1), (["e11", "R"], 1),
    (["h5"], 2), (["so3", "aff1"], 1), (["so3", "R", "R"], 2), (["heis", "aff1"], 1),
    (["se3"], 6), (["so3", "so3"], 5), (["so3", "se2"], 3), (["se2", "se2"], 2), (["so3", "sl2"], 2),
    (["osc", "aff1"], 1), (["so3", "heis"], 1), (["so3", "e11"], 1), (["se2", "heis"], 1),
    (["so3", "so3", "R"], 3), (["se3", "R"], 2), (["so3", "osc"], 2), (["se2", "osc"], 1),
    (["so3", "se2", "R"], 2), (["h5", "aff1"], 1), (["so3", "n4"], 1),
    (["so3", "se2", "R", "R"], 3), (["so3", "so3", "R", "R"], 3), (["se3", "R", "R"], 2),
    (["osc", "osc"], 2), (["se2", "se2", "aff1"], 1), (["so3", "h5"], 1), (["so3", "sl2", "aff1"], 1),
    (["se3", "aff1"], 1), (["se2", "se2", "R", "R"], 1), (["so3", "osc", "R"], 1),
]


def direct_sum(kinds):
    blocks = [block(k) for k in kinds]
    if len(blocks) == 1:
        return blocks[0], [(0, blocks[0].n)]
    n = sum(b.n for b in blocks)
    rows, cas, names, spans = [], [], [], []
    off = 0
    for bi, b in enumerate(blocks):
        for a, bb, k, v in b.rows():
            rows.append((a + off, bb + off, k + off, v))
        for C in b.casimirs:
            cas.append(C.embed(n, off))
        names += [f"{nm}_{bi + 1}" for nm in b.names]
        spans.append((off, off + b.n))
        off += b.n
    return Algebra(names, rows, cas, None, "+".join(kinds)), spans


def transform_algebra(g, T, Tinv, names):
    """c'^l_ab = T_ai T_bj c^k_ij (T^-1)_kl."""
    n = g.n
    # first W[i][j][l] = sum_k c^k_ij Tinv[k][l]
    W = [[[sum((g.c[i][j][k] * Tinv[k][l] for k in range(n) if g.c[i][j][k]), F(0)) for l in range(n)]
          for j in range(n)] for i in range(n)]
    rows = []
    for a in range(n):
        for b in range(a + 1, n):
            for l in range(n):
                s = F(0)
                for i in range(n):
                    if not T[a][i]:
                        continue
                    for j in range(n):
                        if T[b][j] and W[i][j][l]:
                            s += T[a][i] * T[b][j] * W[i][j][l]
                if s:
                    rows.append((a, b, l, s))
    cas = [C.linear_subst(Tinv) for C in g.casimirs]
    return Algebra(names, rows, cas, None, g.label)


# Builtins as the README documents them (used to read specs exactly).
BUILTIN_KIND = {"so3": "so3", "se3": "se3", "sl2": "sl2", "se2": "se2", "heisenberg": "heis"}


def algebra_of_spec(spec):
    alg = spec["algebra"]
    if isinstance(alg, str):
        return block(BUILTIN_KIND[alg])
    return Algebra(alg["coordinates"], [(a, b, k, fparse(v)) for a, b, k, v in alg["structure_constants"]])


# ==========================================================================
# Exact reading of a spec
# ==========================================================================


class ExactSystem:
    """The spec read exactly: algebra, h, Casimirs, first integrals, mu_e, noise."""

    def __init__(self, spec, casimir_exprs=None):
        self.spec = spec
        self.g = algebra_of_spec(spec)
        g = self.g
        names = g.names
        params = {}
        for k, v in (spec.get("parameters") or {}).items():
            params[k] = parse_poly(v, [], params).const_value() if isinstance(v, str) else fparse(v)
        self.params = params
        P = lambda s: parse_poly(s, names, params)  # noqa: E731
        self.h = P(spec["hamiltonian"])
        if casimir_exprs is not None:
            self.cas = [P(s) for s in casimir_exprs]
        elif spec.get("casimirs") is not None:
            self.cas = [P(s) for s in spec["casimirs"]]
        else:
            self.cas = list(g.casimirs)
        self.fis = [P(s) for s in (spec.get("first_integrals") or [])]
        self.mu = [P(v).const_value() for v in spec["equilibrium"]]
        self.noise = [[P(v).const_value() for v in s] for s in (spec.get("noise") or [])]

    def eq_residual(self):
        return self.g.adstar(self.h.grad_at(self.mu), self.mu)

    def noise_residuals(self):
        return [self.g.adstar(s, self.mu) for s in self.noise]

    def linearisation(self):
        """A[b][m] = d/dmu_m (ad*_{Dh(mu)} mu)_b at mu_e, and B_i = ad*_{sigma_i}."""
        g, n, mu = self.g, self.g.n, self.mu
        dh = self.h.grad_at(mu)
        H = self.h.hess_at(mu)
        c = g.c
        A = mat_zero(n, n)
        for b in range(n):
            for m in range(n):
                s = F(0)
                for a in range(n):
                    for k in range(n):
                        if c[a][b][k]:
                            if H[a][m] and mu[k]:
                                s += c[a][b][k] * H[a][m] * mu[k]
                    if c[a][b][m] and dh[a]:
                        s += c[a][b][m] * dh[a]
                A[b][m] = s
        Bs = [g.adstar_matrix(s) for s in self.noise]
        return A, Bs


def q_of(P, A, Bs):
    """Q = sym(P At + At^T P + sum B^T P B), At = A + 1/2 sum B^2."""
    n = len(P)
    At = [list(r) for r in A]
    for B in Bs:
        At = mat_add(At, mat_mul(B, B), F(1, 2))
    Q = mat_add(mat_mul(P, At), mat_mul(mat_T(At), P))
    for B in Bs:
        Q = mat_add(Q, mat_mul(mat_mul(mat_T(B), P), B))
    return [[(Q[i][j] + Q[j][i]) / 2 for j in range(n)] for i in range(n)]


# ==========================================================================
# The generator
# ==========================================================================


def rand_rat(rng, num=3, dens=(1, 1, 1, 2, 3, 5), zero_ok=True):
    while True:
        v = F(rng.randint(-num, num), rng.choice(dens))
        if v or zero_ok:
            return v


def rand_T(rng, n):
    """Random integer matrix, entries in [-2, 2], det != 0, moderate conditioning."""
    import numpy as np
    while True:
        T = [[rng.choice([-2, -1, -1, 0, 0, 0, 1, 1, 2]) for _ in range(n)] for _ in range(n)]
        for i in range(n):                 # a bias towards the identity keeps cond small
            if rng.random() < 0.6:
                T[i][i] = rng.choice([1, -1, 2])
        Tn = np.array(T, dtype=float)
        if abs(np.linalg.det(Tn)) < 0.5:
            continue
        if np.linalg.cond(Tn) > 200:
            continue
        return [[F(x) for x in r] for r in T]


def rand_scale(rng):
    u = rng.uniform(-6, 6)
    e = math.floor(u)
    mant = F(round(10 ** (u - e) * 1000), 1000)
    return mant * F(10) ** e


def quad_poly(n, H, b):
    """1/2 x^T H x + b.x"""
    t = {}
    for i in range(n):
        for j in range(i, n):
            v = H[i][j] / 2 if i == j else H[i][j]
            if v:
                e = [0] * n
                e[i] += 1
                e[j] += 1
                t[tuple(e)] = t.get(tuple(e), F(0)) + v
        if b[i]:
            e = [0] * n
            e[i] = 1
            t[tuple(e)] = t.get(tuple(e), F(0)) + b[i]
    return Poly(n, t)


def combo(rng, basis, zero_ok=True):
    v = [F(0)] * (len(basis[0]) if basis else 0)
    for w in basis:
        c = rand_rat(rng)
        v = [x + c * y for x, y in zip(v, w)]
    if not zero_ok and basis and all(x == 0 for x in v):
        return combo(rng, basis, zero_ok)
    return v


def sym_basis(n):
    out = []
    for i in range(n):
        for j in range(i, n):
            M = mat_zero(n, n)
            M[i][j] = M[j][i] = F(1)
            out.append(M)
    return out


class System:
    pass


def gen_system(rng, idx, seed, force_canonical=False, force_random_basis=None):
    """One random system in canonical coordinates, and its spec (perhaps in a
    random rational basis).  Returns (spec, ref_spec, meta)."""
    kinds = rng.choices([c for c, _ in COMBOS], weights=[w for _, w in COMBOS])[0]
    g, spans = direct_sum(kinds)
    n = g.n
    meta = {"algebra": g.label, "dim": n}

    # -- equilibrium
    mu = [F(0)] * n
    for (lo, hi), kind in zip(spans, kinds):
        special = rng.random() < 0.2
        for i in range(lo, hi):
            if special and rng.random() < 0.6:
                mu[i] = F(0)
            else:
                mu[i] = F(rng.choice([-3, -2, -1, 1, 2, 3]), rng.choice([1, 1, 2]))
            if rng.random() < 0.25:
                mu[i] = F(0)
    iso = g.isotropy(mu)
    cas = g.casimirs
    G = [C.grad_at(mu) for C in cas]               # gradients, one per Casimir
    Gspan = [v for v in G if any(v)]

    # -- first integral kind
    fi_kind = None
    r = rng.random()
    if r < 0.10 and len(spans) >= 2:
        fi_kind = "block_energy"
    elif r < 0.22:
        fi_kind = "linear"

    # -- Hamiltonian: H, b (linear), cubic part
    def rand_H(definite):
        if definite:
            L = [[F(rng.choice([-1, 0, 0, 1])) for _ in range(n)] for _ in range(n)]
            H = mat_mul(L, mat_T(L))
            for i in range(n):
                H[i][i] += F(rng.randint(1, 4), rng.choice([1, 2]))
            if rng.random() < 0.3:
                H = mat_scale(H, F(-1))
            return H
        H = mat_zero(n, n)
        for i in range(n):
            for j in range(i, n):
                v = rand_rat(rng) if (i == j or rng.random() < 0.5) else F(0)
                H[i][j] = H[j][i] = v
        return H

    definite = rng.random() < 0.7
    cubic = Poly(n)
    fis = []
    eta = None
    if fi_kind != "linear":
        H = rand_H(definite)
        if fi_kind == "block_energy":
            for (lo, hi) in spans:         # separable
                for i in range(n):
                    for j in range(n):
                        if (lo <= i < hi) != (lo <= j < hi):
                            H[i][j] = F(0)
        if rng.random() < 0.25:
            for _ in range(rng.randint(1, 3)):
                vs = [rng.randrange(n) for _ in range(3)]
                if fi_kind == "block_energy":
                    lo, hi = next(s for s in spans if s[0] <= vs[0] < s[1])
                    vs = [lo + (v % (hi - lo)) for v in vs]
                cubic = cubic + _p(n, {tuple(vs): rand_rat(rng, zero_ok=False)})
            meta["cubic"] = True
        # xi0 = Dh(mu_e): in the span of the Casimir gradients (then the first
        # variation is solvable), sometimes only in the isotropy, sometimes 0.
        r2 = rng.random()
        if r2 < 0.15 or not iso:
            xi0 = [F(0)] * n
        elif r2 < 0.85 and Gspan:
            xi0 = combo(rng, Gspan)
        else:
            xi0 = combo(rng, iso)
        dc = cubic.grad_at(mu)
        Hm = mat_vec(H, mu)
        b = [x - y - z for x, y, z in zip(xi0, Hm, dc)]
        h = quad_poly(n, H, b) + cubic
    else:
        # linear first integral F = <eta, mu>: h invariant under the coadjoint
        # flow of eta: sym(H K) = 0, K^T b = 0, with K = ad*_eta; plus the
        # equilibrium condition H mu + b + Dcubic(mu) = xi in g_mu (affine system).
        if iso and rng.random() < 0.7:
            eta = combo(rng, iso, zero_ok=False)
        else:
            eta = [F(0)] * n
            eta[rng.randrange(n)] = F(1)
        K = g.adstar_matrix(eta)
        extra = Poly(n)
        etap = Poly(n, {tuple(int(j == i) for j in range(n)): eta[i] for i in range(n) if eta[i]})
        if rng.random() < 0.3:
            extra = etap * etap * etap * rand_rat(rng, zero_ok=False) * F(1, 6)
            if cas and rng.random() < 0.5:
                extra = extra + etap * rng.choice(cas) * rand_rat(rng, zero_ok=False)
            meta["cubic"] = True
        SB = sym_basis(n)
        nS, nb, ni = len(SB), n, len(iso)
        rows, rhs = [], []
        # sym(H K) = 0 -> for each i <= j: (H K)_ij + (H K)_ji = 0
        HK = [mat_mul(S, K) for S in SB]
        for i in range(n):
            for j in range(i, n):
                rows.append([HK[s][i][j] + HK[s][j][i] for s in range(nS)] + [F(0)] * (nb + ni))
                rhs.append(F(0))
        KT = mat_T(K)
        for i in range(n):
            rows.append([F(0)] * nS + list(KT[i]) + [F(0)] * ni)
            rhs.append(F(0))
        dex = extra.grad_at(mu)
        Smu = [mat_vec(S, mu) for S in SB]
        for i in range(n):
            rows.append([Smu[s][i] for s in range(nS)] + [F(int(i == j)) for j in range(nb)]
                        + [-iso[q][i] for q in range(ni)])
            rhs.append(-dex[i])
        x0, N = solve_affine(rows, rhs)
        if x0 is None:
            return None
        x = list(x0)
        for v in N:
            c = rand_rat(rng)
            x = [a + c * w for a, w in zip(x, v)]
        H = mat_zero(n, n)
        for s in range(nS):
            if x[s]:
                H = mat_add(H, SB[s], x[s])
        b = x[nS:nS + nb]
        h = quad_poly(n, H, b) + extra
        if h.degree() < 2:
            return None
        fis = [etap]
        cubic = extra
    meta["definite_H"] = definite if fi_kind != "linear" else None

    # -- noise
    k = rng.choices([0, 1, 2, 3], weights=[1, 5, 3, 1])[0]
    noise = [combo(rng, iso, zero_ok=False) for _ in range(k)] if iso else []
    intended = "compatible"
    r3 = rng.random()
    if r3 < 0.025 and fi_kind != "linear":   # deliberately not an equilibrium
        delta = [rand_rat(rng) for _ in range(n)]
        if any(g.adstar(delta, mu)):
            h = h + Poly(n, {tuple(int(j == i) for j in range(n)): delta[i] for i in range(n) if delta[i]})
            intended = "not_an_equilibrium"
    elif r3 < 0.05:                 # deliberately incompatible noise
        s = [rand_rat(rng) for _ in range(n)]
        if any(g.adstar(s, mu)):
            noise.append(s)
            intended = "noise_incompatible"
    meta["intended"] = intended
    if fi_kind == "block_energy":      # the energy of the first block (after any perturbation)
        lo, hi = spans[0]
        keep = Poly(n, {k: v for k, v in h.t.items() if any(k[lo:hi]) and not any(k[:lo] + k[hi:])})
        if not keep.is_zero():
            fis = [keep]
        else:
            fi_kind = None
    meta["fi"] = fi_kind
    meta["noise_fields"] = len(noise)

    # -- exact sanity in canonical coordinates
    for C in cas:
        assert g.is_casimir(C), f"{g.label}: not a Casimir"
    for Fq in fis:
        assert g.bracket(Fq, h).is_zero(), f"{g.label}: first integral not conserved"
    eq_ok = not any(g.adstar(h.grad_at(mu), mu))
    nz_ok = all(not any(g.adstar(s, mu)) for s in noise)
    assert eq_ok == (intended != "not_an_equilibrium"), "equilibrium construction"
    assert nz_ok == (intended != "noise_incompatible"), "noise construction"

    # -- basis
    random_basis = (rng.random() < 0.7) if force_random_basis is None else force_random_basis
    if force_canonical:
        random_basis = False
    if random_basis:
        T = rand_T(rng, n)
        Tinv = inverse(T)
        names = [f"y{i + 1}" for i in range(n)]
        g2 = transform_algebra(g, T, Tinv, names)
        h2 = h.linear_subst(Tinv)
        cas2 = list(g2.casimirs)
        fis2 = [Fq.linear_subst(Tinv) for Fq in fis]
        mu2 = mat_vec(T, mu)
        TinvT = mat_T(Tinv)
        noise2 = [mat_vec(TinvT, s) for s in noise]
        # identity check: (ad*_{xi'} mu')' = T ad*_xi mu on random vectors
        for _ in range(2):
            xi = [rand_rat(rng) for _ in range(n)]
            m = [rand_rat(rng) for _ in range(n)]
            lhs = g2.adstar(mat_vec(TinvT, xi), mat_vec(T, m))
            rhs_ = mat_vec(T, g.adstar(xi, m))
            assert lhs == rhs_, "basis transformation identity"
        meta["basis"] = "random"
        meta["T"] = [[int(x) for x in r] for r in T]
        meta["det_T"] = int(det(T))
        alg_spec = {"coordinates": names,
                    "structure_constants": [[a, b, k, fstr(v)] for a, b, k, v in g2.rows()]}
        gw, hw, casw, fisw, muw, noisew = g2, h2, cas2, fis2, mu2, noise2
    else:
        meta["basis"] = "canonical"
        names = g.names
        if g.builtin and rng.random() < 0.85:
            alg_spec = g.builtin
        else:
            alg_spec = {"coordinates": names,
                        "structure_constants": [[a, b, k, fstr(v)] for a, b, k, v in g.rows()]}
        gw, hw, casw, fisw, muw, noisew = g, h, cas, fis, mu, noise
    meta["builtin"] = alg_spec if isinstance(alg_spec, str) else None

    # -- Casimirs: given (each scaled by 10^u) or omitted
    give = rng.random() < 0.5 or not isinstance(alg_spec, dict)
    if isinstance(alg_spec, str):
        give = rng.random() < 0.5       # omitted: the builtin's own
    spec = {"name": f"rs-{seed}-{idx:05d}",
            "description": f"random study: {g.label}, dim {n}, basis {meta['basis']}",
            "algebra": alg_spec,
            "hamiltonian": hw.to_str(names)}
    if give:
        scales = [rand_scale(rng) for _ in casw]
        spec["casimirs"] = [(C * s).to_str(names) for C, s in zip(casw, scales)]
        meta["casimirs"] = "given"
        meta["casimir_scales"] = [fstr(s) for s in scales]
    else:
        meta["casimirs"] = "omitted"
        # Discovery to degree 4 in a dense basis of dimension >= 6 takes
        # seconds to minutes (8 dimensions: 60-170 s on the 2-core machine).
        # All Casimirs here have degree <= 2, so degree-2 discovery is
        # complete; keep the default degree for a few, to time it.
        if isinstance(alg_spec, dict) and random_basis and n >= 6:
            keep_default = rng.random() < (0.25 if n == 6 else 0.02)
            if not keep_default:
                spec["settings"] = {"discovery_degree": 2}
        meta["discovery_degree"] = (spec.get("settings") or {}).get("discovery_degree", 4)
    if fisw:
        spec["first_integrals"] = [Fq.to_str(names) for Fq in fisw]
    spec["equilibrium"] = [fstr(x) for x in muw]
    spec["noise"] = [[fstr(x) for x in s] for s in noisew]
    spec["stopping"] = {"epsilon": "1/10", "delta": "1/1000"}

    # -- the reference's spec: same system, custom constants, Casimirs unscaled
    ref_spec = dict(spec)
    ref_spec["algebra"] = {"coordinates": names,
                           "structure_constants": [[a, b, k, fstr(v)] for a, b, k, v in gw.rows()]}
    ref_spec["casimirs"] = [C.to_str(names) for C in casw]

    # -- re-read the written spec exactly and confirm the construction
    ex = ExactSystem(json.loads(json.dumps(spec)))
    assert ex.g.n == n
    assert ex.h.t == hw.t
    assert (not any(any(r) for r in [ex.eq_residual()])) == eq_ok, "written spec: equilibrium"
    assert all(not any(r) for r in ex.noise_residuals()) == nz_ok, "written spec: noise"
    for C in ex.cas:
        assert ex.g.is_casimir(C), "written spec: Casimir"
    for Fq in ex.fis:
        assert ex.g.bracket(Fq, ex.h).is_zero(), "written spec: first integral"
    # ground truth facts
    Gw = [C.grad_at(muw) for C in casw] + [Fq.grad_at(muw) for Fq in fisw]
    dh = hw.grad_at(muw)
    if Gw:
        x0, _ = solve_affine(mat_T(Gw), [-v for v in dh])
        meta["first_variation_solvable"] = x0 is not None
    else:
        meta["first_variation_solvable"] = not any(dh)
    meta["casimir_rank_at_mu"] = rank([C.grad_at(muw) for C in casw]) if casw else 0
    meta["isotropy_dim"] = len(iso)
    meta["fi_commutes_with_noise"] = [all(gw.bracket(Fq, Poly(n, {tuple(int(j == i) for j in range(n)): s[i]
                                                                for i in range(n) if s[i]})).is_zero()
                                          for s in noisew) for Fq in fisw]
    return spec, ref_spec, meta


def gen_one(seed, i):
    """System number i: deterministic (its own random stream, retried with
    another stream when a construction has no solution)."""
    attempt = 0
    while True:
        r = gen_system(random.Random(f"{seed}:{i}:{attempt}"), i, seed)
        if r is not None:
            return r
        attempt += 1


def _gen_job(a):
    return gen_one(*a)


def generate(seed, count, workers=1):
    """Deterministic list of (spec, ref_spec, meta), the same for any number of workers."""
    if workers <= 1 or count < 20:
        return [gen_one(seed, i) for i in range(count)]
    with cf.ProcessPoolExecutor(max_workers=workers) as ex:
        return list(ex.map(_gen_job, [(seed, i) for i in range(count)], chunksize=16))


# ==========================================================================
# The independent reference (numpy_pipeline) and exact confirmations
# ==========================================================================

_NP = None
_FALLBACKS = [0]


def numpy_pipeline():
    """Import bench/numpy_pipeline.py.  One robustness wrapper: its
    largest generalized eigenvalue calls scipy.linalg.eigh(sQ, sP), whose
    Cholesky of P fails when P passed its definiteness tolerance but is
    ill-conditioned (LinAlgError); then the same number is computed from
    the eigendecomposition of sP instead.  And its smallest eigenvalue
    returns -inf (not definite) for a matrix with inf/nan entries, which
    its Nelder-Mead reaches when it runs off to infinity.  Both are counted
    in 'gen_max_fallbacks'."""
    global _NP
    if _NP is None:
        sys.path.insert(0, HERE)
        import numpy as np
        import scipy.linalg
        import numpy_pipeline as m   # noqa: E402
        orig = m._gen_max

        def gen_max(Q, P, s):
            try:
                return orig(Q, P, s)
            except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
                _FALLBACKS[0] += 1
                w, V = np.linalg.eigh(s * P)
                if w.min() <= 0:
                    return math.inf
                Wi = V / np.sqrt(w)
                return float(np.linalg.eigvalsh(Wi.T @ (s * Q) @ Wi)[-1])
        m._gen_max = gen_max
        orig_lmin = m._lmin

        def lmin(M):
            # Nelder-Mead can step to t = inf/nan; eigvalsh then raises
            if M.shape[0] and not np.all(np.isfinite(M)):
                _FALLBACKS[0] += 1
                return -math.inf
            try:
                return orig_lmin(M)
            except np.linalg.LinAlgError:
                _FALLBACKS[0] += 1
                return -math.inf
        m._lmin = lmin
        _NP = m
    return _NP


def hp_ray_limit(Rex, Qex, sign, d, s2_tol):
    """Sigma^2 along the ray t = 10^k d (k = 0, 2, ..., 24) of the multiplier
    family, in 100-digit arithmetic from the exact reduced matrices
    (Rex = [Rp, Rk_1, ...], Qex likewise), and its limit: when the infimum
    is only approached as |t| -> infinity, the float search stops where
    Z^T P0 Z reaches condition 1e8, at a basis-dependent distance from the
    limit.  Returns (limit or None, values)."""
    import mpmath
    dmax = max(abs(x) for x in d)
    if dmax == 0:
        return None, []
    dr = [F(x / dmax).limit_denominator(10 ** 6) for x in d]
    vals = []
    with mpmath.workdps(100):
        for k in range(0, 26, 2):
            t = [x * 10 ** k for x in dr]
            R = [list(r) for r in Rex[0]]
            Q = [list(r) for r in Qex[0]]
            for ti, Rk, Qk in zip(t, Rex[1:], Qex[1:]):
                R = mat_add(R, Rk, ti)
                Q = mat_add(Q, Qk, ti)
            Rm = mpmath.matrix([[mpmath.mpf(x.numerator) / x.denominator * sign for x in r] for r in R])
            Qm = mpmath.matrix([[mpmath.mpf(x.numerator) / x.denominator * sign for x in r] for r in Q])
            try:
                L = mpmath.cholesky(Rm)
            except (ZeroDivisionError, ValueError):
                vals.append(None)
                continue
            Li = mpmath.inverse(L)
            M = Li * Qm * Li.T
            M = (M + M.T) / 2
            ev = mpmath.eigsy(M, eigvals_only=True)
            vals.append(float(max(ev)))
    good = [v for v in vals if v is not None]
    if len(good) < 3 or vals[-1] is None:
        return (min(good) if good else None), vals
    a, b, c = vals[-3], vals[-2], vals[-1]
    lim = min(good)
    if a is not None and b is not None:
        den = (c - b) - (b - a)
        if den != 0 and (c - b) * (b - a) > 0:        # Aitken on a geometric tail
            est = c - (c - b) ** 2 / den
            if est < lim and (c - est) <= 1e-6 * max(abs(c), 1e-300) + (c - b):
                lim = est
    lim = max(lim, 0.0)
    return (lim if lim > s2_tol else 0.0), vals


def refine_family_infimum(ex, out):
    """numpy_pipeline minimises Sigma^2 over the multiplier family (t) with
    Nelder-Mead, which in a random basis can run off to t ~ 1e120 and stop
    far above the infimum (found by --self-test).  Here the same restricted
    problem f(t) = lambda_max(Z^T Q(t) Z, Z^T P0(t) Z) is minimised again for
    family dimension 1 or 2: the reduced matrices are built in exact
    arithmetic (rational bases of ker G^T and of the multiplier family) and
    rounded once, then f is searched on homogeneous, scale-normalised
    coordinates (a grid plus golden section; t -> infinity included; f is
    quasi-convex on the definite region).  Points where +-Z^T P0 Z has
    condition number above 1e8 count as infeasible (their f is not
    resolved).  Returns (value, info) or None."""
    import numpy as np
    n, mu = ex.g.n, ex.mu
    K = ex.cas + ex.fis
    if not K:
        return None
    Grows = [C.grad_at(mu) for C in K]                     # m x n
    dh = ex.h.grad_at(mu)
    x_p, N = solve_affine(mat_T(Grows), [-v for v in dh])
    if x_p is None:
        return None
    r = len(N)
    if r == 0 or r > 2:
        return None
    Z = nullspace(Grows, n)                                 # vectors z, G^T z = 0
    if not Z:
        return None
    Zm = mat_T(Z)                                           # n x k
    Hk = [C.hess_at(mu) for C in K]

    def P_of(lam):
        P = ex.h.hess_at(mu)
        for l, Hc in zip(lam, Hk):
            if l:
                P = mat_add(P, Hc, l)
        return P

    def D_of(lam):                                          # direction: no D2h term
        P = mat_zero(n, n)
        for l, Hc in zip(lam, Hk):
            if l:
                P = mat_add(P, Hc, l)
        return P
    A, Bs = ex.linearisation()
    mats = [P_of(x_p)] + [D_of(v) for v in N]
    red = lambda X: mat_mul(mat_mul(mat_T(Zm), X), Zm)      # noqa: E731
    Rs = [np.array([[float(x) for x in row] for row in red(X)]) for X in mats]
    Qs = [np.array([[float(x) for x in row] for row in red(q_of(X, A, Bs))]) for X in mats]
    Bn = [np.array([[float(x) for x in row] for row in B]) for B in Bs]
    s2_tol = 1e-10 * max(1.0, sum(float(np.linalg.norm(B, 2)) ** 2 for B in Bn))
    nR = [max(float(np.linalg.norm(X, 2)), 1e-300) for X in Rs]
    Rh = [X / s for X, s in zip(Rs, nR)]
    Qh = [X / s for X, s in zip(Qs, nR)]
    evals = [0]

    sign = 1     # set by the loop below (f reads it)

    def f(coef):
        evals[0] += 1
        R = sum(ci * Ri for ci, Ri in zip(coef, Rh))
        w = np.linalg.eigvalsh(sign * R)
        # definite, condition <= 1e8, and not a cancellation (|R| tiny
        # against its normalised terms: there rounding alone decides)
        if w[0] <= 1e-7 * sum(abs(ci) for ci in coef) or w[-1] > 1e8 * w[0]:
            return math.inf
        Q = sum(ci * Qi for ci, Qi in zip(coef, Qh))
        try:
            v = float(scipy_eigh(sign * Q, sign * R)[-1])
        except Exception:  # noqa: BLE001
            return math.inf
        return v if v > s2_tol else 0.0

    def golden_min(g, lo, hi, grid, iters=80, extra=()):
        xs = sorted([lo + (hi - lo) * i / (grid - 1) for i in range(grid)] + [x for x in extra if lo <= x <= hi])
        vs = [g(x) for x in xs]
        i = min(range(len(xs)), key=lambda j: vs[j])
        best = (vs[i], xs[i])
        if not math.isfinite(best[0]):
            return best
        a = xs[i - 1] if i > 0 else xs[i]
        b = xs[i + 1] if i < len(xs) - 1 else xs[i]
        gr = (math.sqrt(5) - 1) / 2
        x1, x2 = b - gr * (b - a), a + gr * (b - a)
        f1, f2 = g(x1), g(x2)
        for _ in range(iters):
            if f1 <= f2:
                b, x2, f2 = x2, x1, f1
                x1 = b - gr * (b - a)
                f1 = g(x1)
            else:
                a, x1, f1 = x1, x2, f2
                x2 = a + gr * (b - a)
                f2 = g(x2)
        for v, x in ((f1, x1), (f2, x2)):
            if v < best[0]:
                best = (v, x)
        return best

    pi2 = math.pi / 2

    def coef_to_t(coef):
        """homogeneous coefficients -> t in the exact parametrisation x_p + sum t_i N_i"""
        if abs(coef[0]) < 1e-15:
            return None
        return [coef[i + 1] / nR[i + 1] / (coef[0] / nR[0]) for i in range(r)]
    results = []
    for sg in (1, -1):
        sign = sg
        if r == 1:
            v, phi = golden_min(lambda p: f([math.cos(p), math.sin(p)]), -pi2, pi2, 401)
            coef = [math.cos(phi), math.sin(phi)]
        else:
            best_phi = {}

            def along(psi, grid=121):
                cps, sps = math.cos(psi), math.sin(psi)
                v, p = golden_min(lambda p: f([math.cos(p), math.sin(p) * cps, math.sin(p) * sps]), -pi2, pi2,
                                  grid, iters=60)
                best_phi[psi] = p
                return v
            v, psi = golden_min(along, 0.0, math.pi, 61, iters=50)
            phi = best_phi.get(psi, 0.0)
            coef = [math.cos(phi), math.sin(phi) * math.cos(psi), math.sin(phi) * math.sin(psi)]
        if math.isfinite(v):
            results.append((v, {"r": r, "sign": sg, "coef": coef, "t": coef_to_t(coef),
                                "at_infinity": abs(coef[0]) < 1e-9}))
    if not results:
        return None
    v, info = min(results, key=lambda x: x[0])
    info["evals"] = evals[0]
    info["signs_feasible"] = [x[1]["sign"] for x in results]
    # pinned at the conditioning cut-off (or at infinity): follow the ray
    coef = info["coef"]
    sign = info["sign"]
    Rb = sum(ci * Ri for ci, Ri in zip(coef, Rh))
    w = np.linalg.eigvalsh(sign * Rb)
    info["cond"] = float(w[-1] / w[0]) if w[0] > 0 else math.inf
    info["approached"] = info["at_infinity"]
    if info["cond"] > 1e6 or info["at_infinity"]:
        d = [coef[i + 1] / nR[i + 1] for i in range(r)]
        Rex = [red(X) for X in mats]
        Qex = [red(q_of(X, A, Bs)) for X in mats]
        lim, seq = hp_ray_limit(Rex, Qex, sign, d, s2_tol)
        info["ray"] = seq
        flat = all(x is not None and abs(x - v) <= 1e-9 * max(abs(v), 1e-12) for x in seq[2:])
        if r == 2 and not flat:
            # pinned at the conditioning cut-off of a 2-parameter family: the
            # limit at infinity depends on an asymptote (an offset across the
            # direction) that is not searched, so the value is not resolved
            info["unresolved"] = True
        if lim is not None and lim < v:
            info["ray_limit"] = lim
            info["approached"] = True
            v = lim
    return v, info


def scipy_eigh(a, b):
    import scipy.linalg
    return scipy.linalg.eigh(a, b, eigvals_only=True)


def hp_spectrum(ex):
    """Eigenvalues of the exact linearisation A at 120 digits (mpmath):
    a defective eigenvalue of multiplicity k then moves by about 1e-120^(1/k),
    so a real part above 1e-10 |A| is a genuine instability."""
    import mpmath
    A, _ = ex.linearisation()
    with mpmath.workdps(120):
        M = mpmath.matrix([[mpmath.mpf(x.numerator) / x.denominator for x in r] for r in A])
        E = mpmath.eig(M, left=False, right=False)
        norm = float(mpmath.mnorm(M, 1)) if len(A) else 0.0
        re = max((float(mpmath.re(e)) for e in E), default=0.0)
    return re, norm


REFERENCE_PARSE = "exact"


def prepare_exact(ref_spec):
    """numpy_pipeline's Prepared object, built from the exact reading of the
    reference spec here instead of numpy_pipeline.prepare (whose sympy
    Casimir / bracket checks take up to 20 s on a dense 8-dimensional
    algebra).  Derivatives are evaluated exactly at mu_e and rounded once;
    everything numpy_pipeline.certify does afterwards is unchanged.  The
    Casimirs, first integrals and the Jacobi identity are checked exactly by
    the generator.  --reference-parse sympy uses numpy_pipeline.prepare."""
    import numpy as np
    npp = numpy_pipeline()
    ex = ExactSystem(ref_spec)
    n = ex.g.n
    mu = ex.mu
    flat = ex.h.grad_at(mu) + [x for r in ex.h.hess_at(mu) for x in r]
    for K in ex.cas + ex.fis:
        flat += K.grad_at(mu) + [x for r in K.hess_at(mu) for x in r]
    flat = [float(x) for x in flat]
    c = np.array([[[float(ex.g.c[a][b][k]) for k in range(n)] for b in range(n)] for a in range(n)])
    st = ref_spec.get("stopping")
    eps_delta = (float(parse_poly(st["epsilon"], []).const_value()),
                 float(parse_poly(st["delta"], []).const_value())) if st else None
    return npp.Prepared(name=ref_spec.get("name", "?"), spec=ref_spec, coords=ex.g.names, n=n, c=c,
                        ders=lambda *args: flat, m_cas=len(ex.cas), m_fi=len(ex.fis),
                        mu_e=np.array([float(x) for x in mu]),
                        sigmas=[np.array([float(x) for x in s]) for s in ex.noise],
                        eps_delta=eps_delta, checks={})


def reference(ref_spec, spec, parse=None):
    """Run numpy_pipeline on the reference spec; add the linearisation's
    norm, and exact confirmation of its definite form."""
    import numpy as np
    npp = numpy_pipeline()
    t0 = time.perf_counter()
    _FALLBACKS[0] = 0
    try:
        if (parse or REFERENCE_PARSE) == "sympy":
            pp = npp.prepare(ref_spec)
        else:
            pp = prepare_exact(ref_spec)
        out = npp.certify(pp)
    except Exception as exc:  # noqa: BLE001
        return {"error": f"{type(exc).__name__}: {exc}"}
    res = {"verdict": out.get("verdict"), "verdict_robust": out.get("verdict"),
           "time": time.perf_counter() - t0}
    if _FALLBACKS[0]:
        res["gen_max_fallbacks"] = _FALLBACKS[0]
    for k in ("sigma2", "sigma2_P", "Q_depends_on_finsler_m", "definiteness", "max_real_eig",
              "lambda_min_restricted", "finsler_m"):
        if k in out:
            res[k] = out[k]
    mults = out.get("multipliers")
    if mults:
        res["multipliers"] = list(mults.get("lambda", [])) + list(mults.get("nu", []))
        res["family_dimension"] = mults.get("family_dimension")
    # ||A||, A as numpy_pipeline builds it
    if out.get("verdict") not in ("not_an_equilibrium", "noise_incompatible", None):
        n = pp.n
        vals = np.asarray(pp.ders(*pp.mu_e), dtype=float)
        dh, Hh = vals[:n], vals[n:n + n * n].reshape(n, n)
        ad_dh = np.tensordot(dh, pp.c, axes=(0, 0))
        A = np.einsum("abk,am,k->bm", pp.c, Hh, pp.mu_e) + ad_dh
        ev = np.linalg.eigvals(A)
        res["normA"] = float(np.linalg.norm(A, 2))
        res["max_re"] = float(ev.real.max())
        try:
            res["max_re_hp"], res["normA1_hp"] = hp_spectrum(ExactSystem(ref_spec))
        except Exception as exc:  # noqa: BLE001
            res["hp_error"] = str(exc)[:200]
        # The reference's verdict with its instability test made robust:
        # numpy_pipeline calls A unstable above 1e-9 |A|, which rounding alone
        # passes for defective spectra (a nilpotent A in a random basis).
        rv = res["verdict"]
        if rv in ("linearly_unstable", "inconclusive") and "max_re_hp" in res:
            rv = ("linearly_unstable" if res["max_re_hp"] > 1e-10 * max(1.0, res["normA1_hp"])
                  else "inconclusive")
        res["verdict_robust"] = rv
    if out.get("P") is not None:
        P = np.array(out["P"])
        try:
            res["condP"] = float(np.linalg.cond(P))
        except Exception:  # noqa: BLE001
            pass
    # infimum known?
    if res.get("verdict") == "stable":
        res["infimum_known"] = not out.get("Q_depends_on_finsler_m", False)
        res["infimum"] = out["sigma2"] if res["infimum_known"] else None
        if res["infimum_known"] and (res.get("family_dimension") or 0) > 0:
            # numpy_pipeline's Nelder-Mead over the family is not reliable
            # (it runs off to |t| ~ 1e20..1e120 in random bases, where its
            # values are rounding artefacts, above or below the infimum):
            # use the exact-data 1-D/2-D search instead (sigma2_neldermead
            # keeps numpy_pipeline's own number).
            res["sigma2_neldermead"] = out["sigma2"]
            try:
                rf = refine_family_infimum(ExactSystem(ref_spec), out)
            except Exception as exc:  # noqa: BLE001
                rf = None
                res["refine_error"] = str(exc)[:200]
            if rf is not None and rf[1].get("unresolved"):
                res["sigma2_refined"] = rf[0]
                res["refine_info"] = rf[1]
                res["infimum_known"] = False
                res["infimum"] = None
                res["infimum_unknown_reason"] = "family dimension 2, approached as |t| -> infinity"
            elif rf is not None:
                res["sigma2_refined"] = rf[0]
                res["refine_info"] = rf[1]
                res["infimum"] = rf[0]
            else:
                res["infimum_known"] = False
                res["infimum"] = None
                res["infimum_unknown_reason"] = ("family dimension > 2" if res["family_dimension"] > 2
                                                 else "no well-conditioned definite point found")
        try:
            res["exact_definite"] = exact_confirm_reference(spec, ref_spec, res)
        except Exception as exc:  # noqa: BLE001
            res["exact_definite"] = None
            res["exact_definite_error"] = str(exc)[:200]
        if not res["exact_definite"]:
            # numpy_pipeline's "stable" is not confirmed: its definite P can be
            # a rounding artefact at |t| ~ 1e20 (seen with an unstable A)
            hp_unst = res.get("max_re_hp") is not None and \
                res["max_re_hp"] > 1e-10 * max(1.0, res.get("normA1_hp") or 0.0)
            res["verdict_robust"] = "linearly_unstable" if hp_unst else "inconclusive"
            res["infimum_known"] = False
            res["infimum"] = None
            res["infimum_unknown_reason"] = "definite form not confirmed exactly"
    return res


def exact_confirm_reference(spec, ref_spec, res):
    """Does an exact definite energy-Casimir form exist where the reference
    found one?  The exact affine family of multipliers solving the first
    variation, Z an exact basis of ker G^T, and Z^T P0(t) Z tested by exact
    LDL^T at rational points near the reference's choices: the refined
    search's point (its sign), then numpy_pipeline's multipliers projected
    onto the family (its sign).  By Finsler's lemma some M then makes P
    definite."""
    import numpy as np
    ex = ExactSystem(ref_spec)
    n = ex.g.n
    K = ex.cas + ex.fis
    mu = ex.mu
    G = [C.grad_at(mu) for C in K]
    dh = ex.h.grad_at(mu)
    H = ex.h.hess_at(mu)
    Hs = [C.hess_at(mu) for C in K]
    if G:
        x0, N = solve_affine(mat_T(G), [-v for v in dh])
        if x0 is None:
            return False
    else:
        if any(dh):
            return False
        x0, N = [], []
    Z = nullspace(G, n) if G else [[F(int(i == j)) for i in range(n)] for j in range(n)]
    if not Z:
        return True
    Zm = mat_T(Z)

    def R_of(tr):
        lam = list(x0)
        for ti, v in zip(tr, N):
            lam = [a + ti * b for a, b in zip(lam, v)]
        P0 = [list(r) for r in H]
        for l, Hc in zip(lam, Hs):
            if l:
                P0 = mat_add(P0, Hc, l)
        return mat_mul(mat_mul(mat_T(Zm), P0), Zm)
    cands = []
    info = res.get("refine_info") or {}
    if info.get("t") is not None and len(info["t"]) == len(N):
        cands.append((info["t"], info["sign"]))
    elif info.get("at_infinity") and len(info.get("coef", [])) == len(N) + 1:
        cands.append(([1e9 * c for c in info["coef"][1:]], info["sign"]))
    lam_ref = np.array(res.get("multipliers") or [0.0] * len(K), dtype=float)
    if N:
        Nm = np.array([[float(x) for x in v] for v in N]).T
        t, *_ = np.linalg.lstsq(Nm, lam_ref - np.array([float(x) for x in x0]), rcond=None)
    else:
        t = []
    cands.append((list(t), 1 if res.get("definiteness") == "positive" else -1))
    for tt, sign in cands:
        for den in (10 ** 3, 10 ** 6, 10 ** 9, 10 ** 12):
            tr = [F(float(x)).limit_denominator(den) for x in tt]
            if is_pos_def(mat_scale(R_of(tr), F(sign))):
                return True
    return False


def exact_check_certificate(spec, cert):
    """Independent exact checks of a stable certificate."""
    out = {}
    P = [[fparse(x) for x in r] for r in cert["P"]]
    choice = cert.get("casimir_choice") or {}
    sign = int(choice.get("sign", 1))
    out["P_definite"] = is_pos_def(mat_scale(P, F(sign)))
    try:
        conserved = cert.get("conserved") or []
        names_c = [c for c in conserved if c.get("kind") == "casimir"]
        names_f = [c for c in conserved if c.get("kind") != "casimir"]
        ex = ExactSystem(spec, casimir_exprs=[c["expression"] for c in names_c])
        g = ex.g
        for C in ex.cas:
            if not g.is_casimir(C):
                out["conserved_ok"] = False
        K = ex.cas + [parse_poly(c["expression"], g.names, ex.params) for c in names_f]
        for Fq in K[len(ex.cas):]:
            if not g.bracket(Fq, ex.h).is_zero():
                out["conserved_ok"] = False
        out.setdefault("conserved_ok", True)
        mu = ex.mu
        lam = [fparse(x) for x in choice["multipliers"]]
        M = [[fparse(x) for x in r] for r in choice["M"]]
        G = [C.grad_at(mu) for C in K]                     # m x n
        fv = ex.h.grad_at(mu)
        for l, gk in zip(lam, G):
            fv = [a + l * b for a, b in zip(fv, gk)]
        out["first_variation_zero"] = not any(fv)
        Pr = ex.h.hess_at(mu)
        for l, C in zip(lam, K):
            if l:
                Pr = mat_add(Pr, C.hess_at(mu), l)
        if G:
            Gm = mat_T(G)                                   # n x m
            Pr = mat_add(Pr, mat_mul(mat_mul(Gm, M), G))
        out["P_rebuilt_equal"] = (Pr == P)
        A, Bs = ex.linearisation()
        PA = mat_mul(P, A)
        out["drift_residual_zero"] = not any(any(x) for x in mat_add(PA, mat_T(PA)))
        Q = q_of(P, A, Bs)
        if cert.get("Q") is not None:
            out["Q_equal"] = ([[fparse(x) for x in r] for r in cert["Q"]] == Q)
        S = fparse(cert["sigma2_exact"]) if cert.get("sigma2_exact") is not None else None
        if S is not None:
            Mx = mat_add(mat_scale(P, S * sign), mat_scale(Q, F(-sign)))
            out["bound_psd"] = is_pos_semidef(Mx)
    except Exception as exc:  # noqa: BLE001
        out["error"] = f"{type(exc).__name__}: {str(exc)[:200]}"
    return out


# ==========================================================================
# The engine runner
# ==========================================================================


def run_engine(binpath, spec_path, workdir, timeout):
    base = os.path.splitext(os.path.basename(spec_path))[0]
    cert_path = os.path.join(workdir, base + ".cert.json")
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    row = {}
    t0 = time.perf_counter()
    try:
        p = subprocess.run([binpath, "certify", spec_path, "-o", cert_path], capture_output=True,
                           text=True, timeout=timeout, env=env)
        row["certify_exit"] = p.returncode
        if p.returncode != 0:
            row["stderr"] = p.stderr[-600:]
    except subprocess.TimeoutExpired:
        row["certify_exit"] = "timeout"
    row["certify_time"] = time.perf_counter() - t0
    cert = None
    if row["certify_exit"] == 0 and os.path.exists(cert_path):
        try:
            with open(cert_path) as fh:
                cert = json.load(fh)
        except Exception as exc:  # noqa: BLE001
            row["cert_error"] = str(exc)[:200]
        t1 = time.perf_counter()
        try:
            p = subprocess.run([binpath, "check", cert_path], capture_output=True, text=True,
                               timeout=timeout, env=env)
            row["check_exit"] = p.returncode
            if p.returncode != 0:
                row["check_stderr"] = (p.stdout + p.stderr)[-600:]
        except subprocess.TimeoutExpired:
            row["check_exit"] = "timeout"
        row["check_time"] = time.perf_counter() - t1
    return row, cert, cert_path


def summarise_cert(cert):
    import numpy as np
    r = {"verdict": cert.get("verdict"), "level": cert.get("level")}
    for k in ("sigma2", "sigma2_exact", "sigma2_sharp"):
        if k in cert:
            r[k] = cert[k]
    opt = cert.get("optimisation")
    if opt:
        for k in ("attained", "infimum", "within_tolerance", "first_definite_sigma2", "q_depends_on_M",
                  "method", "optimised", "condition_number", "cond_P", "condP"):
            if k in opt:
                r["opt_" + k] = opt[k]
        for k, v in opt.items():             # anything about conditioning, whatever its name
            if "cond" in k.lower() and ("opt_" + k) not in r:
                r["opt_" + k] = v
    for k, v in cert.items():
        if "cond" in k.lower() and k not in ("conserved",):
            r[k] = v
    if cert.get("P") is not None:
        try:
            P = np.array([[float(F(x)) for x in row] for row in cert["P"]])
            r["condP"] = float(np.linalg.cond(P))
        except Exception:  # noqa: BLE001
            pass
    ch = cert.get("casimir_choice")
    if ch:
        r["sign"] = ch.get("sign")
    cons = cert.get("conserved") or []
    r["n_casimirs"] = sum(1 for c in cons if c.get("kind") == "casimir")
    r["n_discovered"] = sum(1 for c in cons if c.get("source") == "discovered")
    return r


# ==========================================================================
# Per-spec evaluation and the report
# ==========================================================================


def judge(row, name):
    """Flags for one engine on one spec."""
    e = row["engines"][name]
    ref = row.get("reference") or {}
    flags = []
    v = e.get("verdict")
    if e.get("certify_exit") != 0:
        flags.append("certify_failed")
        return flags
    if e.get("check_exit") != 0:
        flags.append("check_failed")
    rv = ref.get("verdict_robust") or ref.get("verdict")
    normA = ref.get("normA") or 0.0
    max_re = ref.get("max_re")
    clearly_unstable = max_re is not None and max_re > 1e-6 * max(1.0, normA)
    none_unstable = max_re is None or max_re <= 1e-9 * max(1.0, normA)
    ex = e.get("exact") or {}
    if v == "stable":
        if ex.get("P_definite") is False:
            flags.append("false_stable_P_not_definite")
        if clearly_unstable:
            flags.append("false_stable_ref_unstable_eig")
        for k in ("P_rebuilt_equal", "first_variation_zero", "drift_residual_zero", "bound_psd",
                  "conserved_ok", "Q_equal"):
            if ex.get(k) is False:
                flags.append("exact_" + k + "_failed")
        if ex.get("error"):
            flags.append("exact_check_error")
    hp = ref.get("max_re_hp")
    hp_unstable = hp is not None and hp > 1e-10 * max(1.0, ref.get("normA1_hp") or 0.0)
    if v == "stable" and hp_unstable:
        flags.append("false_stable_hp_unstable_eig")
    if v == "linearly_unstable":
        if max_re is None:
            flags.append("unstable_no_reference")
        elif none_unstable:
            # numpy finds no eigenvalue above 1e-9 |A|; the 120-digit spectrum decides
            flags.append("false_unstable_ref_none" if not hp_unstable else "unstable_numpy_none_hp_confirms")
        elif not clearly_unstable:
            flags.append("unstable_ref_marginal" if hp_unstable else "false_unstable_hp_none")
        elif not hp_unstable and hp is not None:
            flags.append("false_unstable_hp_none")
    if v == "inconclusive" and ref.get("verdict") == "stable":
        flags.append("inconclusive_ref_definite" if ref.get("exact_definite")
                     else "inconclusive_ref_definite_unconfirmed")
    if v == "stable" and rv != "stable" and rv is not None:
        flags.append("stable_where_reference_not")
    if v in ("not_an_equilibrium", "noise_incompatible") and v != row["meta"]["intended"]:
        flags.append("unexpected_" + v)
    if row["meta"]["intended"] != "compatible" and v != row["meta"]["intended"]:
        flags.append("missed_" + row["meta"]["intended"])
    if rv and v and rv != v and not (v == "inconclusive" and rv == "stable") \
            and not (v == "stable" and rv != "stable"):
        flags.append(f"verdict_differs:{v}/ref:{rv}")
    # claims about sharpness
    inf = ref_infimum(e, ref)
    if v == "stable" and inf is not None and e.get("sigma2") is not None:
        excess = e["sigma2"] - inf
        first = e.get("opt_first_definite_sigma2") or 0.0
        allowed = 1e-6 * max(inf, first) * 1.01 + 1e-9 * inf + 1e-300
        if e.get("opt_within_tolerance") is True and excess > allowed:
            flags.append("within_tolerance_claim_false")
        if e.get("opt_attained") is True and excess > 1e-8 * max(inf, 1e-300) + 1e-12:
            flags.append("attained_claim_false")
        oi = e.get("opt_infimum")
        if oi is not None and abs(oi - inf) > 1e-6 * max(abs(inf), 1e-12):
            flags.append("engine_infimum_differs")
    if v == "stable" and rv == "stable" and ref.get("infimum_known") and ref.get("definiteness"):
        sgn = 1 if ref["definiteness"] == "positive" else -1
        if e.get("sign") is not None and int(e["sign"]) != sgn:
            flags.append("sign_differs")
    rel = e.get("rel_excess")
    if rel is not None and rel < -1e-8:
        # an exactly verified value below the reference: the reference is not at the infimum
        flags.append("reference_above_verified_value" if exact_verified(e) else "below_reference_infimum")
    if rel is not None and rel > 1e-2:
        flags.append("excess_over_1e-2")
    return flags


def exact_verified(e):
    ex = e.get("exact") or {}
    return bool(ex) and all(ex.get(k) is True for k in (
        "P_definite", "P_rebuilt_equal", "first_variation_zero", "drift_residual_zero", "bound_psd",
        "conserved_ok"))


def ref_infimum(e, ref):
    """The reference infimum for this engine row, or None.  A reference value
    below 1e-8 where the engine's Sigma^2 = 0 is verified exactly here is
    rounding (numpy_pipeline floors at 1e-10 of the noise scale): 0."""
    if (ref or {}).get("verdict_robust") != "stable" or not ref.get("infimum_known"):
        return None
    inf = ref.get("infimum")
    if inf is not None and 0 < inf < 1e-8 and e.get("sigma2") == 0 and exact_verified(e):
        return 0.0
    return inf


def rel_excess(e, ref):
    if e.get("verdict") != "stable":
        return None
    inf = ref_infimum(e, ref)
    s = e.get("sigma2")
    if inf is None or s is None or not (inf > 0):
        return None
    return s / inf - 1.0


def quant(xs, q):
    if not xs:
        return None
    xs = sorted(xs)
    k = min(len(xs) - 1, max(0, int(math.ceil(q * len(xs))) - 1))
    return xs[k]


def fmt(x, digits=3):
    if x is None:
        return "-"
    if isinstance(x, float):
        if x == 0:
            return "0"
        if abs(x) < 1e-3 or abs(x) >= 1e4:
            return f"{x:.{digits}g}"
        return f"{x:.{digits}g}"
    return str(x)


def report(rows, names):
    stats = {}
    for nm in names:
        s = {}
        es = [(r, r["engines"][nm]) for r in rows if nm in r["engines"]]
        s["specs"] = len(es)
        verdicts = {}
        for r, e in es:
            verdicts[e.get("verdict") or f"exit {e.get('certify_exit')}"] = \
                verdicts.get(e.get("verdict") or f"exit {e.get('certify_exit')}", 0) + 1
        s["verdicts"] = verdicts
        fl = {}
        for r, e in es:
            for f in e.get("flags", []):
                key = f.split(":")[0] if f.startswith("verdict_differs") else f
                fl[key] = fl.get(key, 0) + 1
        s["flags"] = fl
        false_stable = sum(1 for r, e in es if any(f.startswith("false_stable") for f in e.get("flags", [])))
        false_unstable = sum(1 for r, e in es if any(f.startswith("false_unstable") for f in e.get("flags", [])))
        check_fail = sum(1 for r, e in es if "check_failed" in e.get("flags", []))
        s["false_stable"] = false_stable
        s["false_unstable"] = false_unstable
        s["check_fail"] = check_fail
        s["false_total"] = sum(1 for r, e in es if any(
            f.startswith("false_") or f == "check_failed" for f in e.get("flags", [])))
        s["exact_bound_fail"] = sum(1 for r, e in es if any(
            f.startswith("exact_") for f in e.get("flags", [])))
        s["inconclusive_ref_definite"] = fl.get("inconclusive_ref_definite", 0)
        s["inconclusive_ref_definite_unconfirmed"] = fl.get("inconclusive_ref_definite_unconfirmed", 0)
        st = [(r, e) for r, e in es if e.get("verdict") == "stable"]
        s["attained"] = sum(1 for r, e in st if e.get("opt_attained") is True)
        s["approached"] = sum(1 for r, e in st if e.get("opt_attained") is False)
        s["within_tol_false"] = sum(1 for r, e in st if e.get("opt_within_tolerance") is False)
        s["within_tol_claim_false"] = fl.get("within_tolerance_claim_false", 0)
        s["attained_claim_false"] = fl.get("attained_claim_false", 0)
        s["engine_inf_differs"] = fl.get("engine_infimum_differs", 0)
        eid = [abs(e["opt_infimum"] / r["reference"]["infimum"] - 1) for r, e in st
               if e.get("opt_infimum") is not None and (r.get("reference") or {}).get("infimum_known")
               and (r["reference"].get("infimum") or 0) > 0 and e.get("rel_excess") is not None]
        s["engine_inf_q"] = (quant(eid, 0.5), quant(eid, 0.99), max(eid) if eid else None)
        s["q_dep_M"] = sum(1 for r, e in st if e.get("opt_q_depends_on_M") is True)
        rels = [e["rel_excess"] for r, e in st if e.get("rel_excess") is not None]
        s["n_rel"] = len(rels)
        s["rel_q"] = {q: quant(rels, q) for q in (0.5, 0.9, 0.99, 1.0)}
        s["rel_min"] = min(rels) if rels else None
        s["rel_above"] = {t: sum(1 for x in rels if x > t) for t in (1e-6, 1e-4, 1e-2, 0.1)}
        s["both_zero"] = sum(1 for r, e in st if ref_infimum(e, r.get("reference")) == 0
                             and e.get("sigma2") == 0)
        s["ref_zero_engine_pos"] = sum(1 for r, e in st if ref_infimum(e, r.get("reference")) == 0
                                       and (e.get("sigma2") or 0) > 0)
        s["not_optimised"] = sum(1 for r, e in st if e.get("opt_optimised") is False)
        s["ref_above_verified"] = fl.get("reference_above_verified_value", 0)
        s["infimum_unknown"] = sum(1 for r, e in st if (r.get("reference") or {}).get("verdict") == "stable"
                                   and not r["reference"].get("infimum_known"))
        ct = [e["certify_time"] for r, e in es if e.get("certify_time") is not None]
        kt = [e["check_time"] for r, e in es if e.get("check_time") is not None]
        s["t_certify"] = (quant(ct, 0.5), max(ct) if ct else None)
        s["t_check"] = (quant(kt, 0.5), max(kt) if kt else None)
        s["timeouts"] = sum(1 for r, e in es if e.get("certify_exit") == "timeout")
        s["exit_nonzero"] = sum(1 for r, e in es if e.get("certify_exit") not in (0,))
        stats[nm] = s

    lines = []
    hdr = "| metric | " + " | ".join(names) + " |"
    lines.append(hdr)
    lines.append("|" + " --- |" * (len(names) + 1))

    def add(label, fn):
        lines.append(f"| {label} | " + " | ".join(fn(stats[nm]) for nm in names) + " |")
    add("specs", lambda s: str(s["specs"]))
    allv = sorted({v for s in stats.values() for v in s["verdicts"]})
    for v in allv:
        add(f"verdict `{v}`", lambda s, v=v: str(s["verdicts"].get(v, 0)))
    add("certify exit != 0 (timeouts)", lambda s: f"{s['exit_nonzero']} ({s['timeouts']})")
    add("**false verdicts, total**", lambda s: f"**{s['false_total']}**")
    add("  stable, P not exactly definite, or an eigenvalue of A with Re > 1e-6 |A| (numpy) or > 1e-10 |A| (120 digits)",
        lambda s: str(s["false_stable"]))
    add("  linearly_unstable, no eigenvalue with Re > 1e-9 |A| (numpy) and none > 1e-10 |A| (120 digits)",
        lambda s: str(s["false_unstable"]))
    add("  `check` exit != 0 on its own certificate", lambda s: str(s["check_fail"]))
    add("stable: independent exact re-check failed (P rebuilt, first variation, PA+A^TP=0, S sP - sQ >= 0, Q)",
        lambda s: str(s["exact_bound_fail"]))
    add("inconclusive where an exact definite form exists", lambda s: str(s["inconclusive_ref_definite"]))
    add("inconclusive where the reference is definite but not confirmed exactly",
        lambda s: str(s["inconclusive_ref_definite_unconfirmed"]))
    add("stable: infimum attained / approached (the certificate's `attained`)",
        lambda s: f"{s['attained']} / {s['approached']}")
    add("stable: `optimised: false` (no optimisation over the Casimir freedom)", lambda s: str(s["not_optimised"]))
    add("stable: Q depends on M (engine)", lambda s: str(s["q_dep_M"]))
    add("stable: reference infimum unknown (Q depends on M; family dim > 2; no confirmed point)",
        lambda s: str(s["infimum_unknown"]))
    add("stable: reference infimum 0: engine 0 / engine > 0",
        lambda s: f"{s['both_zero']} / {s['ref_zero_engine_pos']}")
    add("Sigma^2/inf - 1: systems with a known positive infimum", lambda s: str(s["n_rel"]))
    for q, lab in ((0.5, "50%"), (0.9, "90%"), (0.99, "99%"), (1.0, "max")):
        add(f"  quantile {lab}", lambda s, q=q: fmt(s["rel_q"][q]))
    add("  min (negative = below the reference infimum)", lambda s: fmt(s["rel_min"]))
    add("  of which below by > 1e-8 with Sigma^2 verified exactly (the reference is not at the infimum)",
        lambda s: str(s["ref_above_verified"]))
    for t in (1e-6, 1e-4, 1e-2, 0.1):
        add(f"  count > {t:g}", lambda s, t=t: str(s["rel_above"][t]))
    add("within_tolerance false", lambda s: str(s["within_tol_false"]))
    add("within_tolerance true, yet Sigma^2 above the reference infimum by more than the tolerance",
        lambda s: str(s["within_tol_claim_false"]))
    add("attained true, yet Sigma^2 above the reference infimum (1e-8)", lambda s: str(s["attained_claim_false"]))
    add("engine's own `optimisation.infimum` vs reference: abs rel. diff. 50% / 99% / max",
        lambda s: " / ".join(fmt(x) for x in s["engine_inf_q"]))
    add("engine's own `optimisation.infimum` differs from the reference by > 1e-6 rel.",
        lambda s: str(s["engine_inf_differs"]))
    add("certify time, median / max (s)", lambda s: f"{fmt(s['t_certify'][0])} / {fmt(s['t_certify'][1])}")
    add("check time, median / max (s)", lambda s: f"{fmt(s['t_check'][0])} / {fmt(s['t_check'][1])}")
    other = sorted({f for s in stats.values() for f in s["flags"]})
    if other:
        lines.append("")
        lines.append("Flags (per binary):")
        lines.append("")
        lines.append("| flag | " + " | ".join(names) + " |")
        lines.append("|" + " --- |" * (len(names) + 1))
        for f in other:
            lines.append(f"| {f} | " + " | ".join(str(stats[nm]["flags"].get(f, 0)) for nm in names) + " |")
    return "\n".join(lines), stats


def population_table(rows):
    """What was generated, and what the reference says (binary independent)."""
    def cnt(key):
        d = {}
        for r in rows:
            k = key(r)
            d[k] = d.get(k, 0) + 1
        return d
    lines = ["| population | count |", "| --- | --- |"]
    for lab, key in (("dimension", lambda r: r["meta"]["dim"]),
                     ("basis", lambda r: r["meta"]["basis"]),
                     ("Casimirs", lambda r: r["meta"]["casimirs"]),
                     ("first integral", lambda r: r["meta"].get("fi")),
                     ("intended", lambda r: r["meta"]["intended"]),
                     ("reference verdict (instability by the 120-digit spectrum)",
                      lambda r: (r.get("reference") or {}).get("verdict_robust") or "error"),
                     ("reference stable, definite form confirmed exactly",
                      lambda r: (r.get("reference") or {}).get("exact_definite")
                      if (r.get("reference") or {}).get("verdict") == "stable" else "n/a"),
                     ("reference infimum over the Casimir freedom",
                      lambda r: "n/a" if (r.get("reference") or {}).get("verdict") != "stable" else (
                          "unknown: " + (r["reference"].get("infimum_unknown_reason") or "Q depends on M")
                          if not r["reference"].get("infimum_known") else
                          ("0" if r["reference"].get("infimum") == 0 else
                           ("> 0, multiplier family searched" if r["reference"].get("sigma2_refined") is not None
                            else "> 0, no multiplier family")))),
                     ("reference infimum over a multiplier family only approached as |t| -> infinity",
                      lambda r: bool(((r.get("reference") or {}).get("refine_info") or {}).get("approached"))
                      if (r.get("reference") or {}).get("sigma2_refined") is not None else "n/a"),
                     ("numpy_pipeline errors", lambda r: bool((r.get("reference") or {}).get("error"))),
                     ("numpy_pipeline robustness fallbacks used",
                      lambda r: bool((r.get("reference") or {}).get("gen_max_fallbacks")))):
        for k, v in sorted(cnt(key).items(), key=lambda kv: str(kv[0])):
            lines.append(f"| {lab}: {k} | {v} |")
    alg = cnt(lambda r: r["meta"]["algebra"])
    lines.append("| algebras (distinct) | " + str(len(alg)) + " |")
    return "\n".join(lines)


# ==========================================================================
# Driver
# ==========================================================================


def spec_sha(text):
    return hashlib.sha256(text.encode()).hexdigest()


def write_specs(items, d):
    os.makedirs(d, exist_ok=True)
    paths = []
    for spec, ref_spec, meta in items:
        p = os.path.join(d, spec["name"] + ".json")
        text = json.dumps(spec)
        with open(p, "w") as fh:
            fh.write(text)
        with open(os.path.join(d, spec["name"] + ".ref.json"), "w") as fh:
            json.dump(ref_spec, fh)
        with open(os.path.join(d, spec["name"] + ".meta.json"), "w") as fh:
            json.dump(meta, fh, indent=1)
        paths.append((p, text))
    return paths


def _ref_job(args):
    import warnings
    warnings.simplefilter("ignore", RuntimeWarning)    # numpy_pipeline's Nelder-Mead overflows
    ref_spec, spec, parse = args
    return reference(ref_spec, spec, parse)


def self_test(n=50, seed=12345):
    """The numpy reference on a system and on the same system in a random
    basis: identical verdicts and infima (1e-8 relative)."""
    bad = 0
    done = 0
    i = 0
    while done < n:
        rng_state = f"selftest:{seed}:{i}"
        r1 = gen_system(random.Random(rng_state), i, seed, force_random_basis=False)
        r2 = gen_system(random.Random(rng_state), i, seed, force_random_basis=True)
        i += 1
        if r1 is None or r2 is None:
            continue
        (s1, rs1, m1), (s2, rs2, m2) = r1, r2
        a = reference(rs1, s1)
        b = reference(rs2, s2)
        done += 1
        ok = a.get("verdict_robust") == b.get("verdict_robust")
        detail = ""
        if ok and a.get("verdict") == "stable":
            if a.get("infimum_known") != b.get("infimum_known"):
                ok = False
                detail = "infimum_known differs"
            elif a.get("infimum_known"):
                x, y = a["infimum"], b["infimum"]
                if abs(x - y) > 1e-8 * max(abs(x), abs(y), 1e-300) and not (x == 0 == y):
                    # tiny values: rounding noise around 0 (numpy floors at 1e-10 scale)
                    ok = abs(x - y) <= 1e-12
                    detail = f"infimum {x!r} vs {y!r}"
        if a.get("max_re_hp") is not None and b.get("max_re_hp") is not None:
            ra = a["max_re_hp"] / max(1.0, a["normA1_hp"])
            rb = b["max_re_hp"] / max(1.0, b["normA1_hp"])
            xa, xb = a["max_re_hp"], b["max_re_hp"]
            if ((ra > 1e-10) != (rb > 1e-10)) or \
                    (max(ra, rb) > 1e-10 and abs(xa - xb) > 1e-8 * max(abs(xa), abs(xb))):
                ok = False
                detail += f" max Re {a['max_re_hp']} vs {b['max_re_hp']}"
        for x in (a, b):
            if x.get("error") or x.get("gen_max_fallbacks"):
                detail += f" [{x.get('error') or 'fallbacks %d' % x['gen_max_fallbacks']}]"
        print(f"  #{i - 1:<3} {m1['algebra']:>18} dim {m1['dim']} fi={m1.get('fi')} det T={m2.get('det_T')}: "
              f"{a.get('verdict_robust')} {fmt(a.get('infimum'), 12)} | {b.get('verdict_robust')} "
              f"{fmt(b.get('infimum'), 12)} {'ok' if ok else 'MISMATCH'} {detail}")
        if not ok:
            bad += 1
    print(f"self-test: {done} systems, {bad} mismatches")
    assert bad == 0, "basis transformation changes the reference verdict or infimum"
    # the fast exact reading of the reference spec against numpy_pipeline.prepare:
    # the same numbers (structure constants, derivatives at mu_e, mu_e, noise)
    import numpy as np
    npp = numpy_pipeline()
    bad2 = 0
    for j in range(12):
        r = gen_system(random.Random(f"selftest-parse:{seed}:{j}"), j, seed)
        if r is None:
            continue
        s, rsp, m = r
        pa, pb = prepare_exact(rsp), npp.prepare(rsp)
        da = np.asarray(pa.ders(*pa.mu_e), dtype=float)
        db = np.asarray(pb.ders(*pb.mu_e), dtype=float)
        same = (np.array_equal(pa.c, pb.c) and np.array_equal(pa.mu_e, pb.mu_e)
                and (pa.m_cas, pa.m_fi) == (pb.m_cas, pb.m_fi)
                and all(np.array_equal(x, y) for x, y in zip(pa.sigmas, pb.sigmas))
                and len(pa.sigmas) == len(pb.sigmas)
                and float(np.abs(da - db).max(initial=0.0)) <= 1e-9 * max(1.0, float(np.abs(db).max(initial=0.0))))
        va, vb = npp.certify(pa).get("verdict"), npp.certify(pb).get("verdict")
        print(f"  parse exact vs sympy: {m['algebra']:>18} dim {m['dim']}: data "
              f"{'same' if same else 'DIFFERENT'} (max derivative difference "
              f"{float(np.abs(da - db).max(initial=0.0)):.2g}); numpy verdicts {va} | {vb}")
        bad2 += not same
    print(f"self-test (reference parsing): {bad2} mismatches")
    assert bad2 == 0, "prepare_exact disagrees with numpy_pipeline.prepare"
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 epilog=__doc__[__doc__.index("Usage"):__doc__.index("Conventions")],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--count", type=int, default=2000)
    ap.add_argument("--bin", action="append", default=[], metavar="NAME=PATH",
                    help="engine binary (repeatable)")
    ap.add_argument("--out", default="random_study.jsonl", help="per-spec rows (JSONL)")
    ap.add_argument("--md", default=None, help="also write the printed tables here")
    ap.add_argument("--workdir", default=None, help="where specs and certificates go (default: a temp dir)")
    ap.add_argument("--only-generate", metavar="DIR", default=None, help="only write the specs to DIR")
    ap.add_argument("--self-test", action="store_true")
    ap.add_argument("--reference-cache", default=None, metavar="FILE",
                    help="JSONL of an earlier run: reuse its reference results (matched by spec SHA-256)")
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--gate", action="store_true",
                    help="exit 1 on a false verdict, a certificate its own check rejects, an exact "
                         "re-check that fails, an inconclusive where an exact definite form exists, "
                         "a within_tolerance claim the reference contradicts, or a timeout (for CI)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cases", default="/work/study-cases", help="copy specs with flagged results here")
    ap.add_argument("--report-only", metavar="JSONL", default=None,
                    help="recompute the flags and tables from the rows of an earlier run (no runs)")
    ap.add_argument("--reference-parse", choices=["exact", "sympy"], default="exact",
                    help="how the reference reads its spec: exact (fast, default) or "
                         "numpy_pipeline.prepare (sympy, up to 20 s per 8-dim spec)")
    args = ap.parse_args(argv)
    global REFERENCE_PARSE
    REFERENCE_PARSE = args.reference_parse

    if args.self_test:
        return self_test(seed=args.seed if args.seed != 1 else 12345)
    if args.report_only:
        with open(args.report_only) as fh:
            rows = [json.loads(line) for line in fh if line.strip()]
        names = sorted({nm for r in rows for nm in r["engines"]})
        for r in rows:
            for nm in r["engines"]:
                e = r["engines"][nm]
                e["rel_excess"] = rel_excess(e, r.get("reference"))
                e["flags"] = judge(r, nm)
        text = "\n".join([f"# Random study (re-analysed from {args.report_only}): {len(rows)} systems", "",
                          population_table(rows), "", report(rows, names)[0]])
        print(text)
        if args.md:
            with open(args.md, "w") as fh:
                fh.write(text + "\n")
        return 0

    t_start = time.time()
    t0 = time.time()
    items = generate(args.seed, args.count, args.workers)
    t_gen = time.time() - t0
    print(f"generated {len(items)} systems in {t_gen:.1f} s", file=sys.stderr)
    if args.only_generate:
        write_specs(items, args.only_generate)
        print(f"wrote {len(items)} specs (and .ref.json, .meta.json) to {args.only_generate}")
        return 0

    bins = []
    for b in args.bin:
        nm, _, path = b.partition("=")
        if not path:
            ap.error(f"--bin {b}: expected NAME=PATH")
        bins.append((nm, os.path.abspath(path)))

    workdir = args.workdir or tempfile.mkdtemp(prefix="random_study_")
    spec_dir = os.path.join(workdir, "specs")
    paths = write_specs(items, spec_dir)
    rows = []
    for (spec, ref_spec, meta), (p, text) in zip(items, paths):
        rows.append({"name": spec["name"], "spec_path": p, "spec_sha256": spec_sha(text),
                     "meta": meta, "engines": {}})

    # ---- reference (cached or computed, 2 processes)
    cache = {}
    if args.reference_cache:
        with open(args.reference_cache) as fh:
            for line in fh:
                line = line.strip()
                if line:
                    d = json.loads(line)
                    if d.get("reference") is not None:
                        cache[d["spec_sha256"]] = d["reference"]
    todo = [i for i, r in enumerate(rows) if r["spec_sha256"] not in cache]
    for i, r in enumerate(rows):
        if r["spec_sha256"] in cache:
            r["reference"] = cache[r["spec_sha256"]]
            r["reference_cached"] = True
    t0 = time.time()
    if todo:
        with cf.ProcessPoolExecutor(max_workers=args.workers) as ex:
            futs = {ex.submit(_ref_job, (items[i][1], items[i][0], args.reference_parse)): i for i in todo}
            done = 0
            for fut in cf.as_completed(futs):
                i = futs[fut]
                try:
                    rows[i]["reference"] = fut.result()
                except Exception as exc:  # noqa: BLE001
                    rows[i]["reference"] = {"error": str(exc)[:300]}
                done += 1
                if done % 200 == 0:
                    print(f"  reference {done}/{len(todo)} ({time.time() - t0:.0f} s)", file=sys.stderr)
    t_ref = time.time() - t0
    print(f"reference: {len(todo)} computed, {len(rows) - len(todo)} from cache, {t_ref:.1f} s",
          file=sys.stderr)

    # ---- engines
    t_eng = {}
    for nm, path in bins:
        cdir = os.path.join(workdir, "certs-" + nm)
        os.makedirs(cdir, exist_ok=True)
        t0 = time.time()

        def job(i, path=path, cdir=cdir):
            r = rows[i]
            er, cert, cert_path = run_engine(path, r["spec_path"], cdir, args.timeout)
            if cert is not None:
                er.update(summarise_cert(cert))
                er["cert_path"] = cert_path
                if cert.get("verdict") == "stable" and cert.get("P") is not None:
                    er["exact"] = exact_check_certificate(items[i][0], cert)
            return i, er
        with cf.ThreadPoolExecutor(max_workers=args.workers) as ex:
            futs = [ex.submit(job, i) for i in range(len(rows))]
            done = 0
            for fut in cf.as_completed(futs):
                i, er = fut.result()
                rows[i]["engines"][nm] = er
                done += 1
                if done % 200 == 0:
                    print(f"  {nm}: {done}/{len(rows)} ({time.time() - t0:.0f} s)", file=sys.stderr)
        t_eng[nm] = time.time() - t0
        for r in rows:
            e = r["engines"][nm]
            e["rel_excess"] = rel_excess(e, r.get("reference"))
            e["flags"] = judge(r, nm)
        print(f"{nm}: {time.time() - t0:.1f} s", file=sys.stderr)

    # ---- keep flagged cases
    serious = ("false_", "check_failed", "exact_", "inconclusive_ref_definite", "verdict_differs",
               "below_reference_infimum", "unexpected_", "missed_", "certify_failed",
               "sign_differs", "unstable_ref_marginal", "within_tolerance_claim_false", "attained_claim_false",
               "engine_infimum_differs", "stable_where_reference_not", "unstable_numpy_none")
    # and the 10 largest excesses over the reference infimum, per binary
    worst = set()
    for nm, _ in bins:
        ex_rows = sorted((r for r in rows if r["engines"][nm].get("rel_excess") is not None),
                         key=lambda r: -r["engines"][nm]["rel_excess"])
        worst |= {r["name"] for r in ex_rows[:10] if r["engines"][nm]["rel_excess"] > 1e-2}
    n_cases = 0
    for r in rows:
        fl = sorted({f for nm, _ in bins for f in r["engines"][nm].get("flags", [])
                     if f.startswith(serious)})
        if r["name"] in worst:
            fl.append("largest_excess")
        r["case_flags"] = fl
        if fl and args.cases:
            os.makedirs(args.cases, exist_ok=True)
            shutil.copy(r["spec_path"], os.path.join(args.cases, r["name"] + ".json"))
            for suffix in (".ref.json", ".meta.json"):
                src = r["spec_path"][:-5] + suffix
                if os.path.exists(src):
                    shutil.copy(src, os.path.join(args.cases, r["name"] + suffix))
            for nm, _ in bins:
                cp = r["engines"][nm].get("cert_path")
                if cp and os.path.exists(cp):
                    shutil.copy(cp, os.path.join(args.cases, f"{r['name']}.{nm}.cert.json"))
            r["case_path"] = os.path.join(args.cases, r["name"] + ".json")
            n_cases += 1

    with open(args.out, "w") as fh:
        for r in rows:
            fh.write(json.dumps(r) + "\n")

    names = [nm for nm, _ in bins]
    parts = [f"# Random study: {len(rows)} systems, seed {args.seed}", ""]
    parts.append(f"Generation {t_gen:.0f} s; reference {t_ref:.0f} s "
                 f"({len(todo)} computed, {len(rows) - len(todo)} cached); "
                 + "; ".join(f"{nm} {t:.0f} s" for nm, t in t_eng.items())
                 + f"; total {time.time() - t_start:.0f} s.")
    parts.append("")
    parts.append(population_table(rows))
    parts.append("")
    if names:
        table, stats = report(rows, names)
        parts.append(table)
        parts.append("")
        parts.append(f"{n_cases} flagged specs copied to {args.cases}.")
    text = "\n".join(parts)
    print(text)
    if args.md:
        with open(args.md, "w") as fh:
            fh.write(text + "\n")
    if args.gate and names:
        failed = []
        for nm, s in stats.items():
            for key in ("false_total", "exact_bound_fail", "inconclusive_ref_definite",
                        "within_tol_claim_false", "timeouts"):
                if s.get(key):
                    failed.append(f"{nm}: {key} = {s[key]}")
        if failed:
            print("GATE FAILED: " + "; ".join(failed), file=sys.stderr)
            return 1
        print("gate passed: no false verdict, no failed re-check, no lost definite form, "
              "no false within_tolerance claim, no timeout")
    return 0


if __name__ == "__main__":
    sys.exit(main())
