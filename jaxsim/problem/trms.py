"""The TRMS tracking problem (of the ``trms_lqr_tuning`` study and the ``jaxsim_trms`` env):
scenario, parametrisation, loss.

Decision vector ``θ (16,)`` — natural logarithms of ``diag Q (7)``, ``diag R (2)`` and the process-
noise intensity ``diag W (7)`` of the Kalman–Bucy observer (the measurement intensity ``V`` is
fixed by the sensor noise, since only ``W/V`` matters for the gain).

Loss of one closed-loop simulation of the *nonlinear* plant (sampled LQG tracker, noisy angle
measurements, saturated inputs) following pitch and yaw square waves:

    J = Σ_channels ∫ τ(t) |e(t)| dt  +  ρ ∫ ‖u_sat − u_eq‖² dt  +  κ ∫ Σ max(0, |u| − u_max)² dt
        + μ · max(0, ρ(Φ_cl) − (1 − margin))²

* ``τ(t)`` is the time since that channel's last reference switch (the ITAE of each step, summed
  over the steps: plain ITAE would weigh the last step of a repeated square wave the most);
* ``e = r − y`` on the true angles; ``u`` the commanded voltage, ``u_sat`` the applied one;
* the last term is the closed-loop stability constraint: ``Φ_cl`` the one-period transition of the
  sampled linear loop (:func:`~jaxsim.control.lqg_tracker.sampled_closed_loop_matrix`), whose
  spectral radius must stay below ``1 − margin``; a design whose Riccati solve fails gives NaN.

The same loss (same noise key: common random numbers) is given to every tuner.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control import lqg_tracker
from jaxsim.core.metrics import energy_integrand, itae_integrand, saturation_excess_integrand
from jaxsim.core.pytree import replace
from jaxsim.core.rollout import ClosedLoop, Timing, fold
from jaxsim.core.signals import Square
from jaxsim.plants.trms import PARAMETER_SETS, angle_sensor, hover_equilibrium, linearize_at, trms_plant

N_Q, N_R, N_W = 7, 2, 7
N_THETA = N_Q + N_R + N_W
PERTURBED = ("I1", "I2", "kc", "a1", "a2")  # the Monte-Carlo parameters (issue: ±20 %)


@dataclass(frozen=True)
class Scenario:
    """Everything a loss evaluation depends on (units: s, rad, V)."""

    parameter_set: str = "feedback_manufacturer"
    pitch_center: float = -0.05
    pitch_amplitude: float = 0.15
    pitch_period: float = 20.0
    yaw_amplitude: float = 0.2
    yaw_period: float = 30.0
    yaw_delay: float = 5.0
    t_final: float = 60.0
    ts: float = 0.01
    noise_std: float = 2e-3
    sign_smoothing: float = 0.05
    rho_energy: float = 0.01
    kappa_saturation: float = 10.0
    stability_margin: float = 1e-3
    penalty_weight: float = 1e4


class Breakdown(NamedTuple):
    """The terms of one evaluation (``total`` is the loss; the others are unweighted integrals,
    except ``stability``, the weighted constraint penalty)."""

    itae: jax.Array
    energy: jax.Array
    saturation: jax.Array
    stability: jax.Array
    total: jax.Array


class TRMSTuning:
    """Scenario-bound problem: ``loss(θ)``, ``loss_on(θ, plant_params, key, noise_std)``, bounds."""

    def __init__(self, scenario: Scenario):
        self.scenario = sc = scenario
        self.nominal = PARAMETER_SETS[sc.parameter_set]
        x_eq, u_eq, res = hover_equilibrium(self.nominal, sc.pitch_center, 0.0)
        if float(res) > 1e-9:
            raise ValueError(f"pitch_center: {sc.pitch_center} rad is outside the trim envelope")
        self.x_eq, self.u_eq = x_eq, u_eq
        self.lin = linearize_at(self.nominal, x_eq, u_eq)
        self.reference = Square(
            amplitude=jnp.array([sc.pitch_amplitude, sc.yaw_amplitude]),
            period=jnp.array([sc.pitch_period, sc.yaw_period]),
            offset=jnp.array([sc.pitch_center, 0.0]),
            t0=jnp.array([0.0, sc.yaw_delay]),
        )
        self.timing = Timing(t_final=sc.t_final, dt=sc.ts)
        self.v = jnp.eye(2) * sc.noise_std**2 * sc.ts  # continuous-equivalent intensity of sampled noise

    # ------------------------------------------------------------------ parametrisation
    def bryson_theta(self) -> np.ndarray:
        """Starting point: Bryson's rule (1/max² on angles, rates, motor states; 1/u_max² on inputs)
        and a process-noise intensity of 1e-4 on every state."""
        sc = self.scenario
        q = np.array([1 / sc.pitch_amplitude**2, 1 / sc.yaw_amplitude**2, 1, 1, 1, 1, 1])
        r = np.full(N_R, 1 / float(self.nominal.u_max) ** 2)
        w = np.full(N_W, 1e-4)
        return np.log(np.concatenate([q, r, w]))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Search box in θ: 10^[−2, 4] for Q, 10^[−3, 2] for R, 10^[−8, 0] for W."""
        lo = np.log(10.0) * np.concatenate([np.full(N_Q, -2.0), np.full(N_R, -3.0), np.full(N_W, -8.0)])
        hi = np.log(10.0) * np.concatenate([np.full(N_Q, 4.0), np.full(N_R, 2.0), np.full(N_W, 0.0)])
        return lo, hi

    @staticmethod
    def weights(theta: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
        e = jnp.exp(theta)
        return jnp.diag(e[:N_Q]), jnp.diag(e[N_Q : N_Q + N_R]), jnp.diag(e[N_Q + N_R :])

    def design(self, theta: jax.Array) -> lqg_tracker.LQGTrackerParams:
        q, r, w = self.weights(theta)
        u_max = self.nominal.u_max
        return lqg_tracker.design(self.lin, self.x_eq, self.u_eq, q, r, w, self.v, self.scenario.ts, -u_max, u_max)

    def stability_violation(self, params: lqg_tracker.LQGTrackerParams) -> jax.Array:
        """``max(0, ρ(Φ_cl) − (1 − margin))`` (zero iff feasible).

        Eigenvalue derivatives are singular at repeated eigenvalues, so the differentiated path only
        sees ``Φ_cl`` when the constraint is active (a fixed matrix with distinct eigenvalues
        stands in otherwise: the double-``where`` trick keeps NaN out of inactive gradients)."""
        phi = lqg_tracker.sampled_closed_loop_matrix(self.lin, params, self.scenario.ts)
        limit = 1.0 - self.scenario.stability_margin
        spectral_radius = lambda m: jnp.max(jnp.abs(jnp.linalg.eigvals(m)))  # noqa: E731
        active = jax.lax.stop_gradient(spectral_radius(phi)) > limit
        stand_in = jnp.diag(jnp.linspace(0.1, 0.5, phi.shape[0]))
        rho = spectral_radius(jnp.where(active, phi, stand_in))
        return jnp.where(active, rho - limit, 0.0)

    # ------------------------------------------------------------------ loss
    def plant_params(self, exact_friction: bool = False, factors: Any = None):
        """Nominal plant parameters (friction surrogate unless ``exact_friction``), with the
        ``PERTURBED`` parameters scaled by ``factors (5,)`` if given."""
        p = self.nominal if exact_friction else replace(self.nominal, sign_smoothing=self.scenario.sign_smoothing)
        if factors is None:
            return p
        return replace(p, **{name: getattr(p, name) * f for name, f in zip(PERTURBED, factors)})

    def closed_loop(self, params: lqg_tracker.LQGTrackerParams, plant_params: Any, noise_std: Any) -> ClosedLoop:
        ctrl, est = lqg_tracker.lqg_tracker(params)
        return ClosedLoop(
            trms_plant(plant_params), ctrl, reference=self.reference, sensor=angle_sensor(noise_std), estimator=est
        )

    def step_terms(self, t: jax.Array, r: jax.Array, y: jax.Array, u: jax.Array, u_max: Any) -> jax.Array:
        """Increments ``(3,)`` of ``(ITAE per step, ∫‖u_sat − u_eq‖², ∫ saturation excess²)`` over one
        controller period starting at tick time ``t`` (s), with reference ``r (2,)``, true angles
        ``y (2,)`` and commanded voltages ``u (2,)`` held over the period.  The ITAE weight of each
        axis is the time since its square wave's last switch, the wave taken as periodic for all t
        (so before the yaw wave's first switch at ``t0`` its weight is ``t − t0 + period/2``)."""
        ts, ref = self.scenario.ts, self.reference
        since_switch = jnp.mod(t - ref.t0, 0.5 * ref.period)
        u_sat = jnp.clip(u, -u_max, u_max)
        return ts * jnp.stack(
            [
                jnp.sum(itae_integrand(since_switch, r - y)),
                jnp.sum(energy_integrand(u_sat, self.u_eq)),
                jnp.sum(saturation_excess_integrand(u, u_max)),
            ]
        )

    def step_loss(self, t: jax.Array, r: jax.Array, y: jax.Array, u: jax.Array, u_max: Any) -> jax.Array:
        """The loss accrued over one controller period (the weighted :meth:`step_terms`; the loss of
        a simulation is their sum plus the stability penalty of a linear design)."""
        return self.combine(self.step_terms(t, r, y, u, u_max), 0.0).total

    def loop_terms(self, loop: ClosedLoop, key: jax.Array) -> jax.Array:
        """Sums ``(3,)`` of :meth:`step_terms` over one simulation of ``loop`` from the trim state."""
        u_max = loop.plant.params.u_max

        def running(acc, tick):
            return acc + self.step_terms(tick.t, tick.r, tick.y, tick.u, u_max)

        return fold(loop, self.x_eq, self.timing, running, jnp.zeros(3), key=key)[0]

    def rollout_terms(
        self, params: lqg_tracker.LQGTrackerParams, plant_params: Any, key: jax.Array, noise_std: Any
    ) -> jax.Array:
        """``(ITAE per step, ∫‖u_sat − u_eq‖², ∫ saturation excess²)`` of one simulation."""
        return self.loop_terms(self.closed_loop(params, plant_params, noise_std), key)

    def combine(self, terms: jax.Array, stability: Any) -> Breakdown:
        sc = self.scenario
        total = terms[0] + sc.rho_energy * terms[1] + sc.kappa_saturation * terms[2] + stability
        return Breakdown(terms[0], terms[1], terms[2], stability, total)

    def stability_penalty(self, params: lqg_tracker.LQGTrackerParams) -> jax.Array:
        return self.scenario.penalty_weight * self.stability_violation(params) ** 2

    def breakdown(
        self, theta: jax.Array, plant_params: Any = None, key: jax.Array | None = None, noise_std: Any = None
    ) -> Breakdown:
        """Every term of the loss for one simulation (defaults: nominal plant with the scenario's
        friction surrogate, the fixed noise key 0, the scenario's noise level)."""
        plant_params = self.plant_params() if plant_params is None else plant_params
        key = jax.random.PRNGKey(0) if key is None else key
        noise_std = self.scenario.noise_std if noise_std is None else noise_std
        params = self.design(theta)
        return self.combine(self.rollout_terms(params, plant_params, key, noise_std), self.stability_penalty(params))

    def loss(self, theta: jax.Array) -> jax.Array:
        """The tuning objective (nominal plant, friction surrogate, fixed noise key)."""
        return self.breakdown(theta).total
