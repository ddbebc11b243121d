"""PPO baseline of the ``trms_lqr_tuning`` study: brax's PPO trained on the study's TRMS task
(:func:`jaxsim.envs.trms_env`, reward = −per-step loss), its policy evaluated with the study's loss.

The trained policy is rolled out deterministically (the mode of its action distribution) from the
trim state over the study's horizon; its inputs are then replayed through the study's own loss
(:meth:`~jaxsim.problem.trms.TRMSTuning.loop_terms` on an open-loop controller), so the PPO
row is scored exactly as the LQG designs (no stability penalty: it applies to linear designs only).
Budget: environment steps (controller ticks) and wall time of ``ppo.train`` *including* its
compilation, which brax does inside ``train``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control.open_loop import open_loop
from jaxsim.core.rollout import ClosedLoop
from jaxsim.problem.trms import Breakdown, TRMSTuning


@dataclass(frozen=True)
class PPOSettings:
    """brax PPO hyper-parameters (names as in ``brax.training.agents.ppo.train``)."""

    num_timesteps: int
    num_envs: int = 64
    batch_size: int = 64
    num_minibatches: int = 8
    unroll_length: int = 20
    num_updates_per_batch: int = 4
    action_repeat: int = 5
    learning_rate: float = 1e-3
    entropy_cost: float = 1e-3
    discounting: float = 0.98
    reward_scaling: float = 1.0
    angle_spread: float = 0.05  # rad, uniform ± perturbation of the initial angles in training
    seed: int = 0


class PolicyRollout(NamedTuple):
    """Deterministic rollout: ``t, x, u`` per tick ``(N,), (N, 7), (N, 2)``; ``reward (N,)``."""

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    reward: np.ndarray


class PPOResult(NamedTuple):
    loss: Breakdown  # the study's loss of the policy's inputs (friction surrogate, as the tuners)
    loss_exact_friction: float  # −Σ rewards of the policy on the plant with exact sgn friction
    env_steps: int  # controller ticks simulated in training
    wall_s: float  # ppo.train wall time, compilation included
    rollout: PolicyRollout  # exact-friction rollout (for the response plot)

    def design_row(self) -> dict[str, Any]:
        """The study's ``designs`` row (no stability penalty: it applies to linear designs only)."""
        b = self.loss
        terms = {"itae": b.itae, "energy": b.energy, "saturation": b.saturation, "stability_penalty": 0.0}
        return {"design": "brax_ppo", "loss": b.total, **terms, "loss_exact_friction": self.loss_exact_friction}

    def report(self, n_ticks: int) -> tuple[dict[str, float], dict[str, Any]]:
        """The study's PPO metrics and its ``tuners`` row; ``n_ticks`` per episode turns env steps
        into simulations of the horizon."""
        episodes = self.env_steps / n_ticks
        metrics = {
            "loss_rl_ppo": self.loss.total,
            "loss_exact_friction_rl_ppo": self.loss_exact_friction,
            "return_rl_ppo": -self.rollout_loss,  # Σ env rewards: must equal −loss_rl_ppo
            "env_steps_rl_ppo": self.env_steps,
            "sims_rl_ppo": episodes,
            "wall_rl_ppo_s": self.wall_s,
        }
        row = {
            "tuner": "brax_ppo",
            "best_loss": self.loss.total,
            "sims": episodes,
            "wall_s": self.wall_s,
            "message": f"{self.env_steps} env steps (ticks) = {episodes:.0f} episodes of the horizon; "
            "wall time includes brax's compilation",
        }
        return metrics, row

    rollout_loss: float  # −Σ env rewards of the policy rollout on the surrogate plant (== loss.total)


def policy_rollout(env: Any, policy: Any, n_ticks: int, repeat: int) -> PolicyRollout:
    """Roll ``policy`` (deterministic) out for ``n_ticks`` ticks, holding each action ``repeat`` ticks."""
    if n_ticks % repeat:
        raise ValueError(f"n_ticks: must be a multiple of action_repeat ({repeat}), got {n_ticks}")

    @jax.jit
    def run(key):
        def decide(s, _):
            a, _ = policy(s.obs, key)

            def tick(s, _):
                s2 = env.step(s, a)
                return s2, (env.time(s.pipeline_state.k), s.pipeline_state.x, env.input(a), s2.reward)

            return jax.lax.scan(tick, s, None, length=repeat)

        _, out = jax.lax.scan(decide, env.reset(key), None, length=n_ticks // repeat)
        return jax.tree_util.tree_map(lambda v: v.reshape((n_ticks,) + v.shape[2:]), out)

    return PolicyRollout(*(np.asarray(v) for v in run(jax.random.PRNGKey(0))))


def train_and_evaluate(problem: TRMSTuning, settings: PPOSettings) -> PPOResult:
    """Train brax PPO on the study's task and score its deterministic policy with the study's loss."""
    from brax.training.agents.ppo import train as ppo

    from jaxsim.envs import trms_env

    n_ticks = int(round(problem.scenario.t_final / problem.scenario.ts))
    spread = jnp.zeros(7).at[:2].set(settings.angle_spread)
    env = trms_env(problem, x0_spread=spread)
    start = time.perf_counter()
    make_policy, params, _ = ppo.train(
        env,
        num_timesteps=settings.num_timesteps,
        episode_length=n_ticks,
        action_repeat=settings.action_repeat,
        num_envs=settings.num_envs,
        batch_size=settings.batch_size,
        num_minibatches=settings.num_minibatches,
        unroll_length=settings.unroll_length,
        num_updates_per_batch=settings.num_updates_per_batch,
        learning_rate=settings.learning_rate,
        entropy_cost=settings.entropy_cost,
        discounting=settings.discounting,
        reward_scaling=settings.reward_scaling,
        normalize_observations=True,
        seed=settings.seed,
        num_evals=0,
        run_evals=False,
    )
    wall = time.perf_counter() - start
    per_step = settings.batch_size * settings.unroll_length * settings.num_minibatches * settings.action_repeat
    env_steps = int(np.ceil(settings.num_timesteps / per_step)) * per_step  # brax runs whole training steps
    policy = make_policy(params, deterministic=True)

    env = trms_env(problem)
    smooth = policy_rollout(env, policy, n_ticks, settings.action_repeat)
    exact = policy_rollout(trms_env(problem, exact_friction=True), policy, n_ticks, settings.action_repeat)
    loop = ClosedLoop(env.task.plant, open_loop(jnp.asarray(smooth.u)), reference=problem.reference)
    terms = jax.jit(problem.loop_terms)(loop, jax.random.PRNGKey(0))
    loss = problem.combine(terms, jnp.zeros(()))
    return PPOResult(
        loss=Breakdown(*(float(v) for v in loss)),
        loss_exact_friction=-float(np.sum(exact.reward)),
        env_steps=env_steps,
        wall_s=wall,
        rollout=exact,
        rollout_loss=-float(np.sum(smooth.reward)),
    )


def ppo_baseline(problem: TRMSTuning, settings: PPOSettings) -> PPOResult | None:
    """:func:`train_and_evaluate`, or ``None`` when ``num_timesteps`` is 0 or brax is not installed."""
    import importlib.util

    if settings.num_timesteps <= 0 or importlib.util.find_spec("brax") is None:
        return None
    return train_and_evaluate(problem, settings)
