"""Deprecated: the stationary Kalman filter is :func:`jaxsim.control.kalman_gain.discrete_kalman`.

The toolkit has one steady-state Kalman API, in python-control's argument order ``(A, C, Q, R)``
(``control.dlqe(A, G, C, QN, RN)`` ≙ ``discrete_kalman(A, C, QN, RN, G)``, predictor gain
``L = A K``) and :func:`jaxsim.control.kalman_gain.kalman_bucy` for continuous time.
:func:`steady_state_kalman` ``(F, Q, H, R)`` — the old order — stays one release as a thin alias.
"""

from __future__ import annotations

import warnings
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.control.kalman_gain import discrete_kalman
from jaxsim.estimation.kalman import symmetrize


class SteadyStateKalman(NamedTuple):
    """``predicted_cov`` P⁻ ``(n, n)``, ``filtered_cov`` P⁺ ``(n, n)``, ``gain`` K ``(n, p)`` of the update
    ``x⁺ = x⁻ + K (y − H x⁻)``, ``innovation_cov`` S ``(p, p)``."""

    predicted_cov: jax.Array
    filtered_cov: jax.Array
    gain: jax.Array
    innovation_cov: jax.Array


def steady_state_kalman(F: Any, Q: Any, H: Any, R: Any) -> SteadyStateKalman:
    """Deprecated alias: ``discrete_kalman(F, H, Q, R)`` (note the order) repackaged with the
    innovation covariance ``S = H P⁻ Hᵀ + R``.  Checks and errors are ``discrete_kalman``'s, naming
    ``F, H, Q, R``."""
    warnings.warn(
        "steady_state_kalman(F, Q, H, R) is deprecated; use "
        "jaxsim.control.kalman_gain.discrete_kalman(A, C, Q, R) (python-control's order)",
        DeprecationWarning,
        stacklevel=2,
    )
    gain = discrete_kalman(F, H, Q, R, names=("F", "H", "Q", "R"))
    h, r = (jnp.atleast_2d(jnp.asarray(m, gain.p_prior.dtype)) for m in (H, R))
    s = symmetrize(h @ gain.p_prior @ h.T + r)
    return SteadyStateKalman(gain.p_prior, gain.p_post, gain.k, s)
