"""Block-diagram algebra on LTI systems: python-control's ``series``, ``parallel`` and ``feedback``.

The state of a combination stacks the states of its parts in argument order (``[x₁; x₂]``).  A
number or matrix may stand for a static gain (a system with no states); a scalar becomes ``k·I``
of the size the other system needs.  Continuous parts give a :class:`~jaxsim.core.system.Plant`,
discrete parts (all with the same ``dt``) a ``StateSpace``; everything is ``jnp``, so the result
is differentiable in the parts' matrices.  The matrix algebra of each combination runs as one jitted
program per shape (eagerly, each of its few dozen small operations was compiled on its own: ~1 s on
the first call of a new size).
"""

from __future__ import annotations

import functools
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.system import Plant
from jaxsim.core.validation import is_concrete
from jaxsim.lti.statespace import StateSpace, to_state_space, wrap


def _is_scalar_gain(x: Any) -> bool:
    if isinstance(x, (StateSpace, Plant)) or np.ndim(x) != 0:
        return False
    dtype = x.dtype if hasattr(x, "dtype") else np.asarray(x).dtype
    return np.dtype(dtype).kind in "biuf"


def _gain_as(name: str, k: Any, rows: int, cols: int) -> StateSpace:
    if rows != cols:
        raise ValueError(f"{name}: a scalar gain stands for k·I, but this position needs a {rows}×{cols} gain")
    return to_state_space(jnp.asarray(k) * jnp.eye(rows), name)


def _common_dt(parts: list[tuple[str, StateSpace]]) -> float | None:
    """The sampling period shared by the parts; static gains (no states) adapt to any."""
    dts = {(name, s.dt) for name, s in parts if s.n_states > 0}
    values = {dt for _, dt in dts}
    if len(values) > 1:
        desc = ", ".join(f"{n}: {'continuous' if dt is None else f'dt={dt}'}" for n, dt in sorted(dts, key=str))
        raise ValueError(f"{parts[-1][0]}: cannot combine systems with different time bases ({desc})")
    return values.pop() if values else parts[0][1].dt


def _block_diag(a1: jnp.ndarray, a2: jnp.ndarray) -> jnp.ndarray:
    n1, n2 = a1.shape[0], a2.shape[0]
    dtype = jnp.result_type(a1, a2)
    top = jnp.concatenate([a1, jnp.zeros((n1, n2), dtype)], axis=1)
    bottom = jnp.concatenate([jnp.zeros((n2, n1), dtype), a2], axis=1)
    return jnp.concatenate([top, bottom], axis=0)


def _series2(s1: StateSpace, s2: StateSpace, names: tuple[str, str]) -> StateSpace:
    """``s2 ∘ s1``: the output of ``s1`` drives ``s2``."""
    if s1.n_outputs != s2.n_inputs:
        raise ValueError(f"{names[1]}: has {s2.n_inputs} inputs but {names[0]} has {s1.n_outputs} outputs")
    return _series_matrices(s1, s2, _common_dt([(names[0], s1), (names[1], s2)]))


@functools.partial(jax.jit, static_argnums=2)
def _series_matrices(s1: StateSpace, s2: StateSpace, dt: float | None) -> StateSpace:
    a = _block_diag(s1.a, s2.a)
    a = a.at[s1.n_states :, : s1.n_states].set(s2.b @ s1.c)
    b = jnp.concatenate([s1.b, s2.b @ s1.d], axis=0)
    c = jnp.concatenate([s2.d @ s1.c, s2.c], axis=1)
    return StateSpace(a, b, c, s2.d @ s1.d, dt)


def _parallel2(s1: StateSpace, s2: StateSpace, names: tuple[str, str]) -> StateSpace:
    if (s1.n_outputs, s1.n_inputs) != (s2.n_outputs, s2.n_inputs):
        raise ValueError(
            f"{names[1]}: has {s2.n_outputs} outputs and {s2.n_inputs} inputs, {names[0]} has "
            f"{s1.n_outputs} and {s1.n_inputs}; parallel needs equal sizes"
        )
    return _parallel_matrices(s1, s2, _common_dt([(names[0], s1), (names[1], s2)]))


@functools.partial(jax.jit, static_argnums=2)
def _parallel_matrices(s1: StateSpace, s2: StateSpace, dt: float | None) -> StateSpace:
    return StateSpace(
        _block_diag(s1.a, s2.a),
        jnp.concatenate([s1.b, s2.b], axis=0),
        jnp.concatenate([s1.c, s2.c], axis=1),
        s1.d + s2.d,
        dt,
    )


def _operands(systems: tuple[Any, ...], size_of_scalar) -> list[tuple[str, StateSpace]]:
    if not systems:
        raise ValueError("sys: need at least one system")
    names = [f"sys{i + 1}" for i in range(len(systems))]
    anchor = next((to_state_space(s, n) for s, n in zip(systems, names) if not _is_scalar_gain(s)), None)
    out = []
    for i, (s, n) in enumerate(zip(systems, names)):
        if _is_scalar_gain(s):
            rows, cols = size_of_scalar(anchor, i, out)
            out.append((n, _gain_as(n, s, rows, cols)))
        else:
            out.append((n, to_state_space(s, n)))
    return out


def series(*systems: Any) -> Plant | StateSpace:
    """python-control's ``series(sys1, sys2, ..., sysn)``: ``sys1`` first, its output into ``sys2``, …
    (the transfer function ``Gₙ ⋯ G₂ G₁``)."""

    def size(anchor, i, done):
        if done:  # after a system: keep its output size
            return done[-1][1].n_outputs, done[-1][1].n_outputs
        k = 1 if anchor is None else anchor.n_inputs
        return k, k

    parts = _operands(systems, size)
    name, acc = parts[0]
    for nxt_name, nxt in parts[1:]:
        acc = _series2(acc, nxt, (name, nxt_name))
        name = nxt_name
    return wrap(acc)


def parallel(*systems: Any) -> Plant | StateSpace:
    """python-control's ``parallel(sys1, ..., sysn)``: same input to all, outputs summed."""

    def size(anchor, i, done):
        return (1, 1) if anchor is None else (anchor.n_outputs, anchor.n_inputs)

    parts = _operands(systems, size)
    name, acc = parts[0]
    for nxt_name, nxt in parts[1:]:
        acc = _parallel2(acc, nxt, (name, nxt_name))
    return wrap(acc)


def feedback(sys1: Any, sys2: Any = 1, sign: int = -1) -> Plant | StateSpace:
    """python-control's ``feedback(sys1, sys2=1, sign=-1)``: ``y = sys1(u + sign·sys2(y))``.

    The closed loop from ``u`` to ``y`` (the output of ``sys1``); negative feedback by default.
    With feedthrough in both parts the loop must be well posed: ``I − sign·D₁D₂`` invertible.

    Raises:
        ValueError: naming ``sys1``/``sys2`` for mismatched sizes or time bases, ``sign`` if not
            ±1, ``sys2`` for an ill-posed algebraic loop (concrete ``D``s only; traced: NaN).
    """
    if not (is_concrete(sign) and np.ndim(sign) == 0 and float(sign) in (-1.0, 1.0)):
        raise ValueError(f"sign: must be -1 (negative feedback) or +1 (positive feedback), got {sign!r}")
    s1 = to_state_space(sys1, "sys1")
    if _is_scalar_gain(sys2):
        s2 = _gain_as("sys2", sys2, s1.n_inputs, s1.n_outputs)
    else:
        s2 = to_state_space(sys2, "sys2")
    if (s2.n_inputs, s2.n_outputs) != (s1.n_outputs, s1.n_inputs):
        raise ValueError(
            f"sys2: must map the {s1.n_outputs} outputs of sys1 to its {s1.n_inputs} inputs, "
            f"got {s2.n_inputs} inputs and {s2.n_outputs} outputs"
        )
    dt = _common_dt([("sys1", s1), ("sys2", s2)])
    sg = float(sign)
    if is_concrete(s1.d) and is_concrete(s2.d):
        loop = np.eye(s1.n_outputs) - sg * np.asarray(s1.d) @ np.asarray(s2.d)
        if np.linalg.cond(loop) > 1e12:
            raise ValueError(
                "sys2: the feedback loop is algebraically ill-posed: I − sign·D1·D2 is singular "
                "(the feedthrough terms cancel around the loop)"
            )
    return wrap(_feedback_matrices(s1, s2, sg, dt))


@functools.partial(jax.jit, static_argnums=(2, 3))
def _feedback_matrices(s1: StateSpace, s2: StateSpace, sg: float, dt: float | None) -> StateSpace:
    m1, n1 = s1.n_inputs, s1.n_states
    loop = jnp.eye(s1.n_outputs, dtype=s1.d.dtype) - sg * s1.d @ s2.d
    # y = Cy [x1; x2] + Dy u, from (I − sign·D1 D2) y = C1 x1 + sign·D1 C2 x2 + D1 u
    cy = jnp.linalg.solve(loop, jnp.concatenate([s1.c, sg * s1.d @ s2.c], axis=1))
    dy = jnp.linalg.solve(loop, s1.d)
    # u1 = u + sign·(C2 x2 + D2 y)
    cu = sg * s2.d @ cy
    cu = cu.at[:, n1:].add(sg * s2.c)
    du = jnp.eye(m1, dtype=dy.dtype) + sg * s2.d @ dy
    a = _block_diag(s1.a, s2.a) + jnp.concatenate([s1.b @ cu, s2.b @ cy], axis=0)
    b = jnp.concatenate([s1.b @ du, s2.b @ dy], axis=0)
    return StateSpace(a, b, cy, dy, dt)
