"""Loading an MJCF model and resolving names in it (the static half of the MJX adapter).

Everything here runs once, on concrete NumPy data, when a plant is built; nothing is traced.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import mujoco
import numpy as np


def load_mjcf(source: "str | os.PathLike[str] | mujoco.MjModel") -> mujoco.MjModel:
    """Compile an MJCF model from an XML string, a file path or an existing ``MjModel``."""
    if isinstance(source, mujoco.MjModel):
        return source
    if isinstance(source, (str, os.PathLike)):
        text = os.fspath(source)
        if text.lstrip().startswith("<"):
            return mujoco.MjModel.from_xml_string(text)
        if not os.path.isfile(text):
            raise ValueError(f"source: neither MJCF XML (starting with '<') nor an existing file: {text!r}")
        return mujoco.MjModel.from_xml_path(text)
    raise ValueError(f"source: expected an MJCF XML string, a path or a mujoco.MjModel, got {type(source)!r}")


def _names(model: mujoco.MjModel, obj: mujoco.mjtObj, count: int) -> tuple[str, ...]:
    return tuple(mujoco.mj_id2name(model, obj, i) or "" for i in range(count))


def joint_names(model: mujoco.MjModel) -> tuple[str, ...]:
    return _names(model, mujoco.mjtObj.mjOBJ_JOINT, model.njnt)


def actuator_names(model: mujoco.MjModel) -> tuple[str, ...]:
    return _names(model, mujoco.mjtObj.mjOBJ_ACTUATOR, model.nu)


def sensor_names(model: mujoco.MjModel) -> tuple[str, ...]:
    return _names(model, mujoco.mjtObj.mjOBJ_SENSOR, model.nsensor)


_QPOS_WIDTH = {
    int(mujoco.mjtJoint.mjJNT_FREE): 7,
    int(mujoco.mjtJoint.mjJNT_BALL): 4,
    int(mujoco.mjtJoint.mjJNT_SLIDE): 1,
    int(mujoco.mjtJoint.mjJNT_HINGE): 1,
}
_QVEL_WIDTH = {
    int(mujoco.mjtJoint.mjJNT_FREE): 6,
    int(mujoco.mjtJoint.mjJNT_BALL): 3,
    int(mujoco.mjtJoint.mjJNT_SLIDE): 1,
    int(mujoco.mjtJoint.mjJNT_HINGE): 1,
}


@dataclass(frozen=True)
class Layout:
    """Static description of a compiled model: sizes, joint layout and the selected outputs.

    ``joints`` lists ``(type, qpos_address, dof_address)`` per joint (MuJoCo's ``mjtJoint`` codes);
    ``outputs`` lists ``(kind, start, width)`` with kind ``"state"`` (an index into the plant state
    ``(qpos, qvel)``) or ``"sensor"`` (an index into ``sensordata``).
    """

    nq: int
    nv: int
    nu: int
    joints: tuple[tuple[int, int, int], ...]
    actuators: tuple[str, ...]
    output_names: tuple[str, ...]
    outputs: tuple[tuple[str, int, int], ...]

    @property
    def n_states(self) -> int:
        return self.nq + self.nv

    @property
    def n_outputs(self) -> int:
        return sum(width for _, _, width in self.outputs)

    @property
    def needs_forward(self) -> bool:
        """Whether an output reads sensor data (computed by ``mjx.forward``)."""
        return any(kind == "sensor" for kind, _, _ in self.outputs)


def _resolve_output(model: mujoco.MjModel, name: str) -> tuple[str, int, int]:
    """``name`` → ``(kind, start, width)``; forms ``sensor:S``, ``qpos:J``, ``qvel:J`` or a bare name
    (a sensor first, then a joint's position)."""
    joints, sensors = joint_names(model), sensor_names(model)
    kind, _, bare = name.rpartition(":")
    if kind not in ("", "sensor", "qpos", "qvel"):
        raise ValueError(f"outputs: unknown prefix {kind!r} in {name!r}; use sensor:, qpos: or qvel:")
    if kind in ("", "sensor") and bare in sensors:
        i = sensors.index(bare)
        return "sensor", int(model.sensor_adr[i]), int(model.sensor_dim[i])
    if kind in ("", "qpos", "qvel") and bare in joints:
        j = joints.index(bare)
        jtype = int(model.jnt_type[j])
        if kind == "qvel":
            return "state", model.nq + int(model.jnt_dofadr[j]), _QVEL_WIDTH[jtype]
        return "state", int(model.jnt_qposadr[j]), _QPOS_WIDTH[jtype]
    raise ValueError(
        f"outputs: no {'sensor or joint' if not kind else kind.replace('q', 'joint ')} named {bare!r}; "
        f"joints: {[j for j in joints if j]}, sensors: {[s for s in sensors if s]}"
    )


def layout(model: mujoco.MjModel, outputs: "tuple[str, ...] | list[str] | None" = None) -> Layout:
    """The static :class:`Layout` of ``model``; ``outputs=None`` selects every named joint's position."""
    if outputs is None:
        outputs = tuple(n for n in joint_names(model) if n)
    if isinstance(outputs, str):
        raise ValueError(f"outputs: expected a sequence of names, got the string {outputs!r}")
    outputs = tuple(outputs)
    if not outputs:
        raise ValueError("outputs: select at least one output (the model has no named joint)")
    joints = tuple(
        (int(t), int(q), int(v))
        for t, q, v in zip(np.asarray(model.jnt_type), np.asarray(model.jnt_qposadr), np.asarray(model.jnt_dofadr))
    )
    return Layout(
        nq=int(model.nq),
        nv=int(model.nv),
        nu=int(model.nu),
        joints=joints,
        actuators=actuator_names(model),
        output_names=outputs,
        outputs=tuple(_resolve_output(model, n) for n in outputs),
    )
