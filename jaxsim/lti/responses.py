"""Open-loop time responses: python-control's ``forced_response`` (alias ``lsim``), ``step_response``,
``impulse_response`` and ``initial_response``.

Results are :class:`TimeResponse` NamedTuples ``(time, outputs, states)`` shaped as python-control's
``TimeResponseData``, time on the **last** axis:

* ``forced_response``/``initial_response``: ``outputs (p, N)``, ``states (n, N)``;
* ``step_response``/``impulse_response``: one trace per input, ``outputs (p, m, N)``,
  ``states (n, m, N)``;
* a SISO system (or a selected single input/output pair) squeezes to ``outputs (N,)`` and
  ``states (n, N)`` unless ``squeeze=False``.

How the response is computed:

* LTI, continuous time — exact discretisation on the (uniform) grid ``T``: the input is linearly
  interpolated between samples (``hold="linear"``, python-control's convention, exact through
  :func:`~jaxsim.lti.discretize.hold_matrices`) or held (``hold="zoh"``, exact through
  :func:`jaxsim.core.discretize.c2d_zoh`).  Steps are constant inputs, so both holds give the same
  exact step response; an impulse is the initial state ``x(0⁺) = B eⱼ`` (python-control: the
  ``D δ(t)`` term is not representable and left out).
* LTI, discrete time — the difference equation; ``T`` must be spaced by ``dt``; an impulse is
  ``u₀ = 1/dt`` (unit area).
* A nonlinear :class:`~jaxsim.core.system.Plant` — ``substeps`` steps of the toolkit's ``solver``
  (:mod:`jaxsim.core.integrators`, RK4 by default) per sample interval, the input held or
  linearly interpolated at every stage time; ``y_k = h(x_k, u_k)`` (the current input, as
  python-control's ``C x + D u``).  ``impulse_response`` is LTI only.

All pure ``jnp`` with a ``lax.scan``: ``jit``/``vmap``/``grad`` through them in the system's
parameters, ``U`` and ``X0``.  ``T`` must then be given explicitly (its length is static).
"""

from __future__ import annotations

from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.discretize import c2d_zoh
from jaxsim.core.integrators import RK4, Solver
from jaxsim.core.loops import fori
from jaxsim.core.system import Plant
from jaxsim.core.validation import check_finite, check_positive_int, check_real, is_concrete
from jaxsim.lti.discretize import hold_matrices
from jaxsim.lti.poles_zeros import pole
from jaxsim.lti.statespace import StateSpace, as_state_space, is_lti

DEFAULT_T_NUM = 1000
HOLDS = ("linear", "zoh")


class TimeResponse(NamedTuple):
    """``time (N,)`` in s; ``outputs`` and ``states`` shaped as in the module docstring (time last).

    Unpacks as python-control's ``t, y, x = ...(return_states=True)``; ``.time``, ``.outputs``,
    ``.states`` as python-control's ``TimeResponseData``; :func:`jaxsim.lti.step_info` takes it."""

    time: jax.Array
    outputs: jax.Array
    states: jax.Array


# --- the system and the time grid --------------------------------------------------------------


def _sizes(sys: Any) -> tuple[int, int, int]:
    if is_lti(sys):
        s = as_state_space(sys)
        return s.n_states, s.n_inputs, s.n_outputs
    if isinstance(sys, Plant):
        return sys.n_states, sys.n_inputs, sys.n_outputs
    as_state_space(sys)  # raises the standard message
    raise AssertionError("unreachable")


def _concrete_system(sys: Any) -> bool:
    leaves = (as_state_space(sys),) if is_lti(sys) else (sys.params,)
    return is_concrete(leaves)


def default_time(sys: Any, T_num: int | None = None, t_final: float | None = None) -> np.ndarray:  # noqa: N803
    """A uniform grid from 0 long enough for the slowest decaying mode (``7/σ_min`` s, σ the decay
    rate of the slowest stable pole; ``10/|λ|_min`` if a pole is not in the open left half-plane,
    10 s for a nonlinear plant) unless ``t_final`` is given; ``T_num`` points (1000 by default;
    a discrete system samples every ``dt``).  Concrete systems only: under ``jit`` pass ``T``."""
    if not _concrete_system(sys):
        raise ValueError("T: required when the system is traced (jit/vmap/grad); pass the time points")
    dt_sys = as_state_space(sys).dt if is_lti(sys) else None
    if t_final is None:
        t_final = 10.0
        if is_lti(sys) and as_state_space(sys).n_states:
            lam = np.asarray(pole(sys))
            if dt_sys is not None:
                lam = np.log(lam[np.abs(lam) > 0].astype(complex)) / dt_sys
            rates = -lam.real
            mags = np.abs(lam)
            if lam.size and np.all(rates > 1e-12 * np.maximum(mags, 1.0)):
                t_final = 7.0 / float(np.min(rates))
            elif np.any(mags > 0):
                t_final = 10.0 / float(np.min(mags[mags > 0]))
    else:
        t_final = float(t_final)
        if not np.isfinite(t_final) or t_final <= 0:
            raise ValueError(f"T: a scalar T is the final time and must be positive, got {t_final!r}")
    if dt_sys is not None:
        n = int(np.floor(t_final / dt_sys + 1e-9)) + 1
        if T_num is None:
            n = min(n, DEFAULT_T_NUM)
        else:
            n = check_positive_int("T_num", T_num)
        return np.arange(n) * dt_sys
    n = DEFAULT_T_NUM if T_num is None else check_positive_int("T_num", T_num)
    return np.linspace(0.0, t_final, n)


def _time(sys: Any, T: Any, T_num: int | None) -> jax.Array:  # noqa: N803
    if T is None or np.ndim(T) == 0:
        return jnp.asarray(default_time(sys, T_num, None if T is None else T))
    t = jnp.asarray(T)
    check_real("T", t)
    t = t.astype(jnp.result_type(t, float))
    if t.ndim != 1 or t.shape[0] < 1:
        raise ValueError(f"T: expected a 1-D array of time points, got shape {tuple(t.shape)}")
    check_finite("T", t)
    if is_concrete(t) and t.shape[0] > 1:
        step = np.diff(np.asarray(t))
        if np.any(step <= 0) or not np.allclose(step, step[0], rtol=1e-9, atol=0.0):
            raise ValueError("T: time points must be increasing and equally spaced")
        dt_sys = as_state_space(sys).dt if is_lti(sys) else None
        if dt_sys is not None and not np.isclose(step[0], dt_sys, rtol=1e-9, atol=0.0):
            raise ValueError(
                f"T: a discrete system with dt={dt_sys} needs time points spaced by dt, got spacing {step[0]:.6g}"
            )
    return t


def _initial_state(X0: Any, n: int) -> jax.Array:  # noqa: N803
    x0 = jnp.asarray(X0)
    check_real("X0", x0)
    x0 = x0.astype(jnp.result_type(x0, float))
    if x0.ndim == 0:
        x0 = jnp.full((n,), x0)
    elif x0.shape != (n,):
        raise ValueError(f"X0: expected a scalar or shape ({n},), got {tuple(x0.shape)}")
    check_finite("X0", x0)
    return x0


def _inputs(U: Any, m: int, n_t: int) -> jax.Array:  # noqa: N803
    u = jnp.asarray(U)
    check_real("U", u)
    u = u.astype(jnp.result_type(u, float))
    if u.ndim == 0:
        u = jnp.full((m, n_t), u)
    elif u.ndim == 1 and m == 1 and u.shape[0] == n_t:
        u = u.reshape(1, n_t)
    if u.shape != (m, n_t):
        raise ValueError(
            f"U: expected a scalar, ({n_t},) for a single input, or ({m}, {n_t}) "
            f"(inputs × time points), got {tuple(jnp.shape(U))}"
        )
    check_finite("U", u)
    return u


# --- simulation kernels (time on axis 0 inside, moved last at the end) ---------------------------


def _lti_continuous(s: StateSpace, t: jax.Array, u: jax.Array, x0: jax.Array, hold: str) -> jax.Array:
    """States ``(N, n)`` of a continuous LTI system on the uniform grid ``t`` (inputs ``u (N, m)``)."""
    if t.shape[0] == 1 or s.n_states == 0:
        return jnp.broadcast_to(x0, (t.shape[0], s.n_states))
    dt = t[1] - t[0]
    if hold == "zoh":
        ad, bd = c2d_zoh(s.a, s.b, dt)

        def step(x, uk):
            x_next = ad @ x + bd @ uk[0]
            return x_next, x_next
    else:
        ad, g0, g1 = hold_matrices(s.a, s.b, dt)

        def step(x, uk):
            x_next = ad @ x + (g0 - g1) @ uk[0] + g1 @ uk[1]
            return x_next, x_next

    pairs = jnp.stack([u[:-1], u[1:]], axis=1)  # (N − 1, 2, m)
    _, xs = jax.lax.scan(step, x0, pairs)
    return jnp.concatenate([x0[None], xs], axis=0)


def _lti_discrete(s: StateSpace, u: jax.Array, x0: jax.Array) -> jax.Array:
    def step(x, uk):
        x_next = s.a @ x + s.b @ uk
        return x_next, x_next

    _, xs = jax.lax.scan(step, x0, u[:-1])
    return jnp.concatenate([x0[None], xs], axis=0)


def _nonlinear(
    plant: Plant, t: jax.Array, u: jax.Array, x0: jax.Array, hold: str, solver: Solver, substeps: int
) -> jax.Array:
    if t.shape[0] == 1:
        return x0[None]
    dt = t[1] - t[0]
    h = dt / substeps

    def interval(x, k):
        t0, u0, u1 = t[k], u[k], u[k + 1]

        def field(tt, z):
            uu = u0 if hold == "zoh" else u0 + (u1 - u0) * ((tt - t0) / dt)
            return plant.f(z, uu, tt)

        x_next = fori(0, substeps, lambda i, z: solver.step(field, t0 + i * h, z, h), x)
        return x_next, x_next

    _, xs = jax.lax.scan(interval, x0, jnp.arange(t.shape[0] - 1))
    return jnp.concatenate([x0[None], xs], axis=0)


@partial(jax.jit, static_argnames=("hold", "solver", "substeps"))
def _simulate(
    sys: Any, t: jax.Array, u: jax.Array, x0: jax.Array, hold: str, solver: Solver, substeps: int
) -> tuple[jax.Array, jax.Array]:
    """``(states (N, n), outputs (N, p))`` for inputs ``u (N, m)``."""
    if is_lti(sys):
        s = as_state_space(sys)
        xs = _lti_discrete(s, u, x0) if s.dt is not None else _lti_continuous(s, t, u, x0, hold)
        return xs, xs @ s.c.T + u @ s.d.T
    xs = _nonlinear(sys, t, u, x0, hold, solver, substeps)
    ys = jax.vmap(sys.h)(xs, u) if sys.feedthrough is not None else jax.vmap(sys.h)(xs)
    return xs, ys


def _check_options(hold: str, substeps: int) -> int:
    if hold not in HOLDS:
        raise ValueError(f"hold: expected one of {HOLDS}, got {hold!r}")
    return check_positive_int("substeps", substeps)


def _index(name: str, idx: Any, size: int) -> int | None:
    if idx is None:
        return None
    if isinstance(idx, (bool, np.bool_)) or not isinstance(idx, (int, np.integer)) or not 0 <= idx < size:
        raise ValueError(f"{name}: expected an index in [0, {size}), got {idx!r}")
    return int(idx)


def _squeeze(y: jax.Array, x: jax.Array, siso: bool, squeeze: bool | None, traces: bool):
    """``y (p, [m,] N)`` → ``(N,)`` and ``x (n, [m,] N)`` → ``(n, N)`` when squeezing."""
    if squeeze is False or not siso:
        return y, x
    y = y[0, 0] if traces else y[0]
    x = x[:, 0] if traces else x
    return y, x


# --- public functions ---------------------------------------------------------------------------


def forced_response(
    sys: Any,
    T: Any = None,
    U: Any = 0.0,
    X0: Any = 0.0,
    *,  # noqa: N803
    hold: str = "linear",
    squeeze: bool | None = None,
    solver: Solver = RK4,
    substeps: int = 10,
) -> TimeResponse:
    """python-control's ``forced_response(sys, T, U, X0)``: the response to the input ``U``.

    Args:
        sys: an LTI system or a nonlinear :class:`Plant`.
        T: ``(N,)`` equally spaced times in s (a discrete system: spaced by ``dt``; may be omitted
            there, then ``N`` comes from ``U``).
        U: inputs ``(m, N)`` (``(N,)`` for one input, a scalar for a constant).
        X0: initial state ``(n,)`` or a scalar.
        hold: ``"linear"`` (python-control's, input linear between samples) or ``"zoh"``.
        squeeze: ``None`` squeezes a SISO system's outputs to ``(N,)``; ``False`` never.
        solver, substeps: the integrator for a nonlinear plant (``substeps`` steps per interval).

    Raises:
        ValueError: naming ``T`` (not 1-D, not uniform, NaN, missing under tracing), ``U``/``X0``
            (shape, NaN), ``hold``, ``substeps``, ``sys`` (not a system).
    """
    n, m, p = _sizes(sys)
    substeps = _check_options(hold, substeps)
    if T is None:
        if is_lti(sys) and as_state_space(sys).dt is not None and np.ndim(U) >= 1:
            T = np.arange(np.shape(U)[-1]) * as_state_space(sys).dt
        else:
            raise ValueError(
                "T: the time points are required (only a discrete system given an input array U can do without)"
            )
    t = _time(sys, T, None)
    u = _inputs(U, m, t.shape[0])
    x0 = _initial_state(X0, n)
    xs, ys = _simulate(sys, t, u.T, x0, hold, solver, substeps)
    y, x = _squeeze(ys.T, xs.T, m == 1 and p == 1, squeeze, traces=False)
    return TimeResponse(t, y, x)


lsim = forced_response
"""Alias of :func:`forced_response` (same argument order ``sys, T, U, X0``; note that
``control.matlab.lsim`` takes ``sys, U, T, X0`` and returns ``yout, T, xout``)."""


def _per_input(sys: Any, t: jax.Array, inputs: list[int], x0_of, u_of, solver, substeps):
    """Stack one simulation per selected input along a new axis 1: ``(p, k, N)``, ``(n, k, N)``."""
    ys, xs = [], []
    for j in inputs:
        x, y = _simulate(sys, t, u_of(j), x0_of(j), "zoh", solver, substeps)
        ys.append(y.T)
        xs.append(x.T)
    return jnp.stack(ys, axis=1), jnp.stack(xs, axis=1)


def step_response(
    sys: Any,
    T: Any = None,
    X0: Any = 0.0,
    input: int | None = None,  # noqa: A002,N803
    output: int | None = None,
    T_num: int | None = None,
    squeeze: bool | None = None,
    *,
    solver: Solver = RK4,
    substeps: int = 10,
) -> TimeResponse:
    """python-control's ``step_response(sys, T, X0, input, output, T_num)``: a unit step on each
    input in turn (all others zero) from ``X0``; exact for LTI systems.

    ``T``: ``(N,)`` times, a scalar final time, or ``None`` (concrete systems: :func:`default_time`).
    ``input``/``output``: keep only that input's trace / that output.  Shapes: module docstring.
    """
    n, m, p = _sizes(sys)
    substeps = check_positive_int("substeps", substeps)
    i_in, i_out = _index("input", input, m), _index("output", output, p)
    t = _time(sys, T, T_num)
    x0 = _initial_state(X0, n)
    dtype = jnp.result_type(t, x0)
    inputs = list(range(m)) if i_in is None else [i_in]
    ys, xs = _per_input(
        sys, t, inputs, lambda j: x0, lambda j: jnp.zeros((t.shape[0], m), dtype).at[:, j].set(1.0), solver, substeps
    )
    if i_out is not None:
        ys = ys[i_out : i_out + 1]
    y, x = _squeeze(ys, xs, ys.shape[0] == 1 and ys.shape[1] == 1, squeeze, traces=True)
    return TimeResponse(t, y, x)


def impulse_response(
    sys: Any,
    T: Any = None,
    input: int | None = None,  # noqa: A002,N803
    output: int | None = None,
    T_num: int | None = None,
    squeeze: bool | None = None,
) -> TimeResponse:
    """python-control's ``impulse_response(sys, T, input, output, T_num)`` for an LTI system: a unit
    impulse on each input in turn (continuous: ``x(0⁺) = B eⱼ``, the ``D δ(t)`` output term left
    out; discrete: ``u₀ = 1/dt``).  Shapes as :func:`step_response`."""
    if not is_lti(sys):
        raise ValueError(
            "sys: impulse_response needs an LTI system (a nonlinear plant has no well-defined impulse response)"
        )
    s = as_state_space(sys)
    n, m, p = s.n_states, s.n_inputs, s.n_outputs
    i_in, i_out = _index("input", input, m), _index("output", output, p)
    t = _time(sys, T, T_num)
    dtype = jnp.result_type(t, s.a)
    inputs = list(range(m)) if i_in is None else [i_in]
    zeros_u = jnp.zeros((t.shape[0], m), dtype)
    if s.dt is None:
        ys, xs = _per_input(sys, t, inputs, lambda j: s.b[:, j].astype(dtype), lambda j: zeros_u, RK4, 1)
    else:
        ys, xs = _per_input(
            sys, t, inputs, lambda j: jnp.zeros((n,), dtype), lambda j: zeros_u.at[0, j].set(1.0 / s.dt), RK4, 1
        )
    if i_out is not None:
        ys = ys[i_out : i_out + 1]
    y, x = _squeeze(ys, xs, ys.shape[0] == 1 and ys.shape[1] == 1, squeeze, traces=True)
    return TimeResponse(t, y, x)


def initial_response(
    sys: Any,
    T: Any = None,
    X0: Any = 0.0,
    output: int | None = None,  # noqa: N803
    T_num: int | None = None,
    squeeze: bool | None = None,
    *,
    solver: Solver = RK4,
    substeps: int = 10,
) -> TimeResponse:
    """python-control's ``initial_response(sys, T, X0, output, T_num)``: the free response from
    ``X0`` (zero input).  Shapes as :func:`forced_response` (squeezed for a SISO system or a
    selected ``output``)."""
    n, m, p = _sizes(sys)
    substeps = check_positive_int("substeps", substeps)
    i_out = _index("output", output, p)
    t = _time(sys, T, T_num)
    x0 = _initial_state(X0, n)
    u = jnp.zeros((t.shape[0], m), jnp.result_type(t, x0))
    xs, ys = _simulate(sys, t, u, x0, "zoh", solver, substeps)
    ys = ys.T if i_out is None else ys.T[i_out : i_out + 1]
    y, x = _squeeze(ys, xs.T, (m == 1 and p == 1) or i_out is not None, squeeze, traces=False)
    return TimeResponse(t, y, x)
