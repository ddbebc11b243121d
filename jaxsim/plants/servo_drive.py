"""Loaded electric servo drive of joint 2 of a PUMA-type arm (seed 000, paper 2, eq. 4.1).

State ``x = [x1, x2, x3]``: ``x1`` angle of the gearbox output shaft = joint angle ``q2`` (rad),
``x2`` motor-rotor speed (rad/s), ``x3`` armature current (A).  Input ``u = [U]``, the drive voltage
(V) before the power amplifier.  Outputs ``y = [x1, x3]`` (angle and current; the rotor speed is not
measured).  Time in seconds.

The paper's display equation was lost in extraction; it is rebuilt here in the standard form of
the authors' group (spec §2.2, the variable list at seed lines 1757–1784)::

    ẋ1 = x2 / i_r
    ẋ2 = [k_m x3 − (k_v + h*/i_r²) x2 − M_dry sign(x2) − M*/i_r + M̃(t)] / (J + H*/i_r²)
    ẋ3 = [−k_ω x2 − R_m x3 + k_y U] / L_m

``H*(t)`` is the arm's inertia about joint 2, ``h*(t) = Ḣ*(t)`` (the paper states this identity) the
Coriolis coefficient of the joint speed, ``M*(t)`` gravity plus cross-coupling from the other links,
all referred to the joint and divided by ``i_r²`` or ``i_r`` to refer them to the rotor.  ``M̃(t)``
is the unknown fault torque: from ``t_fault`` the viscous and dry friction grow by 50 %,
``M̃ = −Δk_v x2 − ΔM_dry sign(x2)``.

The arm's coupling equations (paper ref. [22]) were lost too.  We derive them [ours] for an
anthropomorphic RRR arm without offsets (joint 1 vertical, joints 2 and 3 horizontal; ``q2`` from
the horizontal, ``q3`` relative elbow angle), links modelled as bodies symmetric about their
longitudinal axes (inertia ``Js`` about it, ``Jn`` about transverse axes through the centre of
mass), the load a point mass at the tip.  With the other joints moving as prescribed functions of
time (``q1 = 2 sin 1.5t``, ``q3 = sin 2t``, paper lines 1880–1882) the joint-2 Lagrange equation is

    τ2 = M22 q̈2 + ∂M22/∂q3 q̇3 q̇2 + [M23 q̈3 + ∂M23/∂q3 q̇3² − ½ ∂M11/∂q2 q̇1² + ∂V/∂q2]

so ``H* = M22(q3)``, ``h* = Ḣ* = ∂M22/∂q3 q̇3`` and ``M*`` is the bracket.  The ``Js`` values enter
only through ``M11`` (the ``q̇1²`` centrifugal term).  All derivatives of ``M`` and ``V`` come from
``jax.grad``; those of the prescribed motions are closed-form.  No self-tuning correcting device
is modelled (the paper does not describe it).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.reduced_model import ReducedModel, SlidingBounds
from jaxsim.core.system import Plant
from jaxsim.core.validation import check_finite, check_positive


@pytree_dataclass
class DriveParams:
    """Drive constants, paper lines 1869–1876 (SI units)."""

    R_m: Any = 0.5  # armature resistance, Ω
    L_m: Any = 5e-4  # armature inductance, H
    k_w: Any = 0.04  # back-EMF coefficient, V·s/rad
    k_m: Any = 0.04  # torque constant, N·m/A
    J: Any = 1e-4  # rotor + gearbox inertia referred to the rotor, kg·m²
    i_r: Any = 100.0  # gear ratio
    k_v: Any = 0.005  # viscous friction, N·m·s/rad
    M_dry: Any = 0.02  # dry friction, N·m
    k_y: Any = 100.0  # power-amplifier gain


@pytree_dataclass
class ArmParams:
    """PUMA-type arm, paper lines 1856–1865 (kg, m, kg·m²); ``g`` in m/s²."""

    m1: Any = 35.8
    m2: Any = 3.5
    m3: Any = 3.0
    m_load: Any = 1.0
    l1: Any = 0.2
    l2: Any = 0.5
    l3: Any = 0.4
    lc1: Any = 0.1
    lc2: Any = 0.12
    lc3: Any = 0.1
    Js1: Any = 0.32
    Js2: Any = 0.0047
    Js3: Any = 0.004
    Jn2: Any = 0.12
    Jn3: Any = 0.067
    g: Any = 9.81


@pytree_dataclass
class OtherJoints:
    """Prescribed motion ``q1 = a1 sin(w1 t)``, ``q3 = a3 sin(w3 t)`` (rad, rad/s), paper lines 1880–1882."""

    a1: Any = 2.0
    w1: Any = 1.5
    a3: Any = 1.0
    w3: Any = 2.0


@pytree_dataclass
class FaultParams:
    """Friction fault: ``k_v`` and ``M_dry`` grow by the given fractions from ``onset`` (s)."""

    onset: Any = 3.0
    viscous_increase: Any = 0.5
    dry_increase: Any = 0.5


@pytree_dataclass
class ServoParams:
    drive: DriveParams = DriveParams()
    arm: ArmParams = ArmParams()
    motion: OtherJoints = OtherJoints()
    fault: FaultParams = FaultParams()


class Coupling(NamedTuple):
    """Arm coupling seen by joint 2: ``H`` (kg·m²), ``h = Ḣ`` (kg·m²/s), ``M`` (N·m), all at the joint."""

    H: jax.Array
    h: jax.Array
    M: jax.Array


def _m11(a: ArmParams, q2: jax.Array, q3: jax.Array) -> jax.Array:
    """Inertia about the vertical joint-1 axis."""
    th2, th3 = q2, q2 + q3
    r2 = a.lc2 * jnp.cos(th2)
    r3 = a.l2 * jnp.cos(th2) + a.lc3 * jnp.cos(th3)
    rl = a.l2 * jnp.cos(th2) + a.l3 * jnp.cos(th3)
    return (
        a.Js1
        + a.Js2 * jnp.sin(th2) ** 2
        + a.Jn2 * jnp.cos(th2) ** 2
        + a.m2 * r2**2
        + a.Js3 * jnp.sin(th3) ** 2
        + a.Jn3 * jnp.cos(th3) ** 2
        + a.m3 * r3**2
        + a.m_load * rl**2
    )


def _m22(a: ArmParams, q3: jax.Array) -> jax.Array:
    c3 = jnp.cos(q3)
    return (
        a.Jn2
        + a.m2 * a.lc2**2
        + a.Jn3
        + a.m3 * (a.l2**2 + a.lc3**2 + 2 * a.l2 * a.lc3 * c3)
        + a.m_load * (a.l2**2 + a.l3**2 + 2 * a.l2 * a.l3 * c3)
    )


def _m23(a: ArmParams, q3: jax.Array) -> jax.Array:
    c3 = jnp.cos(q3)
    return a.Jn3 + a.m3 * (a.lc3**2 + a.l2 * a.lc3 * c3) + a.m_load * (a.l3**2 + a.l2 * a.l3 * c3)


def _potential(a: ArmParams, q2: jax.Array, q3: jax.Array) -> jax.Array:
    return a.g * (
        (a.m2 * a.lc2 + (a.m3 + a.m_load) * a.l2) * jnp.sin(q2) + (a.m3 * a.lc3 + a.m_load * a.l3) * jnp.sin(q2 + q3)
    )


def other_joints(m: OtherJoints, t: jax.Array) -> tuple[jax.Array, ...]:
    """``(q̇1, q3, q̇3, q̈3)`` at time ``t``."""
    s3, c3 = jnp.sin(m.w3 * t), jnp.cos(m.w3 * t)
    return (m.a1 * m.w1 * jnp.cos(m.w1 * t), m.a3 * s3, m.a3 * m.w3 * c3, -m.a3 * m.w3**2 * s3)


def inertia(p: ServoParams, t: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(H*, h*) = (M22, Ṁ22)`` at time ``t`` (they depend on ``q3(t)`` only)."""
    _, q3, dq3, _ = other_joints(p.motion, t)
    return _m22(p.arm, q3), jax.grad(_m22, argnums=1)(p.arm, q3) * dq3


def coupling(p: ServoParams, q2: jax.Array, t: jax.Array) -> Coupling:
    """``H*, h*, M*`` for joint angle ``q2`` (rad) at time ``t`` (s)."""
    a = p.arm
    dq1, q3, dq3, ddq3 = other_joints(p.motion, t)
    H, h = inertia(p, t)
    M = (
        _m23(a, q3) * ddq3
        + jax.grad(_m23, argnums=1)(a, q3) * dq3**2
        - 0.5 * jax.grad(_m11, argnums=1)(a, q2, q3) * dq1**2
        + jax.grad(_potential, argnums=1)(a, q2, q3)
    )
    return Coupling(H, h, M)


def total_inertia(p: ServoParams, t: jax.Array) -> jax.Array:
    """``J_t = J + H*/i_r²`` referred to the rotor (kg·m²)."""
    return p.drive.J + inertia(p, t)[0] / p.drive.i_r**2


def fault_active(p: ServoParams, t: jax.Array) -> jax.Array:
    return (t >= p.fault.onset).astype(jnp.result_type(t, float))


def fault_torque(p: ServoParams, x: jax.Array, t: jax.Array) -> jax.Array:
    """The fault ``M̃(t) = −Δk_v x2 − ΔM_dry sign(x2)`` at the rotor (N·m); zero before the onset."""
    d = p.drive
    dk = p.fault.viscous_increase * d.k_v
    dm = p.fault.dry_increase * d.M_dry
    return -fault_active(p, t) * (dk * x[1] + dm * jnp.sign(x[1]))


def dynamics(p: ServoParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ`` of eq. (4.1) with the fault torque included; ``u = [U]`` in volts."""
    d = p.drive
    c = coupling(p, x[0], t)
    jt = d.J + c.H / d.i_r**2
    torque = (
        d.k_m * x[2] - (d.k_v + c.h / d.i_r**2) * x[1] - d.M_dry * jnp.sign(x[1]) - c.M / d.i_r + fault_torque(p, x, t)
    )
    return jnp.stack([x[1] / d.i_r, torque / jt, (-d.k_w * x[1] - d.R_m * x[2] + d.k_y * u[0]) / d.L_m])


def output(p: ServoParams, x: jax.Array) -> jax.Array:
    """``y = [x1, x3]``: joint angle (rad) and armature current (A)."""
    return jnp.stack([x[0], x[2]])


def validate(p: ServoParams) -> None:
    for name in ("R_m", "L_m", "k_w", "k_m", "J", "i_r", "k_y"):
        check_positive(name, getattr(p.drive, name))
    for name in ("k_v", "M_dry"):
        check_positive(name, getattr(p.drive, name), allow_zero=True)
    for name in ("m2", "m3", "Jn2", "Jn3"):
        check_positive(name, getattr(p.arm, name))
    check_finite("motion", p.motion)
    check_finite("fault", p.fault)


def servo_drive_plant(params: ServoParams | None = None) -> Plant:
    """The drive as a :class:`~jaxsim.core.system.Plant` (3 states, 1 input, 2 outputs)."""
    p = ServoParams() if params is None else params
    validate(p)
    return Plant(p, dynamics, output, n_states=3, n_inputs=1, n_outputs=2, name="servo_drive_joint2")


def initial_state(p: ServoParams, q2_0: float = 0.0) -> jax.Array:
    """A state at rest at angle ``q2_0`` (rad) with the current that holds the load at ``t = 0``."""
    c = coupling(p, jnp.asarray(q2_0, float), jnp.asarray(0.0))
    return jnp.stack([jnp.asarray(q2_0, float), jnp.asarray(0.0), c.M / (p.drive.i_r * p.drive.k_m)])


# --- the reduced model (2.2) the fault-identification observer runs on -------------------------
#
# [ours, consistent with every constant the paper states: k = 2, F4 = 0, F2 = 1, Q = −1, P = 1,
# W = 2, N* = 0, M* = 2, "Φ̇x is expressed through y2"].  Reduced states x*1 = x1 and
# x*2 = x2/i_r + φ(t) x3 with φ = −a L_m/(i_r k_ω), a = (k_v + h*/i_r²)/J_t: this φ cancels the
# unmeasured speed in ẋ*2, leaving (with b = k_m/J_t, c = M_dry/J_t, m = M*/(i_r J_t))
#     ẋ*1 = x*2 − φ y2
#     ẋ*2 = (b/i_r − φ R_m/L_m + φ̇) y2 + φ k_y U/L_m − (c/i_r) sign(x2) − m/i_r + d/i_r
# where d = M̃/J_t is the fault and sign(x2) = sign(i_r (x*2 − φ y2)) the nonlinearity Ψ.  The
# canonical coordinates z1 = x*1, z2 = x*2 + Q x*1 give F1 = −Q, F2 = 1, F3 = −Q², F4 = Q,
# D1 = 0, D2 = 1/i_r, so M̃ is identified as J_t · d̂ with d̂ = i_r k1 v_eq (P = 1).


@pytree_dataclass
class ObserverModelParams:
    """What the observer believes: nominal plant parameters and the coordinate gain ``Q`` (< 0)."""

    plant: ServoParams = ServoParams()
    Q: Any = -1.0


def phi(p: ServoParams, t: jax.Array) -> jax.Array:
    """``φ(t) = −a(t) L_m/(i_r k_ω)`` (A⁻¹·rad), a known function of time only."""
    d = p.drive
    H, h = inertia(p, t)
    a = (d.k_v + h / d.i_r**2) / (d.J + H / d.i_r**2)
    return -a * d.L_m / (d.i_r * d.k_w)


def _known_terms(
    op: ObserverModelParams, t: jax.Array, y: jax.Array, u: jax.Array, z2: jax.Array
) -> tuple[jax.Array, jax.Array]:
    p, Q = op.plant, op.Q
    d = p.drive
    ph, dph = jax.jvp(lambda tt: phi(p, tt), (t,), (jnp.ones_like(t),))
    jt = total_inertia(p, t)
    m = coupling(p, y[0], t).M / (d.i_r * jt)
    x2_hat = d.i_r * (z2[0] - Q * y[0] - ph * y[1])
    dx2star = (
        (d.k_m / (jt * d.i_r) - ph * d.R_m / d.L_m + dph) * y[1]
        + ph * d.k_y * u[0] / d.L_m
        - d.M_dry / (jt * d.i_r) * jnp.sign(x2_hat)
        - m / d.i_r
    )
    return -ph * y[1], jnp.reshape(dx2star - Q * ph * y[1], (1,))


def _angle(op: ObserverModelParams, y: jax.Array) -> jax.Array:
    return y[0]


def reduced_model(params: ObserverModelParams | None = None) -> ReducedModel:
    """The drive's reduced model as a :class:`~jaxsim.core.reduced_model.ReducedModel` (the input of
    :func:`jaxsim.estimation.reduced_order_smo.reduced_order_smo`)."""
    op = ObserverModelParams() if params is None else params
    validate(op.plant)
    Q = jnp.asarray(op.Q, float)
    return ReducedModel(
        F1=-Q,
        F2=jnp.ones(1),
        F3=jnp.reshape(-(Q**2), (1,)),
        F4=jnp.reshape(Q, (1, 1)),
        D1=jnp.asarray(0.0),
        D2=jnp.reshape(1.0 / jnp.asarray(op.plant.drive.i_r, float), (1,)),
        params=op,
        known=_known_terms,
        reduced_output=_angle,
    )


def reduced_state(p: ServoParams, x: jax.Array, t: jax.Array, Q: float = -1.0) -> jax.Array:
    """The true canonical state ``z = (x1, x2/i_r + φ x3 + Q x1)`` of plant state ``x``."""
    return jnp.stack([x[0], x[1] / p.drive.i_r + phi(p, t) * x[2] + Q * x[0]])


def fault_torque_from_estimate(p: ServoParams, t: jax.Array, d_hat: jax.Array) -> jax.Array:
    """``M̃̂ = J_t(t) · d̂`` (N·m)."""
    return total_inertia(p, t) * d_hat


def sliding_bounds(p: ServoParams, fault_bound: float) -> SlidingBounds:
    """Bounds (3.3) for the drive: ``N1 = M1 = N2 = 0``, ``M2 = 2 M_dry/(i_r J_t,min)`` (the sign
    nonlinearity, the paper's ``M* = 2``), ``β = fault_bound/J_t,min`` for ``|M̃| ≤ fault_bound`` (N·m).

    ``J_t,min`` uses the smallest ``H*`` over all elbow angles, so the bounds hold for any motion.
    """
    check_positive("fault_bound", fault_bound, allow_zero=True)
    d = p.drive
    h_min = float(jnp.min(jax.vmap(lambda q3: _m22(p.arm, q3))(jnp.linspace(0.0, 2 * jnp.pi, 721))))
    jt_min = float(d.J) + h_min / float(d.i_r) ** 2
    return SlidingBounds(M2=2.0 * float(d.M_dry) / (float(d.i_r) * jt_min), beta=float(fault_bound) / jt_min)
