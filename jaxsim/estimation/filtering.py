"""The one filter interface and the one scanned predict/update loop of the Gaussian filters.

:class:`FilterMember` is a Gaussian filter as a pair of pure step functions with its parameters —
``predict(params, state, u)`` and ``update(params, state, y, mask)`` on a
:class:`~jaxsim.estimation.types.GaussianState`.  The Kalman filter
(:func:`~jaxsim.estimation.lgssm.linear_member`), the EKF (:func:`~jaxsim.estimation.ekf.ekf_member`)
and the sigma-point filters (:func:`~jaxsim.estimation.ukf.sigma_point_member`,
:func:`~jaxsim.estimation.ukf.ukf_member`) each build one, and every user of a filter takes one:
the scanned EKF/UKF (:func:`scan_member`), the IMM bank (:mod:`~jaxsim.estimation.imm`) and the
closed-loop :class:`~jaxsim.core.system.Estimator` (:func:`~jaxsim.estimation.adapters.filter_estimator`).

:func:`scan_filter` runs update-then-predict over the measurements in one ``lax.scan`` (the initial
belief is the prior of the first step), applies the optional χ² gate and collects a
:class:`~jaxsim.estimation.types.FilterResult`; it takes bare ``update(state, y_t, mask_t, params_t)``
and ``predict(state, u_t, params_t)`` so that the time-varying linear filter can slice its matrices
per step.

Every public filter with a ``gate`` argument checks it with :func:`check_gate` before tracing.
"""

from __future__ import annotations

from typing import Any, Callable

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.validation import check_positive_scalar
from jaxsim.estimation.types import FilterResult, GaussianState, Innovation, SqrtGaussianState

UpdateFn = Callable[[Any, jax.Array, jax.Array, Any], tuple[Any, Innovation]]
PredictFn = Callable[[Any, Any, Any], Any]


@pytree_dataclass
class FilterMember:
    """A Gaussian filter: its parameters (a pytree — tunable, vmappable) and pure step functions.

    * ``predict(params, state, u) -> state``: the time update with the input ``u`` (``None`` when
      the filter runs without inputs);
    * ``update(params, state, y, mask) -> (state, Innovation)``: the measurement update with
      ``y (p,)`` and the availability ``mask (p,)`` (masked components are ignored and may be NaN);
    * ``observe(params, x) -> ŷ (p,)``: the noise-free measurement of a state (``None``: not given;
      the closed-loop adapter's ``read="output"`` needs it);
    * ``n_outputs``: the measurement dimension ``p`` it expects (``None``: unknown, not checked).

    ``state`` is a :class:`~jaxsim.estimation.types.GaussianState`.  Build one with
    :func:`~jaxsim.estimation.lgssm.linear_member`, :func:`~jaxsim.estimation.ekf.ekf_member`,
    :func:`~jaxsim.estimation.ukf.sigma_point_member` / :func:`~jaxsim.estimation.ukf.ukf_member`
    (or by hand with any functions of these signatures).
    """

    params: Any
    predict: Callable[[Any, GaussianState, Any], GaussianState] = static_field()
    update: Callable[[Any, GaussianState, jax.Array, jax.Array], tuple[GaussianState, Innovation]] = static_field()
    n_outputs: int | None = static_field(default=None)
    observe: Callable[[Any, jax.Array], jax.Array] | None = static_field(default=None)


def _cov(state: Any) -> jax.Array:
    if isinstance(state, SqrtGaussianState):
        return state.chol @ jnp.swapaxes(state.chol, -1, -2)
    return state.cov


def check_gate(gate: Any) -> float | None:
    """``None`` (no gate) or a positive, finite χ² threshold on the NIS, returned as ``float`` (a jit
    static argument).  ``gate ≤ 0`` or NaN would reject every update and ``inf`` none, silently."""
    return None if gate is None else check_positive_scalar("gate", gate)


def scan_filter(
    init: Any,
    predict: PredictFn,
    update: UpdateFn,
    y: jax.Array,
    mask: jax.Array,
    u: jax.Array | None = None,
    params_t: Any = None,
    gate: float | None = None,
) -> FilterResult:
    """Run ``update`` then ``predict`` at each step of ``y (T, p)`` with availability ``mask (T, p)``.

    ``u (T, m)`` and the pytree ``params_t`` (leaves with a leading ``T`` axis) are sliced per step.
    With ``gate``, an update whose NIS exceeds the threshold is replaced by a pure prediction.
    """

    def step(state, x):
        y_t, m_t, u_t, p_t = x
        post, innov = update(state, y_t, m_t, p_t)
        accepted = jnp.any(m_t)
        if gate is not None:
            ok = innov.nis <= gate
            skipped, _ = update(state, y_t, jnp.zeros_like(m_t), p_t)
            post = jax.tree_util.tree_map(lambda a, b: jnp.where(ok, a, b), post, skipped)
            innov = innov._replace(log_likelihood=jnp.where(ok, innov.log_likelihood, 0.0))
            accepted = accepted & ok
        return predict(post, u_t, p_t), (state, post, innov, accepted)

    _, (prior, post, innov, accepted) = jax.lax.scan(step, init, (y, mask, u, params_t))
    return FilterResult(
        means=post.mean,
        covs=_cov(post),
        predicted_means=prior.mean,
        predicted_covs=_cov(prior),
        log_likelihood=jnp.sum(innov.log_likelihood),
        log_likelihoods=innov.log_likelihood,
        innovations=innov.residual,
        innovation_covs=innov.cov,
        nis=innov.nis,
        dof=innov.dof,
        accepted=accepted,
    )


def scan_member(
    member: FilterMember,
    init: GaussianState,
    y: jax.Array,
    mask: jax.Array,
    u: jax.Array | None = None,
    gate: float | None = None,
) -> FilterResult:
    """:func:`scan_filter` with the steps of ``member`` (prior ``init`` of the first step; ``y (T, p)``,
    ``mask (T, p)``, ``u (T, m)`` or ``None``; optional χ² ``gate``)."""

    def update(state, y_t, m_t, _):
        return member.update(member.params, state, y_t, m_t)

    def predict(state, u_t, _):
        return member.predict(member.params, state, u_t)

    return scan_filter(init, predict, update, y, mask, u, None, gate)
