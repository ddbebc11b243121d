"""The result type every tuner returns (:class:`TuneResult`, :class:`History`) and the shared argument checks."""

from __future__ import annotations

from typing import Any, NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_int  # noqa: F401  (one integer check; re-exported for tune, pso, search)
from jaxsim.problem.reparam import check_bounds


class History(NamedTuple):
    """Per step (tuner step, swarm iteration, or batch of a random/grid search), NumPy arrays.

    best_loss ``(T,)``: loss of the best point kept so far; sims ``(T,)``: cumulative simulations;
    wall_s ``(T,)``: cumulative seconds since the first step (compilation excluded); loss ``(T,)``:
    the lowest loss evaluated at that step (over the running starts, the swarm, the batch).
    Gradient tuner only (``None`` otherwise): grad_norm ``(T,)`` of the start giving ``loss``, in
    unconstrained coordinates; loss_per_start, grad_norm_per_start, violation_per_start ``(T, S)``.
    """

    best_loss: np.ndarray
    sims: np.ndarray
    wall_s: np.ndarray
    loss: np.ndarray | None = None
    grad_norm: np.ndarray | None = None
    loss_per_start: np.ndarray | None = None
    grad_norm_per_start: np.ndarray | None = None
    violation_per_start: np.ndarray | None = None


class TuneResult(NamedTuple):
    """What every tuner and search returns.

    params: the best point (the params pytree of a Problem, or ``params0``'s structure for
    :func:`optim.tune`, or the point ``(d,)`` of a search over a plain box); loss: its loss (without
    penalty terms for the gradient tuner; the searches' penalised loss); history: :class:`History`;
    n_sims: simulations used (loss evaluations × scenarios; for ``tune`` a gradient evaluation counts
    ``grad_cost`` of them: 1 by default, its measured cost with ``grad_cost="measure"``); wall_s:
    seconds of stepping (compile excluded); compile_s: setup and compilation; converged: whether
    the tuner's convergence test was met (``tune``: gradient norm or relative improvement; ``pso``:
    swarm collapsed or no improvement for ``patience`` iterations; random and grid search have
    none: ``False``), not merely that the budget ran out; message: why it stopped.  Gradient tuner
    only: start_index (the start that found ``params``), constraint_violation ``Σ max(0, g)`` at
    ``params``, multipliers (augmented Lagrangian), n_steps, mode ("forward" / "reverse"), n_evals
    (gradient evaluations plus line-search trials, each × scenarios per loss evaluation; ``n_sims``
    weighs them by ``grad_cost``), grad_cost (loss-evaluation equivalents of one gradient
    evaluation: 1, given, or measured by :func:`optim.tune.grad_cost`).  u: the point in the
    tuner's own coordinates (unconstrained for ``tune``, search coordinates for the searches).
    """

    params: Any
    loss: float
    history: History
    n_sims: int
    wall_s: float
    compile_s: float = 0.0
    converged: bool = False
    message: str = ""
    start_index: int = 0
    u: Any = None
    constraint_violation: float = 0.0
    multipliers: Any = None
    n_steps: int = 0
    mode: str = ""
    n_evals: int = 0
    grad_cost: float = 1.0

    @property
    def x(self) -> Any:
        """Deprecated alias of :attr:`params` (the searches' old name for the best point)."""
        return self.params


SearchHistory = History
"""Deprecated alias: the searches now return :class:`History`."""
SearchResult = TuneResult
"""Deprecated alias: every tuner returns :class:`TuneResult`."""


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


def check_number(name: str, value: Any, *, allow_zero: bool = False) -> float:
    """Require a finite positive (or non-negative) number; return it as ``float``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: must be a number, got {value!r}") from None
    if not np.isfinite(v) or (v < 0 if allow_zero else v <= 0):
        rel = "non-negative" if allow_zero else "positive"
        raise ValueError(f"{name}: must be finite and {rel}, got {value!r}")
    return v


def check_some_loss_finite(best_loss: float, where: str, hint: str = "") -> None:
    """Raise the error every tuner and search shares when no evaluated loss was finite.

    ``where`` says what was evaluated (``"30 particles × 100 iterations"``), ``hint`` what to check.
    """
    if not np.isfinite(best_loss):
        raise ValueError(
            f"loss: not finite (NaN/inf) at any evaluated point ({where}); nothing to "
            f"return{'; ' + hint if hint else ''}"
        )
