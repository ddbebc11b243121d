"""Ball on a swing (ball and beam on a motor shaft) with its full, unsimplified dynamics (seed 004
part 1 §B10, Tsarik/Gusev).

A straight beam is fixed on a motor shaft (beam angle ``θ`` to the horizon, inertia ``J_f``); a ball
(mass ``m``, radius ``r``, inertia ``J_b``) rolls on it without slipping.  The beam's surface is at
distance ``d − r`` from the shaft axis, so the ball centre runs on a line at distance ``d`` from the
axis in the beam frame (``d = r``: the surface passes through the axis, the paper's ``ρ = R/cos φ``).
With ``φ`` the centre's polar angle in the beam frame (from the beam normal) the along-beam coordinate
is ``s = d tan φ`` and the centre's distance from the axis ``ρ(φ) = d / cos φ``.

Generalised coordinates ``q = (θ, φ)`` (rad), state ``x = (θ, φ, θ̇, φ̇)``, input: motor torque ``u``
(N·m) on ``θ``.  Energies (SI units, gravity along world ``−y``):

    p = Rot(θ) (s, d)                         ball centre in the world (m)
    T = ½ J_f θ̇² + ½ m |ṗ|² + ½ J_b (θ̇ − ṡ/r)²   (rolling: the ball turns by −ds/r relative to the beam)
    V = m g p_y = m g (s sin θ + d cos θ)

and the equations of motion are written out in closed form (:func:`mass_and_bias`), checked in the
tests against :func:`jaxsim.core.lagrangian.euler_lagrange` (autodiff of ``T`` and ``V``).

The virtual holonomic constraint ``θ = kφ`` reduces the unactuated row to the αβγ-equation
``α(φ) φ̈ + β(φ) φ̇² + γ(φ) = 0`` whose integral is

    I(φ, φ̇) = Ψ(φ) φ̇² + W(φ),   Ψ(φ) = exp(2∫₀^φ β/α),   W(φ) = ∫₀^φ 2Ψγ/α

(Gauss–Legendre quadrature; ``d/dt[Ψφ̇²] = −2Ψγφ̇/α`` along solutions).  :func:`orbit` finds the
periodic solution through ``(φ_a, 0)``; :func:`transverse_linearisation` the coefficients of
``ẋ⊥ = A(t) x⊥ + B(t) v`` for ``x⊥ = (I − I*, y, ẏ)``, ``y = θ − kφ``, ``v = ÿ``.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.integrators import RK4_ROLLED
from jaxsim.core.pytree import pytree_dataclass

_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(12)
_GL_X = 0.5 * (_GL_NODES + 1.0)  # nodes on [0, 1]
_GL_W = 0.5 * _GL_WEIGHTS


@pytree_dataclass
class Params:
    """Physical parameters (SI).  All ASSUMED: the paper gives symbols only (spec §B10).

    ``m`` ball mass (kg), ``r`` ball radius (m), ``j_b`` ball inertia (kg·m²; ``None`` → solid sphere
    ``2/5 m r²``), ``j_f`` beam + shaft inertia (kg·m²), ``d`` distance of the ball-centre line from the
    shaft axis (m; ``None`` → ``r``, the paper's ``ρ = R/cos φ``), ``g`` (m/s²).
    """

    m: Any = 0.1
    r: Any = 0.025
    j_b: Any = None
    j_f: Any = 0.01
    d: Any = None
    g: Any = 9.81

    def ball_inertia(self):
        return 0.4 * self.m * self.r**2 if self.j_b is None else self.j_b

    def height(self):
        return self.r if self.d is None else self.d


def _check(p: Params) -> None:
    for name in ("m", "r", "j_f", "g"):
        v = getattr(p, name)
        if isinstance(v, (int, float)) and not v > 0:
            raise ValueError(f"{name} must be positive, got {v}")


def along_beam(p: Params, phi: jax.Array) -> jax.Array:
    """``s = d tan φ`` (m): the ball centre's coordinate along the beam."""
    return p.height() * jnp.tan(phi)


def centre(p: Params, q: jax.Array) -> jax.Array:
    """Ball centre in the world ``(2,)`` (m) for ``q = (θ, φ)``."""
    th, phi = q[0], q[1]
    s, d = along_beam(p, phi), p.height()
    c, sn = jnp.cos(th), jnp.sin(th)
    return jnp.stack([c * s - sn * d, sn * s + c * d])


def kinetic(p: Params, q: jax.Array, qd: jax.Array) -> jax.Array:
    """Kinetic energy ``T(q, q̇)`` (J)."""
    v = jax.jvp(lambda z: centre(p, z), (q,), (qd,))[1]
    s_dot = jax.jvp(lambda f: along_beam(p, f), (q[1],), (qd[1],))[1]
    spin = qd[0] - s_dot / p.r
    return 0.5 * p.j_f * qd[0] ** 2 + 0.5 * p.m * v @ v + 0.5 * p.ball_inertia() * spin**2


def potential(p: Params, q: jax.Array) -> jax.Array:
    """Potential energy ``V(q) = m g p_y`` (J)."""
    return p.m * p.g * centre(p, q)[1]


def energy(p: Params, x: jax.Array) -> jax.Array:
    """Total energy ``T + V`` (J) of the state ``x = (θ, φ, θ̇, φ̇)``: conserved when ``u = 0``."""
    return kinetic(p, x[:2], x[2:]) + potential(p, x[:2])


def mass_and_bias(p: Params, q: jax.Array, qd: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``M(q) (2, 2)`` and ``h(q, q̇) (2,)`` with ``M q̈ + h = (u, 0)``, in closed form (module docstring).

    With ``s' = ds/dφ``, the kinetic energy is ``½ q̇ᵀ M(φ) q̇``:

        M₁₁ = J_f + J_b + m (d² + s²),   M₁₂ = −(m d + J_b/r) s',   M₂₂ = (m + J_b/r²) s'²

    and, ``M`` depending on ``φ`` alone, ``h = (M₁₁' θ̇ φ̇ + M₁₂' φ̇², −½ M₁₁' θ̇² + ½ M₂₂' φ̇²) + ∂V/∂q``
    (primes: ``d/dφ``).  The same equations as Euler–Lagrange by autodiff of :func:`kinetic` and
    :func:`potential` (the tests hold ``M`` to 1e-12 and ``q̈`` to 1e-11); written out because the nested ``jacfwd``
    made every program that evaluates them (the αβγ quadratures, the transverse linearisation)
    several times larger to trace and compile."""
    th, phi = q[0], q[1]
    thd, phd = qd[0], qd[1]
    d, m, jb = p.height(), p.m, p.ball_inertia()
    tan = jnp.tan(phi)
    s = d * tan
    s1 = d * (1.0 + tan**2)  # ds/dφ
    s2 = 2.0 * s1 * tan  # d²s/dφ²
    roll = m * d + jb / p.r  # coupling through the ball's rolling
    slide = m + jb / p.r**2
    m11, m12, m22 = p.j_f + jb + m * (d**2 + s**2), -roll * s1, slide * s1**2
    dm11, dm12, dm22 = 2.0 * m * s * s1, -roll * s2, 2.0 * slide * s1 * s2
    c, sn = jnp.cos(th), jnp.sin(th)
    mg = m * p.g
    h1 = dm11 * thd * phd + dm12 * phd**2 + mg * (s * c - d * sn)
    h2 = -0.5 * dm11 * thd**2 + 0.5 * dm22 * phd**2 + mg * s1 * sn
    return jnp.stack([jnp.stack([m11, m12]), jnp.stack([m12, m22])]), jnp.stack([h1, h2])


def dynamics(p: Params, x: jax.Array, u: jax.Array) -> jax.Array:
    """``ẋ (4,)`` for the state ``x = (θ, φ, θ̇, φ̇)`` and torque ``u`` (N·m): ``M q̈ = (u, 0) − h``."""
    q, qd = x[:2], x[2:]
    mass, h = mass_and_bias(p, q, qd)
    rhs = jnp.stack([u - h[0], -h[1]])
    det = mass[0, 0] * mass[1, 1] - mass[0, 1] ** 2  # M ≻ 0: a 2×2 inverse, no LAPACK call in the loop
    qdd = jnp.stack([mass[1, 1] * rhs[0] - mass[0, 1] * rhs[1], mass[0, 0] * rhs[1] - mass[0, 1] * rhs[0]]) / det
    return jnp.concatenate([qd, qdd])


# ---------------------------------------------------------------- virtual constraint θ = kφ


def abg(p: Params, k: Any, phi: jax.Array) -> jax.Array:
    """``(α, β, γ)(φ)`` of the reduced equation ``α φ̈ + β φ̇² + γ = 0`` on ``θ = kφ`` (shape ``(3,)``)."""
    q = jnp.stack([k * phi, phi])
    mass, g0 = mass_and_bias(p, q, jnp.zeros(2))
    _, h1 = mass_and_bias(p, q, jnp.stack([k, 1.0]))
    alpha = k * mass[1, 0] + mass[1, 1]
    return jnp.stack([alpha, h1[1] - g0[1], g0[1]])


def psi(p: Params, k: Any, phi: jax.Array) -> jax.Array:
    """``Ψ(φ) = exp(2∫₀^φ β/α ds)`` (12-node Gauss–Legendre: the integrands are smooth on |φ| < π/2)."""
    c = jax.vmap(lambda s: abg(p, k, s))(phi * _GL_X)
    return jnp.exp(2.0 * phi * jnp.sum(_GL_W * c[:, 1] / c[:, 0]))


def w_potential(p: Params, k: Any, phi: jax.Array) -> jax.Array:
    """``W(φ) = ∫₀^φ 2Ψ(s)γ(s)/α(s) ds`` (nested Gauss–Legendre)."""
    s = phi * _GL_X
    c = jax.vmap(lambda z: abg(p, k, z))(s)
    ps = jax.vmap(lambda z: psi(p, k, z))(s)
    return phi * jnp.sum(_GL_W * 2.0 * ps * c[:, 2] / c[:, 0])


def integral(p: Params, k: Any, phi: jax.Array, phi_dot: jax.Array) -> jax.Array:
    """The integral ``I(φ, φ̇) = Ψ(φ) φ̇² + W(φ)`` of the αβγ-equation (rad²/s²)."""
    return psi(p, k, phi) * phi_dot**2 + w_potential(p, k, phi)


def reduced_field(p: Params, k: Any, z: jax.Array) -> jax.Array:
    """``(φ̇, φ̈)`` of the αβγ-equation for ``z = (φ, φ̇)``."""
    a, b, c = abg(p, k, z[0])
    return jnp.stack([z[1], -(b * z[1] ** 2 + c) / a])


def _flow(p: Params, k: Any, z0: jax.Array, duration: jax.Array, steps: int) -> jax.Array:
    h = duration / steps

    def step(z, _):
        z1 = RK4_ROLLED.step(lambda t, y: reduced_field(p, k, y), 0.0, z, h)
        return z1, z1

    _, zs = jax.lax.scan(step, z0, None, length=steps)
    return jnp.concatenate([z0[None], zs])


def orbit(p: Params, k: Any, amplitude: Any, samples: int, newton: int = 8) -> tuple[jax.Array, jax.Array]:
    """The periodic solution of the αβγ-equation through ``(φ_a, 0)``.

    Returns ``(period (s), z (samples + 1, 2))``: ``z_j = (φ, φ̇)`` at ``t_j = j·T/samples`` (RK4 at that
    step; ``samples`` even).  The half period is found by Newton on ``φ̇(T/2) = 0`` (derivative ``φ̈(T/2)``) (the reduced
    equation is even under ``φ → −φ``), started from the small-oscillation period ``2π√(α(0)/γ′(0))``.
    """
    if samples % 2:
        raise ValueError(f"samples must be even, got {samples}")
    _check(p)
    z0 = jnp.stack([jnp.asarray(amplitude, float), 0.0])
    half = samples // 2
    a0 = abg(p, k, jnp.asarray(0.0))[0]
    dgamma = jax.grad(lambda f: abg(p, k, f)[2])(jnp.asarray(0.0))
    t_half = jnp.pi * jnp.sqrt(a0 / dgamma)

    def newton_step(_, th):  # d/dT_half of φ̇(T_half) is φ̈ there (the flow's own field)
        end = _flow(p, k, z0, th, half)[-1]
        return th - end[1] / reduced_field(p, k, end)[1]

    t_half = jax.lax.fori_loop(0, newton, newton_step, t_half)
    period = 2.0 * t_half
    return period, _flow(p, k, z0, period, samples)


# ---------------------------------------------------------------- transverse coordinates


def phi_ddot(p: Params, k: Any, x: jax.Array, v: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Partial feedback linearisation: ``(φ̈, u)`` that give ``ÿ = v`` for ``y = θ − kφ``."""
    mass, h = mass_and_bias(p, x[:2], x[2:])
    pdd = -(mass[1, 0] * v + h[1]) / (k * mass[1, 0] + mass[1, 1])
    tdd = v + k * pdd
    return pdd, mass[0, 0] * tdd + mass[0, 1] * pdd + h[0]


def pfl_torque(p: Params, k: Any, x: jax.Array, v: jax.Array) -> jax.Array:
    """Motor torque ``u = P⁻¹(v − R)`` (N·m) for the new control ``v = ÿ``."""
    return phi_ddot(p, k, x, v)[1]


def transverse_state(p: Params, k: Any, x: jax.Array, i_star: Any) -> jax.Array:
    """``x⊥ = (I(φ, φ̇) − I*, y, ẏ)`` with ``y = θ − kφ``."""
    return jnp.stack([integral(p, k, x[1], x[3]) - i_star, x[0] - k * x[1], x[2] - k * x[3]])


def integral_rate(p: Params, k: Any, phi, phi_dot, y, y_dot, v) -> jax.Array:
    """``dI/dt = 2Ψφ̇[(βφ̇² + γ)/α + φ̈]`` with ``φ̈`` from the full dynamics under ``ÿ = v``."""
    x = jnp.stack([k * phi + y, phi, k * phi_dot + y_dot, phi_dot])
    a, b, c = abg(p, k, phi)
    pdd, _ = phi_ddot(p, k, x, v)
    return 2.0 * psi(p, k, phi) * phi_dot * ((b * phi_dot**2 + c) / a + pdd)


def transverse_linearisation(p: Params, k: Any, z: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``A (3, 3)``, ``B (3,)`` of ``ẋ⊥ = A x⊥ + B v`` at the orbit point ``z = (φ*, φ̇*)`` (autodiff)."""
    g = jax.grad(lambda w: integral_rate(p, k, z[0], z[1], w[0], w[1], w[2]))(jnp.zeros(3))
    a = jnp.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]).at[0, 1:].set(g[:2])
    b = jnp.stack([g[2], 0.0, 1.0])
    return a, b
