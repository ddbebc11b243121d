"""Robust reducers: CVaR against the Rockafellar–Uryasev minimisation (SciPy), limits, bad input."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize

from optim.robust import cvar, mean, robust_loss, worst_case


@pytest.mark.parametrize("alpha", [0.0, 0.5, 0.8, 0.9, 0.95, 0.97])
def test_cvar_equals_the_rockafellar_uryasev_minimum(alpha):
    losses = np.random.default_rng(7).gamma(2.0, 1.5, size=50)
    ru = lambda t: t + np.mean(np.maximum(losses - t, 0.0)) / (1 - alpha)  # noqa: E731
    oracle = scipy.optimize.minimize_scalar(
        ru, bounds=(losses.min() - 1, losses.max() + 1), method="bounded", options={"xatol": 1e-12}
    ).fun
    assert float(cvar(jnp.asarray(losses), alpha)) == pytest.approx(oracle, rel=1e-8)


def test_cvar_limits_and_gradient():
    x = jnp.array([3.0, -1.0, 7.0, 2.0])
    assert float(cvar(x, 0.0)) == pytest.approx(float(mean(x)))
    assert float(cvar(x, 0.75)) == pytest.approx(7.0)  # worst 25 % of 4 samples = the max
    assert float(worst_case(x)) == 7.0
    assert float(cvar(x, 0.5)) == pytest.approx(5.0)  # mean of the two worst
    g = jax.grad(lambda v: cvar(v, 0.5))(x)
    np.testing.assert_allclose(g, [0.5, 0.0, 0.5, 0.0])


def test_robust_loss_vmaps_over_pytree_samples_and_checks_them():
    samples = {"k": jnp.array([1.0, 2.0, 3.0]), "b": jnp.array([0.0, 1.0, -1.0])}
    f = robust_loss(lambda p, s: (p * s["k"] + s["b"]) ** 2, samples, worst_case)
    assert float(f(1.0)) == pytest.approx(max((1 * 1 + 0) ** 2, (2 + 1) ** 2, (3 - 1) ** 2))
    with pytest.raises(ValueError, match="samples"):
        robust_loss(lambda p, s: p, {"a": jnp.ones(3), "b": jnp.ones(2)})
    with pytest.raises(ValueError, match="alpha"):
        cvar(jnp.ones(3), 1.0)
