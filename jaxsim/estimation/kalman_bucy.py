"""Continuous-time and continuous–discrete Kalman filtering.

Model ``dx = (A x + B u) dt + G dw``, ``E[dw dwᵀ] = Q_c dt``.

* Continuous–discrete (samples at discrete times): between samples the moments obey
  ``ṁ = A m + B u``, ``Ṗ = A P + P Aᵀ + G Q_c Gᵀ``; :func:`continuous_discrete_predict` integrates
  them with a fixed-step solver (RK4 by default) and the update is the discrete one.  For an LTI
  model it reproduces ``c2d_zoh``/``van_loan`` to the solver's order.
* Kalman–Bucy (continuous measurement ``dz = C x dt + dv``, ``E[dv dvᵀ] = R_c dt``):
  ``ṁ = A m + B u + K (y − C m)``, ``K = P Cᵀ R_c⁻¹``, ``Ṗ = A P + P Aᵀ + G Q_c Gᵀ − P Cᵀ R_c⁻¹ C P``
  (:func:`kalman_bucy_derivative`, :func:`kalman_bucy_step`);
  its stationary covariance solves the filter CARE: :func:`jaxsim.control.kalman_gain.kalman_bucy`
  (:func:`steady_state_kalman_bucy` is its deprecated alias).
"""

from __future__ import annotations

import warnings
from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.control.kalman_gain import kalman_bucy
from jaxsim.core.integrators import RK4, Solver
from jaxsim.core.loops import fori
from jaxsim.estimation.kalman import symmetrize
from jaxsim.estimation.types import GaussianState


def _gqg(Qc: jax.Array, G: jax.Array | None) -> jax.Array:
    return Qc if G is None else G @ Qc @ G.T


def _integrate(solver: Solver, field, z: jax.Array, dt: Any, substeps: int) -> jax.Array:
    h = jnp.asarray(dt) / substeps
    return fori(0, substeps, lambda i, x: solver.step(field, i * h, x, h), z)


def continuous_discrete_predict(
    state: GaussianState,
    A: jax.Array,
    Qc: jax.Array,
    dt: Any,
    *,
    B: jax.Array | None = None,
    u: jax.Array | None = None,
    G: jax.Array | None = None,
    substeps: int = 10,
    solver: Solver = RK4,
) -> GaussianState:
    """Integrate ``ṁ = A m + B u``, ``Ṗ = A P + P Aᵀ + G Q_c Gᵀ`` over ``dt`` (``u`` held)."""
    n = state.mean.shape[0]
    gqg = _gqg(Qc, G)
    bu = jnp.zeros((n,), state.mean.dtype) if B is None or u is None else B @ u

    def field(_, z):
        m, P = z[:n], z[n:].reshape(n, n)
        return jnp.concatenate([A @ m + bu, (A @ P + P @ A.T + gqg).ravel()])

    z = _integrate(solver, field, jnp.concatenate([state.mean, state.cov.ravel()]), dt, substeps)
    return GaussianState(z[:n], symmetrize(z[n:].reshape(n, n)))


def kalman_bucy_derivative(
    state: GaussianState,
    y: jax.Array,
    A: jax.Array,
    C: jax.Array,
    Qc: jax.Array,
    Rc: jax.Array,
    *,
    B: jax.Array | None = None,
    u: jax.Array | None = None,
    G: jax.Array | None = None,
) -> GaussianState:
    """``(ṁ, Ṗ)`` of the Kalman–Bucy filter for the measured signal ``y (p,)``."""
    m, P = state
    k = jnp.linalg.solve(Rc, C @ P).T
    dm = A @ m + k @ (y - C @ m)
    if B is not None and u is not None:
        dm = dm + B @ u
    dP = A @ P + P @ A.T + _gqg(Qc, G) - k @ Rc @ k.T
    return GaussianState(dm, symmetrize(dP))


def kalman_bucy_step(
    state: GaussianState,
    y: jax.Array,
    A: jax.Array,
    C: jax.Array,
    Qc: jax.Array,
    Rc: jax.Array,
    dt: Any,
    *,
    B: jax.Array | None = None,
    u: jax.Array | None = None,
    G: jax.Array | None = None,
    substeps: int = 1,
    solver: Solver = RK4,
) -> GaussianState:
    """Advance the Kalman–Bucy filter by ``dt`` with ``y`` and ``u`` held."""
    n = state.mean.shape[0]

    def field(_, z):
        d = kalman_bucy_derivative(GaussianState(z[:n], z[n:].reshape(n, n)), y, A, C, Qc, Rc, B=B, u=u, G=G)
        return jnp.concatenate([d.mean, d.cov.ravel()])

    z = _integrate(solver, field, jnp.concatenate([state.mean, state.cov.ravel()]), dt, substeps)
    return GaussianState(z[:n], symmetrize(z[n:].reshape(n, n)))


def steady_state_kalman_bucy(A: Any, C: Any, Qc: Any, Rc: Any, *, G: Any = None) -> tuple[jax.Array, jax.Array]:
    """Deprecated alias of :func:`jaxsim.control.kalman_gain.kalman_bucy` ``(A, C, Qc, Rc, G)`` — the
    toolkit's one steady-state Kalman–Bucy API — returning ``(P (n, n), K (n, p))`` in this order
    (``kalman_bucy`` returns the named ``KalmanBucyGain(l, p)``).  Checks and errors are
    ``kalman_bucy``'s, naming ``A, C, Qc, Rc``."""
    warnings.warn(
        "steady_state_kalman_bucy is deprecated; use jaxsim.control.kalman_gain.kalman_bucy(A, C, W, V, G) "
        "(it returns KalmanBucyGain(l, p))",
        DeprecationWarning,
        stacklevel=2,
    )
    gain = kalman_bucy(A, C, Qc, Rc, G, names=("A", "C", "Qc", "Rc"))
    return gain.p, gain.l
