"""Sweep designs over named parameters: full grid, Latin hypercube and Sobol (``scipy.stats.qmc``).

A :class:`Design` is a table of points: ``names`` (d parameter names) and ``values`` of shape
``(P, d)``.  Each point gets its own Monte Carlo.  Ranges are ``(lo, hi)`` with ``lo ≤ hi``
(``lo = hi`` pins a parameter); a range with ``lo > hi`` raises ``ValueError`` naming the parameter.
"""

from __future__ import annotations

import itertools
import math
from typing import Mapping, NamedTuple, Sequence

import numpy as np
from scipy.stats import qmc


class Design(NamedTuple):
    """``kind`` (``"grid"``, ``"lhs"``, ``"sobol"``, ``"points"``), ``names`` and ``values (P, d)``."""

    kind: str
    names: tuple[str, ...]
    values: np.ndarray

    def __len__(self) -> int:  # type: ignore[override]
        return int(self.values.shape[0])

    def point(self, i: int) -> dict[str, float]:
        return {n: float(v) for n, v in zip(self.names, self.values[i])}

    def describe(self) -> dict:
        return {"kind": self.kind, "names": list(self.names), "values": self.values.tolist()}


def _bounds(name: str, lo: float, hi: float) -> tuple[float, float]:
    try:
        lo, hi = float(lo), float(hi)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: range bounds must be numbers, got {lo!r}:{hi!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError(f"{name}: range bounds must be finite, got {lo!r}:{hi!r}")
    if lo > hi:
        raise ValueError(f"{name}: range has lo={lo!r} > hi={hi!r}")
    return lo, hi


def _check_names(names: Sequence[str]) -> tuple[str, ...]:
    for n in names:
        if not isinstance(n, str) or not n:
            raise ValueError(f"ranges: parameter names must be non-empty strings, got {n!r}")
    return tuple(names)


def _count(name: str, n: int) -> int:
    if isinstance(n, bool) or int(n) != n or int(n) < 1:
        raise ValueError(f"{name}: number of points must be a positive integer, got {n!r}")
    return int(n)


def single_point() -> Design:
    """A design with one point and no parameters (a plain Monte Carlo)."""
    return Design("points", (), np.zeros((1, 0)))


def points(names: Sequence[str], values: np.ndarray) -> Design:
    """A design from explicit points ``values (P, d)``."""
    names = _check_names(names)
    values = np.asarray(values, np.float64).reshape(-1, len(names)) if names else np.zeros((1, 0))
    if not np.all(np.isfinite(values)):
        raise ValueError("values: design points must be finite")
    return Design("points", names, values)


def grid(ranges: Mapping[str, tuple[float, float, int]]) -> Design:
    """Full factorial grid: ``{name: (lo, hi, n)}`` → ``n`` evenly spaced values per parameter
    (``linspace``, ends included; ``n = 1`` gives ``lo``); points in C order (last name fastest)."""
    names = _check_names(list(ranges))
    axes = []
    for name in names:
        try:
            lo, hi, n = ranges[name]
        except (TypeError, ValueError):
            raise ValueError(f"{name}: expected (lo, hi, n), got {ranges[name]!r}") from None
        lo, hi = _bounds(name, lo, hi)
        axes.append(np.linspace(lo, hi, _count(name, n)))
    values = np.array(list(itertools.product(*axes)), np.float64).reshape(-1, len(names))
    return Design("grid", names, values)


def _qmc_design(kind: str, engine_cls, ranges: Mapping[str, tuple[float, float]], n: int, seed: int) -> Design:
    names = _check_names(list(ranges))
    if not names:
        raise ValueError("ranges: at least one parameter is needed")
    n = _count("n", n)
    bounds = []
    for name in names:
        try:
            lo, hi = ranges[name][:2]
        except (TypeError, ValueError):
            raise ValueError(f"{name}: expected (lo, hi), got {ranges[name]!r}") from None
        bounds.append(_bounds(name, lo, hi))
    lo, hi = np.array(bounds).T
    engine = engine_cls(len(names), rng=np.random.default_rng(seed))
    unit = engine.random(n)
    return Design(kind, names, lo + unit * (hi - lo))


def latin_hypercube(ranges: Mapping[str, tuple[float, float]], n: int, seed: int = 0) -> Design:
    """``n`` Latin-hypercube points (``scipy.stats.qmc.LatinHypercube``, seeded) in the ranges."""
    return _qmc_design("lhs", qmc.LatinHypercube, ranges, n, seed)


def sobol(ranges: Mapping[str, tuple[float, float]], n: int, seed: int = 0) -> Design:
    """``n`` scrambled Sobol points (``scipy.stats.qmc.Sobol``, seeded); ``n`` a power of 2 keeps
    the sequence balanced (SciPy warns otherwise)."""
    return _qmc_design("sobol", qmc.Sobol, ranges, n, seed)


def parse_range(text: str) -> tuple[str, float, float, int | None]:
    """``"name=lo:hi[:n]"`` → ``(name, lo, hi, n or None)``; ``ValueError`` on malformed text."""
    if "=" not in text:
        raise ValueError(f"--param {text!r}: expected name=lo:hi[:n]")
    name, spec = (s.strip() for s in text.split("=", 1))
    parts = spec.split(":")
    if not name or len(parts) not in (2, 3):
        raise ValueError(f"--param {text!r}: expected name=lo:hi[:n]")
    try:
        lo, hi = float(parts[0]), float(parts[1])
    except ValueError:
        raise ValueError(f"--param {name}: lo and hi must be numbers, got {parts[0]!r}:{parts[1]!r}") from None
    n = None
    if len(parts) == 3:
        try:
            n = int(parts[2])
        except ValueError:
            raise ValueError(f"--param {name}: n must be an integer, got {parts[2]!r}") from None
    _bounds(f"--param {name}", lo, hi)
    if n is not None:
        _count(f"--param {name}", n)
    return name, lo, hi, n
