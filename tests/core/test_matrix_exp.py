"""The single-Padé matrix exponential against SciPy (value and Fréchet derivative)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from jaxsim.core.matrix_exp import MAX_SQUARINGS, THETA_13, expm


@pytest.mark.parametrize("norm", [1e-6, 1e-2, 0.5, 3.0, 40.0, 2e3])
def test_expm_matches_scipy(norm):
    """Across the scaling range (no squaring up to many squarings), relative error near rounding."""
    a = np.random.default_rng(1).normal(size=(6, 6))
    a *= norm / np.abs(a).sum(axis=0).max()
    ref = scipy.linalg.expm(a)
    err = np.abs(np.asarray(jax.jit(expm)(a)) - ref).max() / np.abs(ref).max()
    assert err < 1e-13 * max(1.0, norm)


def test_expm_derivatives_match_scipy_frechet():
    """Forward mode gives SciPy's Fréchet derivative; reverse mode is its adjoint (⟨G, L(E)⟩ = ⟨L*(G), E⟩)."""
    rng = np.random.default_rng(2)
    a, e, g = (rng.normal(size=(5, 5)) for _ in range(3))
    a *= 8.0  # a few squarings
    _, tangent = jax.jvp(expm, (a,), (e,))
    ref = scipy.linalg.expm_frechet(a, e, compute_expm=False)
    assert np.abs(np.asarray(tangent) - ref).max() < 1e-10 * np.abs(ref).max()
    cotangent = jax.grad(lambda m: jnp.sum(g * expm(m)))(a)
    assert np.sum(np.asarray(cotangent) * e) == pytest.approx(np.sum(g * ref), rel=1e-10)


def test_expm_beyond_squaring_range_is_nan_and_gradient_finite_below():
    big = np.eye(3) * THETA_13 * 2.0 ** (MAX_SQUARINGS + 1)
    assert np.all(np.isnan(np.asarray(expm(big))))
    # a diagonal with a large positive entry: unneeded squarings would overflow, yet no NaN leaks
    a = np.diag([-3.0, 0.1, 30.0])
    grad = jax.grad(lambda m: expm(m)[0, 0])(a)
    assert np.all(np.isfinite(np.asarray(grad)))
    assert float(grad[0, 0]) == pytest.approx(np.exp(-3.0), rel=1e-12)


def test_expm_rejects_non_square():
    with pytest.raises(ValueError, match="a: expected a square matrix"):
        expm(np.ones((2, 3)))
