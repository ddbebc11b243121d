"""max_along/min_along: the value of jnp.max/min and JAX's derivative wherever that is finite (the
case where it is not — a recomputed operand rounded differently — is exercised through the fuzzy
centroid in ``tests/control/fuzzy/test_gradient_under_other_rounding.py``)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.core.robust_extrema import max_along, min_along


@pytest.mark.parametrize("axis", [0, 1])
def test_value_and_derivative_equal_jax_with_and_without_ties(axis):
    x = jnp.array([[0.3, 0.9, 0.9], [0.1, -0.2, 0.9], [0.3, 0.5, 0.0]])  # ties in both directions
    t = jnp.arange(9.0).reshape(3, 3) - 4.0
    for ours, ref in ((max_along, jnp.max), (min_along, jnp.min)):
        v, dv = jax.jvp(lambda a: ours(a, axis), (x,), (t,))
        rv, rdv = jax.jvp(lambda a: ref(a, axis=axis), (x,), (t,))
        np.testing.assert_array_equal(v, rv)
        np.testing.assert_allclose(dv, rdv, rtol=0, atol=1e-15)
        g = jax.grad(lambda a: jnp.sum(jnp.sin(ours(a, axis))))(x)
        rg = jax.grad(lambda a: jnp.sum(jnp.sin(ref(a, axis=axis))))(x)
        np.testing.assert_allclose(g, rg, rtol=0, atol=1e-15)
