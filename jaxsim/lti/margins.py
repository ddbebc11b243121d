"""Gain, phase, stability and delay margins of a SISO loop transfer function ``L``, at python-control's
definitions, differentiable so that a margin can be a tuning constraint.

Definitions (``ω`` in rad/s; ``L(jω)``, or ``L(e^{jω·dt})`` with ``0 ≤ ω < π/dt`` in discrete time):

* phase crossover frequencies ``ω_pc ≥ 0``: ``Im L = 0`` with ``Re L ≤ 0`` (``ω = 0`` counts when the
  DC gain is finite and ≤ 0); gain margin ``GM = 1/|L(jω_pc)|`` (a ratio, not dB); of several,
  the one nearest 1 in log scale (``min |log GM|``); ``inf`` (frequency NaN) if there is none;
* gain crossover frequencies ``ω_gc > 0``: ``|L| = 1``; phase margin
  ``PM = (∠L(jω_gc) mod 360°) − 180°``; of several, the smallest ``|PM|``; ``inf`` (NaN) if none;
* stability margin: the smallest local minimum of ``|1 + L(jω)|`` over ``ω > 0`` (an interior
  stationary point, python-control's definition: ``inf`` when ``|1 + L|`` has no such minimum,
  e.g. when it is monotonic);
* delay margin (not in python-control; MATLAB's ``allmargin`` definition, in seconds also in
  discrete time): the smallest extra loop delay ``τ`` that puts ``L(jω)e^{−jωτ}`` on −1 at a gain
  crossover: ``min over ω_gc of ((PM mod 360°)·π/180)/ω_gc``, ``inf`` without crossover.  It
  assumes the nominal closed loop is stable.

How (``jit``/``vmap``/``grad``-able; no polynomial root finding):

1. ``L`` is evaluated on a log-spaced grid of ``n_grid`` frequencies spanning three decades beyond
   the break frequencies of the poles and zeros (and past the frequency beyond which ``|L| ≠ 1``
   is guaranteed by ``‖A‖ + ‖B‖‖C‖/|1 − |D||``), plus nine points around each lightly or heavily
   damped complex pole and zero (``ω_d + σ·{0, ±0.3, ±0.75, ±1.5, ±3}``), so resonances are resolved;
2. sign changes of ``log|L|`` (gain crossovers), ``Im L/|L|`` (phase crossovers) and
   ``d|1 + L|²/d log ω`` (from − to +: local minima) on that grid bracket the crossings;
3. bisection in ``log ω`` to float64 resolution, then the implicit-function theorem gives the
   derivative of each crossing frequency with respect to the system's matrices
   (:mod:`jaxsim.lti._roots`), so the margins' gradients are exact first derivatives.

Limits: two crossings inside one grid cell (a ratio of about ``10^(decades/n_grid)``) or a crossing
that only touches ``|L| = 1`` / the real axis are not found (python-control's polynomial method
finds tangencies); margins of a loop with poles on the imaginary axis are found between them.
"""

from __future__ import annotations

from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_positive_int, is_concrete
from jaxsim.lti._resolvent import resolve, schur_factors
from jaxsim.lti._roots import bisect, implicit, sign_change_brackets
from jaxsim.lti.frequency import frequency_points
from jaxsim.lti.poles_zeros import zero_candidates
from jaxsim.lti.statespace import StateSpace, as_state_space

DEFAULT_N_GRID = 2000
RESIDUAL_TOL = 1e-6  # |f(root)| above this after bisection: a discontinuity (pole on the axis), not a root
_RESONANCE_OFFSETS = (-3.0, -1.5, -0.75, -0.3, 0.0, 0.3, 0.75, 1.5, 3.0)


class Margin(NamedTuple):
    """``margin``: gain margin (ratio), phase margin (deg), the phase crossover frequency of the gain
    margin ``wcg`` and the gain crossover frequency of the phase margin ``wcp`` (rad/s) —
    python-control's four values, in its order — and the delay margin ``dm`` (s)."""

    gm: jax.Array
    pm: jax.Array
    wcg: jax.Array
    wcp: jax.Array
    dm: jax.Array


class StabilityMargins(NamedTuple):
    """``stability_margins``: python-control's ``gm, pm, sm, wpc, wgc, wms`` (ratio, deg, distance
    to −1, and the frequencies in rad/s where each is attained)."""

    gm: jax.Array
    pm: jax.Array
    sm: jax.Array
    wpc: jax.Array
    wgc: jax.Array
    wms: jax.Array


class AllMargins(NamedTuple):
    """Every crossing found (``returnall=True``), fixed length ``k`` with NaN in unused slots when
    traced; concrete input drops them (python-control's variable-length arrays)."""

    gm: jax.Array
    pm: jax.Array
    sm: jax.Array
    wpc: jax.Array
    wgc: jax.Array
    wms: jax.Array
    dm: jax.Array


# --- the loop and its grid ----------------------------------------------------------------------


def _siso(sys: Any) -> StateSpace:
    s = as_state_space(sys)
    if not s.is_siso():
        raise ValueError(
            f"sys: margins need a SISO loop transfer function, got {s.n_outputs} outputs and {s.n_inputs} inputs"
        )
    return s


def _continuous_roots(s: StateSpace, poles: jax.Array) -> jax.Array:
    """Poles and finite zeros as ``s``-plane points (``ln z/dt`` in discrete time); NaN for none."""
    if s.n_states:
        _, w, keep, _, _ = zero_candidates(s)
        z = jnp.where(keep, w, jnp.nan)
    else:
        z = jnp.zeros((0,), poles.dtype)
    r = jnp.concatenate([poles, z.astype(poles.dtype)])
    r = jnp.where(jnp.isfinite(r), r, jnp.nan)
    if s.dt is not None:
        r = jnp.where(jnp.abs(r) > 0, jnp.log(jnp.where(jnp.abs(r) > 0, r, 1.0)) / s.dt, jnp.nan)
    return jax.lax.stop_gradient(r)


def _asymptotic_crossing(w1: jax.Array, g1: jax.Array, g2: jax.Array, ratio: float) -> jax.Array:
    """Where ``|L| = 1`` along the power law through ``|L(w1)| = g1`` and ``|L(ratio·w1)| = g2``, if that
    law reaches 1 beyond ``w1`` in the direction of ``ratio`` (else NaN)."""
    slope = (jnp.log(g2) - jnp.log(g1)) / jnp.log(ratio)  # d log|L| / d log ω
    w_star = w1 * g1 ** (-1.0 / jnp.where(slope == 0, 1.0, slope))
    beyond = (w_star - w1) * (ratio - 1.0) > 0
    ok = jnp.isfinite(w_star) & (jnp.abs(slope) > 0.5) & beyond
    return jnp.where(ok, w_star, jnp.nan)


def _grid(s: StateSpace, poles: jax.Array, factors, n_grid: int) -> jax.Array:
    """Sorted log-frequencies ``ln ω`` bracketing every crossing (see the module docstring)."""
    r = _continuous_roots(s, poles)
    mag = jnp.abs(r)
    feature = jnp.isfinite(mag) & (mag > 1e-300)
    lo_f = jnp.min(jnp.where(feature, mag, jnp.inf))
    hi_f = jnp.max(jnp.where(feature, mag, -jnp.inf))
    has_f = jnp.isfinite(lo_f)
    lo = jnp.where(has_f, lo_f, 1.0) * 1e-3
    hi = jnp.where(has_f, hi_f, 1.0) * 1e3
    if s.dt is not None:  # the whole band up to the Nyquist frequency
        hi = jnp.asarray(np.pi / s.dt * (1.0 - 1e-9), s.a.dtype)
        lo = jnp.minimum(lo, hi * 1e-6)
    # beyond the break frequencies |L| follows a power law: extend the grid to where it crosses 1
    probe = jnp.stack([lo, lo / 10.0, hi, hi * 10.0])
    g = jnp.abs(_loop_and_slope(s, factors, probe, False)[0])
    lo = jnp.fmin(lo, _asymptotic_crossing(lo, g[0], g[1], 0.1) / 30.0)
    if s.dt is None:
        hi = jnp.fmax(hi, _asymptotic_crossing(hi, g[2], g[3], 10.0) * 30.0)
    base = jnp.linspace(jnp.log(lo), jnp.log(hi), n_grid)
    # points around complex poles and zeros: ω_d + |σ|·offsets
    wd, sig = jnp.abs(r.imag), jnp.abs(r.real)
    extra = wd[:, None] + sig[:, None] * jnp.asarray(_RESONANCE_OFFSETS)[None, :]
    ok = (wd[:, None] > 0) & (extra > lo) & (extra < hi) & jnp.isfinite(extra)
    extra = jnp.log(jnp.where(ok, extra, lo)).ravel()
    return jnp.sort(jnp.concatenate([base, extra]))


# --- the crossing functions of v = ln ω: one evaluation for all kinds -----------------------------

_GAIN, _PHASE, _SLOPE = 0, 1, 2


def _loop_and_slope(s: StateSpace, factors, w: jax.Array, slope: bool) -> tuple[jax.Array, jax.Array]:
    """``L`` and ``dL/d ln ω`` at the frequencies ``w`` (``(K,)``); the derivative only if ``slope``."""
    x = frequency_points(s, w)
    cdtype = x.dtype
    res = resolve(s.a, jnp.broadcast_to(s.b.astype(cdtype), x.shape + s.b.shape), x, factors)
    c = s.c.astype(cdtype)
    loop = jnp.einsum("ij,njk->nik", c, res)[:, 0, 0] + s.d[0, 0]
    if not slope:
        return loop, jnp.zeros_like(loop)
    dloop_dx = -jnp.einsum("ij,njk->nik", c, resolve(s.a, res, x, factors))[:, 0, 0]
    dx_dv = x if s.dt is None else 1j * w * s.dt * x  # x = jω or e^{jω·dt}, ω = e^v
    return loop, dloop_dx * dx_dv


def _safe_loop(s: StateSpace, s0: StateSpace, factors, w: jax.Array) -> jax.Array:
    """``L`` at ``w`` with derivatives, where a point on a pole (``L`` infinite, e.g. ``ω = 0`` with an
    integrator) keeps its primal inf/NaN but is differentiated at a harmless frequency instead: an
    infinite resolvent would turn the zero cotangent of that entry into NaN for all the others."""
    l0 = _loop_and_slope(s0, factors, w, False)[0]
    finite = jnp.isfinite(l0)
    w_safe = jnp.where(finite, w, w[jnp.argmax(finite)])
    return jnp.where(finite, _loop_and_slope(s, factors, w_safe, False)[0], l0)


def _kind_values(kind: np.ndarray, loop: jax.Array, dloop: jax.Array) -> jax.Array:
    """Per slot: ``log|L|`` (gain crossover), ``Im L/|L|`` (phase crossover) or
    ``d|1 + L|²/d ln ω`` (stationary points of the distance to −1)."""
    mag = jnp.abs(loop)
    values = [jnp.log(mag), loop.imag / mag, 2.0 * jnp.real(jnp.conj(1.0 + loop) * dloop)]
    return jnp.select([kind == _GAIN, kind == _PHASE], values[:2], values[2])


def _crossings(s: StateSpace, n_grid: int, k: int, epsw: float, with_sm: bool):
    """Crossing frequencies (``(K,)`` each kind, ``K = k``) with validity, and ``L`` there; the
    phase crossovers get a leading slot for ``ω = 0``."""
    s0 = jax.tree_util.tree_map(jax.lax.stop_gradient, s)
    if s.n_states:
        factors = schur_factors(s.a)
        poles = jnp.diagonal(factors[0])
    else:
        factors, poles = None, jnp.zeros((0,), jnp.result_type(s.a, jnp.complex64))
    grid = _grid(s0, jax.lax.stop_gradient(poles), factors, n_grid)
    kinds = (_GAIN, _PHASE, _SLOPE) if with_sm else (_GAIN, _PHASE)
    kind = np.repeat(np.asarray(kinds), k)

    def f(v, sys):
        loop, dloop = _loop_and_slope(sys, factors, jnp.exp(v), with_sm)
        return _kind_values(kind, loop, dloop)

    loop_g, dloop_g = _loop_and_slope(s0, factors, jnp.exp(grid), with_sm)
    lo, ok = [], []
    for kd in kinds:
        values = _kind_values(np.full(grid.shape, kd), loop_g, dloop_g)
        idx, valid = sign_change_brackets(jax.lax.stop_gradient(values), k, rising_only=kd == _SLOPE)
        lo.append(idx)
        ok.append(valid)
    idx, valid = jnp.concatenate(lo), jnp.concatenate(ok)
    v, residual = bisect(f, s, grid[idx], grid[idx + 1])
    # a sign change across a pole on the axis is a jump, not a root (log|L| and sin ∠L are scale-free;
    # the slope kind only brackets − → + changes, which poles do not produce)
    valid = valid & ((kind == _SLOPE) | (jnp.abs(residual) <= RESIDUAL_TOL))
    v = implicit(f, s, v, valid)
    w = jnp.exp(v)
    # ω = 0 is a phase crossover when the DC gain is finite and ≤ 0 (python-control's root at 0);
    # in discrete time ω = 0 and the Nyquist frequency are stationary points of |1 + L| (L(e^{jθ}) is
    # conjugate-symmetric about both), so they are minima of it when |1 + L| rises away from them
    nyquist = np.pi / s.dt if s.dt is not None else 0.0
    w_all = jnp.concatenate([w, jnp.asarray([0.0, nyquist], w.dtype)])
    loop = _safe_loop(s, s0, factors, w_all)
    loop_w, dc, l_nyq = loop[:-2], loop[-2], loop[-1]
    dc0 = jax.lax.stop_gradient(dc)
    ok0 = jnp.isfinite(dc0.real) & (dc0.real <= 0) & (epsw <= 0.0)
    sl = [slice(i * k, (i + 1) * k) for i in range(len(kinds))]
    w_pc = jnp.concatenate([jnp.zeros((1,), w.dtype), w[sl[_PHASE]]])
    l_pc = jnp.concatenate([dc[None], loop_w[sl[_PHASE]]])
    ok_pc = jnp.concatenate([ok0[None], valid[sl[_PHASE]]])
    ok_pc = ok_pc & (jax.lax.stop_gradient(l_pc.real) <= 0) & (w_pc >= epsw)
    gc = (w[sl[_GAIN]], loop_w[sl[_GAIN]], valid[sl[_GAIN]] & (w[sl[_GAIN]] > epsw))
    ms = None
    if with_sm:
        w_ms, l_ms, ok_ms = w[sl[_SLOPE]], loop_w[sl[_SLOPE]], valid[sl[_SLOPE]] & (w[sl[_SLOPE]] > epsw)
        if s.dt is not None:
            slope_g = _kind_values(np.full(grid.shape, _SLOPE), loop_g, dloop_g)
            w_ms = jnp.concatenate([w_ms, jnp.asarray([0.0, nyquist], w.dtype)])
            l_ms = jnp.concatenate([l_ms, dc[None], l_nyq[None]])
            ok_ms = jnp.concatenate([ok_ms, ((slope_g[0] > 0) & (epsw <= 0.0))[None], (slope_g[-1] < 0)[None]])
        ms = (w_ms, l_ms, ok_ms)
    return (w_pc, l_pc, ok_pc), gc, ms


def _pick(score: jax.Array, ok: jax.Array, values: tuple[jax.Array, ...], missing: tuple[float, ...]):
    """The entries of ``values`` at the valid slot of least ``score`` (first one on ties)."""
    score = jnp.where(ok, jax.lax.stop_gradient(score), jnp.inf)
    i = jnp.argmin(score)
    any_ok = jnp.any(ok & jnp.isfinite(score))
    return tuple(jnp.where(any_ok, v[i], m) for v, m in zip(values, missing))


@partial(jax.jit, static_argnums=(1, 2, 3, 4))
def _all(s: StateSpace, n_grid: int, k: int, epsw: float, with_sm: bool):
    (w_pc, l_pc, ok_pc), (w_gc, l_gc, ok_gc), ms = _crossings(s, n_grid, k, epsw, with_sm)
    gm = 1.0 / jnp.abs(l_pc)
    pm = jnp.mod(jnp.degrees(jnp.angle(l_gc)), 360.0) - 180.0
    dm = jnp.radians(jnp.mod(pm, 360.0)) / w_gc
    sm = None if ms is None else (jnp.abs(1.0 + ms[1]), ms[0], ms[2])
    return (gm, w_pc, ok_pc), (pm, w_gc, ok_gc, dm), sm


def _options(s: StateSpace, n_grid: int | None, max_crossings: int | None, epsw: float) -> tuple[int, int, float]:
    n_grid = DEFAULT_N_GRID if n_grid is None else check_positive_int("n_grid", n_grid)
    k = 2 * s.n_states + 2 if max_crossings is None else check_positive_int("max_crossings", max_crossings)
    epsw = float(epsw)
    if not np.isfinite(epsw) or epsw < 0:
        raise ValueError(f"epsw: must be a non-negative frequency in rad/s, got {epsw!r}")
    return n_grid, k, epsw


def stability_margins(
    sys: Any, returnall: bool = False, epsw: float = 0.0, *, n_grid: int | None = None, max_crossings: int | None = None
) -> StabilityMargins | AllMargins:
    """python-control's ``stability_margins(sys, returnall=False, epsw=0.0)`` (definitions in the
    module docstring).

    Args:
        sys: SISO loop transfer function ``L`` (continuous or discrete LTI system).
        returnall: every crossing (:class:`AllMargins`, with the delay margin per gain crossover)
            instead of the critical one.
        epsw: frequencies below this (rad/s) are treated as static gain and ignored.
        n_grid: bracketing grid size (default :data:`DEFAULT_N_GRID`).
        max_crossings: most crossings of each kind kept (default ``2n + 2``, enough for an
            ``n``-state SISO loop).

    Returns:
        :class:`StabilityMargins` (scalars), or :class:`AllMargins`.

    Raises:
        ValueError: naming ``sys`` (not SISO, not LTI), ``epsw``, ``n_grid``, ``max_crossings``.
    """
    s = _siso(sys)
    (gm, w_pc, ok_pc), (pm, w_gc, ok_gc, dm), (sm, w_ms, ok_ms) = _all(
        s, *_options(s, n_grid, max_crossings, epsw), True
    )
    if returnall:
        out = AllMargins(gm, pm, sm, w_pc, w_gc, w_ms, dm)
        oks = (ok_pc, ok_gc, ok_ms, ok_pc, ok_gc, ok_ms, ok_gc)
        if is_concrete(out):
            return AllMargins(*(np.asarray(v)[np.asarray(o)] for v, o in zip(out, oks)))
        return AllMargins(*(jnp.where(o, v, jnp.nan) for v, o in zip(out, oks)))
    inf, nan = float("inf"), float("nan")
    gm_sel, w_pc_sel = _pick(jnp.abs(jnp.log(gm)), ok_pc & jnp.isfinite(gm), (gm, w_pc), (inf, nan))
    pm_sel, w_gc_sel = _pick(jnp.abs(pm), ok_gc, (pm, w_gc), (inf, nan))
    sm_sel, w_ms_sel = _pick(sm, ok_ms, (sm, w_ms), (inf, nan))
    return StabilityMargins(gm_sel, pm_sel, sm_sel, w_pc_sel, w_gc_sel, w_ms_sel)


def margin(sys: Any, *, n_grid: int | None = None, max_crossings: int | None = None) -> Margin:
    """python-control's ``margin(sys)`` — ``gm, pm, wcg, wcp`` — plus the delay margin ``dm`` (s).

    ``gm, pm, wcg, wcp, dm = margin(L)``; ``jaxsim.lti.compat.margin`` returns exactly
    python-control's four values.  ``jit``/``vmap``/``grad``-able (see the module docstring)."""
    s = _siso(sys)
    (gm, w_pc, ok_pc), (pm, w_gc, ok_gc, dm), _ = _all(s, *_options(s, n_grid, max_crossings, 0.0), False)
    inf, nan = float("inf"), float("nan")
    gm_sel, w_pc_sel = _pick(jnp.abs(jnp.log(gm)), ok_pc & jnp.isfinite(gm), (gm, w_pc), (inf, nan))
    pm_sel, w_gc_sel = _pick(jnp.abs(pm), ok_gc, (pm, w_gc), (inf, nan))
    (dm_sel,) = _pick(dm, ok_gc, (dm,), (inf,))
    return Margin(gm_sel, pm_sel, w_pc_sel, w_gc_sel, dm_sel)


def delay_margin(sys: Any, *, n_grid: int | None = None, max_crossings: int | None = None) -> jax.Array:
    """The delay margin alone (s), see the module docstring."""
    return margin(sys, n_grid=n_grid, max_crossings=max_crossings).dm
