"""A MEMS AHRS: the sensor-error model of seed 004 part 3 §2.5 (Luchkina, Table 1), a prescribed
flight-manoeuvre truth, raw ("before") attitude estimates and a multiplicative EKF ("after").

Frames: NED navigation frame, FRD body frame; ``R(Θ) = R_z(ψ) R_y(θ) R_x(φ)`` maps body to NED
(:mod:`jaxsim.core.rotations`), quaternions ``[w, x, y, z]`` body → NED.  SI units throughout (rad,
rad/s, m/s², µT for the magnetic field, °C).

Sensor model (per axis, constants drawn once per run by :func:`draw_constants`)::

    ω_m = ω + b_g + k_T (T − T0) + g_k + w_g         gyro: bias, temperature, Gauss–Markov, white
    f_m = (1 + s_a) f + b_a + w_a                     accelerometer: scale factor, bias, white
    m_m = (1 + s_m) m + b_m + w_m                     magnetometer: scale (incl. deviation), bias, white

with ``g_k`` the first-order Gauss–Markov sequence of :func:`gauss_markov` (exact discretisation,
stationary start): ``g_{k+1} = e^{−dt/τ} g_k + σ√(1 − e^{−2dt/τ}) w_k``, autocovariance
``σ² e^{−|Δt|/τ}`` (:func:`gauss_markov_autocovariance`).

The MEKF (:func:`mekf_run`) has 22 error states ``[δθ, c_g, g_g, b_a, b_m, s_a, s_m]`` (3 each)
and ``δV``: the body-frame attitude error ``R = R̂ exp([δθ×])``, the constant gyro bias, its
Gauss–Markov part, the accelerometer bias, the magnetometer residual bias, the accelerometer and
magnetometer (residual) scale factors, and the error of the low-passed airspeed (Gauss–Markov with the
low-pass time constant; without it the slowly varying airspeed error times the turn rate biases the
tilt and the filter is overconfident in turns).  It propagates with the gyro and updates
with the gravity direction (accelerometer minus the air-data estimate of the linear acceleration
``a_b = ω × [V, 0, 0]``) and the full magnetometer vector; an update is skipped while the norm of its
vector departs from ``g`` (or ``|m_N|``) by more than a gate (the paper's "correction limiting
during changes of the motion mode", which rejects accelerometer and magnetometer outliers).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.rotations import euler_from_rotation, quat_exp, quat_mul, rotation_from_quat, skew
from jaxsim.core.validation import check_positive, check_positive_int, check_shape

DEG = jnp.pi / 180.0
GRAVITY = 9.80665  # m/s²
MG = 1e-3 * GRAVITY  # m/s² per milli-g
NX = 22  # MEKF error states

__all__ = [
    "AhrsErrors",
    "Constants",
    "Flight",
    "MekfResult",
    "MekfTuning",
    "accel_tilt",
    "corrupt",
    "draw_constants",
    "euler_error",
    "euler_from_quat",
    "flight_truth",
    "gauss_markov",
    "gauss_markov_autocovariance",
    "mag_heading",
    "mekf_run",
    "quat_from_euler",
    "specific_force_jacobian",
    "body_rate",
    "earth_field",
    "ComplementaryGains",
    "ComplementaryResult",
    "complementary_run",
]


@pytree_dataclass
class AhrsErrors:
    """Table 1 of Luchkina (seed 004 part 3, §2.5), converted to SI; every value a 1-σ size.

    Constant errors (bias, scale factor, temperature coefficient) are drawn per run and per axis as
    zero-mean Gaussians with these σ (assumed: the table gives magnitudes "≈ …")."""

    gyro_bias: Any = 0.2 * DEG  # rad/s (≈ 0.2 °/s)
    gyro_temp_coeff: Any = 0.01 * DEG  # rad/s/°C (≈ 0.01 °/s/°C)
    gyro_white: Any = 90.0 * DEG / 3600.0  # rad/s per sample (≈ 90 °/h σ)
    gyro_gm_sigma: Any = 0.05 * DEG  # rad/s (≈ 0.05 °/s σ)
    gyro_gm_tau: Any = 300.0  # s (correlation time ≈ 300 s)
    accel_bias: Any = 5.0 * MG  # m/s² (≈ 5 mg)
    accel_scale: Any = 0.01  # (≈ 1 %)
    accel_white: Any = 1.5 * MG  # m/s² per sample (1.5 mg σ)
    mag_bias: Any = 10.0  # µT (≈ 10 µT incl. deviation)
    mag_scale: Any = 0.30  # (≈ 30 % incl. deviation)
    mag_white: Any = 0.3  # µT per sample (0.3 µT σ)
    pressure_white: Any = 130.0  # Pa per sample, static and total pressure (0.13 kPa σ)
    temperature_white: Any = 0.5  # °C per sample, indicated temperature (0.5 °C σ)


class Constants(NamedTuple):
    """Per-run constant errors, each ``(3,)``: gyro bias (rad/s), gyro temperature coefficient
    (rad/s/°C), accelerometer bias (m/s²) and scale, magnetometer bias (µT) and scale."""

    gyro_bias: jax.Array
    gyro_temp_coeff: jax.Array
    accel_bias: jax.Array
    accel_scale: jax.Array
    mag_bias: jax.Array
    mag_scale: jax.Array


def draw_constants(key: jax.Array, errors: AhrsErrors) -> Constants:
    """Zero-mean Gaussian constant errors with the σ of ``errors`` (one draw per axis)."""
    ks = jax.random.split(key, 6)
    sig = (
        errors.gyro_bias,
        errors.gyro_temp_coeff,
        errors.accel_bias,
        errors.accel_scale,
        errors.mag_bias,
        errors.mag_scale,
    )
    return Constants(*[s * jax.random.normal(k, (3,)) for s, k in zip(sig, ks)])


def gauss_markov(key: jax.Array, sigma: Any, tau: Any, dt: float, n: int, dim: int = 3) -> jax.Array:
    """First-order Gauss–Markov sequence ``(n, dim)``, stationary from the first sample (exact
    discretisation): ``x_0 ~ N(0, σ²)``, ``x_{k+1} = a x_k + σ√(1 − a²) w_k``, ``a = e^{−dt/τ}``."""
    n = check_positive_int("n", n)
    check_positive("dt", dt)
    check_positive("tau", tau)
    check_positive("sigma", sigma, allow_zero=True)
    a = jnp.exp(-dt / tau)
    k0, k1 = jax.random.split(key)
    x0 = sigma * jax.random.normal(k0, (dim,))
    w = sigma * jnp.sqrt(1.0 - a * a) * jax.random.normal(k1, (n - 1, dim))

    def step(x, wk):
        x = a * x + wk
        return x, x

    _, xs = jax.lax.scan(step, x0, w)
    return jnp.concatenate([x0[None], xs])


def gauss_markov_autocovariance(lag: Any, sigma: Any, tau: Any) -> jax.Array:
    """Closed form ``σ² e^{−|lag|/τ}`` of the stationary first-order Gauss–Markov process."""
    return sigma**2 * jnp.exp(-jnp.abs(jnp.asarray(lag, float)) / tau)


# --- the flight (truth) ---------------------------------------------------------------------------


@pytree_dataclass
class Flight:
    """A prescribed flight segment (assumed: the paper shows its Fig. 1 but gives no numbers).

    Constant airspeed ``speed`` along the body x axis (zero angle of attack and sideslip); a
    longitudinal manoeuvre (pitch up by ``pitch_amp`` and back, ``pitch_start``/``pitch_duration``)
    and a lateral one (a coordinated turn through ``turn_angle``, bank ``φ = atan(V ψ̇/g)``,
    ``turn_start``/``turn_duration``); each transition is a quintic smooth step.  Temperature falls
    linearly by ``temp_drop`` °C over ``duration``."""

    speed: Any = 50.0  # m/s
    pitch_amp: Any = 10.0 * DEG
    pitch_start: Any = 0.15  # fraction of the duration
    pitch_duration: Any = 0.2
    turn_angle: Any = 270.0 * DEG
    turn_start: Any = 0.45
    turn_duration: Any = 0.35
    heading0: Any = 30.0 * DEG
    temp0: Any = 15.0  # °C
    temp_drop: Any = 10.0  # °C over the flight
    duration: float = 600.0  # s (static)


def _smoothstep(u: jax.Array) -> jax.Array:
    u = jnp.clip(u, 0.0, 1.0)
    return u**3 * (10.0 - 15.0 * u + 6.0 * u * u)


def _euler_of_t(fl: Flight, t: jax.Array) -> jax.Array:
    T = fl.duration
    s_turn = _smoothstep((t / T - fl.turn_start) / fl.turn_duration)
    psi = fl.heading0 + fl.turn_angle * s_turn
    half = 0.5 * fl.pitch_duration
    theta = fl.pitch_amp * (
        _smoothstep((t / T - fl.pitch_start) / half) - _smoothstep((t / T - fl.pitch_start - half) / half)
    )
    psi_dot = jax.grad(lambda tt: fl.turn_angle * _smoothstep((tt / T - fl.turn_start) / fl.turn_duration))(t)
    phi = jnp.arctan(fl.speed * psi_dot / GRAVITY)
    return jnp.stack([phi, theta, psi])


def _velocity(fl: Flight, t: jax.Array) -> jax.Array:
    e = _euler_of_t(fl, t)
    th, ps = e[1], e[2]
    return fl.speed * jnp.stack([jnp.cos(th) * jnp.cos(ps), jnp.cos(th) * jnp.sin(ps), -jnp.sin(th)])


def body_rate(euler: jax.Array, euler_dot: jax.Array) -> jax.Array:
    """Body rate ``ω (3,)`` of zyx Euler angles and their rates."""
    phi, th = euler[0], euler[1]
    dphi, dth, dpsi = euler_dot[0], euler_dot[1], euler_dot[2]
    return jnp.stack(
        [
            dphi - dpsi * jnp.sin(th),
            dth * jnp.cos(phi) + dpsi * jnp.cos(th) * jnp.sin(phi),
            -dth * jnp.sin(phi) + dpsi * jnp.cos(th) * jnp.cos(phi),
        ]
    )


def flight_truth(fl: Flight, t: jax.Array) -> dict[str, jax.Array]:
    """Truth at times ``t (n,)``: ``euler (n, 3)``, body rate ``omega (n, 3)`` rad/s, specific force
    ``f (n, 3)`` (body, m/s²), body linear acceleration ``a_body (n, 3)``, temperature ``temp (n,)`` °C
    and airspeed ``speed (n,)`` m/s.
    All derivatives by forward-mode autodiff of the smooth profile (no finite differences)."""

    def one(tt):
        e, de = jax.jvp(lambda s: _euler_of_t(fl, s), (tt,), (jnp.ones_like(tt),))
        _, a_n = jax.jvp(lambda s: _velocity(fl, s), (tt,), (jnp.ones_like(tt),))
        R = rotation_from_quat(quat_from_euler(e))
        a_b = R.T @ a_n
        f = R.T @ (a_n - jnp.array([0.0, 0.0, GRAVITY]))
        return e, body_rate(e, de), f, a_b

    e, w, f, a = jax.vmap(one)(t)
    temp = fl.temp0 - fl.temp_drop * t / fl.duration
    speed = jnp.full(t.shape, 1.0) * fl.speed
    return {"euler": e, "omega": w, "f": f, "a_body": a, "temp": temp, "speed": speed}


def quat_from_euler(euler: jax.Array) -> jax.Array:
    """Quaternion of ``R_z(ψ) R_y(θ) R_x(φ)`` for ``euler = [φ, θ, ψ]`` (rad)."""
    z = jnp.zeros_like(euler[0])
    qx = quat_exp(jnp.stack([euler[0], z, z]))
    qy = quat_exp(jnp.stack([z, euler[1], z]))
    qz = quat_exp(jnp.stack([z, z, euler[2]]))
    return quat_mul(qz, quat_mul(qy, qx))


def euler_from_quat(q: jax.Array) -> jax.Array:
    """``[φ, θ, ψ]`` (rad) of a quaternion ``(4,)``."""
    return euler_from_rotation(rotation_from_quat(q))


def euler_error(est: jax.Array, true: jax.Array) -> jax.Array:
    """``est − true`` with every angle wrapped to ``(−π, π]``."""
    d = est - true
    return jnp.arctan2(jnp.sin(d), jnp.cos(d))


def earth_field(intensity: float = 50.0, inclination: float = 70.0 * DEG) -> jax.Array:
    """NED geomagnetic vector (µT), zero declination (assumed mid-latitude values)."""
    return intensity * jnp.array([jnp.cos(inclination), 0.0, jnp.sin(inclination)])


# --- sensors --------------------------------------------------------------------------------------


def corrupt(
    key: jax.Array,
    errors: AhrsErrors,
    consts: Constants,
    truth: dict[str, jax.Array],
    m_ned: jax.Array,
    dt: float,
) -> dict[str, jax.Array]:
    """Sensor outputs of Table 1 over a flight: ``gyro, accel, mag (n, 3)``, ``airspeed (n,)`` (from
    the two pressure channels: ``V = √(2 (p_t − p_s)/ρ)``, ρ = 1.1 kg/m³ assumed) and indicated
    ``temp (n,)``; also the Gauss–Markov gyro part ``gyro_gm (n, 3)``."""
    e = truth["euler"]
    n = e.shape[0]
    kg, kw, ka, km, kp, kt = jax.random.split(key, 6)
    gm = gauss_markov(kg, errors.gyro_gm_sigma, errors.gyro_gm_tau, dt, n)
    dT = truth["temp"] - truth["temp"][0]
    gyro = (
        truth["omega"]
        + consts.gyro_bias
        + consts.gyro_temp_coeff * dT[:, None]
        + gm
        + errors.gyro_white * jax.random.normal(kw, (n, 3))
    )
    accel = (
        (1.0 + consts.accel_scale) * truth["f"] + consts.accel_bias + errors.accel_white * jax.random.normal(ka, (n, 3))
    )
    Rs = jax.vmap(lambda x: rotation_from_quat(quat_from_euler(x)))(e)
    m_b = jnp.einsum("nji,j->ni", Rs, m_ned)
    mag = (1.0 + consts.mag_scale) * m_b + consts.mag_bias + errors.mag_white * jax.random.normal(km, (n, 3))
    rho = 1.1
    v_true = truth["speed"]
    qd = 0.5 * rho * v_true**2
    p_noise = errors.pressure_white * jax.random.normal(kp, (n, 2))
    speed = jnp.sqrt(jnp.maximum(2.0 * (qd + p_noise[:, 0] - p_noise[:, 1]) / rho, 0.0))
    temp = truth["temp"] + errors.temperature_white * jax.random.normal(kt, (n,))
    return {"gyro": gyro, "accel": accel, "mag": mag, "airspeed": speed, "temp": temp, "gyro_gm": gm}


def accel_tilt(f: jax.Array) -> jax.Array:
    """Roll and pitch ``(…, 2)`` from a specific force ``f (…, 3)`` taken as ``−g`` (no correction)."""
    phi = jnp.arctan2(-f[..., 1], -f[..., 2])
    theta = jnp.arctan2(f[..., 0], jnp.sqrt(f[..., 1] ** 2 + f[..., 2] ** 2))
    return jnp.stack([phi, theta], axis=-1)


def mag_heading(m: jax.Array, roll: jax.Array, pitch: jax.Array) -> jax.Array:
    """Heading (rad) from a body magnetic vector ``m (…, 3)`` levelled with ``roll, pitch``
    (zero declination): ``m_h = R_y(θ) R_x(φ) m``, ``ψ = atan2(−m_h,y, m_h,x)``."""
    cp, sp = jnp.cos(roll), jnp.sin(roll)
    ct, st = jnp.cos(pitch), jnp.sin(pitch)
    my = cp * m[..., 1] - sp * m[..., 2]
    mz = sp * m[..., 1] + cp * m[..., 2]
    mx = ct * m[..., 0] + st * mz
    return jnp.arctan2(-my, mx)


# --- the multiplicative EKF -----------------------------------------------------------------------


@pytree_dataclass
class MekfTuning:
    """Noise model of the MEKF (SI).  ``accel_sigma`` / ``mag_sigma``: per-axis measurement σ of the
    gravity (m/s²) and field (µT) vectors after the air-data correction; ``accel_gate`` /
    ``mag_gate``: the correction-limiting thresholds on the vector norms."""

    gyro_white: Any = 90.0 * DEG / 3600.0
    gyro_bias: Any = 0.2 * DEG
    gm_sigma: Any = 0.05 * DEG
    gm_tau: Any = 300.0
    accel_bias: Any = 5.0 * MG
    mag_bias: Any = 0.2
    accel_scale: Any = 0.01
    mag_scale: Any = 0.005
    accel_sigma: Any = 0.05
    mag_sigma: Any = 0.5
    attitude0: Any = 2.0 * DEG
    airspeed_sigma: Any = 0.3  # m/s, σ of the low-passed airspeed error (noise and √ bias)
    accel_gate: Any = 0.5  # m/s²: no accelerometer correction while | |f − a_b| − g | exceeds it
    mag_gate: Any = 3.0  # µT: no magnetometer correction while | |m| − |m_N| | exceeds it


class MekfResult(NamedTuple):
    """``q (n, 4)`` attitude estimates, the attitude block ``P_att (n, 3, 3)`` of the error covariance,
    the gyro bias estimate ``bias (n, 3)`` (constant + Gauss–Markov part) and the fractions of accepted
    accelerometer / magnetometer updates."""

    q: jax.Array
    P_att: jax.Array
    bias: jax.Array
    accel_accepted: jax.Array
    mag_accepted: jax.Array


def specific_force_jacobian(q: jax.Array, v_ned: jax.Array) -> jax.Array:
    """``∂(R(q exp δθ)ᵀ v)/∂δθ`` at ``δθ = 0``: ``[R(q)ᵀ v ×]`` (analytic; tested against jacfwd)."""
    return skew(rotation_from_quat(q).T @ v_ned)


def mekf_run(
    tun: MekfTuning,
    q0: jax.Array,
    gyro: jax.Array,
    accel: jax.Array,
    mag: jax.Array,
    airspeed: jax.Array,
    m_ned: jax.Array,
    dt: float,
    airspeed_tau: float = 10.0,
    update_every: int = 1,
) -> MekfResult:
    """Run the 22-state MEKF (module docstring) over gyro/accel/mag ``(n, 3)`` and ``airspeed (n,)``.

    ``airspeed`` is low-passed (first order, ``airspeed_tau`` s) before the linear-acceleration
    correction ``a_b = (ω_m − ĉ − ĝ) × [V̂, 0, 0]``.  The corrections run every ``update_every``
    samples (their residual errors are correlated in time; correcting at the full sensor rate would
    treat them as white and make the filter overconfident).  Covariance updates in Joseph form."""
    update_every = check_positive_int("update_every", update_every)
    check_shape("q0", q0, (4,))
    n = gyro.shape[0]
    for name, arr in (("accel", accel), ("mag", mag)):
        check_shape(name, arr, (n, 3))
    check_shape("airspeed", airspeed, (n,))
    check_positive("dt", dt)
    a_gm = jnp.exp(-dt / tun.gm_tau)
    a_v = jnp.exp(-dt / airspeed_tau)
    g_ned = jnp.array([0.0, 0.0, GRAVITY])
    I3 = jnp.eye(3)
    Z3 = jnp.zeros((3, 3))
    P0 = jnp.diag(
        jnp.concatenate(
            [
                jnp.full(3, tun.attitude0**2),
                jnp.full(3, tun.gyro_bias**2),
                jnp.full(3, tun.gm_sigma**2),
                jnp.full(3, tun.accel_bias**2),
                jnp.full(3, tun.mag_bias**2),
                jnp.full(3, tun.accel_scale**2),
                jnp.full(3, tun.mag_scale**2),
                jnp.full(1, tun.airspeed_sigma**2),
            ]
        )
    )
    Qd = jnp.diag(
        jnp.concatenate(
            [
                jnp.full(3, (tun.gyro_white * dt) ** 2),
                jnp.zeros(3),
                jnp.full(3, tun.gm_sigma**2 * (1.0 - a_gm**2)),
                jnp.zeros(12),
                jnp.full(1, tun.airspeed_sigma**2 * (1.0 - a_v**2)),
            ]
        )
    )
    R_a = tun.accel_sigma**2 * I3
    R_m = tun.mag_sigma**2 * I3

    def update(x, P, y, h, H, R, ok):
        S = H @ P @ H.T + R
        nu = y - h - H @ x
        K = P @ H.T @ jnp.linalg.inv(S)
        IKH = jnp.eye(NX) - K @ H
        P_new = IKH @ P @ IKH.T + K @ R @ K.T
        x = jnp.where(ok, x + K @ nu, x)
        P = jnp.where(ok, P_new, P)
        return x, 0.5 * (P + P.T), ok

    def step(carry, inp):
        q, c, g, ba, bm, sa, sm, dv, P, v_hat = carry
        w_m, f_m, m_m, v_m, k = inp
        due = k % update_every == update_every - 1
        # propagate
        w = w_m - c - g
        phi = w * dt
        q = quat_mul(q, quat_exp(phi))
        q = q / jnp.linalg.norm(q)
        g = a_gm * g
        Phi_tt = rotation_from_quat(quat_exp(phi)).T
        F = jnp.eye(NX).at[:3, :3].set(Phi_tt).at[:3, 3:9].set(jnp.concatenate([-dt * I3, -dt * I3], 1))
        F = F.at[6:9, 6:9].set(a_gm * I3).at[21, 21].set(a_v)
        dv = a_v * dv
        P = F @ P @ F.T + Qd
        v_hat = v_hat + (dt / airspeed_tau) * (v_m - v_hat)
        # accelerometer: f_m − a_b = R̂ᵀ(−g) + b_a
        w = w_m - c - g
        a_b = jnp.cross(w, jnp.array([v_hat + dv, 0.0, 0.0]))
        Rq = rotation_from_quat(q)
        x = jnp.zeros(NX)
        # the bias error also enters the air-data correction: a_b,true = â_b − (δc + δg) × v_b
        Sv = skew(jnp.array([v_hat + dv, 0.0, 0.0]))
        # f_m = (1 + s_a)∘(a_b + R̂ᵀ(−g)) + b_a
        f_hat = a_b + Rq.T @ (-g_ned)
        Da = jnp.diag(1.0 + sa)
        H_a = jnp.concatenate(
            [
                Da @ specific_force_jacobian(q, -g_ned),
                Da @ Sv,
                Da @ Sv,
                I3,
                Z3,
                jnp.diag(f_hat),
                Z3,
                (Da @ jnp.cross(w, jnp.array([1.0, 0.0, 0.0])))[:, None],
            ],
            axis=1,
        )
        ok_a = (jnp.abs(jnp.linalg.norm(f_m - a_b) - GRAVITY) <= tun.accel_gate) & due
        x, P, ok_a = update(x, P, f_m, (1.0 + sa) * f_hat + ba, H_a, R_a, ok_a)
        # m_m = (1 + s_m)∘R̂ᵀm_N + b_m
        m_hat = Rq.T @ m_ned
        Dm = jnp.diag(1.0 + sm)
        H_m = jnp.concatenate(
            [Dm @ specific_force_jacobian(q, m_ned), Z3, Z3, Z3, I3, Z3, jnp.diag(m_hat), jnp.zeros((3, 1))], axis=1
        )
        ok_m = (jnp.abs(jnp.linalg.norm(m_m) - jnp.linalg.norm(m_ned)) <= tun.mag_gate) & due
        x, P, ok_m = update(x, P, m_m, (1.0 + sm) * m_hat + bm, H_m, R_m, ok_m)
        # reset
        q = quat_mul(q, quat_exp(x[:3]))
        q = q / jnp.linalg.norm(q)
        c, g, ba, bm = c + x[3:6], g + x[6:9], ba + x[9:12], bm + x[12:15]
        sa, sm, dv = sa + x[15:18], sm + x[18:21], dv + x[21]
        G = jnp.eye(NX).at[:3, :3].set(I3 - 0.5 * skew(x[:3]))
        P = G @ P @ G.T
        return (q, c, g, ba, bm, sa, sm, dv, P, v_hat), (q, P[:3, :3], c + g, ok_a, ok_m)

    z3 = jnp.zeros(3)
    carry0 = (jnp.asarray(q0, float), z3, z3, z3, z3, z3, z3, jnp.zeros(()), P0, airspeed[0])
    _, (qs, Pa, bias, oka, okm) = jax.lax.scan(step, carry0, (gyro, accel, mag, airspeed, jnp.arange(n)))
    return MekfResult(qs, Pa, bias, jnp.sum(oka) / (n // update_every), jnp.sum(okm) / (n // update_every))


# --- the complementary filter ---------------------------------------------------------------------


@pytree_dataclass
class ComplementaryGains:
    """Gains of :func:`complementary_run`: crossover ``omega_c`` (rad/s) of the tilt (accelerometer)
    and heading (magnetometer) loops, and the bias-integral gain ``k_i = ki_ratio·ω_c²`` (1/s²)."""

    tilt_crossover: Any = 0.05
    heading_crossover: Any = 0.05
    ki_ratio: Any = 0.25
    accel_gate: Any = 0.5


class ComplementaryResult(NamedTuple):
    """``q (n, 4)`` attitude estimates and the gyro bias estimate ``bias (n, 3)`` (rad/s)."""

    q: jax.Array
    bias: jax.Array


def complementary_run(
    gains: ComplementaryGains,
    q0: jax.Array,
    gyro: jax.Array,
    accel: jax.Array,
    mag: jax.Array,
    airspeed: jax.Array,
    dt: float,
    airspeed_tau: float = 10.0,
) -> ComplementaryResult:
    """Explicit complementary filter (Mahony et al. 2008, "two position signals" of the paper) with
    gyro-bias integral, the same air-data acceleration correction and correction limiting as
    :func:`mekf_run`.  Tilt: ``ω_a = u_m × û`` with ``u_m = −(f_m − a_b)/|·|`` and ``û = R̂ᵀe_z``;
    heading: ``ω_m = (ψ_mag − ψ̂)·R̂ᵀe_z`` (magnetometer levelled with the estimated tilt).  Then
    ``ω̂ = ω_m − b̂ + ω_c,a ω_a + ω_c,m ω_m`` and ``ḃ = −k_i,a ω_a − k_i,m ω_m``."""
    check_shape("q0", q0, (4,))
    n = gyro.shape[0]
    for name, arr in (("accel", accel), ("mag", mag)):
        check_shape(name, arr, (n, 3))
    check_shape("airspeed", airspeed, (n,))
    check_positive("dt", dt)
    e_z = jnp.array([0.0, 0.0, 1.0])
    kpa, kpm = gains.tilt_crossover, gains.heading_crossover
    kia, kim = gains.ki_ratio * kpa**2, gains.ki_ratio * kpm**2

    def step(carry, inp):
        q, b, v_hat = carry
        w_m, f_m, m_m, v_m = inp
        v_hat = v_hat + (dt / airspeed_tau) * (v_m - v_hat)
        a_b = jnp.cross(w_m - b, jnp.array([v_hat, 0.0, 0.0]))
        g_b = -(f_m - a_b)
        ok = jnp.abs(jnp.linalg.norm(g_b) - GRAVITY) <= gains.accel_gate
        R = rotation_from_quat(q)
        u_hat = R.T @ e_z
        w_a = jnp.where(ok, jnp.cross(g_b / jnp.linalg.norm(g_b), u_hat), 0.0)
        e = euler_from_rotation(R)
        dpsi = mag_heading(m_m, e[0], e[1]) - e[2]
        w_h = jnp.arctan2(jnp.sin(dpsi), jnp.cos(dpsi)) * u_hat
        w = w_m - b + kpa * w_a + kpm * w_h
        b = b - dt * (kia * w_a + kim * w_h)
        q = quat_mul(q, quat_exp(w * dt))
        q = q / jnp.linalg.norm(q)
        return (q, b, v_hat), (q, b)

    carry0 = (jnp.asarray(q0, float), jnp.zeros(3), airspeed[0])
    _, (qs, bs) = jax.lax.scan(step, carry0, (gyro, accel, mag, airspeed))
    return ComplementaryResult(qs, bs)
