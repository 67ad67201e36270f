"""Sweep the rigid body with the independent numpy/scipy pipeline.

The same grid as `verify sweep fixtures/rigid-body-major-axis.json --param
I2=... --param I3=...`: for each point the spec's parameters are replaced,
`numpy_pipeline.prepare` builds the problem (sympy, timed separately) and
`numpy_pipeline.certify` runs steps 1-7 in floating point. Prints points per
second with and without the sympy preparation, then compares the verdicts and
Sigma^2 with the engine's lines given by --lines (relative 1e-6).
"""
import argparse, copy, json, sys, time
from fractions import Fraction
sys.path.insert(0, __file__.rsplit("/", 1)[0])
import numpy_pipeline as npp

ap = argparse.ArgumentParser()
ap.add_argument("--count", type=int, default=20)
ap.add_argument("--lines", help="the engine's sweep lines for the same grid")
args = ap.parse_args()
spec = json.load(open("fixtures/rigid-body-major-axis.json"))
lo, hi, k = Fraction(1, 10), Fraction(6), args.count
grid = [lo + (hi - lo) * i / (k - 1) for i in range(k)]
results, t_prep, t_cert = {}, 0.0, 0.0
for i2 in grid:
    for i3 in grid:
        s = copy.deepcopy(spec)
        s["parameters"]["I2"], s["parameters"]["I3"] = str(i2), str(i3)
        t0 = time.perf_counter()
        pp = npp.prepare(s)
        t1 = time.perf_counter()
        out = npp.certify(pp)
        t2 = time.perf_counter()
        t_prep += t1 - t0
        t_cert += t2 - t1
        results[(str(i2), str(i3))] = (out["verdict"], out["sigma2"])
n = len(results)
print(json.dumps({"points": n, "numpy_points_per_s_certify_only": n / t_cert,
                  "numpy_points_per_s_with_sympy_prepare": n / (t_prep + t_cert)}))
if args.lines:
    agree, worst = 0, 0.0
    for line in open(args.lines):
        r = json.loads(line)
        key = (r["exact_parameters"]["I2"], r["exact_parameters"]["I3"])
        key = tuple(str(Fraction(x)) for x in key)
        if key not in results:
            continue
        verdict, s2 = results[key]
        assert verdict == r["verdict"], (key, verdict, r)
        if verdict == "stable":
            worst = max(worst, abs(s2 - r["sigma2"]) / max(abs(r["sigma2"]), 1e-12))
        agree += 1
    assert agree == n, (agree, n)
    assert worst < 1e-6, worst
    print(json.dumps({"compared": agree, "verdicts_agree": True, "max_relative_sigma2_difference": worst}))
