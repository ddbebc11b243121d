"""MJCF models as toolkit plants, their rigid-body physics computed by MuJoCo MJX.

Optional extra: ``pip install "jaxsim-control[mjx]"`` (mujoco, mujoco-mjx).

* :func:`mjcf_plant` — any MJCF model (XML string, path or ``MjModel``) as a
  :class:`~jaxsim.core.system.Plant`: state ``(qpos, qvel)``, input ``ctrl``, outputs by name;
  continuous field from ``mjx.forward`` or the ``mjx.step`` map (:mod:`jaxsim.mjx.plant`).
* :func:`actuated_plant` — an MJCF rigid body driven by actuator models written in the toolkit.
* :func:`trms_mjx_plant` / :func:`helicopter_mjx_plant` — the twin-rotor and 3-DOF helicopter stands
  (MuJoCo rigid body, our motor models); :func:`auv_mjx_plant` — the AUV's rigid body (free joint).

Each has a consistency test against the toolkit's ODE plant in ``tests/mjx``.
"""

try:
    import mujoco as _mujoco  # noqa: F401
    from mujoco import mjx as _mjx  # noqa: F401
except ImportError as exc:  # pragma: no cover - depends on the environment
    raise ImportError('jaxsim.mjx needs the "mjx" extra: pip install "jaxsim-control[mjx]"') from exc

from jaxsim.mjx.actuated import ActuatedParams, actuated_plant
from jaxsim.mjx.auv import auv_mjcf, auv_mjx_plant
from jaxsim.mjx.helicopter_3dof import helicopter_mjcf, helicopter_mjx_plant
from jaxsim.mjx.model import Layout, layout, load_mjcf
from jaxsim.mjx.plant import (
    FIELDS,
    MJCFParams,
    forward_field,
    mjcf_params,
    mjcf_plant,
    qpos_rate,
    step,
    step_field,
    step_sequence,
)
from jaxsim.mjx.trms import trms_mjcf, trms_mjx_plant

__all__ = [
    "ActuatedParams",
    "FIELDS",
    "auv_mjcf",
    "auv_mjx_plant",
    "helicopter_mjcf",
    "helicopter_mjx_plant",
    "Layout",
    "MJCFParams",
    "actuated_plant",
    "forward_field",
    "layout",
    "load_mjcf",
    "mjcf_params",
    "mjcf_plant",
    "qpos_rate",
    "step",
    "step_field",
    "step_sequence",
    "trms_mjcf",
    "trms_mjx_plant",
]
