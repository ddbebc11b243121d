"""Particle filter: resampling schemes, ESS, convergence to the Kalman filter, no-resampling mode."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation.lgssm import kalman_filter, lgssm, sample
from jaxsim.estimation.particle import (
    bootstrap_filter,
    effective_sample_size,
    particle_model_from_lgssm,
    resample,
    systematic_resample,
)

MODEL = lgssm(
    F=[[1.0, 0.1], [0.0, 0.95]],
    Q=np.diag([0.01, 0.05]),
    H=[[1.0, 0.0]],
    R=[[0.2]],
    m0=[0.0, 0.5],
    P0=np.diag([1.0, 0.5]),
)


def _counts(idx, n):
    return jnp.bincount(idx, length=n)


def test_systematic_counts_are_floor_or_ceil_of_expected():
    w = jax.random.dirichlet(jax.random.PRNGKey(0), jnp.ones(50))
    for k in jax.random.split(jax.random.PRNGKey(1), 20):
        c = np.asarray(_counts(systematic_resample(k, w), 50))
        nw = 50 * np.asarray(w)
        assert np.all((c == np.floor(nw)) | (c == np.ceil(nw)))
        assert c.sum() == 50


@pytest.mark.parametrize("method", ["systematic", "stratified", "multinomial"])
def test_resampling_is_unbiased(method):
    n = 40
    logw = jnp.log(jax.random.dirichlet(jax.random.PRNGKey(2), jnp.ones(n)))
    keys = jax.random.split(jax.random.PRNGKey(3), 4000)
    counts = jax.vmap(lambda k: _counts(resample(k, logw, method), n))(keys)
    mean = np.asarray(counts.mean(axis=0))
    sd = np.sqrt(n * np.exp(np.asarray(logw)) / 4000)  # multinomial sd of the mean (an upper bound for the others)
    assert np.all(np.abs(mean - n * np.exp(np.asarray(logw))) < 5 * sd + 1e-9)


def test_effective_sample_size_limits():
    assert float(effective_sample_size(jnp.zeros(100))) == pytest.approx(100.0, rel=1e-12)
    assert float(effective_sample_size(jnp.array([0.0] + [-jnp.inf] * 9))) == pytest.approx(1.0, rel=1e-12)


def test_particle_filter_approaches_kalman_filter_as_particles_grow():
    _, y = sample(MODEL, jax.random.PRNGKey(4), 25)
    kf = kalman_filter(MODEL, y)
    pm = particle_model_from_lgssm(MODEL)
    sd = np.sqrt(np.asarray(jnp.diagonal(kf.covs, axis1=1, axis2=2)))
    errors, ll_errors = [], []
    for n in (100, 1000, 10000):
        run = jax.jit(jax.vmap(lambda k: bootstrap_filter(pm, k, y, n_particles=n)))
        res = run(jax.random.split(jax.random.PRNGKey(5), 4))
        errors.append(float(np.sqrt(np.mean(((np.asarray(res.means) - np.asarray(kf.means)) / sd) ** 2))))
        ll_errors.append(float(np.mean(np.abs(np.asarray(res.log_likelihood) - float(kf.log_likelihood)))))
    assert errors[0] > errors[1] > errors[2], errors
    assert errors[2] < errors[0] / 4 and errors[2] < 0.05, errors  # Monte-Carlo error ∝ 1/√N
    assert ll_errors[2] < ll_errors[0] and ll_errors[2] < 0.2, ll_errors


def test_no_resampling_mode_degenerates_and_resampling_keeps_particles_alive():
    _, y = sample(MODEL, jax.random.PRNGKey(6), 40)
    pm = particle_model_from_lgssm(MODEL)
    with_rs = bootstrap_filter(pm, jax.random.PRNGKey(7), y, n_particles=500, resampling="systematic")
    without = bootstrap_filter(pm, jax.random.PRNGKey(7), y, n_particles=500, resampling=None)
    assert not bool(jnp.any(without.resampled)) and bool(jnp.any(with_rs.resampled))
    assert float(without.ess[-1]) < 0.1 * float(jnp.min(with_rs.ess[-10:]))
    always = bootstrap_filter(pm, jax.random.PRNGKey(7), y, n_particles=500, resampling="stratified", ess_threshold=1.0)
    assert bool(jnp.all(always.resampled[1:]))


def test_bad_particle_arguments():
    pm = particle_model_from_lgssm(MODEL)
    y = np.zeros((5, 1))
    with pytest.raises(ValueError, match="^resampling:"):
        bootstrap_filter(pm, jax.random.PRNGKey(0), y, n_particles=10, resampling="residual")
    with pytest.raises(ValueError, match="^ess_threshold:"):
        bootstrap_filter(pm, jax.random.PRNGKey(0), y, n_particles=10, ess_threshold=1.5)
    with pytest.raises(ValueError, match="^n_particles:"):
        bootstrap_filter(pm, jax.random.PRNGKey(0), y, n_particles=0)
