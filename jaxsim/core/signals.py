"""Reference and disturbance signals ``s(t)``.

Every signal is a pytree dataclass whose numbers (amplitudes, slopes, times) are array leaves, so a
batch of signals is one ``vmap`` away.  Calling a signal at a scalar time ``t`` returns an array of
shape ``(k,)`` (a scalar amplitude gives ``k = 1``).  Time is in the model's unit (seconds for the
seed papers).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass, static_field


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

    def __call__(self, t: jax.Array) -> jax.Array:
        out = self.terms[0](t)
        for s in self.terms[1:]:
            out = out + s(t)
        return out


def sample(signal: Any, ts: jax.Array) -> jax.Array:
    """Evaluate ``signal`` on a time grid ``ts`` of shape ``(N,)``; returns ``(N, k)``."""
    return jax.vmap(signal)(jnp.asarray(ts))
