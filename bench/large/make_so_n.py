#!/usr/bin/env python3
"""Write the spec of the free rigid body on so(n) (dimension n(n-1)/2).

    python3 bench/large/make_so_n.py N [--plane I J] [--sigma S] [-o FILE]

Coordinates M_a_b (a < b) in the basis E_ab = e_a e_b^T - e_b e_a^T, with
[E_ab, E_bc] = E_ac (so(n) as skew-symmetric matrices under the
commutator). The inertia is Manakov's, J_a = a + 1, so the Hamiltonian is
H = 1/2 sum_{a<b} M_ab^2 / (J_a + J_b), and the quadratic Casimir
C = 1/2 sum M_ab^2 (-tr(M^2)/4) is given. The equilibrium is the stationary
rotation in the plane (I, J) (M_IJ = 1, the rest 0), and the noise one
field along that plane, sigma E_IJ (it commutes with M_e: compatible).
Above 64 coordinates (n >= 13) `verify certify` runs the large pipeline.
"""
import argparse, json, sys

ap = argparse.ArgumentParser()
ap.add_argument("n", type=int)
ap.add_argument("--plane", nargs=2, type=int, default=[0, 1])
ap.add_argument("--sigma", default="3/10")
ap.add_argument("-o", "--output")
a = ap.parse_args()
n = a.n
pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]
index = {p: k for k, p in enumerate(pairs)}
name = lambda i, j: f"M_{i}_{j}"


def element(i, j):
    """E_ij as (sign, index) with E_ji = -E_ij."""
    return (1, index[(i, j)]) if i < j else (-1, index[(j, i)])


# [E_ab, E_cd] = d_bc E_ad - d_ac E_bd - d_bd E_ac + d_ad E_bc
rows = {}
for x, (a1, b1) in enumerate(pairs):
    for y, (c1, d1) in enumerate(pairs):
        if x >= y:
            continue
        out = {}
        for (i, j, s, cond) in [(a1, d1, 1, b1 == c1), (b1, d1, -1, a1 == c1), (a1, c1, -1, b1 == d1), (b1, c1, 1, a1 == d1)]:
            if cond and i != j:
                sg, k = element(i, j)
                out[k] = out.get(k, 0) + s * sg
        for k, c in out.items():
            if c != 0:
                rows[(x, y, k)] = c
structure = [[x, y, k, c] for (x, y, k), c in sorted(rows.items())]
J = [i + 1 for i in range(n)]
h = " + ".join(f"{name(i, j)}^2/{2 * (J[i] + J[j])}" for (i, j) in pairs)
cas = "(" + " + ".join(f"{name(i, j)}^2" for (i, j) in pairs) + ")/2"
p, q = sorted(a.plane)
eq = [1 if (i, j) == (p, q) else 0 for (i, j) in pairs]
noise = ["sigma" if (i, j) == (p, q) else 0 for (i, j) in pairs]
spec = {
    "name": f"so{n}-rigid-body",
    "description": f"The free rigid body on so({n}) (Manakov inertia J_a = a + 1), turning in the plane ({p}, {q}), with one noise field along that plane (bench/large/make_so_n.py).",
    "algebra": {"coordinates": [name(i, j) for (i, j) in pairs], "structure_constants": structure},
    "parameters": {"sigma": a.sigma},
    "hamiltonian": h,
    "casimirs": [cas],
    "equilibrium": eq,
    "noise": [noise],
    "stopping": {"epsilon": 0.1, "delta": 0.001},
}
text = json.dumps(spec)
if a.output:
    open(a.output, "w").write(text + "\n")
else:
    sys.stdout.write(text + "\n")
