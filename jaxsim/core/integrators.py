"""Fixed-step integrators for ``ẋ = f(t, x)``.

Each solver is a small frozen object with one method, ``step(f, t, x, dt) -> x_next``, so the
rollout can swap them like diffrax's solver objects:

* :data:`EULER`, :data:`RK4` — explicit Runge–Kutta methods given by their Butcher tableau
  (:class:`ExplicitRK`; a new explicit method is a new tableau);
* :data:`RK4_ROLLED` — the same RK4 arithmetic with its four stages in a ``lax.scan``
  (:class:`RolledRK4`): the vector field is traced and compiled once instead of four times, for
  heavy fields (a Lagrangian plant's nested derivatives) whose compile time dominates;
* :class:`SemiImplicitEuler` — linearly implicit (Rosenbrock–Euler) step
  ``x + dt (I − dt J)⁻¹ f(t, x)`` with ``J = ∂f/∂x`` from ``jacfwd``: A-stable, for stiff parts such
  as high-gain observers;
* :class:`ExponentialEuler` — ``x + dt φ₁(dt J) f(t, x)`` with ``φ₁(z) = (eᶻ − 1)/z`` evaluated by one
  matrix exponential of an augmented matrix.  For an LTI plant with its input held constant over
  the step (zero-order hold) this *is* the exact discretisation, whatever ``dt``.

``x`` is a 1-D array of shape ``(n,)``; ``t`` and ``dt`` are scalars in the model's time unit.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

VectorField = Callable[[jax.Array, jax.Array], jax.Array]


@dataclass(frozen=True)
class ExplicitRK:
    """Explicit Runge–Kutta method given by its Butcher tableau (``a`` strictly lower triangular)."""

    name: str
    a: tuple[tuple[float, ...], ...]
    b: tuple[float, ...]
    c: tuple[float, ...]
    order: int

    def step(self, f: VectorField, t: jax.Array, x: jax.Array, dt: jax.Array) -> jax.Array:
        stages: list[jax.Array] = []
        for i, ci in enumerate(self.c):
            xi = x
            for aij, kj in zip(self.a[i], stages):
                if aij != 0.0:
                    xi = xi + dt * aij * kj
            stages.append(f(t + ci * dt, xi))
        incr = sum(bi * ki for bi, ki in zip(self.b, stages) if bi != 0.0)
        return x + dt * incr


EULER = ExplicitRK("euler", a=((),), b=(1.0,), c=(0.0,), order=1)
HEUN = ExplicitRK("heun", a=((), (1.0,)), b=(0.5, 0.5), c=(0.0, 1.0), order=2)
RK4 = ExplicitRK(
    "rk4",
    a=((), (0.5,), (0.0, 0.5), (0.0, 0.0, 1.0)),
    b=(1 / 6, 1 / 3, 1 / 3, 1 / 6),
    c=(0.0, 0.5, 0.5, 1.0),
    order=4,
)


@dataclass(frozen=True)
class RolledRK4:
    """Classical RK4 with its stages in a ``lax.scan`` over ``(c_i, b_i)``: ``k_i = f(t + c_i dt,
    x + c_i dt k_{i−1})``, ``x + dt Σ b_i k_i`` — the tableau of :data:`RK4` (each stage uses only the
    previous one), so the results equal :data:`RK4`'s to rounding while ``f`` appears once in the
    program (a quarter of its compile time; the scan costs a little at run time)."""

    name: str = "rk4_rolled"
    order: int = 4

    def step(self, f: VectorField, t: jax.Array, x: jax.Array, dt: jax.Array) -> jax.Array:
        def stage(carry: tuple[jax.Array, jax.Array], cb: jax.Array) -> tuple[tuple[jax.Array, jax.Array], None]:
            k_prev, acc = carry
            k = f(t + cb[0] * dt, x + cb[0] * dt * k_prev)
            return (k, acc + cb[1] * k), None

        cb = jnp.asarray(np.column_stack([RK4.c, RK4.b]), dtype=jnp.result_type(x, float))
        (_, acc), _ = jax.lax.scan(stage, (jnp.zeros_like(x), jnp.zeros_like(x)), cb)
        return x + dt * acc


RK4_ROLLED = RolledRK4()


def _field_and_jacobian(f: VectorField, t: jax.Array, x: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``f(t, x)`` and ``∂f/∂x`` (forward mode: states are few)."""
    return f(t, x), jax.jacfwd(lambda z: f(t, z))(x)


@dataclass(frozen=True)
class SemiImplicitEuler:
    """Linearly implicit Euler: one Newton iteration of backward Euler, Jacobian by ``jacfwd``."""

    name: str = "semi_implicit_euler"
    order: int = 1

    def step(self, f: VectorField, t: jax.Array, x: jax.Array, dt: jax.Array) -> jax.Array:
        fx, jac = _field_and_jacobian(f, t, x)
        lhs = jnp.eye(x.shape[0], dtype=x.dtype) - dt * jac
        return x + dt * jnp.linalg.solve(lhs, fx)


def phi1_times(mat: jax.Array, vec: jax.Array, dt: jax.Array) -> jax.Array:
    """Return ``dt · φ₁(dt·mat) · vec`` via ``expm([[mat, vec], [0, 0]]·dt)`` (top-right column)."""
    n = mat.shape[0]
    aug = jnp.zeros((n + 1, n + 1), dtype=mat.dtype)
    aug = aug.at[:n, :n].set(mat).at[:n, n].set(vec)
    return jax.scipy.linalg.expm(aug * dt)[:n, n]


@dataclass(frozen=True)
class ExponentialEuler:
    """Exponential Euler step; exact for ``ẋ = A x + b`` with ``A, b`` constant over the step."""

    name: str = "exponential_euler"
    order: int = 1

    def step(self, f: VectorField, t: jax.Array, x: jax.Array, dt: jax.Array) -> jax.Array:
        fx, jac = _field_and_jacobian(f, t, x)
        return x + phi1_times(jac, fx, dt)


Solver = ExplicitRK | SemiImplicitEuler | ExponentialEuler


def integrate(
    f: VectorField,
    x0: jax.Array,
    t0: float,
    dt: float,
    n_steps: int,
    solver: Solver = RK4,
) -> tuple[jax.Array, jax.Array]:
    """Integrate ``ẋ = f(t, x)`` with ``n_steps`` fixed steps.

    Returns ``(ts, xs)`` with ``ts`` of shape ``(n_steps + 1,)`` and ``xs`` of shape
    ``(n_steps + 1, n)``; ``xs[0] = x0``.
    """
    if int(n_steps) < 1:
        raise ValueError(f"n_steps: must be a positive integer, got {n_steps!r}")
    if not np.isfinite(float(dt)) or float(dt) <= 0:
        raise ValueError(f"dt: must be positive and finite, got {dt!r}")
    x0 = jnp.asarray(x0)
    dt_arr = jnp.asarray(dt, dtype=x0.dtype)
    ts = t0 + dt_arr * jnp.arange(n_steps + 1, dtype=x0.dtype)

    def body(x, t):
        x_next = solver.step(f, t, x, dt_arr)
        return x_next, x_next

    _, xs = jax.lax.scan(body, x0, ts[:-1])
    return ts, jnp.concatenate([x0[None], xs], axis=0)
