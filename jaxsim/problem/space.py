"""Parameter spaces: one declaration gives the tuners' reparametrisation and the searches' box.

::

    space = ParamSpace(
        kp=Param(lo=0.0, hi=50.0, init=1.0),                      # scalar, linear scale
        ki=Param(lo=1e-3, hi=20.0, init=0.5, log=True),          # searched in log coordinates
        q=Param(lo=1e-2, hi=1e4, init=np.ones(7), log=True),     # vector parameter
        e=Sorted(lo=0.05, hi=1.5, init=(0.75, 1.2)),             # ordered vector (fuzzy breakpoints)
    )

* ``space.init`` — the params pytree: a dict ``name -> array`` (shape of ``init``; float64);
* ``space.box`` — ``(lo, hi)``, flat ``(d,)`` NumPy arrays in *search coordinates*: the value for a
  linear :class:`Param`, ``log`` of it for ``log=True``, the increments ``x_i − x_{i−1}`` (with
  ``x_{−1} = origin``) for :class:`Sorted`; every point of the box is an admissible parameter set;
* ``space.to_search(params) -> z (d,)`` and ``space.from_search(z) -> params`` — pure, ``jit``/``vmap``-able;
* ``space.reparam`` — a dict of :mod:`jaxsim.problem.reparam` objects for the gradient tuner
  (unconstrained ``u`` ↔ params): :class:`~jaxsim.problem.reparam.Interval` on the box of a linear
  :class:`Param`, :class:`~jaxsim.problem.reparam.LogInterval` for ``log=True``,
  :class:`~jaxsim.problem.reparam.SortedBreakpoints` (ordered, unbounded above) for :class:`Sorted`;
  any of them can be replaced by passing ``reparam=`` to the declaration;
* ``space.names`` — the search coordinates' names in order (``"kp"``, ``"q[3]"``, ``"Δe[1]"``, or
  the ``labels`` given).

Declarations are checked when made: finite bounds, ``lo < hi``, ``init`` inside the box (strictly
inside for linear/log parameters, whose tuner reparametrisation is open), ``lo > 0`` for ``log``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.problem.reparam import Interval, LogInterval, Reparam, SortedBreakpoints


def _array(name: str, value: Any) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: must be a number or an array of numbers, got {value!r}") from None
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: must be finite, got {value!r}")
    return arr


def _bounds(name: str, lo: Any, hi: Any, shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    a, b = _array(f"{name}.lo", lo), _array(f"{name}.hi", hi)
    try:
        a, b = np.broadcast_to(a, shape).copy(), np.broadcast_to(b, shape).copy()
    except ValueError:
        raise ValueError(f"{name}: lo {a.shape} and hi {b.shape} do not broadcast to init's shape {shape}") from None
    if not np.all(a < b):
        raise ValueError(f"{name}: need lo < hi element-wise, got lo={lo!r}, hi={hi!r}")
    return a, b


@dataclass(frozen=True, eq=False)
class Param:
    """A scalar or array parameter in the box ``[lo, hi]`` (broadcast to ``init``'s shape).

    ``log=True``: searched in ``log`` coordinates (``lo > 0``), tuned through a
    :class:`~jaxsim.problem.reparam.LogInterval`; otherwise linear, tuned through an
    :class:`~jaxsim.problem.reparam.Interval`.  ``labels``: names of the elements (default
    ``name`` or ``name[i]``); ``reparam``: replaces the default tuner reparametrisation.
    """

    lo: Any
    hi: Any
    init: Any
    log: bool = False
    labels: tuple[str, ...] | None = None
    reparam: Reparam | None = None

    def _checked(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        x0 = _array(f"{name}.init", self.init)
        lo, hi = _bounds(name, self.lo, self.hi, x0.shape)
        if self.log and not np.all(lo > 0):
            raise ValueError(f"{name}.lo: a log-scaled parameter needs lo > 0, got {self.lo!r}")
        if self.reparam is None and not np.all((x0 > lo) & (x0 < hi)):
            raise ValueError(
                f"{name}.init: must lie strictly inside (lo, hi) = ({self.lo!r}, {self.hi!r}), got {self.init!r}"
            )
        if self.reparam is not None and not np.all((x0 >= lo) & (x0 <= hi)):
            raise ValueError(f"{name}.init: must lie inside [lo, hi] = [{self.lo!r}, {self.hi!r}], got {self.init!r}")
        return x0, lo, hi


@dataclass(frozen=True, eq=False)
class Sorted:
    """An increasing vector ``origin < x_0 < x_1 < …`` (fuzzy breakpoints), ``init`` of shape ``(n,)``.

    Search coordinates are the increments ``z_i = x_i − x_{i−1}`` (``x_{−1} = origin``), each in
    ``[lo_i, hi_i]`` (``lo``/``hi`` broadcast to ``(n,)``, ``lo ≥ min_gap``), so every box point is
    ordered.  The tuner's default reparametrisation is ``SortedBreakpoints(origin, min_gap)``: ordered
    with gaps above ``min_gap`` under any gradient step, not bounded above.
    """

    lo: Any
    hi: Any
    init: Any
    origin: float = 0.0
    min_gap: float = 0.0
    labels: tuple[str, ...] | None = None
    reparam: Reparam | None = None

    def _checked(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        x0 = _array(f"{name}.init", self.init)
        if x0.ndim != 1 or x0.size == 0:
            raise ValueError(f"{name}.init: a Sorted parameter is a vector of shape (n,), got shape {x0.shape}")
        origin = float(_array(f"{name}.origin", self.origin))
        gap = float(_array(f"{name}.min_gap", self.min_gap))
        if gap < 0:
            raise ValueError(f"{name}.min_gap: must be non-negative, got {self.min_gap!r}")
        lo, hi = _bounds(name, self.lo, self.hi, x0.shape)
        if not np.all(lo >= gap):
            raise ValueError(f"{name}.lo: the increments' lower bounds must be ≥ min_gap={gap}, got {self.lo!r}")
        inc = np.diff(np.concatenate([[origin], x0]))
        if not np.all(inc > gap):
            raise ValueError(
                f"{name}.init: must increase from origin={origin} with gaps > min_gap={gap}, got {self.init!r}"
            )
        if not np.all((inc >= lo) & (inc <= hi)):
            raise ValueError(
                f"{name}.init: its increments {inc.tolist()} must lie in [lo, hi] = [{lo.tolist()}, {hi.tolist()}]"
            )
        return x0, lo, hi


class _Entry:
    """One declared parameter, checked: kind, shape, slice of the flat search vector, box, reparam."""

    def __init__(self, name: str, decl: Param | Sorted, start: int):
        x0, lo, hi = decl._checked(name)
        self.name, self.decl, self.shape = name, decl, x0.shape
        self.size = int(x0.size)
        self.start, self.stop = start, start + self.size
        self.init = x0
        self.sorted = isinstance(decl, Sorted)
        self.log = bool(getattr(decl, "log", False))
        self.origin = float(decl.origin) if self.sorted else 0.0
        if self.log:
            self.box = (np.log(lo).ravel(), np.log(hi).ravel())
        else:
            self.box = (lo.ravel(), hi.ravel())
        if decl.reparam is not None:
            self.reparam = decl.reparam
        elif self.sorted:
            self.reparam = SortedBreakpoints(lo=self.origin, min_gap=float(decl.min_gap))
        elif self.log:
            self.reparam = LogInterval(jnp.asarray(lo), jnp.asarray(hi))
        else:
            self.reparam = Interval(jnp.asarray(lo), jnp.asarray(hi))
        labels = decl.labels
        if labels is not None:
            labels = tuple(str(v) for v in labels)
            if len(labels) != self.size:
                raise ValueError(f"{name}.labels: need {self.size} labels, got {len(labels)}")
            self.names = labels
        elif self.shape == ():
            self.names = (name,)
        else:
            prefix = "Δ" if self.sorted else ""
            self.names = tuple(f"{prefix}{name}[{i}]" for i in range(self.size))

    def to_search(self, x: jax.Array) -> jax.Array:
        x = jnp.ravel(jnp.asarray(x))
        if self.sorted:
            return jnp.diff(jnp.concatenate([jnp.full((1,), self.origin, x.dtype), x]))
        return jnp.log(x) if self.log else x

    def from_search(self, z: jax.Array) -> jax.Array:
        if self.sorted:
            return self.origin + jnp.cumsum(z)
        x = jnp.exp(z) if self.log else z
        return x.reshape(self.shape)


class ParamSpace:
    """Named parameters (:class:`Param`, :class:`Sorted`) in declaration order; see the module docstring."""

    def __init__(self, **params: Param | Sorted):
        if not params:
            raise ValueError("ParamSpace: declare at least one parameter")
        self._entries: list[_Entry] = []
        start = 0
        for name, decl in params.items():
            if not isinstance(decl, (Param, Sorted)):
                raise ValueError(f"{name}: expected a Param or Sorted declaration, got {type(decl).__name__}")
            entry = _Entry(name, decl, start)
            self._entries.append(entry)
            start = entry.stop
        self.dim = start
        self.names = tuple(n for e in self._entries for n in e.names)
        if len(set(self.names)) != len(self.names):
            raise ValueError(f"ParamSpace: coordinate names must be unique, got {self.names}")
        lo = np.concatenate([e.box[0] for e in self._entries])
        hi = np.concatenate([e.box[1] for e in self._entries])
        self.box = (lo, hi)
        self.reparam = {e.name: e.reparam for e in self._entries}
        self.declarations = dict(params)
        self._init_arrays: dict[Any, dict[str, jax.Array]] = {}  # per float dtype (x64 on or off)

    def __len__(self) -> int:
        return self.dim

    def __repr__(self) -> str:
        return f"ParamSpace({', '.join(e.name for e in self._entries)}; {self.dim} search coordinates)"

    @property
    def keys(self) -> tuple[str, ...]:
        """Parameter names (the keys of the params dict)."""
        return tuple(e.name for e in self._entries)

    @property
    def init(self) -> dict[str, jax.Array]:
        """The initial parameters, ``name -> float array`` of the declared shape (a new dict each
        time; its arrays are made once — creating them was a third of a warm tuner call's host time
        on the PID problem)."""
        dtype = jnp.result_type(float)
        if dtype not in self._init_arrays:
            self._init_arrays[dtype] = {e.name: jnp.asarray(e.init, dtype) for e in self._entries}
        return dict(self._init_arrays[dtype])

    def to_search(self, params: dict[str, Any]) -> jax.Array:
        """Params dict → flat ``(d,)`` vector in search coordinates (see the module docstring)."""
        missing = [e.name for e in self._entries if e.name not in params]
        if missing:
            raise ValueError(f"params: missing {', '.join(missing)} (the space declares {', '.join(self.keys)})")
        return jnp.concatenate([e.to_search(params[e.name]) for e in self._entries])

    def from_search(self, z: jax.Array) -> dict[str, jax.Array]:
        """Flat ``(d,)`` search vector → params dict (the inverse of :meth:`to_search`)."""
        z = jnp.asarray(z)
        if z.shape != (self.dim,):
            raise ValueError(f"z: expected shape ({self.dim},) for {self!r}, got {tuple(z.shape)}")
        return {e.name: e.from_search(z[e.start : e.stop]) for e in self._entries}

    def flat(self, params: dict[str, Any]) -> dict[str, float]:
        """``{coordinate name: value}`` of concrete ``params`` (values, not search coordinates; for
        tables): ``"kp"``, ``"q[3]"``; a :class:`Sorted` entry's values are named ``"e[i]"``."""
        out = {}
        for e in self._entries:
            values = np.ravel(np.asarray(params[e.name], float))
            names = e.names if not e.sorted or e.decl.labels else [f"{e.name}[{i}]" for i in range(e.size)]
            out.update({n: float(v) for n, v in zip(names, values)})
        return out
