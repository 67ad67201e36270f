#!/usr/bin/env python3
"""Write the spec of a chain of k coupled rigid bodies (so(3)^k, dimension 3k).

    python3 bench/large/make_chain.py K [--kappa K] [--inertia I1 I2 I3] [--axis A] [--sigma S] [-o FILE]

Body i has momentum (P1_i, P2_i, P3_i), Hamiltonian
sum_i sum_a Pa_i^2/(2 Ia) + kappa sum_i Pi_i . Pi_{i+1}, Casimirs |Pi_i|^2/2,
equilibrium: every body with unit momentum along axis A (1, 2 or 3), and one
noise field sigma along A on every body (compatible: it rotates each body
about its own momentum). Above 64 coordinates `verify certify` runs the
large pipeline on it.
"""
import argparse, json, sys

ap = argparse.ArgumentParser()
ap.add_argument("k", type=int)
ap.add_argument("--kappa", default="-1/10")
ap.add_argument("--inertia", nargs=3, default=["3", "2", "1"])
ap.add_argument("--axis", type=int, default=1)
ap.add_argument("--sigma", default="3/10")
ap.add_argument("-o", "--output")
a = ap.parse_args()
k, ax = a.k, a.axis - 1
name = lambda c, i: f"P{c + 1}_{i}"
coords = [name(c, i) for i in range(k) for c in range(3)]
rows = []
for i in range(k):
    o = 3 * i
    rows += [[o, o + 1, o + 2, 1], [o + 1, o + 2, o, 1], [o + 2, o, o + 1, 1]]
h = []
for i in range(k):
    h += [f"{name(c, i)}^2/(2*I{c + 1})" for c in range(3)]
    if i + 1 < k:
        h += [f"kappa*{name(c, i)}*{name(c, i + 1)}" for c in range(3)]
spec = {
    "name": f"chain-{k}",
    "description": f"{k} rigid bodies coupled by kappa Pi_i . Pi_(i+1), each turning about axis {a.axis}, with one noise field along that axis on every body (bench/large/make_chain.py).",
    "algebra": {"coordinates": coords, "structure_constants": rows},
    "parameters": {"I1": a.inertia[0], "I2": a.inertia[1], "I3": a.inertia[2], "kappa": a.kappa, "sigma": a.sigma},
    "hamiltonian": " + ".join(h),
    "casimirs": [f"({name(0, i)}^2 + {name(1, i)}^2 + {name(2, i)}^2)/2" for i in range(k)],
    "equilibrium": [1 if j % 3 == ax else 0 for j in range(3 * k)],
    "noise": [["sigma" if j % 3 == ax else 0 for j in range(3 * k)]],
    "stopping": {"epsilon": 0.1, "delta": 0.001},
}
text = json.dumps(spec, indent=1)
if a.output:
    open(a.output, "w").write(text + "\n")
else:
    sys.stdout.write(text + "\n")
