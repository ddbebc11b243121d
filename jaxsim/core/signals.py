"""Reference and disturbance signals ``s(t)``.

Every signal is a pytree dataclass whose numbers (amplitudes, slopes, times) are array leaves, so a
batch of signals is one ``vmap`` away.  Calling a signal at a scalar time ``t`` returns an array of
shape ``(k,)`` (a scalar amplitude gives ``k = 1``).  Time is in the model's unit (seconds for the
seed papers).

Parameters are checked by :func:`check_signal` (called by :func:`sample` and by the rollout's
``simulate``/``fold`` for the reference and the disturbance), not when a signal is built: signals
are pytrees, rebuilt on every unflatten — as gradients, or as an optimiser's zero-filled state,
where a zero ``period`` is legitimate.  It raises ``ValueError`` naming the field
(``reference.amplitude: must be finite``) for a NaN/inf parameter, a ``Square`` period ≤ 0 or duty
outside ``[0, 1]``, and ``Piecewise`` times out of order.  Inside ``jit``/``vmap`` (traced
parameters) nothing can be raised: a NaN parameter gives NaN values, an infinite amplitude gives
±inf after its switching time and NaN before it (``inf · 0``).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.validation import check_finite, check_positive, is_concrete


def _vec(x: Any) -> jax.Array:
    return jnp.atleast_1d(jnp.asarray(x))


def _after(t: jax.Array, t0: jax.Array) -> jax.Array:
    return (t >= t0).astype(jnp.result_type(t, t0, float))


@pytree_dataclass
class Constant:
    """``s(t) = value``."""

    value: Any = 0.0

    def __call__(self, t: jax.Array) -> jax.Array:
        return _vec(self.value) + 0.0 * t


@pytree_dataclass
class Step:
    """``s(t) = amplitude · 1(t ≥ t0)``."""

    amplitude: Any = 1.0
    t0: Any = 0.0

    def __call__(self, t: jax.Array) -> jax.Array:
        return _vec(self.amplitude) * _after(t, self.t0)


@pytree_dataclass
class FilteredStep:
    """``s(t) = amplitude · (1 − exp(−(t − t0)/tau)) · 1(t ≥ t0)``: a step through a first-order
    reference prefilter of time constant ``tau > 0`` (a servo's smoothed set-point move)."""

    amplitude: Any = 1.0
    tau: Any = 0.1
    t0: Any = 0.0

    def validate(self, name: str) -> None:
        """``tau`` must be positive."""
        check_positive(f"{name}.tau", self.tau)

    def __call__(self, t: jax.Array) -> jax.Array:
        late = _after(t, self.t0)
        return _vec(self.amplitude) * (-jnp.expm1(-jnp.maximum(t - self.t0, 0.0) / self.tau)) * late


@pytree_dataclass
class Ramp:
    """``s(t) = slope · (t − t0) · 1(t ≥ t0)``."""

    slope: Any = 1.0
    t0: Any = 0.0

    def __call__(self, t: jax.Array) -> jax.Array:
        return _vec(self.slope) * (t - self.t0) * _after(t, self.t0)


@pytree_dataclass
class Sine:
    """``s(t) = offset + amplitude · sin(2π·frequency·t + phase)``; frequency in Hz."""

    amplitude: Any = 1.0
    frequency: Any = 1.0
    phase: Any = 0.0
    offset: Any = 0.0

    def __call__(self, t: jax.Array) -> jax.Array:
        return _vec(self.offset) + _vec(self.amplitude) * jnp.sin(
            2 * jnp.pi * _vec(self.frequency) * t + _vec(self.phase)
        )


@pytree_dataclass
class Square:
    """Square wave between ``offset − amplitude`` and ``offset + amplitude``.

    High for the first ``duty`` fraction of each ``period`` (starting at ``t0``), low otherwise.
    """

    amplitude: Any = 1.0
    period: Any = 1.0
    duty: Any = 0.5
    offset: Any = 0.0
    t0: Any = 0.0

    def validate(self, name: str) -> None:
        """Period > 0 and duty in ``[0, 1]`` (see :func:`check_signal`)."""
        check_positive(f"{name}.period", self.period)
        if is_concrete(self.duty) and np.any((np.asarray(self.duty) < 0) | (np.asarray(self.duty) > 1)):
            raise ValueError(f"{name}.duty: must lie in [0, 1], got {np.asarray(self.duty)!r}")

    def __call__(self, t: jax.Array) -> jax.Array:
        phase = jnp.mod(t - self.t0, self.period) / self.period
        high = jnp.where(phase < self.duty, 1.0, -1.0)
        return _vec(self.offset) + _vec(self.amplitude) * high


@pytree_dataclass
class Piecewise:
    """Piecewise-constant (``linear=False``) or piecewise-linear signal through ``(times, values)``.

    ``times`` has shape ``(p,)`` (increasing); ``values`` shape ``(p,)`` or ``(p, k)``.  Before
    ``times[0]`` the signal holds ``values[0]``, after ``times[-1]`` it holds ``values[-1]``.
    """

    times: Any
    values: Any
    linear: bool = static_field(default=False)

    def validate(self, name: str) -> None:
        """``times`` 1-D and non-decreasing, one row of ``values`` per time (see :func:`check_signal`)."""
        shape_t, shape_v = np.shape(self.times), np.shape(self.values)
        if len(shape_t) != 1 or len(shape_v) not in (1, 2) or shape_v[0] != shape_t[0]:
            raise ValueError(
                f"{name}.values: expected shape ({shape_t[0] if shape_t else 'p'},) or "
                f"(p, k) to match times of shape {shape_t}, got {shape_v}"
            )
        if is_concrete(self.times) and np.any(np.diff(np.asarray(self.times)) < 0):
            raise ValueError(f"{name}.times: must be non-decreasing, got {np.asarray(self.times)!r}")

    def __call__(self, t: jax.Array) -> jax.Array:
        times = jnp.asarray(self.times)
        values = jnp.asarray(self.values)
        values = values[:, None] if values.ndim == 1 else values
        if self.linear:
            return jax.vmap(lambda col: jnp.interp(t, times, col), in_axes=1)(values)
        idx = jnp.clip(jnp.searchsorted(times, t, side="right") - 1, 0, times.shape[0] - 1)
        return values[idx]


@pytree_dataclass
class Sum:
    """Sum of several signals (shapes must broadcast)."""

    terms: tuple

    def validate(self, name: str) -> None:
        """Each term's own checks (see :func:`check_signal`)."""
        for i, term in enumerate(self.terms):
            _validate(f"{name}.terms[{i}]", term)

    def __call__(self, t: jax.Array) -> jax.Array:
        out = self.terms[0](t)
        for s in self.terms[1:]:
            out = out + s(t)
        return out


def _validate(name: str, signal: Any) -> None:
    validate = getattr(signal, "validate", None)
    if callable(validate):
        validate(name)


def check_signal(name: str, signal: Any) -> None:
    """Raise ``ValueError`` naming ``name.field`` for a signal parameter that is NaN/inf, or that the
    signal's own ``validate(name)`` rejects (``Square.period ≤ 0``, ``Piecewise.times`` unordered).

    Any pytree signal works (a user's own class too: every float leaf must be finite; it may add a
    ``validate(name)`` method).  Traced leaves (inside ``jit``/``vmap``) are skipped.
    """
    for path, leaf in jax.tree_util.tree_flatten_with_path(signal)[0]:
        check_finite(f"{name}{jax.tree_util.keystr(path)}", leaf)
    _validate(name, signal)


def sample(signal: Any, ts: jax.Array) -> jax.Array:
    """Evaluate ``signal`` on a time grid ``ts`` of shape ``(N,)``; returns ``(N, k)``.

    Raises ``ValueError`` for bad signal parameters (:func:`check_signal`, named ``signal.…``).
    """
    check_signal("signal", signal)
    return jax.vmap(signal)(jnp.asarray(ts))
