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
# # A stability map of the Lagrange top, proved box by box
#
# The Lagrange top (a symmetric heavy top, `I1 = I2`) spinning upright at
# `Pi3 = p` with noise about its symmetry axis is stable exactly where it
# spins fast enough: `p^2 > 4 mgl I1` (the fast top; the paper's third
# example). A *box* spec asks the engine for every parameter value in a
# rectangle at once: it bisects the box `(mgl, p)` in `[1/2, 3/2] x [1, 3]`
# into sub-boxes and proves each one stable (a definite energy–Casimir form
# on the whole closed sub-box, and a bound on `Sigma^2` over it), linearly
# unstable (on the whole sub-box), or leaves it undecided, in exact
# arithmetic. Near the curve the sub-boxes shrink; none that is proved
# stable may touch the unstable side.
#
# Run as a script (`python examples/lagrange_top_map.py [--out DIR]`) or
# open it as a notebook (jupytext). It checks every sub-box against the
# closed form and writes `lagrange-top-map.png`.

# %%
import argparse
from fractions import Fraction
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

import energy_casimir as ec  # noqa: E402

parser = argparse.ArgumentParser(description="A stability map of the Lagrange top")
parser.add_argument("--out", default="out/gallery")
args, _ = parser.parse_known_args()  # (a notebook kernel adds its own arguments)
OUT = Path(args.out)
OUT.mkdir(parents=True, exist_ok=True)

# %%
spec = {
    "name": "lagrange-top-map",
    "algebra": "se3",
    "parameters": {"I1": 1, "I3": "1/2", "mgl": 1, "p": 3, "sigma": "3/10"},
    "hamiltonian": "(Pi1^2 + Pi2^2)/(2*I1) + Pi3^2/(2*I3) + mgl*Gamma3",
    "casimirs": ["(Gamma1^2 + Gamma2^2 + Gamma3^2)/2", "Pi1*Gamma1 + Pi2*Gamma2 + Pi3*Gamma3"],
    "first_integrals": ["Pi3"],
    "equilibrium": [0, 0, "p", 0, 0, 1],
    "noise": [[0, 0, "sigma", 0, 0, 0]],
    "box": {"parameters": {"mgl": ["1/2", "3/2"], "p": ["1", "3"]}, "max_depth": 10},
}
cert = ec.certify(spec)
ec.check(cert)  # re-proved from the certificate alone
print(f"{cert.name}: {cert.verdict}; {len(cert['sub_boxes'])} sub-boxes")
print(f"  unstable {cert['unstable_fraction']:.4%} of the box, undecided {cert['undecided_fraction']:.4%}")

# %% [markdown]
# Every sub-box against the closed form, in exact arithmetic: `p^2 - 4 mgl
# I1` (with `I1 = 1`) is increasing in `p` and decreasing in `mgl` on the
# box, so it is positive on a whole sub-box exactly when it is positive at
# the corner `(mgl_hi, p_lo)`, and negative on the whole sub-box exactly
# when it is negative at `(mgl_lo, p_hi)`.

# %%
names = cert["parameters"]  # the order of a sub-box's lo and hi
assert names == ["mgl", "p"]
counts = {}
for box in cert["sub_boxes"]:
    (mgl_lo, p_lo), (mgl_hi, p_hi) = ([Fraction(x) for x in box[end]] for end in ("lo", "hi"))
    counts[box["verdict"]] = counts.get(box["verdict"], 0) + 1
    if box["verdict"] == "stable":
        assert p_lo**2 - 4 * mgl_hi > 0, box
    elif box["verdict"] == "linearly_unstable":
        assert p_hi**2 - 4 * mgl_lo < 0, box
print("sub-boxes by verdict:", counts)
assert counts.get("stable", 0) > 0 and counts.get("linearly_unstable", 0) > 0
# The exact area below the curve p = 2 sqrt(mgl) inside the box is the
# integral of (2 sqrt(mgl) - 1) over mgl in [1/2, 3/2], divided by the
# box's area 2; the unstable sub-boxes cover part of it.
below = ((4 / 3) * (1.5**1.5 - 0.5**1.5) - 1.0) / 2
print(f"  area below the curve: {below:.4%} of the box")
assert cert["unstable_fraction"] <= below <= cert["unstable_fraction"] + cert["undecided_fraction"]

# %%
colours = {"stable": "#4c9a5b", "linearly_unstable": "#c4453c", "undecided": "#d9d9d9"}
fig, ax = plt.subplots(figsize=(6.4, 4.8), constrained_layout=True)
for box in cert["sub_boxes"]:
    (x0, y0), (x1, y1) = ([float(Fraction(x)) for x in box[end]] for end in ("lo", "hi"))
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor=colours[box["verdict"]], edgecolor="white", lw=0.4))
mgl = np.linspace(0.5, 1.5, 200)
ax.plot(mgl, 2 * np.sqrt(mgl), color="black", lw=1.5, label="p² = 4 mgl I1 (fast-top threshold)")
for verdict, colour in colours.items():
    ax.add_patch(Rectangle((0, 0), 0, 0, facecolor=colour, label=verdict.replace("_", " ")))
ax.set_xlim(0.5, 1.5)
ax.set_ylim(1, 3)
ax.set_xlabel("mgl")
ax.set_ylabel("spin p")
ax.set_title("Lagrange top, noise about the axis: proved sub-boxes")
ax.legend(loc="upper left", fontsize=8)
fig.savefig(OUT / "lagrange-top-map.png", dpi=110)
print(f"wrote {OUT / 'lagrange-top-map.png'}")
