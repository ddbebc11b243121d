"""Quartz-flexure pendulous accelerometer (force-rebalance type) — seed 004, Gnusarev (spec
seed004_part4.md B6).

The paper's chain is pendulum → angle pick-off gain ``K_du`` → regulator → torquer gain ``K_dm`` →
pendulum, with mechanical stops; it prints **no numbers**, so every value below is assumed for a
Q-Flex-class quartz pendulum (spec B6 "Toolkit": natural frequency 100–1000 Hz, range ±(10–50) g).

Pendulum (angle θ, rad; rate ω, rad/s; torquer current ``i``, A; input acceleration ``a``, m/s²)::

    J θ̈ + c θ̇ + k θ + M_stop(θ) = m_l·a − K_dm·i

with ``M_stop(θ) = k_stop·(θ − clip(θ, −θ_stop, θ_stop))`` (stiff stops beyond ``θ_stop``).  Pick-off
voltage ``v = K_du θ`` (V).  State ``x = [θ, ω]``.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass

G0 = 9.80665  # m/s² per g


@pytree_dataclass
class Params:
    """Assumed Q-Flex-class values (spec B6: "all values [assumed]")."""

    J: Any = 1.5e-8  # kg·m², proof mass 0.6 g at 5 mm (assumed)
    f_n: Any = 200.0  # Hz, open-loop natural frequency of the flexure (assumed, spec 100–1000 Hz)
    zeta: Any = 0.5  # squeeze-film damping ratio (assumed)
    m_l: Any = 3.0e-6  # kg·m, pendulosity 0.6 g × 5 mm (assumed)
    K_dm: Any = 0.0226  # N·m/A, torquer: scale factor ≈ 1.3 mA/g (assumed)
    K_du: Any = 1000.0  # V/rad, capacitive pick-off (assumed)
    theta_stop: Any = 2.0e-3  # rad, stops: 25 µm gap at ~12 mm (assumed)
    k_stop_ratio: Any = 100.0  # stop stiffness / flexure stiffness (assumed)

    @property
    def k(self) -> Any:
        """Flexure stiffness, N·m/rad: ``J (2π f_n)²``."""
        return self.J * (2 * jnp.pi * self.f_n) ** 2

    @property
    def c(self) -> Any:
        """Damping, N·m·s/rad: ``2 ζ J 2π f_n``."""
        return 2 * self.zeta * self.J * 2 * jnp.pi * self.f_n


def check_params(p: Params) -> None:
    """ValueError naming the first non-positive field (concrete input)."""
    for name in ("J", "f_n", "zeta", "m_l", "K_dm", "K_du", "theta_stop", "k_stop_ratio"):
        v = np.asarray(getattr(p, name), dtype=float)
        if not np.all(np.isfinite(v)) or np.any(v <= 0):
            raise ValueError(f"{name}: must be finite and positive, got {getattr(p, name)!r}")


def dynamics(p: Params, x: jax.Array, i: Any, a: Any) -> jax.Array:
    """``ẋ = [ω, θ̈]`` for state ``x = [θ, ω]`` (shape ``(2,)``), current ``i`` (A), acceleration ``a`` (m/s²)."""
    th, om = x[0], x[1]
    stop = p.k_stop_ratio * p.k * (th - jnp.clip(th, -p.theta_stop, p.theta_stop))
    acc = (p.m_l * a - p.K_dm * i - p.c * om - p.k * th - stop) / p.J
    return jnp.stack([om, acc])


def pickoff(p: Params, x: jax.Array) -> jax.Array:
    """Pick-off voltage ``K_du θ`` (V)."""
    return p.K_du * x[0]


def rk4_step(p: Params, x: jax.Array, i: Any, a: Any, h: Any) -> jax.Array:
    """One classical RK4 step of length ``h`` (s) with ``i``, ``a`` held."""
    f = lambda y: dynamics(p, y, i, a)  # noqa: E731
    k1 = f(x)
    k2 = f(x + 0.5 * h * k1)
    k3 = f(x + 0.5 * h * k2)
    k4 = f(x + h * k3)
    return x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def linear_model(p: Params) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
    """Inside the stops: ``A (2,2)``, ``B_i (2,1)`` (current), ``B_a (2,1)`` (acceleration), ``C (1,2)`` (volts)."""
    a = jnp.array([[0.0, 1.0], [-p.k / p.J, -p.c / p.J]])
    bi = jnp.array([[0.0], [-p.K_dm / p.J]])
    ba = jnp.array([[0.0], [p.m_l / p.J]])
    c = jnp.array([[p.K_du, 0.0]])
    return a, bi, ba, c


def scale_factor(p: Params) -> Any:
    """Rebalance current per g at null (A/g): ``m_l g0 / K_dm``."""
    return p.m_l * G0 / p.K_dm
