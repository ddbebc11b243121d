"""Welch cross-spectral densities and the H1 frequency-response estimator, pure JAX.

Conventions are SciPy's ``scipy.signal.csd`` / ``welch`` defaults: periodic Hann window, segments of
``nperseg`` samples overlapping by ``noverlap`` (default ``nperseg // 2``), each segment's mean
removed (``detrend='constant'``), one-sided density scaling (units²/Hz), mean over segments.  With
``P_xy = conj(X)·Y`` the H1 estimate of the response from ``u`` to ``y`` is ``P_uy / P_uu`` (unbiased
by noise on ``y``), the coherence ``|P_uy|² / (P_uu P_yy)``.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.validation import check_int, check_positive_scalar


class FRFEstimate(NamedTuple):
    """``f`` ``(nperseg//2 + 1,)`` Hz; ``h`` complex response ``y/u``; ``coherence`` in [0, 1];
    ``p_uu``, ``p_yy`` auto-spectra (unit²/Hz)."""

    f: jax.Array
    h: jax.Array
    coherence: jax.Array
    p_uu: jax.Array
    p_yy: jax.Array


def _segments(x: jax.Array, nperseg: int, step: int) -> jax.Array:
    n_seg = (x.shape[-1] - nperseg) // step + 1
    idx = jnp.arange(n_seg)[:, None] * step + jnp.arange(nperseg)[None, :]
    return x[..., idx]  # (..., n_seg, nperseg)


def _sizes(n: int, nperseg: int, noverlap: int | None) -> tuple[int, int]:
    nperseg = check_int("nperseg", nperseg, low=2)
    noverlap = nperseg // 2 if noverlap is None else check_int("noverlap", noverlap, low=0)
    if noverlap >= nperseg:
        raise ValueError(f"noverlap: must be < nperseg = {nperseg}, got {noverlap}")
    if n < nperseg:
        raise ValueError(f"nperseg: {nperseg} exceeds the record length {n}")
    return nperseg, nperseg - noverlap


def csd(
    x: jax.Array, y: jax.Array, fs: float, nperseg: int, noverlap: int | None = None
) -> tuple[jax.Array, jax.Array]:
    """Welch cross-spectral density ``P_xy`` of two records of equal length ``(N,)`` (leading batch
    axes allowed) sampled at ``fs`` Hz; returns ``(f (nperseg//2+1,), P_xy (..., nperseg//2+1))``."""
    x, y = jnp.asarray(x), jnp.asarray(y)
    if x.shape != y.shape:
        raise ValueError(f"y: shape {tuple(y.shape)} must equal x's {tuple(x.shape)}")
    fs = check_positive_scalar("fs", fs)
    nperseg, step = _sizes(x.shape[-1], nperseg, noverlap)
    k = jnp.arange(nperseg)
    w = 0.5 - 0.5 * jnp.cos(2 * jnp.pi * k / nperseg)  # periodic Hann

    def spectrum(s: jax.Array) -> jax.Array:
        seg = _segments(s, nperseg, step)
        seg = seg - jnp.mean(seg, axis=-1, keepdims=True)
        return jnp.fft.rfft(seg * w, axis=-1)

    p = jnp.mean(jnp.conj(spectrum(x)) * spectrum(y), axis=-2) / (fs * jnp.sum(w * w))
    scale = jnp.full(nperseg // 2 + 1, 2.0).at[0].set(1.0)
    if nperseg % 2 == 0:
        scale = scale.at[-1].set(1.0)
    return jnp.fft.rfftfreq(nperseg, 1.0 / fs), p * scale


def frf_h1(u: jax.Array, y: jax.Array, fs: float, nperseg: int, noverlap: int | None = None) -> FRFEstimate:
    """H1 estimate of the frequency response from input record ``u`` to output record ``y``."""
    f, p_uy = csd(u, y, fs, nperseg, noverlap)
    _, p_uu = csd(u, u, fs, nperseg, noverlap)
    _, p_yy = csd(y, y, fs, nperseg, noverlap)
    p_uu, p_yy = jnp.real(p_uu), jnp.real(p_yy)
    h = p_uy / p_uu
    return FRFEstimate(f, h, jnp.abs(p_uy) ** 2 / (p_uu * p_yy), p_uu, p_yy)
