#!/usr/bin/env python3
"""Vectorised numpy Stratonovich Heun for the stochastic rigid body (so3) and
heavy top (se3): the baseline a user would write, for the side-by-side
simulation benchmark (bench/simulate_side_by_side.sh).

    d mu = ad*_{Dh(mu)} mu dt + sum_i ad*_{sigma_i} mu o dW^i,
    so3:  ad*_xi mu = mu x xi;   se3: ad*_(xi,u)(Pi,Gamma) = (Pi x xi + Gamma x u, Gamma x xi).

The Hamiltonian must be quadratic (Dh = H mu + b); H, b and the noise come
from the spec through sympy, once, outside the timed loop. All paths are
advanced together (arrays of shape (paths, n)); numpy runs this on one core.

Usage: numpy_heun.py SPEC PATHS STEPS   -> one JSON line with path-steps/s and
the Casimir drift (which Heun does not conserve).
"""
import json
import subprocess
import sys
import time

try:
    import numpy as np
    import sympy as sp
except ImportError:
    subprocess.check_call([sys.executable, "-m", "pip", "install", "--quiet", "numpy", "sympy"])
    import numpy as np
    import sympy as sp

COORDS = {"so3": ["Pi1", "Pi2", "Pi3"], "se3": ["Pi1", "Pi2", "Pi3", "Gamma1", "Gamma2", "Gamma3"]}


def load(path):
    spec = json.load(open(path))
    algebra = spec["algebra"]
    names = COORDS[algebra]
    syms = sp.symbols(names)
    params = {sp.Symbol(k): sp.Rational(str(v)) for k, v in spec.get("parameters", {}).items()}
    h = sp.sympify(spec["hamiltonian"].replace("^", "**")).subs(params)
    grad = [sp.diff(h, s) for s in syms]
    H = np.array([[float(sp.diff(g, s)) for s in syms] for g in grad])
    b = np.array([float(g.subs({s: 0 for s in syms})) for g in grad])
    ev = lambda e: float(sp.sympify(str(e).replace("^", "**")).subs(params))
    mu_e = np.array([ev(x) for x in spec["equilibrium"]])
    noise = np.array([[ev(x) for x in f] for f in spec["noise"]])
    return algebra, H, b, mu_e, noise


def coad(algebra, xi, mu):
    if algebra == "so3":
        return np.cross(mu, xi)
    pi, gamma = mu[:, :3], mu[:, 3:]
    w, u = xi[:, :3], xi[:, 3:]
    return np.concatenate([np.cross(pi, w) + np.cross(gamma, u), np.cross(gamma, w)], axis=1)


def casimirs(algebra, mu):
    if algebra == "so3":
        return [np.sum(mu * mu, axis=1)]
    return [np.sum(mu[:, 3:] ** 2, axis=1), np.sum(mu[:, :3] * mu[:, 3:], axis=1)]


def main():
    path, paths, steps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    algebra, H, b, mu_e, noise = load(path)
    dt = 1e-3
    rng = np.random.default_rng(1)
    mu = np.tile(mu_e + 0.01, (paths, 1))
    c0 = casimirs(algebra, mu)
    t = time.perf_counter()
    for _ in range(steps):
        dw = rng.standard_normal((paths, len(noise))) * np.sqrt(dt)
        nz = dw @ noise
        xi = mu @ H.T + b
        f1 = coad(algebra, xi * dt + nz, mu)
        stage = mu + f1
        xi2 = stage @ H.T + b
        f2 = coad(algebra, xi2 * dt + nz, stage)
        mu = mu + 0.5 * (f1 + f2)
    secs = time.perf_counter() - t
    drift = max(float(np.max(np.abs(c - c0_))) for c, c0_ in zip(casimirs(algebra, mu), c0))
    print(json.dumps({"spec": path, "scheme": "numpy-heun", "paths": paths, "steps": steps, "seconds": round(secs, 3),
                      "path_steps_per_second": paths * steps / secs, "casimir_drift": drift}))


if __name__ == "__main__":
    main()
