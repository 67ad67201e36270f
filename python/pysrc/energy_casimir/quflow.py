"""quflow's HDF5 files in and out: a Zeitlin spec from a quflow state, and
states written back in quflow's layout.

quflow (Modin and Viviani's Zeitlin-model integrator) writes simulations with
``quflow.save`` / ``quflow.QuData`` as HDF5 files holding

* ``state``: one row per output, quflow's real spherical-harmonic
  coefficients ``omega`` of the vorticity (``qtype`` ``"shr"``), length
  ``N^2``, the coefficient of ``T_lm`` at index ``l^2 + l + m``
  (``W = quflow.shr2mat(omega) = sum omega_lm T_lm``);
* ``qtime`` and ``time``: quflow's step time and the time ``t``, with
  ``time = qtime * hbar`` and ``hbar = 2 / sqrt(N^2 - 1)``;
* the attributes ``N``, ``version`` and ``created`` on the group.

The engine's spec takes the same coefficients as
``{"harmonics": [[l, m, value], ...]}`` in the same basis, so a state passes
through unchanged. **Times**: the engine's time is quflow's ``t`` (the
``time`` dataset, quflow's "seconds"): a growth rate, ``Sigma^2`` and a
stopping time in a certificate are per unit ``t``. quflow's integrators
step in ``qtime = t / hbar``; a rate per unit ``qtime`` is ``hbar`` times
the rate per unit ``t`` (:func:`rate_per_qtime`).

h5py is needed (``pip install h5py``, or the ``quflow`` extra of this
package); nothing else here imports it.

>>> round(hbar(8), 12)                      # 2 / sqrt(63)
0.251976315339
>>> round(rate_per_qtime(0.183823, 8), 6)   # a growth rate per unit t, per qtime step
0.046319
>>> ind2elm(elm2ind(3, -2))
(3, -2)
>>> harmonics([0.5, 0.0, 0.25, 0.0])        # l = 0 (the mean) is dropped
[[1, 0, 0.25]]
"""

from __future__ import annotations

import datetime
import math
import os
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Union

import numpy as np

__all__ = [
    "QuflowState",
    "elm2ind",
    "harmonics",
    "hbar",
    "ind2elm",
    "omega_from_harmonics",
    "rate_per_qtime",
    "read",
    "write",
    "zeitlin_spec",
]

PathLike = Union[str, "os.PathLike[str]"]

#: The quflow version whose conventions the files written here follow
#: (quflow's ``version`` attribute; the scaling of ``T_lm`` and of ``time``
#: is the one quflow has used since December 2023).
QUFLOW_VERSION = "0.1.0"


def hbar(N: int) -> float:
    """quflow's ``hbar = 2 / sqrt(N^2 - 1)``."""
    N = _check_n(N, "N")
    return 2.0 / math.sqrt(N * N - 1)


def rate_per_qtime(rate: float, N: int) -> float:
    """A rate per unit ``t`` (the engine's time) as a rate per unit of
    quflow's ``qtime = t / hbar``: ``rate * hbar``."""
    return rate * hbar(N)


def elm2ind(l: int, m: int) -> int:
    """quflow's index of ``(l, m)`` in ``omega``: ``l^2 + l + m``."""
    if l < 0 or abs(m) > l:
        raise ValueError(f"(l, m) = ({l}, {m}): need l >= 0 and |m| <= l")
    return l * l + l + m


def ind2elm(index: int) -> tuple:
    """The ``(l, m)`` of index ``l^2 + l + m``."""
    if index < 0:
        raise ValueError(f"index {index} is negative")
    l = math.isqrt(index)
    return l, index - l * (l + 1)


def harmonics(omega: Sequence[float]) -> List[list]:
    """The spec's ``[[l, m, value], ...]`` of quflow's ``omega`` (length
    ``N^2``): every nonzero coefficient with ``l >= 1`` (``l = 0`` is the
    mean, a multiple of the identity, which the engine's su(N) drops)."""
    omega = _omega_vector(omega, "omega")
    out = []
    for index, value in enumerate(omega):
        l, m = ind2elm(index)
        if l >= 1 and value != 0.0:
            out.append([l, m, float(value)])
    return out


def omega_from_harmonics(entries: Sequence[Sequence[float]], N: int) -> np.ndarray:
    """quflow's ``omega`` (length ``N^2``) of the spec's
    ``[[l, m, value], ...]``; repeated ``(l, m)`` add up, as in the spec."""
    N = _check_n(N, "N")
    omega = np.zeros(N * N)
    for k, entry in enumerate(entries):
        if len(entry) != 3:
            raise ValueError(f"harmonics[{k}]: expected [l, m, value], got {entry!r}")
        l, m, value = entry
        if int(l) != l or int(m) != m or not 0 <= l <= N - 1 or abs(m) > l:
            raise ValueError(f"harmonics[{k}]: (l, m) = ({l}, {m}) is not a harmonic of N = {N} (0 <= l <= N - 1, |m| <= l)")
        if not math.isfinite(float(value)):
            raise ValueError(f"harmonics[{k}]: value {value!r} is not finite")
        omega[elm2ind(int(l), int(m))] += float(value)
    return omega


@dataclass(frozen=True)
class QuflowState:
    """One output step of a quflow file."""

    #: quflow's real spherical-harmonic coefficients, length ``N^2``.
    omega: np.ndarray
    N: int
    #: quflow's ``time``: ``t``, the engine's time.
    time: Optional[float]
    #: quflow's ``qtime = t / hbar``.
    qtime: Optional[float]
    #: The row read (from 0).
    step: int
    path: str


def read(path: PathLike, step: int = -1, *, datapath: str = "/") -> QuflowState:
    """The state at output ``step`` (from 0; negative counts from the end,
    ``-1`` the last) of a file quflow wrote with ``quflow.save`` or
    ``quflow.QuData``: the ``state`` dataset under ``datapath``, its
    ``time`` and ``qtime``, and the group's ``N``. Complex coefficients
    (``qtype`` ``"shc"``) are converted to quflow's real ones."""
    h5py = _h5py()
    path = os.fspath(path)
    with h5py.File(path, "r") as f:
        if datapath not in f:
            raise ValueError(f"{path}: no group {datapath!r}")
        group = f[datapath]
        if "state" not in group:
            found = ", ".join(sorted(group.keys())) or "nothing"
            hint = " (a quflow QuSimulation file: its `mat` dataset holds matrices; save them with numpy.save and give the spec {\"npy\": ...})" if "mat" in group else ""
            raise ValueError(f"{path}: no dataset `state` in {datapath!r} (found {found}){hint}")
        states = group["state"]
        if states.ndim != 2:
            raise ValueError(f"{path}: `state` has shape {states.shape}, expected (outputs, N^2)")
        rows, width = states.shape
        N = _n_of(group, width, path)
        if rows == 0:
            raise ValueError(f"{path}: `state` has no rows")
        if not isinstance(step, (int, np.integer)) or isinstance(step, bool):
            raise ValueError(f"step: expected an integer, got {step!r}")
        if not -rows <= step < rows:
            raise ValueError(f"step: {step} is out of range for {rows} outputs (0 to {rows - 1}, or -1 to -{rows})")
        row = int(step) % rows
        qtype = states.attrs.get("qtype", "shr")
        if isinstance(qtype, bytes):
            qtype = qtype.decode()
        data = np.asarray(states[row])
        if qtype == "shr":
            omega = np.asarray(data, dtype=float)
        elif qtype == "shc":
            omega = _shc_to_shr(np.asarray(data, dtype=complex), N)
        else:
            raise ValueError(f"{path}: `state` has qtype {qtype!r}; expected 'shr' or 'shc'")
        if not np.all(np.isfinite(omega)):
            raise ValueError(f"{path}: `state` row {row} has a value that is not finite")
        time = _entry(group, "time", row, rows, path)
        qtime = _entry(group, "qtime", row, rows, path)
    return QuflowState(omega=omega, N=N, time=time, qtime=qtime, step=row, path=path)


def zeitlin_spec(
    state: Union[PathLike, QuflowState, Sequence[float]],
    *,
    noise: Sequence[Any],
    step: int = -1,
    N: Optional[int] = None,
    name: Optional[str] = None,
    parameters: Optional[Dict[str, Any]] = None,
    stopping: Optional[Dict[str, Any]] = None,
    settings: Optional[Dict[str, Any]] = None,
) -> Dict[str, Any]:
    """A Zeitlin spec (a dict for :func:`energy_casimir.certify`) whose
    equilibrium is a quflow state: a file's output ``step`` (see
    :func:`read`), a :class:`QuflowState`, or an ``omega`` vector (then
    ``N`` is ``sqrt(len(omega))``).

    Each ``noise`` entry is a profile expression in ``z`` (a string, as in
    any Zeitlin spec), a dict passed through (``{"harmonics": ...}``,
    ``{"npy": ...}``), or quflow's ``omega`` of the noise's stream function
    (converted to harmonics)."""
    if isinstance(state, QuflowState):
        qs = state
    elif isinstance(state, (str, os.PathLike)):
        qs = read(state, step)
    else:
        omega = _omega_vector(state, "state")
        qs = QuflowState(omega=omega, N=math.isqrt(len(omega)), time=None, qtime=None, step=0, path="")
    if N is not None and N != qs.N:
        raise ValueError(f"N: {N} given, but the state has N = {qs.N}")
    fields = []
    for k, entry in enumerate(noise):
        if isinstance(entry, (str, dict)):
            fields.append(entry)
        else:
            omega = _omega_vector(entry, f"noise[{k}]")
            if len(omega) != qs.N * qs.N:
                raise ValueError(f"noise[{k}]: {len(omega)} coefficients, expected N^2 = {qs.N * qs.N}")
            fields.append({"harmonics": harmonics(omega)})
    equilibrium = harmonics(qs.omega)
    if not equilibrium:
        raise ValueError("state: every coefficient with l >= 1 is zero (the state is a multiple of the identity)")
    where = f" of {os.path.basename(qs.path)}, output {qs.step}" if qs.path else ""
    when = ""
    if qs.time is not None:
        when = f" at t = {qs.time!r}" + (f" (qtime {qs.qtime!r})" if qs.qtime is not None else "")
    spec: Dict[str, Any] = {
        "name": name or (f"quflow-{os.path.splitext(os.path.basename(qs.path))[0]}-step{qs.step}" if qs.path else f"quflow-n{qs.N}"),
        "description": f"The quflow state{where}{when}, N = {qs.N}, as quflow's real spherical harmonics (shr2mat).",
        "zeitlin": {"N": qs.N, "equilibrium": {"harmonics": equilibrium}, "noise": fields},
    }
    if parameters is not None:
        spec["parameters"] = dict(parameters)
    if stopping is not None:
        spec["stopping"] = dict(stopping)
    if settings is not None:
        spec["settings"] = dict(settings)
    return spec


def write(
    path: PathLike,
    omegas: Any,
    *,
    time: Optional[Sequence[float]] = None,
    qtime: Optional[Sequence[float]] = None,
    datapath: str = "/",
) -> None:
    """Append states to a quflow file in ``quflow.save``'s layout (created
    if missing): ``omegas`` is one ``omega`` (length ``N^2``) or rows of
    them, or harmonics lists ``[[l, m, value], ...]`` (then the file's
    ``N`` must exist). Give the times as ``time`` (``t``) or ``qtime``, one
    per row; without either, ``qtime`` counts on from the file's last in
    steps of 1, as quflow's ``save`` does. quflow reads the result with
    ``quflow.load`` or ``h5py`` (``quflow.shr2mat(f["state"][-1])``)."""
    h5py = _h5py()
    path = os.fspath(path)
    if time is not None and qtime is not None:
        raise ValueError("give time or qtime, not both")
    with h5py.File(path, "a") as f:
        group = f.require_group(datapath)
        existing_n = int(group.attrs["N"]) if "N" in group.attrs else None
        rows = _rows(omegas, existing_n)
        width = rows.shape[1]
        N = math.isqrt(width)
        if N * N != width or N < 2:
            raise ValueError(f"omegas: rows of {width} coefficients; expected N^2 with N >= 2")
        if existing_n is not None and existing_n != N:
            raise ValueError(f"{path}: the file has N = {existing_n}, the states N = {N}")
        count = rows.shape[0]
        now = datetime.datetime.now().isoformat()
        if "state" not in group:
            states = group.create_dataset("state", (0, width), dtype="f8", maxshape=(None, width), chunks=(1, width))
            states.attrs["qtype"] = "shr"
            group.create_dataset("qtime", (0,), dtype="f8", maxshape=(None,))
            group.create_dataset("time", (0,), dtype="f8", maxshape=(None,))
            group.attrs["N"] = np.int64(N)
            group.attrs["version"] = QUFLOW_VERSION
            group.attrs["created"] = now
        states = group["state"]
        if states.shape[1] != width:
            raise ValueError(f"{path}: `state` rows hold {states.shape[1]} coefficients, the states {width}")
        before = states.shape[0]
        qtimes = _times(time, qtime, count, N, group, before)
        for name in ("state", "qtime", "time"):
            group[name].resize(before + count, axis=0)
            group[name].attrs["modified"] = now
        states[before:, :] = rows
        group["qtime"][before:] = qtimes
        group["time"][before:] = qtimes * hbar(N)


def _h5py():
    try:
        import h5py
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("quflow files need h5py: pip install h5py (or energy-casimir[quflow])") from e
    return h5py


def _check_n(N: Any, what: str) -> int:
    if isinstance(N, bool) or int(N) != N or N < 2:
        raise ValueError(f"{what}: expected an integer N >= 2, got {N!r}")
    return int(N)


def _omega_vector(values: Any, what: str) -> np.ndarray:
    omega = np.asarray(values, dtype=float)
    if omega.ndim != 1:
        raise ValueError(f"{what}: expected one vector of N^2 coefficients, got shape {omega.shape}")
    n = math.isqrt(len(omega))
    if n * n != len(omega) or n < 1:
        raise ValueError(f"{what}: {len(omega)} coefficients is not N^2")
    if not np.all(np.isfinite(omega)):
        raise ValueError(f"{what}: a coefficient is not finite")
    return omega


def _n_of(group: Any, width: int, path: str) -> int:
    n = math.isqrt(width)
    if n * n != width:
        raise ValueError(f"{path}: `state` rows hold {width} coefficients, not N^2")
    if "N" in group.attrs:
        attr = int(group.attrs["N"])
        if attr != n:
            raise ValueError(f"{path}: the attribute N = {attr} does not match `state` rows of {width} = {n}^2 coefficients")
    if n < 2:
        raise ValueError(f"{path}: N = {n}; the engine needs N >= 2")
    return n


def _entry(group: Any, name: str, row: int, rows: int, path: str) -> Optional[float]:
    if name not in group:
        return None
    data = group[name]
    if data.ndim != 1 or data.shape[0] != rows:
        raise ValueError(f"{path}: `{name}` has shape {data.shape}, expected ({rows},) like `state`")
    return float(data[row])


def _shc_to_shr(c: np.ndarray, N: int) -> np.ndarray:
    # quflow's shc2shr: r_l0 = Re c_l0, r_{l,m} = sqrt(2) (-1)^m Re c_{l,m},
    # r_{l,-m} = sqrt(2) (-1)^m Im c_{l,m} (m > 0).
    r = np.zeros(N * N)
    for l in range(N):
        r[elm2ind(l, 0)] = c[elm2ind(l, 0)].real
        for m in range(1, l + 1):
            s = math.sqrt(2.0) * (-1.0) ** m
            r[elm2ind(l, m)] = s * c[elm2ind(l, m)].real
            r[elm2ind(l, -m)] = s * c[elm2ind(l, m)].imag
    return r


def _rows(omegas: Any, n: Optional[int]) -> np.ndarray:
    # Rows of three numbers are harmonics entries: no omega has 3 = N^2 entries.
    if isinstance(omegas, list) and omegas and isinstance(omegas[0], (list, tuple)) and len(omegas[0]) == 3:
        if n is None:
            raise ValueError("omegas: harmonics lists need the file's N (write an omega vector first)")
        return omega_from_harmonics(omegas, n)[None, :]
    rows = np.asarray(omegas, dtype=float)
    if rows.ndim == 1:
        rows = rows[None, :]
    if rows.ndim != 2:
        raise ValueError(f"omegas: expected omega vectors, got shape {rows.shape}")
    if not np.all(np.isfinite(rows)):
        raise ValueError("omegas: a coefficient is not finite")
    return rows


def _times(time: Any, qtime: Any, count: int, N: int, group: Any, before: int) -> np.ndarray:
    given = time if time is not None else qtime
    if given is None:
        start = float(group["qtime"][before - 1]) + 1.0 if before > 0 else 0.0
        return start + np.arange(count, dtype=float)
    values = np.atleast_1d(np.asarray(given, dtype=float))
    what = "time" if time is not None else "qtime"
    if values.shape != (count,):
        raise ValueError(f"{what}: {values.size} values for {count} states")
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{what}: a value is not finite")
    return values / hbar(N) if time is not None else values
