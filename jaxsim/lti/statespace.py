"""LTI systems in state-space form, and how they become toolkit plants.

A system is ``ẋ = A x + B u``, ``y = C x + D u`` (continuous time) or ``x⁺ = A x + B u``,
``y = C x + D u`` with sampling period ``dt`` (discrete time).  :class:`StateSpace` holds the four
matrices as pytree leaves (so they can be tuned, vmapped and differentiated) and ``dt`` as static
metadata (``None`` for continuous time).

:func:`ss` is python-control's constructor.  A continuous-time system comes back as a toolkit
:class:`~jaxsim.core.system.Plant` whose ``params`` is the :class:`StateSpace`, with the exact
feedthrough ``D u`` (``Plant.feedthrough``), so it drops straight into a
:class:`~jaxsim.core.rollout.ClosedLoop`.  A discrete-time system comes back as the
:class:`StateSpace` itself: the rollout integrates continuous plants, so a sampled model is for
analysis, responses and design.  Every function of :mod:`jaxsim.lti` accepts either form.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.system import Plant
from jaxsim.core.validation import check_finite, check_real, is_concrete


@pytree_dataclass
class StateSpace:
    """``(A, B, C, D)`` of shapes ``(n, n)``, ``(n, m)``, ``(p, n)``, ``(p, m)``; ``dt`` the sampling
    period in seconds (static), ``None`` for continuous time."""

    a: jax.Array
    b: jax.Array
    c: jax.Array
    d: jax.Array
    dt: float | None = static_field(default=None)

    @property
    def n_states(self) -> int:
        return int(self.a.shape[-1])

    @property
    def n_inputs(self) -> int:
        return int(self.b.shape[-1])

    @property
    def n_outputs(self) -> int:
        return int(self.c.shape[-2])

    @property
    def is_discrete(self) -> bool:
        return self.dt is not None

    def is_siso(self) -> bool:
        return self.n_inputs == 1 and self.n_outputs == 1


def _lti_dynamics(params: StateSpace, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    return params.a @ x + params.b @ u


def _lti_output(params: StateSpace, x: jax.Array) -> jax.Array:
    return params.c @ x


def _lti_feedthrough(params: StateSpace, u: jax.Array) -> jax.Array:
    return params.d @ u


def lti_plant(sys: StateSpace, name: str = "lti") -> Plant:
    """The continuous-time ``sys`` as a :class:`Plant` (``params`` is ``sys``, ``D u`` exact).

    The plant functions are module-level, so two LTI plants of the same sizes share one jit cache
    entry whatever their matrices."""
    if sys.dt is not None:
        raise ValueError(
            f"sys: a discrete-time system (dt={sys.dt!r}) cannot be a Plant, whose "
            "dynamics are continuous; keep the StateSpace, or model the plant in continuous time"
        )
    return Plant(
        params=sys,
        dynamics=_lti_dynamics,
        output=_lti_output,
        n_states=sys.n_states,
        n_inputs=sys.n_inputs,
        n_outputs=sys.n_outputs,
        name=name,
        feedthrough=_lti_feedthrough,
    )


def is_lti(sys: Any) -> bool:
    """True for a :class:`StateSpace` or a plant built by :func:`lti_plant` (``ss``, ``tf``, ``zpk``)."""
    if isinstance(sys, StateSpace):
        return True
    return isinstance(sys, Plant) and isinstance(sys.params, StateSpace) and sys.dynamics is _lti_dynamics


def as_state_space(sys: Any, name: str = "sys") -> StateSpace:
    """The :class:`StateSpace` of an LTI system given as a ``StateSpace`` or an LTI :class:`Plant`.

    Raises:
        ValueError: naming ``name`` for a nonlinear plant (linearise it first with
            :func:`jaxsim.core.linearize`) or anything else.
    """
    if isinstance(sys, StateSpace):
        return sys
    if isinstance(sys, Plant):
        if is_lti(sys):
            return sys.params
        raise ValueError(
            f"{name}: plant {sys.name!r} is not an LTI plant (built by ss, tf or zpk); "
            "linearise it first (jaxsim.core.linearize) and pass ss(*linearization)"
        )
    raise ValueError(
        f"{name}: expected an LTI system (a Plant from ss/tf/zpk or a StateSpace), got {type(sys).__name__}"
    )


def wrap(sys: StateSpace) -> Plant | StateSpace:
    """What the constructors and interconnections return: a :class:`Plant` in continuous time, the
    :class:`StateSpace` itself in discrete time."""
    return lti_plant(sys) if sys.dt is None else sys


def check_dt(dt: Any) -> float | None:
    """Normalise python-control's ``dt``: ``None``/``0`` → continuous (``None``), a positive float →
    that sampling period.  ``True`` (python-control's "unspecified period") is rejected."""
    if dt is None:
        return None
    if isinstance(dt, (bool, np.bool_)) or not is_concrete(dt) or np.ndim(dt) != 0:
        raise ValueError(f"dt: must be None/0 (continuous time) or the sampling period in seconds, got {dt!r}")
    value = float(dt)
    if value == 0.0:
        return None
    if not np.isfinite(value) or value < 0.0:
        raise ValueError(f"dt: must be None/0 (continuous time) or a positive sampling period, got {dt!r}")
    return value


def _as_matrix(name: str, m: Any, shape: tuple[int | None, int | None], vector_axis: int) -> jax.Array:
    """``m`` as a float 2-D array; a scalar is ``(1, 1)``; a 1-D array lies along ``vector_axis``."""
    arr = jnp.asarray(m)
    check_real(name, arr)
    arr = arr.astype(jnp.result_type(arr, float))
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    elif arr.ndim == 1:
        arr = arr.reshape((-1, 1) if vector_axis == 0 else (1, -1))
    if arr.ndim != 2 or any(s is not None and s != a for s, a in zip(shape, arr.shape)):
        want = "(" + ", ".join("·" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"{name}: expected shape {want}, got {tuple(np.shape(m))}")
    check_finite(name, arr)
    return arr


def state_space(A: Any, B: Any, C: Any, D: Any = 0.0, dt: Any = None) -> StateSpace:  # noqa: N803
    """A checked :class:`StateSpace` (the data behind :func:`ss`).

    Scalars are ``1 × 1``; a 1-D ``B`` is a column, a 1-D ``C`` a row; a scalar ``D`` broadcasts to
    ``(p, m)``.  An empty ``A`` (``n = 0``) is a static gain ``D``.

    Raises:
        ValueError: naming ``A``/``B``/``C``/``D`` for a wrong shape, a complex dtype or a
            non-finite entry (values checked on concrete input only), or ``dt`` for a bad period.
    """
    dt = check_dt(dt)
    a = _as_matrix("A", A, (None, None), 0) if np.size(A) else jnp.zeros((0, 0))
    if a.shape[0] != a.shape[1]:
        raise ValueError(f"A: expected a square matrix, got shape {tuple(a.shape)}")
    n = a.shape[0]
    if n == 0:
        d = _as_matrix("D", D, (None, None), 0)
        p, m = d.shape
        return StateSpace(a, jnp.zeros((0, m), d.dtype), jnp.zeros((p, 0), d.dtype), d, dt)
    b = _as_matrix("B", B, (n, None), 0)
    c = _as_matrix("C", C, (None, n), 1)
    p, m = c.shape[0], b.shape[1]
    if np.ndim(D) == 0:
        check_real("D", jnp.asarray(D))
        check_finite("D", D)
        d = jnp.full((p, m), D, dtype=jnp.result_type(jnp.asarray(D), float))
    else:
        d = _as_matrix("D", D, (p, m), 1 if p == 1 else 0)
    dtype = jnp.result_type(a, b, c, d)
    return StateSpace(a.astype(dtype), b.astype(dtype), c.astype(dtype), d.astype(dtype), dt)


def ss(A: Any, B: Any, C: Any, D: Any = 0.0, dt: Any = None) -> Plant | StateSpace:  # noqa: N803
    """python-control's ``ss(A, B, C, D[, dt])``: a continuous-time :class:`Plant` with exact
    feedthrough (``dt`` ``None`` or 0), or a discrete-time :class:`StateSpace` (``dt > 0`` s).

    Shapes: ``A (n, n)``, ``B (n, m)``, ``C (p, n)``, ``D (p, m)`` (scalar ``D`` broadcasts).  Pure
    ``jnp``: the matrices may be traced (``grad``/``vmap`` through ``ss``); values are checked only
    when concrete.  A :class:`jaxsim.core.linearize.Linearization` unpacks into it: ``ss(*lin)``.
    """
    return wrap(state_space(A, B, C, D, dt))


def static_gain(k: Any, name: str = "sys") -> StateSpace:
    """A scalar or matrix gain as a state-space system with no states (``D = k``)."""
    return state_space(jnp.zeros((0, 0)), None, None, k)


def to_state_space(sys: Any, name: str = "sys") -> StateSpace:
    """:func:`as_state_space`, plus numbers and arrays as static gains (for interconnections)."""
    if isinstance(sys, (StateSpace, Plant)):
        return as_state_space(sys, name)
    try:
        arr = jnp.asarray(sys)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected an LTI system or a gain, got {type(sys).__name__}") from None
    if arr.ndim > 2:
        raise ValueError(f"{name}: a gain must be a scalar or a matrix, got shape {tuple(arr.shape)}")
    check_real(name, arr)
    check_finite(name, arr)
    return static_gain(arr.reshape((1, 1)) if arr.ndim == 0 else jnp.atleast_2d(arr), name)
