"""Interacting multiple model (IMM) estimator with linear, EKF or UKF members.

``transition[i, j] = P(mode_{t+1} = j | mode_t = i)`` (rows sum to one; FilterPy's ``M``).  One cycle:

* :func:`imm_predict` — mixing ``c̄_j = Σᵢ Πᵢⱼ μᵢ``, ``ωᵢⱼ = Πᵢⱼ μᵢ / c̄_j``; every member starts
  from its mixed belief ``m⁰ⱼ = Σᵢ ωᵢⱼ mᵢ``, ``P⁰ⱼ = Σᵢ ωᵢⱼ (Pᵢ + (mᵢ − m⁰ⱼ)(mᵢ − m⁰ⱼ)ᵀ)`` and
  predicts; the mode probabilities become the predicted ``c̄``;
* :func:`imm_update` — every member updates, ``μⱼ ∝ c̄ⱼ Λⱼ`` (``Λⱼ`` its innovation likelihood,
  combined in log space);
* :func:`imm_estimate` — the moment-matched mixture.

Members may have different functions (constant-velocity and coordinated-turn models, say); they
are unrolled over the (static) number of members, each a :class:`FilterMember`.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.validation import check_covariance, check_finite, check_probabilities, check_shape, check_square
from jaxsim.estimation import kalman
from jaxsim.estimation.ekf import ekf_predict, ekf_update
from jaxsim.estimation.lgssm import prepare_measurements
from jaxsim.estimation.nonlinear import NonlinearSSM, validate_nonlinear
from jaxsim.estimation.types import GaussianState, Innovation
from jaxsim.estimation.ukf import MerweScaledSigmaPoints, check_merwe, ukf_predict, ukf_update
from jaxsim.precision import to_common_float


@pytree_dataclass
class FilterMember:
    """One model of a bank: ``predict(params, state, u) -> state`` and
    ``update(params, state, y, mask) -> (state, Innovation)`` with its parameters; ``n_outputs`` the
    measurement dimension ``p`` it expects (``None``: unknown, not checked)."""

    params: Any
    predict: Callable[[Any, GaussianState, Any], GaussianState] = static_field()
    update: Callable[[Any, GaussianState, jax.Array, jax.Array], tuple[GaussianState, Innovation]] = static_field()
    n_outputs: int | None = static_field(default=None)


def _linear_predict(p, state, u):
    return kalman.predict(state, p["F"], p["Q"], p.get("B"), u)


def _linear_update(p, state, y, mask):
    return kalman.update(state, y, p["H"], p["R"], mask=mask)


def linear_member(F: Any, Q: Any, H: Any, R: Any, B: Any = None) -> FilterMember:
    """A Kalman-filter member with matrices ``F (n, n)``, ``Q``, ``H (p, n)``, ``R``, ``B (n, m)``
    (shapes, finiteness and PSD of ``Q, R`` checked on concrete values)."""
    params = {"F": jnp.asarray(F), "Q": jnp.asarray(Q), "H": jnp.asarray(H), "R": jnp.asarray(R)}
    check_square("F", params["F"])
    n = params["F"].shape[0]
    check_finite("F", params["F"])
    check_covariance("Q", params["Q"], n)
    check_shape("H", params["H"], (None, n))
    check_finite("H", params["H"])
    check_covariance("R", params["R"], params["H"].shape[0])
    if B is not None:
        params["B"] = jnp.asarray(B)
        check_shape("B", params["B"], (n, None))
        check_finite("B", params["B"])
    return FilterMember(params, _linear_predict, _linear_update, params["H"].shape[0])


def _ekf_predict(model, state, u):
    return ekf_predict(state, lambda x: model.f(x, u), model.Q)


def _ekf_update(model, state, y, mask):
    return ekf_update(state, y, model.h, model.R, mask=mask)


def ekf_member(model: NonlinearSSM) -> FilterMember:
    """An EKF member from a :class:`~jaxsim.estimation.nonlinear.NonlinearSSM` (its ``m0, P0`` unused)."""
    validate_nonlinear(model)
    return FilterMember(model, _ekf_predict, _ekf_update, model.n_outputs)


def _ukf_predict(p, state, u):
    model, scheme = p
    return ukf_predict(state, lambda x: model.f(x, u), model.Q, scheme)


def _ukf_update(p, state, y, mask):
    model, scheme = p
    return ukf_update(state, y, model.h, model.R, scheme, mask=mask)


def ukf_member(model: NonlinearSSM, alpha: float = 1.0, beta: float = 2.0, kappa: float = 0.0) -> FilterMember:
    """A UKF member (Merwe scaled sigma points; admissible ranges in :class:`MerweScaledSigmaPoints`)."""
    validate_nonlinear(model)
    scheme = MerweScaledSigmaPoints(alpha, beta, kappa)
    check_merwe(scheme, model.n_states)
    return FilterMember((model, scheme), _ukf_predict, _ukf_update, model.n_outputs)


@pytree_dataclass
class IMM:
    """Members (a tuple of :class:`FilterMember`) and the mode transition matrix ``(M, M)``."""

    members: tuple
    transition: jax.Array


class IMMState(NamedTuple):
    """Member beliefs ``means (M, n)``, ``covs (M, n, n)`` and mode probabilities ``probs (M,)``."""

    means: jax.Array
    covs: jax.Array
    probs: jax.Array


class IMMResult(NamedTuple):
    """Scanned IMM: combined ``means (T, n)``, ``covs (T, n, n)``, ``mode_probs (T, M)``, member
    ``member_means (T, M, n)``, ``member_covs (T, M, n, n)``, per-step and total log-likelihood."""

    means: jax.Array
    covs: jax.Array
    mode_probs: jax.Array
    member_means: jax.Array
    member_covs: jax.Array
    log_likelihoods: jax.Array
    log_likelihood: jax.Array


def imm(members: Any, transition: Any) -> IMM:
    """Build an :class:`IMM`; checks that ``transition`` is ``(M, M)`` row-stochastic and that the
    members agree on the measurement dimension."""
    members = tuple(members)
    k = len(members)
    if np.shape(transition) != (k, k):
        raise ValueError(f"transition: expected shape ({k}, {k}) for {k} members, got {tuple(np.shape(transition))}")
    check_probabilities("transition", transition)  # values only when concrete (NumPy, not staged in jit)
    declared = [getattr(mem, "n_outputs", None) for mem in members]
    if len({p for p in declared if p is not None}) > 1:
        raise ValueError(f"members: measurement dimensions differ, got {declared}")
    return IMM(members, jnp.asarray(transition))


def _output_dim(model: IMM) -> int | None:
    """The members' measurement dimension ``p`` (``None`` when no member declares it)."""
    return next((p for p in (getattr(mem, "n_outputs", None) for mem in model.members) if p is not None), None)


def _check_state(state: IMMState, n_members: int | None = None) -> None:
    """Shapes; finite means, PSD covariances and probabilities (non-negative, sum 1) when concrete."""
    means, covs, probs = state
    shapes = tuple(tuple(np.shape(a)) for a in state)
    if len(shapes[0]) != 2 or shapes[1] != shapes[0] + shapes[0][-1:] or shapes[2] != shapes[0][:1]:
        raise ValueError(f"means, covs, probs: expected shapes (M, n), (M, n, n), (M,), got "
                         f"{shapes[0]}, {shapes[1]}, {shapes[2]}")
    if n_members is not None and shapes[2] != (n_members,):
        raise ValueError(f"probs: expected shape ({n_members},) for {n_members} members, got {shapes[2]}")
    check_finite("means", means)
    check_covariance("covs", covs)
    check_probabilities("probs", probs)


def imm_init(means: Any, covs: Any, probs: Any) -> IMMState:
    """Initial state: ``means (M, n)``, ``covs (M, n, n)`` (PSD), ``probs (M,)`` (non-negative,
    summing to 1 to ``1e-10``; 16 ε in float32).  Checked on concrete values; under ``jit`` negative
    probabilities give NaN estimates and a wrong sum is silently renormalised by the first update."""
    state = IMMState(jnp.asarray(means), jnp.asarray(covs), jnp.asarray(probs))
    _check_state(state)
    return state


def _check_measurement(model: IMM, y: jax.Array) -> None:
    p = _output_dim(model)
    if p is not None and np.shape(y) != (p,):
        raise ValueError(f"y: expected {p} components per measurement (the members' output dimension), "
                         f"got shape {tuple(np.shape(y))}")


def _mix(state: IMMState, pi: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    cbar = state.probs @ pi
    omega = pi * state.probs[:, None] / cbar[None, :]  # ω[i, j]
    mixed_means = omega.T @ state.means
    d = state.means[None, :, :] - mixed_means[:, None, :]  # [j, i, :]
    mixed_covs = jnp.einsum("ij,jikl->jkl", omega, state.covs[None] + d[..., :, None] * d[..., None, :])
    return mixed_means, mixed_covs, cbar


def imm_predict(model: IMM, state: IMMState, u: Any = None) -> IMMState:
    """Mix the member beliefs, predict each member, and carry the predicted mode probabilities."""
    mixed_means, mixed_covs, cbar = _mix(state, model.transition)
    preds = [mem.predict(mem.params, GaussianState(mixed_means[j], mixed_covs[j]), u)
             for j, mem in enumerate(model.members)]
    return IMMState(jnp.stack([p.mean for p in preds]), jnp.stack([p.cov for p in preds]), cbar)


def imm_update(model: IMM, state: IMMState, y: jax.Array, mask: Any = None) -> tuple[IMMState, jax.Array]:
    """Update every member with ``y (p,)``; returns the new state and ``log p(y | past)``."""
    _check_measurement(model, y)
    m = kalman.full_mask(y.shape[0], mask)
    outs = [mem.update(mem.params, GaussianState(state.means[j], state.covs[j]), y, m)
            for j, mem in enumerate(model.members)]
    ll = jnp.stack([o[1].log_likelihood for o in outs])
    log_joint = jnp.log(state.probs) + ll
    total = jax.scipy.special.logsumexp(log_joint)
    probs = jnp.exp(log_joint - total)
    new = IMMState(jnp.stack([o[0].mean for o in outs]), jnp.stack([o[0].cov for o in outs]), probs)
    return new, total


def imm_estimate(state: IMMState) -> GaussianState:
    """The combined (moment-matched) estimate ``Σ μⱼ mⱼ`` and its covariance."""
    mean = state.probs @ state.means
    d = state.means - mean
    cov = jnp.einsum("j,jkl->kl", state.probs, state.covs + d[:, :, None] * d[:, None, :])
    return GaussianState(mean, cov)


def imm_filter(
    model: IMM, init: IMMState, y: Any, u: Any = None, *, mask: Any = None, missing: str = "error"
) -> IMMResult:
    """Scanned IMM over ``y (T, p)``: ``init`` is the belief before ``y_0``; update, then predict.

    ``init`` (checked as in :func:`imm_init`), ``y``, ``u`` and the float parameters of the members
    are cast to one float dtype (:func:`jaxsim.precision.to_common_float`); ``y`` must have the
    members' output dimension ``p``.
    """
    _check_state(init, len(model.members))
    data = (IMMState(*map(jnp.asarray, init)), jnp.asarray(y), None if u is None else jnp.asarray(u))
    (init, y, u), model = to_common_float(data, model)
    p = _output_dim(model)
    y, m = prepare_measurements(y, np.shape(y)[-1] if p is None else p, mask, missing)

    def step(state, x):
        y_t, m_t, u_t = x
        post, ll = imm_update(model, state, y_t, m_t)
        est = imm_estimate(post)
        return imm_predict(model, post, u_t), (est.mean, est.cov, post.probs, post.means, post.covs, ll)

    _, (means, covs, probs, mm, mc, ll) = jax.lax.scan(step, init, (y, m, u))
    return IMMResult(means, covs, probs, mm, mc, ll, jnp.sum(ll))
