"""Static multiple-model adaptive estimation (a Bayesian bank of Kalman filters) and Wald's SPRT.

Bank: ``M`` hypotheses (a :class:`~jaxsim.estimation.lgssm.LinearGaussianSSM` whose fields carry a
leading model axis ``M``), one Kalman filter each (``vmap``), posterior model probabilities
``log P(hᵢ | y_0..y_t) = log P(hᵢ) + Σ_{s≤t} log p(y_s | y_<s, hᵢ) − normaliser`` and the mixture
estimate.  No mode switching (that is the IMM).

Wald's sequential probability ratio test on a log-likelihood-ratio sequence ``Λ_t = Σ λ_s``
(``λ_s = log p₁(y_s|…) − log p₀(y_s|…)``, e.g. the per-step log-likelihoods of two filters):
accept H1 when ``Λ ≥ A = ln((1 − β)/α)``, accept H0 when ``Λ ≤ B = ln(β/(1 − α))`` (``α``, ``β`` the
type-I and type-II error probabilities).  Wald's approximate average sample numbers (overshoot
neglected) with ``μ₀ = E₀[λ] < 0``, ``μ₁ = E₁[λ] > 0``::

    E₀[N] = (α A + (1 − α) B)/μ₀,    E₁[N] = ((1 − β) A + β B)/μ₁

and Golubkov's bank size ``N = max((A − B)/μ₁, E₀[N])`` (seed 004, "size of a bank of competing
Kalman filters", eqs. 1–2): steps to cross from ``B`` to ``A`` after a change, or to reject it.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_probabilities
from jaxsim.estimation.lgssm import LinearGaussianSSM, kalman_filter
from jaxsim.estimation.types import FilterResult


class BankResult(NamedTuple):
    """``log_probs (T, M)`` posterior model log-probabilities after each step; ``means (T, n)``,
    ``covs (T, n, n)`` the mixture estimate; ``filtered`` the per-model results (leading axis M)."""

    log_probs: jax.Array
    means: jax.Array
    covs: jax.Array
    filtered: FilterResult


def bank_posterior(log_likelihoods: jax.Array, log_prior: jax.Array) -> jax.Array:
    """Posterior model log-probabilities ``(T, M)`` from per-model per-step ``(M, T)`` log-likelihoods."""
    log_joint = log_prior[:, None] + jnp.cumsum(log_likelihoods, axis=1)
    return (log_joint - jax.scipy.special.logsumexp(log_joint, axis=0, keepdims=True)).T


def bank_filter(
    models: LinearGaussianSSM,
    y: Any,
    u: Any = None,
    *,
    prior: Any = None,
    mask: Any = None,
    missing: str = "error",
    form: str = "joseph",
) -> BankResult:
    """Run one Kalman filter per hypothesis (fields of ``models`` stacked on axis 0) over ``y (T, p)``;
    ``prior (M,)`` probabilities (non-negative, sum 1; default uniform)."""
    n_models = int(np.shape(models.m0)[0])
    prior = jnp.full((n_models,), 1.0 / n_models) if prior is None else jnp.asarray(prior)
    if prior.shape != (n_models,):
        raise ValueError(f"prior: expected shape ({n_models},), got {tuple(prior.shape)}")
    check_probabilities("prior", prior)
    run = jax.vmap(lambda mdl: kalman_filter(mdl, y, u, mask=mask, missing=missing, form=form))
    res = run(models)
    log_probs = bank_posterior(res.log_likelihoods, jnp.log(prior))
    w = jnp.exp(log_probs)  # (T, M)
    means = jnp.einsum("tm,mtn->tn", w, res.means)
    d = res.means - means[None]
    covs = jnp.einsum("tm,mtkl->tkl", w, res.covs + d[..., :, None] * d[..., None, :])
    return BankResult(log_probs, means, covs, res)


def sprt_thresholds(alpha: float, beta: float) -> tuple[float, float]:
    """Wald's thresholds ``(A, B) = (ln((1 − β)/α), ln(β/(1 − α)))``."""
    for name, v in (("alpha", alpha), ("beta", beta)):
        if not 0.0 < float(v) < 0.5:
            raise ValueError(f"{name}: must lie in (0, 0.5), got {v!r}")
    return float(np.log((1.0 - beta) / alpha)), float(np.log(beta / (1.0 - alpha)))


class SPRTResult(NamedTuple):
    """``decision``: +1 accept H1, −1 accept H0, 0 undecided at the end; ``n_samples``: samples used
    (the horizon if undecided); ``llr (T,)``: the running log-likelihood ratio (frozen after a decision)."""

    decision: jax.Array
    n_samples: jax.Array
    llr: jax.Array


def sprt(increments: jax.Array, upper: float | jax.Array, lower: float | jax.Array) -> SPRTResult:
    """Run Wald's test on ``increments (T,)`` until ``Λ`` leaves ``(lower, upper)``."""

    def step(carry, lam):
        llr, decision, n = carry
        active = decision == 0
        llr = jnp.where(active, llr + lam, llr)
        n = n + active.astype(n.dtype)
        decision = jnp.where(active & (llr >= upper), 1, jnp.where(active & (llr <= lower), -1, decision))
        return (llr, decision, n), llr

    inc = jnp.asarray(increments)
    init = (jnp.zeros((), inc.dtype), jnp.zeros((), jnp.int32), jnp.zeros((), jnp.int32))
    (_, decision, n), llr = jax.lax.scan(step, init, inc)
    return SPRTResult(decision, n, llr)


def wald_asn(alpha: float, beta: float, mu0: Any, mu1: Any) -> tuple[jax.Array, jax.Array]:
    """Wald's average sample numbers ``(E₀[N], E₁[N])`` for mean increments ``mu0 < 0 < mu1``."""
    a, b = sprt_thresholds(alpha, beta)
    return (alpha * a + (1.0 - alpha) * b) / jnp.asarray(mu0), ((1.0 - beta) * a + beta * b) / jnp.asarray(mu1)


def sprt_bank_size(alpha: float, beta: float, mu0: Any, mu1: Any) -> jax.Array:
    """Golubkov's bank size ``max((A − B)/μ₁, (α A + (1 − α) B)/μ₀)``."""
    a, b = sprt_thresholds(alpha, beta)
    return jnp.maximum((a - b) / jnp.asarray(mu1), (alpha * a + (1.0 - alpha) * b) / jnp.asarray(mu0))
