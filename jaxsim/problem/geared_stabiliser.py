"""Closed loops of the geared two-mass stabiliser (:mod:`jaxsim.plants.geared_stabiliser`) and their
tuning problems: the modal controller + observer with a roll internal model
(:mod:`jaxsim.control.modal_observer`) and a PID baseline (seed 004, #17; spec B7).

Both loops are simulated by one ``lax.scan`` of fixed RK4 steps over plant + controller states (the
controller is continuous, as in the paper's Simulink model).  The ship's roll is ``φ = A·sin(Ω t)``;
the error is the optical unit's angle to the horizon ``θ2``.  The backlash is exact (``eps=None``)
or smoothed (``eps`` rad, :func:`~jaxsim.plants.geared_stabiliser.smooth_dead_zone`) for gradients.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control import modal_observer as mo
from jaxsim.core.integrators import RK4
from jaxsim.plants import geared_stabiliser as gs
from jaxsim.problem.problem import Problem
from jaxsim.problem.space import Param, ParamSpace


class Run(NamedTuple):
    """Samples every ``stride`` steps: ``t (T,)`` s, ``theta (T,)`` rad (the error θ2), ``u (T,)`` N·m."""

    t: jax.Array
    theta: jax.Array
    u: jax.Array


def _scan(
    rate: Callable[[jax.Array, jax.Array], jax.Array],
    out: Callable[[jax.Array, jax.Array], tuple[jax.Array, jax.Array]],
    x0: jax.Array,
    dt: float,
    n_steps: int,
    stride: int,
    noise: jax.Array,
) -> Run:
    if n_steps % stride:
        raise ValueError(f"stride: must divide the number of steps {n_steps}, got {stride}")

    def outer(x, tv):
        t0, v = tv
        theta, u = out(t0, x, v)

        def inner(x, t):
            return RK4.step(lambda tt, xx: rate(tt, xx, v), t, x, dt), None

        x, _ = jax.lax.scan(inner, x, t0 + dt * jnp.arange(stride))
        return x, (t0, theta, u)

    t0s = dt * stride * jnp.arange(n_steps // stride)
    _, (t, theta, u) = jax.lax.scan(outer, x0, (t0s, noise))
    return Run(t, theta, u)


def sensor_noise(key: jax.Array | None, sigma: Any, n_steps: int, stride: int) -> jax.Array:
    """White angle-sensor noise ``σ·N(0, 1)`` (rad), one sample per stride held over it; zeros for ``key=None``."""
    n = n_steps // stride
    if key is None:
        return jnp.zeros(n)
    return sigma * jax.random.normal(key, (n,))


def steps_of(t_final: float, dt: float, stride: int) -> int:
    """Steps of ``dt`` in ``t_final``, rounded to a multiple of ``stride``; ``ValueError`` if non-positive."""
    if not (dt > 0 and t_final > 0):
        raise ValueError(f"t_final, dt: must be positive, got {t_final!r}, {dt!r}")
    n = int(round(t_final / dt / stride)) * stride
    if n < stride:
        raise ValueError(f"t_final: shorter than one stride ({stride}·{dt} s)")
    return n


def simulate_modal(
    plant: gs.StabiliserParams,
    design: mo.ModalDesign,
    amplitude: Any,
    omega: Any,
    *,
    t_final: float,
    dt: float,
    stride: int = 10,
    eps: Any = None,
    key: jax.Array | None = None,
    sigma: Any = 0.0,
) -> Run:
    """Plant + observer from rest; ``u = −K x̂ − C_w ŵ``; the observer measures ``θ2 + v``, ``v``
    :func:`sensor_noise` (``key``, ``sigma`` rad)."""

    def u_of(x):
        return mo.control(design, x[4:])

    def rate(t, x, v):
        u = u_of(x)
        d = gs.disturbance(plant, amplitude, omega, t)
        return jnp.concatenate([gs.dynamics(plant, x[:4], u, d, eps), mo.observer_rate(design, x[4:], u, x[0] + v)])

    n = steps_of(t_final, dt, stride)
    noise = sensor_noise(key, sigma, n, stride)
    return _scan(rate, lambda t, x, v: (x[0], u_of(x)), jnp.zeros(11), dt, n, stride, noise)


def simulate_pid(
    plant: gs.StabiliserParams,
    gains: dict[str, Any],
    amplitude: Any,
    omega: Any,
    *,
    t_final: float,
    dt: float,
    stride: int = 10,
    eps: Any = None,
    key: jax.Array | None = None,
    sigma: Any = 0.0,
) -> Run:
    """Plant + integrator from rest (the angle measured as ``θ2 + v``, :func:`sensor_noise`);
    ``u = −(kp·θ2 + ki·∫θ2 dt + kd·ω1)``: P and I on the unit's angle, the damping term on the motor speed
    ``ω1`` (a tachometer; with the derivative of the unit's own angle the undamped, non-collocated
    resonance is unstable for every gain set)."""

    def u_of(x, v):
        return -(gains["kp"] * (x[0] + v) + gains["ki"] * x[4] + gains["kd"] * x[3])

    def rate(t, x, v):
        u = u_of(x, v)
        d = gs.disturbance(plant, amplitude, omega, t)
        return jnp.concatenate([gs.dynamics(plant, x[:4], u, d, eps), x[:1] + v])

    n = steps_of(t_final, dt, stride)
    noise = sensor_noise(key, sigma, n, stride)
    return _scan(rate, lambda t, x, v: (x[0], u_of(x, v)), jnp.zeros(5), dt, n, stride, noise)


def window(run: Run, t_from: float) -> jax.Array:
    """Mask ``(T,)`` of the samples at ``t ≥ t_from`` (the steady part)."""
    return run.t >= t_from - 1e-9


def rms(run: Run, t_from: float) -> jax.Array:
    """RMS of ``θ2`` over ``t ≥ t_from`` (rad)."""
    m = window(run, t_from)
    return jnp.sqrt(jnp.sum(jnp.where(m, run.theta**2, 0.0)) / jnp.sum(m))


def peak(run: Run, t_from: float) -> jax.Array:
    """``max |θ2|`` over ``t ≥ t_from`` (rad)."""
    return jnp.max(jnp.where(window(run, t_from), jnp.abs(run.theta), 0.0))


def error_response(design: mo.ModalDesign, plant: gs.StabiliserParams, omega: Any) -> jax.Array:
    """``|θ2/d|(jω)`` rad/(N·m) of the linear (backlash-free) closed loop, disturbance torque on mass 1 to
    the error; ``ω`` array of rad/s.  Zero at the internal model's frequencies (0 and ``Ω``)."""
    a, b, c = gs.linear_model(plant)
    m = mo.closed_loop_matrix(design, a, b, c)
    bd = jnp.concatenate([b[:, 0], jnp.zeros(7)])
    cd = jnp.zeros(11).at[0].set(1.0)

    def one(w):
        return jnp.abs(cd @ jnp.linalg.solve(1j * w * jnp.eye(11) - m, bd.astype(complex)))

    return jax.vmap(one)(jnp.atleast_1d(jnp.asarray(omega, dtype=float)))


def roll_error_amplitude(design: mo.ModalDesign, plant: gs.StabiliserParams, amplitude: Any, omega: Any) -> jax.Array:
    """Steady error amplitude (rad) of the linear loop under the roll ``amplitude·sin(ω t)``: the gear-rolling
    torque amplitude ``J1(1 − 1/N)·A·ω²`` times :func:`error_response`."""
    omega = jnp.atleast_1d(jnp.asarray(omega, dtype=float))
    torque = plant.J1 * (1.0 - 1.0 / plant.gear_ratio) * amplitude * omega**2
    return torque * error_response(design, plant, omega)


def _bounded(loss: jax.Array, cap: float = 1e8) -> jax.Array:
    """``min(loss, cap)``, NaN → ``cap`` (an unstable design scores finite)."""
    return jnp.where(jnp.isfinite(loss), jnp.minimum(loss, cap), cap)


def _roll_problem(
    name: str,
    space: ParamSpace,
    run: Callable[[Any, jax.Array, jax.Array, jax.Array], Run],
    amplitudes: Any,
    omegas: Any,
    t_from: float,
) -> Problem:
    """The tuning problem shared by both controllers: ``run(params, amplitude, omega, key) -> Run``
    scored by the mean-square error over ``t ≥ t_from`` in arcmin² (:func:`_bounded`), averaged over the
    roll scenarios ``(amplitudes[i], omegas[i])``."""

    def loss(p, draw, key):
        return _bounded((rms(run(p, draw["amplitude"], draw["omega"], key), t_from) / gs.ARCMIN) ** 2)

    scenarios = {"amplitude": jnp.asarray(amplitudes, float), "omega": jnp.asarray(omegas, float)}
    return Problem.from_loss(name, space, loss, scenarios=scenarios)


def modal_problem(
    plant: gs.StabiliserParams,
    omega_model: float,
    amplitudes: Any,
    omegas: Any,
    *,
    t_final: float,
    t_from: float,
    dt: float,
    eps: float,
    sigma: float = 0.0,
    stride: int = 10,
) -> Problem:
    """Tune ``radius`` (controller Butterworth radius / ω0) and ``ratio`` (observer radius / controller
    radius): loss = mean over the roll scenarios ``(amplitudes[i], omegas[i])`` of the mean-square error
    over ``t ≥ t_from`` in arcmin² (smooth backlash, ``eps`` rad; angle-sensor noise ``sigma`` rad from the
    problem's fixed key — common random numbers — which makes faster poles cost accuracy)."""
    a, b, c = gs.linear_model(plant)
    w0 = gs.natural_frequency(plant)
    space = ParamSpace(
        radius=Param(lo=0.3, hi=2.0, init=1.0, log=True),  # × ω0 (paper: bandwidth = ω0)
        ratio=Param(lo=3.0, hi=20.0, init=10.0, log=True),  # paper: an order of magnitude faster
    )

    def run(p, amplitude, omega, key):
        design = mo.modal_design(a, b, c, omega_model, p["radius"] * w0, p["ratio"])
        return simulate_modal(
            plant, design, amplitude, omega, t_final=t_final, dt=dt, stride=stride, eps=eps, key=key, sigma=sigma
        )

    return _roll_problem("backlash_stabiliser_modal", space, run, amplitudes, omegas, t_from)


def pid_problem(
    plant: gs.StabiliserParams,
    amplitudes: Any,
    omegas: Any,
    *,
    t_final: float,
    t_from: float,
    dt: float,
    eps: float,
    sigma: float = 0.0,
    stride: int = 10,
) -> Problem:
    """Tune the PID ``(kp, ki, kd)`` (:func:`simulate_pid`) on the same loss as :func:`modal_problem`.  Start:
    a triple pole at ``ω_c = ω0/6`` of the rigid loop ``J s³ + kd s² + kp s + ki`` (``J = J1 + J2``); box: two
    decades around it.  Unstable gain sets score up to ``1e8`` (finite, so swarms can rank them)."""
    wc = float(gs.natural_frequency(plant)) / 6.0
    j = float(plant.J1 + plant.J2)
    k0 = {"kp": 3 * j * wc**2, "ki": j * wc**3, "kd": 3 * j * wc}
    space = ParamSpace(**{k: Param(lo=v / 10, hi=v * 10, init=v, log=True) for k, v in k0.items()})

    def run(p, amplitude, omega, key):
        return simulate_pid(
            plant, p, amplitude, omega, t_final=t_final, dt=dt, stride=stride, eps=eps, key=key, sigma=sigma
        )

    return _roll_problem("backlash_stabiliser_pid", space, run, amplitudes, omegas, t_from)


def roll_scenarios(
    n: int, seed: int, amp_deg: tuple[float, float], period_s: tuple[float, float]
) -> dict[str, np.ndarray]:
    """``n`` roll draws: amplitude uniform in ``amp_deg`` (degrees → rad), period uniform in ``period_s``
    (→ ω rad/s); fixed by ``seed`` (the same draws for every tuner)."""
    rng = np.random.default_rng(seed)
    amp = np.deg2rad(rng.uniform(*amp_deg, n))
    omega = 2 * np.pi / rng.uniform(*period_s, n)
    return {"amplitude": amp, "omega": omega}
