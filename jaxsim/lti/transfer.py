"""SISO transfer functions and zero-pole-gain models as LTI plants: python-control's ``tf`` and ``zpk``.

Both return the controller canonical realisation of :func:`jaxsim.core.transfer_function.tf2ss`
(the one ``scipy.signal.tf2ss`` uses) wrapped like :func:`~jaxsim.lti.statespace.ss`: a
:class:`~jaxsim.core.system.Plant` with exact ``D`` in continuous time, a ``StateSpace`` in
discrete time (polynomials then in ``z``).  Coefficients are in descending powers; everything is
``jnp``, so a loss can be differentiated with respect to the coefficients, zeros, poles and gain.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.system import Plant
from jaxsim.core.transfer_function import tf2ss
from jaxsim.core.validation import check_finite, check_real, is_concrete
from jaxsim.lti.statespace import StateSpace, check_dt, state_space, wrap


def _coefficients(name: str, c: Any) -> jax.Array:
    """A 1-D real coefficient array (a scalar is a constant polynomial)."""
    if isinstance(c, (list, tuple)) and any(isinstance(e, (list, tuple, np.ndarray)) for e in c):
        raise ValueError(
            f"{name}: nested coefficient lists (MIMO transfer functions) are not supported; "
            "build MIMO systems with ss, or interconnect SISO ones"
        )
    arr = jnp.asarray(c)
    check_real(name, arr)
    arr = jnp.atleast_1d(arr.astype(jnp.result_type(arr, float)))
    if arr.ndim != 1:
        raise ValueError(
            f"{name}: expected a 1-D array of coefficients (descending powers), got shape {tuple(arr.shape)}"
        )
    if arr.shape[0] == 0:
        raise ValueError(f"{name}: needs at least one coefficient")
    check_finite(name, arr)
    return arr


def _strip_leading_zeros(name: str, c: jax.Array) -> jax.Array:
    """Drop exact leading zeros of a concrete polynomial (a traced one is kept as given)."""
    if not is_concrete(c):
        return c
    nonzero = np.flatnonzero(np.asarray(c) != 0.0)
    if nonzero.size == 0:
        return c[-1:]
    return c[int(nonzero[0]) :]


def tf_state_space(num: Any, den: Any, dt: Any = None) -> StateSpace:
    """The checked :class:`StateSpace` behind :func:`tf`."""
    dt = check_dt(dt)
    num = _strip_leading_zeros("num", _coefficients("num", num))
    den = _strip_leading_zeros("den", _coefficients("den", den))
    if is_concrete(den) and not np.any(np.asarray(den) != 0.0):
        raise ValueError("den: the denominator polynomial is zero")
    if num.shape[0] > den.shape[0]:
        raise ValueError(
            f"num: the transfer function is not proper (numerator degree {num.shape[0] - 1} > "
            f"denominator degree {den.shape[0] - 1}); it has no state-space realisation"
        )
    a, b, c, d = tf2ss(num, den)
    return state_space(a, b, c, d, dt)


def tf(num: Any, den: Any, dt: Any = None) -> Plant | StateSpace:
    """python-control's ``tf(num, den[, dt])`` for a SISO system ``num(s)/den(s)``.

    Args:
        num: numerator coefficients, descending powers of ``s`` (or ``z``), 1-D.
        den: denominator coefficients, 1-D, not all zero; ``len(num) ≤ len(den)`` after exact
            leading zeros are dropped (a proper transfer function).
        dt: ``None``/0 for continuous time, else the sampling period in seconds.

    Returns:
        A :class:`Plant` (continuous; ``n = len(den) − 1`` states, exact ``D`` feedthrough) or a
        discrete :class:`StateSpace`.  Under tracing, a zero leading ``den`` coefficient gives NaN.

    Raises:
        ValueError: naming ``num``/``den`` for nested (MIMO) lists, complex, NaN/inf or empty
            coefficients, an improper ratio or a zero denominator; ``dt`` for a bad period.
    """
    return wrap(tf_state_space(num, den, dt))


def _roots(name: str, r: Any) -> jax.Array:
    arr = jnp.atleast_1d(jnp.asarray(r))
    if arr.ndim != 1:
        raise ValueError(f"{name}: expected a 1-D array of roots, got shape {tuple(arr.shape)}")
    arr = arr.astype(jnp.result_type(arr, float))
    check_finite(name, arr)
    if is_concrete(arr) and np.iscomplexobj(np.asarray(arr)):
        v = np.asarray(arr)
        upper, lower = np.sort_complex(v[v.imag > 0]), np.sort_complex(np.conj(v[v.imag < 0]))
        if upper.shape != lower.shape or not np.allclose(upper, lower, rtol=1e-10, atol=1e-12):
            raise ValueError(f"{name}: complex roots must come in conjugate pairs (a real system), got {v!r}")
    return arr


def poly_from_roots(roots: jax.Array) -> jax.Array:
    """Monic polynomial ``Π (s − rᵢ)``, descending powers, real part (roots in conjugate pairs)."""
    coeffs = jnp.ones((1,), dtype=jnp.result_type(roots, float))
    for i in range(roots.shape[0]):
        coeffs = jnp.convolve(coeffs, jnp.stack([jnp.ones((), roots.dtype), -roots[i]]))
    return jnp.real(coeffs)


def zpk(zeros: Any, poles: Any, gain: Any, dt: Any = None) -> Plant | StateSpace:
    """python-control's ``zpk(zeros, poles, gain[, dt])``: ``k Π(s − zᵢ) / Π(s − pⱼ)``.

    Args:
        zeros: ``(nz,)`` finite zeros (complex ones in conjugate pairs).
        poles: ``(n,)`` poles, ``n ≥ nz`` (complex ones in conjugate pairs).
        gain: scalar ``k`` (the leading-coefficient ratio, not the DC gain).
        dt: as :func:`tf`.

    Raises:
        ValueError: naming ``zeros``/``poles``/``gain`` for bad shapes, NaN/inf, unpaired complex
            roots, more zeros than poles.
    """
    z = _roots("zeros", zeros)
    p = _roots("poles", poles)
    k = jnp.asarray(gain)
    if k.ndim != 0:
        raise ValueError(f"gain: expected a scalar, got shape {tuple(k.shape)}")
    check_real("gain", k)
    check_finite("gain", k)
    if z.shape[0] > p.shape[0]:
        raise ValueError(f"zeros: more zeros ({z.shape[0]}) than poles ({p.shape[0]}): the system is not proper")
    return tf(k * poly_from_roots(z), poly_from_roots(p), dt)
