"""Synthetic field maps and bilinear look-up (jaxsim.plants.geophysical_map) against closed forms."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

import jaxsim  # noqa: F401  (float64)
from jaxsim.plants import geophysical_map as gm

SP, N = 100.0, 24
ORIGIN = jnp.array([-500.0, 300.0])


def test_bilinear_is_exact_on_a_plane_and_matches_scipy_on_a_random_grid():
    rng = np.random.default_rng(0)
    x = ORIGIN[0] + SP * np.arange(N)
    y = ORIGIN[1] + SP * np.arange(N)
    plane = 2.0 + 0.3 * x[None, :] - 0.7 * y[:, None]
    rough = rng.normal(size=(N, N))
    pts = np.stack([rng.uniform(x[0], x[-1], 40), rng.uniform(y[0], y[-1], 40)], 1)
    got = np.asarray(jax.jit(gm.bilinear, static_argnums=2)(jnp.stack([plane, rough]), ORIGIN, SP, jnp.asarray(pts)))
    np.testing.assert_allclose(got[:, 0], 2.0 + 0.3 * pts[:, 0] - 0.7 * pts[:, 1], rtol=1e-12)
    ref = RegularGridInterpolator((y, x), rough)(pts[:, ::-1])
    np.testing.assert_allclose(got[:, 1], ref, rtol=1e-12, atol=1e-12)
    jac = np.asarray(
        jax.jit(gm.bilinear_jacobian, static_argnums=2)(jnp.asarray(plane)[None], ORIGIN, SP, jnp.asarray(pts))
    )
    np.testing.assert_allclose(jac[:, 0], np.broadcast_to([0.3, -0.7], (40, 2)), rtol=1e-12)


def test_random_field_has_the_prescribed_mean_gradient_and_vmaps_over_keys():
    keys = jax.random.split(jax.random.PRNGKey(3), 3)
    grf = lambda k, ell: gm.gaussian_random_field(k, (N, N), SP, ell, 2e-3)  # noqa: E731
    ells = jnp.array([400.0, 400.0, 400.0, 800.0])
    batch = jax.jit(jax.vmap(grf))(jnp.concatenate([keys, keys[:1]]), ells)
    np.testing.assert_allclose(np.asarray(gm.mean_gradient_modulus(batch, SP)), 2e-3, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(batch[1]), np.asarray(jax.jit(grf)(keys[1], 400.0)), rtol=1e-10, atol=1e-13)
    # a longer correlation length gives a smoother field: smaller mean |∂²f/∂y²| at equal mean |∇f|
    lap = np.mean(np.abs(np.diff(np.asarray(batch), 2, axis=1)), axis=(1, 2))
    assert lap[3] < lap[0]


def test_bad_input_raises():
    with pytest.raises(ValueError, match="corr_length"):
        gm.gaussian_random_field(jax.random.PRNGKey(0), (N, N), SP, -1.0, 1.0)
    with pytest.raises(ValueError, match="shape"):
        gm.gaussian_random_field(jax.random.PRNGKey(0), (2, N), SP, 1.0, 1.0)
