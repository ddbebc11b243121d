"""Bench calibration of a strapdown IMU on a single-axis rotary table (Parusnikov's method, as lectured by
Golovan; seed 004 part 1, B3): the 24-state linear calibration filter, its information matrix for
observability rank tests, and the covariance channel whose final trace a rotation plan is tuned on.

Frames: ENU navigation frame ``x``; instrument frame ``z``.  One cycle rotates the IMU about instrument
axis ``k`` laid horizontal along East, ``A_zx(t) = R_k(ϑ(t)) M_k`` (``M_k`` puts axis ``k`` East, the
next axis North; ``R_k`` the frame rotation of eq. 4 about ``e_k``), so ``ω_z = A_zx u_x + ω e_k`` and
``f_z = A_zx f_x`` with ``u_x = U(0, cos φ, sin φ)``, ``f_x = (0, 0, g)``.

State (eq. 13), 24 components: ``[β_x (3, rad), Δf⁰ (3, m/s²), Γ11 Γ21 Γ22 Γ31 Γ32 Γ33 (6), ν⁰ (3, rad/s),
Θ (9, row-major)]``; optionally ``τ`` (s, gyro–accelerometer time skew, eq. 17) and ``k_f`` (3, m/s²/K,
accelerometer-bias temperature coefficients, eq. 20).  Model (eqs. 11–15, the slow ENU frame)::

    β̇_x = −[u_x×] β_x + A_xz (ν⁰ + Θ ω_z) + q,          (q: gyro white noise, rad/√s)
    z_x = G β_x + A_xz (Δf⁰ + Γ f_z + k_f T + (ω_z × f_z) τ) + w,   G = [[0, −g, 0], [g, 0, 0], [0, 0, 0]]

``A_xz = A_zxᵀ``; ``w``: accelerometer white noise averaged over the step, ``R = N_a² / Δt``.  Discretised
per step by first order, ``F_k = I + A_k Δt``, ``Q = diag(N_g² Δt)`` on β (Δt ≪ the rotation period).
Everything is a pure function of per-step arrays, so the plan's rates can be differentiated through.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.rotations import skew as skew_matrix
from jaxsim.estimation import kalman
from jaxsim.estimation.types import GaussianState
from jaxsim.inertial.carousel import EARTH_RATE

GRAVITY = 9.81  # m/s² (assumed)
N_BASE = 24
# M_k: rows are the instrument axes in ENU; axis k along East, axis k+1 along North, axis k+2 Up
_BASE = jnp.array(
    [
        [[1.0, 0, 0], [0, 1, 0], [0, 0, 1]],
        [[0.0, 0, 1], [1, 0, 0], [0, 1, 0]],
        [[0.0, 1, 0], [0, 0, 1], [1, 0, 0]],
    ]
)


class Plan(NamedTuple):
    """Per-step table programme: ``axis (n,)`` int instrument axis laid East (0, 1, 2), ``rate (n,)`` rad/s
    table rate (0 = at rest), ``angle (n,)`` rad table angle ϑ, ``temperature (n,)`` K above reference."""

    axis: jax.Array
    rate: jax.Array
    angle: jax.Array
    temperature: jax.Array


def plan_from_segments(axes, rates, steps, dt: float, temperature=None) -> Plan:
    """Per-step :class:`Plan` from segments ``axes (S,)`` int, ``rates (S,)`` rad/s, ``steps (S,)`` ints
    (static); ϑ restarts at 0 in each segment.  ``temperature``: per-step array (K) or ``None`` (zero)."""
    steps = np.asarray(steps, int)
    axis = jnp.asarray(np.repeat(np.asarray(axes, int), steps))
    within = jnp.asarray(np.concatenate([np.arange(n) for n in steps]) * dt)
    rate = jnp.repeat(jnp.asarray(rates, float), steps, total_repeat_length=int(steps.sum()))
    temp = jnp.zeros(axis.shape[0]) if temperature is None else jnp.asarray(temperature, float)
    return Plan(axis, rate, rate * within, temp)


def attitude(axis: jax.Array, angle: jax.Array) -> jax.Array:
    """``A_zx (3, 3)``: instrument axis ``axis`` East, rotated by ``angle`` (rad) about it (eq. 4 for axis 0)."""
    e = jax.nn.one_hot(axis, 3)
    c, s = jnp.cos(angle), jnp.sin(angle)
    rot = c * jnp.eye(3) + (1 - c) * jnp.outer(e, e) - s * skew_matrix(e)
    return rot @ _BASE[axis]


def kinematics(axis, rate, angle, latitude: float, gravity: float = GRAVITY, earth_rate: float = EARTH_RATE):
    """``(A_zx, ω_z (rad/s), f_z (m/s²))`` at one step (eq. 5 for axis 0)."""
    A = attitude(axis, angle)
    u = earth_rate * jnp.array([0.0, jnp.cos(latitude), jnp.sin(latitude)])
    w = A @ u + rate * jax.nn.one_hot(axis, 3)
    f = A @ jnp.array([0.0, 0.0, gravity])
    return A, w, f


def n_states(skew: bool = False, thermal: bool = False) -> int:
    """24, plus 1 for the time skew ``τ``, plus 3 for the temperature coefficients ``k_f``."""
    return N_BASE + int(skew) + 3 * int(thermal)


def step_matrices(
    axis,
    rate,
    angle,
    temperature,
    latitude: float,
    dt: float,
    *,
    skew: bool = False,
    thermal: bool = False,
    gravity: float = GRAVITY,
    earth_rate: float = EARTH_RATE,
) -> tuple[jax.Array, jax.Array]:
    """``F (n, n)`` and ``H (3, n)`` of one step (eqs. 14–15, with the optional eq. 17 and 20 columns).
    ``earth_rate = 0`` gives the structural model the paper's observability argument uses."""
    A, w, f = kinematics(axis, rate, angle, latitude, gravity, earth_rate)
    Axz = A.T
    n = n_states(skew, thermal)
    u = earth_rate * jnp.array([0.0, jnp.cos(latitude), jnp.sin(latitude)])
    Fg = jnp.array([[f[0], 0, 0, 0, 0, 0], [0, f[0], f[1], 0, 0, 0], [0, 0, 0, f[0], f[1], f[2]]])
    Om = jnp.kron(jnp.eye(3), w[None, :])  # Θ ω = Om vec(Θ) (row-major)
    top = jnp.concatenate([-skew_matrix(u), jnp.zeros((3, 9)), Axz, Axz @ Om], axis=1)
    G = jnp.array([[0.0, -gravity, 0], [gravity, 0, 0], [0, 0, 0]])
    H = jnp.concatenate([G, Axz, Axz @ Fg, jnp.zeros((3, 12))], axis=1)
    extra = []
    if skew:
        extra.append((Axz @ jnp.cross(w, f))[:, None])
    if thermal:
        extra.append(Axz * temperature)
    if extra:
        H = jnp.concatenate([H, *extra], axis=1)
        top = jnp.concatenate([top, jnp.zeros((3, n - N_BASE))], axis=1)
    Acont = jnp.zeros((n, n)).at[:3].set(top)
    return jnp.eye(n) + Acont * dt, H


def model_arrays(
    plan: Plan,
    latitude: float,
    dt: float,
    *,
    skew: bool = False,
    thermal: bool = False,
    gravity: float = GRAVITY,
    earth_rate: float = EARTH_RATE,
):
    """Per-step ``F (N, n, n)``, ``H (N, 3, n)`` of a plan."""

    def fn(a, r, th, T):
        return step_matrices(
            a, r, th, T, latitude, dt, skew=skew, thermal=thermal, gravity=gravity, earth_rate=earth_rate
        )

    return jax.vmap(fn)(plan.axis, plan.rate, plan.angle, plan.temperature)


def noise(n: int, dt: float, gyro_noise: float, accel_noise: float) -> tuple[jax.Array, jax.Array]:
    """``Q (n, n)`` (gyro white noise ``N_g`` rad/√s on β over ``dt``) and ``R (3, 3) = N_a²/Δt`` (``N_a`` m/s/√s)."""
    Q = jnp.zeros((n, n)).at[jnp.arange(3), jnp.arange(3)].set(gyro_noise**2 * dt)
    return Q, jnp.eye(3) * accel_noise**2 / dt


def information(F: jax.Array, H: jax.Array, R: jax.Array) -> jax.Array:
    """Fisher information of the initial state without process noise, ``Σ_k Ψ_kᵀ Hᵀ R⁻¹ H Ψ_k``,
    ``Ψ_k = F_{k−1} ⋯ F_0`` (``Ψ_0 = I``); its rank is the number of observable directions."""
    Ri = jnp.linalg.inv(R)

    def step(carry, fh):
        psi, J = carry
        Fk, Hk = fh
        HP = Hk @ psi
        return (Fk @ psi, J + HP.T @ Ri @ HP), None

    n = F.shape[-1]
    return jax.lax.scan(step, (jnp.eye(n), jnp.zeros((n, n))), (F, H))[0][1]


def rank(J: jax.Array, scale: jax.Array, rtol: float = 1e-12) -> int:
    """Numerical rank of the information ``J`` normalised by the prior σ ``scale (n,)``: singular values
    of ``D J D`` above ``rtol`` times the largest (``D = diag(scale)``)."""
    J, scale = np.asarray(J), np.asarray(scale)
    s = np.linalg.svd(scale[:, None] * J * scale[None, :], compute_uv=False)
    return int(np.sum(s > rtol * s[0]))


def covariance_run(F: jax.Array, H: jax.Array, Q: jax.Array, R: jax.Array, P0: jax.Array) -> jax.Array:
    """Final posterior covariance ``(n, n)`` of the Kalman covariance channel (update, then predict)."""

    def step(P, fh):
        Fk, Hk = fh
        st = GaussianState(jnp.zeros(P.shape[0]), P)
        post = kalman.condition(st, jnp.zeros(3), Hk, R)[0].cov
        return kalman.propagate_covariance(post, Fk, Q), post

    return jax.lax.scan(step, P0, (F, H))[1][-1]


def gains(F: jax.Array, H: jax.Array, Q: jax.Array, R: jax.Array, P0: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Kalman gains ``(N, n, 3)`` of the linear filter (they do not depend on the data) and the final
    posterior covariance ``(n, n)``; Joseph update by :func:`jaxsim.estimation.kalman.condition`."""

    def step(P, fh):
        Fk, Hk = fh
        post = kalman.condition(GaussianState(jnp.zeros(P.shape[0]), P), jnp.zeros(3), Hk, R)[0].cov
        K = post @ Hk.T @ jnp.linalg.inv(R)  # K = P⁺ Hᵀ R⁻¹
        return kalman.propagate_covariance(post, Fk, Q), (K, post)

    K, posts = jax.lax.scan(step, P0, (F, H))[1]
    return K, posts[-1]


def run_monte_carlo(rng: np.random.Generator, n_runs: int, F, H, Q, R, P0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n_runs`` Monte-Carlo runs of the filter at once (NumPy, batched over runs; the gains, which do not
    depend on the data, from the jitted :func:`gains`): truth ``x_0 ~ N(0, P0)`` through the linear model
    with gyro noise, accelerometer-noise measurements, the filter from ``N(0, P0)``.  Returns the final
    true states ``(M, n)``, estimates ``(M, n)`` and the final posterior covariance ``(n, n)``."""
    K, P = (np.asarray(a) for a in jax.jit(gains)(F, H, Q, R, P0))
    F, H, Q, R, P0 = (np.asarray(a) for a in (F, H, Q, R, P0))
    n = P0.shape[0]
    x = rng.standard_normal((n_runs, n)) @ np.linalg.cholesky(P0).T
    m = np.zeros((n_runs, n))
    sq, LR = np.sqrt(np.diagonal(Q)), np.linalg.cholesky(R)
    for k in range(F.shape[0]):
        z = x @ H[k].T + rng.standard_normal((n_runs, 3)) @ LR.T
        m = m + (z - m @ H[k].T) @ K[k].T
        if k == F.shape[0] - 1:
            return x, m, P
        x = x @ F[k].T + rng.standard_normal((n_runs, n)) * sq
        m = m @ F[k].T
    raise ValueError("empty plan")


def normalised_trace(P: jax.Array, prior_sigma: jax.Array) -> jax.Array:
    """``tr(D⁻¹ P D⁻¹)`` with ``D = diag(prior_sigma)``: the remaining fraction of prior variance, summed."""
    return jnp.sum(jnp.diagonal(P) / prior_sigma**2)


def state_names(skew: bool = False, thermal: bool = False) -> list[str]:
    names = ["beta_E", "beta_N", "beta_U", "df0_1", "df0_2", "df0_3"]
    names += ["G11", "G21", "G22", "G31", "G32", "G33", "nu0_1", "nu0_2", "nu0_3"]
    names += [f"Th{i}{j}" for i in range(1, 4) for j in range(1, 4)]
    if skew:
        names.append("tau")
    if thermal:
        names += ["kf1", "kf2", "kf3"]
    return names
