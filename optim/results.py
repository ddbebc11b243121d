"""Results of the gradient-free searches (particle swarm, random, grid) and their box checks."""

from __future__ import annotations

from typing import Any, NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_int  # noqa: F401  (one integer check; re-exported for tune, pso, search)
from optim.reparam import check_bounds


class SearchHistory(NamedTuple):
    """Per iteration (swarm iteration, or batch of a random/grid search), NumPy arrays ``(T,)``.

    best_loss: best loss found so far; sims: cumulative simulations; wall_s: cumulative seconds.
    """

    best_loss: np.ndarray
    sims: np.ndarray
    wall_s: np.ndarray


class SearchResult(NamedTuple):
    """Outcome of a search: best point ``x`` ``(d,)``, its ``loss``, the history, simulations used,
    seconds of searching (setup and compilation excluded, reported as ``compile_s``), a message."""

    x: Any
    loss: float
    history: SearchHistory
    n_sims: int
    wall_s: float
    compile_s: float = 0.0
    message: str = ""


def as_box(lo: Any, hi: Any) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Validate search bounds and return them as float arrays of shape ``(d,)``.

    Raises ``ValueError`` naming ``lo``/``hi`` for non-finite bounds, ``lo ≥ hi``, or shapes that
    do not give a 1-D box.
    """
    a = np.asarray(lo, dtype=float)
    b = np.asarray(hi, dtype=float)
    try:
        a, b = np.broadcast_arrays(a, b)
    except ValueError:
        raise ValueError(f"lo/hi: shapes {np.shape(lo)} and {np.shape(hi)} do not broadcast") from None
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"lo/hi: must describe a 1-D box of shape (d,), got shape {a.shape}")
    check_bounds(a, b)
    return jnp.asarray(a), jnp.asarray(b)


def check_some_loss_finite(best_loss: float, where: str, hint: str = "") -> None:
    """Raise the error every tuner and search shares when no evaluated loss was finite.

    ``where`` says what was evaluated (``"30 particles × 100 iterations"``), ``hint`` what to check.
    """
    if not np.isfinite(best_loss):
        raise ValueError(f"loss: not finite (NaN/inf) at any evaluated point ({where}); nothing to "
                         f"return{'; ' + hint if hint else ''}")


