"""Quanser-type 3-DOF helicopter stand: travel, elevation and pitch hinges, two thrusters.

Seed 004, lines 3444–3653 (spec ``seed004_part1.md`` §B2): an arm on a post rotates about the vertical
axis (travel ``φ``) and a horizontal axis (elevation ``θ``); the helicopter body at the arm's end
rotates about the arm (pitch ``ψ``) and carries a front and a back propeller.  The paper gives the
reduced equations with no numbers, so this module builds the rigid body from public parameters of
the Quanser 3-DOF helicopter as quoted by MPCtools/jMPC (Åkesson 2006, Lund; spec §B2.4):
``la = 0.66 m``, ``lh = 0.177 m``, ``Kf = 0.5 N/V``, ``Fg = 0.5 N`` (so ``Tg = la·Fg``), ``Je = 0.91 kg·m²``,
``Jp = 0.0364 kg·m²`` — and derives the equations of motion of that geometry with
:mod:`jaxsim.core.lagrangian` (Euler–Lagrange by autodiff: exact inertial coupling, no small-angle
simplification).  Geometry (body frames; the :mod:`jaxsim.mjx.helicopter_3dof` MJCF model is the same):

* arm frame ``R_arm = Rz(φ)·R_{−y}(θ)`` at the pivot (``θ > 0`` raises the helicopter end);
  counterweight ``m_w`` at ``(−lw, 0, 0)`` with extra arm inertia ``(ε, J_arm, J_arm)``;
* helicopter body ``R_arm·Rx(ψ)`` at ``(la, 0, 0)``: mass ``m_h = Jp/lh²`` (two motors at ``±lh``)
  with centre ``hp`` below the pitch axis, inertia ``(m_h lh², ε, m_h lh²)``;
* front/back thrust ``F_f, F_b`` along the body's ``z`` at ``(0, ±lh, 0)``; motor lag
  ``τm Ḟ = Kf V − F`` per motor; viscous friction ``B·rate`` on each hinge.

Assumed (no public value found; each listed in :data:`ASSUMPTIONS`): ``m_w = 1.87 kg`` (lever ``lw`` then
follows from ``Tg``), ``J_arm = Je − m_h la² − m_w lw²``, ``hp = 5 mm``, damping ``a = 0.2 s⁻¹`` per axis
(``B = a·J``; the paper suggests 0.1–1 s⁻¹), ``τm = 0.05 s``.

At rest the travel inertia is ``Je + Jp = 0.946 kg·m²`` (the motors sit beside the arm), MPCtools'
``Jt = 0.91``; the model keeps the consistent rigid body rather than a separate ``Jt``.

State ``x = (φ, θ, ψ, φ̇, θ̇, ψ̇, F_f, F_b)`` (8,), input ``u = (V_f, V_b)`` volts, output ``(φ, θ, ψ)`` rad.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.lagrangian import body_energy, euler_lagrange, point_force, rotation
from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.system import Plant
from jaxsim.core.validation import check_positive, is_concrete

STATE_NAMES = (
    "travel",
    "elevation",
    "pitch",
    "travel_rate",
    "elevation_rate",
    "pitch_rate",
    "thrust_front",
    "thrust_back",
)
INPUT_NAMES = ("v_front", "v_back")
OUTPUT_NAMES = ("travel", "elevation", "pitch")
GRAVITY = 9.81
EPS_INERTIA = 1e-4  # kg·m², the near-zero principal moments (MuJoCo needs positive inertia)

ASSUMPTIONS = {
    "m_w": "counterweight mass 1.87 kg (Quanser-type; no value in the paper)",
    "hp": "pitch-body centre 5 mm below the pitch axis (a weak pendulum, a_ψ0 ≈ 1.6 s⁻²)",
    "damping": "viscous friction B = 0.2 s⁻¹ × axis inertia (paper: a_·1 'e.g. 0.1–1 s⁻¹')",
    "tau_m": "motor thrust lag 0.05 s",
}


@pytree_dataclass
class HelicopterParams:
    """Rigid-body and motor parameters (SI).  Defaults: MPCtools/jMPC's Quanser numbers + assumptions."""

    la: Any = 0.66  # m, pivot → helicopter body
    lh: Any = 0.177  # m, pitch axis → each motor
    kf: Any = 0.5  # N/V, thrust per volt
    fg: Any = 0.5  # N, net weight at the helicopter end (Tg = la·Fg)
    je: Any = 0.91  # kg·m², elevation inertia at θ = ψ = 0 (sets J_arm)
    jp: Any = 0.0364  # kg·m², pitch inertia (sets m_h = Jp/lh²)
    m_w: Any = 1.87  # kg, counterweight (assumed)
    hp: Any = 0.005  # m, body centre below the pitch axis (assumed)
    damping: Any = 0.2  # 1/s, B = damping × inertia per axis (assumed)
    tau_m: Any = 0.05  # s, motor lag (assumed)


def derived(p: HelicopterParams) -> dict[str, jax.Array]:
    """Masses, lever and inertias implied by ``p``: ``m_h, lw, j_arm`` and damping ``b (3,)`` (N·m·s)."""
    m_h = p.jp / p.lh**2
    lw = (m_h * p.la - p.la * p.fg / GRAVITY) / p.m_w
    j_arm = p.je - m_h * p.la**2 - p.m_w * lw**2
    # B = damping × axis inertia at rest: travel turns the arm and the pitch body (je + jp)
    b = p.damping * jnp.stack([jnp.asarray(p.je + p.jp, float), jnp.asarray(p.je, float), jnp.asarray(p.jp, float)])
    return {"m_h": m_h, "lw": lw, "j_arm": j_arm, "b": b}


def arm_pose(q: jax.Array) -> tuple[jax.Array, jax.Array]:
    return rotation((0, 0, 1), q[0]) @ rotation((0, -1, 0), q[1]), jnp.zeros(3)


def body_pose(p: HelicopterParams, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    rot_arm, _ = arm_pose(q)
    return rot_arm @ rotation((1, 0, 0), q[2]), rot_arm @ jnp.stack([p.la, 0.0 * p.la, 0.0 * p.la])


def energies(p: HelicopterParams):
    """``(T(q, q̇), V(q))`` of arm + counterweight and the helicopter body."""
    d = derived(p)
    t_arm, v_arm = body_energy(
        arm_pose, p.m_w, jnp.stack([-d["lw"], 0.0, 0.0]), jnp.stack([EPS_INERTIA, d["j_arm"], d["j_arm"]]), GRAVITY
    )
    t_body, v_body = body_energy(
        lambda q: body_pose(p, q),
        d["m_h"],
        jnp.stack([0.0, 0.0, -p.hp]),
        jnp.stack([d["m_h"] * p.lh**2, EPS_INERTIA, d["m_h"] * p.lh**2]),
        GRAVITY,
    )
    return (lambda q, qd: t_arm(q, qd) + t_body(q, qd)), (lambda q: v_arm(q) + v_body(q))


def thrust_forces(p: HelicopterParams, q: jax.Array, thrust: jax.Array) -> jax.Array:
    """Generalised forces ``(3,)`` of front/back thrusts ``(2,)`` (N) along the body ``z`` axis."""
    pose = lambda z: body_pose(p, z)  # noqa: E731
    up = jnp.array([0.0, 0.0, 1.0])
    return point_force(pose, jnp.stack([0.0, p.lh, 0.0]), thrust[0] * up, q) + point_force(
        pose, jnp.stack([0.0, -p.lh, 0.0]), thrust[1] * up, q
    )


def motor_derivatives(p: HelicopterParams, thrust: jax.Array, u: jax.Array) -> jax.Array:
    """``Ḟ = (Kf V − F)/τm`` for both motors."""
    return (p.kf * u - thrust) / p.tau_m


def dynamics(p: HelicopterParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ`` for ``x (8,)`` and motor voltages ``u (2,)``."""
    q, qd, thrust = x[:3], x[3:6], x[6:]
    kinetic, potential = energies(p)
    force = thrust_forces(p, q, thrust) - derived(p)["b"] * qd
    qdd = euler_lagrange(kinetic, potential, q, qd, force)
    return jnp.concatenate([qd, qdd, motor_derivatives(p, thrust, u)])


def output(p: HelicopterParams, x: jax.Array) -> jax.Array:
    """``y = (φ, θ, ψ)`` (rad)."""
    return x[:3]


def validate_params(p: HelicopterParams) -> None:
    for name in ("la", "lh", "kf", "je", "jp", "m_w", "tau_m"):
        check_positive(name, getattr(p, name))
    for name in ("fg", "hp", "damping"):
        check_positive(name, getattr(p, name), allow_zero=True)
    with jax.ensure_compile_time_eval():
        j_arm = derived(p)["j_arm"]
    if is_concrete(j_arm) and float(j_arm) <= 0:
        raise ValueError(f"je: too small for the masses (arm inertia Je − m_h la² − m_w lw² = {float(j_arm):.3g})")


def helicopter_plant(params: HelicopterParams | None = None) -> Plant:
    """The 3-DOF helicopter as a :class:`Plant` (8 states, 2 inputs, 3 outputs)."""
    params = HelicopterParams() if params is None else params
    validate_params(params)
    return Plant(params, dynamics, output, n_states=8, n_inputs=2, n_outputs=3, name="helicopter_3dof")


def hover_voltage(p: HelicopterParams) -> jax.Array:
    """Equal motor voltages holding ``θ = ψ = 0`` (total thrust ``Fg``, m/s² free)."""
    return jnp.full((2,), 0.5 * p.fg / p.kf)
