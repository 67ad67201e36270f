"""Type stubs of the extension module (the Rust engine). Use the wrappers in
``energy_casimir`` rather than these directly."""

from os import PathLike
from typing import Any, Callable, List, Optional, Tuple, Union

_Path = Union[str, PathLike[str]]

class SpecError(ValueError):
    """A spec is not valid input."""

    path: str
    message: str

class CheckError(ValueError):
    """A certificate failed its check."""

    path: str
    message: str
    kind: str

def certify_text(
    text: str, base: Optional[_Path] = None, progress: Optional[Callable[[int, int], Any]] = None
) -> str: ...
def check_text(
    text: str, base: Optional[_Path] = None, progress: Optional[Callable[[int, int], Any]] = None
) -> Tuple[str, str, Optional[str], Optional[float]]: ...
def validate_text(text: str, base: Optional[_Path] = None) -> None: ...
def stopping_time(epsilon: float, delta: float, sigma2: float) -> Optional[float]: ...
def simulate_text(
    text: str,
    base: Optional[_Path] = None,
    paths: int = 10000,
    dt: float = 0.01,
    t_end: Optional[float] = None,
    outputs: int = 200,
    seed: int = 1,
    bins: int = 80,
    scheme: str = "lie",
    observable: Optional[str] = None,
    epsilon: Optional[float] = None,
    delta: Optional[float] = None,
    force: bool = False,
    progress: Optional[Callable[[int, int], Any]] = None,
    shard: Optional[Tuple[int, int]] = None,
    merge: Optional[List[Tuple[str, str]]] = None,
) -> str: ...
def simulate_fluid_text(
    text: str,
    base: Optional[_Path] = None,
    mode: Optional[int] = None,
    ny: Optional[int] = None,
    paths: Optional[int] = None,
    dt: float = 0.01,
    t_end: Optional[float] = None,
    outputs: int = 200,
    seed: int = 1,
    force: bool = False,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> str: ...
def simulate_zeitlin_text(
    text: str,
    base: Optional[_Path] = None,
    block: Optional[int] = None,
    paths: Optional[int] = None,
    dt: float = 0.01,
    t_end: Optional[float] = None,
    outputs: int = 200,
    seed: int = 1,
    force: bool = False,
    progress: Optional[Callable[[int, int], Any]] = None,
    delta: Optional[float] = None,
) -> str: ...
def zeitlin_fields_text(text: str, base: Optional[_Path] = None) -> str: ...
def engine_version() -> str: ...
def sweep_text(
    text: str,
    base: Optional[_Path] = None,
    params: List[str] = ...,
    random: Optional[int] = None,
    seed: int = 0,
    numeric: bool = False,
    shard: Optional[str] = None,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> Tuple[
    List[str],
    Tuple[
        List[int],
        List[List[float]],
        List[Optional[str]],
        List[Optional[str]],
        List[float],
        List[float],
        List[Optional[str]],
        List[str],
    ],
]: ...
