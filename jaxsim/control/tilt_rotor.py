"""Emergency control of a tilt-rotor quadcopter flying on two adjacent rotors (seed 004 part 3, #8;
plant :mod:`jaxsim.plants.tilt_rotor`).

With only the front rotors 1 and 4 left, the control is ``u = [ω_1, ω_4, ϑ_1, ϑ_4]`` (the paper's
eq. (1)).  Level hover is then impossible: both thrusts act ahead of the centre of mass, so their
pitch moment can only be cancelled by tilting the rotors (whose horizontal thrust, acting ``h`` above
the centre of mass, makes a counter-moment) — and the body must pitch until the total thrust is
vertical again.  :func:`hover_trim` solves the six equilibrium equations (force and moment) for the
four inputs and the body's roll and pitch by Levenberg–Marquardt from a vmapped set of starts (the
paper's "eq. (2) solved for u"); :func:`level_hover_defect` shows by the same solver that with the
body held level no input balances the vehicle.

The controller is an LQR with integral action on the position error, designed on the linearisation
at the trim in error coordinates ``e = (r − r_ref, v − v_ref, φ, Ω, ξ)`` (``φ`` the rotation vector
of ``q_trim⁻¹ ⊗ q``, ``ξ = ∫(r − r_ref) dt``), so attitude changes steer the total thrust and the
centre of mass follows the reference (return to base, descent).  Inputs are clipped to the motor
and servo limits.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.control.lqr import lqr
from jaxsim.core.least_squares import levenberg_marquardt_solve
from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.rotations import quat_exp, quat_mul, quat_rotation_vector
from jaxsim.core.system import Controller
from jaxsim.plants import tilt_rotor as tr

WORKING = (0, 3)
"""Indices of the working rotors (1 and 4, the front pair)."""

N_ERR = 15
"""Error-state size: position, velocity, attitude, body rate, integral of the position error."""


def full_input(u: jax.Array) -> jax.Array:
    """The plant's ``(8,)`` input from ``u = [ω_1, ω_4, ϑ_1, ϑ_4]`` (the failed rotors' entries 0)."""
    full = jnp.zeros(8, u.dtype)
    return full.at[jnp.array(WORKING)].set(u[:2]).at[4 + jnp.array(WORKING)].set(u[2:])


def attitude(roll: jax.Array, pitch: jax.Array) -> jax.Array:
    """Quaternion of zero yaw, then ``pitch`` about ``y``, then ``roll`` about ``x`` (rad)."""
    zero = jnp.zeros_like(roll)
    return quat_mul(quat_exp(jnp.stack([zero, pitch, zero])), quat_exp(jnp.stack([roll, zero, zero])))


def hover_state(q: jax.Array, position: Any = (0.0, 0.0, 0.0)) -> jax.Array:
    """``x (13,)`` at rest at ``position`` (m) with attitude ``q``."""
    return jnp.concatenate([jnp.asarray(position, q.dtype), jnp.zeros(3, q.dtype), q, jnp.zeros(3, q.dtype)])


def trim_residual(p: tr.TiltRotorParams, z: jax.Array) -> jax.Array:
    """Linear (m/s²) and angular (rad/s²) accelerations ``(6,)`` at rest for ``z = [ω_1, ω_4, ϑ_1,
    ϑ_4, roll, pitch]``; zero at an equilibrium."""
    xdot = tr.dynamics(p, hover_state(attitude(z[4], z[5])), full_input(z[:4]), jnp.zeros(()))
    return jnp.concatenate([xdot[3:6], xdot[10:13]])


class Trim(NamedTuple):
    """A hover equilibrium: ``u (4,)`` (rad/s, rad), ``roll``/``pitch`` (rad), its quaternion ``q (4,)``
    and the residual ``cost = Σ residual²`` of :func:`trim_residual` (≈ 0 at a true equilibrium)."""

    u: jax.Array
    roll: jax.Array
    pitch: jax.Array
    q: jax.Array
    cost: jax.Array


def hover_trim(p: tr.TiltRotorParams, starts: jax.Array, tilt_max: float, max_steps: int = 200) -> Trim:
    """The equilibrium from ``starts (S, 6)`` (vmapped Levenberg–Marquardt runs) with positive rotor
    speeds, ``|ϑ_i| ≤ tilt_max`` and the smallest ``|pitch|``; ``cost`` is ``inf`` if no run found one
    (residual above 1e-12)."""
    runs = jax.vmap(lambda z0: levenberg_marquardt_solve(lambda z: trim_residual(p, z), z0, max_steps=max_steps))(
        starts
    )
    z = runs.u
    # fold the angles into (−π, π]; speeds enter squared, so their sign is irrelevant
    ang = jnp.mod(z[:, 2:] + jnp.pi, 2 * jnp.pi) - jnp.pi
    z = jnp.concatenate([jnp.abs(z[:, :2]), ang], axis=1)
    ok = (runs.cost < 1e-12) & jnp.all(jnp.abs(z[:, 2:4]) <= tilt_max, axis=1)
    score = jnp.where(ok, jnp.abs(z[:, 5]), jnp.inf)
    best = jnp.argmin(score)
    zb = z[best]
    return Trim(zb[:4], zb[4], zb[5], attitude(zb[4], zb[5]), jnp.where(ok[best], runs.cost[best], jnp.inf))


def level_hover_defect(p: tr.TiltRotorParams, starts: jax.Array, max_steps: int = 200) -> jax.Array:
    """Smallest ``Σ residual²`` ((m/s²)² + (rad/s²)²) over ``starts (S, 4)`` of ``[ω_1, ω_4, ϑ_1, ϑ_4]``
    with the body held level (roll = pitch = 0): positive iff no level hover exists."""

    def one(z0: jax.Array) -> jax.Array:
        f = lambda u: trim_residual(p, jnp.concatenate([u, jnp.zeros(2, u.dtype)]))  # noqa: E731
        return levenberg_marquardt_solve(f, z0, max_steps=max_steps).cost

    return jnp.min(jax.vmap(one)(starts))


def error_state(x: jax.Array, x_ref: jax.Array, q_trim: jax.Array) -> jax.Array:
    """``(12,)``: ``r − r_ref``, ``v − v_ref`` (world), the rotation vector of ``q_trim⁻¹ ⊗ q`` (rad)
    and ``Ω`` (rad/s); ``x_ref (13,)`` holds the reference position and velocity first."""
    q_err = quat_mul(q_trim * jnp.array([1.0, -1.0, -1.0, -1.0]), x[6:10] / jnp.linalg.norm(x[6:10]))
    return jnp.concatenate([x[:3] - x_ref[:3], x[3:6] - x_ref[3:6], quat_rotation_vector(q_err), x[10:13]])


def error_dynamics(p: tr.TiltRotorParams, trim: Trim, e: jax.Array, du: jax.Array) -> jax.Array:
    """``ė (12,)`` near the trim for the error state ``e (12,)`` (reference at rest at the origin) and the
    input deviation ``du (4,)``; the attitude error rate is taken as ``φ̇ = Ω``, exact to first order at
    ``φ = 0`` (the linearisation point)."""
    x = jnp.concatenate([e[:6], quat_mul(trim.q, quat_exp(e[6:9])), e[9:12]])
    xdot = tr.dynamics(p, x, full_input(trim.u + du), jnp.zeros(()))
    return jnp.concatenate([xdot[:6], x[10:13], xdot[10:13]])


def linearise(p: tr.TiltRotorParams, trim: Trim) -> tuple[jax.Array, jax.Array]:
    """``(A (15, 15), B (15, 4))`` of the error dynamics at the trim (integral states appended)."""
    a12, b12 = jax.jacfwd(lambda e, du: error_dynamics(p, trim, e, du), argnums=(0, 1))(jnp.zeros(12), jnp.zeros(4))
    a = jnp.zeros((N_ERR, N_ERR)).at[:12, :12].set(a12).at[12:, :3].set(jnp.eye(3))
    b = jnp.zeros((N_ERR, 4)).at[:12].set(b12)
    return a, b


@pytree_dataclass
class TiltRotorLQRParams:
    """``k (4, 15)``: LQR gain; ``u_trim (4,)``; ``q_trim (4,)``; ``u_lo``/``u_hi (4,)``: input limits."""

    k: Any
    u_trim: Any
    q_trim: Any
    u_lo: Any
    u_hi: Any


def lqr_params(
    a: jax.Array, b: jax.Array, q: jax.Array, r: jax.Array, trim: Trim, omega_max: float, tilt_max: float
) -> TiltRotorLQRParams:
    """Gains from the weights ``q (15, 15)``, ``r (4, 4)`` (differentiable: the Riccati solver's implicit
    derivatives) and the limits ``0 ≤ ω ≤ omega_max`` (rad/s), ``|ϑ| ≤ tilt_max`` (rad)."""
    return TiltRotorLQRParams(
        k=lqr(a, b, q, r).k,
        u_trim=trim.u,
        q_trim=trim.q,
        u_lo=jnp.array([0.0, 0.0, -tilt_max, -tilt_max]),
        u_hi=jnp.array([omega_max, omega_max, tilt_max, tilt_max]),
    )


def _init(params: TiltRotorLQRParams, r0: jax.Array, y0: jax.Array) -> jax.Array:
    return jnp.zeros(3, y0.dtype)


def _step(params: TiltRotorLQRParams, xi: jax.Array, r: jax.Array, y: jax.Array, dt: Any, t: jax.Array):
    e = error_state(y, r, params.q_trim)
    u = jnp.clip(params.u_trim - params.k @ jnp.concatenate([e, xi]), params.u_lo, params.u_hi)
    return xi + dt * e[:3], full_input(u)


def lqr_controller(params: TiltRotorLQRParams) -> Controller:
    """``u = clip(u_trim − K [e; ξ])`` on the full measured state, ``ξ`` the integral of the position
    error (controller state); the reference is a ``(13,)`` signal (position and velocity first)."""
    return Controller(params=params, init=_init, step=_step, name="tilt_rotor_lqr")


@pytree_dataclass
class ReturnPath:
    """Reference: from ``start (3,)`` (m) fly level to above ``base (3,)`` in ``t_transit`` s, then descend
    to ``base`` in ``t_descent`` s, each leg a quintic (minimum-jerk) blend; holds ``base`` after.
    Calling it at ``t`` gives ``(13,)``: position, velocity, ``q_trim``, zero rate."""

    start: Any
    base: Any
    t_transit: Any
    t_descent: Any
    q_trim: Any

    def __call__(self, t: jax.Array) -> jax.Array:
        start, base = jnp.asarray(self.start), jnp.asarray(self.base)
        above = base.at[2].set(start[2])

        def blend(s: jax.Array, dur: Any) -> tuple[jax.Array, jax.Array]:
            s = jnp.clip(s, 0.0, 1.0)
            return 10 * s**3 - 15 * s**4 + 6 * s**5, (30 * s**2 - 60 * s**3 + 30 * s**4) / dur

        s1, ds1 = blend(t / self.t_transit, self.t_transit)
        s2, ds2 = blend((t - self.t_transit) / self.t_descent, self.t_descent)
        pos = start + (above - start) * s1 + (base - above) * s2
        vel = (above - start) * ds1 + (base - above) * ds2
        return jnp.concatenate([pos, vel, jnp.asarray(self.q_trim), jnp.zeros(3)])
