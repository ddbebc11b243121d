"""ZUPT filter kernels against independent references: the 9-state attitude dynamics against the spec's
equations (3)–(5) through SciPy's matrix exponential, the process noise against a fine quadrature, the
measurement rows against eq. (8), the covariance channel against a NumPy Kalman recursion (PSD), and the
dense FLOP count against XLA's cost analysis."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from jaxsim.inertial import zupt
from tests.covariance import assert_covariance_close

LAT, DT = math.radians(60.0), 2.0
NG, NA = 1e-6, 2e-4
U = zupt.EARTH_RATE


def spec_a9() -> np.ndarray:
    """Eqs. (3)–(5): Φ̇_E = U sinφ Φ_N − U cosφ Φ_U + ε_E, Φ̇_N = −U sinφ Φ_E + ε_N, Φ̇_U = U cosφ Φ_E + ε_U."""
    s, c = U * math.sin(LAT), U * math.cos(LAT)
    a = np.zeros((9, 9))
    a[:3, :3] = [[0, s, -c], [-s, 0, 0], [c, 0, 0]]
    a[:3, 3:6] = np.eye(3)
    return a


def test_model9_against_the_spec_equations_and_quadrature():
    m = zupt.model9(LAT, DT, NG, NA)
    a = spec_a9()
    np.testing.assert_allclose(m.F, scipy.linalg.expm(a * DT), rtol=1e-12, atol=1e-15)
    s = np.linspace(0, DT, 101)  # Q = ∫ e^{As} G Qc Gᵀ e^{Aᵀs} ds by Simpson's rule
    g = np.zeros((9, 3))
    g[:3] = np.eye(3)
    vals = np.array([scipy.linalg.expm(a * si) @ g @ g.T @ scipy.linalg.expm(a * si).T * NG**2 for si in s])
    q = scipy.integrate.simpson(vals, x=s, axis=0)
    np.testing.assert_allclose(m.Q, q, rtol=1e-8, atol=1e-24)
    # eq. (8): n_E = −g Φ_N + δa_E, n_N = g Φ_E + δa_N, n_U − g = δa_U; R = N_a²/Δt
    h = np.zeros((3, 9))
    h[0, 1], h[1, 0] = -zupt.GRAVITY, zupt.GRAVITY
    h[:, 6:] = np.eye(3)
    np.testing.assert_allclose(m.H, h, atol=1e-15)
    np.testing.assert_allclose(m.R, np.eye(3) * NA**2 / DT, rtol=1e-14)


def test_model15_blocks():
    m = zupt.model15(LAT, DT, NG, NA, 1e-3, 1e-4)
    F = np.asarray(m.F)
    np.testing.assert_allclose(F[:3, :3], np.asarray(zupt.model9(LAT, DT, NG, NA).F)[:3, :3], rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(F[3:6, 6:9], DT * np.eye(3), atol=1e-3)  # δr picks up δV·Δt
    np.testing.assert_allclose(F[6:9, 12:15], DT * np.eye(3), atol=1e-3)  # δV picks up δa·Δt
    assert F[6, 1] == pytest.approx(-zupt.GRAVITY * DT, rel=1e-6)  # δV̇_E = −g Φ_N
    assert m.H.shape == (6, 15) and np.allclose(np.diag(m.R), [1e-6] * 3 + [1e-8] * 3)


def test_covariance_channel_against_numpy_recursion():
    m = zupt.model9(LAT, DT, NG, NA)
    P0 = np.diag([1e-4, 1e-4, 3e-2, 1e-10, 1e-10, 1e-10, 1e-4, 1e-4, 1e-4])
    covs = np.asarray(jax.jit(zupt.covariance_run, static_argnums=2)(m, jnp.asarray(P0), 25))
    F, Q, H, R = (np.asarray(x) for x in m)
    P = P0
    for k in range(25):
        S = H @ P @ H.T + R
        K = P @ H.T @ np.linalg.inv(S)
        post = P - K @ S @ K.T
        assert_covariance_close(covs[k], post, rtol=1e-7)
        assert np.linalg.eigvalsh(0.5 * (covs[k] + covs[k].T)).min() > -1e-18
        P = F @ post @ F.T + Q


def test_dense_flops_against_xla_cost_analysis():
    m = zupt.model9(LAT, DT, NG, NA)
    cost = jax.jit(zupt.covariance_step).lower(m, jnp.eye(9)).compile().cost_analysis()
    cost = cost[0] if isinstance(cost, (list, tuple)) else cost
    if not cost or "flops" not in cost:
        pytest.skip("XLA reports no FLOP count on this backend")
    assert zupt.dense_flops(9, 3) == pytest.approx(cost["flops"], rel=0.2)
    assert zupt.dense_flops(15, 6) > 4 * zupt.dense_flops(9, 3)


def test_bad_input_names_the_argument():
    with pytest.raises(ValueError, match="dt"):
        zupt.model9(LAT, 0.0, NG, NA)
    with pytest.raises(ValueError, match="accel_noise"):
        zupt.model15(LAT, DT, NG, -1.0)
