"""Certify the stability of stochastic Lie–Poisson equilibria from Python.

The stochastic energy–Casimir method (Arnaudon, Ganaba and Holm) as the
Rust engine ``verify`` implements it, called in-process: a spec (a dict, JSON
text or a path) in, a :class:`Certificate` out, and :func:`check` to re-verify
any certificate. The certificate is byte for byte what ``verify certify``
writes, so certificates made here pass ``verify check`` and the other way
round.

>>> import energy_casimir as ec
>>> cert = ec.certify({
...     "name": "rigid-body", "algebra": "so3",
...     "parameters": {"I1": 3, "I2": 2, "I3": 1, "sigma": "3/10"},
...     "hamiltonian": "Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3)",
...     "equilibrium": [1, 0, 0], "noise": [["sigma", 0, 0]]})
>>> cert.verdict, cert.level
('stable', 'exact')
>>> cert.sigma2_exact  # sigma^2 I1 (I2 - I3) / (I3 (I1 - I2)) = 0.09 * 3
Fraction(27, 100)
>>> round(cert.stopping_time(0.1, 0.001), 6)  # ln(100) / 0.27
17.056186
>>> ec.check(cert).verdict
'stable'
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

from . import _core
from ._core import CheckError, SpecError

__all__ = [
    "Certificate",
    "CheckError",
    "CheckReport",
    "SpecError",
    "certify",
    "check",
    "merge_shards",
    "simulate",
    "simulate_fluid",
    "simulate_zeitlin",
    "sweep",
    "to_xarray",
    "validate",
    "zeitlin_fields",
    "__version__",
]

__version__: str = _core.engine_version()

SpecLike = Union[Dict[str, Any], str, "os.PathLike[str]"]
ProgressLike = Union[None, bool, Callable[[int, int], Any]]


class _Progress:
    """What a ``progress=`` argument becomes: the callback the engine calls
    with ``(done, total)``, and ``close()`` for a bar it opened.

    ``progress`` may be ``None`` (nothing), a callable (called as is), or
    ``True``: a ``tqdm`` bar if tqdm is installed, else one line on
    standard error that is rewritten in place.
    """

    def __init__(self, progress: ProgressLike, desc: str) -> None:
        self._bar: Any = None
        self._desc = desc
        self._shown = False
        self.callback: Optional[Callable[[int, int], Any]] = None
        if progress is None or progress is False:
            return
        if progress is True:
            try:
                from tqdm.auto import tqdm
            except ImportError:
                self.callback = self._text
            else:
                self._bar = tqdm(total=0, desc=desc, unit="step")
                self.callback = self._tqdm
            return
        if not callable(progress):
            raise TypeError(f"progress: expected a callable, True or None, got {type(progress).__name__}")
        self.callback = progress

    def _tqdm(self, done: int, total: int) -> None:
        bar = self._bar
        if bar.total != total:
            bar.total = total
        bar.update(done - bar.n)

    def _text(self, done: int, total: int) -> None:
        import sys

        share = 100.0 * done / total if total else 100.0
        sys.stderr.write(f"\r{self._desc}: {done}/{total} steps ({share:.0f}%)")
        sys.stderr.flush()
        self._shown = True

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
        elif self._shown:
            import sys

            sys.stderr.write("\n")
            sys.stderr.flush()

    def __enter__(self) -> "_Progress":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _json_default(obj: Any) -> Any:
    """Spec values json cannot write: Fractions as exact ``"p/q"`` strings,
    numpy arrays and scalars as lists and numbers."""
    if isinstance(obj, Fraction):
        return f"{obj.numerator}/{obj.denominator}"
    if hasattr(obj, "tolist"):
        return obj.tolist()
    raise TypeError(f"a spec value of type {type(obj).__name__} cannot be written as JSON")


def _read_input(obj: Any, what: str, base_dir: Optional[Union[str, "os.PathLike[str]"]]):
    """``(json_text, base_folder)`` for a dict, JSON text or a path."""
    if isinstance(obj, dict):
        try:
            return json.dumps(obj, allow_nan=False, default=_json_default), base_dir
        except ValueError as e:
            raise ValueError(f"{what}: the spec holds a NaN or an infinity, which JSON cannot carry ({e})") from None
    if isinstance(obj, str) and not obj.strip():
        raise ValueError(f"{what}: an empty string is neither JSON text nor a path")
    if isinstance(obj, os.PathLike) or (isinstance(obj, str) and not obj.lstrip().startswith(("{", "["))):
        path = Path(obj)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as e:
            # The same kind of error (FileNotFoundError, IsADirectoryError,
            # PermissionError...), with what was being read.
            raise type(e)(e.errno, f"{what}: cannot read {str(path)[:200]!r}: {e.strerror or e}") from e
        return text, base_dir if base_dir is not None else path.parent
    if isinstance(obj, str):
        return obj, base_dir
    raise TypeError(f"{what}: expected a dict, JSON text or a path, got {type(obj).__name__}")


def _base(base: Any) -> Optional[str]:
    return None if base is None else os.fspath(base)


def _rational(text: Any) -> Fraction:
    return Fraction(str(text))


def _float_up(q: Fraction) -> float:
    """The least double at or above ``q`` (``float(q)`` rounds to nearest)."""
    f = float(q)
    if Fraction(f) < q:
        f = math.nextafter(f, math.inf)
    return f


def _matrix(rows: Any):
    import numpy as np

    if rows is None:
        return None
    return np.array([[float(_rational(x)) for x in row] for row in rows], dtype=float).reshape(len(rows), -1)


class Certificate:
    """A certificate: the engine's claim about one spec, with its evidence.

    Attributes mirror the certificate's JSON fields (``to_dict()`` gives all
    of them). Matrices (``P``, ``Q``) are numpy arrays of the nearest doubles
    to the exact rationals the certificate states; ``P_exact`` and
    ``Q_exact`` keep them as :class:`fractions.Fraction`.
    """

    def __init__(self, data: Dict[str, Any], text: Optional[str] = None, base_dir: Optional[str] = None):
        if not isinstance(data, dict) or "verdict" not in data:
            raise TypeError("Certificate: expected a certificate (a dict with a 'verdict')")
        self._data = data
        self._text = text
        self._base_dir = base_dir

    # The claim.
    @property
    def name(self) -> str:
        """The spec's name."""
        return self._data.get("name", "")

    @property
    def verdict(self) -> str:
        """``stable``, ``linearly_unstable``, ``inconclusive``, ``not_an_equilibrium`` or ``noise_incompatible``;
        a box certificate's also ``partly_stable``, ``partly_unstable``, ``partly_not_an_equilibrium``,
        ``partly_noise_incompatible`` or ``undecided`` (docs/boxes.md)."""
        return self._data["verdict"]

    @property
    def reason(self) -> str:
        """One sentence explaining the verdict."""
        return self._data.get("reason", "")

    @property
    def theorem(self) -> str:
        """What the certificate claims, in its own words (generated from its data and re-derived by
        ``check``): which linearised SDE, which norm, the bound and its Markov corollary."""
        return self._data.get("theorem", {}).get("statement", "")

    @property
    def not_checked(self) -> str:
        """What the certificate does not check (the nonlinear system; for fluids, the PDE)."""
        return self._data.get("theorem", {}).get("not_checked", "")

    @property
    def level(self) -> Optional[str]:
        """How the claim is established: ``exact``, ``verified_float``, ``exact_structure``, ``float`` or ``numerical`` (``None``: no claim)."""
        return self._data.get("level")

    @property
    def kind(self) -> str:
        """``finite`` (a Lie–Poisson system), ``fluid``, ``zeitlin``, ``large`` or ``box``."""
        return self._data.get("kind", "finite")

    @property
    def sigma2(self) -> Optional[float]:
        """The growth constant ``Sigma^2`` (when stable)."""
        s = self._data.get("sigma2")
        return None if s is None else float(s)

    @property
    def sigma2_exact(self) -> Optional[Fraction]:
        """``Sigma^2`` as the exact rational the certificate proves (level ``exact``)."""
        s = self._data.get("sigma2_exact")
        return None if s is None else _rational(s)

    @property
    def sigma2_upper(self) -> Optional[float]:
        """A proved upper bound on ``Sigma^2`` (level ``verified_float``)."""
        s = self._data.get("sigma2_upper")
        return None if s is None else float(s)

    @property
    def sigma2_bound(self) -> Optional[float]:
        """The ``Sigma^2`` a guarantee is computed from: the exact value rounded up, else the proved upper bound, else the estimate."""
        if self.sigma2_exact is not None:
            return _float_up(self.sigma2_exact)
        if self.sigma2_upper is not None:
            return self.sigma2_upper
        return self.sigma2

    def stopping_time(self, epsilon: float, delta: float) -> float:
        """``T(eps, delta) = ln(eps/delta) / Sigma^2`` for ``eps > delta > 0``:
        ``P(|dmu_t|^2 > eps) <= (delta/eps) e^{Sigma^2 t}`` stays below 1 up to
        ``T`` (``math.inf`` when ``Sigma^2 = 0``). Rounded down, from
        :attr:`sigma2_bound`.

        >>> import energy_casimir as ec
        >>> c = ec.certify("fixtures/rigid-body-major-axis.json")
        >>> c.stopping_time(0.1, 0.001) <= math.log(100) / 0.27
        True
        """
        epsilon, delta = float(epsilon), float(delta)
        if not (math.isfinite(epsilon) and math.isfinite(delta) and epsilon > delta > 0):
            raise ValueError(f"stopping_time: need eps > delta > 0, got eps = {epsilon!r}, delta = {delta!r}")
        s = self.sigma2_bound
        if self.verdict != "stable" or s is None:
            raise ValueError(f"stopping_time: the verdict is {self.verdict!r}, not 'stable': no stopping time is certified")
        t = _core.stopping_time(epsilon, delta, s)
        return math.inf if t is None else t

    @property
    def growth_rate(self) -> Optional[float]:
        """The real part of the unstable eigenvalue of the linearised drift
        (``linearly_unstable``): of a finite-dimensional system, of a fluid's
        fastest x-mode (``instability.growth_rate``), or of a Zeitlin
        state (``growth_rate``, per unit of quflow's ``t``)."""
        inst = self._data.get("instability")
        if isinstance(inst, dict) and isinstance(inst.get("eigenvalue"), dict):
            return float(inst["eigenvalue"]["re"])
        if isinstance(inst, dict) and isinstance(inst.get("growth_rate"), (int, float)):
            return float(inst["growth_rate"])
        if isinstance(self._data.get("growth_rate"), (int, float)):
            return float(self._data["growth_rate"])
        return None

    # The evidence.
    @property
    def P(self):
        """The conserved quadratic form ``P`` (numpy array), when the certificate states it."""
        return _matrix(self._data.get("P"))

    @property
    def Q(self):
        """The generator's form ``Q`` with ``L(x^T P x) = x^T Q x`` (numpy array), when stated."""
        return _matrix(self._data.get("Q"))

    @property
    def P_exact(self) -> Optional[List[List[Fraction]]]:
        """``P`` as exact rationals."""
        rows = self._data.get("P")
        return None if rows is None else [[_rational(x) for x in row] for row in rows]

    @property
    def Q_exact(self) -> Optional[List[List[Fraction]]]:
        """``Q`` as exact rationals."""
        rows = self._data.get("Q")
        return None if rows is None else [[_rational(x) for x in row] for row in rows]

    @property
    def casimir_choice(self) -> Optional[Dict[str, Any]]:
        """The Casimir choice: the multipliers and the Casimir Hessian ``M`` (rational strings)."""
        return self._data.get("casimir_choice")

    @property
    def multipliers(self) -> Optional[List[Fraction]]:
        """The multipliers of the conserved quantities, exactly."""
        m = (self.casimir_choice or {}).get("multipliers")
        return None if m is None else [_rational(x) for x in m]

    @property
    def stopping(self) -> Optional[Dict[str, Any]]:
        """The stopping-time record for the spec's ``stopping`` section."""
        return self._data.get("stopping")

    def to_dict(self) -> Dict[str, Any]:
        """The certificate's JSON as a dict (a deep copy)."""
        return json.loads(self.to_json())

    def to_json(self) -> str:
        """The certificate as JSON text, exactly as ``verify certify`` writes it."""
        if self._text is None:
            self._text = json.dumps(self._data, indent=2)
        return self._text

    def save(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Write the certificate to ``path`` (for ``verify check``)."""
        Path(path).write_text(self.to_json(), encoding="utf-8")

    def check(self) -> "CheckReport":
        """Re-verify this certificate (:func:`check`)."""
        return check(self)

    def __getitem__(self, key: str) -> Any:
        return self._data[key]

    def __repr__(self) -> str:
        s2 = "" if self.sigma2 is None else f", sigma2={self.sigma2!r}"
        return f"Certificate(name={self.name!r}, verdict={self.verdict!r}, level={self.level!r}{s2})"


@dataclass(frozen=True)
class CheckReport:
    """What a successful :func:`check` established."""

    name: str
    verdict: str
    level: Optional[str]
    sigma2: Optional[float]


def certify(
    spec: SpecLike,
    *,
    base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
    progress: ProgressLike = None,
) -> Certificate:
    """Certify a spec: a dict, JSON text, or the path of a spec file.

    The spec format is the engine's (README, ``schema/``): finite-dimensional
    Lie–Poisson systems, fluids (``"fluid"``), the Zeitlin model
    (``"zeitlin"``) and large systems. Files a spec names (a Zeitlin
    ``.npy`` field) are read relative to ``base_dir``, by default the spec
    file's folder (the current folder for a dict or text).

    Raises :class:`SpecError` (``.path``, ``.message``) for invalid input.
    The GIL is released while the engine works. Fluid, Zeitlin and large
    specs can take seconds to minutes: Ctrl-C stops them
    (``KeyboardInterrupt``; the engine stops at its next step), and
    ``progress`` reports them: a callable gets ``(done, total)`` about ten
    times a second, ``True`` draws a tqdm bar if tqdm is installed (else a
    line on standard error). Steps are x-mode solves for fluids, block
    operations for the Zeitlin model and stages for large systems; a
    search has a budget, so the count may jump at its end or wait at the
    budget's end while it runs long (``docs/python.md``).

    >>> import energy_casimir as ec
    >>> ec.certify("fixtures/rigid-body-intermediate-axis.json").verdict
    'linearly_unstable'
    >>> try:
    ...     ec.certify({"name": "x", "algebra": "so3", "hamiltonian": "Pi1^2",
    ...                 "equilibrium": [1, 0], "noise": []})
    ... except ec.SpecError as e:
    ...     print(e.path)
    $.equilibrium
    """
    text, base = _read_input(spec, "certify", base_dir)
    with _Progress(progress, "certify") as p:
        out = _core.certify_text(text, _base(base), progress=p.callback)
    return Certificate(json.loads(out), out, _base(base))


def validate(spec: SpecLike, *, base_dir: Optional[Union[str, "os.PathLike[str]"]] = None) -> None:
    """Parse a spec without certifying it; raises :class:`SpecError` if it is invalid."""
    text, base = _read_input(spec, "validate", base_dir)
    _core.validate_text(text, _base(base))


def check(
    certificate: Union[Certificate, Dict[str, Any], str, "os.PathLike[str]"],
    *,
    base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
    progress: ProgressLike = None,
) -> CheckReport:
    """Re-verify a certificate (a :class:`Certificate`, a dict, JSON text or a path).

    The engine re-derives everything from the embedded spec and trusts no
    stored number. Raises :class:`CheckError` with ``.path`` (the first field
    that fails), ``.message`` and ``.kind`` (``"failed"`` or ``"bad_input"``).
    Ctrl-C stops a long re-derivation; ``progress`` as in :func:`certify`.

    >>> import energy_casimir as ec
    >>> d = ec.certify("fixtures/rigid-body-major-axis.json").to_dict()
    >>> d["sigma2"] = 0.26
    >>> try:
    ...     ec.check(d)
    ... except ec.CheckError as e:
    ...     print(e.kind, e.path)
    failed $.sigma2
    """
    if isinstance(certificate, Certificate):
        text, base = certificate.to_json(), base_dir if base_dir is not None else certificate._base_dir
    else:
        text, base = _read_input(certificate, "check", base_dir)
    with _Progress(progress, "check") as p:
        name, verdict, level, sigma2 = _core.check_text(text, _base(base), progress=p.callback)
    return CheckReport(name=name, verdict=verdict, level=level, sigma2=sigma2)


def _arrays(obj: Any) -> Any:
    """Numbers and lists of numbers as numpy arrays, recursively in dicts."""
    import numpy as np

    if isinstance(obj, dict):
        return {k: _arrays(v) for k, v in obj.items()}
    if isinstance(obj, list) and obj and not any(isinstance(x, (dict, str)) for x in obj):
        try:
            return np.asarray(obj, dtype=float)
        except (TypeError, ValueError):
            return obj
    if isinstance(obj, list):
        return [_arrays(x) for x in obj]
    return obj


def simulate(
    spec: SpecLike,
    *,
    paths: int = 10_000,
    dt: float = 0.01,
    t_end: Optional[float] = None,
    seed: int = 1,
    outputs: int = 200,
    bins: int = 80,
    scheme: str = "lie",
    observable: Optional[str] = None,
    epsilon: Optional[float] = None,
    delta: Optional[float] = None,
    force: bool = False,
    progress: ProgressLike = None,
    base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
    shard: Optional[Union[str, Tuple[int, int]]] = None,
) -> Dict[str, Any]:
    """Monte Carlo of the stochastic system next to what the certificate claims.

    The study of ``verify simulate`` (same defaults), in-process: the
    nonlinear SDE from ``mu_e + sqrt(delta) v`` (``v`` the fastest-growing
    direction of a stable equilibrium), the linearised SDE, its exact second
    moments ``E|x_t|_P^2 / delta``, the worst start and the bound
    ``exp(Sigma^2 t)``. Returns the report as a dict whose series are numpy
    arrays: ``report["nonlinear"]["times"]``, ``["mean"]`` (times x
    coordinates), ``["norm_mean_over_delta"]``, ``["norm_std_error_over_delta"]``,
    ``["exceedance"]``; ``report["exact_moments_over_delta"]``,
    ``report["bound_over_delta"]``, ``report["histogram"]["counts"]`` (times x
    bins) and ``["range"]``; ``report["exceedance"]`` per level.

    ``t_end`` defaults to ``8 T(eps, delta)`` kept within ``[1, 200]``. A
    study estimated above 15 minutes is refused unless ``force=True``.
    Raises :class:`SpecError` for an invalid spec, ``ValueError`` for
    invalid settings. The GIL is released while it runs; Ctrl-C stops it
    (``KeyboardInterrupt``, after the blocks of 256 paths in flight), and
    ``progress(done, total)`` counts paths (both ensembles), called about
    ten times a second from the calling thread (``True``: a tqdm bar, as
    in :func:`certify`).

    ``shard=(k, n)`` (or ``"k/n"``) runs only shard ``k`` of ``n`` (a share
    of the paths of each ensemble, as ``verify simulate --shard k/n``, for a
    job array) and returns its shard file as a dict, the JSON the CLI
    writes: save it with ``json.dump`` and merge all ``n`` with
    :func:`merge_shards` (or ``verify simulate --merge``). The estimate that
    refuses long runs counts the shard's share.

    >>> import energy_casimir as ec
    >>> r = ec.simulate("fixtures/rigid-body-major-axis.json", paths=200, t_end=2.0)
    >>> float(r["nonlinear"]["times"][-1]), r["sigma2"]
    (2.0, 0.27)
    >>> bool((r["exact_moments_over_delta"] <= r["bound_over_delta"] * (1 + 1e-12)).all())
    True
    """
    text, base = _read_input(spec, "simulate", base_dir)
    shard_pair = None if shard is None else _shard_pair(shard)
    with _Progress(progress, "simulate") as p:
        out = _simulate(
            text, base, p.callback, paths, dt, t_end, outputs, seed, bins, scheme, observable, epsilon, delta, force, shard=shard_pair
        )
    if shard_pair is not None:
        return json.loads(out)
    return _arrays(json.loads(out))


def _shard_pair(shard: Any) -> Tuple[int, int]:
    """``(k, n)`` from ``(k, n)`` or ``"k/n"``."""
    try:
        if isinstance(shard, str):
            k_text, n_text = shard.split("/")
            k, n = int(k_text), int(n_text)
        else:
            k, n = shard
            if isinstance(k, bool) or isinstance(n, bool) or int(k) != k or int(n) != n:
                raise ValueError
            k, n = int(k), int(n)
    except (TypeError, ValueError):
        raise ValueError(f"shard: expected (k, n) or 'k/n' with 0 <= k < n, got {shard!r}") from None
    if not 0 <= k < n:
        raise ValueError(f"shard: expected 0 <= k < n, got ({k}, {n})")
    return k, n


def merge_shards(
    spec: SpecLike,
    shards: Sequence[Union[str, "os.PathLike[str]", Mapping[str, Any]]],
    *,
    paths: int = 10_000,
    dt: float = 0.01,
    t_end: Optional[float] = None,
    seed: int = 1,
    outputs: int = 200,
    bins: int = 80,
    scheme: str = "lie",
    observable: Optional[str] = None,
    epsilon: Optional[float] = None,
    delta: Optional[float] = None,
    base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
) -> Dict[str, Any]:
    """Merge the shards of a study into the report an unsharded run gives.

    ``shards`` are shard files (paths, as ``verify simulate --shard``
    writes them) or the dicts :func:`simulate` returns with ``shard=``,
    all ``n`` of one split; the options are those the shards ran with.
    The merge is exact (the shards hold exact sums): the report equals
    :func:`simulate`'s without ``shard``, number for number. Shards of
    another spec or other options, of another engine version, two
    different shards with one index, or a missing shard raise
    ``ValueError`` naming the file and the field.

    >>> import energy_casimir as ec
    >>> spec = "fixtures/rigid-body-major-axis.json"
    >>> parts = [ec.simulate(spec, paths=600, t_end=1.0, outputs=20, shard=(k, 3)) for k in range(3)]
    >>> merged = ec.merge_shards(spec, parts, paths=600, t_end=1.0, outputs=20)
    >>> whole = ec.simulate(spec, paths=600, t_end=1.0, outputs=20)
    >>> bool((merged["nonlinear"]["norm_mean_over_delta"] == whole["nonlinear"]["norm_mean_over_delta"]).all())
    True
    """
    if isinstance(shards, (str, bytes, os.PathLike, Mapping)):
        raise TypeError("shards: expected a list of shard files or dicts, got one")
    text, base = _read_input(spec, "merge_shards", base_dir)
    documents = []
    for i, shard in enumerate(shards):
        if isinstance(shard, Mapping):
            documents.append((f"shards[{i}]", json.dumps(shard, default=_json_default)))
        elif isinstance(shard, (str, os.PathLike)):
            path = os.fspath(shard)
            with open(path, encoding="utf-8") as f:
                documents.append((path, f.read()))
        else:
            raise TypeError(f"shards[{i}]: expected a path or a dict, got {type(shard).__name__}")
    if not documents:
        raise ValueError("shards: no shard files")
    out = _core.simulate_text(
        text,
        _base(base),
        paths=int(paths),
        dt=float(dt),
        t_end=None if t_end is None else float(t_end),
        outputs=int(outputs),
        seed=int(seed),
        bins=int(bins),
        scheme=str(scheme),
        observable=observable,
        epsilon=None if epsilon is None else float(epsilon),
        delta=None if delta is None else float(delta),
        merge=documents,
    )
    return _arrays(json.loads(out))


def _simulate(
    text: str,
    base: Any,
    progress: Optional[Callable[[int, int], Any]],
    paths: int,
    dt: float,
    t_end: Optional[float],
    outputs: int,
    seed: int,
    bins: int,
    scheme: str,
    observable: Optional[str],
    epsilon: Optional[float],
    delta: Optional[float],
    force: bool,
    shard: Optional[Tuple[int, int]] = None,
) -> str:
    return _core.simulate_text(
        text,
        _base(base),
        paths=int(paths),
        dt=float(dt),
        t_end=None if t_end is None else float(t_end),
        outputs=int(outputs),
        seed=int(seed),
        bins=int(bins),
        scheme=str(scheme),
        observable=observable,
        epsilon=None if epsilon is None else float(epsilon),
        delta=None if delta is None else float(delta),
        force=bool(force),
        progress=progress,
        shard=shard,
    )


def simulate_fluid(
    spec: SpecLike,
    *,
    mode: Optional[int] = None,
    ny: Optional[int] = None,
    paths: Optional[int] = None,
    dt: float = 0.01,
    t_end: Optional[float] = None,
    outputs: int = 200,
    seed: int = 1,
    force: bool = False,
    base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
    progress: ProgressLike = None,
) -> Dict[str, Any]:
    """One x-mode of a fluid spec's discretised linear SDE beside its certified growth.

    What ``verify simulate FLUID-SPEC`` runs (same defaults,
    docs/simulation.md "Fluid specs"): the analysis again on the simulation's
    grid ``ny`` (default the spec's, at most 32; 16 for the compressible
    model), the mode ``mode`` (default the largest certified growth; the
    gravest for the compressible model) started from the direction whose
    ``E V`` grows fastest, a Monte Carlo of ``paths`` paths (default 1000)
    and the exact second moment. Returns the report as a dict whose series
    are numpy arrays: ``times``, ``monte_carlo_mean`` and
    ``monte_carlo_std_error`` (of ``E V(t) / V(0)``), ``exact``,
    ``certified_bound`` (``exp(Sigma_k^2 t)``), ``initial_rate_bound``;
    ``sigma2_mode`` (the certified ``Sigma_k^2`` on that grid), ``summary``
    and ``notes``. A Monte Carlo estimated above 15 minutes is refused, and
    an exact moment above 2 minutes skipped, unless ``force=True``. Raises
    :class:`SpecError` for an invalid spec, ``ValueError`` for invalid
    settings or a spec without certified growth. Ctrl-C stops a run
    (``KeyboardInterrupt``); ``progress`` as in :func:`certify` (the count
    is planned once, when the Monte Carlo and the exact moment start, in
    thousands of flops; it is ``(0, 0)`` during the analysis on the grid).

    >>> import energy_casimir as ec
    >>> r = ec.simulate_fluid("fixtures/fluids/arnold-boundary-sin.json", ny=16, paths=100, t_end=1.0, outputs=4)
    >>> r["m"], r["ny"], round(r["sigma2_mode"], 4)
    (1, 16, 0.2626)
    >>> bool((r["exact"] <= r["certified_bound"] * (1 + 1e-9)).all())
    True
    """
    text, base = _read_input(spec, "simulate_fluid", base_dir)
    with _Progress(progress, "simulate_fluid") as p:
        out = _core.simulate_fluid_text(
            text,
            _base(base),
            mode=None if mode is None else int(mode),
            ny=None if ny is None else int(ny),
            paths=None if paths is None else int(paths),
            dt=float(dt),
            t_end=None if t_end is None else float(t_end),
            outputs=int(outputs),
            seed=int(seed),
            force=bool(force),
            progress=p.callback,
        )
    return _arrays(json.loads(out))


def simulate_zeitlin(
    spec: SpecLike,
    *,
    block: Optional[int] = None,
    paths: Optional[int] = None,
    dt: float = 0.01,
    t_end: Optional[float] = None,
    outputs: int = 200,
    seed: int = 1,
    force: bool = False,
    delta: Optional[float] = None,
    base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
    progress: ProgressLike = None,
) -> Dict[str, Any]:
    """One block of a Zeitlin spec's linearised SDE beside its certified bound.

    What ``verify simulate ZEITLIN-SPEC`` runs (same defaults,
    docs/simulation.md "Zeitlin specs"): for a state zonal in some frame and
    certified ``stable``, the perturbation's entries on the diagonal
    ``block`` (the azimuthal wavenumber ``m``; default the largest
    ``lambda_max(Q_m, P_m)``) evolve by themselves; started from the
    direction whose ``E|z|_P^2`` grows fastest, a Monte Carlo of ``paths``
    paths (default 1000) and the scheme's exact second moment give
    ``E|z_t|_P^2 / |z_0|_P^2``. Returns the report as a dict whose series
    are numpy arrays: ``times`` (the model's ``t``, quflow's) and
    ``times_qtime`` (``t / hbar``), ``monte_carlo_mean``,
    ``monte_carlo_std_error``, ``exact``, ``certified_bound``
    (``exp(sigma2_upper t)``, proved) and ``block_bound``
    (``exp(lambda_max t)`` of the block); ``nonlinear``: a tenth as many
    paths (at least 2) of the nonlinear stochastic Zeitlin model
    (isospectral midpoint) from ``W_e + sqrt(delta) X`` on the same Brownian
    increments (``delta`` default 1e-6), its ``mean`` and ``std_error`` of
    ``E|W_t - W_e|_P^2 / delta`` and its ``casimir_drift`` (None above N =
    64); ``summary`` and ``notes``.
    ``t_end=None`` is one growth time ``1 / lambda_max`` kept to about 2
    minutes of computation. A Monte Carlo estimated above 15 minutes is
    refused, and an exact moment above 2 minutes skipped, unless
    ``force=True``. Raises :class:`SpecError` for an invalid spec and
    ``ValueError`` for invalid settings or a certificate with nothing to
    compare (not stable, or zonal in no frame). Ctrl-C stops a run;
    ``progress`` as in :func:`certify`.

    >>> import energy_casimir as ec
    >>> spec = {"name": "z", "zeitlin": {"N": 8, "equilibrium": "z + 0.3*z^3", "noise": ["3*z^2"]},
    ...         "settings": {"casimir_momentum": False}}
    >>> r = ec.simulate_zeitlin(spec, paths=200, t_end=1.0, outputs=4)
    >>> r["kind"], r["block"], bool((r["exact"] <= r["certified_bound"] * (1 + 1e-6)).all())
    ('zeitlin-simulation', 1, True)
    >>> r["nonlinear"]["paths"], bool(r["nonlinear"]["casimir_drift"] < 1e-12)
    (20, True)
    """
    text, base = _read_input(spec, "simulate_zeitlin", base_dir)
    with _Progress(progress, "simulate_zeitlin") as p:
        out = _core.simulate_zeitlin_text(
            text,
            _base(base),
            block=None if block is None else int(block),
            paths=None if paths is None else int(paths),
            dt=float(dt),
            t_end=None if t_end is None else float(t_end),
            outputs=int(outputs),
            seed=int(seed),
            force=bool(force),
            progress=p.callback,
            delta=None if delta is None else float(delta),
        )
    return _arrays(json.loads(out))


def zeitlin_fields(spec: SpecLike, *, base_dir: Optional[Union[str, "os.PathLike[str]"]] = None) -> Dict[str, Any]:
    """A Zeitlin spec's fields as quflow's ``omega`` vectors (real
    spherical-harmonic coefficients at index ``l^2 + l + m``, length
    ``N^2``), ready for :func:`energy_casimir.quflow.write`.

    Returns ``{"N", "state", "noise": [...], "mode"}``: the equilibrium as
    the engine reads it (a profile quantised, harmonics or a ``.npy`` matrix
    as given), each noise field's stream matrix, and for a state zonal in
    some frame the perturbation its certificate is about, in the spec's own
    frame: ``mode["kind"]`` is ``"unstable_eigenvector"`` (the
    fastest-growing eigenvector of a linearly unstable state: the linearised
    drift maps ``real`` to ``rate real + frequency imaginary``) or
    ``"fastest_growing_start"`` (a stable state's start whose ``E|dW|_P^2``
    grows at ``Sigma^2``, ``rate``); ``block`` is its azimuthal wavenumber
    in the zonal frame. ``mode`` is None otherwise. N at most 256.

    >>> import energy_casimir as ec
    >>> f = ec.zeitlin_fields("fixtures/zeitlin/jet-n64.json")
    >>> f["N"], f["state"].shape, f["mode"]["kind"], round(f["mode"]["rate"], 6)
    (64, (4096,), 'unstable_eigenvector', 0.140955)
    """
    text, base = _read_input(spec, "zeitlin_fields", base_dir)
    return _arrays(json.loads(_core.zeitlin_fields_text(text, _base(base))))


def _range_text(name: str, r: Any) -> str:
    """``NAME=START:STOP:COUNT`` from ``(start, stop, count)`` or a string."""
    if isinstance(r, str):
        return f"{name}={r}"
    try:
        start, stop, count = r
    except (TypeError, ValueError):
        raise ValueError(f"params[{name!r}]: expected (start, stop, count) or 'START:STOP:COUNT', got {r!r}") from None

    def number(x: Any) -> str:
        if isinstance(x, Fraction):
            return f"{x.numerator}/{x.denominator}"
        if isinstance(x, float) and not math.isfinite(x):
            raise ValueError(f"params[{name!r}]: {x!r} is not a finite number")
        return str(x)

    if isinstance(count, bool) or not float(count).is_integer() or int(count) < 1:
        raise ValueError(f"params[{name!r}]: the count must be a positive integer, got {count!r}")
    return f"{name}={number(start)}:{number(stop)}:{int(count)}"


def sweep(
    spec: SpecLike,
    params: Optional[Mapping[str, Any]] = None,
    *,
    random: Optional[int] = None,
    seed: int = 0,
    numeric: bool = False,
    shard: Optional[Union[str, Tuple[int, int]]] = None,
    progress: ProgressLike = None,
    base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
) -> Dict[str, Any]:
    """Certify ``spec`` over a grid (or ``random`` points) of its parameters.

    ``params`` maps each swept parameter to ``(start, stop, count)`` (numbers
    or Fractions) or ``"START:STOP:COUNT"``; without it the spec's own
    ``sweep`` ranges are used. ``numeric=True`` gives floating-point verdicts
    (level ``numerical``, much faster). ``shard=(k, n)`` keeps the points
    whose index is ``k`` modulo ``n``, as ``verify sweep --shard k/n``.

    Returns columns in index order, ready for ``pandas.DataFrame(columns)``
    (pandas is not needed): ``index``, one float column per parameter,
    ``verdict``, ``level``, ``sigma2`` and ``T`` (NaN where absent; ``inf``
    for ``Sigma^2 = 0``), and
    ``error`` (None unless the spec is invalid at that point), plus
    ``lines``: the JSON lines ``verify sweep`` writes (for ``verify merge``
    and ``verify plot-sweep``).

    Ctrl-C stops the sweep (``KeyboardInterrupt``). ``progress(done,
    total)`` is called about ten times a second from the calling thread
    (``True``: a tqdm bar, as in :func:`certify`).

    >>> import energy_casimir as ec
    >>> cols = ec.sweep("fixtures/rigid-body-major-axis.json", {"I2": ("3/2", "5/2", 3)})
    >>> # sigma^2 (a3/a2 - 1) with a_i = 1/I_i - 1/I1, I = (3, I2, 1), sigma = 0.3:
    >>> # a3/a2 = 2, 4, 10 at I2 = 3/2, 2, 5/2.
    >>> [float(x) for x in cols["I2"]], [float(x) for x in cols["sigma2"]]
    ([1.5, 2.0, 2.5], [0.09, 0.27, 0.81])
    """
    import numpy as np

    text, base = _read_input(spec, "sweep", base_dir)
    ranges = [_range_text(k, v) for k, v in (params or {}).items()]
    shard_text = None
    if shard is not None:
        shard_text = shard if isinstance(shard, str) else f"{int(shard[0])}/{int(shard[1])}"
    with _Progress(progress, "sweep") as p:
        names, out = _core.sweep_text(
            text,
            _base(base),
            params=ranges,
            random=None if random is None else int(random),
            seed=int(seed),
            numeric=bool(numeric),
            shard=shard_text,
            progress=p.callback,
        )
    index, values, verdict, level, sigma2, t, error, lines = out
    columns: Dict[str, Any] = {"index": np.array(index, dtype=np.int64)}
    for n, v in zip(names, values):
        columns[n] = np.array(v, dtype=float)
    columns["verdict"] = verdict
    columns["level"] = level
    columns["sigma2"] = np.array(sigma2, dtype=float)
    columns["T"] = np.array(t, dtype=float)
    columns["error"] = error
    columns["lines"] = lines
    return columns


def to_xarray(result: Mapping[str, Any]) -> Any:
    """A result as an ``xarray.Dataset``, with dimensions, units and long
    names, as climate and ocean tools expect (needs xarray; without it the
    results stay dicts of numpy arrays).

    * :func:`simulate` / :func:`merge_shards`: dimensions ``t`` (output
      times, the model's time), ``coordinate`` (the algebra's coordinate
      names) and ``bin`` (histogram bin centres of the observable);
      variables ``nonlinear_mean`` (t, coordinate),
      ``nonlinear_norm_mean_over_delta``, its standard error and
      ``nonlinear_exceedance`` (the same for ``linearised_`` on stable
      systems), ``exact_moments_over_delta``, ``worst_case_over_delta``,
      ``bound_over_delta`` and ``histogram_counts`` (t, bin); the scalars
      (``sigma2``, ``stopping_time``, ``epsilon``, ``delta``, the
      settings as ``parameters_*``, each ensemble's Casimir drift) as
      attributes.
    * :func:`simulate_fluid`: dimension ``t``; ``monte_carlo_mean``,
      ``monte_carlo_std_error``, ``exact``, ``certified_bound``,
      ``initial_rate_bound``; the mode, grid and summary as attributes.
    * :func:`simulate_zeitlin`: dimension ``t`` with ``qtime`` (``t /
      hbar``) beside it; ``monte_carlo_mean``, ``monte_carlo_std_error``,
      ``exact``, ``certified_bound``, ``block_bound``; the block, ``N``,
      ``hbar`` and the rates as attributes.
    * :func:`sweep`: one dimension per swept parameter when the points are a
      full grid (else a ``point`` dimension with the parameters as
      coordinates); ``verdict``, ``level``, ``sigma2``, ``T`` and ``error``.

    Attributes are numbers and strings only, so ``to_netcdf`` writes them.

    >>> import energy_casimir as ec
    >>> ds = ec.to_xarray(ec.simulate("fixtures/rigid-body-major-axis.json", paths=200, t_end=2.0, outputs=20))
    >>> dict(ds["nonlinear_mean"].sizes), ds["coordinate"].values.tolist(), ds.attrs["sigma2"]
    ({'t': 21, 'coordinate': 3}, ['Pi1', 'Pi2', 'Pi3'], 0.27)
    >>> grid = ec.to_xarray(ec.sweep("fixtures/rigid-body-major-axis.json", {"I2": (1.5, 2.5, 3), "I3": (0.5, 1.0, 2)}))
    >>> dict(grid["sigma2"].sizes)
    {'I2': 3, 'I3': 2}
    """
    from ._xarray import to_xarray as convert

    return convert(result)
