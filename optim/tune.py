"""Gradient tuner: ``tune(problem, ...)`` (or ``tune(loss, params0, ...)``) with any optax optimiser.

:func:`gradient_tuner` is the optax-like pure pair ``(init, step)`` (a user may own the loop);
:func:`tune` is that pair plus the host loop (history, early stopping, callback, progress bar).

The tuner works in unconstrained space: ``x = apply(reparam, u)`` (see :mod:`jaxsim.problem.reparam`), so
bounds, positivity and orderings hold at every step.  General inequality constraints
``g(x) ≤ 0`` (``constraints(x)`` returns ``g``, any shape) enter the objective in ``u``-space as

* ``"penalty"``: ``J = f + (w/2)·Σ max(0, g)²`` (its minimiser violates active constraints by
  about ``λ*/w``);
* ``"augmented_lagrangian"`` (Powell–Hestenes–Rockafellar): ``J = f + (1/2w)·Σ[max(0, λ + w g)² − λ²]``
  with multipliers ``λ ← max(0, λ + w g)`` every ``multiplier_every`` steps, which drives the
  violation to zero at a finite ``w`` (``w`` = ``penalty_weight``).

Several starts (``n_starts``; start 0 is ``params0``, the others ``u0 + init_spread·N(0, 1)``) step
together in one ``vmap``; ``steps_per_call`` steps run on the device in one ``lax.scan`` (a chunk)
that evaluates the stopping rules after every step and skips the remaining steps (``lax.cond``,
no loss evaluation) once no start is running; the host syncs once per chunk, then records the
history (the same records, step for step, as one step per call), updates the progress bar and
replays ``callback`` over the chunk's steps.  The compiled chunk is cached across calls
(:mod:`optim.compile_cache`): a second ``tune`` with the same loss object (or Problem), optimiser
settings, reparametrisation, settings and shapes traces and compiles nothing.

A start *converges* (and stops) when its gradient norm at an iterate (not at a rejected line-search
trial) falls to ``gtol`` or its kept point has not improved by ``rtol`` (relative) for ``patience``
steps; ``TuneResult.converged`` says whether the start returned did, as opposed to running out of
steps, and ``message`` gives the last gradient norm.

Which point is kept: the evaluated iterate with the lowest objective — without constraints the
loss; with ``"penalty"`` the penalised loss (the problem being solved); with
``"augmented_lagrangian"`` a point with total violation ``Σ max(0, g) ≤ constraint_tol`` beats any
infeasible one, feasible points are ranked by the loss and infeasible ones by
``f + (w/2)Σ max(0, g)²``.  A start whose loss or gradient turns NaN/inf
stops there (the others go on; a line-search trial of :func:`optim.lbfgs.lbfgs` is the exception:
the optimiser cuts the step instead); the run stops when no start is left and says so in ``message``,
returning the best finite point.

Gradients: ``mode="reverse"`` (``value_and_grad``) or ``"forward"`` (``jacfwd`` on the flattened
``u``, the value comes with it); ``"auto"`` (:func:`use_forward_mode`) takes forward mode while
unconstrained parameters × starts ≤ :data:`FORWARD_MODE_MAX_PARAMS`: the vmapped starts multiply
forward mode's tangent lanes, not reverse mode's single adjoint pass.  The count cannot tell every
loss: on the fuzzy-PID race loss (4 parameters) reverse mode is 3× faster, on the TRMS LQR loss
(16) 2.6× (implicit Riccati derivatives: one adjoint solve against one tangent solve per lane).
``"measure"`` compiles the ``"auto"`` rule's mode and times one of its steps; when
:data:`MEASURE_HORIZON_STEPS` such steps would cost at least its compilation, it compiles the other
mode too, times both and runs the faster — once per (loss, optimiser, settings, shapes), cached like
the compiled steps: the first call may pay a second compilation, later calls nothing; the choice is
on ``TuneResult.mode``.

Accounting: a gradient evaluation (loss and gradient, in either mode) of a start still running
counts ``grad_cost`` loss evaluations times ``sims_per_eval`` — by default ``grad_cost = 1`` (an
evaluation is an evaluation: reproducible counts); ``grad_cost="measure"`` measures what one
gradient evaluation costs in loss evaluations (:func:`grad_cost`, wall-clock, once per problem and
cached), or pass the number; a line-search trial inside ``optax.lbfgs`` counts one loss evaluation
for its backtracking search and ``grad_cost`` for its zoom search (its trials evaluate the
gradient); :func:`optim.lbfgs.lbfgs`'s trials are the tuner's own steps, each one gradient evaluation.
``n_sims`` sums these (loss-evaluation equivalents, comparable with the swarm's and the
searches'); ``n_evals`` counts the evaluations themselves.  ``wall_s`` is the stepping time; the
setup (initial state, tracing, compilation, the ``grad_cost`` measurement, ``mode="measure"``'s
timings) is ``compile_s``.

Optimisers: any optax transformation; ``method="lbfgs"`` (:func:`optim.lbfgs.lbfgs`: L-BFGS with a
backtracking line search whose trials are the tuner's steps, so the compiled step holds the loss
once; a NaN/inf trial is cut like any failed trial, not the end of the start) converges in far
fewer loss evaluations than Adam on smooth deterministic losses (the PID problem: see the issue-18
measurements); Adam (``optax.adam(1e-2)``) stays the default, since
L-BFGS's line search stalls on losses with kinks (saturations, ``|e|`` in ITAE) and on noisy ones.
"""

from __future__ import annotations

import functools
import time
from typing import Any, Callable, Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax
from jax.flatten_util import ravel_pytree

from jaxsim.core.progress import postfix, progress_bar
from jaxsim.core.validation import check_finite
from jaxsim.problem import Problem, penalised
from jaxsim.problem.reparam import apply, check_domain, invert
from optim.compile_cache import LRUCache, callable_key, key_or_none
from optim.lbfgs import evaluated_an_iterate, evaluates_trial, find_state, forget_reference, is_trial_linesearch
from optim.lbfgs import lbfgs as trial_lbfgs
from optim.results import History, TuneResult, check_int, check_number, check_some_loss_finite

FORWARD_MODE_MAX_PARAMS = 32
"""``mode="auto"`` uses forward mode while unconstrained parameters × starts stay at most this.

Measured on the 2-core CPU this project runs on (``experiments/benchmarks/ad_mode_crossover.py``,
closed-loop PID loss, 300 ticks, one start): forward mode was faster at every tested count up to 30
(4–8× at 3 gains) and reverse mode took over between 36 and 96; 32 stays on the safe side for
losses with heavier per-step work, where reverse mode's relative overhead is smaller.  With
vmapped starts forward mode pushes parameters × starts tangent lanes through the rollout while
reverse mode's cost grows with the starts alone: issue 18 measured reverse mode 1.3× faster than
forward at 3 gains × 32 starts (96 lanes), consistent with the same threshold on the product."""

Mode = Literal["auto", "forward", "reverse", "measure"]
Method = Literal["adam", "lbfgs"]
ConstraintMethod = Literal["penalty", "augmented_lagrangian"]


class TunerState(NamedTuple):
    """State of :func:`gradient_tuner` (every leaf has a leading axis of ``S`` starts): current point
    ``u`` (unconstrained), optimiser state, multipliers, the best point kept so far and its
    ``(loss, violation, merit)``, per-start flags (``alive``: no NaN/inf seen; ``active``: not
    stopped by the convergence test), steps since the last improvement, step counter."""

    u: Any
    opt_state: Any
    lam: jax.Array
    best_u: Any
    best_f: jax.Array
    best_v: jax.Array
    best_m: jax.Array
    best_step: jax.Array
    alive: jax.Array  # no NaN/inf seen
    active: jax.Array  # not stopped early
    since_improve: jax.Array
    step: jax.Array


class StepInfo(NamedTuple):
    """What one step of :func:`gradient_tuner` evaluated, per start (leading axis ``S``): the loss
    ``f`` at the current point (before the update), its gradient norm (unconstrained coordinates),
    the total constraint violation, whether it was finite, whether the start was still running,
    loss evaluations it cost (line-search trials included) and the point ``x`` (params)."""

    f: jax.Array
    grad_norm: jax.Array
    violation: jax.Array
    finite: jax.Array
    ran: jax.Array
    evals: jax.Array
    x: Any


def _ranking(f, v, m, bf, bv, bm, tol, rtol, feasible_first):
    """``(better, improved)``: comparison of a new point with the kept one (module docstring)."""
    if not feasible_first:
        return m < bm, m < bm - rtol * jnp.abs(bm)
    feas, bfeas = v <= tol, bv <= tol
    better = jnp.where(feas & bfeas, f < bf, jnp.where(feas, True, jnp.where(bfeas, False, m < bm)))
    improved = jnp.where(
        feas & bfeas,
        f < bf - rtol * jnp.abs(bf),
        jnp.where(feas, ~bfeas, jnp.where(bfeas, False, m < bm - rtol * jnp.abs(bm))),
    )
    return better, improved


def _tree_where(c: jax.Array, a: Any, b: Any) -> Any:
    return jax.tree_util.tree_map(lambda x, y: jnp.where(c, x, y), a, b)


class _Settings(NamedTuple):
    """Validated static settings of one run."""

    w: float
    tol: float
    rtol: float
    gtol: float
    patience: int | None
    multiplier_every: int
    al: bool
    use_forward: bool
    sims_per_eval: int


def _make_objective(terms: Callable, reparam: Any, cfg: _Settings):
    """``objective(u, lam) -> (J, (f, g, violation, merit))`` in unconstrained space, from
    ``terms(x) -> (f, g)`` (:func:`_joined`, or a Problem's ``loss_and_violation``)."""

    def objective(u: Any, lam: jax.Array):
        f, g = terms(apply(reparam, u))
        f = jnp.asarray(f)
        if f.shape != ():
            raise ValueError(f"loss: must return a scalar, got shape {f.shape}")
        g = jnp.ravel(jnp.asarray(g, f.dtype))
        merit = penalised(f, g, cfg.w)
        if cfg.al:
            j = f + jnp.sum(jnp.maximum(lam + cfg.w * g, 0.0) ** 2 - lam**2) / (2 * cfg.w)
        else:
            j = merit
        return j, (f, g, jnp.sum(jnp.maximum(g, 0.0)), merit)

    return objective


def _joined(loss: Callable, constraints: Callable | None) -> Callable:
    """``x -> (loss(x), g)`` with ``g = constraints(x)`` (empty without constraints)."""
    return lambda x: (loss(x), jnp.zeros((0,)) if constraints is None else constraints(x))


def _make_value_and_grad(objective: Callable, use_forward: bool):
    """``(J, aux), grad`` by reverse mode, or by ``jacfwd`` over the flattened ``u``."""

    def value_and_grad(u: Any, lam: jax.Array):
        if not use_forward:
            return jax.value_and_grad(objective, has_aux=True)(u, lam)
        flat, unravel = ravel_pytree(u)

        def value_twice(v: jax.Array):
            j, aux = objective(unravel(v), lam)
            return j, (j, aux)

        grad_flat, (j, aux) = jax.jacfwd(value_twice, has_aux=True)(flat)
        return (j, aux), unravel(grad_flat)

    return value_and_grad


def _make_step(objective: Callable, opt: optax.GradientTransformation, reparam: Any, cfg: _Settings):
    """One tuner step for one start: evaluate, keep the best point, update, stop rules."""
    value_and_grad = _make_value_and_grad(objective, cfg.use_forward)
    extra_args = isinstance(opt, optax.GradientTransformationExtraArgs)

    def tuner_step(c: TunerState) -> tuple[TunerState, StepInfo]:
        (j, (f, g, viol, merit)), grad = value_and_grad(c.u, c.lam)
        gnorm = optax.tree.norm(grad)
        finite = jnp.isfinite(j) & jnp.isfinite(f) & jnp.isfinite(gnorm)
        running = c.alive & c.active
        better, improved = _ranking(f, viol, merit, c.best_f, c.best_v, c.best_m, cfg.tol, cfg.rtol, cfg.al)
        keep = running & finite & better
        # optim.lbfgs's line-search trials are these evaluations: a non-finite trial is a rejected
        # trial (the optimiser cuts the step), not the end of the start
        trial_linesearch = is_trial_linesearch(c.opt_state)
        trial = evaluates_trial(c.opt_state)
        if extra_args:
            updates, new_state = opt.update(
                grad, c.opt_state, c.u, value=j, grad=grad, value_fn=lambda uu: objective(uu, c.lam)[0]
            )
        else:
            updates, new_state = opt.update(grad, c.opt_state, c.u)
        move = running & (finite | trial)
        lam = c.lam
        if cfg.al:
            due = (c.step + 1) % cfg.multiplier_every == 0
            lam = jnp.where(move & due, jnp.maximum(lam + cfg.w * g, 0.0), lam)
            if trial_linesearch:  # the objective changed: the next trial cannot be compared with the anchor
                new_state = _tree_where(move & due, forget_reference(new_state), new_state)
        since = jnp.where(keep & improved, 0, c.since_improve + 1)
        # a NaN loss can come with a zero gradient; a rejected line-search trial is not an iterate
        stationary = finite & (gnorm <= cfg.gtol) & evaluated_an_iterate(new_state)
        active = c.active & ~stationary
        if cfg.patience is not None:
            active = active & (since < cfg.patience)
        trials = optax.tree_utils.tree_get(new_state, "num_linesearch_steps", None) if extra_args else None
        evals = 1 + (jnp.asarray(trials) if trials is not None else 0)
        new = TunerState(
            u=_tree_where(move, optax.apply_updates(c.u, updates), c.u),
            opt_state=_tree_where(move, new_state, c.opt_state),
            lam=lam,
            best_u=_tree_where(keep, c.u, c.best_u),
            best_f=jnp.where(keep, f, c.best_f),
            best_v=jnp.where(keep, viol, c.best_v),
            best_m=jnp.where(keep, merit, c.best_m),
            best_step=jnp.where(keep, c.step, c.best_step),
            alive=c.alive & (finite | ~running | trial),
            active=active,
            since_improve=since,
            step=c.step + 1,
        )
        new = jax.tree_util.tree_map(lambda a, b: a.astype(b.dtype), new, c)  # fixed avals: one compile
        return new, StepInfo(f, gnorm, viol, finite, running, jnp.where(running, evals, 0), apply(reparam, c.u))

    return tuner_step


def _over_starts(step: Callable, n_starts: int) -> Callable:
    """``step`` of one start applied to every start (leading axis ``S``): ``vmap``, except for a
    single start, which runs unbatched — a batch of one still turns every data-dependent loop of the
    loss (the Riccati solvers' iterations) into a batched loop, and on the TRMS loss that cost about
    1.7 s more tracing and compilation."""
    if n_starts > 1:
        return jax.vmap(step)

    def single(c: Any) -> Any:
        out = step(jax.tree_util.tree_map(lambda a: a[0], c))
        return jax.tree_util.tree_map(lambda a: jnp.expand_dims(a, 0), out)

    return single


def _initial_carry(
    key: jax.Array, u0: Any, spread: jax.Array, opt: optax.GradientTransformation, n_starts: int, m_constraints: int
) -> TunerState:
    """Start 0 is ``u0``, the others ``u0 + spread·N(0, 1)``; strong dtypes so the step compiles once."""
    v0, unravel = ravel_pytree(u0)
    noise = spread * jax.random.normal(key, (n_starts, v0.size), v0.dtype)
    u_starts = jax.vmap(unravel)(v0[None, :] + noise.at[0].set(0.0))
    inf = jnp.full((n_starts,), jnp.inf, v0.dtype)
    carry = TunerState(
        u=u_starts,
        opt_state=jax.vmap(opt.init)(u_starts),
        lam=jnp.zeros((n_starts, m_constraints), v0.dtype),
        best_u=u_starts,
        best_f=inf,
        best_v=inf,
        best_m=inf,
        best_step=jnp.full((n_starts,), -1, jnp.int32),
        alive=jnp.ones((n_starts,), bool),
        active=jnp.ones((n_starts,), bool),
        since_improve=jnp.zeros((n_starts,), jnp.int32),
        step=jnp.zeros((n_starts,), jnp.int32),
    )
    return jax.tree_util.tree_map(lambda a: jnp.array(a, dtype=a.dtype), carry)


def _best_of(
    best_f: Any, best_v: Any, best_m: Any, tol: float, feasible_first: bool, xp: Any = jnp
) -> tuple[jax.Array, jax.Array]:
    """The start whose kept point ranks first, and that point's loss (``xp``: ``jnp`` inside the
    compiled chunk, ``np`` on the host — host-side jnp would compile a handful of eager ops).

    With ``feasible_first`` (augmented Lagrangian), feasible finite points are ranked by the loss
    when there is one; otherwise every start by its merit."""
    f, v, m = xp.asarray(best_f), xp.asarray(best_v), xp.asarray(best_m)
    cand = m
    if feasible_first:
        feasible = v <= tol
        cand = xp.where(xp.any(feasible & xp.isfinite(f)), xp.where(feasible, f, xp.inf), m)
    i = xp.argmin(cand)
    return i, f[i]


class ChunkInfo(NamedTuple):
    """What one chunk of :func:`gradient_tuner` steps evaluated (leading axis ``L`` = chunk length):
    ``step`` the :class:`StepInfo` of every step (``(L, S, …)``), ``best_loss (L,)`` the loss of the
    best kept point after each step, ``ran (L,)`` whether the step ran (a prefix of ``True``: the
    chunk stops stepping once no start is running or the requested steps are done)."""

    step: StepInfo
    best_loss: jax.Array
    ran: jax.Array


def _make_chunk(step: Callable, cfg: _Settings, length: int) -> Callable:
    """``chunk(state, remaining) -> (state, ChunkInfo)``: up to ``min(length, remaining)`` steps in
    one ``lax.scan``; a step whose turn comes after every start stopped (or after ``remaining``) is
    skipped by ``lax.cond`` (no loss evaluation) and marked ``ran = False``."""

    def chunk(state: TunerState, remaining: jax.Array) -> tuple[TunerState, ChunkInfo]:
        blank = jax.tree_util.tree_map(lambda s: jnp.zeros(s.shape, s.dtype), jax.eval_shape(step, state)[1])

        def body(c: TunerState, k: jax.Array):
            go = jnp.any(c.alive & c.active) & (k < remaining)
            new, info = jax.lax.cond(go, step, lambda s: (s, blank), c)
            return new, ChunkInfo(info, _best_of(new.best_f, new.best_v, new.best_m, cfg.tol, cfg.al)[1], go)

        return jax.lax.scan(body, state, jnp.arange(length))

    return chunk


class Tuner(NamedTuple):
    """The optax-like pure pair of :func:`gradient_tuner` (plus a chunked driver and a host-side reader).

    init(params0=None, key=None) -> TunerState: ``S`` starts (start 0 at ``params0``, default the
    problem's ``space.init``); step(state) -> (state, StepInfo): one jitted step of every start;
    chunk(state, remaining) -> (state, ChunkInfo): ``steps_per_call`` steps in one jitted
    ``lax.scan`` with on-device stopping (:class:`ChunkInfo`);
    best(state) -> (params, loss, start): the best point kept so far (host side, NumPy).
    ``settings``, ``reparam``, ``n_starts``, ``steps_per_call``: what the pair was built with;
    ``linesearch_trial_is_gradient``: whether a line-search trial of the optimiser evaluates the
    gradient too (optax's zoom line search) or only the loss (backtracking), for the accounting.
    """

    init: Callable[..., TunerState]
    step: Callable[[TunerState], tuple[TunerState, StepInfo]]
    best: Callable[[TunerState], tuple[Any, float, int]]
    settings: _Settings
    reparam: Any
    n_starts: int
    chunk: Callable[[TunerState, Any], tuple[TunerState, ChunkInfo]] | None = None
    steps_per_call: int = 1
    linesearch_trial_is_gradient: bool = True
    compiled: Callable[[TunerState], Callable] | None = None


class _Resolved(NamedTuple):
    loss: Callable
    params0: Any
    reparam: Any
    constraints: Callable | None
    sims_per_eval: int
    penalty_weight: float
    name: str
    terms: Callable | None = None  # params -> (loss, g): a Problem's loss_and_violation (one call of terms_fn)


def _resolve(
    loss: Any, params0: Any, reparam: Any, constraints: Any, sims_per_eval: Any, penalty_weight: Any
) -> _Resolved:
    """A Problem's defaults (``space.init``, ``space.reparam``, its constraints, scenarios per loss
    evaluation, penalty weight), each overridden by an argument given explicitly; a plain loss
    callable keeps the old signature's defaults."""
    if isinstance(loss, Problem):
        pb = loss
        return _Resolved(
            pb.loss,
            pb.space.init if params0 is None else params0,
            pb.space.reparam if reparam is None else reparam,
            pb.constraints if constraints is None else constraints,
            pb.sims_per_eval if sims_per_eval is None else sims_per_eval,
            pb.penalty_weight if penalty_weight is None else penalty_weight,
            pb.name,
            pb.loss_and_violation if constraints is None else None,
        )
    if not callable(loss):
        raise ValueError(f"loss: must be a Problem or callable, got {type(loss).__name__}")
    if params0 is None:
        raise ValueError("params0: required when tuning a plain loss function (a Problem supplies space.init)")
    return _Resolved(
        loss,
        params0,
        reparam,
        constraints,
        1 if sims_per_eval is None else sims_per_eval,
        100.0 if penalty_weight is None else penalty_weight,
        getattr(loss, "__name__", "loss"),
    )


def _as_float_tree(params0: Any) -> Any:
    if not jax.tree_util.tree_leaves(params0):
        raise ValueError("params0: must contain at least one array")
    return jax.tree_util.tree_map(lambda a: jnp.asarray(a, dtype=jnp.result_type(a, float)), params0)


def use_forward_mode(n_params: int, n_starts: int = 1) -> bool:
    """The ``mode="auto"`` cost model: forward mode iff ``n_params·n_starts ≤``
    :data:`FORWARD_MODE_MAX_PARAMS` (the tangent lanes forward mode pushes through the rollout;
    see the constant for the measurements behind it)."""
    return n_params * n_starts <= FORWARD_MODE_MAX_PARAMS


def optimizer_for(method: Method | None, optimizer: Any) -> optax.GradientTransformation:
    """The optimiser ``tune`` runs: ``optimizer`` if given, else the one ``method`` names
    (``"adam"``: ``optax.adam(1e-2)``, the default; ``"lbfgs"``: :func:`optim.lbfgs.lbfgs`, a
    backtracking (Armijo) line search halving the step, at most 30 cuts, each trial one step of
    the tuner)."""
    if optimizer is not None:
        if method is not None:
            raise ValueError(f"method: give either method or optimizer, not both (method={method!r})")
        return optimizer
    if method is None or method == "adam":
        return optax.adam(1e-2)
    if method == "lbfgs":
        # halving, not optax's default factor 0.8: 20 trials of 0.8 shrink the step only to 1 %, too
        # little on Rosenbrock's valley
        return trial_lbfgs(max_backtracking_steps=30, decrease_factor=0.5)
    raise ValueError(f"method: must be 'adam' or 'lbfgs', got {method!r}")


def _trial_is_gradient(opt: optax.GradientTransformation, u_template: Any) -> bool:
    """Whether a line-search trial of ``opt`` costs a gradient (zoom) or one loss (backtracking)."""
    state = jax.eval_shape(opt.init, u_template)
    return find_state(state, optax.ScaleByBacktrackingLinesearchState) is None


_MODES = LRUCache(128)
"""``mode="measure"``'s choices, ``"forward"`` or ``"reverse"``, keyed like :data:`_TUNERS` less the mode."""


MEASURE_HORIZON_STEPS = 1000
"""``mode="measure"`` compiles the second mode only when this many steps of the first (the
``"auto"`` rule's mode) would take at least as long as the first mode's compilation: below that,
the other mode cannot repay its own compilation (on the PID problem a step costs 0.2 ms against
about 1.5 s of compilation, and the two modes' steps tie)."""


def _faster_mode(candidate: Callable[[str], "Tuner"], first: str, rounds: int = 3) -> str:
    """``mode="measure"``: compile the ``first`` mode's chunk (it stays in the tuner cache for the run
    that follows) and time one step of it from the initial state; if the step is dear enough
    (:data:`MEASURE_HORIZON_STEPS`), compile the other mode too, time both interleaved, the minimum
    over ``rounds`` (each averaging ≥ 5 ms of calls), and return the faster.  A mode JAX cannot
    differentiate the loss in (reverse mode through a ``lax.while_loop``, forward mode through a
    ``jax.custom_vjp``) is left out; if neither compiles, forward mode's error."""
    other = "reverse" if first == "forward" else "forward"
    tuners = {first: candidate(first)}  # the other mode's tuner only if the horizon test asks for it
    state = tuners[first].init()
    one = jnp.asarray(1, jnp.int32)
    exes, errors = {}, {}

    def compile_mode(m: str) -> float:
        if m not in tuners:
            tuners[m] = candidate(m)
        t0 = time.perf_counter()
        try:
            exes[m] = tuners[m].compiled(state)
        except Exception as err:  # noqa: BLE001  (JAX's errors for an unsupported mode vary by type)
            errors[m] = err
        return time.perf_counter() - t0

    def step_time(m: str) -> float:
        return _time_call(lambda s: exes[m](s, one), state)

    compile_s = compile_mode(first)
    if first in exes and MEASURE_HORIZON_STEPS * min(step_time(first) for _ in range(rounds)) < compile_s:
        return first
    compile_mode(other)
    if not exes:
        raise errors["forward"]
    if len(exes) == 1:
        return next(iter(exes))
    times: dict[str, list[float]] = {m: [] for m in exes}
    for _ in range(rounds):
        for m in exes:
            times[m].append(step_time(m))
    return min(times, key=lambda m: min(times[m]))


_TUNERS = LRUCache()
"""Compiled tuners, keyed on (loss, optimiser, reparametrisation, constraints, settings, starts,
chunk length, parameter shapes): a second ``tune`` with the same ones compiles nothing."""
_U_TEMPLATES = LRUCache()


def _default_key() -> jax.Array:
    """``PRNGKey(0)``, for the default (threefry) implementation as a constant: no eager seeding
    program to compile on a cold call."""
    if jax.config.jax_default_prng_impl == "threefry2x32":
        return jnp.asarray(np.zeros(2, np.uint32))
    return jax.random.PRNGKey(0)


def _u_template(reparam: Any, template: Any) -> Any:
    """Shapes and dtypes of ``invert(reparam, template)``, cached by the reparametrisation and the
    template's shapes: tracing the inverse on every call was most of a warm ``tune`` call's host
    time on a small problem (a few ms)."""
    key = key_or_none("u_template", reparam, _u_avals(template))
    return _U_TEMPLATES.get_or_build(key, lambda: jax.eval_shape(lambda x: invert(reparam, x), template))


def _u_avals(u_template: Any) -> tuple:
    leaves, treedef = jax.tree_util.tree_flatten(u_template)
    return treedef, tuple((leaf.shape, str(leaf.dtype)) for leaf in leaves)


def gradient_tuner(
    loss: Problem | Callable[[Any], jax.Array],
    optimizer: optax.GradientTransformation | None = None,
    *,
    params0: Any = None,
    reparam: Any = None,
    constraints: Callable[[Any], jax.Array] | None = None,
    constraint_method: ConstraintMethod = "penalty",
    penalty_weight: float | None = None,
    multiplier_every: int = 50,
    constraint_tol: float = 1e-6,
    n_starts: int = 1,
    init_spread: float = 0.5,
    patience: int | None = None,
    rtol: float = 1e-8,
    gtol: float = 0.0,
    sims_per_eval: int | None = None,
    mode: Mode = "auto",
    steps_per_call: int = 1,
    method: Method | None = None,
) -> Tuner:
    """The gradient tuner as a pure pair ``(init, step)`` a user can drive from their own loop::

        tuner = gradient_tuner(problem, optax.adam(0.05), n_starts=4)
        state = tuner.init(key=jax.random.PRNGKey(0))
        for _ in range(100):
            state, info = tuner.step(state)        # info.f: (4,) losses, info.grad_norm, ...
        params, loss, start = tuner.best(state)

    Arguments as in :func:`tune` (``params0`` here only fixes the structure and the ``"auto"`` mode
    choice; a Problem's ``space.init`` by default).  :func:`tune` is this pair plus the host loop,
    driving ``tuner.chunk`` (``steps_per_call`` steps per jitted call).  Pairs built with the same
    loss object, optimiser settings, reparametrisation, constraints, settings and shapes share their
    compiled functions (:mod:`optim.compile_cache`).
    """
    arguments = dict(locals())  # for the two candidate tuners of mode="measure"
    r = _resolve(loss, params0, reparam, constraints, sims_per_eval, penalty_weight)
    n_starts = check_int("n_starts", n_starts)
    steps_per_call = check_int("steps_per_call", steps_per_call)
    if patience is not None:
        patience = check_int("patience", patience)
    spread = check_number("init_spread", init_spread, allow_zero=True)
    if constraint_method not in ("penalty", "augmented_lagrangian"):
        raise ValueError(f"constraint_method: must be 'penalty' or 'augmented_lagrangian', got {constraint_method!r}")
    if mode not in ("auto", "forward", "reverse", "measure"):
        raise ValueError(f"mode: must be 'auto', 'forward', 'reverse' or 'measure', got {mode!r}")
    opt = optimizer_for(method, optimizer)
    if not (hasattr(opt, "init") and hasattr(opt, "update")):
        raise ValueError(f"optimizer: must be an optax.GradientTransformation, got {type(opt).__name__}")
    template = _as_float_tree(r.params0)
    u_template = _u_template(r.reparam, template)
    n_params = int(sum(np.prod(leaf.shape) for leaf in jax.tree_util.tree_leaves(u_template)))
    auto_forward = use_forward_mode(n_params, n_starts)
    cfg = _Settings(
        w=check_number("penalty_weight", r.penalty_weight),
        tol=check_number("constraint_tol", constraint_tol, allow_zero=True),
        rtol=check_number("rtol", rtol, allow_zero=True),
        gtol=check_number("gtol", gtol, allow_zero=True),
        patience=patience,
        multiplier_every=check_int("multiplier_every", multiplier_every),
        al=r.constraints is not None and constraint_method == "augmented_lagrangian",
        use_forward=mode == "forward" or (mode == "auto" and auto_forward),
        sims_per_eval=check_int("sims_per_eval", r.sims_per_eval),
    )
    m_constraints = 0
    if r.constraints is not None:
        g = jax.eval_shape(lambda u: jnp.ravel(jnp.asarray(r.constraints(apply(r.reparam, u)))), u_template)
        m_constraints = int(np.prod(g.shape))

    def build() -> dict:
        terms = r.terms if r.terms is not None else _joined(r.loss, r.constraints)
        objective = _make_objective(terms, r.reparam, cfg)
        # jitted, so the chunk's shape probe and its ``lax.cond`` share one trace of the step
        one = jax.jit(_over_starts(_make_step(objective, opt, r.reparam, cfg), n_starts))
        start = functools.partial(_initial_carry, opt=opt, n_starts=n_starts, m_constraints=m_constraints)

        def init_from_x(key: jax.Array, x0: Any, spread: jax.Array) -> TunerState:
            u0 = jax.tree_util.tree_map(lambda a, t: a.astype(t.dtype), invert(r.reparam, x0), u_template)
            return start(key, u0, spread)

        return {
            # x0 -> u0 -> starts in one program: one compilation on a cold call, not two
            "init": jax.jit(init_from_x),
            "step": one,
            "chunk": jax.jit(_make_chunk(one, cfg, steps_per_call)),
            "trial_is_gradient": _trial_is_gradient(opt, u_template),
            "executables": {},
            # one compilation instead of one eager op per transform on every new process
            "to_x": jax.jit(lambda u: apply(r.reparam, u)),
            "key0": _default_key(),
        }

    parts = (callable_key(r.loss), opt, r.reparam, callable_key(r.constraints), callable_key(r.terms))
    static = (cfg._replace(sims_per_eval=0), n_starts, m_constraints, steps_per_call, _u_avals(u_template))
    if mode == "measure":  # cfg.use_forward is False here: the key holds no mode
        candidate = lambda m: gradient_tuner(**{**arguments, "mode": m})  # noqa: E731
        first = "forward" if auto_forward else "reverse"
        chosen = _MODES.get_or_build(key_or_none("mode", *parts, static), lambda: _faster_mode(candidate, first))
        # the chosen mode's settings: the same key, and so the same compiled tuner, as the candidate's
        cfg = cfg._replace(use_forward=chosen == "forward")
        static = (cfg._replace(sims_per_eval=0), *static[1:])
    built = _TUNERS.get_or_build(key_or_none("tuner", *parts, static), build)

    def init(params0: Any = None, key: jax.Array | None = None) -> TunerState:
        x0 = template if params0 is None else _as_float_tree(params0)
        check_finite("params0", x0)
        check_domain(r.reparam, x0, "params0")
        k = built["key0"] if key is None else key
        dtype = jnp.result_type(*jax.tree_util.tree_leaves(u_template))  # ravel_pytree's, without an eager op
        state = built["init"](k, x0, np.asarray(spread, dtype))
        check_finite("params0 (in unconstrained space)", jax.tree_util.tree_map(lambda a: np.asarray(a)[0], state.u))
        return state

    def compiled(state: TunerState) -> Callable:
        """The AOT-compiled chunk for ``state``'s shapes (compiled once, then reused)."""
        sig = jax.tree_util.tree_structure(state), tuple((a.shape, a.dtype) for a in jax.tree_util.tree_leaves(state))
        exe = built["executables"].get(sig)
        if exe is None:
            exe = built["chunk"].lower(state, np.int32(0)).compile()
            built["executables"][sig] = exe
        return exe

    def best(state: TunerState) -> tuple[Any, float, int]:
        idx, best_loss = _best_index_and_loss(state, cfg.tol, cfg.al)
        return built["to_x"](_start(state.best_u, idx)), best_loss, idx

    return Tuner(
        init, built["step"], best, cfg, r.reparam, n_starts, built["chunk"], steps_per_call,
        built["trial_is_gradient"], compiled,
    )  # fmt: skip


class _Records(NamedTuple):
    f: list
    grad_norm: list
    violation: list
    best: list
    sims: list
    evals: list
    wall: list


def _run_chunks(
    tuner: Tuner,
    exe: Callable,
    carry: TunerState,
    steps: int,
    cost: tuple[float, float],
    callback: Callable | None,
    bar: Any,
) -> tuple[TunerState, _Records, str, bool]:
    """The host loop: one compiled chunk per iteration, then records, callback replay and stopping.

    ``cost``: loss-evaluation equivalents of one gradient evaluation and of one line-search trial.
    Returns ``(state, records, reason, stopped_by_callback)``."""
    cfg = tuner.settings
    rec = _Records([], [], [], [], [], [], [])
    sims, evals, reason, done, last = 0.0, 0, "", 0, 0.0
    start = time.perf_counter()
    while done < steps:
        carry, out = exe(carry, np.int32(steps - done))
        host = jax.device_get(out)
        now = time.perf_counter() - start
        n = int(np.sum(host.ran))
        info = host.step
        for j in range(n):
            ran = np.asarray(info.ran[j], bool)
            trials = np.asarray(info.evals[j]) - ran
            evals += int(np.sum(info.evals[j])) * cfg.sims_per_eval
            sims += (float(np.sum(ran)) * cost[0] + float(np.sum(trials)) * cost[1]) * cfg.sims_per_eval
            rec.f.append(info.f[j])
            rec.grad_norm.append(info.grad_norm[j])
            rec.violation.append(info.violation[j])
            rec.best.append(float(host.best_loss[j]))
            rec.sims.append(sims)
            rec.evals.append(evals)
            rec.wall.append(last + (now - last) * (j + 1) / n)
        last = now
        bar.update(n)
        if n:
            postfix(bar, f"best {rec.best[-1]:.6g}")
        stop_at = None
        if callback is not None:
            for j in range(n):
                f_now = np.where(info.ran[j] & info.finite[j], info.f[j], np.inf)
                if not np.any(np.isfinite(f_now)):
                    continue
                i = int(np.argmin(f_now))
                x = jax.tree_util.tree_map(lambda a: a[j, i], info.x)
                if callback(done + j, x, float(f_now[i])):
                    stop_at = done + j
                    break
        done += n
        if stop_at is not None:
            return carry, rec, f"stopped by callback at step {stop_at}", True
        alive, active = np.asarray(carry.alive), np.asarray(carry.active)
        if not np.any(alive & active):
            if not np.all(alive):
                reason = f"stopped at step {done - 1}: every start stopped"
            else:
                reason = (
                    f"early stop at step {done - 1}: converged (patience={cfg.patience}, rtol={cfg.rtol:g}, "
                    f"gtol={cfg.gtol:g})"
                )
            break
    return carry, rec, reason, False


def _history(rec: _Records) -> History:
    f_hist, g_hist = np.stack(rec.f), np.stack(rec.grad_norm)
    f_masked = np.where(np.isfinite(f_hist), f_hist, np.inf)
    rows, pick = np.arange(len(rec.f)), np.argmin(f_masked, axis=1)
    return History(
        best_loss=np.asarray(rec.best, float),
        sims=np.asarray(rec.sims, float),
        wall_s=np.asarray(rec.wall),
        loss=f_masked[rows, pick],
        grad_norm=g_hist[rows, pick],
        loss_per_start=f_hist,
        grad_norm_per_start=g_hist,
        violation_per_start=np.stack(rec.violation),
    )


def _non_finite_note(carry: TunerState, history: History, idx: int, best_loss: float) -> str:
    """'' when every start stayed finite; otherwise which starts broke, when, and what was kept."""
    dead = np.flatnonzero(~np.asarray(carry.alive))
    if not dead.size:
        return ""
    bad = ~np.isfinite(history.loss_per_start) | ~np.isfinite(history.grad_norm_per_start)
    first_bad = [int(np.argmax(bad[:, i])) for i in dead]
    return (
        f"; the loss or its gradient was non-finite (NaN/inf) in start(s) {dead.tolist()} at "
        f"step(s) {first_bad}; kept the best finite point (start {idx}, step "
        f"{int(np.asarray(carry.best_step)[idx])}, loss {best_loss:.6g})"
    )


def _convergence(
    carry: TunerState, history: History, idx: int, cfg: _Settings, reason: str, by_callback: bool, steps: int
) -> tuple[bool, str]:
    """Whether start ``idx`` (the one kept) met the convergence test, and the message saying so."""
    last_g = float(history.grad_norm_per_start[-1, idx])
    alive, active = bool(np.asarray(carry.alive)[idx]), bool(np.asarray(carry.active)[idx])
    converged = alive and not active and not by_callback
    test = f"gtol={cfg.gtol:g}" + (f", patience={cfg.patience} at rtol={cfg.rtol:g}" if cfg.patience else "")
    if converged:
        # the last evaluation may be a rejected line-search trial: its gradient norm decides nothing
        stalled = cfg.patience is not None and int(np.asarray(carry.since_improve)[idx]) >= cfg.patience
        why = f"no relative improvement > rtol for {cfg.patience} steps" if stalled else "gradient norm ≤ gtol"
        head = reason or f"converged within {steps} steps"
        return True, f"{head}; start {idx} converged: {why} (last gradient norm {last_g:.3g})"
    if not reason:
        reason = f"ran out of steps: {steps} steps without meeting the convergence test ({test})"
    return False, f"{reason}; last gradient norm {last_g:.3g} (start {idx})"


_GRAD_COSTS = LRUCache(128)
"""Measured :func:`grad_cost` values, keyed like :data:`_TUNERS` (loss, reparametrisation, mode, shapes)."""


def _time_call(fn: Callable, arg: Any, min_seconds: float = 0.005) -> float:
    """Seconds per call of ``fn(arg)`` (blocked), averaged over enough calls to last ``min_seconds``."""
    jax.block_until_ready(fn(arg))
    n, t = 1, 0.0
    while True:
        t0 = time.perf_counter()
        for _ in range(n):
            out = fn(arg)
        jax.block_until_ready(out)
        t = time.perf_counter() - t0
        if t >= min_seconds or n >= 1 << 16:
            return t / n
        n *= 2 if t <= 0 else max(2, min(64, int(np.ceil(1.5 * min_seconds / t))))  # aim past min_seconds


def grad_cost(
    loss: Problem | Callable[[Any], jax.Array],
    params0: Any = None,
    *,
    reparam: Any = None,
    mode: Mode = "auto",
    n_starts: int = 1,
    rounds: int = 5,
) -> float:
    """Cost of one gradient evaluation (the value and the gradient, in the mode ``tune`` would use)
    in units of one loss evaluation: ``t(value_and_grad) / t(loss)``, both jitted for one start at
    ``params0`` (a Problem's ``space.init``), the minimum over ``rounds`` interleaved timing rounds
    (each averaging ≥ 5 ms of calls), at least 1.

    Measured once per (loss object, reparametrisation, mode, shapes) and cached: the first call
    compiles the loss and its ``value_and_grad`` (on the PID problem about 1 s here), later calls
    return the cached number.  ``mode="auto"`` resolves as in :func:`tune` with ``n_starts``.
    Measured on this project's 2-core CPU for :class:`optim.problems.PIDTuning` (3 gains, 300
    ticks): forward mode about 7–8.5, reverse mode 27–31 loss evaluations (issue 18)."""
    r = _resolve(loss, params0, reparam, None, None, None)
    if mode not in ("auto", "forward", "reverse"):
        raise ValueError(f"mode: must be 'auto', 'forward' or 'reverse', got {mode!r}")
    x0 = _as_float_tree(r.params0)
    check_finite("params0", x0)
    check_domain(r.reparam, x0, "params0")
    u0 = invert(r.reparam, x0)
    n_params = int(sum(np.size(leaf) for leaf in jax.tree_util.tree_leaves(u0)))
    forward = mode == "forward" or (mode == "auto" and use_forward_mode(n_params, check_int("n_starts", n_starts)))

    def measure() -> float:
        def objective(u: Any, lam: jax.Array):
            j = jnp.asarray(r.loss(apply(r.reparam, u)))
            return j, ()

        value = jax.jit(lambda u: objective(u, None)[0])
        vg = jax.jit(lambda u: _make_value_and_grad(objective, forward)(u, None))
        t_f, t_g = [], []
        for _ in range(check_int("rounds", rounds)):
            t_f.append(_time_call(value, u0))
            t_g.append(_time_call(vg, u0))
        return max(1.0, min(t_g) / min(t_f))

    key = key_or_none("grad_cost", callable_key(r.loss), r.reparam, forward, _u_avals(u0))
    return float(_GRAD_COSTS.get_or_build(key, measure))


def tune(
    loss: Problem | Callable[[Any], jax.Array],
    params0: Any = None,
    *,
    optimizer: optax.GradientTransformation | None = None,
    steps: int = 200,
    reparam: Any = None,
    constraints: Callable[[Any], jax.Array] | None = None,
    constraint_method: ConstraintMethod = "penalty",
    penalty_weight: float | None = None,
    multiplier_every: int = 50,
    constraint_tol: float = 1e-6,
    n_starts: int = 1,
    key: jax.Array | None = None,
    init_spread: float = 0.5,
    patience: int | None = None,
    rtol: float = 1e-8,
    gtol: float = 0.0,
    callback: Callable[[int, Any, float], bool | None] | None = None,
    sims_per_eval: int | None = None,
    mode: Mode = "auto",
    progress: Any = False,
    method: Method | None = None,
    steps_per_call: int = 32,
    grad_cost: float | str | None = None,
) -> TuneResult:
    """Minimise a :class:`~jaxsim.problem.Problem`'s loss (or ``loss(params)``) by gradient steps.

    Args:
        loss: a Problem (its ``space.init``, ``space.reparam``, ``constraints``, scenarios per loss
            evaluation and ``penalty_weight`` are the defaults of the arguments below), or a plain
            ``params -> scalar`` function, pure and differentiable (jitted by the tuner).
        params0: pytree of arrays inside the domain of ``reparam`` (required for a plain loss).
        optimizer: any ``optax.GradientTransformation`` (default: the one ``method`` names); line-search
            optimisers (``optax.lbfgs``, a ``GradientTransformationExtraArgs``) receive ``value``,
            ``grad`` and ``value_fn``.
        steps: maximum number of steps (gradient evaluations) per start; with
            :func:`optim.lbfgs.lbfgs` a step is one line-search trial.
        reparam: pytree of :mod:`jaxsim.problem.reparam` objects (a prefix of ``params0``); None:
            identity (a Problem: its space's).
        constraints: ``params -> g``; feasible iff every ``g ≤ 0``.
        constraint_method: ``"penalty"`` or ``"augmented_lagrangian"`` (module docstring).
        penalty_weight: ``w`` of the penalty / augmented Lagrangian (default 100, a Problem's own).
        multiplier_every: steps between multiplier updates (augmented Lagrangian).
        constraint_tol: total violation below which a point counts as feasible.
        n_starts, key, init_spread: multi-start (vmapped); perturbations are in ``u``-space.
        patience, rtol: a start stops (converged) once its kept point has not improved by more than
            ``rtol`` (relative) for ``patience`` steps (None: never).
        gtol: a start stops (converged) once its gradient norm (in ``u``-space) is ≤ ``gtol``.
        callback: ``callback(step, params, loss) -> stop``, called for every step with the iterate
            of the start with the lowest loss at that step — after the chunk holding the step has
            run (in step order, once per step).  A true return value stops the run at the end of
            that chunk: the steps the chunk ran after it stay in the history and the result
            (``steps_per_call=1`` stops at the step itself).
        sims_per_eval: simulations one loss evaluation costs (accounting only; default 1, a
            Problem's number of scenarios).
        mode: ``"auto"`` (:func:`use_forward_mode`: forward mode while parameters × starts ≤
            :data:`FORWARD_MODE_MAX_PARAMS`), ``"forward"`` or ``"reverse"`` gradient, or
            ``"measure"``: the faster of the two, timed once per problem and settings (the first
            call compiles both where the steps are dear enough to repay it,
            :data:`MEASURE_HORIZON_STEPS`; the choice is cached and reported in ``TuneResult.mode``).
        progress: ``True`` for a tqdm bar (steps, best loss; updated once per chunk), or a bar
            factory (:mod:`jaxsim.core.progress`).
        method: ``"adam"`` (``optax.adam(1e-2)``, the default) or ``"lbfgs"``
            (:func:`optim.lbfgs.lbfgs`, for smooth deterministic losses), when ``optimizer`` is not
            given.
        steps_per_call: steps run on the device per jitted call (one ``lax.scan``; the stopping
            rules are evaluated inside it and the host syncs once per chunk).  The result does not
            depend on it except through a callback's stop.
        grad_cost: loss-evaluation equivalents of one gradient evaluation for the accounting:
            ``None`` (default) counts it as 1 (reproducible: the counts do not depend on timing);
            ``"measure"``: :func:`grad_cost` measures it once per problem (wall-clock ratio, cached;
            its extra compilation is in ``compile_s``); or a number.

    Returns:
        :class:`~optim.results.TuneResult`; ``converged`` says whether the start kept met the
        convergence test (``gtol`` / ``patience``) rather than running out of steps, and
        ``message`` gives the reason and the last gradient norm.  Accounting: ``n_steps`` steps;
        ``n_evals`` evaluations (one gradient evaluation per running start and step, plus every
        line-search trial), each × ``sims_per_eval``; ``n_sims`` the same in loss-evaluation
        equivalents — a gradient evaluation counts ``grad_cost`` (:attr:`TuneResult.grad_cost`),
        a backtracking line-search trial 1, a zoom line-search trial ``grad_cost`` — so it
        compares with the swarms' and searches' ``n_sims``; ``history.sims`` is its running sum.
        ``compile_s`` holds the setup: initial state, compilation (0 on a second call with the
        same loss object, settings and shapes), the ``grad_cost`` measurement and, on a first call,
        ``mode="measure"``'s second compilation and timings.
    """
    if callback is not None and not callable(callback):
        raise ValueError("callback: must be callable or None")
    steps = check_int("steps", steps)
    if grad_cost is None:
        grad_cost = 1.0
    elif isinstance(grad_cost, str):
        if grad_cost != "measure":
            raise ValueError(f"grad_cost: must be None, 'measure' or a positive number, got {grad_cost!r}")
    else:
        grad_cost = check_number("grad_cost", grad_cost)
    t0 = time.perf_counter()
    tuner = gradient_tuner(
        loss,
        optimizer,
        params0=params0,
        reparam=reparam,
        constraints=constraints,
        constraint_method=constraint_method,
        penalty_weight=penalty_weight,
        multiplier_every=multiplier_every,
        constraint_tol=constraint_tol,
        n_starts=n_starts,
        init_spread=init_spread,
        patience=patience,
        rtol=rtol,
        gtol=gtol,
        sims_per_eval=sims_per_eval,
        mode=mode,
        steps_per_call=steps_per_call,
        method=method,
    )
    cfg = tuner.settings
    carry = tuner.init(None, key)
    exe = tuner.compiled(carry)
    mode_name = "forward" if cfg.use_forward else "reverse"
    if grad_cost == "measure":
        grad_cost = _grad_cost(loss, params0, reparam=reparam, mode=mode_name)
    cost = (grad_cost, grad_cost if tuner.linesearch_trial_is_gradient else 1.0)
    compile_s = time.perf_counter() - t0

    name = loss.name if isinstance(loss, Problem) else "loss"
    bar = progress_bar(progress, total=steps, desc=f"tune {name}", unit="step")
    try:
        carry, rec, reason, by_callback = _run_chunks(tuner, exe, carry, steps, cost, callback, bar)
    finally:
        bar.close()
    wall = rec.wall[-1]
    idx, best_loss = _best_index_and_loss(carry, cfg.tol, cfg.al)
    # a start whose loss or gradient is not finite stops there: its first point was all it evaluated
    check_some_loss_finite(
        best_loss,
        f"the first point of each of the {tuner.n_starts} start(s)",
        f"check params0 and the loss (first values {np.asarray(rec.f[0])})",
    )
    history = _history(rec)
    converged, message = _convergence(carry, history, idx, cfg, reason, by_callback, len(rec.f))
    params, _, _ = tuner.best(carry)
    return TuneResult(
        params=params,
        loss=float(best_loss),
        history=history,
        n_sims=int(round(rec.sims[-1])),
        wall_s=float(wall),
        compile_s=float(compile_s),
        converged=converged,
        message=message + _non_finite_note(carry, history, idx, best_loss),
        start_index=int(idx),
        u=_start(carry.best_u, idx),
        constraint_violation=float(np.asarray(carry.best_v)[idx])
        if cfg.al or constraints is not None or (isinstance(loss, Problem) and loss.constraints is not None)
        else 0.0,
        multipliers=np.asarray(carry.lam[idx]) if cfg.al else None,
        n_steps=len(rec.f),
        mode=mode_name,
        n_evals=int(rec.evals[-1]),
        grad_cost=float(grad_cost),
    )


_grad_cost = grad_cost  # ``tune``'s argument of the same name shadows the function


def _start(tree: Any, idx: int) -> Any:
    """Start ``idx`` of a pytree with a leading starts axis, indexed on the host (no eager device op)."""
    return jax.tree_util.tree_map(lambda a: jnp.asarray(np.asarray(a)[idx]), tree)


def _best_index_and_loss(carry: TunerState, tol: float, feasible_first: bool) -> tuple[int, float]:
    """The start whose kept point ranks first, and that point's loss (host side)."""
    i, f = _best_of(
        np.asarray(carry.best_f), np.asarray(carry.best_v), np.asarray(carry.best_m), tol, feasible_first, xp=np
    )
    return int(i), float(f)
