"""3-DOF (surge, sway, yaw) manoeuvring ship: a substitute for the vessel of seed 000, paper 6.

The paper's vessel is a "full nonlinear 6-DOF model of a small surface landing vessel" (its ref. [31])
whose equations and parameters are **not given**.  We substitute a public linear manoeuvring model:

* sway–yaw: the linear part of the Mariner-class model (L = 160.93 m, U0 = 7.7175 m/s; hydrodynamic
  derivatives of Chislett & Strøm-Tejsen 1965, as tabulated in Fossen's Marine Systems Simulator,
  ``mariner.m``), in the non-dimensional "prime" system ``v' = v/U0``, ``r' = rL/U0``,
  ``t' = tU0/L``:

  ```text
  [m' − Y'v̇    m'x'G − Y'ṙ] [v̇']   [Y'v  Y'r] [v']   [Y'δ]
  [m'x'G − N'v̇  I'z − N'ṙ ] [ṙ'] = [N'v  N'r] [r'] + [N'δ] δ
  ```

* surge: ``(m' − X'u̇) u̇' = X'u (u' − u'_c)``, a first-order response of the speed perturbation ``u``
  to the commanded perturbation ``u_c`` (the engine-speed control, our assumption; time constant
  ``(m' − X'u̇)/(−X'u)·L/U0 ≈ 95 s``);
* rudder servo ``δ̇ = (δ_c − δ)/T_δ`` (``T_δ = 1 s`` as in ``mariner.m``, without its rate limit);
* kinematics: ``ẋ = (U0 + u) cos ψ − v sin ψ``, ``ẏ = (U0 + u) sin ψ + v cos ψ``, ``ψ̇ = r``.

State ``[x, y, ψ, u, v, r, δ]`` (m, m, rad, m/s, m/s, rad/s, rad); input ``[δ_c, u_c]`` (rad, m/s);
output ``[x, y, ψ]``.  Only the kinematics are nonlinear (``cos ψ``, ``sin ψ``), which is what a
model-free *linear* predictor has to cope with.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.system import Plant
from jaxsim.core.validation import check_finite, check_positive


@pytree_dataclass
class ShipParams:
    """Mariner-class linear derivatives (×1e-5 values of ``mariner.m``), main dimensions, servo."""

    L: Any = 160.93  # m
    U0: Any = 7.7175  # m/s
    m: Any = 798e-5
    Iz: Any = 39.2e-5
    xG: Any = -0.023
    Xudot: Any = -42e-5
    Xu: Any = -184e-5
    Yvdot: Any = -748e-5
    Yrdot: Any = -9.354e-5
    Nvdot: Any = 4.646e-5
    Nrdot: Any = -43.8e-5
    Yv: Any = -1160e-5
    Yr: Any = -499e-5
    Nv: Any = -264e-5
    Nr: Any = -166e-5
    Yd: Any = 278e-5
    Nd: Any = -139e-5
    T_rudder: Any = 1.0  # s


def sway_yaw_matrices(p: ShipParams) -> tuple[jax.Array, jax.Array]:
    """Dimensional ``(A, b)`` of ``[v̇, ṙ] = A [v, r] + b δ`` (SI units)."""
    M = jnp.array([[p.m - p.Yvdot, p.m * p.xG - p.Yrdot], [p.m * p.xG - p.Nvdot, p.Iz - p.Nrdot]])
    a_nd = jnp.linalg.solve(M, jnp.array([[p.Yv, p.Yr], [p.Nv, p.Nr]]))
    b_nd = jnp.linalg.solve(M, jnp.array([p.Yd, p.Nd]))
    U, L = p.U0, p.L  # v = U v', r = (U/L) r', d/dt = (U/L) d/dt'
    A = jnp.array([[a_nd[0, 0] * U / L, a_nd[0, 1] * U], [a_nd[1, 0] * U / L**2, a_nd[1, 1] * U / L]])
    b = jnp.array([b_nd[0] * U**2 / L, b_nd[1] * U**2 / L**2])
    return A, b


def dynamics(p: ShipParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ`` for state ``[x, y, ψ, u, v, r, δ]`` and input ``[δ_c, u_c]``."""
    _, _, psi, du, v, r, delta = (x[i] for i in range(7))
    A, b = sway_yaw_matrices(p)
    vr = A @ jnp.stack([v, r]) + b * delta
    surge_rate = p.Xu / (p.m - p.Xudot) * (p.U0 / p.L) * (du - u[1])
    speed = p.U0 + du
    return jnp.stack(
        [
            speed * jnp.cos(psi) - v * jnp.sin(psi),
            speed * jnp.sin(psi) + v * jnp.cos(psi),
            r,
            surge_rate,
            vr[0],
            vr[1],
            (u[0] - delta) / p.T_rudder,
        ]
    )


def output(p: ShipParams, x: jax.Array) -> jax.Array:
    """``[x, y, ψ]`` (m, m, rad)."""
    return x[:3]


def ship_plant(params: ShipParams | None = None) -> Plant:
    """The ship as a :class:`~jaxsim.core.system.Plant` (7 states, 2 inputs, 3 outputs)."""
    p = ShipParams() if params is None else params
    for name in ("L", "U0", "m", "Iz", "T_rudder"):
        check_positive(name, getattr(p, name))
    check_finite("params", p)
    return Plant(p, dynamics, output, n_states=7, n_inputs=2, n_outputs=3, name="ship_3dof_mariner")
