"""Periodic Riccati and Floquet tools against SciPy: a constant system's periodic solution is the
CARE solution, its monodromy is expm(AT); a scalar periodic system's multiplier is exp(∫a)."""

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from jaxsim.control import periodic_riccati as pr
from jaxsim.control import transverse_vhc as tv


def test_constant_system_gives_care_solution():
    a = np.array([[0.0, 1.0], [2.0, -0.5]])
    b = np.array([[0.0], [1.0]])
    q, r = np.diag([3.0, 1.0]), np.array([[0.5]])
    n = 40
    p, res = pr.periodic_riccati(np.repeat(a[None], 2 * n + 1, 0), np.repeat(b[None], 2 * n + 1, 0), q, r, 1.0, 12)
    care = scipy.linalg.solve_continuous_are(a, b, q, r)
    np.testing.assert_allclose(np.asarray(p), np.repeat(care[None], n + 1, 0), rtol=1e-7)
    assert float(res) < 1e-8
    k = pr.gains(np.repeat(b[None], n + 1, 0), r, p)
    np.testing.assert_allclose(np.asarray(k[0]), -np.linalg.solve(r, b.T @ care), rtol=1e-7)


def test_monodromy_constant_and_scalar_periodic():
    a = np.array([[0.0, 1.0], [-4.0, -0.3]])
    n, period = 100, 1.3
    m = pr.monodromy(np.repeat(a[None], 2 * n + 1, 0), period)
    np.testing.assert_allclose(np.asarray(m), scipy.linalg.expm(a * period), rtol=0, atol=1e-7)  # RK4, h = 0.013
    t = np.linspace(0.0, period, 2 * n + 1)
    a_t = (-0.2 + np.cos(2 * np.pi * t / period))[:, None, None]
    mu = pr.floquet_multipliers(a_t, period)
    assert abs(complex(mu[0]) - np.exp(-0.2 * period)) < 1e-9


def test_shape_errors():
    with pytest.raises(ValueError, match="odd number"):
        pr.monodromy(np.zeros((4, 2, 2)), 1.0)
    with pytest.raises(ValueError, match="b must have shape"):
        pr.periodic_riccati(np.zeros((5, 2, 2)), np.zeros((4, 2, 1)), np.eye(2), np.eye(1), 1.0, 2)


def test_gain_interpolation_is_periodic_linear():
    phases = np.linspace(0, 2 * np.pi, 9)
    table = np.stack([np.sin(phases), np.arange(9.0)], axis=1)
    table[-1] = table[0]
    for th in (0.3, 3.0, 6.2):
        got = np.asarray(tv.gain_at(jnp.asarray(th), jnp.asarray(phases), jnp.asarray(table)))
        ref = [np.interp(th, phases, table[:, 0]), np.interp(th, phases, table[:, 1])]
        np.testing.assert_allclose(got, ref, rtol=1e-12)
    assert float(tv.phase(jnp.array([0.2, 0.0]), 1.0)) == 0.0
    assert float(tv.phase(jnp.array([0.0, -1.0]), 2 * np.pi)) == pytest.approx(np.pi / 2)


def test_gradient_through_periodic_riccati_matches_finite_differences():
    import jax

    n, period = 20, 1.0
    t = np.linspace(0.0, period, 2 * n + 1)
    a = np.stack([np.array([[0.0, 1.0], [1.0 + 0.5 * np.cos(2 * np.pi * s), -0.2]]) for s in t])
    b = np.repeat(np.array([[0.0], [1.0]])[None], 2 * n + 1, 0)

    def f(w):
        p, _ = pr.periodic_riccati(a, b, jnp.diag(jnp.stack([w, 1.0])), jnp.eye(1) * 0.3, period, 4)
        return jnp.max(jnp.abs(pr.floquet_multipliers(a + b @ pr_gain_half(b, p, 0.3), period)))

    def pr_gain_half(b, p, r):
        k = pr.gains(b[::2], jnp.eye(1) * r, p)
        kh = jnp.zeros((b.shape[0], 1, 2)).at[::2].set(k).at[1::2].set(0.5 * (k[:-1] + k[1:]))
        return kh

    # compiled whole: called op by op, the loop inside was compiled on its own at every call (16 s), and
    # that eager compilation crashed a test worker in a full-suite run (segmentation fault inside XLA)
    f_c, g_c = jax.jit(f), jax.jit(jax.grad(f))
    g = float(g_c(2.0))
    eps = 1e-5
    fd = (float(f_c(2.0 + eps)) - float(f_c(2.0 - eps))) / (2 * eps)
    assert g == pytest.approx(fd, rel=1e-5, abs=1e-9)
    assert float(f_c(2.0)) < 1.0
