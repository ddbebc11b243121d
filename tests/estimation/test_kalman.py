"""Linear Kalman filter: FilterPy and dynamax as oracles, forms, time variation, masking, bad input."""

from __future__ import annotations

import functools

import dynamax.linear_gaussian_ssm.inference as dyn
import filterpy.kalman
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from dynamax.utils.utils import psd_solve

from jaxsim.estimation import kalman
from jaxsim.estimation.lgssm import kalman_filter, lgssm, sample
from jaxsim.estimation.types import GaussianState
from tests.estimation.helpers import filterpy_kalman, random_model, random_time_varying, simulate_np


def test_filter_matches_filterpy_step_by_step():
    rng = np.random.default_rng(0)
    model = random_model(rng, n=4, p=2, m=1)
    u = rng.standard_normal((30, 1))
    _, y = simulate_np(model, rng, 30, u)
    ours = kalman_filter(model, y, u)

    kf = filterpy.kalman.KalmanFilter(dim_x=4, dim_z=2, dim_u=1)
    kf.F, kf.Q, kf.H, kf.R, kf.B = (np.asarray(v) for v in (model.F, model.Q, model.H, model.R, model.B))
    kf.x, kf.P = np.asarray(model.m0)[:, None].copy(), np.asarray(model.P0).copy()
    means, covs, lls = [], [], []
    for t in range(30):
        kf.update(y[t][:, None])
        means.append(kf.x[:, 0].copy())
        covs.append(kf.P.copy())
        lls.append(kf.log_likelihood)
        kf.predict(u[t][:, None])
    np.testing.assert_allclose(ours.means, means, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(ours.covs, covs, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(ours.log_likelihoods, lls, rtol=1e-9, atol=1e-9)


def test_log_likelihood_matches_dynamax():
    rng = np.random.default_rng(1)
    model = random_model(rng, n=4, p=2, m=1)
    u = rng.standard_normal((40, 1))
    _, y = simulate_np(model, rng, 40, u)
    ours = kalman_filter(model, y, u)
    params = dyn.make_lgssm_params(
        model.m0, model.P0, model.F, model.Q, model.H, model.R, dynamics_input_weights=model.B
    )
    # dynamax's input u[t+1] drives the transition into t+1; ours u[t] drives t → t+1.
    u_dyn = jnp.concatenate([jnp.zeros((1, 1)), jnp.asarray(u[:-1])])
    ref = dyn.lgssm_filter(params, jnp.asarray(y), u_dyn)
    np.testing.assert_allclose(ours.log_likelihood, ref.marginal_loglik, rtol=1e-9)
    # dynamax adds 1e-9·I to S inside its gain solve (psd_solve's diagonal_boost); with the boost
    # off, its filtered moments must equal ours to rounding.
    orig = dyn.psd_solve
    dyn.psd_solve = functools.partial(psd_solve, diagonal_boost=0.0)
    try:
        exact = dyn.lgssm_filter(params, jnp.asarray(y), u_dyn)
    finally:
        dyn.psd_solve = orig
    np.testing.assert_allclose(ours.means, exact.filtered_means, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(ours.covs, exact.filtered_covariances, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(ours.log_likelihood, exact.marginal_loglik, rtol=1e-12)


@pytest.mark.parametrize("form", ["standard", "sqrt"])
def test_update_forms_agree_with_joseph(form):
    rng = np.random.default_rng(2)
    model = random_model(rng, n=5, p=3, m=2)
    u = rng.standard_normal((25, 2))
    _, y = simulate_np(model, rng, 25, u)
    mask = rng.random((25, 3)) > 0.3
    ref = kalman_filter(model, y, u, mask=mask)
    got = kalman_filter(model, y, u, mask=mask, form=form)
    for field in ("means", "covs", "predicted_covs", "log_likelihoods", "nis"):
        np.testing.assert_allclose(getattr(got, field), getattr(ref, field), rtol=1e-9, atol=1e-11)


def test_time_varying_masked_filter_matches_filterpy_step_by_step():
    """``F_t, Q_t, H_t, R_t, B_t`` all vary with ``t``; some steps lose one component, some both
    (the first and the last included).  Oracle: FilterPy's ``KalmanFilter`` fed the per-step
    matrices, updating with the available components only."""
    rng = np.random.default_rng(3)
    t = 14
    model = random_time_varying(rng, t)
    u = rng.standard_normal((t, 1))
    _, y = simulate_np(model, rng, t, u)
    mask = rng.random((t, 2)) > 0.3
    mask[[0, 6, t - 1]] = False
    mask[[2, 9]] = [True, False]
    ref = filterpy_kalman(model, y, u, mask)
    got = kalman_filter(model, np.where(mask, y, np.nan), u, missing="nan")
    for field, want in ref.items():
        np.testing.assert_allclose(np.asarray(getattr(got, field)), want, rtol=1e-10, atol=1e-11, err_msg=field)
    np.testing.assert_allclose(got.log_likelihood, ref["log_likelihoods"].sum(), rtol=1e-11)
    np.testing.assert_array_equal(got.dof, mask.sum(axis=1))
    np.testing.assert_array_equal(got.accepted, mask.any(axis=1))
    # an explicit mask over arbitrary values at the masked entries gives the same run
    same = kalman_filter(model, np.where(mask, y, 1e3), u, mask=mask)
    np.testing.assert_allclose(same.means, got.means, rtol=1e-13, atol=1e-13)


def test_multi_rate_filter_matches_filterpy_on_available_components():
    """Multi-rate: component 0 every step, component 1 every 3rd step (NaN otherwise)."""
    rng = np.random.default_rng(4)
    model = random_model(rng, n=4, p=2)
    _, y = simulate_np(model, rng, 24, None)
    y = y.copy()
    y[np.arange(24) % 3 != 0, 1] = np.nan
    res = kalman_filter(model, y, missing="nan")
    ref = filterpy_kalman(model, y, mask=np.isfinite(y))
    for field, want in ref.items():
        np.testing.assert_allclose(np.asarray(getattr(res, field)), want, rtol=1e-10, atol=1e-11, err_msg=field)
    np.testing.assert_array_equal(res.dof, np.where(np.arange(24) % 3 == 0, 2, 1))
    # a fully masked step is a pure prediction
    full = kalman_filter(model, np.nan_to_num(y), mask=np.arange(24) % 2 == 0)
    np.testing.assert_allclose(full.means[1], full.predicted_means[1], rtol=0, atol=0)
    assert not bool(full.accepted[1]) and bool(full.accepted[0])


def test_vmap_equals_loop():
    rng = np.random.default_rng(5)
    model = random_model(rng, n=3, p=2)
    keys = jax.random.split(jax.random.PRNGKey(0), 6)
    ys = jax.vmap(lambda k: sample(model, k, 20)[1])(keys)
    batched = jax.vmap(lambda y: kalman_filter(model, y))(ys)
    for i in range(6):
        one = kalman_filter(model, ys[i])
        np.testing.assert_allclose(batched.means[i], one.means, rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(batched.log_likelihood[i], one.log_likelihood, rtol=1e-12)
    # vmap over model parameters too (a bank of R values)
    rs = jnp.stack([model.R * s for s in (0.5, 1.0, 2.0)])
    lls = jax.vmap(
        lambda r: kalman_filter(model.__class__(model.F, model.Q, model.H, r, model.m0, model.P0), ys[0]).log_likelihood
    )(rs)
    for s, ll in zip((0.5, 1.0, 2.0), lls):
        m = lgssm(model.F, model.Q, model.H, model.R * s, model.m0, model.P0)
        np.testing.assert_allclose(ll, kalman_filter(m, ys[0]).log_likelihood, rtol=1e-12)


def test_log_likelihood_gradient_matches_finite_differences():
    rng = np.random.default_rng(6)
    model = random_model(rng, n=3, p=1)
    _, y = simulate_np(model, rng, 30, None)

    def ll(log_r):
        m = model.__class__(model.F, model.Q, model.H, jnp.exp(log_r) * jnp.eye(1), model.m0, model.P0)
        return kalman_filter(m, y).log_likelihood

    x0, h = 0.1, 1e-5
    fd = (ll(x0 + h) - ll(x0 - h)) / (2 * h)
    np.testing.assert_allclose(jax.grad(ll)(x0), fd, rtol=1e-6)


def test_joseph_update_stays_symmetric_psd_when_ill_conditioned():
    """Poorly conditioned update: Joseph stays symmetric PSD."""
    P = jnp.diag(jnp.array([1e6, 1e-6]))
    state, _ = kalman.update(
        GaussianState(jnp.zeros(2), P), jnp.array([1.0]), jnp.array([[1.0, 1.0]]), jnp.array([[1e-9]])
    )
    np.testing.assert_allclose(state.cov, state.cov.T, rtol=0, atol=0)
    assert np.min(np.linalg.eigvalsh(np.asarray(state.cov))) > -1e-12


class TestBadInput:
    def setup_method(self):
        rng = np.random.default_rng(7)
        self.model = random_model(rng, n=3, p=2)
        self.y = np.zeros((5, 2))

    def test_non_symmetric_covariance(self):
        q = np.asarray(self.model.Q).copy()
        q[0, 1] += 0.1
        with pytest.raises(ValueError, match="^Q: must be symmetric"):
            lgssm(self.model.F, q, self.model.H, self.model.R, self.model.m0, self.model.P0)

    def test_non_psd_covariance(self):
        with pytest.raises(ValueError, match="^R: must be positive semi-definite"):
            lgssm(self.model.F, self.model.Q, self.model.H, -np.eye(2), self.model.m0, self.model.P0)
        with pytest.raises(ValueError, match="^P0: must be positive semi-definite"):
            lgssm(self.model.F, self.model.Q, self.model.H, self.model.R, self.model.m0, np.diag([1.0, -1.0, 1.0]))

    def test_mismatched_shapes(self):
        with pytest.raises(ValueError, match="^H: expected shape"):
            lgssm(self.model.F, self.model.Q, np.ones((2, 4)), self.model.R, self.model.m0, self.model.P0)
        with pytest.raises(ValueError, match="^y: expected shape"):
            kalman_filter(self.model, np.zeros((5, 3)))
        with pytest.raises(ValueError, match="^mask: expected shape"):
            kalman_filter(self.model, self.y, mask=np.ones((4,), bool))
        with pytest.raises(ValueError, match="^u: given but the model has no input matrix"):
            kalman_filter(self.model, self.y, np.zeros((5, 1)))

    def test_nan_without_mask_policy(self):
        y = self.y.copy()
        y[2, 1] = np.nan
        with pytest.raises(ValueError, match="^y: non-finite value at step 2, component 1"):
            kalman_filter(self.model, y)
        assert np.isfinite(kalman_filter(self.model, y, missing="nan").log_likelihood)
        assert np.isfinite(kalman_filter(self.model, y, mask=np.isfinite(y)).log_likelihood)

    def test_unknown_form(self):
        with pytest.raises(ValueError, match="^form:"):
            kalman_filter(self.model, self.y, form="information")


def test_shared_gain_filter_equals_full_filter_for_every_run():
    from jaxsim.estimation.shared_gain import covariance_sequence, mean_filter

    rng = np.random.default_rng(8)
    model = random_model(rng, n=4, p=2, m=1)
    u = rng.standard_normal((20, 1))
    mask = rng.random((20, 2)) > 0.3
    ys = jax.vmap(lambda k: sample(model, k, 20, u)[1])(jax.random.split(jax.random.PRNGKey(1), 5))
    seq = covariance_sequence(model, 20, mask=mask)
    runs = jax.jit(jax.vmap(lambda y: mean_filter(model, seq, y, u)))(ys)
    for i in range(5):
        ref = kalman_filter(model, ys[i], u, mask=mask)
        np.testing.assert_allclose(runs.means[i], ref.means, rtol=1e-11, atol=1e-12)
        np.testing.assert_allclose(runs.log_likelihood[i], ref.log_likelihood, rtol=1e-12)
    np.testing.assert_allclose(seq.covs, ref.covs, rtol=1e-12)


@pytest.mark.parametrize("k", [1, 2, 3, 4, 6])
def test_unrolled_small_linalg_equals_lapack(k):
    from jaxsim.estimation import linalg

    rng = np.random.default_rng(9 + k)
    a = rng.standard_normal((k, k))
    s = a @ a.T + 0.5 * np.eye(k)
    b, bm = rng.standard_normal(k), rng.standard_normal((k, 3))
    low = np.linalg.cholesky(s)
    np.testing.assert_allclose(linalg.cholesky(jnp.asarray(s)), low, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(linalg.solve_lower(jnp.asarray(low), b), np.linalg.solve(low, b), rtol=1e-10)
    np.testing.assert_allclose(linalg.cho_solve(jnp.asarray(low), bm), np.linalg.solve(s, bm), rtol=1e-9)
    np.testing.assert_allclose(linalg.matmul(jnp.asarray(a), jnp.asarray(bm)), a @ bm, rtol=1e-12, atol=1e-13)
