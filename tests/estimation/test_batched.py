"""Batched log-likelihood kernel (jaxsim.estimation.batched): our serial filter, dynamax and FilterPy
as oracles; shared and per-run covariances, masks, inputs, time variation, blocks, vmap, bad input."""

from __future__ import annotations

import functools

import dynamax.linear_gaussian_ssm.inference as dyn
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from dynamax.utils.utils import psd_solve

from jaxsim.core.pytree import replace
from jaxsim.estimation.batched import STEADY_AFTER, _gain_sequence, batched_kalman_loglik, reached_fixed_point
from jaxsim.estimation.lgssm import kalman_filter, lgssm
from tests.estimation.helpers import filterpy_kalman, random_model, random_time_varying

RUNS, T = 5, 23  # T not a multiple of the block sizes used below: the tail block runs too


def _data(seed, model, runs=RUNS, t=T):
    rng = np.random.default_rng(seed)
    return rng.standard_normal((runs, t, model.n_outputs)) * 2.0, rng


def _serial(model, ys, u=None, mask=None, rs=None, qs=None):
    out = []
    for i in range(ys.shape[0]):
        m = model
        if rs is not None:
            m = replace(m, R=m.R * rs[i])
        if qs is not None:
            m = replace(m, Q=m.Q * qs[i])
        out.append(float(kalman_filter(m, ys[i], u, mask=mask).log_likelihood))
    return np.array(out)


@pytest.mark.parametrize("block", [4, 7, 100])
def test_shared_model_with_inputs_and_mask_equals_serial_filter(block):
    model = random_model(np.random.default_rng(0), n=4, p=2, m=1)
    ys, rng = _data(1, model)
    u = rng.standard_normal((T, 1))
    mask = rng.random((T, 2)) > 0.3
    ys = np.where(mask, ys, np.nan)  # masked entries may be NaN
    got = batched_kalman_loglik(model, ys, u, mask=mask, block=block)
    np.testing.assert_allclose(got, _serial(model, ys, u, mask), rtol=1e-12)


@pytest.mark.parametrize("which", ["r", "q", "both"])
def test_per_run_scales_with_mask_equal_serial_filter(which):
    model = random_model(np.random.default_rng(2), n=3, p=2, m=1)
    ys, rng = _data(3, model)
    u = rng.standard_normal((T, 1))
    mask = rng.random(T) > 0.2
    rs = rng.uniform(0.5, 2.0, RUNS) if which in ("r", "both") else None
    qs = rng.uniform(0.5, 2.0, RUNS) if which in ("q", "both") else None
    got = batched_kalman_loglik(model, ys, u, mask=mask, r_scale=rs, q_scale=qs, block=5)
    np.testing.assert_allclose(got, _serial(model, ys, u, mask, rs, qs), rtol=1e-12)


def test_time_varying_model_shared_and_per_run():
    model = random_time_varying(np.random.default_rng(4), T, n=3, p=2, m=1)
    ys, rng = _data(5, model)
    u = rng.standard_normal((T, 1))
    rs = rng.uniform(0.5, 2.0, RUNS)
    np.testing.assert_allclose(batched_kalman_loglik(model, ys, u, block=6), _serial(model, ys, u), rtol=1e-12)
    np.testing.assert_allclose(
        batched_kalman_loglik(model, ys, u, r_scale=rs, block=6), _serial(model, ys, u, rs=rs), rtol=1e-12
    )


def _dynamax_loglik(model, y, s=1.0):
    params = dyn.make_lgssm_params(model.m0, model.P0, model.F, model.Q, model.H, model.R * s)
    return float(dyn.lgssm_filter(params, jnp.asarray(y)).marginal_loglik)


def test_equals_dynamax_to_1e_10_shared_and_per_run():
    model = random_model(np.random.default_rng(6), n=4, p=2)
    ys, rng = _data(7, model, t=40)
    rs = rng.uniform(0.5, 2.0, RUNS)
    # dynamax adds 1e-9·I to S in its gain solve; switched off here so that both compute the exact filter
    orig = dyn.psd_solve
    dyn.psd_solve = functools.partial(psd_solve, diagonal_boost=0.0)
    try:
        shared = [_dynamax_loglik(model, ys[i]) for i in range(RUNS)]
        per_run = [_dynamax_loglik(model, ys[i], rs[i]) for i in range(RUNS)]
    finally:
        dyn.psd_solve = orig
        jax.config.update("jax_default_matmul_precision", None)
    np.testing.assert_allclose(batched_kalman_loglik(model, ys), shared, rtol=1e-10)
    np.testing.assert_allclose(batched_kalman_loglik(model, ys, r_scale=rs), per_run, rtol=1e-10)


def test_equals_filterpy_per_run():
    model = random_model(np.random.default_rng(8), n=3, p=2)
    ys, rng = _data(9, model, runs=2)
    rs = np.array([0.7, 1.6])
    want = [filterpy_kalman(replace(model, R=model.R * rs[i]), ys[i])["log_likelihoods"].sum() for i in range(2)]
    np.testing.assert_allclose(batched_kalman_loglik(model, ys, r_scale=rs), want, rtol=1e-9)


def test_vmap_and_jit_equal_a_loop_over_chunks():
    model = random_model(np.random.default_rng(10), n=2, p=1)
    ys, rng = _data(11, model, runs=6)
    chunks = ys.reshape(2, 3, T, 1)
    rs = rng.uniform(0.5, 2.0, (2, 3))
    loop = np.stack([batched_kalman_loglik(model, c, r_scale=s) for c, s in zip(chunks, rs)])
    vm = jax.jit(jax.vmap(lambda c, s: batched_kalman_loglik(model, c, r_scale=s)))(chunks, rs)
    np.testing.assert_allclose(vm, loop, rtol=1e-13)
    loop = np.stack([batched_kalman_loglik(model, c) for c in chunks])
    np.testing.assert_allclose(jax.vmap(lambda c: batched_kalman_loglik(model, c))(chunks), loop, rtol=1e-13)


def test_float32_stays_float32():
    model = jax.tree_util.tree_map(lambda a: a.astype(jnp.float32), random_model(np.random.default_rng(12), 2, 1))
    ys, _ = _data(13, model)
    got = batched_kalman_loglik(model, ys.astype(np.float32))
    assert got.dtype == jnp.float32
    np.testing.assert_allclose(got, _serial(model, ys.astype(np.float32)), rtol=1e-4)


LONG = 2 * STEADY_AFTER + 13  # long enough for the fixed-point test, and a tail block


def _constant_velocity(q=0.1, r=1.0):
    """Two axes of position/velocity, positions measured (the Kalman benchmark's model)."""
    f1, q1 = np.array([[1.0, 1.0], [0.0, 1.0]]), q * np.array([[1 / 3, 1 / 2], [1 / 2, 1.0]])
    h = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    F, Q, P0 = np.kron(np.eye(2), f1), np.kron(np.eye(2), q1), np.diag([100.0, 10.0] * 2)
    return lgssm(F, Q, h, r * np.eye(2), np.zeros(4), P0)


def _fixed_point_by_the_test(model) -> bool:
    """What the kernel's test decides: the predicted covariance stopped changing by step STEADY_AFTER."""
    P = _gain_sequence(model, jnp.ones((STEADY_AFTER + 1, model.n_outputs), bool), False, True)[3]
    return bool(reached_fixed_point(P[-2], P[-1]))


def test_steady_gain_after_the_fixed_point_equals_serial_filter():
    """A constant model: steps past STEADY_AFTER share one gain and one block map; float64 and float32."""
    model = _constant_velocity()
    assert _fixed_point_by_the_test(model)
    ys, _ = _data(15, model, runs=3, t=LONG)
    np.testing.assert_allclose(batched_kalman_loglik(model, ys), _serial(model, ys), rtol=1e-12)
    m32 = jax.tree_util.tree_map(lambda a: a.astype(jnp.float32), model)
    got = batched_kalman_loglik(m32, ys.astype(np.float32))
    assert got.dtype == jnp.float32
    np.testing.assert_allclose(got, _serial(m32, ys.astype(np.float32)), rtol=1e-4)


def test_slow_convergence_falls_back_to_a_gain_per_step():
    """q/r = 1e-8: the covariance still shrinks at step STEADY_AFTER, so every step keeps its own gain."""
    model = _constant_velocity(q=1e-8)
    assert not _fixed_point_by_the_test(model)
    ys, _ = _data(16, model, runs=3, t=LONG)
    np.testing.assert_allclose(batched_kalman_loglik(model, ys), _serial(model, ys), rtol=1e-12)


def test_derivative_through_the_fixed_point_test_equals_serial_filters():
    """d/d log q of the total log-likelihood (forward mode, as the tuners use for few parameters)."""
    model = _constant_velocity()
    ys, _ = _data(17, model, runs=2, t=LONG)

    def total(log_q, kernel):
        return jnp.sum(kernel(replace(model, Q=model.Q * jnp.exp(log_q))))

    batched = lambda m: batched_kalman_loglik(m, ys)  # noqa: E731
    serial = lambda m: jax.vmap(lambda y: kalman_filter(m, y).log_likelihood)(jnp.asarray(ys))  # noqa: E731
    d = [jax.jvp(lambda v: total(v, k), (0.3,), (1.0,))[1] for k in (batched, serial)]
    np.testing.assert_allclose(d[0], d[1], rtol=1e-9)


class TestBadInput:
    model = random_model(np.random.default_rng(14), n=2, p=1)
    ys = np.zeros((3, 6, 1))

    def test_ys_wrong_rank_or_width(self):
        with pytest.raises(ValueError, match="^ys:"):
            batched_kalman_loglik(self.model, self.ys[0])
        with pytest.raises(ValueError, match="^ys:"):
            batched_kalman_loglik(self.model, np.zeros((3, 6, 2)))

    @pytest.mark.parametrize("bad", [np.array([1.0, -1.0, 1.0]), np.array([1.0, np.nan, 1.0]), np.ones(2)])
    def test_bad_scales(self, bad):
        with pytest.raises(ValueError, match="^r_scale:"):
            batched_kalman_loglik(self.model, self.ys, r_scale=bad)
        with pytest.raises(ValueError, match="^q_scale:"):
            batched_kalman_loglik(self.model, self.ys, q_scale=bad)

    @pytest.mark.parametrize("scaled", [False, True])
    def test_unmasked_nan_named_with_run_and_step(self, scaled):
        ys = self.ys.copy()
        ys[2, 4, 0] = np.nan
        with pytest.raises(ValueError, match="^ys: non-finite value in run 2 at step 4"):
            batched_kalman_loglik(self.model, ys, r_scale=np.ones(3) if scaled else None)
        mask = np.ones(6, bool)
        mask[4] = False
        assert np.all(np.isfinite(batched_kalman_loglik(self.model, ys, mask=mask)))

    def test_bad_block(self):
        with pytest.raises(ValueError, match="^block:"):
            batched_kalman_loglik(self.model, self.ys, block=0)
