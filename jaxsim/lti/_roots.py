"""Differentiable root finding of scalar functions: bracket on a grid, bisect, implicit derivative.

``f(v, theta)`` maps an array of points ``v`` (shape ``(K,)``) to ``(K,)`` values, elementwise in
``v`` (entry ``i`` depends on ``v[i]`` only; different entries may be different functions), with
parameters ``theta`` (any pytree).  Roots are bracketed by sign changes of sampled values,
refined by bisection on ``stop_gradient(theta)`` (a fixed number of steps: ``jit``/``vmap``-
friendly, nothing to differentiate through), and given their derivative by the implicit-function
theorem, ``dv*/dθ = −(∂f/∂θ)/(∂f/∂v)`` at the root: the value returned is the bisection's ``v*``
exactly, its tangent that of ``v* − f(v*, θ)/f_v`` with ``v*`` and ``f_v`` held fixed (forward and
reverse mode; first derivatives).
"""

from __future__ import annotations

from typing import Any, Callable

import jax
import jax.numpy as jnp

VectorFn = Callable[[jax.Array, Any], jax.Array]
BISECTION_STEPS = 60  # a bracket shrinks by 2^-60: from a grid cell to below float64 resolution


def sign_change_brackets(values: jax.Array, k: int, rising_only: bool = False) -> tuple[jax.Array, jax.Array]:
    """Indices ``i`` (the first ``k``, ascending) with a sign change between ``values[i]`` and
    ``values[i + 1]`` (both finite), and which of the ``k`` slots hold one.  ``rising_only`` keeps
    only ``≤ 0`` → ``> 0`` changes (the minima of a function whose derivative ``values`` is)."""
    a, b = values[:-1], values[1:]
    finite = jnp.isfinite(a) & jnp.isfinite(b)
    change = (a <= 0) & (b > 0) if rising_only else (a > 0) != (b > 0)
    mask = finite & change
    idx = jnp.nonzero(mask, size=k, fill_value=0)[0]
    return idx, jnp.arange(k) < jnp.sum(mask)


def bisect(
    f: VectorFn, theta: Any, lo: jax.Array, hi: jax.Array, steps: int = BISECTION_STEPS
) -> tuple[jax.Array, jax.Array]:
    """Midpoints of the brackets ``[lo, hi]`` (``(K,)``) after ``steps`` bisections of
    ``f(·, stop_gradient(theta))``, and ``f`` at the final left ends (the residual: tiny at a root,
    not at a jump); a bracket without a sign change just shrinks somewhere."""
    theta0 = jax.lax.stop_gradient(theta)
    lo, hi = jax.lax.stop_gradient(lo), jax.lax.stop_gradient(hi)

    def body(_, state):
        a, b, fa = state
        mid = 0.5 * (a + b)
        fm = f(mid, theta0)
        right = (fm > 0) == (fa > 0)  # no sign change on [a, mid]: the root is in [mid, b]
        return jnp.where(right, mid, a), jnp.where(right, b, mid), jnp.where(right, fm, fa)

    a, b, fa = jax.lax.fori_loop(0, steps, body, (lo, hi, f(lo, theta0)))
    return 0.5 * (a + b), fa


def implicit(f: VectorFn, theta: Any, v_star: jax.Array, valid: jax.Array) -> jax.Array:
    """``v_star`` (roots of ``f(·, θ)``, ``(K,)``) carrying the implicit-function derivative with
    respect to ``θ``; slots that are not ``valid``, or where ``∂f/∂v = 0``, get a zero tangent."""
    v0 = jax.lax.stop_gradient(v_star)
    theta0 = jax.lax.stop_gradient(theta)
    f_v = jax.jvp(lambda v: f(v, theta0), (v0,), (jnp.ones_like(v0),))[1]
    ok = valid & jnp.isfinite(f_v) & (f_v != 0)
    g = f(v0, theta) / jnp.where(ok, f_v, 1.0)
    g = jnp.where(ok & jnp.isfinite(jax.lax.stop_gradient(g)), g, 0.0)
    return v0 - (g - jax.lax.stop_gradient(g))
