"""TRMS plant: trim equilibria, jacfwd linearisation against closed-form partials, saturation,
friction surrogate, and the RK4 rollout against SciPy's adaptive integrator."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from jaxsim.core.integrators import integrate
from jaxsim.core.pytree import replace
from jaxsim.plants.trms import (
    FEEDBACK_MANUFACTURER,
    PARAMETER_SETS,
    SCIREP_2022,
    TRMSParams,
    dynamics,
    hover_equilibrium,
    linearize_at,
    main_torque,
    tail_torque,
    trms_plant,
)

P = FEEDBACK_MANUFACTURER


@pytest.mark.parametrize("name", list(PARAMETER_SETS))
@pytest.mark.parametrize("pitch", [-0.2, -0.05, 0.1])
def test_hover_equilibrium_balances_every_torque(name, pitch):
    p = PARAMETER_SETS[name]
    x, u, res = (np.asarray(v) for v in hover_equilibrium(p, pitch, yaw=0.3))
    assert float(res) < 1e-12
    tau1, tau2, m_r = x[4:]
    # closed forms: the main rotor carries gravity, the tail rotor carries the steady reaction torque
    assert main_torque(p, tau1) == pytest.approx(p.Mg * np.sin(pitch), abs=1e-13)
    assert m_r == pytest.approx(p.kc * tau1, abs=1e-13)
    assert tail_torque(p, tau2) == pytest.approx(m_r, abs=1e-13)
    np.testing.assert_allclose(u, [p.T10 * tau1 / p.k1, p.T20 * tau2 / p.k2], atol=1e-13)
    assert np.abs(np.asarray(dynamics(p, jnp.asarray(x), jnp.asarray(u), 0.0))).max() < 1e-12


def test_trim_envelope_of_the_default_set():
    # the tail rotor cannot produce less than −b2²/(4 a2) ≈ −0.10 N·m: ψ = 0.2 rad is out of reach
    assert float(hover_equilibrium(P, 0.2)[2]) > 1e-3
    assert float(hover_equilibrium(SCIREP_2022, 0.2)[2]) < 1e-12


def test_jacfwd_linearisation_matches_closed_form_partials():
    x, u, _ = hover_equilibrium(P, -0.05)
    lin = linearize_at(P, x, u)
    a, b = np.asarray(lin.a), np.asarray(lin.b)
    psi, tau1 = float(x[0]), float(x[4])
    m1 = float(main_torque(P, tau1))
    assert a[2, 0] == pytest.approx(-P.Mg * np.cos(psi) / P.I1, rel=1e-12)
    assert a[2, 2] == pytest.approx(-P.B1psi / P.I1, rel=1e-12)  # dry friction: zero slope at rest
    assert a[2, 3] == pytest.approx(-P.Kgy * m1 * np.cos(psi) / P.I1, rel=1e-12)
    assert a[2, 4] == pytest.approx((2 * P.a1 * tau1 + P.b1) / P.I1, rel=1e-12)
    assert a[3, 6] == pytest.approx(-1 / P.I2, rel=1e-12)
    assert a[6, 4] == pytest.approx(P.kc * (1 - P.T0 * P.T10 / P.T11) / P.Tp, rel=1e-12)
    assert b[6, 0] == pytest.approx(P.kc * P.T0 * P.k1 / (P.T11 * P.Tp), rel=1e-12)
    assert b[5, 1] == pytest.approx(P.k2 / P.T21, rel=1e-12)
    np.testing.assert_array_equal(np.asarray(lin.c), np.eye(7)[:2])
    # and against central differences of the smooth part
    h = 1e-6
    fd = np.stack(
        [
            (np.asarray(dynamics(P, x + h * e, u, 0.0)) - np.asarray(dynamics(P, x - h * e, u, 0.0))) / (2 * h)
            for e in np.eye(7)[[0, 4, 5, 6]]
        ],
        axis=1,
    )
    np.testing.assert_allclose(a[:, [0, 4, 5, 6]], fd, rtol=1e-7, atol=1e-9)


def test_inputs_saturate_and_friction_surrogate_converges_to_sign():
    x = jnp.array([0.1, 0.0, 0.3, -0.2, 0.5, -0.4, 0.05])
    f_sat = dynamics(P, x, jnp.array([10.0, -10.0]), 0.0)
    f_max = dynamics(P, x, jnp.array([P.u_max, -P.u_max]), 0.0)
    np.testing.assert_array_equal(f_sat, f_max)
    exact = np.asarray(dynamics(P, x, jnp.zeros(2), 0.0))
    for eps, tol in [(1e-2, 1e-6), (1e-3, 1e-12)]:
        smooth = np.asarray(dynamics(replace(P, sign_smoothing=eps), x, jnp.zeros(2), 0.0))
        assert np.abs(smooth - exact).max() < tol
    with pytest.raises(ValueError, match="I1: must be positive"):
        trms_plant(TRMSParams(I1=-1.0))


def test_rk4_rollout_matches_scipy_solve_ivp():
    p = replace(P, sign_smoothing=0.05)  # smooth, so an adaptive reference integrator is accurate
    x0 = np.array([-0.05, 0.0, 0.0, 0.0, -0.1, 0.2, 0.0])
    u = np.array([0.6, -0.8])
    f = jax.jit(lambda t, x: dynamics(p, x, jnp.asarray(u), t))
    _, xs = integrate(f, jnp.asarray(x0), 0.0, 1e-3, 5000)
    ref = solve_ivp(lambda t, x: np.asarray(f(t, x)), (0, 5.0), x0, rtol=1e-11, atol=1e-12, t_eval=[5.0])
    np.testing.assert_allclose(np.asarray(xs[-1]), ref.y[:, -1], rtol=1e-7, atol=1e-9)
