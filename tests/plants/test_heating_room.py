"""Heated-room plant (seed 004 #11): state space vs the model equation, the gramian back-solve as a
round trip, and the simulated heater loop plant against SciPy's solve_ivp."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.integrate

from jaxsim.core.integrators import RK4, integrate
from jaxsim.plants import heating_room as hr


def test_state_space_is_model_1():
    p = hr.HeatingRoomParams()
    a, b = hr.state_space(p)
    x, u = np.array([19.0]), np.array([50.0, -5.0, 17.0])
    m_ca, kw, lv = p.capacity, p.envelope, p.ventilation
    direct = (u[0] - kw * (x[0] - u[1]) - lv * (x[0] - u[2])) / m_ca
    assert float((a @ x + b @ u)[0]) == pytest.approx(direct, rel=1e-13)
    assert float(hr.dynamics(p, jnp.asarray(x), jnp.asarray(u), 0.0)[0]) == pytest.approx(direct, rel=1e-13)


def test_backsolve_round_trip_is_unique_and_exact():
    p = hr.HeatingRoomParams(envelope=1.7, ventilation=0.3, capacity=4.0)
    w = np.asarray(hr.gramians(p))
    q = hr.params_from_gramians(*w)
    for name in ("envelope", "ventilation", "capacity"):
        assert float(getattr(q, name)) == pytest.approx(float(getattr(p, name)), rel=1e-12)
    with pytest.raises(ValueError, match="w_heater"):
        hr.params_from_gramians(0.1, -1.0, 0.2)


def test_heater_plant_against_solve_ivp_and_steady_heat():
    room = hr.HeatingRoomParams()
    p = hr.HeatedRoomParams(room=room, t_out=-7.0, t_vent=16.0)
    plant = hr.heated_room(p)
    q = 60.0
    ts, xs = integrate(lambda t, x: plant.f(x, jnp.array([q]), t), jnp.array([15.0]), 0.0, 0.01, 300, RK4)
    ref = scipy.integrate.solve_ivp(
        lambda t, x: [(q - room.envelope * (x[0] + 7.0) - room.ventilation * (x[0] - 16.0)) / room.capacity],
        (0.0, 3.0),
        [15.0],
        rtol=1e-11,
        atol=1e-12,
        t_eval=np.asarray(ts),
    )
    np.testing.assert_allclose(np.asarray(xs[:, 0]), ref.y[0], rtol=1e-9)
    hold = float(hr.steady_heat(room, 21.0, -7.0, 16.0))
    assert float(plant.f(jnp.array([21.0]), jnp.array([hold]), 0.0)[0]) == pytest.approx(0.0, abs=1e-12)
    # vmap over the outdoor temperature equals a loop
    touts = jnp.array([-20.0, 0.0, 5.0])

    def rate(t_out):
        return hr.heater_dynamics(hr.HeatedRoomParams(room, t_out, 16.0), jnp.array([20.0]), jnp.array([q]), 0.0)

    loop = jnp.stack([rate(t) for t in touts])
    np.testing.assert_allclose(np.asarray(jax.vmap(rate)(touts)), np.asarray(loop), rtol=1e-14)


def test_bad_parameters_raise():
    with pytest.raises(ValueError, match="capacity"):
        hr.heating_room(capacity=0.0)
    with pytest.raises(ValueError, match="t_out"):
        hr.heated_room(t_out=float("nan"))
