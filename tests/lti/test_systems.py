"""``ss``/``tf``/``zpk`` and the block-diagram algebra against python-control; the results are toolkit
plants that run in a closed loop and differentiate."""

import control as ct
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxsim.lti as lt
from experiments.benchmarks.python_control_agreement import random_ss, random_tf, rel_diff, to_ours
from jaxsim.core.integrators import ExponentialEuler
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Step
from jaxsim.core.system import Controller, Plant

W = np.logspace(-2, 2, 9)


def _response(sys):
    return lt.frequency_response(sys, W, squeeze=False).response


def _reference(sys):
    return ct.frequency_response(sys, W, squeeze=False).complex


@pytest.mark.parametrize("seed", [0, 1])
def test_ss_tf_zpk_agree_with_python_control(seed):
    rng = np.random.default_rng(seed)
    sys = random_ss(rng, 3, 2, 2)
    assert rel_diff(_response(to_ours(sys)), _reference(sys)) < 1e-12
    num, den = random_tf(rng, 3)
    assert rel_diff(lt.evalfr(lt.tf(num, den), 1j * W)[:, 0, 0], ct.tf(num, den)(1j * W)) < 1e-12
    z, p, k = np.roots(num), np.roots(den), num[0] / den[0]
    assert rel_diff(lt.evalfr(lt.zpk(z, p, k), 1j * W)[:, 0, 0], ct.zpk(z, p, k)(1j * W)) < 1e-12


def test_continuous_systems_are_plants_and_discrete_ones_state_spaces():
    g = lt.tf([2.0, 1.0], [1.0, 3.0])  # biproper: D = 2
    assert isinstance(g, Plant) and g.feedthrough is not None
    np.testing.assert_allclose(np.asarray(g.params.d), [[2.0]])
    np.testing.assert_allclose(
        np.asarray(g.h(jnp.array([0.5]), jnp.array([1.0]))), np.asarray(g.params.c @ jnp.array([0.5]) + 2.0)
    )
    gd = lt.tf([1.0], [1.0, -0.5], dt=0.1)
    assert isinstance(gd, lt.StateSpace) and gd.dt == 0.1
    assert lt.ss(-1.0, 1.0, 1.0, 0.0).n_states == 1  # python-control's scalar form
    assert lt.tf([0.0, 0.0, 1.0], [0.0, 1.0, 1.0]).n_states == 1  # exact leading zeros dropped


def test_a_tf_plant_runs_in_a_closed_loop_like_python_controls_sampled_loop():
    """P control of 1/(s² + s + 1) with zero-order hold: the loop matches python-control's
    ``feedback(c2d(P), K)`` sampled at the ticks."""
    plant, kp, ts = lt.tf([1.0], [1.0, 1.0, 1.0]), 2.0, 0.1
    ctrl = Controller(
        params=jnp.asarray(kp),
        init=lambda p, r0, y0: jnp.zeros(()),
        step=lambda p, s, r, y, dt, t=None: (s, p * (r - y)),
    )
    tr = simulate(
        ClosedLoop(plant, ctrl, reference=Step(1.0)), jnp.zeros(2), Timing(2.0, ts), solver=ExponentialEuler()
    )
    ref = ct.step_response(ct.feedback(kp * ct.c2d(ct.tf([1.0], [1.0, 1.0, 1.0]), ts), 1), np.arange(20) * ts)
    np.testing.assert_allclose(np.asarray(tr.y[:, 0]), ref.outputs, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("seed", [0, 1])
def test_series_parallel_feedback_agree_with_python_control(seed):
    rng = np.random.default_rng(seed)
    g1, g3 = random_ss(rng, 2, 2, 1), random_ss(rng, 2, 2, 1)
    g2 = random_ss(rng, 2, 1, 2)
    g2 = ct.ss(g2.A, g2.B, g2.C, 0.3 * g2.D)
    assert rel_diff(_response(lt.series(to_ours(g1), to_ours(g2))), _reference(ct.series(g1, g2))) < 1e-12
    assert rel_diff(_response(lt.parallel(to_ours(g1), to_ours(g3))), _reference(ct.parallel(g1, g3))) < 1e-12
    for sign in (-1, 1):
        assert (
            rel_diff(_response(lt.feedback(to_ours(g1), to_ours(g2), sign)), _reference(ct.feedback(g1, g2, sign)))
            < 1e-11
        )


def test_gains_and_discrete_parts_combine():
    g = lt.tf([1.0], [1.0, 1.0])
    closed = lt.feedback(lt.series(3.0, g))  # 3/(s + 4)
    np.testing.assert_allclose(float(lt.dcgain(closed)), 0.75, rtol=1e-14)
    gd = lt.c2d(g, 0.1)
    cd = lt.feedback(gd, 2.0)
    assert isinstance(cd, lt.StateSpace) and cd.dt == 0.1
    ref = ct.feedback(ct.c2d(ct.tf([1.0], [1.0, 1.0]), 0.1), 2.0)
    z = np.exp(1j * W * 0.1)
    assert rel_diff(lt.evalfr(cd, z)[:, 0, 0], ref(z)) < 1e-13


def test_closed_loop_dc_gain_is_differentiable_through_tf_and_feedback():
    """T(0) = k·b/(a + k·b) for k·b/(s + a) in unity feedback."""

    def t0(theta):
        k, a = theta
        return lt.dcgain(lt.feedback(lt.series(k, lt.tf(jnp.array([2.0]), jnp.stack([1.0, a])))))

    theta = jnp.array([1.5, 0.7])
    grad = np.asarray(jax.grad(t0)(theta))
    k, a, b = 1.5, 0.7, 2.0
    want = [a * b / (a + k * b) ** 2, -k * b / (a + k * b) ** 2]
    np.testing.assert_allclose(grad, want, rtol=1e-12)
    np.testing.assert_allclose(float(jax.jit(t0)(theta)), k * b / (a + k * b), rtol=1e-14)
