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

**Axes**: a certificate's ``frame.axis`` is in quflow's matrix frame
(that of ``quflow.geometry.rotate``): the direction of the ``l = 1``
coefficients ``(omega_11, omega_1-1, omega_10)`` of a state zonal about
it, with its largest component positive. A Zeitlin certificate's
``time.per_qtime`` gives its rates and stopping time per unit ``qtime``.

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

#: The largest N read: the engine's Zeitlin model goes to N = 4096 (fields
#: given by harmonics to 1024).
MAX_N = 4096


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
    (``qtype`` ``"shc"``) are converted to quflow's real ones. Files of
    quflow's scaling before December 2023 (``time`` not ``qtime * hbar``)
    are refused."""
    h5py = _h5py()
    path = os.fspath(path)
    if not isinstance(step, (int, np.integer)) or isinstance(step, bool):
        raise ValueError(f"step: expected an integer, got {step!r}")
    with _open(h5py, path, "r") as f:
        group = _group(h5py, f, datapath, path)
        if "state" not in group:
            found = ", ".join(sorted(group.keys())) or "nothing"
            hint = " (a quflow QuSimulation file: its `mat` dataset holds matrices; save them with numpy.save and give the spec {\"npy\": ...})" if "mat" in group else ""
            raise ValueError(f"{path}: no dataset `state` in {datapath!r} (found {found}){hint}")
        states = _dataset(h5py, group, "state", path)
        if states.ndim != 2:
            raise ValueError(f"{path}: `state` has shape {states.shape}, expected (outputs, N^2)")
        rows, width = states.shape
        N = _n_of(group, width, path)
        if rows == 0:
            raise ValueError(f"{path}: `state` has no rows")
        if not -rows <= step < rows:
            raise ValueError(f"step: {step} is out of range for {rows} outputs (0 to {rows - 1}, or -1 to -{rows})")
        row = int(step) % rows
        qtype = _qtype(states, path)
        data = np.asarray(states[row])
        omega = np.asarray(data, dtype=float) if qtype == "shr" else _shc_to_shr(np.asarray(data, dtype=complex), N)
        if not np.all(np.isfinite(omega)):
            raise ValueError(f"{path}: `state` row {row} has a value that is not finite")
        time = _entry(h5py, group, "time", row, rows, path)
        qtime = _entry(h5py, group, "qtime", row, rows, path)
    if time is not None and qtime is not None and not math.isclose(time, qtime * hbar(N), rel_tol=1e-9, abs_tol=0.0):
        raise ValueError(
            f"{path}: time {time!r} is not qtime * hbar = {qtime * hbar(N)!r} (hbar = 2/sqrt(N^2 - 1)): "
            "a file of quflow's scaling before December 2023 (its T_lm and time differ), which is not read"
        )
    return QuflowState(omega=omega, N=N, time=time, qtime=qtime, step=row, path=path)


def zeitlin_spec(
    state: Union[PathLike, QuflowState, Sequence[float]],
    *,
    noise: Sequence[Any],
    step: int = -1,
    datapath: str = "/",
    N: Optional[int] = None,
    name: Optional[str] = None,
    parameters: Optional[Dict[str, Any]] = None,
    stopping: Optional[Dict[str, Any]] = None,
    settings: Optional[Dict[str, Any]] = None,
) -> Dict[str, Any]:
    """A Zeitlin spec (a dict for :func:`energy_casimir.certify`) whose
    equilibrium is a quflow state: a file's output ``step`` under
    ``datapath`` (see :func:`read`), a :class:`QuflowState` (``step`` is
    then unused), or an ``omega`` vector (then ``N`` is
    ``sqrt(len(omega))``).

    Each ``noise`` entry is a profile expression in ``z`` (a string, as in
    any Zeitlin spec), a dict passed through (``{"harmonics": ...}``,
    ``{"npy": ...}``), or quflow's ``omega`` of the noise's stream function
    (converted to harmonics)."""
    if isinstance(state, QuflowState):
        qs = state
        if len(qs.omega) != qs.N * qs.N:
            raise ValueError(f"state: {len(qs.omega)} coefficients, but N = {qs.N} needs N^2 = {qs.N * qs.N}")
    elif isinstance(state, (str, os.PathLike)):
        qs = read(state, step, datapath=datapath)
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
    them, or harmonics ``[[l, m, value], ...]`` (then the file's ``N`` must
    exist). Give the times as ``time`` (``t``) or ``qtime``, one per row;
    without either, ``qtime`` counts on from the file's last in steps of 1,
    as quflow's ``save`` does. Everything is checked before the file is
    changed: a refused call leaves it as it was (and creates none). quflow
    reads the result with ``quflow.load`` or ``h5py``
    (``quflow.shr2mat(f["state"][-1])``)."""
    h5py = _h5py()
    path = os.fspath(path)
    if time is not None and qtime is not None:
        raise ValueError("give time or qtime, not both")
    existing_n, before, last_qtime = None, 0, None
    if os.path.exists(path):
        with _open(h5py, path, "r") as f:
            if datapath in f:
                existing_n, before, last_qtime = _appendable(h5py, _group(h5py, f, datapath, path), path)
    rows = _rows(omegas, existing_n)
    width = rows.shape[1]
    N = math.isqrt(width)
    if N * N != width or N < 2:
        raise ValueError(f"omegas: rows of {width} coefficients; expected N^2 with N >= 2")
    if existing_n is not None and existing_n != N:
        raise ValueError(f"{path}: the file has N = {existing_n}, the states N = {N}")
    count = rows.shape[0]
    if count == 0:
        raise ValueError("omegas: no states to write")
    qtimes, times = _times(time, qtime, count, N, last_qtime)
    now = datetime.datetime.now().isoformat()
    with _open(h5py, path, "a") as f:
        group = f.require_group(datapath)
        if "state" not in group:
            states = group.create_dataset("state", (0, width), dtype="f8", maxshape=(None, width), chunks=(1, width))
            states.attrs["qtype"] = "shr"
            group.create_dataset("qtime", (0,), dtype="f8", maxshape=(None,))
            group.create_dataset("time", (0,), dtype="f8", maxshape=(None,))
            group.attrs["N"] = np.int64(N)
            group.attrs["version"] = QUFLOW_VERSION
            group.attrs["created"] = now
        for name in ("state", "qtime", "time"):
            group[name].resize(before + count, axis=0)
            group[name].attrs["modified"] = now
        group["state"][before:, :] = rows
        group["qtime"][before:] = qtimes
        group["time"][before:] = times


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


def _open(h5py: Any, path: str, mode: str):
    try:
        return h5py.File(path, mode)
    except BlockingIOError as e:
        raise OSError(f"{path}: the file is locked (another process has it open): {e}") from e
    except OSError as e:
        if mode == "r" and not os.path.exists(path):
            raise FileNotFoundError(f"{path}: no such file") from e
        raise OSError(f"{path}: not an HDF5 file that can be opened ({e})") from e


def _group(h5py: Any, f: Any, datapath: str, path: str) -> Any:
    if datapath not in f:
        raise ValueError(f"{path}: no group {datapath!r}")
    group = f[datapath]
    if not isinstance(group, h5py.Group):
        raise ValueError(f"{path}: {datapath!r} is a dataset, not a group")
    return group


def _dataset(h5py: Any, group: Any, name: str, path: str) -> Any:
    data = group[name]
    if not isinstance(data, h5py.Dataset):
        raise ValueError(f"{path}: `{name}` is a group, not a dataset")
    return data


def _qtype(states: Any, path: str) -> str:
    qtype = states.attrs.get("qtype", None)
    if isinstance(qtype, bytes):
        qtype = qtype.decode()
    kind = states.dtype.kind
    if kind not in "fc":
        raise ValueError(f"{path}: `state` holds {states.dtype}, not real or complex numbers")
    expected = "shc" if kind == "c" else "shr"
    if qtype is None:
        return expected
    if qtype != expected:
        raise ValueError(f"{path}: `state` has qtype {qtype!r} but {'complex' if kind == 'c' else 'real'} values (qtype {expected!r} expected)")
    return qtype


def _n_of(group: Any, width: int, path: str) -> int:
    n = math.isqrt(width)
    if n * n != width:
        raise ValueError(f"{path}: `state` rows hold {width} coefficients, not N^2")
    if "N" in group.attrs:
        attr = np.asarray(group.attrs["N"])
        try:
            value = float(attr.reshape(-1)[0]) if attr.size == 1 else None
        except (TypeError, ValueError):
            value = None
        if value is None or not math.isfinite(value) or value != int(value):
            raise ValueError(f"{path}: the attribute N = {attr.tolist()!r} is not an integer")
        if int(value) != n:
            raise ValueError(f"{path}: the attribute N = {int(value)} does not match `state` rows of {width} = {n}^2 coefficients")
    if not 2 <= n <= MAX_N:
        raise ValueError(f"{path}: N = {n}; the engine's Zeitlin model takes 2 <= N <= {MAX_N}")
    return n


def _entry(h5py: Any, group: Any, name: str, row: int, rows: int, path: str) -> Optional[float]:
    if name not in group:
        return None
    data = _dataset(h5py, group, name, path)
    if data.ndim != 1 or data.shape[0] != rows:
        raise ValueError(f"{path}: `{name}` has shape {data.shape}, expected ({rows},) like `state`")
    if data.dtype.kind not in "fiu":
        raise ValueError(f"{path}: `{name}` holds {data.dtype}, not real numbers")
    value = float(data[row])
    if not math.isfinite(value):
        raise ValueError(f"{path}: `{name}` at output {row} is {value!r}, not finite")
    return value


def _appendable(h5py: Any, group: Any, path: str) -> tuple:
    """The file's ``N``, rows and last ``qtime``, after checking that rows can
    be appended to it in quflow.save's layout."""
    if "state" not in group:
        clash = [name for name in ("mat", "time", "qtime", "step") if name in group]
        if clash:
            raise ValueError(f"{path}: has {', '.join(clash)} but no `state` (a quflow QuSimulation file, or another layout): not written to")
        return None, 0, None
    states = _dataset(h5py, group, "state", path)
    if states.ndim != 2 or states.maxshape[0] is not None:
        raise ValueError(f"{path}: `state` has shape {states.shape} (maximum {states.maxshape}); rows cannot be appended")
    if _qtype(states, path) != "shr" or states.dtype != np.float64:
        raise ValueError(f"{path}: `state` holds {states.dtype} (qtype 'shc'); only real float64 rows ('shr') are appended")
    rows, width = states.shape
    n = _n_of(group, width, path)
    for name in ("qtime", "time"):
        if name not in group:
            raise ValueError(f"{path}: no dataset `{name}` beside `state`")
        data = _dataset(h5py, group, name, path)
        if data.ndim != 1 or data.shape[0] != rows or data.maxshape[0] is not None or data.chunks is None:
            raise ValueError(f"{path}: `{name}` has shape {data.shape} (maximum {data.maxshape}); expected a resizable ({rows},)")
    last = float(group["qtime"][rows - 1]) if rows > 0 else None
    return n, rows, last


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
    rows = np.asarray(omegas, dtype=float)
    # Rows of three numbers are harmonics entries: no omega has 3 = N^2 entries.
    if rows.ndim == 2 and rows.shape[1] == 3:
        if n is None:
            raise ValueError("omegas: harmonics need the file's N (write an omega vector first)")
        return omega_from_harmonics(rows.tolist(), n)[None, :]
    if rows.ndim == 1:
        rows = rows[None, :]
    if rows.ndim != 2:
        raise ValueError(f"omegas: expected omega vectors, got shape {rows.shape}")
    if not np.all(np.isfinite(rows)):
        raise ValueError("omegas: a coefficient is not finite")
    return rows


def _times(time: Any, qtime: Any, count: int, N: int, last_qtime: Optional[float]) -> tuple:
    """``(qtime, time)`` of the rows to write: the given times as given, the
    other ones converted; counted on from the file's last ``qtime`` when
    neither is given."""
    hb = hbar(N)
    if time is None and qtime is None:
        start = last_qtime + 1.0 if last_qtime is not None else 0.0
        qtimes = start + np.arange(count, dtype=float)
        times = qtimes * hb
        if (count > 1 and np.any(qtimes[1:] == qtimes[:-1])) or (last_qtime is not None and qtimes[0] == last_qtime):
            raise ValueError("qtime: counting on in steps of 1 from the file's last qtime no longer changes it (give the times)")
    else:
        what = "time" if time is not None else "qtime"
        values = np.atleast_1d(np.asarray(time if time is not None else qtime, dtype=float))
        if values.shape != (count,):
            raise ValueError(f"{what}: {values.size} values for {count} states")
        with np.errstate(over="ignore"):  # an overflow is refused below
            qtimes, times = (values / hb, values) if time is not None else (values, values * hb)
    if not (np.all(np.isfinite(qtimes)) and np.all(np.isfinite(times))):
        raise ValueError("time: a value (or its qtime = time / hbar) is not finite")
    return qtimes, times
