"""simulate() against an independent numpy computation of the exact second
moments of the linearised SDE, and the Monte Carlo against those."""

import math
from pathlib import Path

import numpy as np
import pytest

import energy_casimir as ec

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures"


def expm(m):
    """exp(m) by scaling and squaring with a degree-24 Taylor polynomial
    (numpy only; accurate to rounding for the small matrices here)."""
    norm = np.abs(m).sum(axis=1).max()
    k = max(0, int(math.ceil(math.log2(norm))) + 1) if norm > 0 else 0
    a = m / 2.0**k
    out, term = np.eye(len(m)), np.eye(len(m))
    for j in range(1, 25):
        term = term @ a / j
        out = out + term
    for _ in range(k):
        out = out @ out
    return out


def test_exact_moments_rebuilt_in_numpy():
    """dS/dt = A~ S + S A~^T + B S B^T with A~ = A + B^2/2 (Stratonovich to
    Ito), S(0) = x0 x0^T, E|x_t|_P^2 = tr(P S(t)); A and B from the Euler
    equations of the body I = (3, 2, 1) with noise 0.3 e1 about e1."""
    cert = ec.certify(FIXTURES / "rigid-body-major-axis.json")
    r = ec.simulate(FIXTURES / "rigid-body-major-axis.json", paths=2000, t_end=4.0, outputs=40, seed=3)
    P = cert.P

    def cross(v):
        return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])

    inv_i = np.diag([1 / 3, 1 / 2, 1.0])
    pe = np.array([1.0, 0, 0])
    A = cross(pe) @ inv_i - cross(inv_i @ pe)
    B = -cross(np.array([0.3, 0, 0]))
    At = A + 0.5 * B @ B
    eye = np.eye(3)
    # vec(A S + S A^T + B S B^T) = (I (x) A + A (x) I + B (x) B) vec(S), row-major vec.
    L = np.kron(At, eye) + np.kron(eye, At) + np.kron(B, B)
    x0 = np.asarray(r["parameters"]["mu0"]) - pe
    delta = r["delta"]
    assert x0 @ P @ x0 == pytest.approx(delta, rel=1e-12)
    times = r["nonlinear"]["times"]
    s0 = np.outer(x0, x0).reshape(-1)
    ours = np.array([np.trace(P @ (expm(L * t) @ s0).reshape(3, 3)) / delta for t in times])
    assert np.allclose(r["exact_moments_over_delta"], ours, rtol=1e-9, atol=1e-12)
    # Started along the fastest direction: the moment starts growing at the
    # rate Sigma^2 and stays under the bound exp(Sigma^2 t).
    assert np.all(ours <= np.exp(0.27 * times) * (1 + 1e-12))
    assert np.allclose(r["bound_over_delta"], np.exp(0.27 * times), rtol=1e-12)
    # The linearised Monte Carlo agrees with the exact moments within 4
    # standard errors (plus rounding).
    lin = r["linearised"]
    gap = np.abs(lin["norm_mean_over_delta"] - ours)
    assert np.all(gap <= 4 * lin["norm_std_error_over_delta"] + 1e-9), gap.max()
    # The histogram counts every path at every output time.
    counts = r["histogram"]["counts"]
    assert counts.shape == (len(times), r["parameters"]["bins"])
    assert np.all(counts.sum(axis=1) <= 2000)


def test_same_seed_same_paths_and_unstable_specs():
    a = ec.simulate(FIXTURES / "rigid-body-major-axis.json", paths=100, t_end=1.0, outputs=20, seed=5)
    b = ec.simulate(FIXTURES / "rigid-body-major-axis.json", paths=100, t_end=1.0, outputs=20, seed=5)
    assert np.array_equal(a["nonlinear"]["mean"], b["nonlinear"]["mean"])
    u = ec.simulate(FIXTURES / "rigid-body-intermediate-axis.json", paths=100, t_end=1.0, outputs=20)
    assert u["verdict"] == "linearly_unstable" and u["sigma2"] is None and u["linearised"] is None


@pytest.mark.parametrize(
    "kwargs, text",
    [
        ({"scheme": "euler"}, "scheme"),
        ({"observable": "Gamma1"}, "observable"),
        ({"epsilon": 1e-4, "delta": 1e-3}, "delta"),
        ({"paths": 10**9, "dt": 1e-4, "t_end": 200.0}, "force=True"),
    ],
)
def test_bad_settings_are_value_errors(kwargs, text):
    with pytest.raises(ValueError) as e:
        ec.simulate(FIXTURES / "rigid-body-major-axis.json", **kwargs)
    assert text in str(e.value)


def test_fluid_specs_go_to_simulate_fluid():
    with pytest.raises(ValueError) as e:
        ec.simulate(FIXTURES / "fluids" / "channel-sin-walls.json", paths=10)
    assert "simulate_fluid" in str(e.value)
    with pytest.raises(ValueError):
        ec.simulate_fluid(FIXTURES / "rigid-body-major-axis.json")


def test_simulate_fluid_matches_the_command_line():
    """The same study as `verify simulate` (tests/it/fluid_cli.rs): near
    Arnold's boundary the exact moment stays under exp(Sigma_k^2 t) with
    Sigma_k^2 = 0.2626 (docs/errata.md) and far above the paper's
    exp(0.01 t); the Monte Carlo agrees with it."""
    r = ec.simulate_fluid(FIXTURES / "fluids" / "arnold-boundary-sin.json", ny=32, paths=400, t_end=2.0, outputs=10)
    assert r["kind"] == "fluid-simulation" and r["m"] == 1
    assert abs(r["sigma2_mode"] - 0.2626) < 1e-4
    assert (r["exact"] <= r["certified_bound"] * (1 + 1e-9)).all()
    assert (abs(r["monte_carlo_mean"] - r["exact"]) <= 4 * r["monte_carlo_std_error"] + 1e-3 * r["exact"]).all()
    assert r["exact"][-1] > 1.3 * np.exp(0.02)
    assert r["summary"]["monte_carlo_agrees_with_exact"] == 10


@pytest.mark.parametrize(
    "kwargs, text",
    [
        ({"mode": 0}, "mode"),
        ({"ny": 8}, "ny"),
        ({"paths": 1}, "paths"),
        ({"dt": -1.0}, "dt"),
        ({"paths": 10**7, "t_end": 100.0}, "force=True"),
    ],
)
def test_bad_fluid_settings_are_value_errors(kwargs, text):
    with pytest.raises(ValueError) as e:
        ec.simulate_fluid(FIXTURES / "fluids" / "arnold-boundary-sin.json", **kwargs)
    assert text in str(e.value)


def test_progress_counts_both_ensembles_and_ctrl_c_stops_a_long_run(interrupted):
    calls = []
    ec.simulate(FIXTURES / "rigid-body-major-axis.json", paths=3000, t_end=5.0, outputs=20,
                progress=lambda done, total: calls.append((done, total)))
    assert calls[-1] == (6000, 6000)  # stable: the nonlinear and the linearised ensemble
    interrupted("simulate('fixtures/rigid-body-major-axis.json', paths=400000, t_end=200.0, force=True)", 2.0)


def test_simulate_fluid_reports_progress_and_ctrl_c_stops_it(interrupted):
    """The count is planned once and only grows: it is seen part way
    (a run of a few seconds, looked at ten times a second) and ends at its
    total; an exception in the callback stops the run and propagates; Ctrl-C
    ends a run estimated at about 20 minutes (10^6 paths of 1000 steps at
    ny = 32)."""
    arnold = FIXTURES / "fluids" / "arnold-boundary-sin.json"
    calls = []
    r = ec.simulate_fluid(arnold, ny=16, paths=8000, t_end=2.0, outputs=4,
                          progress=lambda done, total: calls.append((done, total)))
    assert r["m"] == 1
    assert calls and calls[-1][0] == calls[-1][1] > 0
    assert any(0 < done < total for done, total in calls), calls
    planned = {total for _, total in calls if total > 0}
    assert len(planned) == 1, planned
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:]))

    class Stop(Exception):
        pass

    def stop(done, total):
        if done > 0:
            raise Stop

    with pytest.raises(Stop):
        ec.simulate_fluid(arnold, ny=16, paths=200000, t_end=10.0, outputs=4, force=True, progress=stop)
    interrupted("simulate_fluid('fixtures/fluids/arnold-boundary-sin.json', paths=10**6, t_end=10.0, force=True)", 2.0)


def test_the_report_counts_the_engine_threads():
    """RAYON_NUM_THREADS sets the engine's threads: the report records them
    (and the time estimate counts them), as `verify simulate` does."""
    import os
    import subprocess
    import sys

    code = (
        "import energy_casimir as ec, sys; "
        "r = ec.simulate(sys.argv[1], paths=64, t_end=1.0, outputs=10); "
        "print(r['parameters']['threads'])"
    )
    for threads in ("1", "3"):
        env = {**os.environ, "RAYON_NUM_THREADS": threads}
        out = subprocess.run(
            [sys.executable, "-c", code, str(FIXTURES / "rigid-body-major-axis.json")],
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
        assert out.stdout.strip() == threads
