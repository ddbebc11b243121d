"""Many measurement sequences through one linear-Gaussian model: one log-likelihood per run, fast.

:func:`batched_kalman_loglik` filters ``ys (runs, T, p)`` — a Monte-Carlo batch of noise draws, or a
sweep over noise scales — and returns each run's total log-likelihood ``(runs,)``.  It computes what
``jax.vmap(lambda y: kalman_filter(model, y).log_likelihood)(ys)`` computes, laid out for speed:

* **Time-major, batch on the fast axis** (per-run scales).  Every per-step quantity is an array whose
  last axis is the run: means ``(n, runs)``, covariances ``(n, n, runs)``.  The small matrix products of a step are
  written as broadcast multiply-and-sum over the tiny axes (``n``, ``p`` ≤ a few), which XLA fuses into
  one loop over runs with SIMD, instead of one tiny GEMM or LAPACK call per run.
* **Transposed block by block** (per-run scales).  The input stays batch-major (each run contiguous).
  It is transposed once in blocks of ``block`` steps (``(runs, T/L, L·p) → (T/L, runs, L·p)``: contiguous pieces of
  ``L·p`` numbers, close to a plain copy), and each block is turned time-major inside the scan while it
  is in cache — a full ``(runs, T, p) → (T, p, runs)`` transpose moves one number at a time and costs
  more than the filter on large batches.
* **Shared model** (``r_scale = q_scale = None``): the covariances, gains and innovation covariances do
  not depend on the data, so the covariance recursion runs once, unbatched (as in
  :mod:`~jaxsim.estimation.shared_gain`, in the written-out Joseph form below).  What is left per run is
  affine in the data — per step ``z = W(ỹ − H m)`` (``W = L_S⁻¹``, ``ℓ += −½ zᵀz``) and
  ``m ← F m + F K (ỹ − H m) + B u`` — so ``k`` steps (``block``, default 8) compose into one affine
  map of ``[m_s, ỹ_s … ỹ_{s+k−1}]`` that returns all ``k`` whitened innovations and ``m_{s+k}``.  The
  maps are built once per call (shared by all runs); the runs then advance ``k`` steps with one GEMM
  ``(runs, n + kp) × (n + kp, kp + n)``, reading ``ys`` in place, runs-major (no transpose).  That is
  about ``2(n + kp)²/k`` flops per run and step (100 for ``n = 4``, ``p = 2``, ``k = 8``) — more than
  the step-by-step ``2p(2n + p) + 2n²``, but at GEMM speed instead of one tiny fused loop per step.
  Memory: ``(n + kp)²/k`` numbers per step for the maps.
* **Steady gain** (shared, constant ``F, H, Q, R``, no mask, no inputs, ``T ≥ 2·``:data:`STEADY_AFTER`):
  the covariance recursion of a detectable model converges to the Riccati fixed point — for the
  benchmark's constant-velocity model it stops changing in float64 after about 50 steps — after which
  every step has the same gain and every block the same map.  The recursion runs :data:`STEADY_AFTER`
  steps (rounded up to whole blocks) and tests ``max|P_h − P_{h−1}| ≤`` :data:`STEADY_TOL` ``· eps ·
  max|P_h|`` on the predicted covariance; if it passes, steps from ``h`` on use step ``h``'s gain and
  one shared block map (``lax.cond``: no host sync, differentiable), otherwise the gain-per-step path
  goes on from step ``h``.  The results equal the per-step path's to rounding (tested against the serial
  filter, and for a slowly converging model that takes the fallback).
* **Per-run noise scales** (``r_scale``/``q_scale``, shape ``(runs,)``: run ``i`` uses ``R·r_scale[i]``
  and ``Q·q_scale[i]``): every run needs its own gain, so the covariance recursion is batched too,
  with the runs on the fast axis.  The update is the Joseph form written out,
  ``P⁺ = P − K Cᵀ − C Kᵀ + K S Kᵀ`` with ``C = P Hᵀ`` — algebraically ``(I − KH) P (I − KH)ᵀ + K R Kᵀ``
  for any gain (so first-order insensitive to gain error) and symmetric by construction, at a third of
  the flops of the product form.  (When ``Q``, ``R`` *and* ``P0`` share one scale ``s`` the gains are
  shared and ``P`` scales by ``s``; that case is not special-cased here.)

Shared availability ``mask`` (``(T,)`` or ``(T, p)``, the same for every run) and shared inputs
``u (T, m)`` are supported, as are time-varying ``F, Q, H, R, B`` (leading ``T`` axis); conventions
(update with ``y_0`` first, ``u[t]`` drives ``t → t+1``) are :func:`~jaxsim.estimation.lgssm.kalman_filter`'s.

Bad input: shapes, the model (:func:`~jaxsim.estimation.lgssm.validate_model`) and the scales
(positive, finite) are checked before tracing.  Non-finite measurements are not scanned up front (that
would be a second pass over the data): an unmasked NaN/inf makes its run's log-likelihood non-finite,
and on concrete input that run is then located and reported as a ``ValueError``.  Under ``jit``/``vmap``
the NaN is returned instead.
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_positive, check_positive_int, check_shape, is_concrete
from jaxsim.estimation import linalg
from jaxsim.estimation.kalman import LOG_2PI
from jaxsim.estimation.lgssm import (
    LinearGaussianSSM,
    is_time_varying,
    prepare_inputs,
    prepare_measurements,
    validate_model,
)
from jaxsim.precision import to_common_float

DEFAULT_BLOCK = 25  # steps per transposed block, per-run covariances
SHARED_BLOCK = 8  # steps per affine map, shared model (measured best of 2–25 at 100–10,000 runs)
GAIN_UNROLL = 4  # covariance-recursion scan unrolled: its loop overhead dominates 1000 tiny steps
STEADY_AFTER = 128  # shared constant model: steps of covariance recursion before the fixed-point test
STEADY_TOL = 4  # ... which passes when max|P_head − P_head−1| ≤ STEADY_TOL · eps · max|P_head| (predicted P)


def batched_kalman_loglik(
    model: LinearGaussianSSM,
    ys: Any,
    u: Any = None,
    *,
    mask: Any = None,
    r_scale: Any = None,
    q_scale: Any = None,
    block: int | None = None,
) -> jax.Array:
    """Total Kalman-filter log-likelihood of each of many measurement sequences through one model.

    Args:
        model: the :class:`~jaxsim.estimation.lgssm.LinearGaussianSSM` (``n`` states, ``p`` outputs).
        ys: measurements ``(runs, T, p)``, batch-major (each run contiguous).
        u: shared inputs ``(T, m)`` (the same for every run); ``u[t]`` drives ``t → t+1``.
        mask: shared availability ``(T,)`` or ``(T, p)`` booleans (``True`` = measured); masked
            entries of ``ys`` are ignored and may hold NaN.
        r_scale: optional ``(runs,)`` positive factors: run ``i`` uses ``R·r_scale[i]``.
        q_scale: optional ``(runs,)`` positive factors: run ``i`` uses ``Q·q_scale[i]``.
        block: a tuning knob — steps per affine map for a shared model (default :data:`SHARED_BLOCK`),
            per transposed block with scales (default :data:`DEFAULT_BLOCK`; the block of all runs
            should fit in cache).

    Returns:
        ``(runs,)`` log-likelihoods, equal to ``kalman_filter(model_i, ys[i], u, mask=mask).log_likelihood``
        to rounding.  Without scales the covariance recursion runs once for all runs (for a constant
        model only until its fixed point); with scales it runs batched (see the module docstring).
        The model, ``ys``, ``u`` and the scales are cast to one float dtype (float64 unless all are
        float32).
    """
    ys = jnp.asarray(ys)
    check_shape("ys", ys, (None, None, None))
    runs, n_steps, p = ys.shape
    validate_model(model, n_steps=n_steps)
    if p != model.n_outputs:
        raise ValueError(f"ys: expected shape (runs, T, {model.n_outputs}), got {tuple(ys.shape)}")
    if block is None:
        block = DEFAULT_BLOCK if (r_scale is not None or q_scale is not None) else SHARED_BLOCK
    block = check_positive_int("block", block)
    scales = {}
    for name, s in (("r_scale", r_scale), ("q_scale", q_scale)):
        if s is not None:
            s = jnp.asarray(s)
            check_shape(name, s, (runs,))
            check_positive(name, s)
            scales[name] = s
    _, m = prepare_measurements(jnp.zeros((n_steps, p), dtype=ys.dtype), p, mask)
    (model, ys, u, scales), _ = to_common_float((model, ys, None if u is None else jnp.asarray(u), scales))
    u = prepare_inputs(u, n_steps, model)
    masked = mask is not None
    if scales:
        one = jnp.ones((runs,), dtype=ys.dtype)
        rs, qs = scales.get("r_scale", one), scales.get("q_scale", one)
        ll = _per_run_loglik(model, ys, m, u, rs, qs, block, masked)
    else:
        ll = _shared_loglik(model, ys, m, u, block, masked)
    if is_concrete(ll):
        _report_non_finite(ll, ys, m)
    return ll


def _report_non_finite(ll: jax.Array, ys: jax.Array, m: jax.Array) -> None:
    """Raise for the first run whose log-likelihood is not finite because of an unmasked bad ``ys``."""
    bad_runs = np.flatnonzero(~np.isfinite(np.asarray(ll)))
    if bad_runs.size == 0:
        return
    i = int(bad_runs[0])
    bad = ~np.isfinite(np.asarray(ys[i])) & np.asarray(m)
    if bad.any():
        t, j = np.argwhere(bad)[0]
        raise ValueError(
            f"ys: non-finite value in run {i} at step {t}, component {j} that is not masked; pass a "
            f"mask (shared by all runs) or filter that run separately"
        )


# --- small products with the runs on the last axis --------------------------------------------------


def _mv(a: jax.Array, v: jax.Array) -> jax.Array:
    """``a (i, k)`` times ``v (k, runs)`` → ``(i, runs)``."""
    return jnp.sum(a[:, :, None] * v[None, :, :], axis=1)


def _bmm(a: jax.Array, b: jax.Array) -> jax.Array:
    """Per run ``a[..., r] @ b[..., r]``: ``(i, k, runs) × (k, j, runs) → (i, j, runs)``; either may
    also be a shared matrix without the runs axis."""
    a3 = a if a.ndim == 3 else a[:, :, None]
    b3 = b if b.ndim == 3 else b[:, :, None]
    return jnp.sum(a3[:, :, None, :] * b3[None, :, :, :], axis=1)


def _bt(a: jax.Array) -> jax.Array:
    """Transpose of the two matrix axes of ``(i, j, runs)``."""
    return jnp.swapaxes(a, 0, 1)


def _cholesky(s: jax.Array) -> list[list[jax.Array]]:
    """Lower Cholesky factor of ``s (p, p, runs)``: a nested list of ``(runs,)`` entries, ``None`` above
    the diagonal."""
    k = s.shape[0]
    low: list[list[Any]] = [[None] * k for _ in range(k)]
    for j in range(k):
        d = s[j, j] - sum((low[j][q] ** 2 for q in range(j)), jnp.zeros_like(s[j, j]))
        low[j][j] = jnp.sqrt(d)
        for i in range(j + 1, k):
            low[i][j] = (s[i, j] - sum((low[i][q] * low[j][q] for q in range(j)), jnp.zeros_like(d))) / low[j][j]
    return low


def _solve_lower(low: list, b: jax.Array) -> jax.Array:
    """``L⁻¹ b`` per run for ``b (p, ..., runs)``."""
    rows: list[jax.Array] = []
    for i in range(len(low)):
        rows.append((b[i] - sum((low[i][q] * rows[q] for q in range(i)), jnp.zeros_like(b[i]))) / low[i][i])
    return jnp.stack(rows)


def _solve_upper_t(low: list, b: jax.Array) -> jax.Array:
    """``L⁻ᵀ b`` per run for ``b (p, ..., runs)``."""
    k = len(low)
    rows: list[Any] = [None] * k
    for i in reversed(range(k)):
        rows[i] = (b[i] - sum((low[q][i] * rows[q] for q in range(i + 1, k)), jnp.zeros_like(b[i]))) / low[i][i]
    return jnp.stack(rows)


# --- the blocked time-major scan ---------------------------------------------------------------------


def time_major_scan(step: Callable, carry: Any, ys: jax.Array, xs: Any, block: int) -> Any:
    """``lax.scan`` of ``step(carry, (y_t (p, runs), x_t)) -> carry`` over ``ys (runs, T, p)`` and the
    per-step pytree ``xs`` (leading ``T`` axis); returns the final carry.

    ``ys`` is transposed in blocks of ``block`` steps (see the module docstring); a last partial block
    is run after the full ones.
    """
    runs, n_steps, p = ys.shape
    size = min(block, n_steps)
    n_blocks = n_steps // size
    head = n_blocks * size

    def run_block(c, yb, xb):  # yb (runs, k, p)
        def inner(c2, x):
            return step(c2, x), None

        return jax.lax.scan(inner, c, (jnp.transpose(yb, (1, 2, 0)), xb))[0]

    y_blocks = jnp.swapaxes(ys[:, :head].reshape(runs, n_blocks, size * p), 0, 1)
    x_blocks = jax.tree_util.tree_map(lambda a: a[:head].reshape((n_blocks, size) + a.shape[1:]), xs)

    def outer(c, b):
        yb, xb = b
        return run_block(c, yb.reshape(runs, size, p), xb), None

    carry = jax.lax.scan(outer, carry, (y_blocks, x_blocks))[0]
    if head < n_steps:
        carry = run_block(carry, ys[:, head:], jax.tree_util.tree_map(lambda a: a[head:], xs))
    return carry


def _at(model: LinearGaussianSSM, name: str, x: dict) -> jax.Array:
    """Field ``name`` at the current step: the scanned slice if time-varying, else the constant (kept
    out of the scanned inputs so that XLA can fold a constant model into the step)."""
    return x[name] if name in x else getattr(model, name)


def _varying(model: LinearGaussianSSM, names: tuple[str, ...]) -> dict[str, jax.Array]:
    return {k: getattr(model, k) for k in names if is_time_varying(model, k)}


def _input_drive(model: LinearGaussianSSM, u: jax.Array | None) -> jax.Array | None:
    """``B_t u_t`` per step, ``(T, n)``, or ``None`` without inputs."""
    if u is None or model.B is None:
        return None
    B = model.B if is_time_varying(model, "B") else model.B[None]
    return jnp.einsum("tij,tj->ti", B, u)


def _masked_noise(R: jax.Array, m_t: jax.Array) -> jax.Array:
    """``R`` with masked components decoupled (unit variance, uncorrelated)."""
    both = m_t[:, None] & m_t[None, :]
    return jnp.where(both, R, jnp.eye(R.shape[0], dtype=R.dtype))


# --- shared model: covariances once, means batched ------------------------------------------------


def _gain_sequence(
    model: LinearGaussianSSM, m: jax.Array, masked: bool, with_covariances: bool = False, P0: jax.Array | None = None
) -> tuple:
    """One unbatched covariance recursion over the ``T = len(m)`` steps from the predicted covariance
    ``P0`` (default ``model.P0``; a time-varying model starts at step 0): per step the gain ``K (T, n, p)``,
    the whitening ``W = L_S⁻¹ (T, p, p)`` and ``−½(log det S + dof·log 2π) (T,)``; with
    ``with_covariances`` also the predicted covariances ``P (T, n, n)`` the gains came from.  Joseph
    form written out (see the module docstring); masked components get zero ``H`` rows, decoupled noise
    and zero ``W`` rows."""
    mm = linalg.matmul
    p = model.n_outputs
    eye = jnp.eye(p, dtype=model.P0.dtype)

    def step(P, x):
        P_prior = P
        H, R, F, Q, m_t = _at(model, "H", x), _at(model, "R", x), _at(model, "F", x), _at(model, "Q", x), x["m"]
        if masked:
            H, R = jnp.where(m_t[:, None], H, 0.0), _masked_noise(R, m_t)
        C = mm(P, H.T)
        S = mm(H, C) + R
        low = linalg.cholesky(0.5 * (S + S.T))
        W = linalg.solve_lower(low, eye)
        K = mm(C, mm(W.T, W))
        KC = mm(K, C.T)
        P = P - KC - KC.T + mm(mm(K, S), K.T)
        P = mm(mm(F, P), F.T) + Q
        if masked:
            W = jnp.where(m_t[:, None], W, 0.0)
        log_norm = -(jnp.sum(jnp.log(jnp.diagonal(low))) + 0.5 * jnp.sum(m_t) * LOG_2PI)
        return 0.5 * (P + P.T), (K, W, log_norm, *((P_prior,) if with_covariances else ()))

    xs = dict(_varying(model, ("H", "R", "F", "Q")), m=m)
    return jax.lax.scan(step, model.P0 if P0 is None else P0, xs, unroll=GAIN_UNROLL)[1]


def _affine_steps(model: LinearGaussianSSM, K: jax.Array, W: jax.Array, m: jax.Array, masked: bool):
    """The mean recursion of a shared model as affine maps of ``(m_t, ỹ_t)`` (``ỹ``: masked entries 0):
    ``z_t = C_t m_t + W_t ỹ_t`` and ``m_{t+1} = A_t m_t + G_t ỹ_t + b_t`` with ``H̃_t`` = ``H_t`` with
    masked rows zeroed, ``G_t = F_t K_t``, ``A_t = F_t − G_t H̃_t``, ``C_t = −W_t H̃_t``; ``b_t = B u_t``
    or ``None``.  Returns ``(A (T, n, n), G (T, n, p), C (T, p, n), W (T, p, p))``."""
    n_steps = K.shape[0]
    F = model.F if is_time_varying(model, "F") else jnp.broadcast_to(model.F, (n_steps, *model.F.shape))
    H = model.H if is_time_varying(model, "H") else jnp.broadcast_to(model.H, (n_steps, *model.H.shape))
    if masked:
        H = jnp.where(m[:, :, None], H, 0.0)
    G = F @ K
    return F - G @ H, G, -(W @ H), W


def _block_map(A: jax.Array, G: jax.Array, C: jax.Array, W: jax.Array, b: jax.Array | None):
    """``k`` consecutive steps as one affine map of ``x = [m_s, ỹ_s, …, ỹ_{s+k−1}]`` (``n + kp``):
    ``[z_s, …, z_{s+k−1}, m_{s+k}] = x Mᵀ + c``.  Returns ``(Mᵀ (n + kp, kp + n), c (kp + n,))``.

    ``A, G, C, W`` hold the ``k`` steps' matrices (:func:`_affine_steps`), ``b`` their ``B u`` or ``None``.
    Built by running the recursion on the map itself: ``m_{s+j} = T_j x + o_j``, ``T_0 = [I 0]``."""
    k, n, p = G.shape
    T = jnp.zeros((n, n + k * p), A.dtype).at[:, :n].set(jnp.eye(n, dtype=A.dtype))
    o = jnp.zeros((n,), A.dtype)
    rows, offsets = [], []
    for j in range(k):
        cols = slice(n + j * p, n + (j + 1) * p)
        rows.append((C[j] @ T).at[:, cols].add(W[j]))
        offsets.append(C[j] @ o)
        T = (A[j] @ T).at[:, cols].add(G[j])
        o = A[j] @ o + (0.0 if b is None else b[j])
    return jnp.concatenate([*rows, T]).T, jnp.concatenate([*offsets, o])


def _advance(carry: tuple, Mt: jax.Array, c: jax.Array, y: jax.Array, valid: int | None = None) -> tuple:
    """All runs through one block map: one GEMM of ``[m, y] (runs, n + size·p)``; ``zᵀz`` summed per run
    over the first ``valid`` innovation entries (default all: a zero-padded last block counts fewer)."""
    mean, acc = carry
    out = jnp.concatenate([mean, y], axis=1) @ Mt + c
    z = out[:, : y.shape[1] if valid is None else valid]
    return out[:, y.shape[1] :], acc + jnp.sum(z * z, axis=1)


def _run_blocks(
    carry: tuple, flat: jax.Array, first: int, k: int, p: int, map_of: Callable, stop: int | None = None
) -> tuple:
    """Advance every run through blocks ``first … stop − 1`` of ``flat (runs, T·p)`` (``stop=None``: to
    the end), ``k`` steps per block; ``map_of(i)`` gives block ``i``'s ``(Mᵀ, c)``.  At the end, a last
    partial block is zero-padded to ``k`` steps and only its real innovations are counted (each map is
    causal: ``z_j`` depends on ``ỹ_0 … ỹ_j``)."""
    width, n_blocks = k * p, flat.shape[1] // (k * p)
    last = n_blocks if stop is None else stop
    if last > first:

        def body(i, c):
            return _advance(c, *map_of(i), jax.lax.dynamic_slice_in_dim(flat, i * width, width, axis=1))

        carry = jax.lax.fori_loop(first, last, body, carry)
    if stop is not None:
        return carry
    rest = flat.shape[1] - n_blocks * width
    if rest:
        y = jnp.pad(flat[:, n_blocks * width :], ((0, 0), (0, width - rest)))
        carry = _advance(carry, *map_of(n_blocks), y, valid=rest)
    return carry


def _maps(steps: tuple, bu: jax.Array | None, k: int) -> tuple[jax.Array, jax.Array]:
    """The block maps of consecutive runs of ``k`` steps: ``(Mᵀ (blocks, …), c (blocks, …))``; a last
    partial block is padded with copies of its last step (and zero inputs)."""
    pad = -len(steps[0]) % k
    if pad:
        steps = tuple(jnp.concatenate([a, jnp.broadcast_to(a[-1], (pad, *a.shape[1:]))]) for a in steps)
        bu = None if bu is None else jnp.pad(bu, ((0, pad), (0, 0)))
    per_block = [a.reshape(-1, k, *a.shape[1:]) for a in steps]
    b = None if bu is None else bu.reshape(-1, k, bu.shape[-1])
    return jax.vmap(_block_map)(*per_block, b)


def _steady_eligible(model: LinearGaussianSSM, masked: bool, bu: Any, n_steps: int, k: int) -> bool:
    """A constant model without mask or inputs, long enough for the fixed-point test to pay off."""
    constant = not any(is_time_varying(model, f) for f in ("F", "H", "R", "Q"))
    return constant and not masked and bu is None and n_steps >= 2 * _steady_head(k)


def reached_fixed_point(P_before: jax.Array, P: jax.Array) -> jax.Array:
    """The fixed-point test on two consecutive predicted covariances: ``max|P − P_before| ≤``
    :data:`STEADY_TOL` ``· eps · max|P|`` (a boolean scalar, traceable)."""
    change = jnp.max(jnp.abs(P - P_before))
    return change <= STEADY_TOL * jnp.finfo(P.dtype).eps * jnp.max(jnp.abs(P))


def _steady_head(k: int) -> int:
    """Steps of covariance recursion before the fixed-point test: :data:`STEADY_AFTER` rounded up to
    whole blocks of ``k``."""
    return -(-STEADY_AFTER // k) * k


@functools.partial(jax.jit, static_argnames=("block", "masked"))
def _shared_loglik(model, ys, m, u, block, masked):
    runs, n_steps, p = ys.shape
    bu = _input_drive(model, u)
    flat = ys.reshape(runs, n_steps * p)  # runs-major, as given: each block is a strided slice
    if masked:
        flat = jnp.where(m.reshape(1, -1), flat, 0.0)  # masked entries may hold NaN
    k = min(block, n_steps)
    carry = (jnp.broadcast_to(model.m0, (runs, model.n_states)), jnp.zeros((runs,), ys.dtype))
    if not _steady_eligible(model, masked, bu, n_steps, k):
        log_norm, carry = _gain_per_step(model, flat, m, bu, carry, model.P0, 0, k, masked)
        return log_norm - 0.5 * carry[1]
    # the first `head` steps as usual (the covariance recursion one step further, for the test), and
    # the map of a block of steps that all take step head's gain
    head = _steady_head(k)
    K, W, log_norm, P = _gain_sequence(model, m[: head + 1], False, with_covariances=True)
    steps = _affine_steps(model, K, W, m[: head + 1], False)
    steps = tuple(jnp.concatenate([a[:head], jnp.broadcast_to(a[head], (k, *a.shape[1:]))]) for a in steps)
    Mts, cs = _maps(steps, None, k)
    b0 = head // k
    carry = _run_blocks(carry, flat, 0, k, p, lambda i: (Mts[i], cs[i]), stop=b0)
    rest_norm, carry = jax.lax.cond(
        reached_fixed_point(P[head - 1], P[head]),
        lambda c: ((n_steps - head) * log_norm[head], _run_blocks(c, flat, b0, k, p, lambda i: (Mts[b0], cs[b0]))),
        lambda c: _gain_per_step(model, flat, m, None, c, P[head], head, k, False),
        carry,
    )
    return jnp.sum(log_norm[:head]) + rest_norm - 0.5 * carry[1]


def _gain_per_step(model, flat, m, bu, carry, P_first, first: int, k: int, masked: bool):
    """Steps ``first … T − 1`` (``first`` a multiple of ``k``; ``first > 0`` only for a constant model)
    with a gain and a block map for every step, from the predicted covariance ``P_first``.
    Returns (their summed log-normalisers, the carry)."""
    K, W, log_norm = _gain_sequence(model, m[first:], masked, P0=P_first)
    steps = _affine_steps(model, K, W, m[first:], masked)
    Mts, cs = _maps(steps, None if bu is None else bu[first:], k)
    b0 = first // k
    return jnp.sum(log_norm), _run_blocks(carry, flat, b0, k, model.n_outputs, lambda i: (Mts[i - b0], cs[i - b0]))


# --- per-run noise scales: covariances batched too -------------------------------------------------


@functools.partial(jax.jit, static_argnames=("block", "masked"))
def _per_run_loglik(model, ys, m, u, rs, qs, block, masked):
    runs, n_steps, p = ys.shape
    n = model.n_states
    xs = _varying(model, ("H", "F", "Q", "R"))
    bu = _input_drive(model, u)
    if bu is not None:
        xs["bu"] = bu
    if masked:
        xs["m"] = m

    def step(c, inp):
        mean, P, acc = c
        y, x = inp
        H, R, F, Q = _at(model, "H", x), _at(model, "R", x), _at(model, "F", x), _at(model, "Q", x)
        r_run = R[:, :, None] * rs
        if masked:
            m_t = x["m"]
            H = jnp.where(m_t[:, None], H, 0.0)
            both = (m_t[:, None] & m_t[None, :])[:, :, None]
            r_run = jnp.where(both, r_run, jnp.eye(p, dtype=ys.dtype)[:, :, None])
        C = _bmm(P, H.T)  # P Hᵀ  (n, p, runs)
        S = _bmm(H, C) + r_run
        S = 0.5 * (S + _bt(S))
        low = _cholesky(S)
        K = _bt(_solve_upper_t(low, _solve_lower(low, _bt(C))))  # C S⁻¹  (n, p, runs)
        res = y - _mv(H, mean)
        if masked:
            res = jnp.where(m_t[:, None], res, 0.0)
        z = _solve_lower(low, res)
        logdet = 2.0 * sum(jnp.log(low[i][i]) for i in range(p))
        dof = jnp.sum(x["m"]) if masked else p
        acc = acc - 0.5 * (jnp.sum(z * z, axis=0) + logdet + dof * LOG_2PI)
        mean = mean + jnp.sum(K * res[None, :, :], axis=1)
        KC = _bmm(K, _bt(C))
        P = P - KC - _bt(KC) + _bmm(_bmm(K, S), _bt(K))
        mean = _mv(F, mean)
        if "bu" in x:
            mean = mean + x["bu"][:, None]
        P = _bmm(_bmm(F, P), F.T) + Q[:, :, None] * qs
        return mean, 0.5 * (P + _bt(P)), acc

    init = (
        jnp.broadcast_to(model.m0[:, None], (n, runs)),
        jnp.broadcast_to(model.P0[:, :, None], (n, n, runs)),
        jnp.zeros((runs,), ys.dtype),
    )
    return time_major_scan(step, init, ys, xs, block)[2]
