"""The fuzzy-P tuning problem of the ``fuzzy_pid_tuning`` study (seed 000, paper 1, spec §1.5).

The static plant ``K/((T1 s+1)(T2 s+1))`` under a P characteristic ``u = φ(e)`` at a set of
operating points ``(g, f)`` (reference and disturbance steps, the disturbance entering as ``u − f``),
simulated together in one vmapped rollout (RK4, plant step = controller period = ``dt``).  For a
characteristic ``char`` (any callable of :mod:`jaxsim.control.fuzzy`), :meth:`FuzzyPTuning.terms`
gives the objective and the normalised constraints

    f = mean_i Σ t·|y_i(t) − y_i(T)|·dt                     (transient ITAE, s²)
    h = [(e_i(T) − e_lin,i)/e_lin,i,                        e_ss no worse than linear K_mds
         (σ_i − σ_max)/σ_max,                               overshoot ≤ σ_max (%)
         (max_t |u| − u_max)/u_max]                         |u| ≤ u_max

with ``e_lin`` the analytic steady-state error of the linear P controller at the maximum stability
degree (:mod:`jaxsim.control.stability_degree`).  On the gradient path (``smooth=True``) the overshoot
is :func:`~jaxsim.core.metrics.soft_overshoot`, bounded by ``σ_max − 3τ`` as the surrogate reads low.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control import fuzzy as fz
from jaxsim.control.fuzzy.controller import FuzzyPIDParams, fuzzy_pid_init, fuzzy_pid_step
from jaxsim.control.fuzzy_steady_state import steady_state_error
from jaxsim.control.stability_degree import max_stability_degree
from jaxsim.core.metrics import itae_integrand, soft_overshoot, step_info
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Step
from jaxsim.core.system import Controller
from jaxsim.plants.second_order import StaticParams, static_plant, static_transfer_function
from jaxsim.problem.problem import Problem, penalised
from jaxsim.problem.space import ParamSpace, Sorted


@dataclass(frozen=True)
class FuzzyPSetup:
    """Plant, operating points, constraints and timing (paper values where the paper has them)."""

    K: float = 2.0  # static plant, paper lines 468–470
    T1: float = 0.1  # s
    T2: float = 0.5  # s
    operating_points: tuple = ((1.0, 0.0), (1.0, 0.3), (0.5, 0.4), (1.5, 0.2))  # (g, f)
    paper_fc: tuple = (0.75, 0.3, 1.2, 1.0)  # (a, b, c, d), paper line 488
    overshoot_max: float = 2.0  # %
    u_max: float = 1.5  # control units
    penalty_weight: float = 100.0
    dt: float = 2e-3  # s, plant step = controller period
    t_final: float = 6.0  # s
    overshoot_temperature: float = 0.05  # %: soft_overshoot temperature on the gradient path
    box_lo: tuple = (0.05, 0.05, 0.02, 0.0)  # search box of (a, c − a, b, d − b)
    box_hi: tuple = (1.5, 1.5, 1.0, 1.5)


class FuzzyPTuning:
    """The loop of :class:`FuzzyPSetup`, its linear references and the problems over characteristics."""

    def __init__(self, setup: FuzzyPSetup):
        self.setup = setup
        params = StaticParams(setup.K, setup.T1, setup.T2)
        self.plant = static_plant(params)
        self.timing = Timing(t_final=setup.t_final, dt=setup.dt)
        self.points = jnp.asarray(setup.operating_points, float)
        num, den = (np.asarray(v) for v in static_transfer_function(params))
        self.k_mds = max_stability_degree(num, den, "P").gains["kp"]
        self.e_lin = jnp.asarray(
            [
                steady_state_error("static", setup.K, fz.linear(self.k_mds), g=g, f=f).error
                for g, f in setup.operating_points
            ]
        )
        self.exact = jax.jit(self._exact)
        self.rollouts_jit = jax.jit(self.rollouts)

    def rollouts(self, char: Any) -> tuple[jax.Array, jax.Array, jax.Array]:
        """``(t, y, u)``, each ``(points, ticks)``: the closed loop with P characteristic ``char``."""
        ctrl = Controller(FuzzyPIDParams(p=char), fuzzy_pid_init, fuzzy_pid_step, name="fuzzy_p")

        def one(gf):
            loop = ClosedLoop(self.plant, ctrl, reference=Step(gf[0]), disturbance=Step(gf[1]))
            tr = simulate(loop, jnp.zeros(2), self.timing)
            return tr.t, tr.y[:, 0], tr.u[:, 0]

        return jax.vmap(one)(self.points)

    def terms(
        self, char: Any, smooth: bool, with_details: bool = True
    ) -> tuple[jax.Array, jax.Array, dict[str, jax.Array]]:
        """``(f, h, details)``: objective, normalised constraints (feasible: ``h ≤ 0``), per-point
        metrics (``{}`` with ``with_details=False``: a loss need not trace the settling times)."""
        s = self.setup
        t, y, u = self.rollouts(char)
        y_final = y[:, -1]
        itae = jnp.sum(itae_integrand(t, y - y_final[:, None]), axis=1) * s.dt
        e_final = self.points[:, 0] - y_final
        bound = s.overshoot_max
        if smooth:
            overshoot = jax.vmap(lambda yy, yf: soft_overshoot(yy, yf, s.overshoot_temperature))(y, y_final)
            bound = s.overshoot_max - 3.0 * s.overshoot_temperature  # the surrogate reads low
        else:
            overshoot = jax.vmap(lambda tt, yy: step_info(tt, yy).overshoot)(t, y)
        u_peak = jnp.max(jnp.abs(u))
        h = jnp.concatenate(
            [
                (e_final - self.e_lin) / self.e_lin,
                (overshoot - bound) / s.overshoot_max,
                jnp.atleast_1d((u_peak - s.u_max) / s.u_max),
            ]
        )
        if not with_details:
            return jnp.mean(itae), h, {}
        settling = jax.vmap(lambda tt, yy: step_info(tt, yy).settling_time)(t, y)
        details = dict(itae=itae, overshoot=overshoot, e_final=e_final, u_peak=u_peak, settling=settling)
        return jnp.mean(itae), h, details

    def penalised(self, char: Any) -> jax.Array:
        """``J = f + (w/2)·Σ max(0, h)²`` with the exact characteristic and overshoot."""
        return self._exact(char)[0]

    def _exact(self, char: Any) -> tuple[jax.Array, tuple[jax.Array, jax.Array, dict[str, jax.Array]]]:
        """``(J, (f, h, details))`` of the exact characteristic from one set of rollouts."""
        f, h, details = self.terms(char, smooth=False)
        return penalised(f, h, self.setup.penalty_weight), (f, h, details)

    def problem(self, name: str, space: ParamSpace, char_of: Callable[[Any], Any], smooth: bool) -> Problem:
        """Objective ``f`` and constraints ``h`` of the characteristic ``char_of(params)``, from one
        set of rollouts (:meth:`~jaxsim.problem.Problem.from_terms`)."""
        return Problem.from_terms(
            name,
            space,
            lambda p: self.terms(char_of(p), smooth, with_details=False)[:2],
            penalty_weight=self.setup.penalty_weight,
        )

    def three_section_space(self) -> ParamSpace:
        """``e = (a, c)``, ``u = (b, d)`` from the paper's controller, searched in ``(a, c − a, b, d − b)``."""
        a, b, c, d = self.setup.paper_fc
        lo, hi = self.setup.box_lo, self.setup.box_hi
        return ParamSpace(
            e=Sorted(lo=lo[:2], hi=hi[:2], init=(a, c), min_gap=0.02), u=Sorted(lo=lo[2:], hi=hi[2:], init=(b, d))
        )


def three_section_of(params: dict, temperature: float, form: str) -> fz.ThreeSection:
    """``{"e": [a, c], "u": [b, d]}`` → the three-section characteristic in ``form`` (exact/smooth)."""
    return fz.ThreeSection(params["e"][0], params["u"][0], params["e"][1], params["u"][1], temperature, form)
