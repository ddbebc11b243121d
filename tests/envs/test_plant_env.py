"""jaxsim.envs: brax API expectations, equivalence with simulate, rewards = −study loss."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal

pytest.importorskip("brax")

import brax.envs  # noqa: E402
from brax.envs.wrappers.training import VmapWrapper, wrap  # noqa: E402

import jaxsim.envs  # noqa: E402  (registers the envs)
from jaxsim.control.open_loop import open_loop  # noqa: E402
from jaxsim.core.metrics import itae  # noqa: E402
from jaxsim.core.rollout import ClosedLoop, Timing, simulate  # noqa: E402
from jaxsim.envs import PlantEnv, Task, static_second_order_env, trms_env  # noqa: E402
from jaxsim.plants.second_order import StaticParams, static_plant  # noqa: E402
from jaxsim.problem.trms import Scenario, TRMSTuning  # noqa: E402

N = 40  # ticks per rollout: short horizons keep compile and run times small


def env_rollout(env, actions, key=jax.random.PRNGKey(0)):  # noqa: B008  (an immutable default)
    """States before each step, rewards, final state of a jitted single-env rollout."""

    @jax.jit
    def run(key, actions):
        def body(s, a):
            s2 = env.step(s, a)
            return s2, (s.pipeline_state.x, s2.reward, s2.done)

        return jax.lax.scan(body, env.reset(key), actions)

    return run(key, actions)


@pytest.fixture(scope="module")
def short_trms():
    """The study's TRMS problem cut to N ticks (same references, weights and trim point)."""
    problem = TRMSTuning(Scenario(t_final=N * 0.01))
    return problem, trms_env(problem)


def random_actions(key, n, m):
    return jax.random.uniform(key, (n, m), minval=-1.2, maxval=1.2)  # some beyond ±1: clipped


def test_registered_and_sized():
    env = brax.envs.get_environment("jaxsim_static_second_order")
    assert isinstance(env, PlantEnv)
    assert env.action_size == 1 and env.observation_size == 3  # (y, ẏ, r − y)
    assert env.backend == "jaxsim"
    for name in ("jaxsim_astatic_second_order", "jaxsim_trms"):
        assert name in brax.envs._envs
    s = jax.jit(env.reset)(jax.random.PRNGKey(0))
    s = jax.jit(env.step)(s, jnp.array([0.5]))
    assert s.obs.shape == (3,) and s.reward.shape == () and s.done.shape == ()


def test_static_env_matches_zoh_oracle_and_itae():
    """Under piecewise-constant inputs the env's RK4 steps follow SciPy's exact ZOH discretisation,
    and −Σ rewards is the ITAE of the trajectory (jaxsim.core.metrics.itae).  10 RK4 substeps per
    period (dt/10 = 1 ms) bring the integration error far below the tolerance."""
    p = StaticParams()
    env = static_second_order_env(p, u_max=5.0, substeps=10)
    actions = random_actions(jax.random.PRNGKey(1), N, 1)
    (_, (xs, rewards, done)) = env_rollout(env, actions)
    u = np.clip(np.asarray(actions[:, 0]), -1, 1) * 5.0
    a = np.array([[0, 1], [-1 / (p.T1 * p.T2), -(p.T1 + p.T2) / (p.T1 * p.T2)]])
    b = np.array([[0], [p.K / (p.T1 * p.T2)]])
    ad, bd, *_ = scipy.signal.cont2discrete((a, b, np.eye(2), np.zeros((2, 1))), 0.01, method="zoh")
    x, ref = np.zeros(2), []
    for k in range(N):
        ref.append(x)
        x = ad @ x + bd[:, 0] * u[k]
    np.testing.assert_allclose(np.asarray(xs), np.array(ref), atol=1e-8)
    t = 0.01 * np.arange(N)
    assert -float(jnp.sum(rewards)) == pytest.approx(float(itae(jnp.asarray(t), 1.0 - xs[:, 0])), rel=1e-12)
    assert not bool(jnp.any(done))


def test_trms_env_equals_simulate_and_study_loss(short_trms):
    """Same inputs: env states == simulate (open-loop controller); rewards == −study step loss;
    −Σ rewards == the study's loss of that simulation (its fold over ticks, stability term 0)."""
    problem, env = short_trms
    actions = random_actions(jax.random.PRNGKey(2), N, 2)
    (last, (xs, rewards, _)) = env_rollout(env, actions)
    u = jax.vmap(env.input)(actions)
    np.testing.assert_allclose(np.asarray(u), np.clip(np.asarray(actions), -1, 1) * 2.5, rtol=1e-14, atol=1e-15)
    loop = ClosedLoop(env.task.plant, open_loop(u), reference=problem.reference)
    tr = jax.jit(lambda lp: simulate(lp, problem.x_eq, problem.timing))(loop)
    np.testing.assert_allclose(np.asarray(xs), np.asarray(tr.x), rtol=0, atol=1e-13)
    np.testing.assert_allclose(np.asarray(last.pipeline_state.x), np.asarray(tr.x_final), atol=1e-13)
    per_step = jax.vmap(lambda t, r, y, uk: problem.step_loss(t, r, y, uk, 2.5))(tr.t, tr.r, tr.y, tr.u)
    np.testing.assert_allclose(np.asarray(rewards), -np.asarray(per_step), rtol=1e-13, atol=1e-16)
    study_loss = problem.combine(problem.loop_terms(loop, jax.random.PRNGKey(0)), 0.0).total
    assert -float(jnp.sum(rewards)) == pytest.approx(float(study_loss), rel=1e-12)
    assert float(study_loss) > 0


def test_vmap_equals_loop(short_trms):
    """brax's VmapWrapper over 3 envs (random initial spread) equals three single-env rollouts."""
    problem, _ = short_trms
    env = trms_env(problem, x0_spread=jnp.array([0.05, 0.05, 0.1, 0.1, 0.0, 0.0, 0.0]))
    batched = VmapWrapper(env, batch_size=3)
    actions = random_actions(jax.random.PRNGKey(3), 3 * 5, 2).reshape(5, 3, 2)

    @jax.jit
    def run_batch(key):
        s = batched.reset(key)
        for a in actions:
            s = batched.step(s, a)
        return s

    sb = run_batch(jax.random.PRNGKey(4))
    keys = jax.random.split(jax.random.PRNGKey(4), 3)
    reset, step = jax.jit(env.reset), jax.jit(env.step)
    for i in range(3):
        s = reset(keys[i])
        for a in actions:
            s = step(s, a[i])
        np.testing.assert_allclose(np.asarray(sb.obs[i]), np.asarray(s.obs), rtol=1e-12, atol=1e-15)
        assert float(sb.reward[i]) == pytest.approx(float(s.reward), rel=1e-12)
    # the spread perturbs the initial angles
    assert float(jnp.std(sb.pipeline_state.x[:, 0])) > 1e-3


def test_training_wrappers_truncate_and_auto_reset():
    """brax.envs.wrappers.training.wrap: after episode_length steps done = truncation = 1 and the
    auto-reset restores the initial observation; a terminated (failed) episode is not truncation."""
    env = static_second_order_env(u_max=5.0)
    wrapped = wrap(env, episode_length=3, action_repeat=1)
    reset, step = jax.jit(wrapped.reset), jax.jit(wrapped.step)
    s0 = reset(jax.random.split(jax.random.PRNGKey(0), 2))
    s = s0
    for k in range(3):
        s = step(s, jnp.ones((2, 1)))
        assert np.all(np.asarray(s.done) == (k == 2))
    assert np.all(np.asarray(s.info["truncation"]) == 1)
    np.testing.assert_array_equal(np.asarray(s.obs), np.asarray(s0.obs))  # auto-reset
    assert np.all(np.asarray(s.info["steps"]) == 3)

    failing = Task(
        plant=static_plant(),
        step_loss=lambda t, r, y, u: 0.0 * t,
        u_low=-5.0,
        u_high=5.0,
        dt=0.01,
        x0=jnp.zeros(2),
        terminate=lambda x: x[0] > 1e-4,
    )
    w2 = wrap(PlantEnv(failing), episode_length=100, action_repeat=1)
    s = jax.jit(w2.reset)(jax.random.split(jax.random.PRNGKey(0), 1))
    st = jax.jit(w2.step)
    for _ in range(20):
        s = st(s, jnp.ones((1, 1)))
        if bool(s.done[0]):
            break
    assert bool(s.done[0]) and float(s.info["truncation"][0]) == 0.0


def test_action_mapping_and_bad_input():
    env = PlantEnv(
        Task(
            plant=static_plant(), step_loss=lambda t, r, y, u: 0.0 * t, u_low=-1.0, u_high=3.0, dt=0.01, x0=jnp.zeros(2)
        )
    )
    u = jax.vmap(env.input)(jnp.array([[-1.0], [0.0], [1.0], [7.0]]))
    np.testing.assert_allclose(np.asarray(u[:, 0]), [-1.0, 1.0, 3.0, 3.0])
    assert float(env.action(env.input(jnp.array([0.3])))[0]) == pytest.approx(0.3)
    base = dict(plant=static_plant(), step_loss=lambda t, r, y, u: 0.0 * t, dt=0.01, x0=jnp.zeros(2))
    with pytest.raises(ValueError, match="u_high"):
        Task(**base, u_low=1.0, u_high=1.0)
    with pytest.raises(ValueError, match="x0"):
        Task(**{**base, "x0": jnp.zeros(3)}, u_low=-1.0, u_high=1.0)
    with pytest.raises(ValueError, match="dt"):
        Task(**{**base, "dt": 0.0}, u_low=-1.0, u_high=1.0)
    with pytest.raises(ValueError, match="u_seq"):
        open_loop(jnp.zeros(3))


def test_auv_env_equals_simulate_and_rest_is_equilibrium():
    """AUV env: same inputs → same states as simulate (control period 0.05 s, 5 RK4 substeps);
    rewards = −(‖η* − η‖² + 1e-3 ‖τ/100‖²)·dt from the trajectory; at rest with zero thrust the
    neutrally buoyant AUV stays put and each reward is −‖η*‖²·dt exactly."""
    env = brax.envs.get_environment("jaxsim_auv")
    assert env.action_size == 6 and env.observation_size == 24
    n = 10
    actions = random_actions(jax.random.PRNGKey(5), n, 6)
    (_, (xs, rewards, _)) = env_rollout(env, actions)
    u = jax.vmap(env.input)(actions)
    loop = ClosedLoop(env.task.plant, open_loop(u))
    tr = jax.jit(lambda lp: simulate(lp, jnp.zeros(12), Timing(n * 0.05, 0.01, controller_period=0.05)))(loop)
    np.testing.assert_allclose(np.asarray(xs), np.asarray(tr.x), rtol=0, atol=1e-13)
    target = np.array(jaxsim.envs.auv.DEFAULT_TARGET)
    expected = (
        np.sum((target - np.asarray(tr.x)[:, :6]) ** 2, axis=1) + 1e-3 * np.sum((np.asarray(u) / 100.0) ** 2, axis=1)
    ) * 0.05
    np.testing.assert_allclose(np.asarray(rewards), -expected, rtol=1e-12)
    assert float(jnp.max(jnp.abs(xs[-1]))) > 1e-3  # the random thrust moved it

    (last, (xs0, rewards0, _)) = env_rollout(env, jnp.zeros((n, 6)))
    assert float(jnp.max(jnp.abs(last.pipeline_state.x))) < 1e-12
    np.testing.assert_allclose(np.asarray(rewards0), -np.sum(target**2) * 0.05, rtol=1e-12)
    with pytest.raises(ValueError, match="target"):
        jaxsim.envs.auv_env(target=(1.0, 2.0))
