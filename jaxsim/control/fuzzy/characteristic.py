"""The fuzzy-PID paper's approximated static characteristic of a fuzzy controller (FC).

Seed 000, paper 1 (spec §1.2, Fig. 2, curve 2): an odd-symmetric characteristic with three sections,

    u(e) = K1·e                         |e| ≤ a        K1 = b/a        ("small" gain)
         = sign(e)·(b + K2·(|e| − a))   a < |e| ≤ c    K2 = (d − b)/(c − a)  ("large" gain)
         = sign(e)·d                    |e| > c        (saturation)

with breakpoints ``0 < a < c`` (error units) and levels ``0 < b ≤ d`` (control units).

Two forms, same parameters:

* ``form="exact"`` — the formula above (kinks at ``±a``, ``±c``; gradients exist away from them);
* ``form="smooth"`` — the same function written with ramps,
  ``u = K1 e + (K2 − K1)(r(e − a) − r(−e − a)) − K2 (r(e − c) − r(−e − c))``, where the ramp
  ``r(x) = max(x, 0)`` is replaced by ``τ·softplus(x/τ)`` (``temperature`` τ in error units).  It is
  odd and smooth, and equals the exact form up to ``O(τ)`` near the corners (≤ ``τ·ln2·|K2 − K1|``
  at ``±a``); use it on the gradient path and the exact form for reporting.

:class:`Linear` (``u = k·e``) is the linear controller's characteristic, so linear and fuzzy
channels are interchangeable in :mod:`.controller` and the steady-state analysis.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.validation import check_finite, check_positive, is_concrete


@pytree_dataclass
class ThreeSection:
    """Breakpoints ``a < c``, levels ``b ≤ d`` (all > 0); build with :func:`three_section`."""

    a: Any
    b: Any
    c: Any
    d: Any
    temperature: Any = 0.01
    form: str = static_field(default="exact")

    @property
    def k1(self) -> jax.Array:
        """Small-signal gain ``b/a``."""
        return jnp.asarray(self.b) / self.a

    @property
    def k2(self) -> jax.Array:
        """Gain of the second section ``(d − b)/(c − a)``."""
        return (jnp.asarray(self.d) - self.b) / (jnp.asarray(self.c) - self.a)

    def __call__(self, e: Any) -> jax.Array:
        e = jnp.asarray(e)
        return exact_value(self, e) if self.form == "exact" else smooth_value(self, e)


def exact_value(p: ThreeSection, e: jax.Array) -> jax.Array:
    """The exact three-section characteristic, element-wise."""
    x = jnp.abs(e)
    outer = jnp.sign(e) * jnp.where(x <= p.c, p.b + p.k2 * (x - p.a), p.d)
    return jnp.where(x <= p.a, p.k1 * e, outer)  # k1·e (not sign·|e|): the right slope at e = 0


def _soft_ramp(x: jax.Array, tau: Any) -> jax.Array:
    return tau * jax.nn.softplus(x / tau)


def smooth_value(p: ThreeSection, e: jax.Array) -> jax.Array:
    """The smooth (softplus-ramp) form, element-wise; odd, ``u(0) = 0`` exactly."""
    tau = p.temperature
    odd_ramp = lambda t: _soft_ramp(e - t, tau) - _soft_ramp(-e - t, tau)  # noqa: E731
    return p.k1 * e + (p.k2 - p.k1) * odd_ramp(p.a) - p.k2 * odd_ramp(p.c)


def validate_three_section(a: Any, b: Any, c: Any, d: Any) -> None:
    """Raise ``ValueError`` naming the offending breakpoint (skipped for traced values)."""
    for name, v in (("a", a), ("b", b), ("c", c), ("d", d)):
        check_finite(name, v)
        check_positive(name, v)
    if not is_concrete((a, b, c, d)):
        return
    if np.any(np.asarray(a) >= np.asarray(c)):
        raise ValueError(f"a: the first breakpoint must be below the second (a < c), got a={a!r}, c={c!r}")
    if np.any(np.asarray(d) < np.asarray(b)):
        raise ValueError(f"d: the saturation level must not be below b (d ≥ b), got b={b!r}, d={d!r}")


def three_section(a: Any, b: Any, c: Any, d: Any, *, form: str = "exact", temperature: Any = 0.01) -> ThreeSection:
    """A validated :class:`ThreeSection`; the paper's static-plant FC is ``three_section(0.75, 0.3, 1.2, 1.0)``.

    Raises:
        ValueError: a non-positive or non-finite value (named), ``a ≥ c`` (named ``a``), ``d < b``
            (named ``d``), unknown ``form``, non-positive ``temperature``.
    """
    if form not in ("exact", "smooth"):
        raise ValueError(f"form: must be 'exact' or 'smooth', got {form!r}")
    validate_three_section(a, b, c, d)
    check_positive("temperature", temperature)
    f = lambda v: jnp.asarray(v, float)  # noqa: E731
    return ThreeSection(f(a), f(b), f(c), f(d), f(temperature), form)


def from_gains(k1: Any, k2: Any, a: Any, c: Any, **kwargs: Any) -> ThreeSection:
    """The characteristic with gains ``K1``, ``K2`` and breakpoints ``a < c``: ``b = K1 a``, ``d = b + K2 (c − a)``."""
    xp = np if is_concrete((k1, k2, a, c)) else jnp  # concrete: plain NumPy, no XLA dispatch
    b = xp.asarray(k1, float) * a
    return three_section(a, b, c, b + xp.asarray(k2, float) * (xp.asarray(c, float) - a), **kwargs)


@pytree_dataclass
class Linear:
    """The linear characteristic ``u = gain·e`` (a linear P, I or D channel)."""

    gain: Any

    def __call__(self, e: Any) -> jax.Array:
        return self.gain * jnp.asarray(e)


def linear(gain: Any) -> Linear:
    """A validated :class:`Linear` characteristic."""
    check_finite("gain", gain)
    return Linear(jnp.asarray(gain, float))
