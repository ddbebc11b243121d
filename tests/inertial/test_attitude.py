"""Attitude updates under classical coning: the motion's body rate by autodiff of its attitude, the
increments by Gauss–Legendre quadrature, quaternions against SciPy, exactness without coning, the
closed-form coning drift against simulation and against its small-λ orders."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from jaxsim.inertial.attitude import (
    ALGORITHMS,
    SAMPLES_PER_UPDATE,
    coning_attitude,
    coning_drift_rate,
    coning_increments,
    coning_rate,
    drift_rate,
    propagate,
    quat_exp,
    quat_mul,
    quat_rotation_vector,
    rotation_vectors,
)

ALPHA, OMEGA = math.radians(1.0), 2 * math.pi


def test_body_rate_is_the_derivative_of_the_attitude_and_increments_its_integral():
    conj = jnp.array([1.0, -1.0, -1.0, -1.0])
    t = jnp.array([0.0, 0.37, 1.9])
    q, qd = jax.jvp(lambda s: coning_attitude(s, 0.3, 2.0), (t,), (jnp.ones(3),))
    np.testing.assert_allclose(2 * quat_mul(q * conj, qd)[:, 1:], coning_rate(t, 0.3, 2.0), atol=1e-13)
    x, w = np.polynomial.legendre.leggauss(20)
    h, t0 = 0.05, 0.2
    inc = np.asarray(coning_increments(3, h, 0.3, 2.0, t0=t0))
    for k in range(3):
        tk = t0 + k * h + (x + 1) * h / 2
        quad = (w[:, None] * np.asarray(coning_rate(tk, 0.3, 2.0))).sum(0) * h / 2
        np.testing.assert_allclose(inc[k], quad, atol=1e-15)


def test_quaternions_against_scipy():
    rng = np.random.default_rng(0)
    for phi in [rng.normal(size=3), 1e-6 * rng.normal(size=3), np.zeros(3), np.array([3.0, 0.1, -0.2])]:
        q = np.asarray(quat_exp(jnp.asarray(phi)))
        ref = Rotation.from_rotvec(phi).as_quat()  # x, y, z, w
        np.testing.assert_allclose(q, np.r_[ref[3], ref[:3]], atol=1e-14)
        np.testing.assert_allclose(quat_rotation_vector(jnp.asarray(q)), phi, atol=1e-10)
    a, b = rng.normal(size=3), rng.normal(size=3)
    prod = quat_mul(quat_exp(jnp.asarray(a)), quat_exp(jnp.asarray(b)))
    ref = (Rotation.from_rotvec(a) * Rotation.from_rotvec(b)).as_quat()
    np.testing.assert_allclose(
        np.asarray(prod) * np.sign(prod[0]), np.r_[ref[3], ref[:3]] * np.sign(ref[3]), atol=1e-14
    )


def test_every_rule_is_exact_for_a_fixed_axis_rotation():
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    rates = 0.7 + 0.3 * np.sin(np.arange(12) * 0.4)  # varying magnitude, fixed axis: no coning
    inc = jnp.asarray(rates[:, None] * axis * 0.01)
    exact = quat_exp(jnp.asarray(axis * rates.sum() * 0.01))
    step = jax.jit(propagate)
    for alg in ALGORITHMS:
        q = step(jnp.array([1.0, 0, 0, 0]), rotation_vectors(inc, alg, previous=inc[0]))
        np.testing.assert_allclose(q[-1], exact, atol=1e-14)


@pytest.mark.parametrize("alg", ["first_order", "three_sample"])  # all four: the study test
def test_simulated_drift_equals_the_closed_form(alg):
    m = SAMPLES_PER_UPDATE[alg]
    f = 20.0
    h, updates = 1 / f, 240 // m
    inc = coning_increments(updates * m, h, ALPHA, OMEGA)
    prev = coning_increments(1, h, ALPHA, OMEGA, t0=-h)[0]
    q = jax.jit(propagate)(coning_attitude(0.0, ALPHA, OMEGA), rotation_vectors(inc, alg, previous=prev))
    t = (jnp.arange(updates) + 1) * m * h
    d = drift_rate(t, coning_attitude(t, ALPHA, OMEGA), q)
    assert float(d[0]) == pytest.approx(float(coning_drift_rate(ALPHA, OMEGA, h, alg)), rel=0.02)


def test_closed_form_orders_and_leading_coefficients():
    s2 = math.sin(ALPHA) ** 2
    for alg, order in (("first_order", 2), ("two_sample_previous", 4), ("two_sample", 4), ("three_sample", 6)):
        h = 1e-2
        r = float(coning_drift_rate(ALPHA, OMEGA, h, alg) / coning_drift_rate(ALPHA, OMEGA, h / 2, alg))
        assert r == pytest.approx(2.0**order, rel=1e-2), alg
    lam = OMEGA * 1e-3
    # first order: −½ sin²α (Ω − sin λ/h) ≈ −s²Ωλ²/12
    assert float(coning_drift_rate(ALPHA, OMEGA, 1e-3, "first_order")) == pytest.approx(
        -s2 * OMEGA * lam**2 / 12, rel=1e-5
    )
    with pytest.raises(ValueError, match="^algorithm:"):
        coning_drift_rate(ALPHA, OMEGA, 0.01, "four_sample")
    with pytest.raises(ValueError, match="^increments:"):
        rotation_vectors(jnp.zeros((5, 3)), "two_sample")
    with pytest.raises(ValueError, match="^q0:"):
        propagate(jnp.zeros(3), jnp.zeros((2, 3)))
