"""LQ tracking of an exosystem's reference through the regulator (Francis) equations.

Exosystem ``ξ̇ = S ξ`` generating the reference ``r = Q_r ξ``; plant ``ẋ = A x + B u``, ``y = C x``.
If ``(Π, Γ)`` solve the regulator equations

    Π S = A Π + B Γ,        C Π = Q_r,

then ``x_ss = Π ξ``, ``u_ss = Γ ξ`` is a steady motion with ``y = r``, and the tracking law

    u = Γ ξ + K (Π ξ − x)          (feed-forward ``L_g = Γ + K Π``:  u = L_g ξ − K x)

drives ``e = y − r`` to zero exponentially for any stabilising ``K`` (the seed paper's eq. (4)).
The equations are linear in ``(Π, Γ)`` and solved at once in Kronecker form
(``(q(n+p)) × (q(n+m))``, small for the exosystems used here); a unique solution exists when
``p = m`` and no transmission zero of ``(A, B, C)`` is an eigenvalue of ``S``.  Differentiable
(through ``jnp.linalg.solve``, whose derivative is the adjoint solve) and vmappable.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control.lqr import lqr
from jaxsim.core.validation import check_finite, check_square, is_concrete


class Exosystem(NamedTuple):
    """``ξ̇ = s ξ`` (``s (q, q)``), reference ``r = q_r ξ`` (``q_r (p, q)``)."""

    s: jax.Array
    q_r: jax.Array


def constant_exosystem(p: int) -> Exosystem:
    """Constant references in ``p`` channels: ``S = 0``, ``ξ = r``."""
    return Exosystem(jnp.zeros((p, p)), jnp.eye(p))


def sinusoidal_exosystem(omega) -> Exosystem:
    """One sinusoid per channel, ``omega (p,)`` in rad/s.

    Channel ``i`` has the state pair ``(ξ_{2i}, ξ_{2i+1}) = (a sin(ωt + φ), a cos(ωt + φ))`` and the
    reference ``r_i = ξ_{2i}``.
    """
    omega = jnp.atleast_1d(jnp.asarray(omega, dtype=float))
    p = omega.shape[0]
    rot = jnp.array([[0.0, 1.0], [-1.0, 0.0]])
    s = jnp.kron(jnp.diag(omega), jnp.ones((2, 2))) * jnp.kron(jnp.eye(p), rot)
    q_r = jnp.kron(jnp.eye(p), jnp.array([[1.0, 0.0]]))
    return Exosystem(s, q_r)


def _vec(m: jax.Array) -> jax.Array:
    return m.T.reshape(-1)  # column-major


def regulator_equations(a, b, c, exo: Exosystem) -> tuple[jax.Array, jax.Array]:
    """Solve ``Π S = A Π + B Γ``, ``C Π = Q_r``; returns ``(Π (n, q), Γ (m, q))``."""
    a, b, c = jnp.asarray(a), jnp.asarray(b), jnp.asarray(c)
    s, q_r = jnp.asarray(exo.s), jnp.asarray(exo.q_r)
    check_square("a", a)
    check_square("exo.s", s)
    n, m, p, q = a.shape[0], b.shape[1], c.shape[0], s.shape[0]
    if b.shape[0] != n or c.shape[1] != n:
        raise ValueError(f"b, c: expected shapes ({n}, m) and (p, {n}), got {tuple(b.shape)}, {tuple(c.shape)}")
    if q_r.shape != (p, q):
        raise ValueError(f"exo.q_r: expected shape ({p}, {q}), got {tuple(q_r.shape)}")
    if p != m:
        raise ValueError(f"c: the regulator equations need as many outputs as inputs (p = m), got p={p}, m={m}")
    for name, v in (("a", a), ("b", b), ("c", c), ("exo.s", s), ("exo.q_r", q_r)):
        check_finite(name, v)
    eye_q = jnp.eye(q, dtype=a.dtype)
    top = jnp.concatenate([jnp.kron(s.T, jnp.eye(n, dtype=a.dtype)) - jnp.kron(eye_q, a), -jnp.kron(eye_q, b)], axis=1)
    bottom = jnp.concatenate([jnp.kron(eye_q, c), jnp.zeros((p * q, m * q), a.dtype)], axis=1)
    lhs = jnp.concatenate([top, bottom], axis=0)
    if is_concrete(lhs):
        cond = np.linalg.cond(np.asarray(lhs))
        if not np.isfinite(cond) or cond > 1e12:
            raise ValueError(
                "(a, b, c, exo): the regulator equations are singular (condition number "
                f"{cond:.3g}) — a transmission zero of (a, b, c) coincides with an exosystem eigenvalue"
            )
    rhs = jnp.concatenate([jnp.zeros(n * q, a.dtype), _vec(q_r)])
    z = jnp.linalg.solve(lhs, rhs)
    pi = z[: n * q].reshape(q, n).T
    gamma = z[n * q :].reshape(q, m).T
    return pi, gamma


class TrackingGains(NamedTuple):
    """``u = Γ ξ + K (Π ξ − x) = feedforward ξ − K x``."""

    k: jax.Array  # (m, n)
    pi: jax.Array  # (n, q)
    gamma: jax.Array  # (m, q)
    feedforward: jax.Array  # (m, q): L_g = Γ + K Π


def lq_tracking(a, b, c, q, r, exo: Exosystem) -> TrackingGains:
    """LQR gain for weights ``q``, ``r`` plus the regulator-equation feed-forward for ``exo``."""
    k = lqr(a, b, q, r).k
    pi, gamma = regulator_equations(a, b, c, exo)
    return TrackingGains(k, pi, gamma, gamma + k @ pi)


def tracking_control(gains: TrackingGains, x: jax.Array, xi: jax.Array) -> jax.Array:
    """``u = Γ ξ + K (Π ξ − x)`` for state ``x (n,)`` and exosystem state ``ξ (q,)``."""
    return gains.gamma @ xi + gains.k @ (gains.pi @ xi - x)
