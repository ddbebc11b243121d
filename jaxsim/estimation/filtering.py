"""The one scanned predict/update loop shared by the Kalman, extended and sigma-point filters.

A filter supplies ``update(state, y_t, mask_t, params_t) -> (state, Innovation)`` and
``predict(state, u_t, params_t) -> state``; :func:`scan_filter` runs update-then-predict over the
measurements in one ``lax.scan`` (the initial belief is the prior of the first step), applies the
optional χ² gate and collects a :class:`~jaxsim.estimation.types.FilterResult`.

Every public filter with a ``gate`` argument checks it with :func:`check_gate` before tracing.
"""

from __future__ import annotations

from typing import Any, Callable

import jax
import jax.numpy as jnp

from jaxsim.core.validation import check_positive_scalar
from jaxsim.estimation.types import FilterResult, Innovation, SqrtGaussianState

UpdateFn = Callable[[Any, jax.Array, jax.Array, Any], tuple[Any, Innovation]]
PredictFn = Callable[[Any, Any, Any], Any]


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
