"""Pole placement (SciPy oracle), Luenberger observers and sliding-mode observer building blocks."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal

from jaxsim.estimation.observers import (
    ackermann,
    current_observer_gain,
    low_pass,
    luenberger_gain,
    luenberger_step,
    place_poles,
    sliding_mode_observer_derivative,
    switching,
)


def _sorted(z):
    z = np.asarray(z, complex)
    return z[np.lexsort((z.imag, z.real))]


@pytest.mark.parametrize("poles", [[-1.0, -2.0, -3.0, -4.0], [-1 + 1j, -1 - 1j, -3.0, -0.5]])
def test_ackermann_equals_scipy_single_input(poles):
    rng = np.random.default_rng(40)
    a, b = rng.standard_normal((4, 4)), rng.standard_normal((4, 1))
    k = np.asarray(ackermann(a, b, np.array(poles)))
    ref = scipy.signal.place_poles(a, b, poles).gain_matrix
    np.testing.assert_allclose(k, ref, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(_sorted(np.linalg.eigvals(a - b @ k)), _sorted(poles), atol=1e-9)


@pytest.mark.parametrize(
    "n,m,poles",
    [
        (4, 2, [-1.0, -2.0, -3.0, -4.0]),
        (5, 2, [-1 + 2j, -1 - 2j, -2.0, -3.0, -0.5]),
        (6, 3, [-1 + 1j, -1 - 1j, -2 + 0.5j, -2 - 0.5j, -3.0, -4.0]),
    ],
)
def test_multi_input_placement_places_the_poles_like_scipy(n, m, poles):
    rng = np.random.default_rng(41 + n)
    a, b = rng.standard_normal((n, n)), rng.standard_normal((n, m))
    k = np.asarray(place_poles(a, b, np.array(poles)))
    ref = scipy.signal.place_poles(a, b, poles)
    ours_eig = np.linalg.eigvals(a - b @ k)
    np.testing.assert_allclose(_sorted(ours_eig), _sorted(ref.computed_poles), atol=1e-8)
    # robustness: eigenvector conditioning comparable to SciPy's KNV/YT result
    cond_ours = np.linalg.cond(np.linalg.eig(a - b @ k)[1])
    cond_ref = np.linalg.cond(np.linalg.eig(a - b @ ref.gain_matrix)[1])
    assert cond_ours < 3.0 * cond_ref, (cond_ours, cond_ref)


def test_deadbeat_luenberger_observer_converges_in_n_steps():
    rng = np.random.default_rng(43)
    a, b, c = rng.standard_normal((3, 3)), rng.standard_normal((3, 1)), rng.standard_normal((1, 3))
    l_pred = luenberger_gain(a, c, np.zeros(3))
    np.testing.assert_allclose(np.linalg.eigvals(a - l_pred @ c), 0.0, atol=1e-4)  # triple root: ε^(1/3)
    x, xh = np.array([1.0, -2.0, 0.5]), np.zeros(3)
    for k in range(3):
        u = np.array([np.sin(k)])
        y = c @ x
        xh = np.asarray(luenberger_step(xh, y, u, a, b, c, l_pred))
        x = a @ x + b @ u
    np.testing.assert_allclose(xh, x, atol=1e-8)
    l_cur = current_observer_gain(a, c, [0.1, 0.2, 0.3])
    np.testing.assert_allclose(_sorted(np.linalg.eigvals(a - a @ l_cur @ c)), _sorted([0.1, 0.2, 0.3]), atol=1e-9)


def test_pole_placement_is_differentiable_in_the_poles():
    a = jnp.array([[0.0, 1.0], [-2.0, -0.5]])
    b = jnp.array([[0.0], [1.0]])
    k = lambda p: ackermann(a, b, jnp.array([p, -3.0]))[0, 0]  # noqa: E731
    h = 1e-6
    np.testing.assert_allclose(jax.grad(k)(-2.0), (k(-2.0 + h) - k(-2.0 - h)) / (2 * h), rtol=1e-6)


def test_pole_placement_bad_input():
    a, b = np.eye(3), np.ones((3, 2))
    with pytest.raises(ValueError, match="^poles: expected 3 poles"):
        place_poles(a, b, [-1.0, -2.0])
    with pytest.raises(ValueError, match="^poles: complex pole"):
        place_poles(a, b, [-1 + 1j, -2.0, -3.0])
    with pytest.raises(ValueError, match="^B: expected shape"):
        place_poles(a, np.ones((2, 1)), [-1.0, -2.0, -3.0])


def _smo_run(mode, epsilon, rho=1.0, dt=1e-4, t_end=4.0):
    """ẋ = d(t) (unknown input |d| ≤ 0.5), y = x; observer dx̂/dt = ρ v(y − x̂)."""
    a, c, l, g = jnp.zeros((1, 1)), jnp.eye(1), jnp.zeros((1, 1)), jnp.eye(1)

    def step(carry, k):
        x, xh, nu_f = carry
        t = k * dt
        d = 0.5 * jnp.sin(t)
        dxh, nu = sliding_mode_observer_derivative(xh, x, None, a, None, c, l, g, rho, mode=mode, epsilon=epsilon)
        nu_f = low_pass(nu_f, nu, 0.02, dt)
        return (x + dt * d, xh + dt * dxh, nu_f), (t, x - xh, nu[0], nu_f[0], d)

    n = int(round(t_end / dt))
    _, out = jax.lax.scan(step, (jnp.ones(1), jnp.zeros(1), jnp.zeros(1)), jnp.arange(n))
    return [np.asarray(o) for o in out]


def test_sliding_mode_observer_reaches_surface_and_recovers_unknown_input():
    t, e, nu, nu_f, d = _smo_run("sign", 0.0)
    reach_bound = 1.0 / (1.0 - 0.5)  # |e0| / (ρ − max|d|)
    after = t > reach_bound
    assert np.all(np.abs(e[after]) <= 2 * 1e-4 * 1.0 + 1e-12)
    assert np.any(np.abs(e[t < 0.9]) > 0.1)  # not there from the start
    late = t > 3.0
    assert np.max(np.abs(nu_f[late] - d[late])) < 0.05  # equivalent injection ≈ d (lag τ·|ḋ| + ripple)
    _, e_s, nu_s, _, d_s = _smo_run("fraction", 1e-3)
    assert np.max(np.abs(nu_s[late] - d_s[late])) < 0.01  # smooth injection tracks d without filtering
    assert np.max(np.abs(e_s[late])) < 2e-3


def test_switching_surrogates_tend_to_sign():
    e = jnp.array([-2.0, -0.1, 0.3, 1.5])
    for mode in ("fraction", "tanh", "saturation"):
        np.testing.assert_allclose(switching(e, mode, 1e-6), np.sign(e), atol=1e-4)
        assert float(switching(jnp.array(0.0), mode, 0.1)) == 0.0
    with pytest.raises(ValueError, match="^mode:"):
        switching(e, "relay")
