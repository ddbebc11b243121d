"""Navigation error models of Motorin's lecture (seed 004 part 1, B4) as linear-Gaussian state-space
models, and the exact error covariance of a Kalman filter run with a wrong (assumed) model.

* Random walk observed by GNSS (eqs. 3–4): ``x_i = x_{i−1} + σ_w w_i`` (two axes), ``y_i = x_i + v_i``,
  ``v ~ N(0, σ_v² I)``.  Per axis the stationary Riccati equation has the closed form
  ``P⁻ = (q + √(q² + 4 q r))/2``, ``P⁺ = P⁻ r/(P⁻ + r)``, ``K = P⁻/(P⁻ + r)`` (``q = σ_w²``, ``r = σ_v²``):
  :func:`random_walk_steady_state`.
* Dead reckoning (eq. 6): ``x¹_{i+1} = x¹_i + V_i Δt sin K_i``, ``x²_{i+1} = x²_i + V_i Δt cos K_i``
  (:func:`dead_reckoning_track`; ``x¹`` east, ``x²`` north, ``K`` the course from north).  With measured
  ``Ṽ = V + ΔV`` and ``K̃ = K + ΔK`` the error ``δx = x̃ − x`` obeys, to first order (eq. 7, reconstructed)::

      δx¹_{i+1} = δx¹_i + Δt (ΔV_i sin K_i + V_i cos K_i ΔK_i)
      δx²_{i+1} = δx²_i + Δt (ΔV_i cos K_i − V_i sin K_i ΔK_i)

  with ``ΔV``, ``ΔK`` first-order Gauss–Markov (``φ = e^{−Δt/τ}``, ``q = σ²(1 − φ²)``; ``τ = ∞`` a random
  constant) appended to the state ``s = (δx¹, δx², ΔV, ΔK)``: :func:`dead_reckoning_error_model`.  The
  difference measurement (eq. 8) of the range to a landmark ``L`` is ``z = s(x̃) − ρ ≈ uᵀ δx + v`` with
  ``u = (x̃ − L)/|x̃ − L|`` (the Jacobian taken on the known nominal track).
* :func:`mismatched_covariance`: a Kalman filter designed on an assumed model ``(F_f, Q_f, H_f, R_f)``
  processes data of a true model ``(F, Q, H, R)``.  Its gains are deterministic, so the second moment of
  ``z = (x, x̂)`` obeys an exact linear recursion (update ``x̂⁺ = (I − K H_f) x̂⁻ + K H x + K v``, predict
  ``x̂ ← F_f x̂⁺``, ``x ← F x + w``) and the actual mean-square error of ``e = C x − x̂`` is
  ``[C, −I] Σ [C, −I]ᵀ`` — beside the covariance the filter claims.  Under the true model the two agree.

Units: metres, seconds, radians.  Covariances are float64 by the toolkit's precision convention.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.estimation import kalman, linalg
from jaxsim.estimation.lgssm import LinearGaussianSSM, at, step_params, validate_model
from jaxsim.estimation.shared_gain import covariance_sequence


def _check_positive(name: str, value: Any) -> None:
    v = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise ValueError(f"{name}: must be positive and finite, got {value!r}")


def random_walk_gnss(sigma_w: Any, sigma_v: Any, sigma_0: Any, dims: int = 2) -> LinearGaussianSSM:
    """Eqs. (3)–(4): ``F = H = I_dims``, ``Q = σ_w² I``, ``R = σ_v² I``, ``x_0 ~ N(0, σ_0² I)``.

    ``sigma_w`` (m per step: mean walking speed × Δt), ``sigma_v`` (m, GNSS error), ``sigma_0`` (m,
    initial uncertainty); concrete values are checked positive (traced ones pass, for vmap/grad)."""
    for name, v in (("sigma_w", sigma_w), ("sigma_v", sigma_v), ("sigma_0", sigma_0)):
        if not isinstance(v, jax.core.Tracer):
            _check_positive(name, v)
    if int(dims) < 1:
        raise ValueError(f"dims: must be a positive integer, got {dims!r}")
    eye = jnp.eye(dims)
    return LinearGaussianSSM(
        F=eye,
        Q=jnp.square(sigma_w) * eye,
        H=eye,
        R=jnp.square(sigma_v) * eye,
        m0=jnp.zeros(dims),
        P0=jnp.square(sigma_0) * eye,
    )


class RandomWalkSteadyState(NamedTuple):
    """Per-axis stationary Kalman filter of a random walk: ``predicted`` P⁻, ``filtered`` P⁺ (m²), ``gain`` K."""

    predicted: jax.Array
    filtered: jax.Array
    gain: jax.Array


def random_walk_steady_state(q: Any, r: Any) -> RandomWalkSteadyState:
    """Closed-form solution of ``P⁻ = P⁻ r/(P⁻ + r) + q`` for ``q = σ_w² > 0``, ``r = σ_v² > 0`` (m²)."""
    q, r = jnp.asarray(q, float), jnp.asarray(r, float)
    pm = 0.5 * (q + jnp.sqrt(q * q + 4.0 * q * r))
    return RandomWalkSteadyState(pm, pm * r / (pm + r), pm / (pm + r))


def gauss_markov(sigma: Any, tau: Any, dt: Any) -> tuple[jax.Array, jax.Array]:
    """``(φ, q) = (e^{−Δt/τ}, σ²(1 − φ²))`` of a first-order Gauss–Markov process of stationary SD ``σ``
    and correlation time ``τ`` (``τ = inf``: a random constant, ``φ = 1``, ``q = 0``)."""
    phi = jnp.exp(-jnp.asarray(dt, float) / jnp.asarray(tau, float))
    return phi, jnp.square(sigma) * (1.0 - phi * phi)


def dead_reckoning_track(start: Any, speed: Any, course: Any, dt: Any) -> jax.Array:
    """Eq. (6): positions ``(T + 1, 2)`` (east, north; m) from ``start (2,)``, ``speed (T,)`` (m/s) and
    ``course (T,)`` (rad from north), ``dt`` (s)."""
    speed, course = jnp.asarray(speed, float), jnp.asarray(course, float)
    if speed.ndim != 1 or course.shape != speed.shape:
        raise ValueError(f"speed, course: expected two (T,) arrays, got {speed.shape} and {course.shape}")
    steps = dt * speed[:, None] * jnp.stack([jnp.sin(course), jnp.cos(course)], axis=1)
    return jnp.concatenate([jnp.asarray(start, float)[None], jnp.asarray(start, float) + jnp.cumsum(steps, 0)])


def range_jacobians(track: Any, landmarks: Any) -> jax.Array:
    """Unit line-of-sight rows ``(T, L, 2)``: ``∂|x − L_j|/∂x`` at each point of ``track (T, 2)``."""
    d = jnp.asarray(track, float)[:, None, :] - jnp.asarray(landmarks, float)[None, :, :]
    return d / jnp.linalg.norm(d, axis=-1, keepdims=True)


def dead_reckoning_error_model(
    speed: Any,
    course: Any,
    dt: float,
    sigma_dv: Any,
    tau_dv: Any,
    sigma_dk: Any,
    tau_dk: Any,
    range_rows: Any,
    sigma_range: Any,
    sigma_pos0: Any,
) -> LinearGaussianSSM:
    """Eq. (7) with Gauss–Markov ``ΔV`` (SD ``sigma_dv`` m/s, ``tau_dv`` s) and ``ΔK`` (SD ``sigma_dk``
    rad, ``tau_dk`` s) appended: state ``(δx¹, δx², ΔV, ΔK)``, time-varying ``F (T, 4, 4)`` along the
    nominal ``speed (T,)``, ``course (T,)``; range differences ``H (T, L, 4)`` from ``range_rows (T, L, 2)``
    (:func:`range_jacobians`), ``R = sigma_range² I``; ``P0 = diag(σ_pos0², σ_pos0², σ_dv², σ_dk²)``.
    Parameters may be traced (a bank vmaps over ``tau_dk``)."""
    speed, course = jnp.asarray(speed, float), jnp.asarray(course, float)
    rows = jnp.asarray(range_rows, float)
    t = speed.shape[0]
    if speed.ndim != 1 or course.shape != (t,):
        raise ValueError(f"speed, course: expected two (T,) arrays, got {speed.shape} and {course.shape}")
    if rows.ndim != 3 or rows.shape[0] != t or rows.shape[2] != 2:
        raise ValueError(f"range_rows: expected shape ({t}, L, 2), got {rows.shape}")
    _check_positive("dt", dt)
    phi_v, q_v = gauss_markov(sigma_dv, tau_dv, dt)
    phi_k, q_k = gauss_markov(sigma_dk, tau_dk, dt)
    s, c = jnp.sin(course), jnp.cos(course)
    F = jnp.broadcast_to(jnp.eye(4), (t, 4, 4))
    F = F.at[:, 0, 2].set(dt * s).at[:, 0, 3].set(dt * speed * c)
    F = F.at[:, 1, 2].set(dt * c).at[:, 1, 3].set(-dt * speed * s)
    F = F.at[:, 2, 2].set(phi_v).at[:, 3, 3].set(phi_k)
    Q = jnp.diag(jnp.stack([0.0 * q_v, 0.0 * q_v, q_v, q_k]))
    n_l = rows.shape[1]
    H = jnp.concatenate([rows, jnp.zeros((t, n_l, 2))], axis=2)
    return LinearGaussianSSM(
        F=F,
        Q=Q,
        H=H,
        R=jnp.square(sigma_range) * jnp.eye(n_l),
        m0=jnp.zeros(4),
        P0=jnp.diag(
            jnp.stack([jnp.square(sigma_pos0), jnp.square(sigma_pos0), jnp.square(sigma_dv), jnp.square(sigma_dk)])
        ),
    )


class MismatchResult(NamedTuple):
    """``actual (T, n_f, n_f)``: mean-square error matrix ``E[(Cx − x̂)(Cx − x̂)ᵀ]`` of the filtered estimate
    after each update; ``claimed (T, n_f, n_f)``: the covariance the filter reports there."""

    actual: jax.Array
    claimed: jax.Array


def mismatched_covariance(
    true: LinearGaussianSSM,
    assumed: LinearGaussianSSM,
    n_steps: int,
    *,
    mask: Any = None,
    C: Any = None,
) -> MismatchResult:
    """Exact actual vs claimed error covariance of the Kalman filter of ``assumed`` on data of ``true``.

    Args:
        true: the model generating the data (``n`` states, ``p`` outputs; inputs ``B`` are not used).
        assumed: the filter's model (``n_f`` states, the same ``p`` outputs).
        n_steps: ``T``; time-varying fields of either model must have ``T`` steps.
        mask: ``(T,)`` or ``(T, p)`` availability of the measurements (default: all available).
        C: ``(n_f, n)`` map from the true state to what the filter estimates (default ``I``, needs ``n_f = n``).

    The filter's gains and ``claimed`` covariances are
    :func:`jaxsim.estimation.shared_gain.covariance_sequence`'s (``kalman_filter``'s: update with ``y_0``
    first, Joseph form); only the joint second moment is new here.
    """
    validate_model(true, n_steps)
    validate_model(assumed, n_steps)
    n, nf = true.n_states, assumed.n_states
    p = true.n_outputs
    if assumed.n_outputs != p:
        raise ValueError(f"assumed: has {assumed.n_outputs} outputs, the true model {p}")
    C = jnp.eye(n) if C is None else jnp.asarray(C, float)
    if C.shape != (nf, n):
        raise ValueError(f"C: expected shape ({nf}, {n}), got {tuple(C.shape)}")
    t = int(n_steps)
    if mask is not None and jnp.shape(mask) not in ((t,), (t, p)):
        raise ValueError(f"mask: expected shape ({t},) or ({t}, {p}), got {tuple(jnp.shape(mask))}")
    seq = covariance_sequence(assumed, t, mask=mask)  # the filter's gains and claimed covariances
    actual = _actual_mse(true, assumed, seq.gains, C)
    return MismatchResult(actual, seq.covs)


@jax.jit
def _actual_mse(true: LinearGaussianSSM, assumed: LinearGaussianSSM, gains: jax.Array, C: jax.Array) -> jax.Array:
    """Second moment of ``(x, x̂)`` through the filter's fixed gains ``(T, n_f, p)``; masked measurement
    components have zero gain columns, so the raw ``H``, ``R`` of both models can be used."""
    n, nf = true.n_states, assumed.n_states
    m0 = jnp.concatenate([true.m0, assumed.m0])
    sigma0 = jnp.outer(m0, m0).at[:n, :n].add(true.P0)
    emap = jnp.concatenate([C, -jnp.eye(nf)], axis=1)  # e = C x − x̂
    mm = linalg.matmul

    def step(sig, inp):
        k, tv_t, tv_f = inp
        H, R, F, Q = (at(true, tv_t, name) for name in ("H", "R", "F", "Q"))
        Hf, Ff = at(assumed, tv_f, "H"), at(assumed, tv_f, "F")
        a_u = jnp.block([[jnp.eye(n), jnp.zeros((n, nf))], [mm(k, H), jnp.eye(nf) - mm(k, Hf)]])
        g = jnp.concatenate([jnp.zeros((n, k.shape[1])), k], axis=0)
        sig_post = kalman.symmetrize(mm(mm(a_u, sig), a_u.T) + mm(mm(g, R), g.T))
        big_f = jax.scipy.linalg.block_diag(F, Ff)
        big_q = jax.scipy.linalg.block_diag(Q, jnp.zeros((nf, nf)))
        sig_next = kalman.symmetrize(mm(mm(big_f, sig_post), big_f.T) + big_q)
        return sig_next, kalman.symmetrize(mm(mm(emap, sig_post), emap.T))

    _, actual = jax.lax.scan(step, sigma0, (gains, step_params(true), step_params(assumed)))
    return actual


__all__ = [
    "random_walk_gnss",
    "RandomWalkSteadyState",
    "random_walk_steady_state",
    "gauss_markov",
    "dead_reckoning_track",
    "range_jacobians",
    "dead_reckoning_error_model",
    "MismatchResult",
    "mismatched_covariance",
]
