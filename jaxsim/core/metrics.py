"""Time-response metrics on a uniform time grid, jittable and vmappable.

Definitions follow python-control's ``step_info`` so the two can be compared sample for sample:

* rise time: from the first sample at ≥ 10 % of the final value to the first at ≥ 90 %;
* settling time: the time of the first sample after the last one outside the band
  ``|y/y_final − 1| ≥ band`` (``0`` if never outside; ``nan`` if still outside at the end);
* overshoot: ``100·(max(sgn·y) − |y_final|)/|y_final|`` in percent, 0 if negative.

Integral criteria use the rectangle rule on the grid (``dt = t[1] − t[0]``): IAE ``Σ|e|dt``,
ISE ``Σe²dt``, ITAE ``Σ t|e| dt``, control energy ``Σ‖u‖²dt``.  Their integrands (``*_integrand``)
are the one definition of these criteria: the running costs of :mod:`jaxsim.core.costs` add the same
integrand tick by tick inside ``fold``.

Smooth surrogates for losses (exact as the temperatures go to 0):

* :func:`soft_overshoot` — softmax-weighted mean of ``v = 100(sgn·y − |y_f|)/|y_f|`` with weights
  ``softmax(v/τ)`` then ``τ·softplus(·/τ)``; ``temperature`` τ in percent (default 0.5 %);
* :func:`soft_settling_time` — softmax-weighted mean of ``t_{i+1}·σ((|y_i/y_f − 1| − band)/τ_b)``
  with weights ``softmax(·/τ_t)``; ``band_temperature`` τ_b dimensionless (default 0.002),
  ``time_temperature`` τ_t in seconds (default 0.02).  Both under-estimate the hard value by
  at most a few temperatures.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp


def _dt(t: jax.Array) -> jax.Array:
    return t[1] - t[0]


# -- integrands (element-wise; summed over samples and channels by the callers) ----------------


def iae_integrand(e: jax.Array) -> jax.Array:
    """``|e|`` (error units)."""
    return jnp.abs(e)


def ise_integrand(e: jax.Array) -> jax.Array:
    """``e²`` (error units squared)."""
    return e**2


def itae_integrand(weight: jax.Array, e: jax.Array) -> jax.Array:
    """``w·|e|`` with the time weight ``w`` (s; ``t`` for the classic ITAE), broadcast against ``e``."""
    return weight * jnp.abs(e)


def energy_integrand(u: jax.Array, offset: jax.Array | float = 0.0) -> jax.Array:
    """``(u − offset)²`` (input units squared; ``offset`` e.g. a trim input)."""
    return (u - offset) ** 2


def saturation_excess_integrand(u: jax.Array, u_max: jax.Array | float) -> jax.Array:
    """``max(0, |u| − u_max)²``: zero inside the limits, quadratic outside."""
    return jnp.maximum(jnp.abs(u) - u_max, 0.0) ** 2


# -- integral criteria over a sampled trajectory ---------------------------------------------------


def iae(t: jax.Array, e: jax.Array) -> jax.Array:
    """Integral of absolute error; ``e`` shape ``(N,)`` or ``(N, k)`` (summed over channels)."""
    return jnp.sum(iae_integrand(e)) * _dt(t)


def ise(t: jax.Array, e: jax.Array) -> jax.Array:
    """Integral of squared error."""
    return jnp.sum(ise_integrand(e)) * _dt(t)


def itae(t: jax.Array, e: jax.Array) -> jax.Array:
    """Integral of time-weighted absolute error."""
    tt = t.reshape(t.shape + (1,) * (e.ndim - 1))
    return jnp.sum(itae_integrand(tt, e)) * _dt(t)


def control_energy(t: jax.Array, u: jax.Array) -> jax.Array:
    """Integral of ``‖u‖²``."""
    return jnp.sum(energy_integrand(u)) * _dt(t)


def steady_state_error(e: jax.Array, tail: int = 1) -> jax.Array:
    """Mean of the last ``tail`` samples of ``e`` (axis 0)."""
    return jnp.mean(e[-tail:], axis=0)


class SteadyState(NamedTuple):
    value: jax.Array  # final value (mean of the tail)
    drift: jax.Array  # change of the signal across the tail window
    converged: jax.Array  # bool: |drift| ≤ atol + rtol·|value|


def steady_state(e: jax.Array, tail: int, rtol: float = 1e-6, atol: float = 1e-9) -> SteadyState:
    """Detect whether ``e`` (shape ``(N,)``) has a steady state over its last ``tail`` samples.

    A signal that keeps drifting (a ramp error, an unbounded response) has no steady state: the
    paper's "∞" cells.  NaN or inf responses are reported as not converged.
    """
    value = e[-1]
    drift = e[-1] - e[-tail]
    ok = jnp.isfinite(value) & (jnp.abs(drift) <= atol + rtol * jnp.abs(value))
    return SteadyState(value, drift, ok)


class StepInfo(NamedTuple):
    rise_time: jax.Array
    settling_time: jax.Array
    overshoot: jax.Array  # percent
    peak: jax.Array
    peak_time: jax.Array
    final_value: jax.Array


def step_info(
    t: jax.Array,
    y: jax.Array,
    y_final: jax.Array | None = None,
    band: float = 0.02,
    rise_limits: tuple[float, float] = (0.1, 0.9),
) -> StepInfo:
    """Step-response characteristics of ``y`` (shape ``(N,)``) on the grid ``t`` (``(N,)``)."""
    yf = y[-1] if y_final is None else jnp.asarray(y_final)
    sgn = jnp.sign(yf)
    n = y.shape[0]
    idx = jnp.arange(n)
    first = lambda mask: jnp.min(jnp.where(mask, idx, n - 1))  # noqa: E731
    lo = first(sgn * (y - rise_limits[0] * yf) >= 0)
    hi = first(sgn * (y - rise_limits[1] * yf) >= 0)
    rise = t[hi] - t[lo]
    outside = jnp.abs(y / yf - 1) >= band
    last_out = jnp.max(jnp.where(outside, idx, -1))
    settled = last_out + 1
    settling = jnp.where(settled < n, t[jnp.minimum(settled, n - 1)], jnp.nan)
    dy = jnp.max(sgn * y) - jnp.abs(yf)
    overshoot = jnp.where(dy > 0, jnp.abs(100.0 * dy / yf), 0.0)
    ip = jnp.argmax(jnp.abs(y))
    return StepInfo(rise, settling, overshoot, jnp.abs(y[ip]), t[ip], yf)


def _softmax_mean(v: jax.Array, temperature: float) -> jax.Array:
    w = jax.nn.softmax(v / temperature)
    return jnp.sum(w * v)


def overshoot_samples(y: jax.Array, y_final: jax.Array) -> jax.Array:
    """``100·(sgn(y_f)·y − |y_f|)/|y_f|``: each sample's excursion beyond the final value, percent."""
    return 100.0 * (jnp.sign(y_final) * y - jnp.abs(y_final)) / jnp.abs(y_final)


def settling_samples(
    t_next: jax.Array, y: jax.Array, y_final: jax.Array, band: float, band_temperature: float
) -> jax.Array:
    """``t_{i+1}·σ((|y_i/y_f − 1| − band)/τ_b)``: the time a sample would set the settling time, s."""
    return t_next * jax.nn.sigmoid((jnp.abs(y / y_final - 1) - band) / band_temperature)


def soft_overshoot(y: jax.Array, y_final: jax.Array | None = None, temperature: float = 0.5) -> jax.Array:
    """Smooth overshoot in percent (see module docstring); ``y`` shape ``(N,)``."""
    yf = y[-1] if y_final is None else jnp.asarray(y_final)
    v = overshoot_samples(y, yf)
    return temperature * jax.nn.softplus(_softmax_mean(v, temperature) / temperature)


def soft_settling_time(
    t: jax.Array,
    y: jax.Array,
    y_final: jax.Array | None = None,
    band: float = 0.02,
    band_temperature: float = 0.002,
    time_temperature: float = 0.02,
) -> jax.Array:
    """Smooth settling time in the unit of ``t`` (see module docstring)."""
    yf = y[-1] if y_final is None else jnp.asarray(y_final)
    t_next = jnp.concatenate([t[1:], t[-1:] + _dt(t)])
    v = settling_samples(t_next, y, yf, band, band_temperature)
    return _softmax_mean(v, time_temperature)
