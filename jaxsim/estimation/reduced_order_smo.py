"""Reduced-order sliding-mode observer for fault identification (seed 000, paper 2, §2–3).

The observer runs on the paper's *transformed reduced model* (2.2): a model of order ``k`` that is
insensitive to the disturbances, in canonical coordinates ``z = (z1, z2)`` with ``z1 = y*`` the
(scalar) reduced output and ``z2 ∈ R^{k−1}``::

    ż1 = F1 z1 + F2·z2 + r1(t, y, u, z2) + D1 d
    ż2 = F3 z1 + F4 z2 + r2(t, y, u, z2) + D2 d

``r1, r2`` collect the known terms (``Ḡu + J̄y + C̄Ψ + ᾱ``; ``Ψ`` may depend on the unmeasured
``z2``), ``d`` is the scalar fault and ``F4`` is Hurwitz (the paper's choice of ``Q``).  The
observer (3.1) is::

    dẑ1/dt = F1 y* + F2·ẑ2 + r1(t, y, u, ẑ2) + k2 e1 + k3 v
    dẑ2/dt = F3 y* + F4 ẑ2 + r2(t, y, u, ẑ2) + K1 v,      e1 = y* − ẑ1,  v = sign(e1)

with ``K1 = P⁻¹ F2ᵀ k1`` and ``F4ᵀP + P F4 = −W``.  In the sliding mode ``e1 = ė1 = 0`` and
``v`` equals its *equivalent* value ``v_eq``; the fault estimate is (3.4)–(3.5)::

    d̂ = D2⁺ K1 v_eq   (D1 = 0),      d̂ = k3 D1⁺ v_eq   (otherwise),      D⁺ = (DᵀD)⁻¹Dᵀ

Two discretisations, both stepping from ``t_k`` to ``t_{k+1}`` with the input ``u_k`` held and
the measurement ``y_{k+1}`` taken at the end of the step:

* ``scheme="implicit_sign"`` — **exact switching**.  Backward Euler on the linear part and on the
  set-valued ``v ∈ Sign(e1)`` (the known terms explicit).  ``e1`` at the new time is affine in
  ``v`` (``e1⁺ = w − g v``, ``g > 0``), so the inclusion has the closed-form solution
  ``v = clip(w/g, −1, 1)``: either the surface is reached within the step (``|v| < 1``, ``e1⁺ = 0``
  and ``v`` *is* the equivalent injection, no ``ε`` needed) or ``v = ±1`` exactly.  No chattering,
  stable for any step; it converges to the Filippov solution as ``dt → 0``.  This is the reference.
* ``scheme="smooth"`` — ``v = switch(e1, width)`` with a smooth switching function from
  :mod:`jaxsim.core.switching` (default the paper's ``e1/(|e1| + ε)``, eq. 3.6), integrated by
  ``solver`` (default the linearly implicit :class:`~jaxsim.core.integrators.SemiImplicitEuler`).
  Inside the boundary layer the gain ``k3`` acts as ``k3/width`` — with the paper's gains an
  eigenvalue near ``−k3/ε`` (``−10⁷ s⁻¹`` for ``ε = 10⁻³``) that explicit methods cannot step over;
  the linearly implicit step is A-stable.  Differentiable in the gains: the path for tuning.

Optionally ``v_eq`` is a first-order low-pass of ``v`` (time constant ``filter_tau``, s; ``0``
means ``v_eq = v``), the classical way to extract the equivalent injection under noise.

**Existence of the sliding mode** (:func:`sliding_existence`) [ours; the paper's gain conditions
are garbled in the source].  Bounds ``‖C̄1ΔΨ‖ ≤ N1‖e2‖ + M1``, ``‖C̄2ΔΨ + Δα‖ ≤ N2‖e2‖ + M2``
(3.3) and ``|d| ≤ β``.  On the surface ``e1 = 0`` the error obeys
``ė2 = (F4 − ρP⁻¹F2ᵀF2) e2 + …`` with ``ρ = k1/k3``; ``V = e2ᵀPe2`` gives the ultimate bound
``δ = √κ(P) · 2(‖P‖M2 + ‖PD2‖β + ρ‖F2‖(M1 + |D1|β)) / λ'`` with
``λ' = λmin(W + 2ρF2ᵀF2) − 2‖P‖N2 − 2ρ‖F2‖N1`` (must be > 0; for ``ρ = 0`` this is the paper's
theorem condition ``λmin(W) ≥ 2‖P‖N2``), and the surface exists (``|v_eq| < 1``) iff
``k3 > (‖F2‖ + N1) δ + M1 + |D1| β``.  Gains failing it raise ``ValueError``.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.integrators import SemiImplicitEuler, Solver
from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.reduced_model import KnownTerms, ReducedModel, SlidingBounds  # noqa: F401  (re-exported)
from jaxsim.core.switching import SWITCHES, get_switch
from jaxsim.core.validation import check_finite, check_positive, check_shape, check_square, is_concrete

SCHEMES = ("implicit_sign", "smooth")


@pytree_dataclass
class SMOGains:
    """The paper's ``k1`` (injection into ``ẑ2``), ``k2`` (linear output injection), ``k3`` (switching gain)."""

    k1: Any = 1e7
    k2: Any = 1.0
    k3: Any = 1e4


@pytree_dataclass
class SMOParams:
    """Everything :func:`smo_step` needs; build it with :func:`reduced_order_smo`."""

    model: ReducedModel
    gains: SMOGains
    P: Any  # (m, m) Lyapunov matrix
    width: Any = 1e-3  # boundary layer of the smooth switch, unit of y*
    filter_tau: Any = 0.0  # s, low-pass on v giving v_eq (0: none)
    switch: str = static_field(default="ratio")
    scheme: str = static_field(default="implicit_sign")
    solver: Solver = static_field(default=SemiImplicitEuler())


class SMOState(NamedTuple):
    z: jax.Array  # (k,) estimate (ẑ1, ẑ2)
    v: jax.Array  # () injection applied over the last step
    v_eq: jax.Array  # () equivalent injection (filtered v)
    y: jax.Array  # (p,) last measurement


class SlidingMargins(NamedTuple):
    delta: float  # ultimate bound of ‖e2‖ on the sliding surface
    k3_min: float  # k3 must exceed this
    decay: float  # λ' > 0: decay rate margin of the e2 Lyapunov function


class SMORun(NamedTuple):
    """Observer outputs at every sample (leading axis ``N``): ``z`` (N, k), ``e1``, ``v``, ``v_eq``, ``d_hat`` (N,)."""

    z: jax.Array
    e1: jax.Array
    v: jax.Array
    v_eq: jax.Array
    d_hat: jax.Array


def lyapunov_P(F4: jax.Array, W: jax.Array) -> jax.Array:
    """Solve ``F4ᵀP + P F4 = −W`` for ``P`` (Kronecker form; ``F4`` is small)."""
    m = F4.shape[0]
    eye = jnp.eye(m, dtype=F4.dtype)
    lhs = jnp.kron(eye, F4.T) + jnp.kron(F4.T, eye)
    p = jnp.linalg.solve(lhs, -W.reshape(-1, order="F")).reshape(m, m, order="F")
    return 0.5 * (p + p.T)


def injection_gain(params: SMOParams) -> jax.Array:
    """``K1 = P⁻¹ F2ᵀ k1`` (shape ``(m,)``)."""
    return jnp.linalg.solve(params.P, params.model.F2) * params.gains.k1


def _blocks(model: ReducedModel) -> tuple[jax.Array, ...]:
    f = lambda a: jnp.asarray(a, dtype=float)  # noqa: E731
    return f(model.F1), f(model.F2), f(model.F3), f(model.F4), f(model.D1), f(model.D2)


def validate_model(model: ReducedModel) -> None:
    F1, F2, F3, F4, D1, D2 = _blocks(model)
    check_square("F4", F4)
    m = F4.shape[0]
    check_shape("F1", F1, ())
    check_shape("F2", F2, (m,))
    check_shape("F3", F3, (m,))
    check_shape("D1", D1, ())
    check_shape("D2", D2, (m,))
    for name, arr in zip(("F1", "F2", "F3", "F4", "D1", "D2"), (F1, F2, F3, F4, D1, D2)):
        check_finite(name, arr)
    if is_concrete(F4) and np.max(np.linalg.eigvals(np.asarray(F4)).real) >= 0:
        raise ValueError(
            f"F4: must be Hurwitz (choose Q so that F4 + Q F2 is stable), "
            f"eigenvalues {np.linalg.eigvals(np.asarray(F4))}"
        )
    if is_concrete(D1) and is_concrete(D2) and float(D1) == 0.0 and not np.any(np.asarray(D2)):
        raise ValueError("D1, D2: the fault does not enter the reduced model (both zero)")


def sliding_existence(model: ReducedModel, gains: SMOGains, P: Any, W: Any, bounds: SlidingBounds) -> SlidingMargins:
    """Check that the sliding surface ``e1 = 0`` exists for these gains (see module docstring).

    Returns the margins; raises ``ValueError`` naming the gain when the surface is unreachable.
    """
    _, F2, _, _, D1, D2 = (np.asarray(b) for b in _blocks(model))
    P, W = np.asarray(P, float), np.asarray(W, float)
    k1, k3 = float(gains.k1), float(gains.k3)
    b = {f: float(getattr(bounds, f)) for f in ("N1", "M1", "N2", "M2", "beta")}
    if any(v < 0 for v in b.values()):
        raise ValueError(f"bounds: must be non-negative, got {b}")
    rho = k1 / k3
    nP, nF2 = np.linalg.norm(P, 2), np.linalg.norm(F2)
    lam = np.linalg.eigvalsh(W + 2 * rho * np.outer(F2, F2)).min()
    decay = lam - 2 * nP * b["N2"] - 2 * rho * nF2 * b["N1"]
    if decay <= 0:
        raise ValueError(
            f"k1: the sliding motion is not stable for these bounds: λmin(W + 2(k1/k3)F2ᵀF2) = {lam:.4g} "
            f"≤ 2‖P‖N2 + 2(k1/k3)‖F2‖N1 = {lam - decay:.4g} (paper's condition λmin(W) ≥ 2‖P‖N*2)"
        )
    eig = np.linalg.eigvalsh(P)
    r = 2 * (nP * b["M2"] + np.linalg.norm(P @ D2) * b["beta"] + rho * nF2 * (b["M1"] + abs(D1) * b["beta"])) / decay
    delta = float(r * np.sqrt(eig.max() / eig.min()))
    k3_min = float((nF2 + b["N1"]) * delta + b["M1"] + abs(D1) * b["beta"])
    if not k3 > k3_min:
        raise ValueError(
            f"k3: the sliding surface e1 = 0 is unreachable: k3 = {k3:.4g} must exceed "
            f"(‖F2‖ + N1)·δ + M1 + |D1|·β = {k3_min:.4g}, where δ = {delta:.4g} bounds ‖e2‖ on the surface "
            f"(raise k3 or k1/k3)"
        )
    return SlidingMargins(delta=delta, k3_min=k3_min, decay=float(decay))


def reduced_order_smo(
    model: ReducedModel,
    gains: SMOGains | None = None,
    *,
    W: Any = None,
    bounds: SlidingBounds | None = None,
    width: float = 1e-3,
    filter_tau: float = 0.0,
    switch: str = "ratio",
    scheme: str = "implicit_sign",
    solver: Solver = SemiImplicitEuler(),  # noqa: B008  (an immutable default)
) -> SMOParams:
    """Validated observer parameters.

    ``W`` (m, m) defaults to ``2·I`` (the paper's ``W = 2`` for ``P = 1``); ``P`` solves the
    Lyapunov equation.  With ``bounds`` the sliding-existence condition is checked
    (:func:`sliding_existence`).  ``width``: boundary layer of ``switch`` (``scheme="smooth"``);
    ``filter_tau``: low-pass time constant on the equivalent injection (s).
    """
    gains = SMOGains() if gains is None else gains
    validate_model(model)
    for name in ("k1", "k2", "k3"):
        check_positive(name, getattr(gains, name))
    check_positive("width", width)
    check_positive("filter_tau", filter_tau, allow_zero=True)
    if scheme not in SCHEMES:
        raise ValueError(f"scheme: must be one of {SCHEMES}, got {scheme!r}")
    get_switch(switch)
    F4 = jnp.asarray(model.F4, float)
    W = 2.0 * jnp.eye(F4.shape[0]) if W is None else jnp.asarray(W, float)
    check_shape("W", W, F4.shape)
    if is_concrete(W) and (not np.allclose(W, W.T) or np.linalg.eigvalsh(np.asarray(W)).min() <= 0):
        raise ValueError(f"W: must be symmetric positive definite, got {np.asarray(W)!r}")
    P = lyapunov_P(F4, W)
    if bounds is not None and is_concrete((gains, bounds)):
        sliding_existence(model, gains, P, W, bounds)
    return SMOParams(
        model=model,
        gains=gains,
        P=P,
        width=jnp.asarray(width, float),
        filter_tau=jnp.asarray(filter_tau, float),
        switch=switch,
        scheme=scheme,
        solver=solver,
    )


def smo_init(params: SMOParams, y0: jax.Array, z2_0: jax.Array | None = None) -> SMOState:
    """Start at ``ẑ1 = y*(y0)`` and ``ẑ2 = z2_0`` (default zeros)."""
    m = jnp.shape(params.model.F2)[0]
    ystar = params.model.reduced_output(params.model.params, y0)
    z2 = jnp.zeros(m, dtype=jnp.result_type(ystar, float)) if z2_0 is None else jnp.asarray(z2_0)
    zero = jnp.zeros((), dtype=z2.dtype)
    return SMOState(z=jnp.concatenate([jnp.reshape(ystar, (1,)), z2]), v=zero, v_eq=zero, y=jnp.asarray(y0))


def _step_implicit_sign(
    p: SMOParams, z: jax.Array, y_prev: jax.Array, t: jax.Array, y: jax.Array, u: jax.Array, dt: jax.Array
) -> tuple[jax.Array, jax.Array]:
    mdl, g = p.model, p.gains
    F1, F2, F3, F4, _, _ = _blocks(mdl)
    ystar = mdl.reduced_output(mdl.params, y)
    z1, z2 = z[0], z[1:]
    r1, r2 = mdl.known(mdl.params, t, y, u, z2)
    lhs = jnp.eye(F4.shape[0], dtype=z.dtype) - dt * F4
    z2_free = jnp.linalg.solve(lhs, z2 + dt * (F3 * ystar + r2))
    z2_per_v = jnp.linalg.solve(lhs, dt * injection_gain(p))
    denom = 1.0 + dt * g.k2
    z1_free = (z1 + dt * (F1 * ystar + F2 @ z2_free + r1 + g.k2 * ystar)) / denom
    z1_per_v = dt * (g.k3 + F2 @ z2_per_v) / denom
    v = jnp.clip((ystar - z1_free) / z1_per_v, -1.0, 1.0)
    z_new = jnp.concatenate([jnp.reshape(z1_free + z1_per_v * v, (1,)), z2_free + z2_per_v * v])
    return z_new, v


def _step_smooth(
    p: SMOParams, z: jax.Array, y_prev: jax.Array, t: jax.Array, y: jax.Array, u: jax.Array, dt: jax.Array
) -> tuple[jax.Array, jax.Array]:
    """One ``solver`` step in output-error coordinates ``ζ = ẑ − (ℓ(t), 0)``.

    ``ℓ`` interpolates ``y*`` linearly across the step (and the other outputs likewise), so the
    switching argument at the step start is the previous, near-zero error rather than the new
    measurement's jump — a linearly implicit step then linearises the switch where it is used.
    """
    mdl, g = p.model, p.gains
    F1, F2, F3, F4, _, _ = _blocks(mdl)
    t0 = t - dt
    dy = y - y_prev
    ys0 = mdl.reduced_output(mdl.params, y_prev)
    dys = mdl.reduced_output(mdl.params, y) - ys0
    k1_vec = injection_gain(p)

    def field(tt: jax.Array, zeta: jax.Array) -> jax.Array:
        frac = (tt - t0) / dt
        yy, ystar = y_prev + frac * dy, ys0 + frac * dys
        e1 = -zeta[0]
        z2 = zeta[1:]
        v = SWITCHES[p.switch](e1, p.width)
        r1, r2 = mdl.known(mdl.params, tt, yy, u, z2)
        dz1 = F1 * ystar + F2 @ z2 + r1 + g.k2 * e1 + g.k3 * v - dys / dt
        dz2 = F3 * ystar + F4 @ z2 + r2 + k1_vec * v
        return jnp.concatenate([jnp.reshape(dz1, (1,)), dz2])

    zeta = z.at[0].add(-ys0)
    zeta_new = p.solver.step(field, t0, zeta, dt)
    z_new = zeta_new.at[0].add(ys0 + dys)
    return z_new, SWITCHES[p.switch](-zeta_new[0], p.width)


def smo_step(
    params: SMOParams, state: SMOState, t_next: jax.Array, y_next: jax.Array, u: jax.Array, dt: jax.Array
) -> SMOState:
    """Advance from ``t_next − dt`` to ``t_next`` with input ``u`` held and measurement ``y_next``."""
    step = _step_implicit_sign if params.scheme == "implicit_sign" else _step_smooth
    z, v = step(params, state.z, state.y, t_next, y_next, u, dt)
    tau = params.filter_tau
    v_eq = (tau * state.v_eq + dt * v) / (tau + dt)
    return SMOState(z=z, v=v, v_eq=v_eq, y=y_next)


def fault_estimate(params: SMOParams, v_eq: jax.Array) -> jax.Array:
    """``d̂`` from the equivalent injection: ``D2⁺K1 v_eq`` if ``D1 = 0``, else ``k3 D1⁺ v_eq``."""
    _, _, _, _, D1, D2 = _blocks(params.model)
    from_z2 = (D2 @ injection_gain(params)) / (D2 @ D2) * v_eq
    from_z1 = params.gains.k3 * v_eq / jnp.where(D1 == 0, 1.0, D1)
    return jnp.where(D1 == 0, from_z2, from_z1)


def smo_filter(params: SMOParams, ts: jax.Array, ys: jax.Array, us: jax.Array, z2_0: jax.Array | None = None) -> SMORun:
    """Run the observer over samples ``ts`` (N,), ``ys`` (N, p), ``us`` (N, m).

    ``us[k]`` is the input held over ``[ts[k], ts[k+1])`` (so ``us[-1]`` is unused); row ``k`` of the
    result is the estimate at ``ts[k]`` (row 0: the initial state, ``v = 0``).
    """
    ts = jnp.asarray(ts)
    if ts.ndim != 1 or ts.shape[0] < 2:
        raise ValueError(f"ts: expected shape (N,) with N ≥ 2, got {tuple(ts.shape)}")
    if jnp.shape(ys)[0] != ts.shape[0] or jnp.shape(us)[0] != ts.shape[0]:
        raise ValueError(f"ys, us: need {ts.shape[0]} rows like ts, got {jnp.shape(ys)[0]} and {jnp.shape(us)[0]}")
    s0 = smo_init(params, ys[0], z2_0)

    def body(s: SMOState, k: tuple) -> tuple[SMOState, SMOState]:
        t_prev, t, y, u = k
        s = smo_step(params, s, t, y, u, t - t_prev)
        return s, s

    _, hist = jax.lax.scan(body, s0, (ts[:-1], ts[1:], ys[1:], us[:-1]))
    z = jnp.concatenate([s0.z[None], hist.z])
    v = jnp.concatenate([s0.v[None], hist.v])
    v_eq = jnp.concatenate([s0.v_eq[None], hist.v_eq])
    ystar = jax.vmap(lambda y: params.model.reduced_output(params.model.params, y))(ys)
    return SMORun(z=z, e1=ystar - z[:, 0], v=v, v_eq=v_eq, d_hat=fault_estimate(params, v_eq))
