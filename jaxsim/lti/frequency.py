"""Frequency responses: python-control's ``evalfr``, ``frequency_response``, ``bode`` and ``dcgain``.

``G(s) = C (sI − A)⁻¹ B + D`` at ``s = jω`` (continuous) or ``z = e^{jω·dt}`` (discrete), through
one Schur decomposition of ``A`` and a triangular solve per frequency (:mod:`jaxsim.lti._resolvent`),
so it is exact to rounding and ``jit``/``vmap``/``grad``-able (any order) in the matrices and in
``ω``.  The Schur form is LAPACK's: CPU.  Shapes follow python-control: ``(N,)`` for a SISO system, ``(p, m, N)``
otherwise
(``squeeze=False`` keeps ``(p, m, N)`` always); ``ω`` in rad/s, phase in rad.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_finite, check_positive_int, check_real, is_concrete
from jaxsim.lti._resolvent import transfer
from jaxsim.lti.poles_zeros import pole, zero
from jaxsim.lti.statespace import StateSpace, as_state_space

DEFAULT_OMEGA_NUM = 1000


def evalfr(sys: Any, x: Any) -> jax.Array:
    """``G(x)`` at complex points ``x`` (any shape ``S``): returns ``S + (p, m)`` complex.

    ``x`` is ``s`` for a continuous system and ``z`` for a discrete one (python-control's
    ``evalfr``).  At a pole the solve is singular: inf/NaN entries, no error.
    """
    s = as_state_space(sys)
    return _evaluate(s, jnp.asarray(x))


def _evaluate(s: StateSpace, x: jax.Array, factors: tuple[jax.Array, jax.Array] | None = None) -> jax.Array:
    return transfer(s.a, s.b, s.c, s.d, x, factors)


def frequency_points(s: StateSpace, omega: jax.Array) -> jax.Array:
    """``jω`` or ``e^{jω·dt}`` for the frequencies ``omega`` (rad/s)."""
    cdtype = jnp.result_type(s.a, jnp.complex64)
    if s.dt is None:
        return 1j * omega.astype(cdtype)
    return jnp.exp(1j * omega.astype(cdtype) * s.dt)


def response_at(s: StateSpace, omega: jax.Array, factors: tuple[jax.Array, jax.Array] | None = None) -> jax.Array:
    """``G`` at the frequencies ``omega`` (shape ``S``), shape ``S + (p, m)``; ``factors``: the
    Schur factors of ``A`` (:func:`jaxsim.lti._resolvent.schur_factors`) when already computed."""
    return _evaluate(s, frequency_points(s, omega), factors)


def dcgain(sys: Any) -> jax.Array:
    """Zero-frequency gain ``G(0)`` (continuous: ``D − C A⁻¹ B``) or ``G(1)`` (discrete), real
    ``(p, m)``, or a scalar for a SISO system.  inf/NaN when there is a pole at ``s = 0``
    (``z = 1``), e.g. an integrator."""
    s = as_state_space(sys)
    g = jnp.real(_evaluate(s, jnp.asarray(0.0 if s.dt is None else 1.0)))
    return g[0, 0] if s.is_siso() else g


def _features(s: StateSpace) -> np.ndarray:
    """Break frequencies (rad/s) of a concrete system: ``|λ|`` of its non-zero poles and zeros."""
    roots = [np.asarray(pole(s))]
    if s.n_inputs == s.n_outputs:
        try:
            roots.append(np.asarray(zero(s)))
        except ValueError:
            pass
    r = np.concatenate(roots) if roots else np.zeros(0)
    if s.dt is not None:
        r = r[np.abs(r) > 0]
        r = np.log(r.astype(complex)) / s.dt
    w = np.abs(r[np.isfinite(r)])
    return w[w > 0]


def default_omega(sys: Any, omega_num: int = DEFAULT_OMEGA_NUM) -> np.ndarray:
    """A log-spaced grid (rad/s) two decades either side of the system's break frequencies (whole
    decades), capped at the Nyquist frequency ``π/dt`` for a discrete system.  Concrete systems
    only: under ``jit`` pass ``omega``."""
    s = as_state_space(sys)
    if not is_concrete((s.a, s.b, s.c, s.d)):
        raise ValueError("omega: required when the system is traced (jit/vmap/grad); pass the frequencies")
    w = _features(s)
    lo, hi = (np.min(w), np.max(w)) if w.size else (1.0, 1.0)
    lo_dec, hi_dec = np.floor(np.log10(lo)) - 2, np.ceil(np.log10(hi)) + 2
    if s.dt is not None:
        nyq = np.pi / s.dt
        hi_dec = min(hi_dec, np.log10(nyq))
        lo_dec = min(lo_dec, hi_dec - 2)
    return np.logspace(lo_dec, hi_dec, check_positive_int("omega_num", omega_num))


def _omega(sys: StateSpace, omega: Any, omega_num: int | None) -> jax.Array:
    if omega is None:
        return jnp.asarray(default_omega(sys, DEFAULT_OMEGA_NUM if omega_num is None else omega_num))
    w = jnp.asarray(omega)
    check_real("omega", w)
    w = jnp.atleast_1d(w.astype(jnp.result_type(w, float)))
    if w.ndim != 1:
        raise ValueError(f"omega: expected a 1-D array of frequencies in rad/s, got shape {tuple(w.shape)}")
    check_finite("omega", w)
    if is_concrete(w) and np.any(np.asarray(w) < 0):
        raise ValueError("omega: frequencies must be non-negative (rad/s)")
    return w


def _squeeze(s: StateSpace, g: jax.Array, squeeze: bool | None) -> jax.Array:
    """``(N, p, m)`` → ``(N,)`` for SISO (unless ``squeeze=False``), else ``(p, m, N)``."""
    if squeeze is not False and s.is_siso():
        return g[:, 0, 0]
    return jnp.moveaxis(g, 0, -1)


class FrequencyResponse(NamedTuple):
    """``magnitude`` ``|G(jω)|``, ``phase`` in rad, ``omega`` in rad/s; unpacks as python-control's
    ``mag, phase, omega``.  ``response`` gives the complex values."""

    magnitude: jax.Array
    phase: jax.Array
    omega: jax.Array

    @property
    def response(self) -> jax.Array:
        return self.magnitude * jnp.exp(1j * self.phase)


def frequency_response(
    sys: Any, omega: Any = None, omega_num: int | None = None, squeeze: bool | None = None
) -> FrequencyResponse:
    """python-control's ``frequency_response(sys, omega)``: magnitude, wrapped phase (``angle``, in
    ``(−π, π]``) and the frequencies.  ``omega`` (rad/s, 1-D) is required under tracing; without it
    :func:`default_omega` chooses ``omega_num`` points."""
    s = as_state_space(sys)
    w = _omega(s, omega, omega_num)
    magnitude, phase = _magnitude_phase(s, jnp.asarray(w))
    return FrequencyResponse(_squeeze(s, magnitude, squeeze), _squeeze(s, phase, squeeze), w)


@jax.jit
def _magnitude_phase(s: StateSpace, w: jax.Array) -> tuple[jax.Array, jax.Array]:
    # one compiled program per shape (eagerly, the resolvent's small operations were each compiled)
    g = response_at(s, w)
    return jnp.abs(g), jnp.angle(g)


def bode(sys: Any, omega: Any = None, omega_num: int | None = None, squeeze: bool | None = None) -> FrequencyResponse:
    """Bode data (no plot): as :func:`frequency_response` but with the phase unwrapped along ``ω``,
    its first value placed in ``(−2π, 0]`` — python-control's ``bode(..., plot=False)`` data."""
    fr = frequency_response(sys, omega, omega_num, squeeze)
    first = fr.phase[..., :1]
    phase = jnp.unwrap(fr.phase - jnp.where(first > 0, 2 * jnp.pi, 0.0), axis=-1)
    return FrequencyResponse(fr.magnitude, phase, fr.omega)
