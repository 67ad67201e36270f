"""The CLI's .npz output (crates/npz, pure Rust) read by numpy itself: every
array equals its JSON counterpart."""

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
FIXTURES = REPO / "fixtures"
CODES = ["stable", "linearly_unstable", "inconclusive", "not_an_equilibrium", "noise_incompatible"]


def verify_binary():
    # ./test.sh runs `cargo test --workspace` first, which builds the debug binary.
    for kind in ("debug", "release"):
        path = REPO / "target" / kind / "verify"
        if path.exists():
            return path
    pytest.skip("no verify binary under target/ (run ./test.sh)")


def test_simulate_npz_equals_the_json(tmp_path):
    subprocess.run([str(verify_binary()), "simulate", str(FIXTURES / "rigid-body-major-axis.json"), "--paths", "300",
                    "--t-end", "3", "--outputs", "30", "--out", str(tmp_path), "--npz"],
                   check=True, capture_output=True, timeout=600)
    z = np.load(tmp_path / "rigid-body-major-axis.npz")
    r = json.loads((tmp_path / "rigid-body-major-axis.json").read_text())
    assert np.array_equal(z["nonlinear_mean"], np.array(r["nonlinear"]["mean"]))
    assert z["nonlinear_mean"].shape == (31, 3)
    assert np.array_equal(z["histogram_counts"], np.array(r["histogram"]["counts"], dtype=float))
    assert np.array_equal(z["exact_moments_over_delta"], r["exact_moments_over_delta"])
    assert np.array_equal(z["linearised_norm_mean_over_delta"], r["linearised"]["norm_mean_over_delta"])
    assert float(z["sigma2"]) == r["sigma2"] == 0.27


def test_sweep_npz_equals_the_lines(tmp_path):
    lines, npz = tmp_path / "s.jsonl", tmp_path / "s.npz"
    subprocess.run([str(verify_binary()), "sweep", str(FIXTURES / "rigid-body-major-axis.json"),
                    "--param", "sigma=0:3/10:4", "--param", "I2=1/2:9/2:5", "-o", str(lines), "--npz", str(npz)],
                   check=True, capture_output=True, timeout=600)
    records = sorted((json.loads(line) for line in lines.read_text().splitlines()), key=lambda r: r["index"])
    z = np.load(npz)
    assert list(z["index"]) == [r["index"] for r in records] == list(range(20))
    assert np.array_equal(z["I2"], [r["parameters"]["I2"] for r in records])
    assert [CODES[c] for c in z["verdict_code"]] == [r["verdict"] for r in records]
    for r, s2, t in zip(records, z["sigma2"], z["T"]):
        assert (np.isnan(s2) and r.get("sigma2") is None) or s2 == r["sigma2"]
        if r.get("T") == "infinity":  # sigma = 0: Sigma^2 = 0
            assert t == np.inf
    # sigma = 0 gives T = inf; I2 = 7/2 and 9/2 exceed I1 = 3 > I3 = 1, so e1
    # is the intermediate axis there: linearly unstable.
    assert np.isinf(z["T"]).any()
    assert set(z["I2"][z["verdict_code"] == 1]) == {3.5, 4.5}
