"""Gradient tuner: ``tune(loss, params0, ...)`` with any optax optimiser.

The tuner works in unconstrained space: ``x = apply(reparam, u)`` (see :mod:`optim.reparam`), so
bounds, positivity and orderings hold at every step.  General inequality constraints
``g(x) ≤ 0`` (``constraints(x)`` returns ``g``, any shape) enter the objective in ``u``-space as

* ``"penalty"``: ``J = f + (w/2)·Σ max(0, g)²`` (its minimiser violates active constraints by
  about ``λ*/w``);
* ``"augmented_lagrangian"`` (Powell–Hestenes–Rockafellar): ``J = f + (1/2w)·Σ[max(0, λ + w g)² − λ²]``
  with multipliers ``λ ← max(0, λ + w g)`` every ``multiplier_every`` steps, which drives the
  violation to zero at a finite ``w`` (``w`` = ``penalty_weight``).

Several starts (``n_starts``; start 0 is ``params0``, the others ``u0 + init_spread·N(0, 1)``) step
together in one ``vmap``; every step is one jitted call, after which the host records the history,
checks early stopping and calls ``callback``.

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

from jaxsim.core.validation import check_finite
from optim.reparam import apply, check_domain, invert
from optim.results import check_int, check_some_loss_finite

FORWARD_MODE_MAX_PARAMS = 32
"""``mode="auto"`` uses forward mode up to this many unconstrained parameters.

Measured on the 2-core CPU this project runs on (``experiments/benchmarks/ad_mode_crossover.py``,
closed-loop PID loss, 300 ticks): forward mode was faster at every tested count up to 30 (4–8× at
3 gains) and reverse mode took over between 36 and 96; 32 stays on the safe side for losses with
heavier per-step work, where reverse mode's relative overhead is smaller."""

Mode = Literal["auto", "forward", "reverse"]
ConstraintMethod = Literal["penalty", "augmented_lagrangian"]


class History(NamedTuple):
    """Per-step record (``T`` steps run, ``S`` starts), NumPy arrays.

    loss ``(T,)``: lowest current loss over the running starts; best_loss ``(T,)``: loss of the
    best point kept so far (see the module docstring); grad_norm ``(T,)``: gradient norm in
    ``u``-space of the start giving ``loss``; sims ``(T,)``: cumulative simulations; wall_s
    ``(T,)``: cumulative seconds since the first step; loss_per_start, grad_norm_per_start,
    violation_per_start ``(T, S)``.
    """

    loss: np.ndarray
    best_loss: np.ndarray
    grad_norm: np.ndarray
    sims: np.ndarray
    wall_s: np.ndarray
    loss_per_start: np.ndarray
    grad_norm_per_start: np.ndarray
    violation_per_start: np.ndarray


class TuneResult(NamedTuple):
    """Outcome of :func:`tune`.

    params: best point (pytree like ``params0``); loss: its loss (without penalty terms);
    history: :class:`History`; n_sims: simulations used; wall_s: seconds of stepping (compile
    excluded); message: why it stopped; start_index: the start that found ``params``;
    u: ``params`` in unconstrained space; constraint_violation: ``Σ max(0, g)`` at ``params``
    (0 without constraints); multipliers: final augmented-Lagrangian multipliers of that start
    (``None`` otherwise); compile_s: compile time; n_steps: steps run; mode: gradient mode used.
    """

    params: Any
    loss: float
    history: History
    n_sims: int
    wall_s: float
    message: str
    start_index: int
    u: Any = None
    constraint_violation: float = 0.0
    multipliers: Any = None
    compile_s: float = 0.0
    n_steps: int = 0
    mode: str = "reverse"


class _Carry(NamedTuple):
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


class _Out(NamedTuple):
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
        feas & bfeas, f < bf - rtol * jnp.abs(bf),
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

    def tuner_step(c: _Carry) -> tuple[_Carry, _Out]:
        (j, (f, g, viol, merit)), grad = value_and_grad(c.u, c.lam)
        gnorm = optax.tree.norm(grad)
        finite = jnp.isfinite(j) & jnp.isfinite(f) & jnp.isfinite(gnorm)
        running = c.alive & c.active
        better, improved = _ranking(f, viol, merit, c.best_f, c.best_v, c.best_m, cfg.tol, cfg.rtol, cfg.al)
        keep = running & finite & better
        if extra_args:
            updates, new_state = opt.update(grad, c.opt_state, c.u, value=j, grad=grad,
                                            value_fn=lambda uu: objective(uu, c.lam)[0])
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
        new = _Carry(
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
        return new, _Out(f, gnorm, viol, finite, running, jnp.where(running, evals, 0), apply(reparam, c.u))

    return tuner_step


def _initial_carry(key: jax.Array, u0: Any, opt: optax.GradientTransformation, n_starts: int,
                   spread: float, m_constraints: int) -> _Carry:
    """Start 0 is ``u0``, the others ``u0 + spread·N(0, 1)``; strong dtypes so the step compiles once."""
    v0, unravel = ravel_pytree(u0)
    noise = spread * jax.random.normal(key, (n_starts, v0.size), v0.dtype)
    u_starts = jax.vmap(unravel)(v0[None, :] + noise.at[0].set(0.0))
    inf = jnp.full((n_starts,), jnp.inf, v0.dtype)
    carry = _Carry(
        u=u_starts,
        opt_state=jax.vmap(opt.init)(u_starts),
        lam=jnp.zeros((n_starts, m_constraints), v0.dtype),
        best_u=u_starts,
        best_f=inf, best_v=inf, best_m=inf,
        best_step=jnp.full((n_starts,), -1, jnp.int32),
        alive=jnp.ones((n_starts,), bool),
        active=jnp.ones((n_starts,), bool),
        since_improve=jnp.zeros((n_starts,), jnp.int32),
        step=jnp.zeros((n_starts,), jnp.int32),
    )
    return jax.tree_util.tree_map(lambda a: jnp.array(a, dtype=a.dtype), carry)


class _Records(NamedTuple):
    f: list
    grad_norm: list
    violation: list
    best: list
    sims: list
    wall: list


def _run_steps(step_fn: Callable, carry: _Carry, steps: int, cfg: _Settings,
               callback: Callable | None) -> tuple[_Carry, _Records, str]:
    """The host loop: one jitted step per iteration, records, callback and stopping."""
    rec = _Records([], [], [], [], [], [])
    sims, reason = 0, f"completed {steps} steps"
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
        f_now = np.where(host.ran & host.finite, host.f, np.inf)
        if callback is not None and np.any(np.isfinite(f_now)):
            i = int(np.argmin(f_now))
            if callback(k, jax.tree_util.tree_map(lambda a: a[i], out.x), float(f_now[i])):
                return carry, rec, f"stopped by callback at step {k}"
        alive, active = np.asarray(carry.alive), np.asarray(carry.active)
        if not np.any(alive & active):
            if not np.all(alive):
                reason = f"stopped at step {k}: every start stopped"
            else:
                reason = (f"early stop at step {k}: converged (patience={cfg.patience}, "
                          f"rtol={cfg.rtol:g}, gtol={cfg.gtol:g})")
            break
    return carry, rec, reason


def _history(rec: _Records) -> History:
    f_hist, g_hist = np.stack(rec.f), np.stack(rec.grad_norm)
    f_masked = np.where(np.isfinite(f_hist), f_hist, np.inf)
    rows, pick = np.arange(len(rec.f)), np.argmin(f_masked, axis=1)
    return History(
        loss=f_masked[rows, pick], best_loss=np.asarray(rec.best, float), grad_norm=g_hist[rows, pick],
        sims=np.asarray(rec.sims), wall_s=np.asarray(rec.wall), loss_per_start=f_hist,
        grad_norm_per_start=g_hist, violation_per_start=np.stack(rec.violation),
    )


def _non_finite_note(carry: _Carry, history: History, idx: int, best_loss: float) -> str:
    """'' when every start stayed finite; otherwise which starts broke, when, and what was kept."""
    dead = np.flatnonzero(~np.asarray(carry.alive))
    if not dead.size:
        return ""
    bad = ~np.isfinite(history.loss_per_start) | ~np.isfinite(history.grad_norm_per_start)
    first_bad = [int(np.argmax(bad[:, i])) for i in dead]
    return (f"; the loss or its gradient was non-finite (NaN/inf) in start(s) {dead.tolist()} at "
            f"step(s) {first_bad}; kept the best finite point (start {idx}, step "
            f"{int(np.asarray(carry.best_step)[idx])}, loss {best_loss:.6g})")


def tune(
    loss: Callable[[Any], jax.Array],
    params0: Any,
    *,
    optimizer: optax.GradientTransformation | None = None,
    steps: int = 200,
    reparam: Any = None,
    constraints: Callable[[Any], jax.Array] | None = None,
    constraint_method: ConstraintMethod = "penalty",
    penalty_weight: float = 100.0,
    multiplier_every: int = 50,
    constraint_tol: float = 1e-6,
    n_starts: int = 1,
    key: jax.Array | None = None,
    init_spread: float = 0.5,
    patience: int | None = None,
    rtol: float = 1e-8,
    gtol: float = 0.0,
    callback: Callable[[int, Any, float], bool | None] | None = None,
    sims_per_eval: int = 1,
    mode: Mode = "auto",
) -> TuneResult:
    """Minimise ``loss(params)`` from ``params0`` by gradient steps of ``optimizer``.

    Args:
        loss: ``params -> scalar``, pure and differentiable (jitted by the tuner).
        params0: pytree of arrays, inside the domain of ``reparam``.
        optimizer: any ``optax.GradientTransformation`` (default ``optax.adam(1e-2)``); line-search
            optimisers (``optax.lbfgs``) receive ``value``, ``grad`` and ``value_fn``.
        steps: maximum number of loss evaluations per start.
        reparam: pytree of :mod:`optim.reparam` objects (a prefix of ``params0``); None: identity.
        constraints: ``params -> g``; feasible iff every ``g ≤ 0``.
        constraint_method: ``"penalty"`` or ``"augmented_lagrangian"`` (module docstring).
        penalty_weight: ``w`` of the penalty / augmented Lagrangian.
        multiplier_every: steps between multiplier updates (augmented Lagrangian).
        constraint_tol: total violation below which a point counts as feasible.
        n_starts, key, init_spread: multi-start (vmapped); perturbations are in ``u``-space.
        patience, rtol: a start stops once its kept point has not improved by more than
            ``rtol`` (relative) for ``patience`` steps (None: never).
        gtol: a start stops once its gradient norm (in ``u``-space) is ≤ ``gtol``.
        callback: ``callback(step, params, loss) -> stop`` after every step, with the current
            iterate of the start with the lowest current loss; a true return value stops the run.
        sims_per_eval: simulations one loss evaluation costs (accounting only).
        mode: ``"auto"``, ``"forward"`` or ``"reverse"`` gradient.
    """
    if not callable(loss):
        raise ValueError(f"loss: must be callable, got {type(loss).__name__}")
    steps = check_int("steps", steps)
    n_starts = check_int("n_starts", n_starts)
    if patience is not None:
        patience = check_int("patience", patience)
    spread = _check_number("init_spread", init_spread, allow_zero=True)
    if constraint_method not in ("penalty", "augmented_lagrangian"):
        raise ValueError("constraint_method: must be 'penalty' or 'augmented_lagrangian', "
                         f"got {constraint_method!r}")
    if mode not in ("auto", "forward", "reverse"):
        raise ValueError(f"mode: must be 'auto', 'forward' or 'reverse', got {mode!r}")
    if callback is not None and not callable(callback):
        raise ValueError("callback: must be callable or None")
    opt = optax.adam(1e-2) if optimizer is None else optimizer
    if not (hasattr(opt, "init") and hasattr(opt, "update")):
        raise ValueError(f"optimizer: must be an optax.GradientTransformation, got {type(opt).__name__}")
    if not jax.tree_util.tree_leaves(params0):
        raise ValueError("params0: must contain at least one array")
    params0 = jax.tree_util.tree_map(lambda a: jnp.asarray(a, dtype=jnp.result_type(a, float)), params0)
    check_finite("params0", params0)
    check_domain(reparam, params0, "params0")
    u0 = invert(reparam, params0)
    check_finite("params0 (in unconstrained space)", u0)
    n_params = int(ravel_pytree(u0)[0].size)
    cfg = _Settings(
        w=_check_number("penalty_weight", penalty_weight),
        tol=_check_number("constraint_tol", constraint_tol, allow_zero=True),
        rtol=_check_number("rtol", rtol, allow_zero=True),
        gtol=_check_number("gtol", gtol, allow_zero=True),
        patience=patience,
        multiplier_every=check_int("multiplier_every", multiplier_every),
        al=constraints is not None and constraint_method == "augmented_lagrangian",
        use_forward=mode == "forward" or (mode == "auto" and n_params <= FORWARD_MODE_MAX_PARAMS),
        sims_per_eval=check_int("sims_per_eval", sims_per_eval),
    )
    m_constraints = 0
    if constraints is not None:
        g = jax.eval_shape(lambda u: jnp.ravel(jnp.asarray(constraints(apply(reparam, u)))), u0)
        m_constraints = int(np.prod(g.shape))

    objective = _make_objective(loss, reparam, constraints, cfg)
    t0 = time.perf_counter()
    carry = jax.jit(_initial_carry, static_argnums=(2, 3, 4, 5))(
        jax.random.PRNGKey(0) if key is None else key, u0, opt, n_starts, spread, m_constraints)
    step_fn = jax.jit(jax.vmap(_make_step(objective, opt, reparam, cfg)))
    step_fn.lower(carry).compile()  # cached by jit for the loop below
    compile_s = time.perf_counter() - t0

    carry, rec, reason = _run_steps(step_fn, carry, steps, cfg, callback)
    wall = rec.wall[-1]
    idx, best_loss = _best_index_and_loss(carry, cfg.tol, cfg.al)
    # a start whose loss or gradient is not finite stops there: its first point was all it evaluated
    check_some_loss_finite(best_loss, f"the first point of each of the {n_starts} start(s)",
                           f"check params0 and the loss (first values {np.asarray(rec.f[0])})")
    history = _history(rec)
    best_u = jax.tree_util.tree_map(lambda a: a[idx], carry.best_u)
    return TuneResult(
        params=apply(reparam, best_u),
        loss=float(best_loss),
        history=history,
        n_sims=int(rec.sims[-1]),
        wall_s=float(wall),
        message=reason + _non_finite_note(carry, history, idx, best_loss),
        start_index=int(idx),
        u=best_u,
        constraint_violation=float(np.asarray(carry.best_v)[idx]) if constraints is not None else 0.0,
        multipliers=np.asarray(carry.lam[idx]) if cfg.al else None,
        compile_s=float(compile_s),
        n_steps=len(rec.f),
        mode="forward" if cfg.use_forward else "reverse",
    )


def _best_index_and_loss(carry: _Carry, tol: float, feasible_first: bool) -> tuple[int, float]:
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
