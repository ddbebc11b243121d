"""Map-matching estimator (jaxsim.estimation.map_matching): the bias-marginal likelihood against SciPy,
and on planar maps (a linear-Gaussian problem) the Monte-Carlo posterior against the exact Kalman one."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.stats import multivariate_normal

import jaxsim  # noqa: F401  (float64)
from jaxsim.estimation import map_matching as mm
from jaxsim.plants import geophysical_map as gm


def test_marginal_likelihood_equals_the_full_gaussian():
    rng = np.random.default_rng(1)
    r = rng.normal(size=(2, 7))
    sc, sw = np.array([0.5, 2.0]), np.array([0.3, 1.5])
    got = float(mm.marginal_log_likelihood(jnp.asarray(r), sc, sw, jnp.array([1.0, 1.0])))
    ref = sum(
        multivariate_normal(np.zeros(7), sw[f] ** 2 * np.eye(7) + sc[f] ** 2 * np.ones((7, 7))).logpdf(r[f])
        for f in range(2)
    )
    assert got == pytest.approx(ref, rel=1e-12)
    only0 = float(mm.marginal_log_likelihood(jnp.asarray(r), sc, sw, jnp.array([1.0, 0.0])))
    assert only0 == pytest.approx(multivariate_normal(np.zeros(7), 0.09 * np.eye(7) + 0.25).logpdf(r[0]), rel=1e-12)


def test_monte_carlo_posterior_matches_the_kalman_posterior_on_planar_maps():
    sp, n = 200.0, 60
    origin = jnp.array([-6000.0, -6000.0])
    xy = origin[0] + sp * np.arange(n)
    grads = np.array([[1e-3, 0.2e-3], [-0.5e-3, 2e-3]])  # two planar fields, units per m
    vals = jnp.asarray(np.stack([g[0] * xy[None, :] + g[1] * xy[:, None] for g in grads]))
    track = jnp.stack([jnp.linspace(-1500.0, 1500.0, 8), jnp.zeros(8)], 1)
    sc, sw, mask, sig = jnp.array([0.3, 1.0]), jnp.array([0.2, 0.5]), jnp.array([1.0, 1.0]), 500.0
    delta = jnp.array([150.0, -220.0])

    @jax.jit
    def estimate(vals, track, delta):  # one compilation for the whole chain
        y = mm.simulate_measurements(jax.random.PRNGKey(2), vals, origin, sp, track, sc, sw)
        post = mm.rb_posterior(jax.random.PRNGKey(3), vals, origin, sp, track + delta, y, sc, sw, mask, sig, 10000)
        jac = gm.bilinear_jacobian(vals, origin, sp, track)
        P = mm.linearised_covariance(jac, sc, sw, mask, sig**2 * jnp.eye(2))
        return y, post, P, gm.bilinear(vals, origin, sp, track + delta)

    y, post, P, phi_ns = estimate(vals, track, delta)
    # exact linear-Gaussian posterior mean by batch least squares over [Δ, c]
    H = np.zeros((16, 4))
    H[:8, :2], H[8:, :2], H[:8, 2], H[8:, 3] = grads[0], grads[1], 1.0, 1.0
    z = np.asarray(y).reshape(-1) - np.asarray(phi_ns).T.reshape(-1)
    P0 = np.diag([sig**2, sig**2, 0.09, 1.0])
    R = np.diag(np.r_[np.full(8, 0.04), np.full(8, 0.25)])
    K = P0 @ H.T @ np.linalg.inv(H @ P0 @ H.T + R)
    Pfull = P0 - K @ H @ P0
    np.testing.assert_allclose(np.asarray(P), Pfull[:2, :2], rtol=1e-9)
    # z = ỹ − φ(y^NS) = −HΔ + c + v: the Kalman posterior mean of Δ is −(K z)[:2]
    mean_ref = -(K @ z)[:2]
    assert float(post.ess) > 200
    np.testing.assert_allclose(
        np.asarray(post.cov), Pfull[:2, :2], rtol=0.15, atol=0.05 * np.sqrt(Pfull[0, 0] * Pfull[1, 1])
    )
    np.testing.assert_allclose(np.asarray(post.mean), mean_ref, atol=0.1 * np.sqrt(np.trace(Pfull[:2, :2])))
    assert float(mm.ellipse_area(P)) == pytest.approx(np.pi * np.sqrt(np.linalg.det(Pfull[:2, :2])), rel=1e-9)


def test_no_field_leaves_the_prior_and_bad_sigma_raises():
    jac = jnp.ones((5, 2, 2))
    P = mm.linearised_covariance(jac, jnp.array([1.0, 1.0]), jnp.array([1.0, 1.0]), jnp.zeros(2), 4.0 * jnp.eye(2))
    np.testing.assert_allclose(np.asarray(P), 4.0 * np.eye(2), rtol=1e-12)
    assert float(mm.radial_rms(P)) == pytest.approx(np.sqrt(8.0))
    with pytest.raises(ValueError, match="sigma_w"):
        mm.linearised_covariance(jac, jnp.array([1.0, 1.0]), jnp.array([0.0, 1.0]), jnp.ones(2), jnp.eye(2))
