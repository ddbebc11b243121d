"""Station-slew pieces: guidance law (1) against finite differences of its own attitude, the standard
slew's inverse-dynamics torque replayed through the plant, the scaled rollout against SciPy."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from jaxsim.control import station_slew as ss
from jaxsim.plants import orbital_station as st


def _nodes():
    phis = np.array([[0, 0, 0], [0.1, -0.2, 0.3], [0.4, 0.1, 0.9], [0.2, 0.5, 1.8]])
    q = []
    for phi in phis:
        a = np.linalg.norm(phi)
        q.append(np.r_[np.cos(a / 2), np.sin(a / 2) * phi / a] if a > 0 else np.r_[1.0, 0, 0, 0])
    return jnp.asarray(np.array(q))


def test_guidance_hits_nodes_and_rate_is_consistent():
    nodes, dt, n = _nodes(), 5.0, 1.1e-3
    g = jax.jit(lambda t: ss.guidance(t, nodes, dt, n))
    for j in range(4):
        q, _ = g(j * dt - (1e-12 if j == 3 else 0.0))
        assert abs(float(q @ nodes[j])) == pytest.approx(1.0, abs=1e-9)
    # ω_cmd − ω_orb is the body rate of q_cmd: q̇ = ½ q ⊗ [0, ω_rel], q̇ by central differences
    t, h = 7.3, 1e-4
    q, w = g(t)
    qdot = (g(t + h)[0] - g(t - h)[0]) / (2 * h)
    rel = 2 * st.quat_mul(q * jnp.array([1.0, -1, -1, -1]), qdot)
    np.testing.assert_allclose(rel[1:], w - st.orbit_rate_body(q, n), atol=1e-8)
    assert abs(float(rel[0])) < 1e-8


def test_standard_slew_torque_replayed_through_the_plant():
    p = st.StationParams()
    dur, n = 3000.0, 500
    # without orbit rate the eigen-axis yaw needs only J_z·ψ̈
    p0 = st.StationParams(orbit_rate=0.0)
    tq = ss.standard_slew_torque(jnp.asarray(700.0), p0, dur)
    psi_dd = np.pi * 2 * np.pi * np.sin(2 * np.pi * 700 / dur) / dur**2
    np.testing.assert_allclose(tq, [0, 0, p0.inertia[2] * psi_dd], atol=1e-9)
    # with orbit rate and gravity gradient: the torque replayed by RK4 ends at 180° yaw, at rest

    h = dur / n
    tq = jax.jit(jax.vmap(lambda t: ss.standard_slew_torque(t, p, dur)))(jnp.arange(2 * n + 1) * h / 2)

    def step(x, k):
        f = lambda x, i: st.rhs(x, tq[i], p)  # noqa: E731
        k1 = f(x, 2 * k)
        k2 = f(x + 0.5 * h * k1, 2 * k + 1)
        k3 = f(x + 0.5 * h * k2, 2 * k + 1)
        k4 = f(x + h * k3, 2 * k + 2)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), None

    x0 = st.rest_state(jnp.array([1.0, 0, 0, 0]), p)
    x = jax.jit(lambda x: jax.lax.scan(step, x, jnp.arange(n))[0])(x0)
    np.testing.assert_allclose(np.abs(x[:4]), [0, 0, 0, 1], atol=1e-6)
    np.testing.assert_allclose(x[4:], st.rest_state(x[:4], p)[4:], atol=1e-9)


def test_rollout_against_solve_ivp_and_terminal_error():
    prob = ss.SlewProblem(n_intervals=4, substeps=100)
    u = jnp.array([[2.0, -1.0, 8.0], [0.0, 0.5, 1.0], [-1.0, 0.0, -3.0], [0.3, 0.2, -6.0]])
    xs = jax.jit(lambda u: ss.rollout(u, prob))(u)
    f = jax.jit(lambda x, uk: st.scaled_rhs(x, uk, prob.params, prob.horizon))
    x = np.asarray(prob.x0())
    for k in range(4):
        sol = solve_ivp(lambda t, x: np.asarray(f(jnp.asarray(x), u[k])), (0, 0.25), x, rtol=1e-11, atol=1e-12)
        x = sol.y[:, -1]
        np.testing.assert_allclose(xs[k + 1], x, rtol=1e-6, atol=1e-8)
    # a state at rest at ±q_f has zero terminal error
    for sign in (1.0, -1.0):
        xf = ss.rest_state_scaled(sign * prob.qf(), prob)
        np.testing.assert_allclose(ss.terminal_error(xf, prob), 0.0, atol=1e-12)
    assert float(ss.fuel(u, prob, 0.0)) == pytest.approx(np.abs(np.asarray(u)).sum() / 4)


def test_trajectory_is_fourth_order_and_the_rollout_is_its_interval_ends():
    prob = ss.SlewProblem(n_intervals=5, substeps=3)
    u = jnp.asarray(np.random.default_rng(1).normal(0, 4, (5, 3)))
    run = jax.jit(ss.trajectory, static_argnums=(1, 2))
    ref = run(u, prob, 96)[-1]
    errs = [float(jnp.max(jnp.abs(run(u, prob, k)[-1] - ref))) for k in (3, 6)]
    assert 12 < errs[0] / errs[1] < 20  # RK4: halving the step divides the error by ≈ 16
    np.testing.assert_allclose(ss.rollout(u, prob), run(u, prob, 3)[::3], rtol=1e-12, atol=1e-14)  # eager vs jit
    assert run(u, prob, 3).shape == (16, 7)


def test_guidance_error_of_an_accelerating_single_axis_rotation_is_the_closed_form():
    """θ(t) = a t²/2 about a fixed axis (no orbit rate): law (1) interpolates θ linearly between nodes,
    so its largest attitude error is a Δt²/8 (mid-interval) and its rate error a Δt/2 (interval ends)."""
    a, step, axis = 2e-4, 0.5, np.array([1.0, 2.0, -2.0]) / 3.0
    t = np.arange(0, 120 + step / 2, step)
    theta = a * t**2 / 2
    q = np.concatenate([np.cos(theta / 2)[:, None], np.sin(theta / 2)[:, None] * axis], axis=1)
    states = jnp.asarray(np.concatenate([q, (a * t)[:, None] * axis], axis=1))
    for every in (4, 20):
        dt = every * step
        e = ss.guidance_error(states, step, every, 0.0)
        assert float(e["angle_rad"]) == pytest.approx(a * dt**2 / 8, rel=1e-6)
        assert float(e["rate_rad_s"]) == pytest.approx(a * dt / 2, rel=1e-9)
    # a constant-rate rotation is followed exactly
    q = np.concatenate([np.cos(0.01 * t / 2)[:, None], np.sin(0.01 * t / 2)[:, None] * axis], axis=1)
    e = ss.guidance_error(jnp.asarray(np.concatenate([q, np.outer(np.full_like(t, 0.01), axis)], 1)), step, 10, 0.0)
    assert float(e["angle_rad"]) < 1e-7 and float(e["rate_rad_s"]) < 1e-12


def test_standard_slew_fuel_without_orbit_rate_is_the_closed_form():
    """Cycloidal yaw without orbit rate: u = J_z ψ̈, so ∫|u| dt = J_z · 2 max ψ̇ = 4 J_z ψ_f / T."""
    p, T = st.StationParams(orbit_rate=0.0), 3000.0
    kg = float(ss.standard_slew_fuel_kg(*ss.standard_slew_history(p, T), p))
    assert kg == pytest.approx(4 * p.inertia[2] * np.pi / T / (p.arm * p.isp * st.G0), rel=1e-6)


def test_fuel_kg_of_scaled_torques():
    prob = ss.SlewProblem(n_intervals=4)
    u = jnp.zeros((4, 3)).at[:, 1].set(jnp.array([2.0, -2.0, 1.0, 0.0]))
    impulse = 5.0 / 4 * prob.horizon * prob.params.inertia[2] / prob.horizon**2  # Σ|ũ|Δτ · T · J_z/T²
    p = prob.params
    assert float(ss.fuel_kg(u, prob)) == pytest.approx(impulse / (p.arm * p.isp * st.G0), rel=1e-14)
