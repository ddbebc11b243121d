"""brax environments for the toolkit's plants (needs the ``brax`` extra: ``pip install -e ".[brax]"``).

:class:`PlantEnv` wraps any :class:`~jaxsim.core.system.Plant` described by a :class:`Task`; the
per-plant modules build tasks.  Importing this package registers the envs with brax::

    import brax.envs, jaxsim.envs
    env = brax.envs.get_environment("jaxsim_trms")          # or jaxsim_static_second_order, jaxsim_auv, ...
    state = jax.jit(env.reset)(jax.random.PRNGKey(0))
    state = jax.jit(env.step)(state, jnp.zeros(env.action_size))
"""

from brax.envs import register_environment

from jaxsim.envs.auv import auv_env
from jaxsim.envs.plant_env import PlantEnv, PlantState, Task, observe_state_and_error
from jaxsim.envs.second_order import astatic_second_order_env, itae_step, static_second_order_env
from jaxsim.envs.trms import trms_env, trms_task

ENVIRONMENTS = {
    "jaxsim_static_second_order": static_second_order_env,
    "jaxsim_astatic_second_order": astatic_second_order_env,
    "jaxsim_trms": trms_env,
    "jaxsim_auv": auv_env,
}
for _name, _factory in ENVIRONMENTS.items():
    register_environment(_name, _factory)

__all__ = [
    "ENVIRONMENTS",
    "PlantEnv",
    "PlantState",
    "Task",
    "astatic_second_order_env",
    "auv_env",
    "itae_step",
    "observe_state_and_error",
    "static_second_order_env",
    "trms_env",
    "trms_task",
]
