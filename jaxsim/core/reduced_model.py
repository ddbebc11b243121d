"""A plant's transformed reduced model and the bounds on its mismatch: the data a plant module gives
its fault-identification observer (seed 000, paper 2, model (2.2) and bounds (3.3)).

Plain pytrees, shared by a plant that knows its own reduced model
(:func:`jaxsim.plants.servo_drive.reduced_model`) and the observer that runs on any such model
(:mod:`jaxsim.estimation.reduced_order_smo`, which documents the model and re-exports these types),
so neither imports the other.
"""

from __future__ import annotations

from typing import Any, Callable

import jax

from jaxsim.core.pytree import pytree_dataclass, static_field

KnownTerms = Callable[[Any, jax.Array, jax.Array, jax.Array, jax.Array], tuple[jax.Array, jax.Array]]


@pytree_dataclass
class ReducedModel:
    """Transformed reduced model (2.2) in canonical coordinates ``z = (z1, z2)``, ``z1 = y*``::

        ż1 = F1 z1 + F2·z2 + r1(t, y, u, z2) + D1 d
        ż2 = F3 z1 + F4 z2 + r2(t, y, u, z2) + D2 d

    with ``d`` the scalar fault; block shapes for ``k − 1 = m``:
    ``F1`` (), ``F2`` (m,), ``F3`` (m,), ``F4`` (m, m), ``D1`` (), ``D2`` (m,).

    ``known(params, t, y, u, z2) -> (r1 (), r2 (m,))`` gives the known terms at time ``t`` for the
    measured output ``y``, held input ``u`` and the (estimated) ``z2``;
    ``reduced_output(params, y) -> y*`` (scalar).
    """

    F1: Any
    F2: Any
    F3: Any
    F4: Any
    D1: Any
    D2: Any
    params: Any
    known: KnownTerms = static_field()
    reduced_output: Callable[[Any, jax.Array], jax.Array] = static_field()


@pytree_dataclass
class SlidingBounds:
    """Bounds (3.3) on the nonlinear mismatch and ``|d| ≤ beta`` on the fault."""

    N1: Any = 0.0
    M1: Any = 0.0
    N2: Any = 0.0
    M2: Any = 0.0
    beta: Any = 0.0
