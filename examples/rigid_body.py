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
# # The stochastic rigid body, and the paper's figure
#
# 1. Certify the major-axis equilibrium (`I = (3, 2, 1)`, noise `0.3 e1`)
#    and print the verdict, `Sigma^2` and the stopping time `T(0.1, 0.001)`.
# 2. Map `Sigma^2` against the middle inertia `I2` (certificates, one per
#    point) beside the closed form `sigma^2 (max(a2, a3)/min(a2, a3) - 1)`,
#    `a_i = 1/I_i - 1/I1`.
# 3. Redraw the paper's figure 1(a) from `simulate`: the density of `Pi1`
#    over time (grey), the mean path (solid) and the mean under isotropic
#    noise `sigma e_i`, `i = 1, 2, 3` (dashed).
#
# Run as a script (`python examples/rigid_body.py [--out DIR] [--paths N]`)
# or open it as a notebook (jupytext). It writes `sigma2-vs-I2.png` and
# `paper-figure-rigid-body.png`.

# %%
import argparse
import json
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import energy_casimir as ec  # noqa: E402

parser = argparse.ArgumentParser(description="The stochastic rigid body, and the paper's figure")
parser.add_argument("--out", default="out/gallery")
parser.add_argument("--paths", type=int, default=2000)
args, _ = parser.parse_known_args()  # (a notebook kernel adds its own arguments)
out = Path(args.out)
out.mkdir(parents=True, exist_ok=True)
try:
    FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
except NameError:  # in a notebook: opened from examples/
    FIXTURES = Path.cwd().parent / "fixtures"

# %% [markdown]
# ## 1. One certificate

# %%
spec = json.loads((FIXTURES / "rigid-body-major-axis.json").read_text())
cert = ec.certify(spec)
print(f"{cert.name}: {cert.verdict} ({cert.level}), Sigma^2 = {cert.sigma2_exact} = {cert.sigma2}")
print(f"T(0.1, 0.001) = {cert.stopping_time(0.1, 0.001):.6f}   (ln(100)/Sigma^2 = {math.log(100) / cert.sigma2:.6f})")
ec.check(cert)

# %% [markdown]
# ## 2. Sigma^2 against I2 (I1 = 3, I3 = 1, sigma = 0.3)

# %%
i2s = np.linspace(1.05, 2.95, 39)
sigma2 = []
for i2 in i2s:
    spec["parameters"]["I2"] = f"{i2:.2f}"
    sigma2.append(ec.certify(spec).sigma2)
a2, a3 = 1 / i2s - 1 / 3, 1.0 - 1 / 3
closed = 0.09 * (np.maximum(a2, a3) / np.minimum(a2, a3) - 1)
worst = float(np.max(np.abs(np.array(sigma2) - closed) / closed))
print(f"Sigma^2 against I2 at {len(i2s)} points: largest relative gap to the closed form {worst:.1e}")
fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(i2s, closed, "-", color="0.6", lw=3, label="closed form")
ax.plot(i2s, sigma2, "o", ms=4, color="C0", label="certified")
ax.set_xlabel("I2   (I1 = 3, I3 = 1, noise 0.3 e1)")
ax.set_ylabel("Sigma^2")
ax.set_yscale("log")
ax.legend()
fig.tight_layout()
fig.savefig(out / "sigma2-vs-I2.png", dpi=120)
plt.close(fig)

# %% [markdown]
# ## 3. The paper's figure: density of Pi1, mean path, isotropic-noise mean

# %%
major = ec.simulate(FIXTURES / "rigid-body-major-axis.json", paths=args.paths, seed=1)
iso = ec.simulate(FIXTURES / "rigid-body-isotropic-noise.json", paths=args.paths, seed=1,
                  t_end=float(major["parameters"]["t_end"]))
times = major["nonlinear"]["times"]
counts = major["histogram"]["counts"]
lo, hi = major["histogram"]["range"]
density = counts / np.maximum(counts.sum(axis=1, keepdims=True), 1)
fig, ax = plt.subplots(figsize=(7, 4))
ax.imshow(density.T, origin="lower", aspect="auto", cmap="Greys",
          extent=(times[0], times[-1], lo, hi), vmax=np.quantile(density, 0.99))
ax.plot(times, major["nonlinear"]["mean"][:, 0], "k-", lw=1.5, label="mean, noise 0.3 e1")
ax.plot(iso["nonlinear"]["times"], iso["nonlinear"]["mean"][:, 0], "k--", lw=1.5, label="mean, isotropic noise")
t_stop = major["stopping_time"]
if t_stop is not None:
    ax.axvline(t_stop, color="C3", lw=1, label=f"T(eps, delta) = {t_stop:.1f}")
ax.set_xlabel("t")
ax.set_ylabel("Pi1")
ax.set_title(f"stochastic rigid body, {args.paths} paths")
ax.legend(loc="lower left", fontsize=8)
fig.tight_layout()
fig.savefig(out / "paper-figure-rigid-body.png", dpi=120)
plt.close(fig)
print(f"mean Pi1 at t = {times[-1]:.0f}: {major['nonlinear']['mean'][-1, 0]:.4f} (noise 0.3 e1), "
      f"{iso['nonlinear']['mean'][-1, 0]:.4f} (isotropic)")
print(f"wrote {out / 'sigma2-vs-I2.png'} and {out / 'paper-figure-rigid-body.png'}")

