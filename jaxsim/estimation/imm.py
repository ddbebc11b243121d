"""Interacting multiple model (IMM) estimator with linear, EKF or UKF members.

``transition[i, j] = P(mode_{t+1} = j | mode_t = i)`` (rows sum to one; FilterPy's ``M``).  One cycle:

* :func:`imm_predict` — mixing ``c̄_j = Σᵢ Πᵢⱼ μᵢ``, ``ωᵢⱼ = Πᵢⱼ μᵢ / c̄_j``; every member starts
  from its mixed belief ``m⁰ⱼ = Σᵢ ωᵢⱼ mᵢ``, ``P⁰ⱼ = Σᵢ ωᵢⱼ (Pᵢ + (mᵢ − m⁰ⱼ)(mᵢ − m⁰ⱼ)ᵀ)`` and
  predicts; the mode probabilities become the predicted ``c̄``;
* :func:`imm_update` — every member updates, ``μⱼ ∝ c̄ⱼ Λⱼ`` (``Λⱼ`` its innovation likelihood,
  combined in log space);
* :func:`imm_estimate` — the moment-matched mixture.

Members may have different functions (constant-velocity and coordinated-turn models, say); they
are unrolled over the (static) number of members, each a
:class:`~jaxsim.estimation.filtering.FilterMember` — the filter interface shared with the scanned
filters and the closed-loop adapter (:func:`linear_member`, :func:`ekf_member`, :func:`ukf_member`
are re-exported here).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import check_covariance, check_finite, check_probabilities
from jaxsim.estimation import kalman
from jaxsim.estimation.ekf import ekf_member
from jaxsim.estimation.filtering import FilterMember
from jaxsim.estimation.lgssm import linear_member, prepare_measurements
from jaxsim.estimation.types import GaussianState
from jaxsim.estimation.ukf import ukf_member
from jaxsim.precision import to_common_float

__all__ = [
    "IMM",
    "FilterMember",
    "IMMResult",
    "IMMState",
    "ekf_member",
    "imm",
    "imm_estimate",
    "imm_filter",
    "imm_init",
    "imm_predict",
    "imm_update",
    "linear_member",
    "ukf_member",
]


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
        raise ValueError(
            f"means, covs, probs: expected shapes (M, n), (M, n, n), (M,), got {shapes[0]}, {shapes[1]}, {shapes[2]}"
        )
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
        raise ValueError(
            f"y: expected {p} components per measurement (the members' output dimension), "
            f"got shape {tuple(np.shape(y))}"
        )


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
    preds = [
        mem.predict(mem.params, GaussianState(mixed_means[j], mixed_covs[j]), u) for j, mem in enumerate(model.members)
    ]
    return IMMState(jnp.stack([p.mean for p in preds]), jnp.stack([p.cov for p in preds]), cbar)


def imm_update(model: IMM, state: IMMState, y: jax.Array, mask: Any = None) -> tuple[IMMState, jax.Array]:
    """Update every member with ``y (p,)``; returns the new state and ``log p(y | past)``."""
    _check_measurement(model, y)
    m = kalman.full_mask(y.shape[0], mask)
    outs = [
        mem.update(mem.params, GaussianState(state.means[j], state.covs[j]), y, m)
        for j, mem in enumerate(model.members)
    ]
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
