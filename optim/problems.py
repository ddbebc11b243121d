"""Reference problems for tuners: classic test functions and the PID tuning problem.

* :func:`sphere`, :func:`rosenbrock`, :func:`rastrigin` — ``x`` ``(d,)`` → scalar, the
  definitions pyswarms' ``utils.functions.single_obj`` uses (minimum 0 at ``0``, ``1``, ``0``).
* :class:`PIDTuning` — the PID of the fuzzy-PID paper's static plant ``K/((T1 s+1)(T2 s+1))``
  (seed 000, paper 1: ``K = 2, T1 = 0.1, T2 = 0.5``, lines 468–470) tuned for a unit step reference
  by the smooth criterion ``J = ∫ (e² + ρ u²) dt`` over a fixed horizon.  The loop is the
  toolkit's sampled-data loop (:func:`jaxsim.core.fold`): discrete PID at period ``ts`` (P and I
  on the error, the filtered derivative ``s/(tf s + 1)`` on the measurement, no saturation), zero-
  order hold, the plant integrated by ``substeps`` RK4 steps per period; the integral is the
  rectangle rule on the ticks.  The ``ρ u²`` term keeps the optimum finite (pure ISE keeps
  improving with ever larger gains until the sampled loop goes unstable).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control.pid import PIDParams, pid
from jaxsim.core.rollout import ClosedLoop, Timing, fold
from jaxsim.core.signals import Step
from jaxsim.plants.second_order import StaticParams, static_plant


def sphere(x: jax.Array) -> jax.Array:
    """``Σ x_i²``."""
    return jnp.sum(x**2)


def rosenbrock(x: jax.Array) -> jax.Array:
    """``Σ 100 (x_{i+1} − x_i²)² + (1 − x_i)²``."""
    return jnp.sum(100.0 * (x[1:] - x[:-1] ** 2) ** 2 + (1.0 - x[:-1]) ** 2)


def rastrigin(x: jax.Array) -> jax.Array:
    """``10 d + Σ (x_i² − 10 cos 2π x_i)``."""
    return 10.0 * x.shape[0] + jnp.sum(x**2 - 10.0 * jnp.cos(2 * jnp.pi * x))


GAIN_NAMES = ("kp", "ki", "kd")


@dataclass(frozen=True)
class PIDTuning:
    """Settings of the PID tuning problem (module docstring); ``loss(gains)`` with gains ``(kp, ki, kd)``.

    Units: ``kp`` input per output unit, ``ki`` per s, ``kd`` s; ``tf``, ``ts``, ``t_final`` in s;
    ``rho`` weighs ``u²`` against ``e²``.  The default box ``lo``/``hi`` holds the optimum well inside.
    """

    K: float = 2.0
    T1: float = 0.1
    T2: float = 0.5
    tf: float = 0.05
    ts: float = 0.01
    substeps: int = 2
    t_final: float = 3.0
    rho: float = 0.01
    reference: float = 1.0
    lo: tuple[float, float, float] = (0.0, 0.0, 0.0)
    hi: tuple[float, float, float] = (20.0, 20.0, 2.0)

    @property
    def timing(self) -> Timing:
        return Timing(t_final=self.t_final, dt=self.ts / self.substeps, controller_period=self.ts)

    @property
    def n_ticks(self) -> int:
        return self.timing.resolve(None)[0]

    def closed_loop(self, gains: jax.Array) -> ClosedLoop:
        """The closed loop for gains ``(3,)`` (``kp, ki, kd``)."""
        g = jnp.asarray(gains)
        params = PIDParams(
            kp=g[0], ki=g[1], kd=g[2], tf=jnp.asarray(self.tf, g.dtype), anti_windup="none", derivative_on="measurement"
        )
        template = pid(kp=1.0, tf=self.tf, anti_windup="none", derivative_on="measurement")
        plant = static_plant(StaticParams(K=self.K, T1=self.T1, T2=self.T2))
        return ClosedLoop(
            plant, dataclasses.replace(template, params=params), reference=Step(jnp.asarray(self.reference, g.dtype))
        )

    def loss(self, gains: jax.Array) -> jax.Array:
        """``J = Σ_k (e_k² + ρ u_k²)·ts`` over the ticks of the horizon; gains ``(3,)``."""
        g = jnp.asarray(gains)
        ts, rho = self.ts, self.rho

        def add(acc: jax.Array, tick) -> jax.Array:
            e = tick.r[0] - tick.y[0]
            return acc + (e**2 + rho * tick.u[0] ** 2) * ts

        return fold(self.closed_loop(g), jnp.zeros(2, g.dtype), self.timing, add, jnp.zeros((), g.dtype))[0]

    @property
    def box(self) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(self.lo, float), np.asarray(self.hi, float)
