"""Five-term Allan-variance fits: exact recovery on noise-free model data, term selection, the
gradient of the loss against finite differences, and NEES consistency of the Hessian covariance on
data drawn exactly as the fit assumes (σ̂² = σ²·χ²_ν/ν, independent over τ)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import stats

from jaxsim.inertial.allan_fit import _log_loss, avar_dof, avar_model, design_matrix, fit_gradient, fit_wls
from jaxsim.inertial.sensor_errors import GyroNoise

DT = 0.01
SIZES = np.array([2**k for k in range(17)])
TAU = SIZES * DT
DOF = np.asarray(avar_dof(2**19, SIZES))
C_TRUE = np.asarray(GyroNoise().as_array())


def test_noise_free_model_data_is_recovered():
    avar = np.asarray(avar_model(TAU, C_TRUE, DT))
    wls = fit_wls(TAU, avar, DOF, DT)
    np.testing.assert_allclose(wls.coeffs, C_TRUE, rtol=1e-7)
    grad = fit_gradient(TAU, avar, DOF, DT, steps=4000)
    np.testing.assert_allclose(grad.coeffs, C_TRUE, rtol=2e-3)
    assert float(grad.loss) < 1e-4
    # model = design matrix @ squares; the sampling term is K²dt²/(6τ)
    a0, a1 = design_matrix(TAU, DT, False), design_matrix(TAU, DT, True)
    np.testing.assert_allclose(a1[:, 1] - a0[:, 1], DT**2 / (6 * TAU), rtol=1e-12, atol=1e-13)  # τ/3 cancels


def test_term_subset_and_sampling_term():
    """Pure random-walk expectation: a (K, N) fit without the sampling term finds N² = K²dt²/6."""
    k2 = 0.4
    avar = k2 * TAU / 3 + k2 * DT**2 / (6 * TAU)
    with_term = fit_wls(TAU, avar, DOF, DT, terms="KN")
    without = fit_wls(TAU, avar, DOF, DT, terms="NK", sampling_correction=False)
    np.testing.assert_allclose(with_term.p, [0, k2, 0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(without.p, [0, k2, 0, k2 * DT**2 / 6, 0], rtol=1e-9, atol=1e-14)
    g = fit_gradient(TAU, avar, DOF, DT, terms="K", steps=1500)
    assert g.coeffs[1] == pytest.approx(np.sqrt(k2), rel=1e-3)
    assert np.isnan(g.cov_log_p[0, 0]) and np.isfinite(g.cov_log_p[1, 1])


def test_gradient_of_the_loss_equals_finite_differences():
    a = design_matrix(TAU, DT)
    rng = np.random.default_rng(0)
    avar = np.asarray(a @ C_TRUE**2) * np.exp(0.1 * rng.standard_normal(len(TAU)))
    z = jnp.log(jnp.asarray(C_TRUE**2)) + 0.2
    g = jax.grad(_log_loss)(z, a, avar, DOF)
    h = 1e-6
    loss = lambda zz: float(_log_loss(zz, a, avar, DOF))  # noqa: E731
    fd = [(loss(z.at[i].add(h)) - loss(z.at[i].add(-h))) / (2 * h) for i in range(5)]
    np.testing.assert_allclose(g, fd, rtol=1e-5)


def test_hessian_covariance_is_nees_consistent_on_chi2_data():
    """σ̂²_j = σ²_j·χ²_ν/ν independent over τ (the fit's own assumption): the mean NEES of log p over
    200 fits lies in the 99 % χ²(5·200)/200 band."""
    runs = 200
    # fewer degrees of freedom than a real record so that the errors are visible, τ where all terms matter
    dof = jnp.asarray(np.maximum(DOF / 64, 3.0))
    model = np.asarray(avar_model(TAU, C_TRUE, DT))
    p_true = C_TRUE**2

    @jax.jit
    def one(k):
        avar = model * jax.random.chisquare(k, dof) / dof
        fit = fit_gradient(TAU, avar, dof, DT, init=p_true, steps=1500, learning_rate=0.02)
        e = jnp.log(fit.p) - jnp.log(p_true)
        return e @ jnp.linalg.solve(fit.cov_log_p, e)

    nees = np.asarray(jax.vmap(one)(jax.random.split(jax.random.PRNGKey(5), runs)))
    lo, hi = stats.chi2.ppf([0.005, 0.995], 5 * runs) / runs
    assert lo <= nees.mean() <= hi, nees.mean()


def test_bad_inputs_name_the_argument():
    avar = np.asarray(avar_model(TAU, C_TRUE, DT))
    with pytest.raises(ValueError, match="^terms:"):
        fit_wls(TAU, avar, DOF, DT, terms="KX")
    with pytest.raises(ValueError, match="^avar:"):
        fit_wls(TAU, avar[:-1], DOF, DT)
    with pytest.raises(ValueError, match="^avar:"):
        fit_gradient(TAU, -avar, DOF, DT)
    with pytest.raises(ValueError, match="^init:"):
        fit_gradient(TAU, avar, DOF, DT, init=np.ones(4))
