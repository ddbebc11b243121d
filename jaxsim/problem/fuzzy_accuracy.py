"""The accuracy problem of the ``fuzzy_pid_accuracy`` study (seed 000, paper 1): plants, controllers
and the batched closed-loop simulation of cases.

Plants: static ``K/((T1 s+1)(T2 s+1))`` and astatic ``K/(s(T s+1))``; the disturbance enters as
``u − f``.  Controllers: linear P/PI at the maximum stability degree
(:func:`jaxsim.control.stability_degree.max_stability_degree`), the paper's three-section fuzzy P and
a fuzzy PI (assumed channels).  A *case* is one closed loop with a step + ramp reference ``g + K_g t``
and disturbance ``f + K_f t``; the cases of one plant and controller structure run in one vmapped
rollout (RK4, plant step = controller period = ``dt``, zero initial state).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control import fuzzy as fz
from jaxsim.control.fuzzy_steady_state import steady_state_error
from jaxsim.control.stability_degree import max_stability_degree
from jaxsim.core.metrics import steady_state, step_info
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Ramp, Step, Sum
from jaxsim.plants.second_order import (
    AstaticParams,
    StaticParams,
    astatic_plant,
    astatic_transfer_function,
    static_plant,
    static_transfer_function,
)
from jaxsim.problem.problem import Problem
from jaxsim.problem.reparam import Positive
from jaxsim.problem.space import Param, ParamSpace, Sorted

PLANTS = ("static", "astatic")
CONTROLLERS = ("linear P", "fuzzy P", "linear PI", "fuzzy PI")


@dataclass(frozen=True)
class AccuracySetup:
    """Plants and fuzzy characteristics (the paper's), the fuzzy PI (assumed) and the simulation."""

    K_static: float = 2.0  # paper lines 468–470
    T1: float = 0.1
    T2: float = 0.5
    K_astatic: float = 2.0  # paper line 609
    T_astatic: float = 0.1
    fc_static: tuple = (0.75, 0.3, 1.2, 1.0)  # (a, b, c, d), paper line 488
    fc_astatic: tuple = (0.2, 0.25, 1.2, 2.0)  # paper lines 619–620
    pi_p_gain_ratio: float = 1.5  # fuzzy PI, P channel: K2/K1 (assumed)
    pi_i_breakpoints: tuple = (0.05, 0.3)  # fuzzy PI, I channel: (a_i, c_i) (assumed)
    pi_i_gain_ratio: float = 2.0  # fuzzy PI, I channel: K2/K1 (assumed)
    dt: float = 1e-3  # s, plant step and controller period
    t_final: float = 20.0  # s: the slowest grid case (fuzzy PI, f = 2.5 and ramps) needs ~15 s
    drift_window: float = 1.0  # s: a steady state must not drift over the last window
    drift_rtol: float = 1e-6


def designs(cfg: AccuracySetup) -> dict[tuple[str, str], dict[str, float]]:
    """Maximum-stability-degree P and PI gains for both plants (computed)."""
    tfs = {
        "static": static_transfer_function(StaticParams(cfg.K_static, cfg.T1, cfg.T2)),
        "astatic": astatic_transfer_function(AstaticParams(cfg.K_astatic, cfg.T_astatic)),
    }
    out = {}
    for plant, (num, den) in tfs.items():
        for structure in ("P", "PI"):
            out[(plant, structure)] = max_stability_degree(np.asarray(num), np.asarray(den), structure).gains
    return out


def channels(cfg: AccuracySetup, gains: dict, plant: str, controller: str) -> tuple[Any, Any]:
    """``(p, i)`` characteristics of one of the four controllers on one plant."""
    fc = cfg.fc_static if plant == "static" else cfg.fc_astatic
    if controller == "linear P":
        return fz.linear(gains[(plant, "P")]["kp"]), None
    if controller == "fuzzy P":
        return fz.three_section(*fc), None
    pi = gains[(plant, "PI")]
    if controller == "linear PI":
        return fz.linear(pi["kp"]), fz.linear(pi["ki"])
    a, _, c, _ = fc
    a_i, c_i = cfg.pi_i_breakpoints
    p = fz.from_gains(pi["kp"], cfg.pi_p_gain_ratio * pi["kp"], a, c)
    i = fz.from_gains(pi["ki"], cfg.pi_i_gain_ratio * pi["ki"], a_i, c_i)
    return p, i


def plant_gain(cfg: AccuracySetup, plant: str) -> float:
    """The gain ``K`` of the static or astatic plant."""
    return cfg.K_static if plant == "static" else cfg.K_astatic


def _plant(cfg: AccuracySetup, name: str):
    if name == "static":
        return static_plant(StaticParams(cfg.K_static, cfg.T1, cfg.T2))
    return astatic_plant(AstaticParams(cfg.K_astatic, cfg.T_astatic))


# ---------------------------------------------------------------------------------------------
# Batched closed-loop simulation


class Case(dict):
    """One simulation: plant, controller label, channel characteristics and the input signals."""


def make_case(
    kind: str,
    plant: str,
    controller: str,
    chars: tuple[Any, Any],
    g: float,
    f: float,
    g_slope: float = 0.0,
    f_slope: float = 0.0,
) -> Case:
    """A :class:`Case` of ``plant`` (``"static"``/``"astatic"``) with channel characteristics ``chars =
    (p, i)`` (``i`` None for a P controller), reference ``g + g_slope·t`` and disturbance ``f + f_slope·t``;
    ``kind`` groups cases for reporting."""
    p, i = chars
    return Case(kind=kind, plant=plant, controller=controller, p=p, i=i, g=g, g_slope=g_slope, f=f, f_slope=f_slope)


def with_steady_states(cfg: AccuracySetup, cases: list[Case]) -> list[Case]:
    """``cases``, each with ``op``: its analytic :class:`~jaxsim.control.fuzzy_steady_state.OperatingPoint`."""
    for c in cases:
        c["op"] = steady_state_error(
            c["plant"],
            plant_gain(cfg, c["plant"]),
            c["p"],
            c["i"],
            g=c["g"],
            g_slope=c["g_slope"],
            f=c["f"],
            f_slope=c["f_slope"],
        )
    return cases


def _stack(trees: list) -> Any:
    return jax.tree_util.tree_map(lambda *xs: np.stack([np.asarray(x, float) for x in xs]), *trees)


def simulate_cases(cfg: AccuracySetup, cases: list[Case], timing: Timing, tail: int, save_every: int):
    """Simulate cases of one plant and one controller structure in one vmapped rollout.

    Returns per case: final error, drift flag, settling time, overshoot, and decimated (t, y, u).
    """
    plant = _plant(cfg, cases[0]["plant"])
    params = _stack([fz.fuzzy_pid(c["p"], c["i"]).params for c in cases])
    template = fz.fuzzy_pid(cases[0]["p"], cases[0]["i"])
    sig = jnp.asarray([[c["g"], c["g_slope"], c["f"], c["f_slope"]] for c in cases], float)

    def one(p, s):
        ref = Sum((Step(s[0]), Ramp(s[1])))
        dist = Sum((Step(s[2]), Ramp(s[3])))
        loop = ClosedLoop(plant, dataclasses.replace(template, params=p), reference=ref, disturbance=dist)
        tr = simulate(loop, jnp.zeros(plant.n_states), timing)
        e = tr.r[:, 0] - tr.y[:, 0]
        ss = steady_state(e, tail, rtol=cfg.drift_rtol)
        info = step_info(tr.t, tr.y[:, 0])
        return (
            ss.value,
            ss.converged,
            info.settling_time,
            info.overshoot,
            tr.t[::save_every],
            tr.y[::save_every, 0],
            tr.u[::save_every, 0],
        )

    out = jax.jit(jax.vmap(one))(params, sig)
    return [tuple(np.asarray(o[k]) for o in out) for k in range(len(cases))]


def _structure_key(case: Case) -> tuple:
    return (case["plant"], jax.tree_util.tree_structure(fz.fuzzy_pid(case["p"], case["i"]).params))


def run_all(cfg: AccuracySetup, cases: list[Case], progress: Callable[..., Any]) -> None:
    """Simulate every case (grouped by plant and controller structure); results are stored in place."""
    timing = Timing(t_final=cfg.t_final, dt=cfg.dt)
    tail = max(2, int(round(cfg.drift_window / cfg.dt)))
    save_every = 10
    groups: dict[tuple, list[Case]] = {}
    for c in cases:
        groups.setdefault(_structure_key(c), []).append(c)
    for key in progress(list(groups), desc="fuzzy_pid_accuracy", unit="group"):
        group = groups[key]
        for c, res in zip(group, simulate_cases(cfg, group, timing, tail, save_every)):
            c["e_sim"], c["converged"], c["settling"], c["overshoot"], c["t"], c["y"], c["u"] = res


# ---------------------------------------------------------------------------------------------


def small_gain(char: Any) -> float:
    """``K1`` of a characteristic (the gain of a linear one)."""
    if isinstance(char, fz.Linear):
        return float(char.gain)
    return float(char.b) / float(char.a)


def mamdani_fit_problem(target: Any, e: jax.Array) -> tuple[Problem, Callable[[dict[str, Any]], Any]]:
    """Breakpoints of :func:`fz.odd_mamdani` (input ``e_bp``, output ``u_bp``, both ordered from 0,
    and the set ``width``) fitted by least squares to the characteristic ``target`` (three-section)
    on the grid ``e``; starts from ``target``'s own breakpoints.  Returns the problem and
    ``build(params) -> Mamdani controller``."""
    u_range = 1.6 * float(target.d)
    u_ref = target(e)
    a, b, c, d = (float(v) for v in (target.a, target.b, target.c, target.d))

    def build(p: dict[str, Any]) -> Any:
        return fz.odd_mamdani(p["e_bp"], p["u_bp"], p["width"], u_range=u_range, n_grid=161)

    def loss(p, draw, key):
        return jnp.mean((fz.static_characteristic(build(p), e) - u_ref) ** 2)

    space = ParamSpace(
        e_bp=Sorted(lo=1e-6, hi=10.0, init=(a, c)),
        u_bp=Sorted(lo=1e-6, hi=10.0, init=(b, d)),
        width=Param(lo=1e-6, hi=10.0, init=0.2 * d, reparam=Positive()),
    )
    return Problem.from_loss("mamdani_fit", space, loss), build
