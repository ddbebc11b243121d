"""Continuous → discrete conversion: python-control's ``c2d(sysc, Ts, method)``.

Methods (``x_k = x(k·Ts)`` unless said otherwise):

* ``"zoh"`` — input held constant over each period: ``Ad = e^{A Ts}``, ``Bd = ∫₀^Ts e^{Aτ}dτ B``
  (:func:`jaxsim.core.discretize.c2d_zoh`).
* ``"foh"`` — input linearly interpolated between samples (triangle hold).  With
  ``Γ₀ = ∫₀^Ts e^{Aτ}dτ B`` and ``Γ₁ = ∫₀^Ts e^{Aτ}(Ts − τ)/Ts dτ B`` (one matrix exponential of
  ``[[A Ts, B Ts, 0], [0, 0, I], [0, 0, 0]]``), ``x_{k+1} = Ad x_k + (Γ₀ − Γ₁) u_k + Γ₁ u_{k+1}``;
  the state ``ξ_k = x_k − Γ₁ u_k`` makes it causal: ``Bd = Γ₀ − Γ₁ + Ad Γ₁``, ``Cd = C``,
  ``Dd = D + C Γ₁`` (SciPy's ``cont2discrete`` realisation).
* ``"gbt"`` with ``alpha`` — generalised bilinear transform ``s ← (z − 1)/(Ts (α z + 1 − α))``;
  ``"tustin"``/``"bilinear"`` (α = ½, optional ``prewarp_frequency`` ω₀ in rad/s: the map is exact
  at ω₀, python-control's rule ``Ts ← 2 tan(ω₀Ts/2)/ω₀``), ``"euler"`` (α = 0),
  ``"backward_diff"`` (α = 1).
* ``"matched"`` — SISO: poles and finite zeros mapped by ``z = e^{s Ts}``, gain set so that the
  DC gains agree (python-control's pole-zero matching; no extra zeros at ``z = −1``).

All are ``jnp``: differentiable in the matrices (``"matched"`` through eigenvalues, so not at
repeated poles or zeros) and in ``Ts`` where ``Ts`` is traced (it must be concrete for the ``dt``
of the result, so in practice differentiate through :func:`hold_matrices`).
"""

from __future__ import annotations

from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.discretize import c2d_zoh
from jaxsim.core.validation import check_positive_scalar, is_concrete
from jaxsim.lti.frequency import dcgain
from jaxsim.lti.poles_zeros import pole, zero
from jaxsim.lti.statespace import StateSpace, as_state_space, wrap
from jaxsim.lti.transfer import tf_state_space

METHODS = ("zoh", "foh", "tustin", "bilinear", "gbt", "euler", "backward_diff", "matched")


def hold_matrices(a: jax.Array, b: jax.Array, dt: Any) -> tuple[jax.Array, jax.Array, jax.Array]:
    """``(Ad, Γ₀, Γ₁)`` for ``ẋ = A x + B u`` over one period ``dt`` (see the module docstring):
    the exact step for an input linear between samples is ``Ad x_k + (Γ₀ − Γ₁) u_k + Γ₁ u_{k+1}``,
    and ``Γ₀`` alone is the zero-order-hold input matrix.  Shapes ``(n, n)``, ``(n, m)``, ``(n, m)``."""
    n, m = b.shape
    dtype = jnp.result_type(a, b, jnp.asarray(dt))
    block = jnp.zeros((n + 2 * m, n + 2 * m), dtype)
    block = (
        block.at[:n, :n].set(a * dt).at[:n, n : n + m].set(b * dt).at[n : n + m, n + m :].set(jnp.eye(m, dtype=dtype))
    )
    e = jax.scipy.linalg.expm(block)
    return e[:n, :n], e[:n, n : n + m], e[:n, n + m :]


def _gbt(s: StateSpace, ts: float, alpha: float) -> tuple[jax.Array, ...]:
    n = s.n_states
    eye = jnp.eye(n, dtype=s.a.dtype)
    lhs = eye - alpha * ts * s.a
    ad = jnp.linalg.solve(lhs, eye + (1.0 - alpha) * ts * s.a)
    bd = jnp.linalg.solve(lhs, ts * s.b)
    cd = jnp.linalg.solve(lhs.T, s.c.T).T
    return ad, bd, cd, s.d + alpha * s.c @ bd


def _matched(s: StateSpace, ts: float) -> StateSpace:
    if not s.is_siso():
        raise ValueError(
            f"sysc: the matched method is for SISO systems, got {s.n_outputs} outputs and {s.n_inputs} inputs"
        )
    p, z = pole(s), zero(s)
    if is_concrete(p) and np.any(np.abs(np.asarray(p)) < 1e-12 * max(1.0, float(np.max(np.abs(np.asarray(p)))))):
        raise ValueError("sysc: the matched method matches the DC gain, which is infinite with a pole at s = 0")
    zp = jnp.exp(p * ts)
    finite = jnp.isfinite(z)
    zz = jnp.exp(jnp.where(finite, z, 0.0) * ts)
    one = jnp.ones((), zp.dtype)
    # Π (z − zz_i) over the finite zeros; a structural (infinite) zero contributes the factor 1
    num = jnp.ones((1,), zp.dtype)
    for i in range(zz.shape[0]):
        factor = jnp.where(finite[i], jnp.stack([one, -zz[i]]), jnp.stack([0 * one, one]))
        num = jnp.convolve(num, factor)
    den = jnp.ones((1,), zp.dtype)
    for i in range(zp.shape[0]):
        den = jnp.convolve(den, jnp.stack([one, -zp[i]]))
    num, den = jnp.real(num), jnp.real(den)
    # DC gain of num/den at z = 1 must equal the continuous one
    gain = dcgain(s) * jnp.polyval(den, 1.0) / jnp.polyval(num, 1.0)
    pad = den.shape[0] - num.shape[0]
    num = jnp.concatenate([jnp.zeros((pad,), num.dtype), gain * num])
    if is_concrete(num):  # structural leading zeros (a strictly proper result) are dropped by tf
        return tf_state_space(np.asarray(num), np.asarray(den), ts)
    return tf_state_space(num, den, ts)


def c2d(
    sysc: Any,
    Ts: Any,
    method: str = "zoh",
    alpha: float | None = None,  # noqa: N803
    prewarp_frequency: float | None = None,
) -> StateSpace:
    """python-control's ``c2d(sysc, Ts, method='zoh', alpha=None, prewarp_frequency=None)``.

    Args:
        sysc: continuous-time LTI system (a Plant from ``ss``/``tf``/``zpk`` or a ``StateSpace``).
        Ts: sampling period in seconds, positive (static: it becomes the result's ``dt``).
        method: one of :data:`METHODS` (see the module docstring).
        alpha: the ``"gbt"`` parameter in ``[0, 1]``.
        prewarp_frequency: rad/s, for ``"tustin"``/``"bilinear"`` (and ``"gbt"`` with α = ½).

    Returns:
        The discrete-time :class:`StateSpace` with ``dt = Ts``.

    Raises:
        ValueError: naming ``method`` (unknown), ``Ts`` (not positive), ``sysc`` (already
            discrete, not LTI, MIMO or with a pole at 0 for ``"matched"``), ``alpha`` (missing or
            outside ``[0, 1]`` for ``"gbt"``), ``prewarp_frequency`` (not positive, or given to a
            method that does not use it).
    """
    if method not in METHODS:
        raise ValueError(f"method: unknown c2d method {method!r}; expected one of {', '.join(METHODS)}")
    s = as_state_space(sysc, "sysc")
    if s.dt is not None:
        raise ValueError(f"sysc: already a discrete-time system (dt={s.dt}); c2d needs a continuous one")
    ts = check_positive_scalar("Ts", Ts)
    if method == "gbt":
        if alpha is None or not (0.0 <= float(alpha) <= 1.0):
            raise ValueError(f"alpha: the gbt method needs alpha in [0, 1], got {alpha!r}")
        alpha = float(alpha)
    else:
        alpha = {"tustin": 0.5, "bilinear": 0.5, "euler": 0.0, "backward_diff": 1.0}.get(method)
    t_map = ts
    if prewarp_frequency is not None:
        w0 = check_positive_scalar("prewarp_frequency", prewarp_frequency)
        if alpha != 0.5:
            raise ValueError(f"prewarp_frequency: only the tustin/bilinear map can be prewarped, not {method!r}")
        if w0 * ts >= np.pi:
            raise ValueError(f"prewarp_frequency: must be below the Nyquist frequency π/Ts = {np.pi / ts:.6g} rad/s")
        t_map = 2.0 * np.tan(w0 * ts / 2.0) / w0
    if s.n_states == 0:
        return StateSpace(s.a, s.b, s.c, s.d, ts)
    if method == "matched":
        return _matched(s, ts)
    return wrap(_discretised(s, ts, t_map, "gbt" if alpha is not None else method, alpha))


@partial(jax.jit, static_argnums=(1, 3, 4))
def _discretised(s: StateSpace, ts: float, t_map: float, method: str, alpha: float | None) -> StateSpace:
    """The zoh / foh / gbt map as one compiled program (eagerly, the matrix exponential's many
    small operations were each compiled on a first call)."""
    if method == "zoh":
        ad, bd = c2d_zoh(s.a, s.b, ts)
        return StateSpace(ad, bd, s.c, s.d, ts)
    if method == "foh":
        ad, g0, g1 = hold_matrices(s.a, s.b, ts)
        return StateSpace(ad, g0 - g1 + ad @ g1, s.c, s.d + s.c @ g1, ts)
    ad, bd, cd, dd = _gbt(s, t_map, alpha)
    return StateSpace(ad, bd, cd, dd, ts)
