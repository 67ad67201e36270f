"""sweep() against the closed forms, shards, progress, and interruption."""

import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import energy_casimir as ec

REPO = Path(__file__).resolve().parents[2]
FIXTURES = REPO / "fixtures"


def test_grid_matches_the_closed_form():
    """Lagrange top under fluctuating gravity: stable iff p^2 > 4 mgl I1,
    then Sigma^2 = 4 sigma^2 / (p^2 - 4 mgl I1) (generator::closed_forms),
    I1 = 1, sigma = 3/10."""
    cols = ec.sweep(FIXTURES / "lagrange-top-fluctuating-gravity.json", {"p": ("5/2", 4, 4), "mgl": (0, 2, 5)})
    assert len(cols["index"]) == 20 and list(cols["index"]) == list(range(20))
    for p, mgl, verdict, s2 in zip(cols["p"], cols["mgl"], cols["verdict"], cols["sigma2"]):
        if p * p > 4 * mgl:
            assert verdict == "stable"
            assert s2 == pytest.approx(4 * 0.09 / (p * p - 4 * mgl), rel=1e-9)
        else:
            assert verdict != "stable"
            assert np.isnan(s2)


def test_shards_partition_the_sweep_and_lines_are_the_clis():
    spec = FIXTURES / "sweeps" / "rigid-body-triangle.json"
    params = {"I1": ("1/100", "1/2", 8), "I2": ("1/100", "1/2", 8)}
    whole = ec.sweep(spec, params, numeric=True)
    parts = [ec.sweep(spec, params, numeric=True, shard=(k, 3)) for k in range(3)]
    assert all(i % 3 == k for k, part in enumerate(parts) for i in part["index"])
    assert sorted(line for part in parts for line in part["lines"]) == sorted(whole["lines"])
    assert all(level == "numerical" for level in whole["level"])
    # The spec's domain (I3 = 1 - I1 - I2 <= 1/2 and >= 1/100) leaves points out.
    assert 0 < len(whole["index"]) < 64
    assert all(0.5 - 1e-12 <= i1 + i2 <= 0.99 + 1e-12 for i1, i2 in zip(whole["I1"], whole["I2"]))
    line = json.loads(whole["lines"][0])
    assert line["sweep"] and line["spec"] and "exact_parameters" in line


def test_progress_reaches_the_total_and_an_exception_in_it_stops_the_sweep():
    calls = []
    cols = ec.sweep(FIXTURES / "rigid-body-major-axis.json", {"I2": (Fraction(11, 10), Fraction(29, 10), 30)},
                    progress=lambda done, total: calls.append((done, total)))
    assert calls and calls[-1] == (30, 30) and len(cols["index"]) == 30
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:]))

    class Stop(Exception):
        pass

    def stop(done, total):
        raise Stop

    with pytest.raises(Stop):
        ec.sweep(FIXTURES / "lagrange-top-fluctuating-gravity.json", {"p": (3, 9, 400), "mgl": (0, 1, 400)},
                 progress=stop)


def test_ctrl_c_stops_a_long_sweep(interrupted):
    """SIGINT to a process running a sweep of 160,000 exact points (minutes
    of work) ends it with KeyboardInterrupt within seconds."""
    interrupted("sweep('fixtures/lagrange-top-fluctuating-gravity.json', {'p': (3, 9, 400), 'mgl': (0, 1, 400)})", 1.5)


@pytest.mark.parametrize(
    "params, text",
    [
        ({"J": (0, 1, 3)}, "J"),
        ({"I2": (3, 1, 3)}, "START"),
        ({"I2": (1, 3)}, "expected (start, stop, count)"),
        ({"I2": (1, float("inf"), 3)}, "finite"),
    ],
)
def test_bad_ranges_are_value_errors(params, text):
    with pytest.raises(ValueError) as e:
        ec.sweep(FIXTURES / "rigid-body-major-axis.json", params)
    assert text in str(e.value)


def test_infinite_stopping_times_and_empty_shards():
    """sigma = 0: Sigma^2 = 0 and T is infinite, not missing; a shard with no
    points still has the parameter columns."""
    cols = ec.sweep(FIXTURES / "rigid-body-major-axis.json", {"sigma": (0, "3/10", 2)})
    assert cols["sigma2"][0] == 0 and cols["T"][0] == float("inf")
    assert cols["T"][1] == pytest.approx(np.log(100) / 0.27)
    empty = ec.sweep(FIXTURES / "sweeps" / "rigid-body-triangle.json", shard=(2600, 2700))
    assert len(empty["index"]) == 0 and "I1" in empty and "I2" in empty
    with pytest.raises(ValueError):
        ec.sweep(FIXTURES / "rigid-body-major-axis.json", {"I2": (1, 3, 2.5)})
