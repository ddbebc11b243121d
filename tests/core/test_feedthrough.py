"""Plants with direct feedthrough (``y = output(x) + D u``) in the closed loop: the sampler reads ``y_k``
with the input held over the previous period, the shapes are checked when the loop is built, and
``linearize`` returns the ``D``."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.core.discretize import c2d_zoh
from jaxsim.core.integrators import ExponentialEuler
from jaxsim.core.linearize import linearize
from jaxsim.core.rollout import ClosedLoop, Timing, fold, simulate
from jaxsim.core.signals import Step
from jaxsim.core.system import Controller, Plant
from jaxsim.lti import ss

A = np.array([[0.0, 1.0], [-2.0, -0.7]])
B = np.array([[0.0], [1.5]])
C = np.array([[1.0, 0.3]])
D = np.array([[0.4]])
KP, REF, TS = 1.3, 1.0, 0.05


def _p_step(params, state, r, y, dt, t=None):  # t: the tick time of the newer controller signature
    return state, params * (r - y)


P_CONTROLLER = Controller(params=jnp.asarray(KP), init=lambda p, r0, y0: jnp.zeros(()), step=_p_step, name="p")


def _expected(n_ticks: int) -> tuple[np.ndarray, np.ndarray]:
    """The sampled-data loop by hand: y_k = C x_k + D u_{k−1} (u_{−1} = 0), u_k = Kp (r − y_k)."""
    ad, bd = (np.asarray(m) for m in c2d_zoh(A, B, TS))
    x, u_prev = np.zeros(2), np.zeros(1)
    ys, us = [], []
    for _ in range(n_ticks):
        y = C @ x + D @ u_prev
        u = KP * (REF - y)
        ys.append(y)
        us.append(u)
        x = ad @ x + bd @ u
        u_prev = u
    return np.array(ys), np.array(us)


def test_the_sampler_reads_the_output_with_the_previous_input_held():
    loop = ClosedLoop(ss(A, B, C, D), P_CONTROLLER, reference=Step(REF))
    tr = simulate(loop, jnp.zeros(2), Timing(t_final=1.0, dt=TS), solver=ExponentialEuler())
    y_ref, u_ref = _expected(20)
    np.testing.assert_allclose(np.asarray(tr.y), y_ref, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(np.asarray(tr.y_meas), y_ref, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(np.asarray(tr.u), u_ref, rtol=1e-12, atol=1e-14)
    # the feedthrough really acts: with D = 0 the loop is different from the first input on
    no_d = simulate(
        ClosedLoop(ss(A, B, C, 0.0), P_CONTROLLER, reference=Step(REF)),
        jnp.zeros(2),
        Timing(t_final=1.0, dt=TS),
        solver=ExponentialEuler(),
    )
    assert abs(float(no_d.y[1, 0] - tr.y[1, 0])) > 0.1


def test_fold_and_gradients_see_the_feedthrough():
    timing = Timing(t_final=1.0, dt=TS)

    def cost(d):
        loop = ClosedLoop(ss(A, B, C, d), P_CONTROLLER, reference=Step(REF))
        return fold(loop, jnp.zeros(2), timing, lambda acc, tick: acc + tick.y[0] ** 2, 0.0, solver=ExponentialEuler())[
            0
        ]

    y_ref, _ = _expected(20)
    np.testing.assert_allclose(float(cost(D)), float(np.sum(y_ref**2)), rtol=1e-12)
    g = float(jax.grad(cost)(jnp.asarray(D)).squeeze())
    h = 1e-6
    fd = (float(cost(D + h)) - float(cost(D - h))) / (2 * h)
    np.testing.assert_allclose(g, fd, rtol=1e-6)


def test_a_feedthrough_of_the_wrong_shape_is_rejected_when_the_loop_is_built():
    plant = Plant(
        params=None,
        dynamics=lambda p, x, u, t: -x + u,
        output=lambda p, x: x,
        n_states=1,
        n_inputs=1,
        n_outputs=1,
        name="bad",
        feedthrough=lambda p, u: jnp.ones(2) * u,
    )
    loop = ClosedLoop(plant, P_CONTROLLER, reference=Step(REF))
    with pytest.raises(
        ValueError, match=r"plant 'bad': feedthrough\(params, u\) returns shape \(2,\), expected \(1,\)"
    ):
        simulate(loop, jnp.zeros(1), Timing(t_final=0.1, dt=TS))
    with pytest.raises(ValueError, match=r"feedthrough\(params, u\)"):
        jax.jit(lambda lp: simulate(lp, jnp.zeros(1), Timing(t_final=0.1, dt=TS)).y)(loop)


def test_h_without_the_input_is_refused_for_a_feedthrough_plant():
    plant = ss(A, B, C, D)
    with pytest.raises(ValueError, match=r"^u: plant 'lti' has a feedthrough term"):
        plant.h(jnp.zeros(2))
    np.testing.assert_allclose(np.asarray(plant.h(jnp.ones(2), jnp.ones(1))), C @ np.ones(2) + D @ np.ones(1))


def test_linearize_returns_the_feedthrough_matrix():
    lin = linearize(ss(A, B, C, D), jnp.zeros(2), jnp.zeros(1))
    for got, want in zip(lin, (A, B, C, D)):
        np.testing.assert_array_equal(np.asarray(got), want)
