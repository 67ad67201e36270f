"""simulate_zeitlin: the CLI's arrays from Python, the exact moment under the
certified bound with the Monte Carlo beside it, refusals named, labelled
arrays, and Ctrl-C."""

import json
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest

import energy_casimir as ec

REPO = Path(__file__).resolve().parents[2]
# The paper's family at N = 8 with noise 3 z^2: stable with the energy in
# the form, Sigma^2 of about 4e-4 (it grows as the noise's amplitude squared).
SPEC = {"name": "z8", "zeitlin": {"N": 8, "equilibrium": "z + 0.3*z^3", "noise": ["3*z^2"]},
        "settings": {"casimir_momentum": False}}
OPTIONS = dict(paths=400, t_end=2.0, dt=0.01, outputs=20, seed=4)


def verify_binary():
    for kind in ("debug", "release"):
        path = REPO / "target" / kind / "verify"
        if path.exists():
            return path
    pytest.skip("no verify binary under target/ (run ./test.sh)")


def test_the_report_is_the_clis_and_stays_under_the_bound(tmp_path):
    r = ec.simulate_zeitlin(SPEC, **OPTIONS)
    cert = ec.certify(SPEC)
    assert r["kind"] == "zeitlin-simulation" and r["N"] == 8
    # hbar = 2 / sqrt(N^2 - 1): times per qtime, and the proved bound.
    hbar = 2 / math.sqrt(63)
    assert r["hbar"] == pytest.approx(hbar, rel=1e-15)
    assert np.allclose(r["times_qtime"], r["times"] / hbar, rtol=1e-14)
    assert np.allclose(r["certified_bound"], np.exp(cert["sigma2_upper"] * r["times"]), rtol=1e-14)
    assert r["initial_rate"] == pytest.approx(cert.sigma2, rel=1e-8)  # the block with the largest lambda_max
    assert (r["exact"] <= r["certified_bound"] * (1 + 1e-6)).all()
    assert (np.abs(r["monte_carlo_mean"] - r["exact"]) <= 4 * r["monte_carlo_std_error"] + 1e-3 * r["exact"]).all()
    # The nonlinear model beside the linear exact moment, Casimirs to rounding.
    nl = r["nonlinear"]
    assert nl["paths"] == 40 and nl["delta"] == 1e-6
    assert (np.abs(nl["mean"] - r["exact"]) <= 4 * nl["std_error"] + 1e-3 * r["exact"]).all()
    assert nl["casimir_drift"] < 1e-12
    # The CLI writes the same arrays.
    spec_file = tmp_path / "z8.json"
    spec_file.write_text(json.dumps(SPEC))
    subprocess.run([str(verify_binary()), "simulate", str(spec_file), "--paths", "400", "--t-end", "2", "--dt", "0.01",
                    "--outputs", "20", "--seed", "4", "--out", str(tmp_path)], check=True, capture_output=True, timeout=600)
    cli = json.loads(next(tmp_path.glob("z8-m*.json")).read_text())
    for key in ("times", "times_qtime", "monte_carlo_mean", "monte_carlo_std_error", "exact", "certified_bound", "block_bound"):
        assert np.array_equal(np.asarray(cli[key]), r[key]), key
    assert np.array_equal(np.asarray(cli["nonlinear"]["mean"]), nl["mean"])
    ds = ec.to_xarray(r)
    assert dict(ds.sizes) == {"t": len(r["times"])}
    assert np.array_equal(ds["qtime"].values, r["times_qtime"])
    assert np.array_equal(ds["nonlinear_mean"].values, nl["mean"]) and ds.attrs["nonlinear_paths"] == 40


def test_what_cannot_be_simulated_is_refused():
    with pytest.raises(ValueError, match="a simulation is set beside a stable certificate's conserved form"):
        ec.simulate_zeitlin(REPO / "fixtures" / "zeitlin" / "jet-n64.json", paths=10, t_end=0.1)
    with pytest.raises(ValueError, match="only states zonal in some frame are simulated"):
        ec.simulate_zeitlin(REPO / "fixtures" / "zeitlin" / "rossby-haurwitz-l2-n7.json", paths=10, t_end=0.1)
    with pytest.raises(ValueError, match="simulate_zeitlin runs Zeitlin specs"):
        ec.simulate_zeitlin(REPO / "fixtures" / "rigid-body-major-axis.json")
    with pytest.raises(ValueError, match=r"block: need 1 <= block <= N - 1 = 7, got 8"):
        ec.simulate_zeitlin(SPEC, block=8, **OPTIONS)
    with pytest.raises(ValueError, match="dt: must be positive"):
        ec.simulate_zeitlin(SPEC, **{**OPTIONS, "dt": -1.0})
    with pytest.raises(ValueError, match="would take about"):
        ec.simulate_zeitlin(SPEC, paths=10**7, t_end=1e4, dt=0.01)


def test_a_tilted_state_simulates_in_its_zonal_frame():
    # The committed tilted fixture (stable, zonal about (-0.48, 0.6, 0.64)):
    # its block's start grows at the certificate's Sigma^2.
    spec = REPO / "fixtures" / "zeitlin" / "tilted-energy-casimir-n32.json"
    r = ec.simulate_zeitlin(spec, paths=20, t_end=0.05, outputs=2)
    cert = json.loads((REPO / "fixtures" / "zeitlin" / "tilted-energy-casimir-n32.cert.json").read_text())
    assert r["axis"] == pytest.approx(cert["frame"]["axis"], abs=1e-12)
    assert r["initial_rate"] == pytest.approx(cert["sigma2"], rel=1e-6)


def test_ctrl_c_stops_a_zeitlin_simulation(interrupted):
    interrupted("simulate_zeitlin({'name': 'z', 'zeitlin': {'N': 32, 'equilibrium': 'z + 0.3*z^3', 'noise': ['3*z^2']},"
                " 'settings': {'casimir_momentum': False}}, paths=10**6, t_end=100.0, force=True)", 2.0)
