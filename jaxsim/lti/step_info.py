"""Step-response characteristics at python-control's definitions: ``step_info``.

The rise time, settling time, overshoot and peak are :func:`jaxsim.core.metrics.step_info`'s (which
follows python-control's definitions); this adds python-control's other entries:

* settling min / max: the smallest / largest of ``y`` from the 90 % rise crossing on, and ``y_final``;
* undershoot: ``−100·y_us/y_final`` in percent for the sample ``y_us`` most opposite to the final
  value when it has the opposite sign, else 0.

With a non-finite final value (an unstable or integrating system) every entry is NaN except the
peak and peak time, which are inf, as python-control reports them.
"""

from __future__ import annotations

import functools
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core import metrics
from jaxsim.core.system import Plant
from jaxsim.lti.frequency import dcgain
from jaxsim.lti.responses import TimeResponse, step_response
from jaxsim.lti.statespace import StateSpace, as_state_space, is_lti


class StepInfo(NamedTuple):
    """python-control's ``step_info`` entries (same units: s and percent), snake_case.  Scalars
    for a single trace, ``(p, m)`` arrays for a MIMO step response."""

    rise_time: jax.Array
    settling_time: jax.Array
    settling_min: jax.Array
    settling_max: jax.Array
    overshoot: jax.Array
    undershoot: jax.Array
    peak: jax.Array
    peak_time: jax.Array
    steady_state_value: jax.Array

    def as_dict(self) -> dict[str, Any]:
        """python-control's dictionary keys (``RiseTime``, ``SettlingTime``, …), values as floats
        (SISO) or nested lists (MIMO)."""
        keys = (
            "RiseTime",
            "SettlingTime",
            "SettlingMin",
            "SettlingMax",
            "Overshoot",
            "Undershoot",
            "Peak",
            "PeakTime",
            "SteadyStateValue",
        )
        return {k: (float(v) if jnp.ndim(v) == 0 else jnp.asarray(v).tolist()) for k, v in zip(keys, self)}


def _one_trace(t: jax.Array, y: jax.Array, yf: jax.Array, band: float, limits: tuple[float, float]) -> StepInfo:
    core = metrics.step_info(t, y, yf, band, limits)
    sgn = jnp.sign(yf)
    n = y.shape[0]
    idx = jnp.arange(n)
    hi = jnp.min(jnp.where(sgn * (y - limits[1] * yf) >= 0, idx, n - 1))
    after = idx >= hi
    s_min = jnp.minimum(jnp.min(jnp.where(after, y, jnp.inf)), yf)
    s_max = jnp.maximum(jnp.max(jnp.where(after, y, -jnp.inf)), yf)
    y_us = y[jnp.argmin(sgn * y)]
    undershoot = jnp.where(sgn * y_us < 0, -100.0 * y_us / yf, 0.0)
    ok = jnp.isfinite(yf)
    nan = jnp.full_like(yf, jnp.nan)
    pick = lambda v: jnp.where(ok, v, nan)  # noqa: E731
    return StepInfo(
        pick(core.rise_time),
        pick(core.settling_time),
        pick(s_min),
        pick(s_max),
        pick(core.overshoot),
        pick(undershoot),
        jnp.where(ok, core.peak, jnp.inf),
        jnp.where(ok, core.peak_time, jnp.inf),
        pick(yf),
    )


@functools.partial(jax.jit, static_argnums=(3, 4))
def _traces(t: jax.Array, y: jax.Array, yf: jax.Array, band: float, limits: tuple[float, float]) -> StepInfo:
    """:func:`_one_trace` over every trace of ``y (..., N)``, one compiled program (eagerly, each of
    its few dozen operations compiled on its own)."""
    fn = lambda yy, ff: _one_trace(t, yy, ff, band, limits)  # noqa: E731
    for _ in range(y.ndim - 1):
        fn = jax.vmap(fn)
    return fn(y, yf)


def step_info(
    sysdata: Any,
    T: Any = None,
    T_num: int | None = None,
    yfinal: Any = None,  # noqa: N803
    SettlingTimeThreshold: float = 0.02,  # noqa: N803
    RiseTimeLimits: tuple[float, float] = (0.1, 0.9),
) -> StepInfo:  # noqa: N803
    """python-control's ``step_info(sysdata, T, T_num, yfinal, SettlingTimeThreshold, RiseTimeLimits)``.

    Args:
        sysdata: an LTI system (its step response on ``T`` is computed, final value = DC gain),
            a nonlinear :class:`Plant` (final value = last sample), a :class:`TimeResponse` from
            :func:`step_response` (final value = last sample), or the step-response samples ``y``
            ``(N,)`` with ``T`` ``(N,)``.
        yfinal: overrides the final value.
        SettlingTimeThreshold: settling band as a fraction of the final value.
        RiseTimeLimits: the rise-time fractions.

    Returns:
        :class:`StepInfo` (``.as_dict()`` gives python-control's dictionary).  Differentiable and
        vmappable where the definitions are (the times are sample times: piecewise constant).
    """
    if isinstance(sysdata, (StateSpace, Plant)):
        resp = step_response(sysdata, T, T_num=T_num, squeeze=False)
        t, y = resp.time, resp.outputs
        yf = dcgain(as_state_space(sysdata)) if is_lti(sysdata) else y[..., -1]
        if is_lti(sysdata) and as_state_space(sysdata).is_siso():
            yf = jnp.reshape(yf, (1, 1))
    elif isinstance(sysdata, TimeResponse):
        t, y = sysdata.time, sysdata.outputs
        yf = y[..., -1]
    else:
        if T is None:
            raise ValueError("T: required with step-response samples (the time of each sample)")
        y = jnp.asarray(sysdata)
        t = jnp.asarray(T)
        if y.shape[-1:] != t.shape or t.ndim != 1:
            raise ValueError(f"T: expected shape ({y.shape[-1]},) to match the samples, got {tuple(t.shape)}")
        yf = y[..., -1]
    if yfinal is not None:
        yf = jnp.broadcast_to(jnp.asarray(yfinal, dtype=jnp.result_type(y, float)), y.shape[:-1])
    yf = jnp.broadcast_to(yf, y.shape[:-1])
    limits = (float(RiseTimeLimits[0]), float(RiseTimeLimits[1]))
    info = _traces(t, y, yf, float(SettlingTimeThreshold), limits)
    if y.ndim == 3 and y.shape[:2] == (1, 1):
        info = StepInfo(*(v[0, 0] for v in info))
    return info
