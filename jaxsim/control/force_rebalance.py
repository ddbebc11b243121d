"""Digital force-rebalance loop of a pendulous accelerometer (seed 004, Gnusarev; spec
seed004_part4.md B6): a sampled PID on the quantised pick-off voltage, a quantised torquer DAC, ZOH.

At every control tick ``k`` (period ``T_s = m·dt``; the plant integrates with RK4 at the base step
``dt``, the regulator updates on ticks where ``step % m == 0`` — masking, so ``m`` may be traced)::

    e_k = Q_adc(K_du θ_k + n_k)                     (V)
    s_k = s_{k−1} + T_s e_k
    i_k = Q_dac(k_p e_k + k_i s_k + k_d (e_k − e_{k−1})/T_s)   (A, held until the next tick)

The instrument's output is the DAC code ``i_k`` converted to g by the scale factor.  ``Q`` rounds to
the quantum ``q`` and clips at ``±full_scale``; with ``tau > 0`` the rounding is the smooth surrogate
:func:`soft_quantize` (gradient path), ``tau = 0`` the exact staircase (reporting).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.plants import quartz_accelerometer as qa


@pytree_dataclass
class Gains:
    """PID gains: ``kp`` A/V, ``ki`` A/(V·s), ``kd`` A·s/V."""

    kp: Any = 2.0e-3
    ki: Any = 0.6
    kd: Any = 5.0e-7


@pytree_dataclass
class Converters:
    """ADC (pick-off) and DAC (torquer) resolution: ``bits`` and symmetric full scale (V, A)."""

    adc_bits: Any = 16.0
    adc_full_scale: Any = 2.5  # V (assumed)
    dac_bits: Any = 16.0
    dac_full_scale: Any = 0.05  # A, ≈ ±38 g (assumed, spec range ±(10–50) g)

    @property
    def q_adc(self) -> Any:
        return 2 * self.adc_full_scale / 2.0**self.adc_bits

    @property
    def q_dac(self) -> Any:
        return 2 * self.dac_full_scale / 2.0**self.dac_bits


def quantize(x: Any, q: Any, full_scale: Any) -> jax.Array:
    """Exact mid-tread quantiser: ``clip(q·round(x/q), ±full_scale)``."""
    return jnp.clip(q * jnp.round(x / q), -full_scale, full_scale)


def soft_quantize(x: Any, q: Any, full_scale: Any, tau: Any) -> jax.Array:
    """Smooth staircase: ``q·(⌊x/q⌋ + σ((frac − ½)/τ))``; → :func:`quantize` as ``τ → 0``
    (differentiable in ``x`` almost everywhere, slope concentrated near the code edges)."""
    y = x / q
    n = jnp.floor(y)
    return jnp.clip(q * (n + jax.nn.sigmoid((y - n - 0.5) / tau)), -full_scale, full_scale)


def _q(x: Any, q: Any, fs: Any, tau: Any) -> jax.Array:
    return soft_quantize(x, q, fs, tau) if tau else quantize(x, q, fs)


class Trace(NamedTuple):
    """Per base step: ``theta`` (rad), ``current`` (A, the held DAC code), ``output_g`` (g)."""

    theta: jax.Array
    current: jax.Array
    output_g: jax.Array


def simulate(
    p: qa.Params,
    gains: Gains,
    conv: Converters,
    accel: jax.Array,
    noise: jax.Array,
    dt: float,
    m: Any = 1,
    substeps: int = 2,
    tau: float = 0.0,
) -> Trace:
    """Closed loop over ``N = accel.shape[0]`` base steps of ``dt`` s.

    ``accel`` (N,) input acceleration, m/s²; ``noise`` (N,) pick-off noise, V (read on control ticks);
    ``m`` control period in base steps (int, may be traced); ``substeps`` RK4 steps per base step;
    ``tau`` soft-quantiser temperature (0: exact).
    """
    if accel.shape != noise.shape or accel.ndim != 1:
        raise ValueError(f"accel/noise: need equal 1-D shapes, got {accel.shape} and {noise.shape}")
    ts = m * dt
    h = dt / substeps

    def step(carry, inp):
        x, s, e_prev, i_held, k = carry
        a, n = inp
        tick = (k % m) == 0
        e = _q(qa.pickoff(p, x) + n, conv.q_adc, conv.adc_full_scale, tau)
        s_new = s + ts * e
        u = gains.kp * e + gains.ki * s_new + gains.kd * (e - e_prev) / ts
        i_new = _q(u, conv.q_dac, conv.dac_full_scale, tau)
        s = jnp.where(tick, s_new, s)
        e_prev = jnp.where(tick, e, e_prev)
        i_held = jnp.where(tick, i_new, i_held)
        x_next = x
        for _ in range(substeps):  # static and small: unrolled (cheaper to compile under grad)
            x_next = qa.rk4_step(p, x_next, i_held, a, h)
        return (x_next, s, e_prev, i_held, k + 1), (x[0], i_held)

    z = jnp.zeros(())
    carry0 = (jnp.zeros(2), z, z, z, jnp.zeros((), jnp.int32))
    _, (theta, cur) = jax.lax.scan(step, carry0, (accel, noise))
    return Trace(theta, cur, cur / qa.scale_factor(p))


def closed_loop_matrices(p: qa.Params, gains: Gains, ts: float) -> tuple[np.ndarray, ...]:
    """Linear discrete closed loop at period ``ts`` (ZOH plant inside the stops, quantisers as
    additive inputs): state ``[θ, ω, s, e_prev]``, inputs ``[a (m/s²), n (V, pick-off noise + ADC
    error), d (A, DAC error)]``, output the DAC code ``i`` (A).  Returns ``A (4,4), B (4,3), C (1,4), D (1,3)``
    (NumPy, via SciPy's matrix exponential)."""
    import scipy.linalg

    a, bi, ba, c = (np.asarray(v) for v in qa.linear_model(p))
    big = np.zeros((4, 4))
    big[:2, :2] = a
    big[:2, 2:3] = bi
    big[:2, 3:4] = ba
    e = scipy.linalg.expm(big * ts)
    ad, bdi, bda = e[:2, :2], e[:2, 2:3], e[:2, 3:4]
    kp, ki, kd = (float(v) for v in (gains.kp, gains.ki, gains.kd))
    g0 = kp + ki * ts + kd / ts
    # i = g0 (C x + n) + ki s_prev − kd/ts e_prev + d
    ci = np.concatenate([g0 * c[0], [ki, -kd / ts]])
    di = np.array([0.0, g0, 1.0])
    A = np.zeros((4, 4))
    B = np.zeros((4, 3))
    A[:2, :2] = ad
    A[:2] += bdi @ ci[None, :]
    B[:2, 0] = bda[:, 0]
    B[:2] += bdi @ di[None, :]
    A[2, :2] = ts * c[0]
    A[2, 2] = 1.0
    B[2, 1] = ts
    A[3, :2] = c[0]
    B[3, 1] = 1.0
    return A, B, ci[None, :], di[None, :]
