"""Model-free one-step output prediction from a block Hankel matrix (seed 000, paper 6).

For an unknown linear system driven by "linearisable" inputs (outputs of an unknown autonomous
exosystem: steps, ramps, sinusoids) the augmented system is autonomous, ``x_{i+1} = A x_i``,
``y_i = C x_i`` (paper eqs. 6–7).  Stack ``ν + 1`` consecutive outputs into a column
``[y_j; …; y_{j+ν}] = 𝒞 x_j`` (𝒞 the observability matrix, ``ν`` the observability index) and
``h + 1`` such columns into the block Hankel matrix ``Y_i`` (``p(ν+1) × (h+1)``; the newest column
ends with ``y_i``).  If 𝒞 has full column rank, ``Y_{i+1} = 𝒜 Y_i`` with ``𝒜 = 𝒞A𝒞^L`` (eq. 21),
so every right null vector of ``Y_i`` also annihilates ``Y_{i+1}`` (eq. 28).  The last block row of
``Y_{i+1}`` is ``[y_{i−h+1} … y_i  y_{i+1}]``; with ``R`` a basis of the right null space and ``r``
its last row this gives ``[y_{i−h+1} … y_i] R_{0:h} + y_{i+1} r = 0`` and (eq. 30)::

    ŷ_{i+1} = −[y_{i−h+1} … y_i] R_{0:h} r⁺,     r⁺ = rᵀ/(r rᵀ)

No model is identified: the prediction uses the last ``h + ν + 1`` samples only and is exact for
noise-free data of any such system whose augmented order ``n ≤ p(ν+1)`` and ``n ≤ h``.  The null
space is taken from an SVD: directions with ``σ ≤ rank_tol·σ_max`` (or, with ``rank`` given, all but
the ``rank`` largest) — the hidden key parameter of the method (spec §6.1): under noise nothing is
exactly null and the tolerance decides what counts as signal.

The paper's settings: window ``h = 15``, ``ν = 4``, sampling step 0.05 s.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_finite, check_positive


def validate_sizes(window: int, nu: int) -> None:
    """``window`` (h) and ``nu`` (ν) must be positive integers with ``window ≥ nu``."""
    for name, v in (("window", window), ("nu", nu)):
        if not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name}: must be a positive integer, got {v!r}")
    if window < nu:
        raise ValueError(
            f"window: must be at least the observability index nu={nu} (the Hankel matrix needs as many "
            f"columns as the system order it must reveal), got {window}"
        )


def block_hankel(ys: jax.Array, rows: int, cols: int) -> jax.Array:
    """Block Hankel matrix of ``ys`` (N, p) with ``rows`` block rows, ``cols`` columns from sample 0.

    Entry (block ``r``, column ``c``) is ``ys[r + c]``; shape ``(p·rows, cols)``.
    """
    idx = jnp.arange(rows)[:, None] + jnp.arange(cols)[None, :]
    blocks = ys[idx]  # (rows, cols, p)
    return jnp.transpose(blocks, (0, 2, 1)).reshape(rows * ys.shape[1], cols)


def predict_next(
    history: jax.Array, window: int = 15, nu: int = 4, rank_tol: float = 1e-10, rank: int | None = None
) -> jax.Array:
    """Predict the next output from ``history`` (``window + nu + 1``, p): samples ``y_{i−h−ν} … y_i``.

    Returns ``ŷ_{i+1}`` of shape ``(p,)``.  Jittable; ``window``, ``nu`` and ``rank`` are static.
    """
    h = window
    Y = block_hankel(history, nu + 1, h + 1)
    _, s, vt = jnp.linalg.svd(Y, full_matrices=True)
    s_full = jnp.zeros(h + 1, dtype=Y.dtype).at[: s.shape[0]].set(s)
    if rank is None:
        null = s_full <= rank_tol * s_full[0]
    else:
        null = jnp.arange(h + 1) >= rank
    R = vt.T * null[None, :]  # (h+1, h+1), masked columns span the right null space
    p = history.shape[1]
    known = Y[nu * p :, 1:]  # last block row shifted: y_{i−h+1} … y_i, shape (p, h)
    k = known @ R[:h, :]  # (p, h+1)
    r = R[h, :]
    return -(k @ r) / (r @ r)


def predict_series(
    ys: jax.Array, window: int = 15, nu: int = 4, rank_tol: float = 1e-10, rank: int | None = None
) -> jax.Array:
    """One-step predictions over a series ``ys`` (N, p): row ``k`` predicts ``ys[k]`` from the
    ``window + nu + 1`` samples before it; the first ``window + nu + 1`` rows are NaN."""
    validate_sizes(window, nu)
    ys = jnp.asarray(ys)
    if ys.ndim != 2:
        raise ValueError(f"ys: expected shape (N, p), got {tuple(ys.shape)}")
    need = window + nu + 1
    if ys.shape[0] <= need:
        raise ValueError(f"ys: need more than window + nu + 1 = {need} samples, got {ys.shape[0]}")
    check_finite("ys", ys)
    check_positive("rank_tol", rank_tol)
    if rank is not None and not (isinstance(rank, (int, np.integer)) and 0 <= rank <= window):
        raise ValueError(f"rank: must be an integer in [0, window={window}], got {rank!r}")
    starts = jnp.arange(ys.shape[0] - need)
    hist = jax.vmap(lambda s: jax.lax.dynamic_slice_in_dim(ys, s, need, axis=0))(starts)
    preds = jax.vmap(lambda hh: predict_next(hh, window, nu, rank_tol, rank))(hist)
    pad = jnp.full((need, ys.shape[1]), jnp.nan, dtype=preds.dtype)
    return jnp.concatenate([pad, preds], axis=0)


def numerical_rank(ys: jax.Array, window: int = 15, nu: int = 4, rank_tol: float = 1e-10) -> int:
    """Rank of the block Hankel matrix over the first ``window + nu + 1`` samples of ``ys``."""
    validate_sizes(window, nu)
    s = np.linalg.svd(np.asarray(block_hankel(jnp.asarray(ys), nu + 1, window + 1)), compute_uv=False)
    return int(np.sum(s > rank_tol * s[0]))
