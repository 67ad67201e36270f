# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Three shear flows against their published numbers
#
# The engine certifies a 2D Euler shear flow `U(y)` x-mode by x-mode: a mode
# is either linearly unstable (an eigenvalue of the discretised drift with
# positive real part, its growth rate) or has a definite energy–Casimir form
# and a certified growth constant `Sigma^2` for the stochastic (transport
# noise) linearisation. Here three classical flows are certified one
# x-wavenumber `k` at a time (a spec with x-period `2 pi / k` and one mode)
# and compared with what the literature says:
#
# * **Michalke's mixing layer** `U = tanh y` (Michalke 1964, J. Fluid Mech.
#   19): the fastest temporal mode has `k = 0.4446` and growth rate
#   `0.1897`. Walls at `y = +-15` stand in for the unbounded layer.
# * **The Bickley jet** `U = sech^2 y`: the sinuous mode is unstable for
#   `0 < k < 2` and neutral at `k = 2`, where `sech^2 y` itself is the
#   neutral eigenfunction with phase speed `2/3` (Drazin & Reid,
#   *Hydrodynamic Stability*, section 31).
# * **Kolmogorov flow** `U = sin y`, periodic in `y`: unstable exactly for
#   x-wavenumbers `k < 1` (Meshalkin & Sinai 1961).
#
# Run as a script from anywhere (`python examples/shear_flows.py [--out DIR]`)
# or open it as a notebook (jupytext). It asserts the published numbers and
# writes `shear-flows.png`.

# %%
import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import energy_casimir as ec  # noqa: E402

parser = argparse.ArgumentParser(description="Three shear flows against their published numbers")
parser.add_argument("--out", default="out/gallery")
args, _ = parser.parse_known_args()  # (a notebook kernel adds its own arguments)
OUT = Path(args.out)
OUT.mkdir(parents=True, exist_ok=True)


def mode(k, shear_flow, y_interval, boundary, noise, ny=256):
    """The certificate of the single x-mode k of U(y) = shear_flow."""
    return ec.certify({
        "name": f"{shear_flow} at k = {k:.6g}",
        "fluid": {
            "model": "incompressible",
            "x_period": 2 * math.pi / k,
            "y_interval": y_interval,
            "boundary": boundary,
            "shear_flow": shear_flow,
            "noise": [noise],
            "ny": ny,
            "x_modes": 1,
        },
    })


def growth(cert):
    """The growth rate, NaN where the mode is not linearly unstable."""
    return cert.growth_rate if cert.verdict == "linearly_unstable" else math.nan


# %% [markdown]
# ## Michalke's mixing layer

# %%
tanh = dict(shear_flow="tanh(y)", y_interval=[-15, 15], boundary="walls", noise="0.2*exp(-y^2)")
at_max = mode(0.4446, **tanh)
print(f"tanh y, k = 0.4446: {at_max.verdict}, growth rate {at_max.growth_rate:.6f} (Michalke: 0.1897)")
assert at_max.verdict == "linearly_unstable"
assert abs(at_max.growth_rate - 0.1897) < 5e-5  # Michalke's four digits
ks_tanh = np.linspace(0.05, 0.95, 19)
certs_tanh = [mode(k, **tanh) for k in ks_tanh]
g_tanh = np.array([growth(c) for c in certs_tanh])
# Every mode of the grid is unstable, and the fastest lies next to
# Michalke's k (grid step 0.05).
assert not np.isnan(g_tanh).any()
assert abs(ks_tanh[g_tanh.argmax()] - 0.4446) <= 0.05
assert g_tanh.max() <= at_max.growth_rate + 1e-6

# %% [markdown]
# ## The Bickley jet

# %%
sech = dict(shear_flow="sech(y)^2", y_interval=[-10, 10], boundary="walls", noise="0.2*exp(-y^2)")
below, above = mode(1.9, **sech), mode(2.01, **sech)
print(f"sech^2 y, k = 1.9: {below.verdict}, growth rate {below.growth_rate:.6f}")
print(f"sech^2 y, k = 2.01: {above.verdict}, Sigma^2 = {above.sigma2:.6f} ({above.level})")
assert below.verdict == "linearly_unstable" and below.growth_rate > 0
assert above.verdict == "stable"  # past the neutral wavenumber 2: certified
ks_sech = np.linspace(0.1, 2.5, 25)
certs_sech = [mode(k, **sech) for k in ks_sech]
g_sech = np.array([growth(c) for c in certs_sech])
# Unstable throughout the band k < 1.9 of the grid, certified stable past 2.
assert all(g > 0 for k, g in zip(ks_sech, g_sech) if k <= 1.9)
assert all(c.verdict == "stable" for k, c in zip(ks_sech, certs_sech) if k > 2)

# %% [markdown]
# ## Kolmogorov flow

# %%
kolmogorov = dict(shear_flow="sin(y)", y_interval=[0, "2*pi"], boundary="periodic", noise="0.3*cos(y)", ny=64)
just_below, just_above = mode(0.99, **kolmogorov), mode(1.01, **kolmogorov)
print(f"sin y, k = 0.99: {just_below.verdict}, growth rate {just_below.growth_rate:.6f}")
print(f"sin y, k = 1.01: {just_above.verdict}, Sigma^2 = {just_above.sigma2:.6f} ({just_above.level})")
assert just_below.verdict == "linearly_unstable"
assert just_above.verdict == "stable"
ks_kol = np.linspace(0.1, 1.5, 15)
certs_kol = [mode(k, **kolmogorov) for k in ks_kol]
g_kol = np.array([growth(c) for c in certs_kol])
# (k = 1 itself is neutral, and the engine says inconclusive there)
assert all(g > 0 for k, g in zip(ks_kol, g_kol) if k < 0.999)
assert all(c.verdict == "stable" for k, c in zip(ks_kol, certs_kol) if k > 1.001)

# %% [markdown]
# ## The three curves
#
# Growth rate of each x-wavenumber certified linearly unstable; a hollow
# marker on the axis is a mode certified stable (a definite energy–Casimir
# form), a cross one the engine leaves inconclusive (the neutral
# wavenumbers themselves).

# %%
fig, axes = plt.subplots(1, 3, figsize=(13, 3.6), constrained_layout=True)
panels = [
    (axes[0], "Michalke: U = tanh y", ks_tanh, g_tanh, certs_tanh, [(0.4446, 0.1897, "Michalke (0.4446, 0.1897)")]),
    (axes[1], "Bickley jet: U = sech² y", ks_sech, g_sech, certs_sech, [(2.0, 0.0, "neutral at k = 2")]),
    (axes[2], "Kolmogorov flow: U = sin y", ks_kol, g_kol, certs_kol, [(1.0, 0.0, "threshold k = 1")]),
]
for ax, title, ks, g, certs, published in panels:
    ax.plot(ks, g, "o-", color="C0", ms=4, label="growth rate (linearly unstable)")
    for verdict, style, colour in (("stable", "o", "C2"), ("inconclusive", "x", "0.4")):
        at = [k for k, c in zip(ks, certs) if c.verdict == verdict]
        if at:
            ax.plot(at, np.zeros(len(at)), style, mfc="white", color=colour, ms=6, label=verdict)
    for k, rate, label in published:
        ax.plot([k], [rate], "*", color="C3", ms=12, label=label)
    ax.set_title(title)
    ax.set_xlabel("x-wavenumber k")
    ax.axhline(0, color="0.6", lw=0.8)
    ax.set_ylim(-0.01, 1.45 * np.nanmax(g))  # room for the legend
    ax.legend(fontsize=8, loc="upper right")
axes[0].set_ylabel("growth rate")
fig.savefig(OUT / "shear-flows.png", dpi=110)
print(f"wrote {OUT / 'shear-flows.png'}")
