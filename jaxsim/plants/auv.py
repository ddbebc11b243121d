"""Fully actuated 6-DOF AUV in Fossen form (seed 002: the follower of the leader–follower formation).

``M ν̇ + C(M, ν) ν + D(d₁, d₂, ν) ν + g(η) = τ`` (paper eq. 1) with ``M = M_R + M_A``, ``C`` from
``M`` (rigid body + added mass, :func:`jaxsim.plants.marine.coriolis_from_mass`),
``D = diag(d₁ᵢ + d₂ᵢ|νᵢ|)``, ``g`` the restoring moments of a neutrally buoyant body whose centre of
gravity lies 0.01 m below the centre of buoyancy, and zyx Euler-angle kinematics ``η̇ = J(η) ν``
(conventions in :mod:`jaxsim.plants.marine`: NED, z down).

State ``x = [x, y, z, φ, θ, ψ, u, v, w, p, q, r]`` (m, rad, m/s, rad/s); input ``τ`` ``(6,)``
(N, N·m) applied directly (the paper has no thruster model, allocation or saturation); output the
whole state (the follower's inertial sensors are taken as exact).

Nominal values: paper lines 970–990 (its ref. [26]).  The "true" plant differs from the nominal
one by ``M_Δ, d_Δ1, d_Δ2`` (paper lines 991–1001); :func:`perturb` applies any deviation and
:data:`PAPER_DEVIATION` is the paper's.

Public API (kept stable; other modules, e.g. an MJCF/MJX model of the rigid body, rely on it):

* :class:`AUVParams` — fields ``M_R``, ``M_A`` ``(6, 6)``, ``d1``, ``d2`` ``(6,)``, ``weight``,
  ``buoyancy`` (N), ``r_g``, ``r_b`` ``(3,)`` (m, body axes); properties ``mass`` (kg, scalar
  ``M_R[0, 0]``), ``inertia`` ``(3, 3)`` (``M_R[3:, 3:]``), ``mass_matrix`` (``M_R + M_A``).
  The paper's ``M_R`` is diagonal: the inertia is about the body origin and the 0.01 m CG offset
  enters **only** the restoring moments (no ``m·S(r_g)`` coupling in ``M_R``). An MJCF body
  matching it has its centre of mass at the body origin and ``diaginertia = diag(inertia)``.
* :func:`rigid_body_forces` ``(params, nu, nu_dot) -> M_R ν̇ + C_R(ν) ν`` ``(6,)`` in body axes —
  the part an independent rigid-body simulator (MuJoCo free joint) must reproduce.
* :func:`kinematics` ``(x) -> J(η)`` ``(6, 6)`` with ``η̇ = J(η) ν``.
* :func:`damping` ``(params, nu) -> D(ν) ν`` and :func:`restoring` ``(params, euler) -> g(η)``.
* :func:`dynamics`, :func:`auv_plant`, :func:`inverse_dynamics`, :func:`perturb`,
  :func:`nominal_params`, :func:`true_params`, :func:`validate`, :func:`initial_state`.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.system import Plant
from jaxsim.core.validation import check_finite, check_positive, check_shape
from jaxsim.plants import marine

GRAVITY = 9.81  # m/s²
N_STATES = 12


def _diag(values: tuple[float, ...]) -> np.ndarray:
    return np.diag(np.asarray(values, dtype=float))


def _array(factory: Any) -> Any:
    return dataclasses.field(default_factory=factory)


@pytree_dataclass
class AUVParams:
    """Physical parameters (array leaves: vmap over them, differentiate through them).

    M_R, M_A ``(6, 6)`` rigid-body and added inertia (kg, kg·m²); d1 ``(6,)`` (N·s/m, N·m·s); d2 ``(6,)`` (N·s²/m²,
    N·m·s²);
    weight, buoyancy (N); r_g, r_b ``(3,)`` centres of gravity and buoyancy in body axes (m).
    """

    M_R: Any = _array(lambda: _diag((170.0, 170.0, 170.0, 10.2, 23.4, 23.4)))  # paper line 979
    M_A: Any = _array(lambda: _diag((15.0, 85.0, 85.0, 5.0, 9.6, 9.6)))  # paper line 982
    d1: Any = _array(lambda: np.array([18.0, 105.0, 105.0, 20.0, 80.0, 80.0]))  # paper line 985
    d2: Any = _array(lambda: np.array([18.0, 105.0, 105.0, 20.0, 80.0, 80.0]))  # paper line 987
    weight: Any = 170.0 * GRAVITY  # W = m_RB·g (assumed: the paper gives no weight)
    buoyancy: Any = 170.0 * GRAVITY  # "zero buoyancy" (neutral): B = W, paper line 990
    r_g: Any = _array(lambda: np.array([0.0, 0.0, 0.01]))  # CG 0.01 m below CB on body z, line 991
    r_b: Any = _array(lambda: np.zeros(3))

    @property
    def mass_matrix(self) -> jax.Array:
        """``M = M_R + M_A`` ``(6, 6)``."""
        return jnp.asarray(self.M_R) + jnp.asarray(self.M_A)

    @property
    def mass(self) -> jax.Array:
        """Rigid-body mass ``m`` (kg) = ``M_R[0, 0]``."""
        return jnp.asarray(self.M_R)[0, 0]

    @property
    def inertia(self) -> jax.Array:
        """Rigid-body inertia about the body origin ``(3, 3)`` (kg·m²) = ``M_R[3:, 3:]``."""
        return jnp.asarray(self.M_R)[3:, 3:]


@pytree_dataclass
class AUVDeviation:
    """A deviation of the true plant from the nominal one: ``mass`` ``(6,)`` (diagonal of ``M_Δ``)
    or ``(6, 6)``, ``d1``, ``d2`` ``(6,)``."""

    mass: Any
    d1: Any
    d2: Any


PAPER_DEVIATION = AUVDeviation(
    mass=np.array([140.0, 140.0, 140.0, 4.0, 7.0, 7.0]),  # M_Δ, paper line 995
    d1=np.array([9.0, 50.0, 50.0, 10.0, 30.0, 30.0]),  # d_Δ1, paper line 997
    d2=np.array([9.0, 50.0, 50.0, 10.0, 30.0, 30.0]),  # d_Δ2, paper line 999
)


def perturb(params: AUVParams, deviation: AUVDeviation, sign: float = 1.0) -> AUVParams:
    """The plant ``params + sign·deviation``; ``M_Δ`` is added to the added-mass block ``M_A`` so
    that the weight (``m_RB·g``) stays the nominal one."""
    dm = jnp.asarray(deviation.mass)
    dm = jnp.diag(dm) if dm.ndim == 1 else dm
    return AUVParams(
        M_R=params.M_R,
        M_A=jnp.asarray(params.M_A) + sign * dm,
        d1=jnp.asarray(params.d1) + sign * jnp.asarray(deviation.d1),
        d2=jnp.asarray(params.d2) + sign * jnp.asarray(deviation.d2),
        weight=params.weight,
        buoyancy=params.buoyancy,
        r_g=params.r_g,
        r_b=params.r_b,
    )


def nominal_params() -> AUVParams:
    """The paper's nominal follower (what the controller knows)."""
    return AUVParams()


def true_params(sign: float = 1.0) -> AUVParams:
    """The paper's "true" follower: nominal ``+ sign·(M_Δ, d_Δ1, d_Δ2)`` (sign assumed +)."""
    return perturb(AUVParams(), PAPER_DEVIATION, sign)


def restoring(params: AUVParams, euler: jax.Array) -> jax.Array:
    """``g(η)`` ``(6,)`` for ``euler = [φ, θ, ψ]``."""
    return marine.restoring_forces(
        euler, params.weight, params.buoyancy, jnp.asarray(params.r_g), jnp.asarray(params.r_b)
    )


def damping(params: AUVParams, nu: jax.Array) -> jax.Array:
    """Damping force ``D(ν) ν`` ``(6,)`` (N, N·m)."""
    return marine.damping_matrix(jnp.asarray(params.d1), jnp.asarray(params.d2), nu) @ nu


def rigid_body_forces(params: AUVParams, nu: jax.Array, nu_dot: jax.Array) -> jax.Array:
    """Rigid-body part ``M_R ν̇ + C_R(ν) ν`` ``(6,)`` (N, N·m), body axes, without added mass,
    damping or restoring forces (Newton–Euler equations of a free rigid body)."""
    m_r = jnp.asarray(params.M_R)
    return m_r @ nu_dot + marine.coriolis_from_mass(m_r, nu) @ nu


def kinematics(x: jax.Array) -> jax.Array:
    """``J(η)`` ``(6, 6)`` of the state ``x`` ``(12,)`` (or ``η`` ``(6,)``): ``η̇ = J(η) ν``."""
    return marine.kinematics_jacobian(x[:6])


@pytree_dataclass
class AUVModel:
    """What the plant integrates: the parameters and ``M⁻¹``, inverted once per rollout (outside the
    time loop) instead of solving with ``M`` at every integrator stage."""

    params: AUVParams
    mass_inverse: jax.Array


def model(params: AUVParams) -> AUVModel:
    """:class:`AUVModel` of ``params`` (``M⁻¹`` by ``jnp.linalg.inv``; differentiable)."""
    return AUVModel(params, jnp.linalg.inv(params.mass_matrix))


def acceleration(m: AUVModel, x: jax.Array, tau: jax.Array) -> jax.Array:
    """Body acceleration ``ν̇ = M⁻¹(τ − C(ν)ν − D(ν)ν − g(η))`` ``(6,)`` at state ``x`` under ``τ``."""
    p = m.params
    rhs = marine.unbalanced_forces(
        p.mass_matrix, x[6:], tau, jnp.asarray(p.d1), jnp.asarray(p.d2), restoring(p, x[3:6])
    )
    return m.mass_inverse @ rhs


def dynamics(m: AUVModel, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ = [J(η) ν, ν̇]`` ``(12,)``."""
    return jnp.concatenate([marine.kinematics_jacobian(x[:6]) @ x[6:], acceleration(m, x, u)])


def output(m: AUVModel, x: jax.Array) -> jax.Array:
    """The whole state (exact inertial navigation)."""
    return x


def inverse_dynamics(params: AUVParams, x: jax.Array, nu_r: jax.Array, nu_r_dot: jax.Array) -> jax.Array:
    """``M ν̇_r + C(ν) ν_r + D(ν) ν_r + g(η)`` with this model's parameters (computed torque)."""
    return marine.inverse_dynamics(
        params.mass_matrix,
        jnp.asarray(params.d1),
        jnp.asarray(params.d2),
        restoring(params, x[3:6]),
        x[6:],
        nu_r,
        nu_r_dot,
    )


def energy(params: AUVParams, x: jax.Array) -> jax.Array:
    """Kinetic + potential energy (J), up to a constant."""
    return marine.kinetic_energy(params.mass_matrix, x[6:]) + marine.potential_energy(
        x[:6], params.weight, params.buoyancy, jnp.asarray(params.r_g), jnp.asarray(params.r_b)
    )


def validate(params: AUVParams) -> None:
    """Shapes and values of every field; ``ValueError`` naming the field."""
    for name in ("M_R", "M_A"):
        check_shape(name, getattr(params, name), (6, 6))
        check_finite(name, getattr(params, name))
    marine.check_mass_matrix("M (= M_R + M_A)", params.mass_matrix)
    for name in ("d1", "d2"):
        check_shape(name, getattr(params, name), (6,))
        check_positive(name, getattr(params, name), allow_zero=True)
    for name in ("r_g", "r_b"):
        check_shape(name, getattr(params, name), (3,))
        check_finite(name, getattr(params, name))
    check_positive("weight", params.weight, allow_zero=True)
    check_positive("buoyancy", params.buoyancy, allow_zero=True)


def auv_plant(params: AUVParams | None = None) -> Plant:
    """The AUV as a :class:`~jaxsim.core.system.Plant` (12 states, 6 inputs, 12 outputs)."""
    p = AUVParams() if params is None else params
    validate(p)
    return Plant(model(p), dynamics, output, n_states=N_STATES, n_inputs=6, n_outputs=N_STATES, name="auv_6dof")


def initial_state(position: Any, euler: Any = (0.0, 0.0, 0.0), nu: Any = None) -> jax.Array:
    """State ``(12,)`` from a position ``(3,)``, Euler angles ``(3,)`` and body velocity ``(6,)``."""
    nu = jnp.zeros(6) if nu is None else jnp.asarray(nu, dtype=float)
    return jnp.concatenate([jnp.asarray(position, dtype=float), jnp.asarray(euler, dtype=float), nu])
