"""Nonlinear state-space model for the extended and sigma-point filters.

``x_{t+1} = f(params, x_t, u_t) + w_t``, ``w_t ~ N(0, Q)``; ``y_t = h(params, x_t) + v_t``,
``v_t ~ N(0, R)``; ``x_0 ~ N(m0, P0)``.  ``u_t`` is ``None`` when the filter is run without inputs.
``params`` is any pytree (tunable, vmappable); ``f`` and ``h`` are static (part of the jit key).
"""

from __future__ import annotations

from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, replace, static_field
from jaxsim.core.validation import check_covariance, check_finite
from jaxsim.precision import to_common_float


@pytree_dataclass
class NonlinearSSM:
    """``params`` pytree, ``Q (n, n)``, ``R (p, p)``, ``m0 (n,)``, ``P0 (n, n)``; static ``transition``
    ``f(params, x, u) -> x_next`` and ``observation`` ``h(params, x) -> y``."""

    params: Any
    Q: jax.Array
    R: jax.Array
    m0: jax.Array
    P0: jax.Array
    transition: Callable[[Any, jax.Array, Any], jax.Array] = static_field()
    observation: Callable[[Any, jax.Array], jax.Array] = static_field()

    @property
    def n_states(self) -> int:
        return int(np.shape(self.m0)[-1])

    @property
    def n_outputs(self) -> int:
        return int(np.shape(self.R)[-1])

    def f(self, x: jax.Array, u: Any = None) -> jax.Array:
        return self.transition(self.params, x, u)

    def h(self, x: jax.Array) -> jax.Array:
        return self.observation(self.params, x)


def nonlinear_ssm(
    transition: Callable, observation: Callable, Q: Any, R: Any, m0: Any, P0: Any, params: Any = None
) -> NonlinearSSM:
    """Build and validate a :class:`NonlinearSSM`."""
    model = NonlinearSSM(
        params, jnp.asarray(Q), jnp.asarray(R), jnp.asarray(m0), jnp.asarray(P0), transition, observation
    )
    validate_nonlinear(model)
    return model


def validate_nonlinear(model: NonlinearSSM) -> None:
    """Shapes and PSD of ``Q, R, P0``; output shapes of ``h`` and of ``f`` (when it accepts ``u=None``)."""
    if np.ndim(model.m0) != 1:
        raise ValueError(f"m0: expected shape (n,), got {tuple(np.shape(model.m0))}")
    n = model.n_states
    check_finite("m0", model.m0)
    check_covariance("P0", model.P0, n)
    check_covariance("Q", model.Q, n)
    check_covariance("R", model.R)
    x = jax.ShapeDtypeStruct((n,), jnp.result_type(model.m0, float))
    try:  # a transition that needs an input cannot be shape-checked without one
        fx = jax.eval_shape(lambda z: model.f(z), x)
    except (TypeError, AttributeError, IndexError):
        fx = None
    if fx is not None and fx.shape != (n,):
        raise ValueError(f"transition: must return shape ({n},), returned {fx.shape}")
    hx = jax.eval_shape(lambda z: model.h(z), x)
    if hx.shape != (model.n_outputs,):
        raise ValueError(f"observation: must return shape ({model.n_outputs},) to match R, returned {hx.shape}")


def common_float_nonlinear(
    model: NonlinearSSM, y: Any, u: Any = None, extra: Any = None
) -> tuple[NonlinearSSM, jax.Array, Any, Any]:
    """``model`` (``Q, R, m0, P0`` and the float leaves of ``params``), ``y``, ``u`` and the float
    leaves of ``extra`` (a sigma-point scheme, say) in one float dtype
    (:func:`jaxsim.precision.to_common_float`); returns ``(model, y, u, extra)``."""
    data = (model.Q, model.R, model.m0, model.P0, jnp.asarray(y), None if u is None else jnp.asarray(u))
    (Q, R, m0, P0, y, u), (params, extra) = to_common_float(data, (model.params, extra))
    return replace(model, params=params, Q=Q, R=R, m0=m0, P0=P0), y, u, extra
