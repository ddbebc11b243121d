"""The fuzzy-PID paper's plants: defaults, exact step responses, input validation."""

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal

from jaxsim.core.integrators import RK4, integrate
from jaxsim.plants.second_order import AstaticParams, StaticParams, astatic_plant, static_plant


def test_paper_defaults():
    sp, ap = StaticParams(), AstaticParams()
    assert (sp.K, sp.T1, sp.T2) == (2.0, 0.1, 0.5)
    assert (ap.K, ap.T) == (2.0, 0.1)


@pytest.mark.parametrize(
    "make, num, den",
    [
        (static_plant, [2.0], [0.05, 0.6, 1.0]),
        (astatic_plant, [2.0], [0.1, 1.0, 0.0]),
    ],
)
def test_open_loop_step_response_matches_scipy(make, num, den):
    plant = make()
    u = jnp.array([1.0])
    ts, xs = integrate(lambda t, x: plant.f(x, u, t), jnp.zeros(2), 0.0, 1e-3, 2000, RK4)
    _, y_ref = scipy.signal.step((num, den), T=np.asarray(ts))
    np.testing.assert_allclose(xs[:, 0], y_ref, atol=1e-9)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"T1": -0.1}, "T1"),
        ({"T2": float("nan")}, "T2"),
        ({"T1": 0.0}, "T1"),
        ({"K": float("inf")}, "K"),
    ],
)
def test_static_plant_rejects_bad_parameters(kwargs, name):
    with pytest.raises(ValueError, match=f"^{name}:"):
        static_plant(**kwargs)


def test_astatic_plant_rejects_bad_parameters():
    with pytest.raises(ValueError, match="^T:"):
        astatic_plant(T=-1.0)
    with pytest.raises(ValueError, match="^K:"):
        astatic_plant(K=float("nan"))
