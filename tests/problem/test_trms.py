"""The TRMS tuning problem: trim, loss terms against an independent simulation, and the gradient
through Riccati solves + rollout against central finite differences."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.core.rollout import Timing, simulate
from jaxsim.problem.trms import N_THETA, Scenario, TRMSTuning

SHORT = Scenario(t_final=3.0, pitch_period=2.0, yaw_period=3.0, yaw_delay=0.5)


@pytest.fixture(scope="module")
def problem():
    return TRMSTuning(SHORT)


def test_operating_point_is_a_trim_point_and_out_of_envelope_raises(problem):
    f = problem.nominal
    from jaxsim.plants.trms import dynamics

    assert np.abs(np.asarray(dynamics(f, problem.x_eq, problem.u_eq, 0.0))).max() < 1e-12
    assert float(problem.x_eq[0]) == SHORT.pitch_center
    with pytest.raises(ValueError, match="pitch_center"):
        TRMSTuning(Scenario(pitch_center=0.25))


def test_loss_terms_equal_an_independent_recomputation_from_the_trajectory(problem):
    theta = jnp.asarray(problem.bryson_theta())
    b = jax.jit(problem.breakdown)(theta)
    params = problem.design(theta)
    loop = problem.closed_loop(params, problem.plant_params(), SHORT.noise_std)
    tr = simulate(loop, problem.x_eq, Timing(t_final=SHORT.t_final, dt=SHORT.ts), key=jax.random.PRNGKey(0))
    t, r, y, u = (np.asarray(v) for v in (tr.t, tr.r, tr.y, tr.u))
    period, t0 = np.array([SHORT.pitch_period, SHORT.yaw_period]), np.array([0.0, SHORT.yaw_delay])
    since = np.mod(t[:, None] - t0, period / 2)
    u_max = float(problem.nominal.u_max)
    itae = np.sum(since * np.abs(r - y)) * SHORT.ts
    energy = np.sum((np.clip(u, -u_max, u_max) - np.asarray(params.u_eq)) ** 2) * SHORT.ts
    sat = np.sum(np.maximum(np.abs(u) - u_max, 0) ** 2) * SHORT.ts
    np.testing.assert_allclose([b.itae, b.energy, b.saturation], [itae, energy, sat], rtol=1e-10, atol=1e-14)
    assert float(b.stability) == 0.0  # Bryson's design is stable at 100 Hz
    expected = itae + SHORT.rho_energy * energy + SHORT.kappa_saturation * sat
    np.testing.assert_allclose(b.total, expected, rtol=1e-12)


def test_gradient_through_riccati_and_rollout_matches_finite_differences(problem):
    theta = jnp.asarray(problem.bryson_theta()) + 0.3
    loss = jax.jit(problem.loss)
    g_fwd = np.asarray(jax.jit(jax.jacfwd(problem.loss))(theta))  # the mode the tuner uses
    assert g_fwd.shape == (N_THETA,)
    for i in (0, 4, 7, 8, 9, 15):  # Q pitch, Q τ1, R u1, R u2, W ψ, W M_R
        e = np.eye(N_THETA)[i] * 1e-5
        fd = (float(loss(theta + e)) - float(loss(theta - e))) / 2e-5
        assert abs(g_fwd[i] - fd) <= 1e-5 * np.abs(g_fwd).max(), (i, g_fwd[i], fd)


def test_an_unstable_sampled_loop_is_penalised(problem):
    theta = np.asarray(problem.bryson_theta())
    theta[:7] += np.log(1e7)  # enormous state weights: gains beyond what 100 Hz sampling can carry
    params = problem.design(jnp.asarray(theta))
    assert float(problem.stability_violation(params)) > 0
    assert float(problem.stability_penalty(params)) > 0
    g = jax.grad(lambda th: problem.stability_penalty(problem.design(th)))(jnp.asarray(theta))
    assert np.all(np.isfinite(np.asarray(g))) and np.abs(np.asarray(g)).max() > 0
