"""Any MJCF model as a toolkit :class:`~jaxsim.core.system.Plant`, its physics computed by MuJoCo MJX.

State ``x = (qpos, qvel)`` of shape ``(nq + nv,)``; input ``u`` = the actuator controls ``ctrl``
``(nu,)``; output ``y`` = the named joints' coordinates or sensors (:func:`~jaxsim.mjx.model.layout`).
Two vector fields are offered (``field=`` of :func:`mjcf_plant`):

* ``"forward"`` (default): ``ẋ = (q̇pos, qacc)`` with ``qacc`` from ``mjx.forward`` (actuation, passive
  forces, gravity, Coriolis terms, constraints) — the model's continuous-time dynamics, so the
  toolkit's solvers (RK4, ...) integrate it and :func:`~jaxsim.core.linearize.linearize` gives the
  continuous ``(A, B)``.  ``q̇pos = qvel`` for hinges and slides, ``½ q ⊗ (0, ω)`` for quaternions.
* ``"step"``: ``ẋ = (mjx.step(x, u) − x)/h`` with ``h`` the model's ``opt.timestep``.  Simulated with
  ``solver=EULER`` and ``Timing(dt=h)``, each integration step *is* one ``mjx.step`` (MuJoCo's own
  integrator and constraint solver); ``jacfwd`` of it differentiates through ``mjx.step`` and gives
  ``(Φ − I)/h``, the discrete transition matrix in the units of ``A``.

:func:`step` and :func:`step_sequence` advance the discrete map directly (``lax.scan`` of ``mjx.step``).
Everything composes with ``jit``/``vmap``/``jacfwd``; the MJX model and a data template are pytree
leaves of the plant's params, the layout (sizes, names) is static.
"""

from __future__ import annotations

import os
from typing import Any

import jax
import jax.numpy as jnp
import mujoco
from mujoco import mjx

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.system import Plant
from jaxsim.mjx.model import Layout, layout, load_mjcf

FIELDS = ("forward", "step")
_FREE, _BALL = int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_BALL)


@pytree_dataclass
class MJCFParams:
    """``model`` (``mjx.Model``) and ``data`` (an ``mjx.Data`` template) are leaves; ``layout`` is static."""

    model: Any
    data: Any
    layout: Layout = static_field()


def mjcf_params(source: "str | os.PathLike[str] | mujoco.MjModel", outputs=None) -> MJCFParams:
    """Compile ``source`` (XML string, path or ``MjModel``) and put it on the JAX device."""
    mj_model = load_mjcf(source)
    lay = layout(mj_model, outputs)
    model = mjx.put_model(mj_model)
    return MJCFParams(model=model, data=mjx.make_data(model), layout=lay)


def check_control(lay: Layout, u: jax.Array) -> None:
    """Raise ``ValueError`` unless ``u`` has shape ``(nu,)`` (shapes are static, so also under jit)."""
    if jnp.shape(u) != (lay.nu,):
        raise ValueError(
            f"u: expected shape ({lay.nu},) — one control per actuator {list(lay.actuators)} — "
            f"got {tuple(jnp.shape(u))}"
        )


def check_state(lay: Layout, x: jax.Array) -> None:
    if jnp.shape(x) != (lay.n_states,):
        raise ValueError(
            f"x: expected shape ({lay.n_states},) = (nq={lay.nq}) + (nv={lay.nv}), got {tuple(jnp.shape(x))}"
        )


def split_state(lay: Layout, x: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``x → (qpos (nq,), qvel (nv,))``."""
    return x[: lay.nq], x[lay.nq :]


def to_data(params: MJCFParams, x: jax.Array, u: jax.Array, t: Any = 0.0) -> Any:
    """The ``mjx.Data`` template with ``qpos, qvel, ctrl, time`` set from ``(x, u, t)``."""
    lay = params.layout
    check_state(lay, x)
    check_control(lay, u)
    qpos, qvel = split_state(lay, x)
    d = params.data
    return d.replace(
        qpos=qpos.astype(d.qpos.dtype),
        qvel=qvel.astype(d.qvel.dtype),
        ctrl=jnp.asarray(u, d.ctrl.dtype),
        time=jnp.asarray(t, d.qpos.dtype),
    )


def _quat_rate(q: jax.Array, omega: jax.Array) -> jax.Array:
    """``q̇ = ½ q ⊗ (0, ω)`` for a (w, x, y, z) quaternion and body-frame angular velocity ``ω``."""
    w, v = q[0], q[1:]
    return 0.5 * jnp.concatenate([-jnp.dot(v, omega)[None], w * omega + jnp.cross(v, omega)])


def qpos_rate(lay: Layout, qpos: jax.Array, qvel: jax.Array) -> jax.Array:
    """Time derivative of ``qpos`` (``(nq,)``) given ``qvel``: MuJoCo's position integration ``d/dt``."""
    if lay.nq == lay.nv and not any(t in (_FREE, _BALL) for t, _, _ in lay.joints):
        return qvel
    parts = []
    for jtype, qa, va in lay.joints:
        if jtype == _FREE:  # world-frame linear velocity, body-frame angular velocity
            parts += [qvel[va : va + 3], _quat_rate(qpos[qa + 3 : qa + 7], qvel[va + 3 : va + 6])]
        elif jtype == _BALL:
            parts.append(_quat_rate(qpos[qa : qa + 4], qvel[va : va + 3]))
        else:
            parts.append(qvel[va : va + 1])
    return jnp.concatenate(parts)


def forward_field(params: MJCFParams, x: jax.Array, u: jax.Array, t: Any = 0.0) -> jax.Array:
    """Continuous-time ``ẋ = (q̇pos, qacc)`` with ``qacc`` from ``mjx.forward``."""
    d = mjx.forward(params.model, to_data(params, x, u, t))
    qpos, qvel = split_state(params.layout, x)
    return jnp.concatenate([qpos_rate(params.layout, qpos, qvel), d.qacc.astype(x.dtype)])


def step(params: MJCFParams, x: jax.Array, u: jax.Array, t: Any = 0.0) -> jax.Array:
    """One ``mjx.step`` of length ``opt.timestep`` from state ``x`` with controls ``u`` held."""
    d = mjx.step(params.model, to_data(params, x, u, t))
    return jnp.concatenate([d.qpos, d.qvel]).astype(x.dtype)


def step_field(params: MJCFParams, x: jax.Array, u: jax.Array, t: Any = 0.0) -> jax.Array:
    """``(step(x, u) − x)/h``: Euler with ``dt = h`` reproduces ``mjx.step`` exactly."""
    return (
        step(params, x, u, t) - x
    ) / params.model.opt.timestep  # a leaf: models differing only in h share compiled code


_FIELD_FUNCTIONS = {"forward": forward_field, "step": step_field}


def rigid_field(kind: str):
    """The vector field function named ``kind`` (one of :data:`FIELDS`)."""
    if kind not in _FIELD_FUNCTIONS:
        raise ValueError(f"field: expected one of {FIELDS}, got {kind!r}")
    return _FIELD_FUNCTIONS[kind]


def output(params: MJCFParams, x: jax.Array) -> jax.Array:
    """The selected outputs, concatenated in the order they were named."""
    lay = params.layout
    sensordata = None
    if lay.needs_forward:
        d = mjx.forward(params.model, to_data(params, x, jnp.zeros(lay.nu, x.dtype)))
        sensordata = d.sensordata.astype(x.dtype)
    parts = [x[a : a + w] if kind == "state" else sensordata[a : a + w] for kind, a, w in lay.outputs]
    return jnp.concatenate(parts)


def mjcf_plant(
    source: "str | os.PathLike[str] | mujoco.MjModel",
    outputs: "list[str] | tuple[str, ...] | None" = None,
    field: str = "forward",
    name: str = "mjcf",
) -> Plant:
    """An MJCF model as a :class:`Plant` (state ``(qpos, qvel)``, input ``ctrl``, named outputs).

    Args:
        source: MJCF XML string, path to an ``.xml`` file, or a compiled ``mujoco.MjModel``.
        outputs: names of sensors or joints (``"sensor:S"``, ``"qpos:J"``, ``"qvel:J"`` or bare);
            default: every named joint's position.  Sensor outputs call ``mjx.forward`` (with
            zero controls: position/velocity sensors only are meaningful).
        field: ``"forward"`` (continuous dynamics from ``mjx.forward``) or ``"step"`` (``mjx.step``
            as an Euler-equivalent field; simulate with ``solver=EULER, dt=opt.timestep``).
        name: the plant's name.

    Sensor outputs need the forward pass; plain joint coordinates are read off the state.
    """
    dyn = rigid_field(field)
    params = mjcf_params(source, outputs)
    lay = params.layout
    return Plant(params, dyn, output, n_states=lay.n_states, n_inputs=lay.nu, n_outputs=lay.n_outputs, name=name)


def step_sequence(params: MJCFParams, x0: jax.Array, controls: jax.Array) -> jax.Array:
    """States after each of ``K`` ``mjx.step``s under ``controls (K, nu)``: shape ``(K, nq + nv)``."""
    controls = jnp.asarray(controls)
    if controls.ndim != 2 or controls.shape[1] != params.layout.nu:
        raise ValueError(f"controls: expected shape (K, {params.layout.nu}), got {tuple(controls.shape)}")

    def body(x, u):
        x = step(params, x, u)
        return x, x

    return jax.lax.scan(body, jnp.asarray(x0, float), controls)[1]
