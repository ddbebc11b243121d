"""Kernel checks of :mod:`jaxsim.inertial.bench_calibration` against independent references: the table
kinematics of eq. 5 in closed form, the measurement matrix against finite differences of the nonlinear
error model, the information matrix against a NumPy loop, and the gains against a NumPy Kalman recursion."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.inertial import bench_calibration as bc

LAT, G = math.radians(55.7), bc.GRAVITY


def test_kinematics_first_cycle_closed_form():
    """Eq. 5 of the lecture: axis 1 East, ω_z = (ω, u cosφ cosϑ + u sinφ sinϑ, −u cosφ sinϑ + u sinφ cosϑ),
    f_z = (0, g sinϑ, g cosϑ)."""
    w, th = 0.3, 0.7
    A, om, f = bc.kinematics(0, w, th, LAT)
    u = bc.EARTH_RATE
    c, s = math.cos(LAT), math.sin(LAT)
    ref_w = [w, u * c * math.cos(th) + u * s * math.sin(th), -u * c * math.sin(th) + u * s * math.cos(th)]
    np.testing.assert_allclose(np.asarray(om), ref_w, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(f), [0, G * math.sin(th), G * math.cos(th)], atol=1e-12)
    for k in range(3):  # every cycle: a rotation with axis k East
        A, om, f = bc.kinematics(k, 0.2, 1.1, LAT)
        np.testing.assert_allclose(np.asarray(A @ A.T), np.eye(3), atol=1e-12)
        assert float(jnp.linalg.det(A)) == pytest.approx(1.0)
        np.testing.assert_allclose(np.asarray(A.T[:, k]), [1, 0, 0], atol=1e-12)


def test_measurement_matrix_against_finite_differences():
    """H x equals the linearised accelerometer residual A_xz Δf_z + G β built element by element from the
    error model (1): Δf = Δf⁰ + Γ f + (ω × f) τ + k_f T, with Γ lower triangular."""
    rng = np.random.default_rng(1)
    th, T = 0.9, 3.0
    F, H = jax.jit(lambda: bc.step_matrices(1, 0.25, th, T, LAT, 1.0, skew=True, thermal=True))()
    A, om, f = (np.asarray(a) for a in bc.kinematics(1, 0.25, th, LAT))
    x = rng.standard_normal(28)
    beta, df0, gam, tau, kf = x[:3], x[3:6], x[6:12], x[24], x[25:28]
    Gm = np.zeros((3, 3))
    Gm[np.tril_indices(3)] = gam
    df = df0 + Gm @ f + np.cross(om, f) * tau + kf * T
    ref = np.array([-G * beta[1], G * beta[0], 0.0]) + A.T @ df
    np.testing.assert_allclose(np.asarray(H @ x), ref, rtol=1e-12, atol=1e-12)
    # attitude dynamics: the β rows of (F − I)/Δt are −[u×]β + A_xz (ν⁰ + Θ ω)
    Th = x[15:24].reshape(3, 3)
    u = bc.EARTH_RATE * np.array([0, math.cos(LAT), math.sin(LAT)])
    ref_dot = -np.cross(u, beta) + A.T @ (x[12:15] + Th @ om)
    np.testing.assert_allclose(np.asarray((F - jnp.eye(28)) @ x)[:3], ref_dot, rtol=1e-12, atol=1e-15)
    # finite differences of the nonlinear measurement in Θ-free form: ∂z/∂τ along the exact ω × f
    eps = 1e-6
    z = lambda t: A.T @ (np.cross(om, f) * t)  # noqa: E731
    np.testing.assert_allclose((z(eps) - z(-eps)) / (2 * eps), np.asarray(H[:, 24]), rtol=1e-8, atol=1e-9)


def _small_model():
    plan = bc.plan_from_segments([0, 0, 1, 2], [0.0, 0.3, 0.2, 0.4], [3, 5, 6, 6], 1.0)
    F, H = jax.jit(lambda p: bc.model_arrays(p, LAT, 1.0))(plan)
    Q, R = bc.noise(24, 1.0, 1e-5, 1e-4)
    return F, H, Q, R


def test_information_and_gains_against_numpy():
    F, H, Q, R = (np.asarray(a) for a in _small_model())
    J = np.zeros((24, 24))
    psi = np.eye(24)
    for k in range(F.shape[0]):
        J += (H[k] @ psi).T @ np.linalg.inv(R) @ (H[k] @ psi)
        psi = F[k] @ psi
    np.testing.assert_allclose(np.asarray(jax.jit(bc.information)(F, H, R)), J, rtol=1e-10, atol=1e-6)
    P0 = np.diag(np.r_[np.full(3, 1e-3), np.full(3, 1e-2), np.full(6, 1e-3), np.full(3, 1e-4), np.full(9, 1e-3)] ** 2)
    P = P0.copy()
    Ks = []
    for k in range(F.shape[0]):
        S = H[k] @ P @ H[k].T + R
        K = P @ H[k].T @ np.linalg.inv(S)
        post = P - K @ S @ K.T
        Ks.append(K)
        P = F[k] @ post @ F[k].T + Q
    K, Pn = jax.jit(bc.gains)(*(jnp.asarray(a) for a in (F, H, Q, R, P0)))
    np.testing.assert_allclose(np.asarray(K), np.array(Ks), rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(np.asarray(Pn), post, rtol=1e-6, atol=1e-20)


def test_rank_of_known_matrix():
    v = np.array([[1.0, 2.0, 0.0], [0.0, 1.0, 1.0]])
    assert bc.rank(v.T @ v, np.ones(3)) == 2
    assert bc.rank(np.eye(4), np.array([1.0, 1e-3, 1.0, 1.0])) == 4
