"""Multi-window α–β tracker with a Sugeno fuzzy window selector (seed 003).

The paper's tracker (seed 003, sections 2–3) in three pure, vectorised stages:

1. **Bank** (:func:`window_bank_filter`, no parameters): at every scan ``t`` and for every window
   ``j = 2..J`` the growing-memory α–β filter (:func:`~jaxsim.estimation.alpha_beta.growing_memory_gains`,
   ``α_k = 2(2k − 1)/(k(k + 1))``, ``β_k = 6/(k(k + 1))``) is run over the last ``j`` plots — the tuple
   ``{x̂⁽²⁾, …, x̂⁽ᴶ⁾}`` of eq. (5).  Its estimate is the least-squares line through those plots.
   While the track is younger than ``j`` scans the window holds every plot so far.  The residual
   norm of window ``j`` at scan ``t`` is ``Δz⁽ʲ⁾_t = ‖z_t − (x̂⁽ʲ⁾_{t−1} + v̂⁽ʲ⁾_{t−1} τ)‖`` (eq. 6); it exists
   from the third plot on (a prediction needs a velocity, i.e. two plots).
2. **Selector** (:func:`select_windows`, the tunable part): the noise scale
   ``σ̂_t = (1/κ)·mean(Δz⁽²⁾)`` over the scans so far (section 4; the paper's formula has no visible
   normaliser, ``κ = 1``), the inputs ``L⁽ʲ⁾ = min(Δz⁽ʲ⁾/σ̂, 3)`` (eq. 7), the memberships
   ``μ_good(L) = 1 − σ(a(L − c))``, ``μ_bad(L) = σ(a(L − c))`` (Fig. 1; a = 5, c = 1.5), and the
   zero-order Sugeno system (:func:`jaxsim.control.fuzzy.sugeno`) with the rules "Q⁽²⁾…Q⁽ᵖ⁾ good,
   Q⁽ᵖ⁺¹⁾…Q⁽ᴶ⁾ bad ⇒ m = p" for ``p = J…2`` and "all bad ⇒ m = 2" (the paper's table).  The final
   window is ``max(m_t, m_{t−1})`` of the raw Sugeno outputs, rounded to the nearest integer.
3. **Selection** (:func:`select_estimates`): the chosen window's estimate and its one-scan prediction.

Exact and smooth forms (``smooth=False/True`` in :func:`select_windows`):

* exact (for reporting): ``m = round(max(m_t, m_{t−1}))`` (halves up), one-hot window weights;
* smooth (for gradients): the max is ``T·log(e^{m_t/T} + e^{m_{t−1}/T})`` (at most ``T·ln 2`` above
  the max) and the rounding becomes soft-min weights ``w_j ∝ exp(−(m − j)²/(2T²))`` over the windows
  (nearest-window selection as ``T → 0``); ``T = temperature``, in window units (default 0.25).

The max with the *raw* previous output is the reading that lets the window fall again: with the
final previous value the maximum could never decrease.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control.fuzzy import evaluate, rule_base, sugeno, terms
from jaxsim.control.fuzzy.inference import FuzzySystem
from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.safe_norm import safe_norm
from jaxsim.core.validation import check_finite, check_positive
from jaxsim.estimation.alpha_beta import window_bank

PAPER_MAX_WINDOW = 10  # J, seed 003 section 4
PAPER_SLOPE = 5.0  # a
PAPER_CENTRE = 1.5  # c
PAPER_CLIP = 3.0  # L clipped at 3 (the universe [0, 3])
T_NORMS = ("product", "min")


def check_max_window(max_window: Any) -> int:
    """``J`` as an int; ``ValueError`` if the window range ``2..J`` is empty (``J < 2``)."""
    if isinstance(max_window, bool) or not isinstance(max_window, (int, np.integer)):
        raise ValueError(f"max_window: must be an integer J ≥ 2, got {max_window!r}")
    if int(max_window) < 2:
        raise ValueError(f"max_window: the window range 2..J is empty for J = {int(max_window)} (need J ≥ 2)")
    return int(max_window)


# -----------------------------------------------------------------------------------------------
# 1. the bank of growing-memory α–β filters


class WindowBank(NamedTuple):
    """Bank outputs over ``T`` scans for the windows ``j = 2..J`` (axis 1, index ``j − 2``).

    positions, velocities: ``(T, J − 1, 2)`` estimates at scan ``t`` from the last ``j`` plots;
    predictions: ``(T, J − 1, 2)`` one-scan predictions for scan ``t + 1``;
    residuals: ``(T, J − 1)`` ``Δz⁽ʲ⁾_t`` (0 where not ``valid``); valid: ``(T,)`` ``t ≥ 2``.
    """

    positions: jax.Array
    velocities: jax.Array
    predictions: jax.Array
    residuals: jax.Array
    valid: jax.Array


def window_bank_filter(z: Any, max_window: int, dt: Any) -> WindowBank:
    """Run the bank on plots ``z (T, 2)`` (m) taken every ``dt`` (s).

    Every window is the growing-memory α–β recursion restarted ``j`` plots back, i.e. the
    least-squares line through those plots: :func:`~jaxsim.estimation.alpha_beta.window_bank` on the
    last ``J`` plots of every scan (vmapped over scans).  A track younger than ``j`` scans uses all
    ``t + 1`` plots so far (window ``min(j, t + 1)``); the first plot is its own estimate, velocity 0.
    """
    big_j = check_max_window(max_window)
    check_positive("dt", dt)
    z = jnp.asarray(z, float)
    if z.ndim != 2 or z.shape[-1] != 2 or z.shape[0] < 1:
        raise ValueError(f"z: expected plots of shape (T, 2) with T ≥ 1, got {tuple(z.shape)}")
    n_scans = z.shape[0]
    t = np.arange(n_scans)[:, None]
    idx = t - big_j + 1 + np.arange(big_j)[None, :]  # (T, J): buffer slots, oldest first
    fits = jax.vmap(lambda last: window_bank(last, dt))(z[np.maximum(idx, 0)])  # (T, J − 1, 2, 2)
    # window min(j, t + 1) never reaches the padded slots (index < 0) of a young track
    used = np.maximum(np.minimum(np.arange(2, big_j + 1)[None, :], t + 1), 2) - 2  # (T, J − 1)
    fits = fits[t, used]
    first = (t == 0)[..., None]
    pos = jnp.where(first, z[:, None, :], fits[:, :, 0])
    vel = jnp.where(first, 0.0, fits[:, :, 1])
    pred = pos + vel * dt
    prev = jnp.concatenate([pred[:1], pred[:-1]], axis=0)
    valid = jnp.asarray(np.arange(n_scans) >= 2)
    resid = safe_norm(z[:, None, :] - prev)
    return WindowBank(pos, vel, pred, jnp.where(valid[:, None], resid, 0.0), valid)


# -----------------------------------------------------------------------------------------------
# 2. the fuzzy selector


@pytree_dataclass
class WindowSelector:
    """Parameters of the selector (array leaves are tunable).

    slopes ``a_j`` and centres ``c_j`` ``(J − 1,)`` of the good/bad sigmoids of inputs ``j = 2..J``;
    ``outputs (J,)`` the rule consequents (``[J, J − 1, …, 2, 2]``); ``kappa`` the σ̂ normaliser;
    ``clip`` the input ceiling (3); static ``tnorm`` ("product" or "min").
    """

    slopes: Any
    centres: Any
    outputs: Any
    kappa: Any = 1.0
    clip: Any = PAPER_CLIP
    tnorm: str = static_field(default="product")

    @property
    def max_window(self) -> int:
        return int(np.shape(self.slopes)[0]) + 1


def window_selector(
    max_window: int = PAPER_MAX_WINDOW,
    slope: Any = PAPER_SLOPE,
    centre: Any = PAPER_CENTRE,
    *,
    kappa: Any = 1.0,
    clip: Any = PAPER_CLIP,
    tnorm: str = "product",
) -> WindowSelector:
    """The paper's selector (J = 10, a = 5, c = 1.5); ``slope``/``centre`` scalars or ``(J − 1,)``.

    Raises:
        ValueError: empty window range (``J < 2``), non-positive slopes, ``kappa`` or ``clip``,
            non-finite centres, unknown ``tnorm``.
    """
    big_j = check_max_window(max_window)
    if tnorm not in T_NORMS:
        raise ValueError(f"tnorm: must be one of {T_NORMS}, got {tnorm!r}")
    for name, v in (("slope", slope), ("centre", centre)):
        if np.shape(v) not in ((), (big_j - 1,)):
            raise ValueError(
                f"{name}: expected a scalar or shape ({big_j - 1},) for max_window={big_j}, got shape {np.shape(v)}"
            )
    a = jnp.broadcast_to(jnp.asarray(slope, float), (big_j - 1,))
    c = jnp.broadcast_to(jnp.asarray(centre, float), (big_j - 1,))
    check_positive("slope", a)
    check_finite("centre", c)
    check_positive("kappa", kappa)
    check_positive("clip", clip)
    outputs = jnp.asarray(list(range(big_j, 1, -1)) + [2], float)
    return WindowSelector(a, c, outputs, jnp.asarray(kappa, float), jnp.asarray(clip, float), tnorm)


def selector_rules(max_window: int):
    """The paper's rule table: ``p = J…2`` (inputs 2..p good, p+1..J bad ⇒ ``m = p``, consequent
    index ``J − p`` into :attr:`WindowSelector.outputs`) and the all-bad rule (index ``J − 1``,
    ``m = 2``); term 0 = good, 1 = bad."""
    big_j = check_max_window(max_window)
    n = big_j - 1
    ant = [[0] * (p - 1) + [1] * (big_j - p) for p in range(big_j, 1, -1)] + [[1] * n]
    return rule_base(ant, list(range(big_j)))


def selector_fis(sel: WindowSelector) -> FuzzySystem:
    """The selector's zero-order Sugeno system over the ``J − 1`` inputs ``L⁽²⁾…L⁽ᴶ⁾``."""
    a, c = jnp.asarray(sel.slopes), jnp.asarray(sel.centres)
    inputs = [
        terms("sigmoid", jnp.stack([jnp.stack([c[i], -a[i]]), jnp.stack([c[i], a[i]])]))
        for i in range(sel.max_window - 1)
    ]
    return sugeno(inputs, sel.outputs, selector_rules(sel.max_window), and_norm=sel.tnorm)


def noise_scale(residuals: Any, valid: Any, kappa: Any = 1.0) -> jax.Array:
    """Running ``σ̂_t = mean(Δz⁽²⁾ over valid scans ≤ t)/κ`` ``(T,)`` (0 before the first valid scan)."""
    r2 = jnp.where(valid, jnp.asarray(residuals)[:, 0], 0.0)
    n = jnp.cumsum(jnp.asarray(valid, float))
    return jnp.cumsum(r2) / jnp.maximum(n, 1.0) / kappa


class Selection(NamedTuple):
    """Selector outputs over ``T`` scans: ``sigma_hat (T,)``, inputs ``L (T, J − 1)``, raw Sugeno
    output ``m_raw (T,)``, final ``m (T,)`` (integer-valued in the exact form), window weights
    ``weights (T, J − 1)`` (one-hot in the exact form)."""

    sigma_hat: jax.Array
    L: jax.Array
    m_raw: jax.Array
    m: jax.Array
    weights: jax.Array


def select_windows(
    sel: WindowSelector, bank: WindowBank, *, smooth: bool = False, temperature: Any = 0.25
) -> Selection:
    """The window chosen at every scan (before the third plot: window 2, i.e. every plot so far)."""
    big_j = sel.max_window
    if bank.residuals.shape[-1] != big_j - 1:
        raise ValueError(f"bank: has {bank.residuals.shape[-1] + 1} as J, the selector {big_j}")
    if smooth:
        check_positive("temperature", temperature)
    sigma = noise_scale(bank.residuals, bank.valid, sel.kappa)
    tiny = jnp.finfo(sigma.dtype).tiny
    L = jnp.minimum(bank.residuals / jnp.maximum(sigma, tiny)[:, None], sel.clip)
    fis = selector_fis(sel)
    m_raw = jnp.where(bank.valid, jax.vmap(lambda x: evaluate(fis, x))(L), 2.0)
    m_prev = jnp.concatenate([m_raw[:1], m_raw[:-1]])
    windows = jnp.arange(2, big_j + 1, dtype=m_raw.dtype)
    if smooth:
        m = temperature * jnp.logaddexp(m_raw / temperature, m_prev / temperature)
        weights = jax.nn.softmax(-((m[:, None] - windows) ** 2) / (2.0 * temperature**2), axis=-1)
    else:
        m = jnp.clip(jnp.floor(jnp.maximum(m_raw, m_prev) + 0.5), 2, big_j)
        weights = (windows[None, :] == m[:, None]).astype(m_raw.dtype)
    return Selection(sigma, L, m_raw, m, weights)


def fixed_window(bank: WindowBank, window: int) -> jax.Array:
    """One-hot weights ``(T, J − 1)`` selecting the same window at every scan."""
    big_j = bank.residuals.shape[-1] + 1
    if isinstance(window, bool) or not isinstance(window, (int, np.integer)) or not 2 <= int(window) <= big_j:
        raise ValueError(f"window: must be an integer in 2..{big_j}, got {window!r}")
    return jnp.broadcast_to(jax.nn.one_hot(int(window) - 2, big_j - 1), bank.residuals.shape)


# -----------------------------------------------------------------------------------------------
# 3. the tracker's output


class TrackEstimate(NamedTuple):
    """``positions``, ``velocities`` ``(T, 2)`` at each scan and ``predictions (T, 2)`` for the next."""

    positions: jax.Array
    velocities: jax.Array
    predictions: jax.Array


def select_estimates(bank: WindowBank, weights: Any) -> TrackEstimate:
    """Blend the bank with window ``weights (T, J − 1)`` (one-hot: pick the chosen window)."""
    w = jnp.asarray(weights)[..., None]
    pick = lambda a: jnp.sum(w * a, axis=-2)  # noqa: E731
    return TrackEstimate(pick(bank.positions), pick(bank.velocities), pick(bank.predictions))


def predicted_plots(estimate: TrackEstimate) -> jax.Array:
    """The prediction each scan's plot is gated against ``(T, 2)`` (row 0 repeats row 0's prediction;
    mask the first scans out of any gate statistic)."""
    p = estimate.predictions
    return jnp.concatenate([p[:1], p[:-1]], axis=0)
