"""PlantEnv.from_problem: replaying the problem's own controller inputs through the env gives
``−Σ rewards`` equal to the problem's objective total on the same run (a disturbed loop)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

pytest.importorskip("brax")

from jaxsim.core import costs  # noqa: E402
from jaxsim.core.signals import Step  # noqa: E402
from jaxsim.envs import PlantEnv  # noqa: E402
from jaxsim.problem import Param, ParamSpace, Problem, Scenario  # noqa: E402
from optim.problems import PIDTuning  # noqa: E402

TUNING = PIDTuning(t_final=0.4)


def _build(p, d):
    loop = TUNING.closed_loop(p["gains"])
    loop = type(loop)(loop.plant, loop.controller, reference=loop.reference, disturbance=Step(d["f"], 0.1))
    return Scenario(loop, jnp.zeros(2), TUNING.timing)


SPACE = ParamSpace(gains=Param(lo=(0, 0, 0), hi=(20, 20, 2), init=(6.0, 4.0, 0.3)))
OBJECTIVE = costs.combine(itae=costs.itae(), energy=(0.01, costs.control_energy()))


def test_env_rewards_replay_the_problems_objective():
    pb = Problem("pid", SPACE, OBJECTIVE, _build, nominal={"f": 0.3})
    env = PlantEnv.from_problem(pb, u_low=-50.0, u_high=50.0)
    tr = pb.simulate(SPACE.init)
    actions = jax.vmap(env.action)(tr.u)

    @jax.jit
    def run(actions):
        def body(s, a):
            s2 = env.step(s, a)
            return s2, (s.pipeline_state.x, s2.reward)

        return jax.lax.scan(body, env.reset(jax.random.PRNGKey(0)), actions)

    _, (xs, rewards) = run(actions)
    np.testing.assert_allclose(xs, tr.x, rtol=1e-10, atol=1e-12)
    total = float(pb.evaluate(SPACE.init).total)
    assert -float(jnp.sum(rewards)) == pytest.approx(total, rel=1e-10)
    assert env.action_size == 1 and env.task.dt == pytest.approx(TUNING.ts)


def test_from_problem_needs_an_additive_objective():
    soft = Problem("pid", SPACE, costs.combine(os=costs.soft_overshoot()), _build, nominal={"f": 0.0})
    with pytest.raises(ValueError, match="not additive"):
        PlantEnv.from_problem(soft)
    loss_only = Problem.from_loss("q", SPACE, lambda p, d, k: jnp.sum(p["gains"]))
    with pytest.raises(ValueError, match="needs an objective"):
        PlantEnv.from_problem(loss_only)
