"""Linear-Gaussian state-space model and its scanned Kalman filter.

``x_{t+1} = F_t x_t + B_t u_t + w_t``, ``w_t ~ N(0, Q_t)``; ``y_t = H_t x_t + v_t``, ``v_t ~ N(0, R_t)``;
``x_0 ~ N(m0, P0)``.  The filter starts from ``N(m0, P0)`` as the prior of ``x_0``, updates with
``y_0``, predicts with ``(F_0, B_0 u_0, Q_0)``, updates with ``y_1``, … (dynamax's convention for the
initial belief, so log-likelihoods compare directly).

Time-varying models: any of ``F, Q, H, R, B`` may carry a leading time axis of length ``T``.

Missing / multi-rate measurements: pass ``mask`` (``(T,)`` or ``(T, p)`` booleans, ``True`` =
available) and/or ``missing="nan"`` (NaN entries of ``y`` are treated as missing).  With the default
``missing="error"`` a NaN in a concrete ``y`` raises ``ValueError``.

χ² gating: ``gate=threshold`` rejects (skips) an update whose NIS exceeds the threshold; the
rejected steps show as ``accepted = False`` (see :mod:`jaxsim.estimation.gating` for thresholds).
The threshold is a jit-static number, always checked: positive and finite, else ``ValueError``.

Dtypes: the model, ``y`` and ``u`` are cast to one float dtype at the boundary
(:func:`jaxsim.precision.to_common_float`), so integer ``m0``/``P0`` and a float32 model with
float64 measurements run (in float64); an all-float32 call stays float32.
"""

from __future__ import annotations

import functools
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import check_covariance, check_finite, check_shape, check_square, is_concrete
from jaxsim.estimation import kalman
from jaxsim.estimation.filtering import FilterMember, check_gate, scan_filter
from jaxsim.estimation.types import FilterResult, GaussianState, Innovation, SqrtGaussianState
from jaxsim.precision import to_common_float

FORMS = ("joseph", "standard", "sqrt")
MISSING_POLICIES = ("error", "nan")


@pytree_dataclass
class LinearGaussianSSM:
    """Parameters of a linear-Gaussian model (all array leaves: vmap over them, grad through them).

    F ``(n, n)``, Q ``(n, n)``, H ``(p, n)``, R ``(p, p)``, m0 ``(n,)``, P0 ``(n, n)``, B ``(n, m)`` or
    ``None``.  ``F, Q, H, R, B`` may have a leading time axis ``(T, ...)``.
    """

    F: jax.Array
    Q: jax.Array
    H: jax.Array
    R: jax.Array
    m0: jax.Array
    P0: jax.Array
    B: jax.Array | None = None

    @property
    def n_states(self) -> int:
        return int(np.shape(self.m0)[-1])

    @property
    def n_outputs(self) -> int:
        return int(np.shape(self.H)[-2])


_BASE_NDIM = {"F": 2, "Q": 2, "H": 2, "R": 2, "B": 2}


def lgssm(F: Any, Q: Any, H: Any, R: Any, m0: Any, P0: Any, B: Any = None) -> LinearGaussianSSM:
    """Build and validate a :class:`LinearGaussianSSM` (arrays converted with ``jnp.asarray``)."""
    model = LinearGaussianSSM(
        jnp.asarray(F),
        jnp.asarray(Q),
        jnp.asarray(H),
        jnp.asarray(R),
        jnp.asarray(m0),
        jnp.asarray(P0),
        None if B is None else jnp.asarray(B),
    )
    validate_model(model)
    return model


def is_time_varying(model: LinearGaussianSSM, name: str) -> bool:
    """Whether field ``name`` carries a leading time axis."""
    value = getattr(model, name)
    return value is not None and np.ndim(value) == _BASE_NDIM[name] + 1


def validate_model(model: LinearGaussianSSM, n_steps: int | None = None) -> None:
    """Shapes of every field; symmetry/PSD of ``Q, R, P0`` when concrete; raises ``ValueError``."""
    m0 = model.m0
    if np.ndim(m0) != 1:
        raise ValueError(f"m0: expected shape (n,), got {tuple(np.shape(m0))}")
    n = int(np.shape(m0)[0])
    check_finite("m0", m0)
    check_covariance("P0", model.P0, n)
    if np.ndim(model.P0) != 2:
        raise ValueError(f"P0: expected shape ({n}, {n}), got {tuple(np.shape(model.P0))}")
    p = None
    for name in ("F", "Q", "H", "R", "B"):
        value = getattr(model, name)
        if value is None:
            continue
        shape = tuple(np.shape(value))
        if len(shape) not in (_BASE_NDIM[name], _BASE_NDIM[name] + 1):
            raise ValueError(f"{name}: expected a matrix or a (T, ...) stack of matrices, got shape {shape}")
        if len(shape) == 3 and n_steps is not None and shape[0] != n_steps:
            raise ValueError(f"{name}: time-varying with {shape[0]} steps, but y has {n_steps}")
        core = shape[-2:]
        if name == "H":
            p = core[0]
        want = {"F": (n, n), "Q": (n, n), "H": (None, n), "R": (p, p), "B": (n, None)}[name]
        if any(w is not None and w != c for w, c in zip(want, core)):
            w = "(" + ", ".join("·" if x is None else str(x) for x in want) + ")"
            raise ValueError(f"{name}: expected shape {w} (or a (T, …) stack of it) for n={n} states, got {shape}")
        if name in ("Q", "R"):
            check_covariance(name, value, core[0])
        else:
            check_finite(name, value)


def prepare_measurements(y: Any, p: int, mask: Any = None, missing: str = "error") -> tuple[jax.Array, jax.Array]:
    """Validate ``y (T, p)`` and build the ``(T, p)`` availability mask; NaN → 0 where masked."""
    if missing not in MISSING_POLICIES:
        raise ValueError(f"missing: expected one of {MISSING_POLICIES}, got {missing!r}")
    y = jnp.asarray(y)
    if y.ndim != 2 or y.shape[1] != p:
        raise ValueError(f"y: expected shape (T, {p}), got {tuple(y.shape)}")
    t = y.shape[0]
    if mask is None:
        m = jnp.ones((t, p), dtype=bool)
    else:
        mask = jnp.asarray(mask)
        if mask.shape not in ((t,), (t, p)):
            raise ValueError(f"mask: expected shape ({t},) or ({t}, {p}), got {tuple(mask.shape)}")
        m = jnp.broadcast_to(mask.astype(bool).reshape(t, -1), (t, p))
    if missing == "nan":
        m = m & jnp.isfinite(y)
    elif is_concrete(y) and is_concrete(m):
        bad = np.asarray(~jnp.isfinite(y) & m)
        if bad.any():
            i, j = np.argwhere(bad)[0]
            raise ValueError(
                f"y: non-finite value at step {i}, component {j} that is not masked; pass a mask "
                f"or missing='nan' to treat NaN as a missing measurement"
            )
    return jnp.where(m, y, 0.0), m


def prepare_inputs(u: Any, t: int, model: LinearGaussianSSM) -> jax.Array | None:
    """Validate ``u (T, m)`` against ``B``."""
    if u is None:
        return None
    if model.B is None:
        raise ValueError("u: given but the model has no input matrix B")
    u = jnp.asarray(u)
    m = int(np.shape(model.B)[-1])
    if u.shape != (t, m):
        raise ValueError(f"u: expected shape ({t}, {m}), got {tuple(u.shape)}")
    check_finite("u", u)
    return u


def step_params(model: LinearGaussianSSM) -> dict[str, jax.Array]:
    """The time-varying fields stacked for ``lax.scan`` (constant fields are closed over)."""
    return {k: getattr(model, k) for k in _BASE_NDIM if is_time_varying(model, k)}


def at(model: LinearGaussianSSM, tv: dict[str, jax.Array], name: str) -> jax.Array | None:
    """Field ``name`` at the current step: the scanned slice if time-varying, else the constant."""
    return tv[name] if name in tv else getattr(model, name)


def common_float_model(model: LinearGaussianSSM, y: Any, u: Any = None) -> tuple[LinearGaussianSSM, jax.Array, Any]:
    """``model``, ``y`` and ``u`` (``None`` allowed) as arrays of one float dtype (see
    :func:`jaxsim.precision.to_common_float`)."""
    (model, y, u), _ = to_common_float((model, jnp.asarray(y), None if u is None else jnp.asarray(u)))
    return model, y, u


def cholesky_psd(m: jax.Array) -> jax.Array:
    """Cholesky factor of a PSD matrix; tolerates a singular ``Q`` via an eigen-factor."""
    w, v = jnp.linalg.eigh(kalman.symmetrize(m))
    return v * jnp.sqrt(jnp.clip(w, 0.0))[None, :]


def kalman_filter(
    model: LinearGaussianSSM,
    y: Any,
    u: Any = None,
    *,
    mask: Any = None,
    missing: str = "error",
    form: str = "joseph",
    gate: float | None = None,
) -> FilterResult:
    """Run the Kalman filter over ``y (T, p)`` (inputs ``u (T, m)``) in one ``lax.scan``.

    Args:
        model: the :class:`LinearGaussianSSM`.
        y: measurements ``(T, p)``; with a mask or ``missing="nan"``, unavailable entries may be NaN.
        u: inputs ``(T, m)``; ``u[t]`` drives the transition from ``t`` to ``t + 1``.
        mask: ``(T,)`` or ``(T, p)`` booleans, ``True`` where a measurement is available.
        missing: ``"error"`` (NaN in an unmasked ``y`` → ``ValueError``) or ``"nan"`` (NaN = missing).
        form: ``"joseph"``, ``"standard"`` or ``"sqrt"`` (Cholesky factors propagated by QR).
        gate: optional χ² threshold on the NIS (positive, finite); an update whose NIS exceeds it
            is skipped.

    The model, ``y`` and ``u`` are cast to one float dtype first (:func:`jaxsim.precision.to_common_float`:
    integer ``m0``/``P0`` become float, a float32 model meets float64 ``y`` in float64).

    Returns:
        :class:`FilterResult` with filtered and predicted moments, innovations and log-likelihood.
    """
    if form not in FORMS:
        raise ValueError(f"form: expected one of {FORMS}, got {form!r}")
    gate = check_gate(gate)
    validate_model(model, n_steps=int(np.shape(y)[0]) if np.ndim(y) >= 1 else None)
    model, y, u = common_float_model(model, y, u)
    y, m = prepare_measurements(y, model.n_outputs, mask, missing)
    u = prepare_inputs(u, y.shape[0], model)
    return _scan_filter(model, y, m, u, form, gate)


@functools.partial(jax.jit, static_argnames=("form", "gate"))
def _scan_filter(model, y, m, u, form, gate) -> FilterResult:
    def update(state, y_t, m_t, p):
        H, R = at(model, p, "H"), at(model, p, "R")
        if form == "sqrt":
            return kalman.sqrt_update(state, y_t, H, cholesky_psd(R), mask=m_t)
        return kalman.update(state, y_t, H, R, mask=m_t, form=form)

    def predict(state, u_t, p):
        F, Q, B = at(model, p, "F"), at(model, p, "Q"), at(model, p, "B")
        if form == "sqrt":
            return kalman.sqrt_predict(state, F, cholesky_psd(Q), B, u_t)
        return kalman.predict(state, F, Q, B, u_t)

    init = GaussianState(model.m0, model.P0)
    if form == "sqrt":
        init = SqrtGaussianState(model.m0, cholesky_psd(model.P0))
    return scan_filter(init, predict, update, y, m, u, step_params(model), gate)


def _linear_predict(p: dict, state: GaussianState, u: Any) -> GaussianState:
    return kalman.predict(state, p["F"], p["Q"], p.get("B"), u)


def _linear_update_joseph(p: dict, state: GaussianState, y: jax.Array, mask: Any) -> tuple[GaussianState, Innovation]:
    return kalman.update(state, y, p["H"], p["R"], mask=mask, form="joseph")


def _linear_update_standard(p: dict, state: GaussianState, y: jax.Array, mask: Any) -> tuple[GaussianState, Innovation]:
    return kalman.update(state, y, p["H"], p["R"], mask=mask, form="standard")


def _linear_observe(p: dict, x: jax.Array) -> jax.Array:
    return p["H"] @ x


# module-level functions, not partials: static fields must compare equal across rebuilt members
_LINEAR_UPDATES = {"joseph": _linear_update_joseph, "standard": _linear_update_standard}


def linear_member(F: Any, Q: Any, H: Any, R: Any, B: Any = None, *, form: str = "joseph") -> FilterMember:
    """The time-invariant Kalman filter ``F (n, n)``, ``Q``, ``H (p, n)``, ``R``, ``B (n, m)`` as a
    :class:`~jaxsim.estimation.filtering.FilterMember` (``params`` a dict of the matrices; ``form``
    ``"joseph"``/``"standard"`` of the covariance update).  Shapes, finiteness and PSD of ``Q, R``
    checked on concrete values."""
    params = {"F": jnp.asarray(F), "Q": jnp.asarray(Q), "H": jnp.asarray(H), "R": jnp.asarray(R)}
    check_square("F", params["F"])
    n = params["F"].shape[0]
    check_finite("F", params["F"])
    check_covariance("Q", params["Q"], n)
    check_shape("H", params["H"], (None, n))
    check_finite("H", params["H"])
    check_covariance("R", params["R"], params["H"].shape[0])
    if B is not None:
        params["B"] = jnp.asarray(B)
        check_shape("B", params["B"], (n, None))
        check_finite("B", params["B"])
    if form not in kalman.UPDATE_FORMS:
        raise ValueError(f"form: expected one of {kalman.UPDATE_FORMS}, got {form!r}")
    return FilterMember(params, _linear_predict, _LINEAR_UPDATES[form], params["H"].shape[0], _linear_observe)


def sample(model: LinearGaussianSSM, key: jax.Array, n_steps: int, u: Any = None) -> tuple[jax.Array, jax.Array]:
    """Draw ``(x (T, n), y (T, p))`` from the model (``u (T, m)`` optional)."""
    n, p = model.n_states, model.n_outputs
    tv = step_params(model)
    k0, k1 = jax.random.split(key)
    x0 = model.m0 + cholesky_psd(model.P0) @ jax.random.normal(k0, (n,), dtype=model.m0.dtype)
    keys = jax.random.split(k1, n_steps)

    def step(x, inp):
        k, u_t, par = inp
        kw, kv = jax.random.split(k)
        H, R = at(model, par, "H"), at(model, par, "R")
        F, Q, B = at(model, par, "F"), at(model, par, "Q"), at(model, par, "B")
        y = H @ x + cholesky_psd(R) @ jax.random.normal(kv, (p,), dtype=x.dtype)
        x_next = F @ x + cholesky_psd(Q) @ jax.random.normal(kw, (n,), dtype=x.dtype)
        if B is not None and u_t is not None:
            x_next = x_next + B @ u_t
        return x_next, (x, y)

    _, (xs, ys) = jax.lax.scan(step, x0, (keys, None if u is None else jnp.asarray(u), tv))
    return xs, ys
