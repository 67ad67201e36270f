"""Results as xarray Datasets: every variable equals the dict's array it
came from, dimensions and units are named, grids unstack, the attributes
survive netCDF, and without xarray the error says what to install."""

import sys
from pathlib import Path

import numpy as np
import pytest

import energy_casimir as ec

xr = pytest.importorskip("xarray")  # test.sh installs it
FIXTURES = Path(__file__).resolve().parents[2] / "fixtures"


def test_a_study_as_a_dataset(tmp_path):
    r = ec.simulate(FIXTURES / "rigid-body-major-axis.json", paths=300, t_end=2.0, outputs=20, bins=16)
    ds = ec.to_xarray(r)
    assert dict(ds.sizes) == {"t": 21, "coordinate": 3, "bin": 16}
    assert ds["coordinate"].values.tolist() == ["Pi1", "Pi2", "Pi3"]
    assert np.array_equal(ds["t"].values, r["nonlinear"]["times"])
    assert "model time" in ds["t"].attrs["units"]
    for ensemble in ("nonlinear", "linearised"):
        assert np.array_equal(ds[f"{ensemble}_mean"].values, r[ensemble]["mean"])
        for key in ("norm_mean_over_delta", "norm_std_error_over_delta", "exceedance"):
            assert np.array_equal(ds[f"{ensemble}_{key}"].values, r[ensemble][key])
        assert ds.attrs[f"{ensemble}_casimir_drift"] == r[ensemble]["casimir_drift"]
    for key in ("exact_moments_over_delta", "worst_case_over_delta", "bound_over_delta"):
        assert np.array_equal(ds[key].values, r[key])
    assert np.array_equal(ds["histogram_counts"].values, r["histogram"]["counts"])
    # Bin centres of the histogram's range split into 16 equal bins.
    lo, hi = r["histogram"]["range"]
    assert ds["bin"].values[0] == pytest.approx(lo + (hi - lo) / 32, rel=1e-12)
    assert ds.attrs["sigma2"] == 0.27 and ds.attrs["parameters_paths"] == 300
    assert ds.attrs["parameters_observable"] == "Pi1"
    # Selecting by label works as users expect.
    assert float(ds["nonlinear_mean"].sel(coordinate="Pi1").isel(t=0)) == r["nonlinear"]["mean"][0][0]
    path = tmp_path / "study.nc"
    ds.to_netcdf(path, engine="scipy")
    back = xr.open_dataset(path, engine="scipy")
    assert np.array_equal(back["bound_over_delta"].values, r["bound_over_delta"])
    assert back.attrs["verdict"] == "stable"


def test_an_unstable_study_has_no_linearised_ensemble():
    r = ec.simulate(FIXTURES / "rigid-body-intermediate-axis.json", paths=200, t_end=1.0, outputs=10)
    ds = ec.to_xarray(r)
    assert "nonlinear_mean" in ds and "linearised_mean" not in ds
    assert ds.attrs["verdict"] == "linearly_unstable"


def test_a_fluid_mode_as_a_dataset(tmp_path):
    r = ec.simulate_fluid(FIXTURES / "fluids" / "arnold-boundary-sin.json", ny=16, paths=100, t_end=1.0, outputs=4)
    ds = ec.to_xarray(r)
    assert dict(ds.sizes) == {"t": len(r["times"])} and len(r["times"]) == 4
    for key in ("monte_carlo_mean", "monte_carlo_std_error", "exact", "certified_bound", "initial_rate_bound"):
        assert np.array_equal(ds[key].values, r[key]), key
    assert ds.attrs["m"] == 1 and ds.attrs["ny"] == 16 and ds.attrs["sigma2_mode_verified"] == 1
    ds.to_netcdf(tmp_path / "fluid.nc", engine="scipy")


def test_a_grid_sweep_unstacks_and_random_points_do_not():
    cols = ec.sweep(FIXTURES / "rigid-body-major-axis.json", {"I2": ("3/2", "5/2", 3), "I3": ("1/2", "1", 2)})
    ds = ec.to_xarray(cols)
    assert dict(ds["sigma2"].sizes) == {"I2": 3, "I3": 2}
    for i in range(len(cols["index"])):
        at = ds["sigma2"].sel(I2=cols["I2"][i], I3=cols["I3"][i])
        assert float(at) == cols["sigma2"][i]
        assert str(ds["verdict"].sel(I2=cols["I2"][i], I3=cols["I3"][i]).values) == cols["verdict"][i]
    line = ec.to_xarray(ec.sweep(FIXTURES / "rigid-body-major-axis.json", {"I2": ("3/2", "5/2", 3)}))
    assert list(line["sigma2"].dims) == ["I2"]
    assert line["sigma2"].sel(I2=2.0).item() == pytest.approx(0.27, rel=1e-12)  # the fixture's own point
    ranges = {"I2": ("3/2", "5/2", 3), "I3": ("1/2", "1", 2)}
    scattered = ec.to_xarray(ec.sweep(FIXTURES / "rigid-body-major-axis.json", ranges, random=5, seed=2))
    assert list(scattered["sigma2"].dims) == ["point"]
    assert scattered["I2"].dims == ("point",) and scattered["I3"].dims == ("point",)


def test_what_is_not_a_result_is_refused(monkeypatch):
    shard = ec.simulate(FIXTURES / "rigid-body-major-axis.json", paths=200, t_end=1.0, outputs=10, shard=(0, 2))
    with pytest.raises(ValueError, match="merge the shards first"):
        ec.to_xarray(shard)
    with pytest.raises(ValueError, match="not a result"):
        ec.to_xarray({"name": "x"})
    with pytest.raises(TypeError, match="expected the dict"):
        ec.to_xarray([1, 2])
    monkeypatch.setitem(sys.modules, "xarray", None)  # as if not installed
    with pytest.raises(ImportError, match=r"pip install xarray"):
        ec.to_xarray({"name": "x"})
