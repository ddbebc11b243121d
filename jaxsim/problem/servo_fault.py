"""The fault-identification problem of the ``smo_fault`` study (seed 000, paper 2): the servo loop,
the reduced-order sliding-mode observer and the relative identification errors.

The loaded drive of joint 2 of a PUMA-type arm (:mod:`jaxsim.plants.servo_drive`, paper constants)
tracks ``q2* = sin t`` under the paper's PID (10, 0.5, 1); from ``t = 3 s`` viscous and dry friction
grow by 50 %.  The observer (:mod:`jaxsim.estimation.reduced_order_smo`) identifies the fault torque
``M̃(t)`` from the angle and the current.  Relative errors are ``|M̃̂ − M̃| / max|M̃|`` over
``t ≥ t_fault + settle`` (``M̃`` jumps through ±0.01 N·m at every speed reversal, so a pointwise
ratio is ill-defined there).  Units: s, rad, A, N·m.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control.pid import PIDParams, pid_init, pid_step
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Sine
from jaxsim.core.system import Controller, Sensor
from jaxsim.estimation import reduced_order_smo as smo
from jaxsim.plants import servo_drive as sd
from jaxsim.problem.problem import Problem
from jaxsim.problem.reparam import Positive
from jaxsim.problem.space import Param, ParamSpace

SPREAD_FIELDS = ("R_m", "L_m", "k_w", "k_m", "J", "k_y")


@dataclass(frozen=True)
class FaultSetup:
    """The observer (paper gains), its switching, the loop's derivative filter and the error statistics."""

    k1: float = 1e7  # paper
    k2: float = 1.0  # paper
    k3: float = 1e4  # paper
    Q: float = -1.0  # paper
    width: float = 1e-3  # rad, boundary layer ε of the smooth switch e/(|e| + ε)
    pid_derivative_filter: float = 1e-3  # s
    fault_bound: float = 0.5  # N·m, |M̃| ≤ this for the existence check
    settle: float = 0.05  # s after the fault onset before errors are counted
    switching_window: float = 5e-3  # s either side of a speed reversal (for the "excluding" metric)


def _pid_init(p, r0, y0):
    return pid_init(p, r0, y0[:1])


def _pid_step(p, s, r, y, ts, t):
    return pid_step(p, s, r, y[:1], ts, t)


def position_loop(cfg: FaultSetup, plant_params: sd.ServoParams, noise: jax.Array) -> ClosedLoop:
    """PID on the measured angle, reference ``sin t``, Gaussian sensor of std ``noise`` (2,)."""
    ctrl = Controller(
        PIDParams(kp=10.0, ki=0.5, kd=1.0, tf=cfg.pid_derivative_filter, anti_windup="none"),
        _pid_init,
        _pid_step,
        name="position_pid",
    )
    return ClosedLoop(
        sd.servo_drive_plant(plant_params),
        ctrl,
        reference=Sine(1.0, 1.0 / (2 * np.pi)),
        sensor=Sensor(params=noise, name="gaussian"),
    )  # gaussian_sensor() is not traceable


def observer(
    cfg: FaultSetup,
    gains: smo.SMOGains | None = None,
    scheme: str = "implicit_sign",
    filter_tau: float = 0.0,
    solver=None,
    check: bool = True,
) -> smo.SMOParams:
    gains = smo.SMOGains(cfg.k1, cfg.k2, cfg.k3) if gains is None else gains
    bounds = sd.sliding_bounds(sd.ServoParams(), cfg.fault_bound) if check else None
    kw = {} if solver is None else {"solver": solver}
    return smo.reduced_order_smo(
        sd.reduced_model(sd.ObserverModelParams(Q=cfg.Q)),
        gains,
        bounds=bounds,
        width=cfg.width,
        filter_tau=filter_tau,
        scheme=scheme,
        **kw,
    )


def run_once(
    cfg: FaultSetup,
    par: smo.SMOParams,
    plant_params: sd.ServoParams,
    noise: jax.Array,
    key: jax.Array,
    ts: float,
    t_final: float,
) -> dict[str, jax.Array]:
    """Simulate loop + observer; returns the time series ``t, M, M_hat, x2, v``."""
    loop = position_loop(cfg, plant_params, noise)
    tr = simulate(loop, sd.initial_state(plant_params, 0.0), Timing(t_final, ts), key=key)
    run = smo.smo_filter(par, tr.t, tr.y_meas, tr.u)
    m_true = jax.vmap(sd.fault_torque, (None, 0, 0))(plant_params, tr.x, tr.t)
    m_hat = jax.vmap(sd.fault_torque_from_estimate, (None, 0, 0))(sd.ServoParams(), tr.t, run.d_hat)
    return {"t": tr.t, "M": m_true, "M_hat": m_hat, "x2": tr.x[:, 1], "v": run.v}


def error_stats(cfg: FaultSetup, s: dict[str, jax.Array], ts: float) -> dict[str, jax.Array]:
    """Relative identification errors of a :func:`run_once` series at step ``ts`` (jittable): median,
    p99, max, max away from speed reversals, max before the fault, and the scale ``max|M̃|``."""
    t, M, M_hat, x2 = s["t"], s["M"], s["M_hat"], s["x2"]
    onset = sd.FaultParams().onset
    scale = jnp.max(jnp.where(t >= onset, jnp.abs(M), 0.0))
    rel = jnp.abs(M_hat - M) / scale
    flip = jnp.concatenate([jnp.zeros(1, bool), jnp.sign(x2[1:]) != jnp.sign(x2[:-1])])
    k = int(round(cfg.switching_window / float(ts)))
    near = jnp.convolve(flip.astype(float), jnp.ones(2 * max(k, 1) + 1), mode="same") > 0
    masked = jnp.where(t >= onset + cfg.settle, rel, jnp.nan)
    pre = (t >= 0.5) & (t < onset)
    return {
        "median": jnp.nanmedian(masked),
        "p99": jnp.nanpercentile(masked, 99.0),
        "max": jnp.nanmax(masked),
        "max_excl_switching": jnp.nanmax(jnp.where(near, jnp.nan, masked)),
        "pre_fault_max": jnp.max(jnp.where(pre, jnp.abs(M_hat), 0.0)) / scale,
        "scale": scale,
    }


def perturbed(scales: jax.Array) -> sd.ServoParams:
    base = sd.ServoParams()
    drive = dataclasses.replace(base.drive, **{f: getattr(base.drive, f) * s for f, s in zip(SPREAD_FIELDS, scales)})
    return dataclasses.replace(base, drive=drive)


def gain_tuning_problem(cfg: FaultSetup, ts: float, noise: jax.Array, keys: jax.Array, window: float) -> Problem:
    """``(k1, k3, τ)`` of the smooth surrogate with an equivalent-injection filter: mean-square
    relative identification error over ``[t_fault + settle, t_fault + window]`` s on one noisy run per
    key of ``keys`` (the plant runs are simulated once; the loss re-runs only the observer).  ``noise``:
    angle (rad) and current (A) noise stds ``(2,)``; step ``ts`` s.  Searched in log coordinates,
    unbounded (``exp``), from ``cfg``'s gains and τ = 1e-4 s."""
    onset = sd.FaultParams().onset
    loop = position_loop(cfg, sd.ServoParams(), jnp.asarray(noise, float))
    timing = Timing(round((onset + window) / ts) * ts, ts)
    trs = jax.jit(jax.vmap(lambda k: simulate(loop, sd.initial_state(sd.ServoParams(), 0.0), timing, key=k)))(keys)
    start = int(round((onset - 0.1) / ts))
    t, y, u, x = jax.tree_util.tree_map(lambda a: a[:, start:], (trs.t, trs.y_meas, trs.u, trs.x))
    m_true = jax.vmap(jax.vmap(sd.fault_torque, (None, 0, 0)), (None, 0, 0))(sd.ServoParams(), x, t)
    template = observer(cfg, scheme="smooth", filter_tau=1e-4, check=False)
    counted, scale = t[0] >= onset + cfg.settle, jnp.max(jnp.abs(m_true))

    def loss(params, draw, key):
        k1, k3, tau = params["theta"]
        par = dataclasses.replace(template, gains=smo.SMOGains(k1, cfg.k2, k3), filter_tau=tau)

        def one(t_, y_, u_, m):
            d_hat = smo.smo_filter(par, t_, y_, u_).d_hat
            m_hat = jax.vmap(sd.fault_torque_from_estimate, (None, 0, 0))(sd.ServoParams(), t_, d_hat)
            return jnp.sum(jnp.where(counted, ((m_hat - m) / scale) ** 2, 0.0)) / jnp.sum(counted)

        return jnp.mean(jax.vmap(one)(t, y, u, m_true))

    theta = Param(
        lo=(1e5, 1e2, 1e-6),
        hi=(1e9, 1e6, 1e-2),
        init=(cfg.k1, cfg.k3, 1e-4),
        log=True,
        labels=("k1", "k3", "filter_tau"),
        reparam=Positive(method="exp"),
    )
    return Problem.from_loss("smo_gains", ParamSpace(theta=theta), loss)
