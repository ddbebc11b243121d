"""Open-loop controllers (they ignore the measurement): play an input sequence, or pass the reference through.

Useful to drive a closed-loop rollout with recorded or random inputs, e.g. to compare a plant
under the same inputs through two paths (``simulate`` vs an env, ODE vs an MJCF model).
:func:`open_loop` plays ``u_seq[k]`` at controller tick ``k``; :func:`feedforward` outputs
``u_k = r(t_k)``, so the reference signal *is* the input (held by zero-order hold over each period).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxsim.core.system import Controller
from jaxsim.core.validation import check_finite


def _init(u_seq: jax.Array, r0: jax.Array, y0: jax.Array) -> jax.Array:
    return jnp.asarray(0)


def _step(u_seq: jax.Array, k: jax.Array, r: jax.Array, y: jax.Array, dt, t) -> tuple[jax.Array, jax.Array]:
    return k + 1, u_seq[jnp.minimum(k, u_seq.shape[0] - 1)]


def open_loop(u_seq: jax.Array) -> Controller:
    """Controller outputting ``u_seq[k]`` at tick ``k`` (``u_seq (N, m)``; the last row is held after ``N``)."""
    u_seq = jnp.asarray(u_seq)
    if u_seq.ndim != 2 or u_seq.shape[0] < 1:
        raise ValueError(f"u_seq: expected shape (N, m) with N ≥ 1, got {tuple(u_seq.shape)}")
    check_finite("u_seq", u_seq)
    return Controller(u_seq, _init, _step, name="open_loop")


def _ff_init(params: None, r0: jax.Array, y0: jax.Array) -> tuple:
    return ()


def _ff_step(params: None, state: tuple, r: jax.Array, y: jax.Array, dt: float, t) -> tuple[tuple, jax.Array]:
    return state, r


def feedforward() -> Controller:
    """A stateless controller returning the reference as the plant input."""
    return Controller(params=None, init=_ff_init, step=_ff_step, name="feedforward")
