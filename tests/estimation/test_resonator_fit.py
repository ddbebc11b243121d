"""Resonator fit: recovers known parameters from noise-free responses (complex, magnitude, with a
hold); the peak formula against a numerical maximum; vmap equals a loop."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize

from jaxsim.estimation.resonator_fit import fit_resonator, hold_factor, peak_frequency, resonator_response

TRUE = jnp.array([2.0, 500.0, np.log(25.0)])
F = jnp.linspace(420.0, 580.0, 81)


def test_peak_frequency_is_the_amplitude_maximum():
    res = scipy.optimize.minimize_scalar(
        lambda f: -abs(complex(resonator_response(TRUE, f))),
        bounds=(450, 550),
        method="bounded",
        options={"xatol": 1e-9},
    )
    assert float(peak_frequency(TRUE[1], jnp.exp(TRUE[2]))) == pytest.approx(res.x, abs=1e-5)


@pytest.mark.parametrize("mode, hold", [("complex", 0.0), ("complex", 1 / 4096), ("magnitude", 0.0)])
def test_fit_recovers_parameters(mode, hold):
    h = resonator_response(TRUE, F) * hold_factor(F, hold)
    data = h if mode == "complex" else jnp.abs(h)
    fit = fit_resonator(F, data, jnp.array([1.0, 490.0, np.log(10.0)]), mode=mode, hold=hold, n_iter=80)
    np.testing.assert_allclose(np.asarray(fit.theta), np.asarray(TRUE), rtol=1e-8)
    assert float(fit.cost) < 1e-20


def test_vmap_equals_loop():
    starts = jnp.array([[1.0, 490.0, 2.0], [3.0, 510.0, 3.5]])
    h = resonator_response(TRUE, F)
    one = jax.jit(lambda t: fit_resonator(F, h, t, n_iter=10).theta)
    batched = jax.jit(jax.vmap(one))(starts)
    loop = jnp.stack([one(t) for t in starts])
    np.testing.assert_allclose(np.asarray(batched), np.asarray(loop), rtol=1e-10)


def test_bad_input_raises():
    with pytest.raises(ValueError, match="mode"):
        fit_resonator(F, jnp.abs(resonator_response(TRUE, F)), TRUE, mode="phase")
    with pytest.raises(ValueError, match="theta0"):
        fit_resonator(F, resonator_response(TRUE, F), TRUE[:2])
