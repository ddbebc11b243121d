"""Geared two-mass stabiliser with backlash (jaxsim.plants.geared_stabiliser) and its closed loop
(jaxsim.problem.geared_stabiliser): the dead zone and its surrogate, the closed loop against SciPy's
solve_ivp at tight tolerance (exact dead zone), the steady mismatch amplitude against the frequency response."""

import dataclasses

import jax
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from jaxsim.control import modal_observer as mo
from jaxsim.plants import geared_stabiliser as gs
from jaxsim.problem import geared_stabiliser as gp

P = gs.StabiliserParams()
A, B, C = (np.asarray(m) for m in gs.linear_model(P))
W0 = float(gs.natural_frequency(P))
OM = 2 * np.pi / 8
DESIGN = jax.jit(mo.modal_design)(A, B, C, OM, W0, 10.0)


def test_dead_zone_and_its_smooth_surrogate():
    z = np.linspace(-3e-4, 3e-4, 601)
    h = 0.5 * float(P.backlash)
    exact = np.asarray(gs.dead_zone(z, h))
    assert np.all(exact[np.abs(z) <= h] == 0) and np.allclose(exact, np.sign(z) * np.maximum(np.abs(z) - h, 0))
    for eps in (1e-5, 1e-6):
        smooth = np.asarray(gs.smooth_dead_zone(z, h, eps))
        assert np.max(np.abs(smooth - exact)) <= eps * np.log(2) + 1e-15
    assert np.allclose(
        gs.linear_model(P)[0] @ np.array([0, 0, 1e-3, 0]),
        gs.dynamics(dataclasses.replace(P, backlash=0.0), np.array([0, 0, 1e-3, 0.0]), 0.0, 0.0),
    )


def test_closed_loop_with_exact_backlash_against_solve_ivp():
    amp = np.deg2rad(10.0)
    run = jax.jit(lambda d: gp.simulate_modal(P, d, amp, 4 * OM, t_final=2.0, dt=2.5e-4, stride=40))(DESIGN)
    d = jax.tree.map(np.asarray, DESIGN)
    h, c = 0.5 * float(P.backlash), float(P.stiffness)
    j1, j2, n = float(P.J1), float(P.J2), float(P.gear_ratio)

    def f(t, x):
        z = x[4:]
        u = -(d.K[0] @ z[:4]) - d.Cw[0] @ z[4:]
        m_e = c * (x[2] - np.clip(x[2], -h, h))
        dist = float(P.friction) - j1 * (1 - 1 / n) * amp * (4 * OM) ** 2 * np.sin(4 * OM * t)
        dx = [x[1], m_e / j2, x[3] - x[1], (u - m_e + dist) / j1]
        dz = d.Aa @ z + d.Ba[:, 0] * u + d.L[:, 0] * (x[0] - d.Ca[0] @ z)
        return np.concatenate([dx, dz])

    t = np.asarray(run.t)
    ref = solve_ivp(f, (0, t[-1]), np.zeros(11), method="LSODA", t_eval=t, rtol=1e-10, atol=1e-13, max_step=2e-3)
    assert ref.success
    scale = np.max(np.abs(ref.y[0]))
    assert scale > 2e-6  # the transient is visible (≈ 2 arcseconds)
    assert np.max(np.abs(np.asarray(run.theta) - ref.y[0])) < 2e-3 * scale


def test_mismatched_roll_amplitude_matches_the_frequency_response():
    linear = dataclasses.replace(P, backlash=0.0)
    amp, om = np.deg2rad(10.0), 10 * OM  # period 0.8 s
    run = jax.jit(lambda d: gp.simulate_modal(linear, d, amp, om, t_final=6.4, dt=1e-3, stride=1))(DESIGN)
    sim = float(gp.peak(run, 6.4 - 0.8))
    want = float(jax.jit(gp.roll_error_amplitude)(DESIGN, linear, amp, om)[0])
    assert sim == pytest.approx(want, rel=2e-3)


def test_bad_parameters_name_the_field():
    with pytest.raises(ValueError, match="J1"):
        gs.check_params(dataclasses.replace(P, J1=0.0))
    with pytest.raises(ValueError, match="backlash"):
        gs.check_params(dataclasses.replace(P, backlash=-1.0))
    with pytest.raises(ValueError, match="gear_ratio"):
        gs.check_params(dataclasses.replace(P, gear_ratio=0.5))
