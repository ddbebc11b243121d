"""L-BFGS with a backtracking (Armijo) line search whose trials are the tuner's own evaluations.

``optax.lbfgs(linesearch=optax.scale_by_backtracking_linesearch(...))`` evaluates trial points
inside its ``update`` through a ``value_fn``: a compiled tuner step then holds two copies of the
loss — the gradient evaluation and the line search's primal — and on a long rollout the second
copy is most of the compile time (TRMS: 13–18 s for the L-BFGS step against 9–11 s for Adam's).

:func:`lbfgs` moves the line search out of ``update``.  Every call evaluates one point — the
loss and its gradient, by the caller — and ``update`` answers where to evaluate next: after an
accepted point, the L-BFGS direction's first trial; after a rejected trial, the same direction
with the step cut by ``decrease_factor``.  So one ``update`` is one trial, the step compiles
the loss once, and an accepted trial's gradient is already there for the next direction (optax's
search evaluates the accepted point a second time, with its gradient, at the start of the next
step).  The accepted points — and so the iterates — are optax's, to rounding: the direction is
``optax.scale_by_lbfgs``'s, and acceptance is the same sufficient-decrease test with the same
step rules (see :func:`lbfgs`).  The cost moves the other way on a rejected trial, which now
also evaluates a gradient.

A trial whose loss is NaN/inf is a rejected trial (the step is cut), not a failure: the tuner asks
:func:`evaluates_trial` whether an evaluation was a trial.  The very first evaluation (``count ==
0`` of the direction's state) is the start itself.
"""

from __future__ import annotations

import math
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import optax

from optim.results import check_int


class TrialLinesearchState(NamedTuple):
    """State of :func:`lbfgs` (scalars unless said): ``direction_state`` the L-BFGS memory
    (``optax.ScaleByLBFGSState``); ``anchor`` the last accepted point (params' tree), its loss
    ``anchor_value`` and the search ``direction`` from it (params' tree, the step is
    ``learning_rate·direction``); ``slope`` ``⟨direction, ∇f(anchor)⟩``; ``learning_rate`` the
    step of the pending trial; ``trials`` (int32) trials of this search evaluated so far, 0 before
    the first evaluation of all; ``accepted`` (bool) whether the point the last ``update`` was given
    became the anchor (an iterate), as opposed to a rejected trial or a search given up."""

    direction_state: Any
    anchor: Any
    anchor_value: jax.Array
    direction: Any
    slope: jax.Array
    learning_rate: jax.Array
    trials: jax.Array
    accepted: jax.Array


def lbfgs(
    memory_size: int = 10,
    max_backtracking_steps: int = 30,
    decrease_factor: float = 0.5,
    increase_factor: float = math.inf,
    max_learning_rate: float = 1.0,
    slope_rtol: float = 1e-4,
    restart_uphill: bool = True,
) -> optax.GradientTransformationExtraArgs:
    """L-BFGS (``optax.scale_by_lbfgs`` directions) with a backtracking line search, one trial per
    ``update``.

    ``update(grad, state, params, value=f)`` takes the gradient and the loss ``f`` at ``params``,
    the point the previous update led to, and returns the step to the next point to evaluate (so
    it comes first in a chain: ``updates`` must be the gradient).  A trial
    at step ``η`` along direction ``d`` from the anchor ``x`` is accepted when
    ``f(x + η d) ≤ f(x) + slope_rtol·η·⟨d, ∇f(x)⟩`` or when it is the
    ``max_backtracking_steps + 1``-th trial of the search with a finite loss; otherwise the next
    trial is at ``decrease_factor·η``.  If the last trial's loss is not finite, the search gives
    up: the next point is the anchor, with step 0 (as optax, the run then stalls there).  A search
    starts at ``η = min(increase_factor·η_prev, max_learning_rate)``, ``η_prev`` the previous
    search's accepted step (1 at first); the default ``increase_factor=inf`` tries the full
    quasi-Newton step in every search (optax's default, 1, never lets the step grow back after a
    cut: on Rosenbrock's valley L-BFGS then crawls).  With ``restart_uphill=False`` these are
    optax's rules: ``optax.lbfgs(memory_size=..., linesearch=optax.scale_by_backtracking_linesearch(...))``
    with the same arguments accepts the same points (tested).  With ``restart_uphill`` (default) a
    direction that is not a descent direction — the sufficient-decrease test alone does not keep
    ``⟨s, y⟩ > 0``, and one such pair can turn it — is replaced by a fresh start of the memory
    (scaled steepest descent) where optax's search would exhaust its trials and stall.

    Args:
        memory_size: number of ``(s, y)`` pairs kept.
        max_backtracking_steps: step cuts per search before its last trial is accepted.
        decrease_factor: factor in (0, 1) cutting the step after a rejected trial.
        increase_factor: factor ≥ 1 on the previous accepted step for a search's first trial.
        max_learning_rate: largest first trial step, > 0.
        slope_rtol: sufficient-decrease constant in (0, 1).
        restart_uphill: restart the memory when its direction is not a descent direction.
    """
    check_int("memory_size", memory_size, 1)
    check_int("max_backtracking_steps", max_backtracking_steps, 0)
    _check_in("decrease_factor", decrease_factor, lambda v: 0.0 < v < 1.0, "a number in (0, 1)")
    _check_in("increase_factor", increase_factor, lambda v: v >= 1.0, "a number >= 1 (inf allowed)")
    _check_in("max_learning_rate", max_learning_rate, lambda v: 0.0 < v < math.inf, "a finite number > 0")
    _check_in("slope_rtol", slope_rtol, lambda v: 0.0 < v < 1.0, "a number in (0, 1)")
    direction_fn = optax.scale_by_lbfgs(memory_size=memory_size)

    def init_fn(params: Any) -> TrialLinesearchState:
        dtype = jnp.real(jnp.asarray(jax.tree_util.tree_leaves(params)[0])).dtype
        zeros = optax.tree.zeros_like(params)
        return TrialLinesearchState(
            direction_state=direction_fn.init(params),
            anchor=zeros,
            anchor_value=jnp.asarray(jnp.inf, dtype),
            direction=zeros,
            slope=jnp.asarray(0.0, dtype),
            learning_rate=jnp.asarray(1.0, dtype),
            trials=jnp.asarray(0, jnp.int32),
            accepted=jnp.asarray(False),
        )

    def update_fn(
        updates: Any, state: TrialLinesearchState, params: Any, *, value: jax.Array, **extra_args: Any
    ) -> tuple[Any, TrialLinesearchState]:
        del extra_args  # grad, value_fn & co.: the gradient is ``updates``; the loss is never called here
        grad = updates
        lr = state.learning_rate
        error = value - state.anchor_value - slope_rtol * lr * state.slope
        error = jnp.where(jnp.isnan(error), jnp.inf, jnp.maximum(error, 0.0))
        first = state.trials == 0
        last = state.trials > max_backtracking_steps
        accept = first | (error <= 0.0) | (last & jnp.isfinite(error))
        give_up = ~first & last & ~jnp.isfinite(error)

        # accepted (or the start): the next search from params
        step_dir, new_dir_state = direction_fn.update(grad, state.direction_state, params)
        if restart_uphill:
            # an Armijo-only search does not keep ⟨s, y⟩ > 0, and a pair with ⟨s, y⟩ < 0 can turn the
            # direction uphill (optax's search then stalls): restart the memory, steepest descent
            uphill = optax.tree.real(optax.tree.vdot(step_dir, grad)) <= 0.0
            # what scale_by_lbfgs's first update gives (empty memory: g·min(1, 1/‖g‖)), without a
            # second copy of its two-loop recursion in the compiled step
            fresh_dir = optax.tree.scale(jnp.minimum(1.0, 1.0 / optax.tree.norm(grad)), grad)
            one = jnp.asarray(1, jnp.int32)
            fresh_state = direction_fn.init(params)._replace(count=one, params=params, updates=grad)
            step_dir = jax.tree_util.tree_map(lambda a, b: jnp.where(uphill, a, b), fresh_dir, step_dir)
            new_dir_state = jax.tree_util.tree_map(lambda a, b: jnp.where(uphill, a, b), fresh_state, new_dir_state)
        direction = optax.tree.scale(-1.0, step_dir)
        # lr: the step that led here (1 at first, 0 after a search gave up: inf·0 must stay 0)
        lr0 = jnp.where(lr > 0, jnp.minimum(increase_factor * lr, max_learning_rate), 0.0)
        new_search = optax.tree.scale(lr0, direction)

        # rejected: the same direction from the anchor, step cut (0 when the search gives up)
        lr_cut = jnp.where(give_up, 0.0, decrease_factor * lr)
        retry = jax.tree_util.tree_map(lambda a, d, p: a + lr_cut * d - p, state.anchor, state.direction, params)

        def pick(if_accept: Any, if_reject: Any) -> Any:
            return jax.tree_util.tree_map(lambda a, b: jnp.where(accept, a, b), if_accept, if_reject)

        step = pick(new_search, retry)
        new_state = TrialLinesearchState(
            direction_state=pick(new_dir_state, state.direction_state),
            anchor=pick(params, state.anchor),
            anchor_value=jnp.where(accept, value, state.anchor_value),
            direction=pick(direction, state.direction),
            slope=jnp.where(accept, optax.tree.real(optax.tree.vdot(direction, grad)), state.slope),
            learning_rate=jnp.where(accept, lr0, lr_cut),
            trials=jnp.where(accept | give_up, 1, state.trials + 1).astype(jnp.int32),
            accepted=accept,
        )
        new_state = optax.tree.cast_like(new_state, other_tree=state)
        return optax.tree.cast_like(step, other_tree=params), new_state

    return optax.GradientTransformationExtraArgs(init_fn, update_fn)


def _check_in(name: str, value: Any, ok: Callable[[float], bool], what: str) -> None:
    try:
        good = not isinstance(value, bool) and ok(float(value))
    except (TypeError, ValueError):
        good = False
    if not good:
        raise ValueError(f"{name}: must be {what}, got {value!r}")


def find_state(opt_state: Any, state_type: type) -> Any:
    """The first sub-state of type ``state_type`` in an optimiser state (any optax chain), or None."""
    found: list[Any] = []

    def visit(x: Any) -> bool:
        if isinstance(x, state_type):
            found.append(x)
            return True
        return False

    jax.tree_util.tree_leaves(opt_state, is_leaf=visit)
    return found[0] if found else None


def is_trial_linesearch(opt_state: Any) -> bool:
    """Whether an optimiser state (any optax chain) holds a :func:`lbfgs` line search."""
    return find_state(opt_state, TrialLinesearchState) is not None


def evaluates_trial(opt_state: Any) -> jax.Array:
    """Whether the point about to be evaluated with ``opt_state`` is a line-search trial (bool
    array), as opposed to the start itself; ``False`` for other optimisers."""
    state = find_state(opt_state, TrialLinesearchState)
    return jnp.asarray(False) if state is None else state.trials > 0


def evaluated_an_iterate(opt_state: Any) -> jax.Array:
    """Whether the point given to the ``update`` that returned ``opt_state`` is an iterate (bool
    array): the start or an accepted trial for :func:`lbfgs`; always ``True`` for other optimisers,
    whose every evaluation is an iterate.  A rejected trial's gradient says nothing about
    convergence: a step into a region where the loss is flat (a saturated reparametrisation) has a
    vanishing gradient and a higher loss."""
    state = find_state(opt_state, TrialLinesearchState)
    return jnp.asarray(True) if state is None else state.accepted


def forget_reference(opt_state: Any) -> Any:
    """``opt_state`` with the pending search's reference loss dropped, so that its next trial is
    accepted: for a caller that changed the objective (an augmented-Lagrangian multiplier update)
    between the anchor's evaluation and the trial's."""

    def visit(x: Any) -> Any:
        if isinstance(x, TrialLinesearchState):
            return x._replace(anchor_value=jnp.full_like(x.anchor_value, jnp.inf))
        return x

    return jax.tree_util.tree_map(visit, opt_state, is_leaf=lambda x: isinstance(x, TrialLinesearchState))
