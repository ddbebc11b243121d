import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.core.loops import fori


def _body(i, x):
    return 0.5 * x + jnp.sin(x) * i


@pytest.mark.parametrize("lower, upper", [(0, 0), (1, 1), (3, 2), (0, 1), (2, 3), (0, 5), (1, 4)])
def test_fori_equals_lax_fori_loop_and_loops_only_for_two_trips_or_more(lower, upper):
    x0 = jnp.array([0.3, -1.2])
    np.testing.assert_array_equal(
        np.asarray(fori(lower, upper, _body, x0)), np.asarray(jax.lax.fori_loop(lower, upper, _body, x0))
    )
    prims = {e.primitive.name for e in jax.make_jaxpr(lambda x: fori(lower, upper, _body, x))(x0).eqns}
    assert bool(prims & {"scan", "while"}) == (upper - lower >= 2)
