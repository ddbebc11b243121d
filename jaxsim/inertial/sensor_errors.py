"""Gyro error generators: the five Allan-variance noise terms of IEEE Std 952 and a Wiener sequence.

A gyro's rate output sampled every ``dt`` (s) is modelled as the sum of five independent terms
(IEEE Std 952-1997, annex C; seed 004 part 3 §2.1, eq. 4), each with the Allan variance it
generates (``τ = m·dt``, ``m ≥ 1`` samples per cluster)::

    R  rate ramp            ω = R·t                              R² τ²/2
    K  rate random walk     b_k = b_{k−1} + K·√dt·w_k             K² τ/3  + K² dt²/(6τ)   (sampling term)
    B  bias instability     1/f noise, one-sided PSD B²/(π f)     ≈ B² · 2 ln2/π (flat, band-limited)
    N  angle random walk    white rate, per-sample std N/√dt      N²/τ
    Q  quantisation         (e_k − e_{k−1})/dt, e ~ N(0, Q²)       3 Q²/τ²

The rate random walk is seed 004's discrete Wiener sequence (eq. 5: increments ``V_i·T`` with
``σ_V² T = K²``), whose Allan variance carries the sampling term ``K² dt²/(6τ)`` that mimics white
noise.  Units: with the rate in u/s (u = rad or °), ``R`` u/s², ``K`` u/s/√s, ``B`` u/s,
``N`` u/√s, ``Q`` u.

The bias instability is synthesised in the frequency domain (random phases and Gaussian amplitudes
over the FFT bins ``1/(n·dt) … 1/(2dt)``): its Allan variance is flat at ``B²·2 ln2/π`` only for
``dt ≪ τ ≪ n·dt`` and falls off towards ``τ → n·dt`` (the band has a lower edge).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import check_positive, check_positive_int

__all__ = [
    "GyroNoise",
    "flicker_noise",
    "gyro_noise",
    "noise_terms",
    "wiener_sequence",
]


@pytree_dataclass
class GyroNoise:
    """The five IEEE-952 coefficients (see the module docstring for units); any may be zero.

    Defaults: a consumer MEMS gyro in °/s, chosen so each term dominates its own decade of τ at
    100 Hz over about 90 min (assumption of the ``allan_wiener`` study; the paper gives no gyro).
    """

    R: Any = 1.1e-5  # °/s², rate ramp
    K: Any = 2.3e-4  # °/s/√s, rate random walk
    B: Any = 2.0e-3  # °/s, bias instability
    N: Any = 3.0e-3  # °/√s, angle random walk
    Q: Any = 5.0e-4  # °, angle quantisation

    def as_array(self) -> jax.Array:
        """``(5,)`` array ``[R, K, B, N, Q]``."""
        return jnp.stack([jnp.asarray(v, float) for v in (self.R, self.K, self.B, self.N, self.Q)])


def wiener_sequence(key: jax.Array, sigma_v: Any, dt: float, n: int, x0: Any = 0.0) -> jax.Array:
    """Seed 004 eq. (5): ``x_k = x0 + Σ_{i≤k} V_i·dt``, ``V_i ~ N(0, σ_V²)`` i.i.d.; shape ``(n,)``.

    ``sigma_v`` (u/s) may be traced; ``dt`` (s) > 0; ``n`` a positive int.  Its intensity is
    ``K² = σ_V² dt``.
    """
    n = check_positive_int("n", n)
    check_positive("dt", dt)
    check_positive("sigma_v", sigma_v, allow_zero=True)
    return x0 + jnp.cumsum(sigma_v * dt * jax.random.normal(key, (n,)))


def flicker_noise(key: jax.Array, b: Any, dt: float, n: int) -> jax.Array:
    """Band-limited 1/f rate noise with one-sided PSD ``B²/(π f)`` on ``[1/(n dt), 1/(2 dt)]``;
    shape ``(n,)``, zero mean.  Its Allan variance is ``≈ B²·2 ln2/π`` for ``dt ≪ τ ≪ n·dt``.

    Each rFFT bin ``k = 1 … n/2`` gets a complex Gaussian amplitude with ``E|X_k|² = n·S(f_k)/(2 dt)``
    (one-sided ``S``), so ``Var x = Σ_k S(f_k)·Δf`` with ``Δf = 1/(n dt)``.
    """
    n = check_positive_int("n", n)
    check_positive("dt", dt)
    check_positive("b", b, allow_zero=True)
    n_bins = n // 2 + 1
    f = jnp.arange(n_bins) / (n * dt)
    psd = jnp.where(f > 0, b**2 / (jnp.pi * jnp.where(f > 0, f, 1.0)), 0.0)
    scale = jnp.sqrt(n * psd / (2.0 * dt))
    kr, ki = jax.random.split(key)
    re = jax.random.normal(kr, (n_bins,))
    im = jax.random.normal(ki, (n_bins,))
    # interior bins: complex, the variance split between real and imaginary parts; the Nyquist bin
    # of an even n is real and appears once in the inverse transform, so it gets twice the variance
    amp = scale * (re + 1j * im) / jnp.sqrt(2.0)
    if n % 2 == 0:
        amp = amp.at[-1].set(jnp.sqrt(2.0) * scale[-1] * re[-1])
    return jnp.fft.irfft(amp, n=n)


def noise_terms(key: jax.Array, noise: GyroNoise, dt: float, n: int) -> jax.Array:
    """The five error terms of ``noise`` as rows ``(5, n)`` in the order ``R, K, B, N, Q`` (u/s),
    sampled at ``t_k = k·dt``, ``k = 0 … n−1``.  Coefficients may be traced (vmap over gyros)."""
    n = check_positive_int("n", n)
    check_positive("dt", dt)
    c = noise.as_array()
    k_rw, k_b, k_n, k_q = jax.random.split(key, 4)
    t = jnp.arange(n) * dt
    ramp = c[0] * t
    rrw = c[1] * jnp.sqrt(dt) * jnp.cumsum(jax.random.normal(k_rw, (n,)))
    flicker = flicker_noise(k_b, c[2], dt, n)
    white = c[3] / jnp.sqrt(dt) * jax.random.normal(k_n, (n,))
    e = c[4] * jax.random.normal(k_q, (n + 1,))
    quant = jnp.diff(e) / dt
    return jnp.stack([ramp, rrw, flicker, white, quant])


def gyro_noise(key: jax.Array, noise: GyroNoise, dt: float, n: int) -> jax.Array:
    """Sum of the five error terms (:func:`noise_terms`): the rate error of one gyro, ``(n,)`` u/s."""
    return jnp.sum(noise_terms(key, noise, dt, n), axis=0)
