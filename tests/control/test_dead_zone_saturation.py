"""Dead zone – linear – saturation law: the three zones, continuity, the smooth surrogate's limit and
gradient (vs finite differences)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control.dead_zone_saturation import dead_zone_saturation, smooth_dead_zone_saturation


def test_three_zones_and_odd_symmetry():
    s = jnp.array([0.0, 0.5, 1.0, 1.5, 3.0, 100.0])
    u = np.asarray(dead_zone_saturation(s, 1.0, 2.0, 3.0))
    np.testing.assert_allclose(u, [0.0, 0.0, 0.0, 1.0, 3.0, 3.0])  # dead, dead, edge, linear, saturated (edge at 2.5)
    np.testing.assert_allclose(np.asarray(dead_zone_saturation(-s, 1.0, 2.0, 3.0)), -u)
    fine = jnp.linspace(-5, 5, 20001)
    assert float(jnp.max(jnp.abs(jnp.diff(dead_zone_saturation(fine, 1.0, 2.0, 3.0))))) <= 2.0 * 5e-4 + 1e-12


def test_smooth_surrogate_limit_and_gradient():
    s = jnp.linspace(-4, 4, 81)
    exact = dead_zone_saturation(s, 1.0, 2.0, 3.0)
    for temp, tol in ((1e-2, 0.03), (1e-4, 3e-4)):
        assert float(jnp.max(jnp.abs(smooth_dead_zone_saturation(s, 1.0, 2.0, 3.0, temp) - exact))) < tol
    f = lambda x: smooth_dead_zone_saturation(x, 1.0, 2.0, 3.0, 0.05)  # noqa: E731
    for x in (0.3, 1.2, 2.4, -1.7):
        fd = (f(x + 1e-6) - f(x - 1e-6)) / 2e-6
        assert float(jax.grad(f)(x)) == pytest.approx(float(fd), rel=1e-5, abs=1e-8)


def test_bad_input_raises():
    with pytest.raises(ValueError, match="gain"):
        dead_zone_saturation(1.0, 0.0, -1.0, 1.0)
    with pytest.raises(ValueError, match="dead_zone"):
        dead_zone_saturation(1.0, -0.1, 1.0, 1.0)
