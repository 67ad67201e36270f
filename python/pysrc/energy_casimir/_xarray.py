"""Results as labelled arrays: :func:`energy_casimir.to_xarray`."""

from __future__ import annotations

from typing import Any, Dict, Mapping

import numpy as np

TIME_UNITS = "model time t (the spec's equations; for the Zeitlin model quflow's t)"


def _attrs(values: Mapping[str, Any]) -> Dict[str, Any]:
    """The entries netCDF can store as attributes: numbers and strings
    (booleans as 0/1; None and containers left out)."""
    out: Dict[str, Any] = {}
    for key, value in values.items():
        if isinstance(value, bool):
            out[key] = int(value)
        elif isinstance(value, (int, float, str, np.integer, np.floating)):
            out[key] = value
    return out


def _var(dims: Any, values: Any, long_name: str, units: str = "1") -> Any:
    return (dims, np.asarray(values, dtype=float), {"long_name": long_name, "units": units})


def _study(xr: Any, r: Mapping[str, Any]) -> Any:
    """A finite-dimensional study (`simulate`, `merge_shards`)."""
    nonlinear = r["nonlinear"]
    times = np.asarray(nonlinear["times"], dtype=float)
    coordinates = list(r.get("coordinates") or [str(i) for i in range(np.shape(nonlinear["mean"])[1])])
    counts = np.asarray(r["histogram"]["counts"], dtype=float)
    lo, hi = (float(x) for x in r["histogram"]["range"])
    edges = np.linspace(lo, hi, counts.shape[1] + 1)
    observable = r["parameters"]["observable"]
    data: Dict[str, Any] = {}
    for ensemble, label in (("nonlinear", "nonlinear SDE"), ("linearised", "linearised SDE")):
        stats = r.get(ensemble)
        if not stats:
            continue
        if not np.array_equal(np.asarray(stats["times"], dtype=float), times):
            raise ValueError(f"{ensemble}.times: not the nonlinear ensemble's output times")
        data[f"{ensemble}_mean"] = _var(("t", "coordinate"), stats["mean"], f"mean of each coordinate, {label}", "coordinate units")
        data[f"{ensemble}_norm_mean_over_delta"] = _var(
            "t", stats["norm_mean_over_delta"], f"Monte Carlo E|dmu_t|_P^2 / delta, {label}")
        data[f"{ensemble}_norm_std_error_over_delta"] = _var(
            "t", stats["norm_std_error_over_delta"], f"standard error of E|dmu_t|_P^2 / delta, {label}")
        data[f"{ensemble}_exceedance"] = _var(
            "t", stats["exceedance"], f"fraction of paths with |dmu_t|_P^2 > epsilon, {label}")
    for key, long_name in (
        ("exact_moments_over_delta", "exact E|dmu_t|_P^2 / delta of the linearised SDE from the start"),
        ("worst_case_over_delta", "largest exact E|dmu_t|_P^2 / delta over starts with |dmu_0|_P^2 = delta"),
        ("bound_over_delta", "certified bound exp(Sigma^2 t)"),
    ):
        if r.get(key) is not None:
            data[key] = _var("t", r[key], long_name)
    data["histogram_counts"] = _var(("t", "bin"), counts, f"paths per bin of {observable}, nonlinear SDE", "paths")
    attrs = _attrs({k: v for k, v in r.items() if k not in ("parameters",)})
    attrs.update(_attrs({f"parameters_{k}": v for k, v in r["parameters"].items()}))
    for ensemble in ("nonlinear", "linearised"):
        if r.get(ensemble):
            attrs[f"{ensemble}_casimir_drift"] = float(r[ensemble]["casimir_drift"])
    return xr.Dataset(
        data,
        coords={
            "t": ("t", times, {"long_name": "time", "units": TIME_UNITS}),
            "coordinate": ("coordinate", coordinates, {"long_name": "coordinate of the Lie–Poisson system"}),
            "bin": ("bin", (edges[:-1] + edges[1:]) / 2, {"long_name": f"centre of a histogram bin of {observable}",
                                                          "units": "coordinate units"}),
        },
        attrs=attrs,
    )


def _fluid(xr: Any, r: Mapping[str, Any]) -> Any:
    """One x-mode of a fluid spec (`simulate_fluid`)."""
    data: Dict[str, Any] = {
        "monte_carlo_mean": _var("t", r["monte_carlo_mean"], "Monte Carlo E V(t) / V(0)"),
        "monte_carlo_std_error": _var("t", r["monte_carlo_std_error"], "standard error of E V(t) / V(0)"),
        "certified_bound": _var("t", r["certified_bound"], "certified bound exp(Sigma_k^2 t)"),
        "initial_rate_bound": _var("t", r["initial_rate_bound"], "exp(initial rate t)"),
    }
    if r.get("exact") is not None:
        data["exact"] = _var("t", r["exact"], "exact E V(t) / V(0) of the discretised linear SDE")
    attrs = _attrs(r)
    attrs.update(_attrs({f"summary_{k}": v for k, v in (r.get("summary") or {}).items()}))
    return xr.Dataset(
        data,
        coords={"t": ("t", np.asarray(r["times"], dtype=float), {"long_name": "time", "units": TIME_UNITS})},
        attrs=attrs,
    )


def _zeitlin(xr: Any, r: Mapping[str, Any]) -> Any:
    """One block of a Zeitlin spec (`simulate_zeitlin`)."""
    data: Dict[str, Any] = {
        "monte_carlo_mean": _var("t", r["monte_carlo_mean"], "Monte Carlo E|z_t|_P^2 / |z_0|_P^2"),
        "monte_carlo_std_error": _var("t", r["monte_carlo_std_error"], "standard error of E|z_t|_P^2 / |z_0|_P^2"),
        "certified_bound": _var("t", r["certified_bound"], "certified bound exp(Sigma^2 t)"),
        "block_bound": _var("t", r["block_bound"], "the block's exp(lambda_max t)"),
    }
    if r.get("exact") is not None:
        data["exact"] = _var("t", r["exact"], "exact E|z_t|_P^2 / |z_0|_P^2 of the split scheme")
    nonlinear = r.get("nonlinear")
    if nonlinear:
        data["nonlinear_mean"] = _var("t", nonlinear["mean"], "nonlinear model: Monte Carlo E|W_t - W_e|_P^2 / delta")
        data["nonlinear_std_error"] = _var("t", nonlinear["std_error"], "standard error of the nonlinear mean")
    attrs = _attrs(r)
    if nonlinear:
        attrs.update(_attrs({f"nonlinear_{k}": v for k, v in nonlinear.items()}))
    attrs.update(_attrs({f"summary_{k}": v for k, v in (r.get("summary") or {}).items()}))
    return xr.Dataset(
        data,
        coords={
            "t": ("t", np.asarray(r["times"], dtype=float), {"long_name": "time", "units": TIME_UNITS}),
            "qtime": ("t", np.asarray(r["times_qtime"], dtype=float),
                      {"long_name": "quflow's integrator time t / hbar", "units": "qtime"}),
        },
        attrs=attrs,
    )


def _sweep(xr: Any, cols: Mapping[str, Any]) -> Any:
    """A sweep's columns: one point per index, unstacked into a grid when
    the points are one."""
    fixed = {"index", "verdict", "level", "sigma2", "T", "error", "lines"}
    params = [k for k in cols if k not in fixed]
    index = np.asarray(cols["index"], dtype=np.int64)
    data = {
        "verdict": ("point", np.asarray(cols["verdict"], dtype=object).astype(str), {"long_name": "verdict"}),
        "level": ("point", np.asarray([x or "" for x in cols["level"]], dtype=str), {"long_name": "verification level"}),
        "sigma2": _var("point", cols["sigma2"], "Sigma^2 (NaN where absent)", "1 / model time"),
        "T": _var("point", cols["T"], "stopping time T(epsilon, delta) (NaN where absent)", "model time"),
        "error": ("point", np.asarray([x or "" for x in cols["error"]], dtype=str), {"long_name": "why the spec is invalid there"}),
    }
    coords = {"index": ("point", index, {"long_name": "index of the point in the sweep"})}
    for p in params:
        coords[p] = ("point", np.asarray(cols[p], dtype=float), {"long_name": f"parameter {p}"})
    ds = xr.Dataset(data, coords=coords)
    # A full grid (every combination of the parameters' values once) becomes
    # one dimension per parameter.
    if params:
        values = [np.unique(np.asarray(cols[p], dtype=float)) for p in params]
        combos = {tuple(float(cols[p][i]) for p in params) for i in range(len(index))}
        if len(combos) == len(index) == int(np.prod([len(v) for v in values])):
            if len(params) == 1:
                ds = ds.swap_dims(point=params[0])
            else:
                ds = ds.set_index(point=params).unstack("point")
            for p in params:
                ds[p].attrs["long_name"] = f"parameter {p}"
    return ds


def to_xarray(result: Mapping[str, Any]) -> Any:
    try:
        import xarray as xr
    except ImportError:
        raise ImportError(
            "to_xarray needs xarray (pip install xarray); without it the results are dicts of numpy arrays"
        ) from None
    if not isinstance(result, Mapping):
        raise TypeError(f"to_xarray: expected the dict simulate, simulate_fluid, simulate_zeitlin, merge_shards or sweep returned, got {type(result).__name__}")
    if result.get("kind") == "fluid-simulation":
        return _fluid(xr, result)
    if result.get("kind") == "zeitlin-simulation":
        return _zeitlin(xr, result)
    if "nonlinear" in result and "histogram" in result:
        return _study(xr, result)
    if "lines" in result and "verdict" in result and "index" in result:
        return _sweep(xr, result)
    if result.get("kind") == "simulate-shard":
        raise ValueError("to_xarray: a shard holds sums, not results: merge the shards first (merge_shards)")
    raise ValueError("to_xarray: not a result of simulate, simulate_fluid, simulate_zeitlin, merge_shards or sweep")
