"""Switching functions for sliding-mode control and observers, exact and smooth.

A sliding-mode law injects ``k·σ(s)`` where ``σ`` is the sign of a switching variable ``s``.  The
exact sign is what the theory uses and what results should be reported with; the smooth forms
replace it inside a *boundary layer* so that an integrator (and ``grad``) can pass through.  All
functions map an array ``s`` element-wise to ``[−1, 1]`` and are odd.  The width parameter has the
unit of ``s``; each one is exact in the limit ``width → 0``:

=====================  ====================================  ==================================  ==========================
function               formula                               boundary layer                      smoothness
=====================  ====================================  ==================================  ==========================
:func:`sign`           ``sign(s)`` (``0`` at ``s = 0``)      none                                discontinuous; zero gradient
:func:`saturation`     ``clip(s/φ, −1, 1)``                  ``|s| ≤ φ`` (linear, slope ``1/φ``)  continuous, kinks at ``±φ``
:func:`tanh_sign`      ``tanh(s/τ)``                         ``|s| ≲ 2τ`` (``tanh 2 = 0.96``)     analytic; slope ``1/τ`` at 0
:func:`ratio_sign`     ``s/(|s| + ε)``                       ``|s| ≲ ε`` (value ½ at ``|s| = ε``) C¹; slope ``1/ε`` at 0
=====================  ====================================  ==================================  ==========================

:func:`smooth_sign` is :func:`tanh_sign` for ``width > 0`` and :func:`sign` for ``width = 0``, chosen
by value (not by name), so a model can carry the smoothing as a tunable parameter.

``ratio_sign`` is the "equivalent injection" formula ``v_eq = e/(|e| + ε)`` of sliding-mode fault
identification (seed 000, paper 2, eq. 3.6).  Its tail converges slowly (error ``ε/|s|``), so for
the same slope at zero it approximates ``sign`` worse than ``tanh_sign`` far from the surface.

Inside a simulation the slope at zero matters most: a gain ``k`` on ``σ(s)`` acts on small ``s``
as the linear gain ``k/width`` — the stiffness an integrator must handle (see
:class:`~jaxsim.core.integrators.SemiImplicitEuler`).  :data:`SWITCHES` maps names to functions with
the common signature ``fn(s, width)`` (``width`` ignored by ``sign``).
"""

from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp

from jaxsim.core.validation import check_positive

Switch = Callable[[jax.Array, jax.Array], jax.Array]


def sign(s: jax.Array, width: jax.Array | float | None = None) -> jax.Array:
    """Exact ``sign(s)`` (``0`` at ``s = 0``); ``width`` is accepted for a common signature and ignored."""
    return jnp.sign(s)


def saturation(s: jax.Array, width: jax.Array | float) -> jax.Array:
    """``clip(s/width, −1, 1)``: linear inside the boundary layer ``|s| ≤ width``."""
    check_positive("width", width)
    return jnp.clip(s / width, -1.0, 1.0)


def tanh_sign(s: jax.Array, width: jax.Array | float) -> jax.Array:
    """``tanh(s/width)``; ``width`` is the temperature τ (within 4 % of ``sign`` for ``|s| ≥ 2τ``)."""
    check_positive("width", width)
    return jnp.tanh(s / width)


def smooth_sign(s: jax.Array, width: jax.Array | float) -> jax.Array:
    """``tanh(s/width)`` where ``width > 0``, the exact ``sign(s)`` where ``width = 0``.

    For a smoothing that is a *parameter* (an array leaf a study switches off for reporting and on
    for the gradient path, e.g. dry friction ``sgn v`` of :mod:`jaxsim.plants.trms`): both branches
    share one compiled function, and the gradient is NaN-free for either (the division is guarded).
    ``width`` must be ``≥ 0`` (the caller validates it; a negative width gives ``sign``)."""
    smooth = width > 0
    return jnp.where(smooth, jnp.tanh(s / jnp.where(smooth, width, 1.0)), jnp.sign(s))


def ratio_sign(s: jax.Array, width: jax.Array | float) -> jax.Array:
    """``s/(|s| + width)``: the paper's equivalent-injection formula with ``ε = width``."""
    check_positive("width", width)
    return s / (jnp.abs(s) + width)


SWITCHES: dict[str, Switch] = {
    "sign": sign,
    "saturation": saturation,
    "tanh": tanh_sign,
    "ratio": ratio_sign,
}


def get_switch(name: str) -> Switch:
    """The switching function called ``name`` (one of :data:`SWITCHES`); ``ValueError`` otherwise."""
    try:
        return SWITCHES[name]
    except KeyError:
        raise ValueError(f"switch: must be one of {sorted(SWITCHES)}, got {name!r}") from None
