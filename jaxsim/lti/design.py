"""Optimal-control and estimation design with python-control's names, argument orders and return
values: ``lqr``/``dlqr`` → ``K, S, E``; ``lqe``/``dlqe`` → ``L, P, E``; ``care``/``dare`` → ``X, L, G``.

Thin wrappers over the toolkit's NamedTuple API, which does the solving, checking and
differentiating (implicit Riccati derivatives): :func:`jaxsim.control.lqr.lqr` / ``dlqr``,
:func:`jaxsim.control.kalman_gain.kalman_bucy` / ``discrete_kalman`` and
:func:`jaxsim.control.riccati.solve_continuous_are` / ``solve_discrete_are``.  What is added here:

* the cross weight ``N`` (``S`` in ``care``/``dare``): the input change ``u = v − R⁻¹Nᵀx`` turns the
  cost ``xᵀQx + 2xᵀNu + uᵀRu`` into one without cross term for ``A − BR⁻¹Nᵀ`` and
  ``Q − NR⁻¹Nᵀ``, with the same Riccati solution, and ``K = K̄ + R⁻¹Nᵀ``;
* the descriptor matrix ``E`` of ``care``/``dare`` (invertible): ``Ẽ = E⁻¹A``, ``B̃ = E⁻¹B`` and
  ``X = E⁻ᵀ X̃ E⁻¹`` (continuous) — the same substitution in discrete time;
* ``E``: the closed-loop eigenvalues (``eig(A − BK)``, ``eig(A − LC)``), complex ``(n,)``.

``lqe`` and ``dlqe`` take ``(A, G, C, QN, RN)`` (python-control's order) and return the predictor
gain ``L`` of ``x̂⁺ = A x̂ + B u + L (y − C x̂)`` (``dlqe``; ``L = A·K_update``) or of the
continuous observer (``lqe``), with ``P`` the steady-state (prior) error covariance.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control import kalman_gain as _kalman
from jaxsim.control import lqr as _lqr
from jaxsim.control import riccati as _riccati
from jaxsim.core.system import Plant
from jaxsim.core.validation import is_concrete
from jaxsim.lti.statespace import StateSpace, as_state_space


class LQRResult(NamedTuple):
    """``K`` ``(m, n)`` for ``u = −K x``; ``S`` ``(n, n)`` the Riccati solution; ``E`` ``(n,)`` the
    closed-loop eigenvalues."""

    K: jax.Array
    S: jax.Array
    E: jax.Array


class LQEResult(NamedTuple):
    """``L`` ``(n, p)`` the observer gain; ``P`` ``(n, n)`` the error covariance; ``E`` ``(n,)`` the
    observer eigenvalues ``eig(A − L C)``."""

    L: jax.Array
    P: jax.Array
    E: jax.Array


class RiccatiResult(NamedTuple):
    """``X`` the stabilising solution, ``L`` the closed-loop eigenvalues, ``G`` the gain."""

    X: jax.Array
    L: jax.Array
    G: jax.Array


def _f(x: Any) -> jax.Array:
    return jnp.atleast_2d(jnp.asarray(x, dtype=float))


def _is_system(x: Any) -> bool:
    return isinstance(x, (StateSpace, Plant))


def _split(args: tuple, name: str, n_mats: int) -> tuple[StateSpace | None, list]:
    """python-control's two call forms: ``(sys, ...)`` or ``(A, B[, C], ...)``."""
    if args and _is_system(args[0]):
        return as_state_space(args[0], "sys"), list(args[1:])
    if len(args) < n_mats:
        raise ValueError(f"sys: {name} expects a system or {n_mats}+ matrices, got {len(args)} arguments")
    return None, list(args)


def _cross(n: int, m: int, nn: Any, name: str) -> jax.Array | None:
    if nn is None:
        return None
    nn = _f(nn)
    if nn.shape != (n, m):
        raise ValueError(f"{name}: expected shape ({n}, {m}), got {tuple(nn.shape)}")
    return nn


def _absorb_cross(a, b, q, r, nn):
    """``(A − BR⁻¹Nᵀ, Q − NR⁻¹Nᵀ, R⁻¹Nᵀ)``; ``N = None`` leaves ``A``, ``Q`` and gives ``None``."""
    if nn is None:
        return a, q, None
    rinv_nt = jnp.linalg.solve(r, nn.T)
    q_bar = q - nn @ rinv_nt
    return a - b @ rinv_nt, 0.5 * (q_bar + q_bar.T), rinv_nt


def _lqr_args(args: tuple, kwargs: dict, name: str):
    sys, rest = _split(args, name, 4)
    if sys is not None:
        a, b = sys.a, sys.b
    else:
        a, b, *rest = rest
    if len(rest) not in (2, 3):
        raise ValueError(f"{name}: expected Q, R[, N] after the system, got {len(rest)} more arguments")
    nn = kwargs.pop("N", rest[2] if len(rest) == 3 else None)
    if kwargs:
        raise TypeError(f"{name}: unexpected keyword arguments {sorted(kwargs)}")
    a, b = _f(a), _f(b)
    return sys, a, b, _f(rest[0]), _f(rest[1]), _cross(a.shape[0], b.shape[1], nn, "N")


def lqr(*args: Any, **kwargs: Any) -> LQRResult:
    """python-control's ``lqr(A, B, Q, R[, N])`` or ``lqr(sys, Q, R[, N])`` → ``K, S, E``.

    Minimises ``∫ xᵀQx + uᵀRu + 2xᵀNu dt``; a discrete-time ``sys`` is passed to :func:`dlqr`
    (python-control does the same).  Checks and derivatives: :func:`jaxsim.control.lqr.lqr`."""
    if args and _is_system(args[0]) and as_state_space(args[0]).dt is not None:
        return dlqr(*args, **kwargs)
    _, a, b, q, r, nn = _lqr_args(args, dict(kwargs), "lqr")
    a_bar, q_bar, shift = _absorb_cross(a, b, q, r, nn)
    gain = _lqr.lqr(a_bar, b, q_bar, r)
    k = gain.k if shift is None else gain.k + shift
    return LQRResult(k, gain.p, jnp.linalg.eigvals(a - b @ k))


def dlqr(*args: Any, **kwargs: Any) -> LQRResult:
    """python-control's ``dlqr(A, B, Q, R[, N])`` or ``dlqr(sys, Q, R[, N])`` → ``K, S, E``
    (``Σ xᵀQx + uᵀRu + 2xᵀNu``; checks and derivatives: :func:`jaxsim.control.lqr.dlqr`)."""
    sys, a, b, q, r, nn = _lqr_args(args, dict(kwargs), "dlqr")
    if sys is not None and sys.dt is None:
        raise ValueError("sys: dlqr needs a discrete-time system (use lqr for a continuous one)")
    a_bar, q_bar, shift = _absorb_cross(a, b, q, r, nn)
    gain = _lqr.dlqr(a_bar, b, q_bar, r)
    k = gain.k if shift is None else gain.k + shift
    return LQRResult(k, gain.p, jnp.linalg.eigvals(a - b @ k))


def _descriptor(a: jax.Array, b: jax.Array, e: Any) -> tuple[jax.Array, jax.Array, jax.Array | None]:
    if e is None:
        return a, b, None
    e = _f(e)
    if e.shape != a.shape:
        raise ValueError(f"E: expected shape {tuple(a.shape)}, got {tuple(e.shape)}")
    if is_concrete(e) and np.linalg.cond(np.asarray(e)) > 1e12:
        raise ValueError("E: must be invertible (a singular descriptor matrix is not supported)")
    return jnp.linalg.solve(e, a), jnp.linalg.solve(e, b), e


def _riccati_args(A, B, Q, R, S, stabilizing):  # noqa: N803
    if not stabilizing:
        raise ValueError("stabilizing: only the stabilising solution is computed (stabilizing=True)")
    a, b, q = _f(A), _f(B), _f(Q)
    r = jnp.eye(b.shape[1], dtype=b.dtype) if R is None else _f(R)
    return a, b, q, r, _cross(a.shape[0], b.shape[1], S, "S")


def care(
    A: Any,
    B: Any,
    Q: Any,
    R: Any = None,
    S: Any = None,
    E: Any = None,  # noqa: N803
    stabilizing: bool = True,
) -> RiccatiResult:
    """python-control's ``care(A, B, Q, R=None, S=None, E=None)`` → ``X, L, G``: the stabilising
    solution of ``AᵀXE + EᵀXA − (EᵀXB + S)R⁻¹(BᵀXE + Sᵀ) + Q = 0``, the closed-loop eigenvalues
    and ``G = R⁻¹(BᵀXE + Sᵀ)`` (``R`` = I when omitted)."""
    a, b, q, r, s = _riccati_args(A, B, Q, R, S, stabilizing)
    at, bt, e = _descriptor(a, b, E)
    a_bar, q_bar, shift = _absorb_cross(at, bt, q, r, s)
    xt = _riccati.solve_continuous_are(a_bar, bt, q_bar, r)
    g = jnp.linalg.solve(r, bt.T @ xt + (0.0 if s is None else s.T))
    x = xt if e is None else jnp.linalg.solve(e.T, jnp.linalg.solve(e.T, xt).T).T
    return RiccatiResult(x, jnp.linalg.eigvals(at - bt @ g), g)


def dare(
    A: Any,
    B: Any,
    Q: Any,
    R: Any,
    S: Any = None,
    E: Any = None,  # noqa: N803
    stabilizing: bool = True,
) -> RiccatiResult:
    """python-control's ``dare(A, B, Q, R, S=None, E=None)`` → ``X, L, G``: the stabilising solution
    of ``AᵀXA − EᵀXE − (AᵀXB + S)(BᵀXB + R)⁻¹(BᵀXA + Sᵀ) + Q = 0``, the closed-loop eigenvalues and
    ``G = (BᵀXB + R)⁻¹(BᵀXA + Sᵀ)``."""
    a, b, q, r, s = _riccati_args(A, B, Q, R, S, stabilizing)
    at, bt, e = _descriptor(a, b, E)
    a_bar, q_bar, _ = _absorb_cross(at, bt, q, r, s)
    xt = _riccati.solve_discrete_are(a_bar, bt, q_bar, r)
    g = jnp.linalg.solve(bt.T @ xt @ bt + r, bt.T @ xt @ at + (0.0 if s is None else s.T))
    x = xt if e is None else jnp.linalg.solve(e.T, jnp.linalg.solve(e.T, xt).T).T
    return RiccatiResult(x, jnp.linalg.eigvals(at - bt @ g), g)


def _lqe_args(args: tuple, name: str):
    sys, rest = _split(args, name, 5)
    if sys is not None:
        a, g, c = sys.a, sys.b, sys.c
    else:
        a, g, c, *rest = rest
    if len(rest) == 3:
        raise ValueError("NN: the cross-covariance of the noises is not supported (nor in python-control)")
    if len(rest) != 2:
        raise ValueError(f"{name}: expected QN, RN after the system, got {len(rest)} more arguments")
    return sys, _f(a), _f(g), _f(c), _f(rest[0]), _f(rest[1])


def lqe(*args: Any) -> LQEResult:
    """python-control's ``lqe(A, G, C, QN, RN)`` or ``lqe(sys, QN, RN)`` (``G = sys.B``) → ``L, P, E``
    for ``ẋ = Ax + Bu + Gw``, ``y = Cx + v`` with noise intensities ``QN``, ``RN``; a discrete-time
    ``sys`` is passed to :func:`dlqe`.  Solved by :func:`jaxsim.control.kalman_gain.kalman_bucy`."""
    if args and _is_system(args[0]) and as_state_space(args[0]).dt is not None:
        return dlqe(*args)
    _, a, g, c, qn, rn = _lqe_args(args, "lqe")
    res = _kalman.kalman_bucy(a, c, qn, rn, g)
    return LQEResult(res.l, res.p, jnp.linalg.eigvals(a - res.l @ c))


def dlqe(*args: Any) -> LQEResult:
    """python-control's ``dlqe(A, G, C, QN, RN)`` or ``dlqe(sys, QN, RN)`` → ``L, P, E``: the
    predictor gain ``L = A K`` (``K`` the update gain of
    :func:`jaxsim.control.kalman_gain.discrete_kalman`), ``P`` the prior covariance."""
    sys, a, g, c, qn, rn = _lqe_args(args, "dlqe")
    if sys is not None and sys.dt is None:
        raise ValueError("sys: dlqe needs a discrete-time system (use lqe for a continuous one)")
    res = _kalman.discrete_kalman(a, c, qn, rn, g)
    el = a @ res.k
    return LQEResult(el, res.p_prior, jnp.linalg.eigvals(a - el @ c))
