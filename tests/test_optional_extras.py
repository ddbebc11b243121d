"""The README's test command installs the ``mjx`` and ``brax`` extras; their tests must not be skipped
silently because an install step went missing (the MJX/brax test modules use ``importorskip``)."""

import importlib

import pytest


@pytest.mark.parametrize(
    "module", ["mujoco", "mujoco.mjx", "brax.envs", "brax.training.agents.ppo.train", "evosax.algorithms"]
)
def test_extra_is_importable(module):
    try:
        importlib.import_module(module)
    except ImportError as err:  # pragma: no cover - the failure is the message
        pytest.fail(
            f"{module} is missing: install the extras with `pip install -e '.[test,mjx,brax,cmaes]'` "
            f"(what `make test` does): {err}"
        )
