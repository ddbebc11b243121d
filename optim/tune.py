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
together in one ``vmap``; every step is one jitted call, after which the host records the history,
checks early stopping and calls ``callback``.  A start *converges* (and stops) when its gradient
norm falls to ``gtol`` or its kept point has not improved by ``rtol`` (relative) for ``patience``
steps; ``TuneResult.converged`` says whether the start returned did, as opposed to running out of
steps, and ``message`` gives the last gradient norm.

Which point is kept: the evaluated iterate with the lowest objective — without constraints the
loss; with ``"penalty"`` the penalised loss (the problem being solved); with
``"augmented_lagrangian"`` a point with total violation ``Σ max(0, g) ≤ constraint_tol`` beats any
infeasible one, feasible points are ranked by the loss and infeasible ones by
``f + (w/2)Σ max(0, g)²``.  A start whose loss or gradient turns NaN/inf
stops there (the others go on); the run stops when no start is left and says so in ``message``,
returning the best finite point.

Gradients: ``mode="reverse"`` (``value_and_grad``) or ``"forward"`` (``jacfwd`` on the flattened
``u``, the value comes with it); ``"auto"`` takes forward mode up to
:data:`FORWARD_MODE_MAX_PARAMS` unconstrained parameters (the crossover measured by
``experiments/benchmarks/ad_mode_crossover.py`` on a closed-loop PID loss).

Accounting: one loss evaluation (with its gradient, in either mode) counts ``sims_per_eval``
simulations per start that is still running; optimisers with a line search (``optax.lbfgs``) add
``sims_per_eval`` per line-search trial.  ``wall_s`` is the stepping time; the setup (initial
state, tracing, compilation) is reported as ``compile_s``.
"""

from __future__ import annotations

import time
from typing import Any, Callable, Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax
from jax.flatten_util import ravel_pytree

from jaxsim.core.progress import postfix, progress_bar
from jaxsim.core.validation import check_finite
from jaxsim.problem import Problem
from jaxsim.problem.reparam import apply, check_domain, invert
from optim.results import History, TuneResult, check_int, check_some_loss_finite

FORWARD_MODE_MAX_PARAMS = 32
"""``mode="auto"`` uses forward mode up to this many unconstrained parameters.

Measured on the 2-core CPU this project runs on (``experiments/benchmarks/ad_mode_crossover.py``,
closed-loop PID loss, 300 ticks): forward mode was faster at every tested count up to 30 (4–8× at
3 gains) and reverse mode took over between 36 and 96; 32 stays on the safe side for losses with
heavier per-step work, where reverse mode's relative overhead is smaller."""

Mode = Literal["auto", "forward", "reverse"]
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


def _check_number(name: str, value: Any, *, allow_zero: bool = False) -> float:
    """Require a finite positive (or non-negative) number; return it as ``float``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: must be a number, got {value!r}") from None
    if not np.isfinite(v) or (v < 0 if allow_zero else v <= 0):
        rel = "non-negative" if allow_zero else "positive"
        raise ValueError(f"{name}: must be finite and {rel}, got {value!r}")
    return v


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


def _make_objective(loss: Callable, reparam: Any, constraints: Callable | None, cfg: _Settings):
    """``objective(u, lam) -> (J, (f, g, violation, merit))`` in unconstrained space."""

    def objective(u: Any, lam: jax.Array):
        x = apply(reparam, u)
        f = jnp.asarray(loss(x))
        if f.shape != ():
            raise ValueError(f"loss: must return a scalar, got shape {f.shape}")
        g = jnp.zeros((0,), f.dtype) if constraints is None else jnp.ravel(jnp.asarray(constraints(x), f.dtype))
        pos = jnp.maximum(g, 0.0)
        merit = f + 0.5 * cfg.w * jnp.sum(pos**2)
        if cfg.al:
            j = f + jnp.sum(jnp.maximum(lam + cfg.w * g, 0.0) ** 2 - lam**2) / (2 * cfg.w)
        else:
            j = merit
        return j, (f, g, jnp.sum(pos), merit)

    return objective


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
        if extra_args:
            updates, new_state = opt.update(
                grad, c.opt_state, c.u, value=j, grad=grad, value_fn=lambda uu: objective(uu, c.lam)[0]
            )
        else:
            updates, new_state = opt.update(grad, c.opt_state, c.u)
        move = running & finite
        lam = c.lam
        if cfg.al:
            due = (c.step + 1) % cfg.multiplier_every == 0
            lam = jnp.where(move & due, jnp.maximum(lam + cfg.w * g, 0.0), lam)
        since = jnp.where(keep & improved, 0, c.since_improve + 1)
        active = c.active & ~(gnorm <= cfg.gtol)
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
            alive=c.alive & (finite | ~running),
            active=active,
            since_improve=since,
            step=c.step + 1,
        )
        new = jax.tree_util.tree_map(lambda a, b: a.astype(b.dtype), new, c)  # fixed avals: one compile
        return new, StepInfo(f, gnorm, viol, finite, running, jnp.where(running, evals, 0), apply(reparam, c.u))

    return tuner_step


def _initial_carry(
    key: jax.Array, u0: Any, opt: optax.GradientTransformation, n_starts: int, spread: float, m_constraints: int
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


class Tuner(NamedTuple):
    """The optax-like pure pair of :func:`gradient_tuner` (plus a host-side reader).

    init(params0=None, key=None) -> TunerState: ``S`` starts (start 0 at ``params0``, default the
    problem's ``space.init``); step(state) -> (state, StepInfo): one jitted step of every start;
    best(state) -> (params, loss, start): the best point kept so far (host side, NumPy).
    ``settings``, ``reparam``, ``n_starts``: what the pair was built with.
    """

    init: Callable[..., TunerState]
    step: Callable[[TunerState], tuple[TunerState, StepInfo]]
    best: Callable[[TunerState], tuple[Any, float, int]]
    settings: _Settings
    reparam: Any
    n_starts: int


class _Resolved(NamedTuple):
    loss: Callable
    params0: Any
    reparam: Any
    constraints: Callable | None
    sims_per_eval: int
    penalty_weight: float
    name: str


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
) -> Tuner:
    """The gradient tuner as a pure pair ``(init, step)`` a user can drive from their own loop::

        tuner = gradient_tuner(problem, optax.adam(0.05), n_starts=4)
        state = tuner.init(key=jax.random.PRNGKey(0))
        for _ in range(100):
            state, info = tuner.step(state)        # info.f: (4,) losses, info.grad_norm, ...
        params, loss, start = tuner.best(state)

    Arguments as in :func:`tune` (``params0`` here only fixes the structure and the ``"auto"`` mode
    choice; a Problem's ``space.init`` by default).  :func:`tune` is this pair plus the host loop.
    """
    r = _resolve(loss, params0, reparam, constraints, sims_per_eval, penalty_weight)
    n_starts = check_int("n_starts", n_starts)
    if patience is not None:
        patience = check_int("patience", patience)
    spread = _check_number("init_spread", init_spread, allow_zero=True)
    if constraint_method not in ("penalty", "augmented_lagrangian"):
        raise ValueError(f"constraint_method: must be 'penalty' or 'augmented_lagrangian', got {constraint_method!r}")
    if mode not in ("auto", "forward", "reverse"):
        raise ValueError(f"mode: must be 'auto', 'forward' or 'reverse', got {mode!r}")
    opt = optax.adam(1e-2) if optimizer is None else optimizer
    if not (hasattr(opt, "init") and hasattr(opt, "update")):
        raise ValueError(f"optimizer: must be an optax.GradientTransformation, got {type(opt).__name__}")
    template = _as_float_tree(r.params0)
    u_template = jax.eval_shape(lambda x: invert(r.reparam, x), template)
    n_params = int(sum(np.prod(leaf.shape) for leaf in jax.tree_util.tree_leaves(u_template)))
    cfg = _Settings(
        w=_check_number("penalty_weight", r.penalty_weight),
        tol=_check_number("constraint_tol", constraint_tol, allow_zero=True),
        rtol=_check_number("rtol", rtol, allow_zero=True),
        gtol=_check_number("gtol", gtol, allow_zero=True),
        patience=patience,
        multiplier_every=check_int("multiplier_every", multiplier_every),
        al=r.constraints is not None and constraint_method == "augmented_lagrangian",
        use_forward=mode == "forward" or (mode == "auto" and n_params <= FORWARD_MODE_MAX_PARAMS),
        sims_per_eval=check_int("sims_per_eval", r.sims_per_eval),
    )
    m_constraints = 0
    if r.constraints is not None:
        g = jax.eval_shape(lambda u: jnp.ravel(jnp.asarray(r.constraints(apply(r.reparam, u)))), u_template)
        m_constraints = int(np.prod(g.shape))
    objective = _make_objective(r.loss, r.reparam, r.constraints, cfg)
    make_carry = jax.jit(_initial_carry, static_argnums=(2, 3, 4, 5))
    step = jax.jit(jax.vmap(_make_step(objective, opt, r.reparam, cfg)))

    def init(params0: Any = None, key: jax.Array | None = None) -> TunerState:
        x0 = template if params0 is None else _as_float_tree(params0)
        check_finite("params0", x0)
        check_domain(r.reparam, x0, "params0")
        u0 = invert(r.reparam, x0)
        check_finite("params0 (in unconstrained space)", u0)
        return make_carry(jax.random.PRNGKey(0) if key is None else key, u0, opt, n_starts, spread, m_constraints)

    def best(state: TunerState) -> tuple[Any, float, int]:
        idx, best_loss = _best_index_and_loss(state, cfg.tol, cfg.al)
        u = jax.tree_util.tree_map(lambda a: a[idx], state.best_u)
        return apply(r.reparam, u), best_loss, idx

    return Tuner(init, step, best, cfg, r.reparam, n_starts)


class _Records(NamedTuple):
    f: list
    grad_norm: list
    violation: list
    best: list
    sims: list
    wall: list


def _run_steps(
    step_fn: Callable, carry: TunerState, steps: int, cfg: _Settings, callback: Callable | None, bar: Any
) -> tuple[TunerState, _Records, str, bool]:
    """The host loop: one jitted step per iteration, records, callback and stopping.

    Returns ``(state, records, reason, stopped_by_callback)``."""
    rec = _Records([], [], [], [], [], [])
    sims, reason = 0, ""
    start = time.perf_counter()
    for k in range(steps):
        carry, out = step_fn(carry)
        host = jax.device_get(out._replace(x=None))
        sims += int(np.sum(host.evals)) * cfg.sims_per_eval
        rec.f.append(host.f)
        rec.grad_norm.append(host.grad_norm)
        rec.violation.append(host.violation)
        rec.best.append(_best_index_and_loss(carry, cfg.tol, cfg.al)[1])
        rec.sims.append(sims)
        rec.wall.append(time.perf_counter() - start)
        bar.update(1)
        postfix(bar, f"best {rec.best[-1]:.6g}")
        f_now = np.where(host.ran & host.finite, host.f, np.inf)
        if callback is not None and np.any(np.isfinite(f_now)):
            i = int(np.argmin(f_now))
            if callback(k, jax.tree_util.tree_map(lambda a: a[i], out.x), float(f_now[i])):
                return carry, rec, f"stopped by callback at step {k}", True
        alive, active = np.asarray(carry.alive), np.asarray(carry.active)
        if not np.any(alive & active):
            if not np.all(alive):
                reason = f"stopped at step {k}: every start stopped"
            else:
                reason = (
                    f"early stop at step {k}: converged (patience={cfg.patience}, rtol={cfg.rtol:g}, gtol={cfg.gtol:g})"
                )
            break
    return carry, rec, reason, False


def _history(rec: _Records) -> History:
    f_hist, g_hist = np.stack(rec.f), np.stack(rec.grad_norm)
    f_masked = np.where(np.isfinite(f_hist), f_hist, np.inf)
    rows, pick = np.arange(len(rec.f)), np.argmin(f_masked, axis=1)
    return History(
        best_loss=np.asarray(rec.best, float),
        sims=np.asarray(rec.sims),
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
        why = (
            "gradient norm ≤ gtol" if last_g <= cfg.gtol else f"no relative improvement > rtol for {cfg.patience} steps"
        )
        head = reason or f"converged within {steps} steps"
        return True, f"{head}; start {idx} converged: {why} (last gradient norm {last_g:.3g})"
    if not reason:
        reason = f"ran out of steps: {steps} steps without meeting the convergence test ({test})"
    return False, f"{reason}; last gradient norm {last_g:.3g} (start {idx})"


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
) -> TuneResult:
    """Minimise a :class:`~jaxsim.problem.Problem`'s loss (or ``loss(params)``) by gradient steps.

    Args:
        loss: a Problem (its ``space.init``, ``space.reparam``, ``constraints``, scenarios per loss
            evaluation and ``penalty_weight`` are the defaults of the arguments below), or a plain
            ``params -> scalar`` function, pure and differentiable (jitted by the tuner).
        params0: pytree of arrays inside the domain of ``reparam`` (required for a plain loss).
        optimizer: any ``optax.GradientTransformation`` (default ``optax.adam(1e-2)``); line-search
            optimisers (``optax.lbfgs``) receive ``value``, ``grad`` and ``value_fn``.
        steps: maximum number of loss evaluations per start.
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
        callback: ``callback(step, params, loss) -> stop`` after every step, with the current
            iterate of the start with the lowest current loss; a true return value stops the run.
        sims_per_eval: simulations one loss evaluation costs (accounting only; default 1, a
            Problem's number of scenarios).
        mode: ``"auto"``, ``"forward"`` or ``"reverse"`` gradient.
        progress: ``True`` for a tqdm bar (steps, best loss), or a bar factory
            (:mod:`jaxsim.core.progress`).

    Returns:
        :class:`~optim.results.TuneResult`; ``converged`` says whether the start kept met the
        convergence test (``gtol`` / ``patience``) rather than running out of steps, and
        ``message`` gives the reason and the last gradient norm.
    """
    if callback is not None and not callable(callback):
        raise ValueError("callback: must be callable or None")
    steps = check_int("steps", steps)
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
    )
    cfg = tuner.settings
    t0 = time.perf_counter()
    carry = tuner.init(None, key)
    tuner.step.lower(carry).compile()  # cached by jit for the loop below
    compile_s = time.perf_counter() - t0

    name = loss.name if isinstance(loss, Problem) else "loss"
    bar = progress_bar(progress, total=steps, desc=f"tune {name}", unit="step")
    try:
        carry, rec, reason, by_callback = _run_steps(tuner.step, carry, steps, cfg, callback, bar)
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
    best_u = jax.tree_util.tree_map(lambda a: a[idx], carry.best_u)
    return TuneResult(
        params=apply(tuner.reparam, best_u),
        loss=float(best_loss),
        history=history,
        n_sims=int(rec.sims[-1]),
        wall_s=float(wall),
        compile_s=float(compile_s),
        converged=converged,
        message=message + _non_finite_note(carry, history, idx, best_loss),
        start_index=int(idx),
        u=best_u,
        constraint_violation=float(np.asarray(carry.best_v)[idx])
        if cfg.al or constraints is not None or (isinstance(loss, Problem) and loss.constraints is not None)
        else 0.0,
        multipliers=np.asarray(carry.lam[idx]) if cfg.al else None,
        n_steps=len(rec.f),
        mode="forward" if cfg.use_forward else "reverse",
    )


def _best_index_and_loss(carry: TunerState, tol: float, feasible_first: bool) -> tuple[int, float]:
    """The start whose kept point ranks first, and that point's loss."""
    f = np.asarray(carry.best_f)
    v = np.asarray(carry.best_v)
    m = np.asarray(carry.best_m)
    feasible = v <= tol
    if feasible_first and np.any(feasible & np.isfinite(f)):
        cand = np.where(feasible, f, np.inf)
    else:
        cand = m
    i = int(np.argmin(cand))
    return i, float(f[i])
