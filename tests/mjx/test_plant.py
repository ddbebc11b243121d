"""The generic MJCF adapter against C MuJoCo (the oracle) and its input checks."""

from __future__ import annotations

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pytest.importorskip("mujoco.mjx")

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from jaxsim.control.open_loop import feedforward  # noqa: E402
from jaxsim.core.integrators import EULER  # noqa: E402
from jaxsim.core.rollout import ClosedLoop, Timing, simulate  # noqa: E402
from jaxsim.core.signals import Sine  # noqa: E402
from jaxsim.mjx import mjcf_params, mjcf_plant, qpos_rate, step_sequence  # noqa: E402

# A damped double pendulum (two hinges, two motors) next to a free-floating body (quaternion qpos).
XML = """<mujoco>
  <option timestep="0.002" integrator="Euler"/>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" damping="0.05"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.03" mass="1" contype="0" conaffinity="0"/>
      <body name="lower" pos="0 0 -0.5">
        <joint name="elbow" type="hinge" axis="0 1 0" damping="0.02"/>
        <geom type="capsule" fromto="0 0 0 0.1 0 -0.4" size="0.03" mass="0.5" contype="0" conaffinity="0"/>
      </body>
    </body>
    <body name="float" pos="2 0 0">
      <joint name="free" type="free"/>
      <geom type="box" size="0.1 0.2 0.3" mass="2" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="m_shoulder" joint="shoulder"/>
    <motor name="m_elbow" joint="elbow"/>
  </actuator>
  <sensor>
    <jointpos name="elbow_angle" joint="elbow"/>
  </sensor>
</mujoco>"""


@pytest.fixture(scope="module")
def model():
    return mujoco.MjModel.from_xml_string(XML)


def _initial_state(model) -> np.ndarray:
    data = mujoco.MjData(model)
    data.qpos[:2] = [0.4, -0.3]
    data.qvel[:] = [0.5, -1.0, 0.1, 0.2, 0.3, 1.5, -2.0, 0.7]
    return np.concatenate([data.qpos, data.qvel])


def test_step_sequence_equals_c_mujoco(model):
    """``lax.scan`` of ``mjx.step`` reproduces C MuJoCo's ``mj_step`` (same integrator)."""
    x0 = _initial_state(model)
    k = np.arange(200)
    controls = np.stack([0.3 * np.sin(0.05 * k), -0.2 * np.cos(0.03 * k)], axis=1)
    xs = np.asarray(jax.jit(step_sequence)(mjcf_params(model), jnp.asarray(x0), jnp.asarray(controls)))
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = x0[: model.nq], x0[model.nq :]
    expected = []
    for u in controls:
        data.ctrl[:] = u
        mujoco.mj_step(model, data)
        expected.append(np.concatenate([data.qpos, data.qvel]))
    np.testing.assert_allclose(xs, np.array(expected), atol=1e-9, rtol=0)
    # the step-field plant simulated with Euler at dt = timestep is the same map
    plant = mjcf_plant(model, field="step")
    loop = ClosedLoop(
        plant=plant,
        controller=feedforward(),
        reference=Sine(
            amplitude=jnp.array([0.3, -0.2]), frequency=jnp.array([0.0, 0.0]), phase=jnp.array([np.pi / 2, np.pi / 2])
        ),
    )
    traj = jax.jit(lambda x: simulate(loop, x, Timing(t_final=0.2, dt=0.002), solver=EULER))(jnp.asarray(x0))
    data.qpos[:], data.qvel[:] = x0[: model.nq], x0[model.nq :]
    data.ctrl[:] = [0.3, -0.2]
    for _ in range(100):
        mujoco.mj_step(model, data)
    np.testing.assert_allclose(traj.x_final, np.concatenate([data.qpos, data.qvel]), atol=1e-9)


def test_forward_field_matches_c_mujoco(model):
    """``(q̇pos, qacc)``: ``qacc`` equals C ``mj_forward``; ``q̇pos`` (quaternion part included) equals the
    finite-difference slope of C ``mj_integratePos``."""
    x0 = _initial_state(model)
    u = np.array([0.7, -0.4])
    plant = mjcf_plant(model)
    xdot = np.asarray(jax.jit(plant.f)(jnp.asarray(x0), jnp.asarray(u), 0.0))
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:], data.ctrl[:] = x0[: model.nq], x0[model.nq :], u
    mujoco.mj_forward(model, data)
    np.testing.assert_allclose(xdot[model.nq :], data.qacc, atol=1e-10)
    eps = 1e-7
    qa, qb = data.qpos.copy(), data.qpos.copy()
    mujoco.mj_integratePos(model, qa, data.qvel, eps)
    mujoco.mj_integratePos(model, qb, data.qvel, -eps)
    np.testing.assert_allclose(xdot[: model.nq], (qa - qb) / (2 * eps), atol=1e-7)
    lay = mjcf_params(model).layout
    np.testing.assert_allclose(qpos_rate(lay, jnp.asarray(data.qpos), jnp.asarray(data.qvel)), xdot[: model.nq])


def test_outputs_by_name_and_vmap(model):
    plant = mjcf_plant(model, outputs=("elbow_angle", "qvel:shoulder", "free"))
    assert plant.n_outputs == 1 + 1 + 7
    xs = jnp.asarray(np.stack([_initial_state(model) * s for s in (1.0, 0.5, -0.2)]))
    ys = jax.jit(jax.vmap(plant.h))(xs)
    for x, y in zip(np.asarray(xs), np.asarray(ys)):  # vmap == the state entries it names
        np.testing.assert_allclose(y, np.concatenate([[x[1]], [x[model.nq]], x[2:9]]), atol=1e-12)


def test_errors_name_the_problem(model):
    with pytest.raises(ValueError, match="outputs: no sensor or joint named 'wrist'"):
        mjcf_plant(model, outputs=("wrist",))
    with pytest.raises(ValueError, match="field"):
        mjcf_plant(model, field="rk45")
    with pytest.raises(ValueError, match="source"):
        mjcf_plant("/no/such/model.xml")
    plant = mjcf_plant(model)
    with pytest.raises(ValueError, match=r"u: expected shape \(2,\)"):
        plant.f(jnp.asarray(_initial_state(model)), jnp.zeros(3), 0.0)
    with pytest.raises(ValueError, match=r"x: expected shape \(17,\)"):
        plant.f(jnp.zeros(5), jnp.zeros(2), 0.0)
