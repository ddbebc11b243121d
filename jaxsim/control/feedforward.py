"""Open-loop (feedforward) controller: the plant input is the reference signal, ``u_k = r(t_k)``.

Lets :func:`~jaxsim.core.rollout.simulate` play a given input sequence into a plant (held by
zero-order hold over each controller period), e.g. to compare two models of one plant.
"""

from __future__ import annotations

import jax

from jaxsim.core.system import Controller


def _init(params: None, r0: jax.Array, y0: jax.Array) -> tuple:
    return ()


def _step(params: None, state: tuple, r: jax.Array, y: jax.Array, dt: float) -> tuple[tuple, jax.Array]:
    return state, r


def feedforward() -> Controller:
    """A stateless controller returning the reference as the plant input."""
    return Controller(params=None, init=_init, step=_step, name="feedforward")
