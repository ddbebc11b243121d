"""Ready-made odd-symmetric single-input fuzzy P controllers parametrised by breakpoints.

Both take breakpoints ``0 < p_1 < … < p_m`` on the error axis and output levels ``q_1 … q_m``, and
build ``2m + 1`` input terms N_m … N_1, Z, P_1 … P_m: triangles peaking at ``0, ±p_k`` whose feet
are the neighbouring peaks (a partition of unity), the outermost ones trapezoids extended as
shoulders.  Rule ``k``: "if e is term k then u is output k", mapping the peak ``±p_k`` to ``±q_k``.

* :func:`odd_sugeno` — zero-order Sugeno with constants ``0, ±q_k``.  With a partition of unity
  and one rule per term the output is *exactly* the piecewise-linear interpolation through
  ``(±p_k, ±q_k)``, constant beyond ``p_m``: for ``m = 2`` the paper's three-section
  characteristic with ``a = p_1, b = q_1, c = p_2, d = q_2``.
* :func:`odd_mamdani` — Mamdani with triangular output terms of half-width ``width`` centred on
  ``0, ±q_k``; its centroid characteristic is a smoothed version of the same shape.

All arguments may be traced, so the breakpoints can be tuned by gradient (pass them through an
order-preserving reparametrisation such as cumulative softplus to keep them sorted).
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from jaxsim.control.fuzzy.inference import FuzzySystem, mamdani, sugeno
from jaxsim.control.fuzzy.membership import Terms
from jaxsim.control.fuzzy.rules import rule_base

SHOULDER = 1e6  # error beyond which the outer shoulders are cut (far outside any universe)


def odd_input_terms(e_breaks: Any) -> Terms:
    """The ``2m + 1`` trapezoidal input terms for peaks ``0, ±p_k`` (ordered N_m … Z … P_m)."""
    p = jnp.asarray(e_breaks, float)
    peaks = jnp.concatenate([-p[::-1], jnp.zeros(1), p])
    left = jnp.concatenate([jnp.full(1, -SHOULDER), peaks[:-1]])
    right = jnp.concatenate([peaks[1:], jnp.full(1, SHOULDER)])
    plateau_l = peaks.at[0].set(-SHOULDER)
    plateau_r = peaks.at[-1].set(SHOULDER)
    return Terms(jnp.stack([left, plateau_l, plateau_r, right], axis=1), "trapezoidal")


def _identity_rules(n: int):
    return rule_base([[k] for k in range(n)], list(range(n)))


def odd_sugeno(e_breaks: Any, u_levels: Any) -> FuzzySystem:
    """Zero-order Sugeno P controller through ``(±p_k, ±q_k)`` (see module docstring)."""
    q = jnp.asarray(u_levels, float)
    consts = jnp.concatenate([-q[::-1], jnp.zeros(1), q])
    terms = odd_input_terms(e_breaks)
    return sugeno([terms], consts, _identity_rules(terms.params.shape[0]))


def odd_mamdani(
    e_breaks: Any, u_levels: Any, width: Any, *, u_range: float, n_grid: int = 201, defuzzifier: str = "centroid"
) -> FuzzySystem:
    """Mamdani P controller: output triangles of half-width ``width`` at ``0, ±q_k`` on a grid of
    ``n_grid`` points over ``[−u_range, u_range]``."""
    q = jnp.asarray(u_levels, float)
    centres = jnp.concatenate([-q[::-1], jnp.zeros(1), q])
    out = Terms(jnp.stack([centres - width, centres, centres + width], axis=1), "triangular")
    terms = odd_input_terms(e_breaks)
    grid = jnp.linspace(-u_range, u_range, n_grid)
    return mamdani([terms], grid, out, _identity_rules(terms.params.shape[0]), defuzzifier=defuzzifier)
