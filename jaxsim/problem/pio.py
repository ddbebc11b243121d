"""Operator–UAV loop for pilot-induced oscillation (PIO): human operator ``K_op·e^{−τs}`` → nonlinear
corrective device (:mod:`jaxsim.control.corrective_device`, optional) → rate-limited actuator and pitch
dynamics (:mod:`jaxsim.plants.uav_pitch`).  Seed 004, #9; spec seed004_part3.md §2.7.

One ``lax.scan`` of fixed steps ``dt``: the operator sees the pitch error ``e = θ_c − θ`` delayed by
exactly ``D = τ/dt`` steps (a ring buffer in the carry, no Padé approximation); the operator output, the
device's output and the elevator command are held over a step (zero-order hold at ``1/dt``); the filter
state, actuator and airframe integrate by RK4 within the step.  ``ncd_on`` (0 or 1, traced) selects the
device or a straight wire, so one compiled function sweeps both.  PIO is flagged when the tail of the
run still oscillates: half the peak-to-peak error over the last ``tail`` seconds above
``threshold``·amplitude (or NaN).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.control import corrective_device as ncd
from jaxsim.core.integrators import RK4
from jaxsim.plants import uav_pitch as up
from jaxsim.problem.problem import Problem
from jaxsim.problem.space import Param, ParamSpace


class Run(NamedTuple):
    """``t (T,)`` s, ``theta (T,)`` rad, ``error (T,)`` rad, ``delta (T,)`` rad elevator, ``y (T,)`` device output."""

    t: jax.Array
    theta: jax.Array
    error: jax.Array
    delta: jax.Array
    y: jax.Array


def delay_steps(tau: float, dt: float) -> int:
    """``τ/dt`` as an integer number of steps; ``ValueError`` if it is not one (to 1e-9) or ``< 1``."""
    d = tau / dt
    if not (dt > 0 and abs(d - round(d)) < 1e-9 and round(d) >= 1):
        raise ValueError(f"tau: must be a positive multiple of dt = {dt!r}, got {tau!r}")
    return int(round(d))


def simulate(
    plant: up.PitchParams,
    device: ncd.NCDParams,
    k_op: Any,
    amplitude: Any,
    ncd_on: Any = 1.0,
    *,
    t_final: float,
    dt: float,
    tau: float,
    t_step: float = 0.5,
    smooth: tuple[float, float] | None = None,
) -> Run:
    """Step command ``θ_c = amplitude`` (rad) from ``t_step``; operator gain ``k_op`` (rad of elevator command
    per rad of error); ``smooth = (ε_s, ε_a)`` uses the device's and the limits' smooth surrogates."""
    n = int(round(t_final / dt))
    d = delay_steps(tau, dt)
    if n <= d:
        raise ValueError(f"t_final: must exceed the delay {tau!r} s")
    soft = smooth is not None

    def step(carry, k):
        x, z, buf = carry
        t = k * dt
        e = jnp.where(t >= t_step - 1e-12, amplitude, 0.0) - x[2]
        u = k_op * buf[k % d]  # the error of D steps ago
        buf = buf.at[k % d].set(e)
        y = jnp.where(ncd_on > 0.5, ncd.output(device, z[0], u, smooth), u)

        def rate(_, s):
            return jnp.concatenate([up.dynamics(plant, s[:5], y, soft), ncd.filter_rate(device, s[5:], u)])  # (1,)

        s = RK4.step(rate, t, jnp.concatenate([x, z]), dt)
        return (s[:5], s[5:], buf), (t, x[2], e, x[3], y)

    init = (jnp.zeros(5), jnp.zeros(1), jnp.zeros(d))
    _, (t, theta, err, delta, y) = jax.lax.scan(step, init, jnp.arange(n))
    return Run(t, theta, err, delta, y)


def tail_swing(run: Run, tail: float) -> jax.Array:
    """Half the peak-to-peak pitch error over the last ``tail`` seconds (rad; NaN stays NaN): the amplitude
    of a sustained oscillation, small for a slow monotone approach."""
    m = run.t >= run.t[-1] - tail
    hi = jnp.max(jnp.where(m, run.error, -jnp.inf))
    lo = jnp.min(jnp.where(m, run.error, jnp.inf))
    return 0.5 * (hi - lo) + 0.0 * jnp.sum(run.error)


def is_pio(run: Run, amplitude: Any, tail: float, threshold: float = 0.1) -> jax.Array:
    """PIO (or divergence): :func:`tail_swing` above ``threshold·|amplitude|``, or not finite."""
    return ~(tail_swing(run, tail) <= threshold * jnp.abs(amplitude))


def tuning_problem(
    plant: up.PitchParams,
    k_op: float,
    amplitude: float,
    *,
    t_final: float,
    dt: float,
    tau: float,
    smooth: tuple[float, float],
) -> Problem:
    """Tune the device ``(k, T1, T2)`` at operator gain ``k_op``: loss = mean-square pitch error over the run
    (rad² → normalised by ``amplitude²``), smooth surrogates; capped at ``1e4``."""
    space = ParamSpace(
        k=Param(lo=0.2, hi=5.0, init=1.0, log=True),
        T1=Param(lo=0.002, hi=0.05, init=0.01, log=True),  # paper 0.01 s
        T2=Param(lo=0.02, hi=1.0, init=0.1, log=True),  # paper 0.1 s
    )

    def loss(p, draw, key):
        dev = ncd.NCDParams(k=p["k"], T1=p["T1"], T2=p["T2"])
        run = simulate(plant, dev, k_op, amplitude, 1.0, t_final=t_final, dt=dt, tau=tau, smooth=smooth)
        j = jnp.mean(run.error**2) / amplitude**2
        return jnp.where(jnp.isfinite(j), jnp.minimum(j, 1e4), 1e4)

    return Problem.from_loss("pio_ncd", space, loss)
