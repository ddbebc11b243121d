"""Inputs that the estimation entry points used to accept and turn into silent garbage (a plausible
number or NaN) and now reject with a ``ValueError`` naming the argument, and mixed dtypes that used
to die inside ``lax.scan`` and are now cast to one float dtype."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation.adapters import ukf_estimator
from jaxsim.estimation.allan import allan_variance
from jaxsim.estimation.cubature import cubature_kalman_filter
from jaxsim.estimation.ekf import extended_kalman_filter
from jaxsim.estimation.imm import (
    IMMState,
    ekf_member,
    imm,
    imm_filter,
    imm_init,
    imm_update,
    linear_member,
    ukf_member,
)
from jaxsim.estimation.lgssm import LinearGaussianSSM, kalman_filter, lgssm
from jaxsim.estimation.mmae import bank_filter
from jaxsim.estimation.nonlinear import nonlinear_ssm
from jaxsim.estimation.parallel import parallel_kalman_filter, parallel_rts_smoother
from jaxsim.estimation.particle import bootstrap_filter, particle_model_from_lgssm
from jaxsim.estimation.shared_gain import covariance_sequence, mean_filter
from jaxsim.estimation.smoothers import extended_rts_smoother, rts_smoother, unscented_rts_smoother
from jaxsim.estimation.ukf import unscented_kalman_filter
from jaxsim.precision import to_common_float

F = np.array([[1.0, 0.1], [0.0, 0.95]])
Q = np.diag([0.01, 0.05])
H = np.array([[1.0, 0.0]])
R = np.array([[0.2]])
M0 = np.array([0.0, 0.5])
P0 = np.diag([1.0, 0.5])
T = 10
Y = np.sin(0.3 * np.arange(T))[:, None]
KEY = jax.random.PRNGKey(3)


def _linear(F=F, Q=Q, H=H, R=R, m0=M0, P0=P0):
    return lgssm(F, Q, H, R, m0, P0)


def _f(params, x, u):
    return params @ x


def _h(params, x):
    return x[:1]


def _nonlinear(F=F, Q=Q, R=R, m0=M0, P0=P0):
    return nonlinear_ssm(_f, _h, Q, R, m0, P0, params=jnp.asarray(F))


# 1. χ² gate ------------------------------------------------------------------------------------

GATED = {
    "kf": lambda gate: kalman_filter(_linear(), Y, gate=gate),
    "rts": lambda gate: rts_smoother(_linear(), Y, gate=gate),
    "ekf": lambda gate: extended_kalman_filter(_nonlinear(), Y, gate=gate),
    "erts": lambda gate: extended_rts_smoother(_nonlinear(), Y, gate=gate),
    "ukf": lambda gate: unscented_kalman_filter(_nonlinear(), Y, gate=gate),
    "urts": lambda gate: unscented_rts_smoother(_nonlinear(), Y, gate=gate),
    "ckf": lambda gate: cubature_kalman_filter(_nonlinear(), Y, gate=gate),
}


@pytest.mark.parametrize("gate", [-1.0, float("nan"), 0.0, float("inf"), True, "9.2"])
@pytest.mark.parametrize("which", sorted(GATED))
def test_gate_must_be_positive_and_finite(which, gate):
    # before: gate ≤ 0 or NaN silently skipped every update (accepted all False), inf skipped none
    with pytest.raises(ValueError, match="^gate: must be"):
        GATED[which](gate)


def test_numpy_gate_is_accepted_and_equals_the_float_gate():
    a = kalman_filter(_linear(), Y, gate=np.float64(0.5))
    b = kalman_filter(_linear(), Y, gate=0.5)
    np.testing.assert_array_equal(a.accepted, b.accepted)
    assert 0 < int(np.sum(a.accepted)) < T  # the gate is active: some updates pass, some not


# 2. UKF sigma-point parameters ------------------------------------------------------------------

BAD_MERWE = [
    (dict(alpha=0.0), "^alpha: must be positive"),
    (dict(alpha=-0.5), "^alpha: must be positive"),
    (dict(alpha=float("nan")), "^alpha: must be finite"),
    (dict(beta=float("inf")), "^beta: must be finite"),
    (dict(kappa=float("nan")), "^kappa: must be finite"),
    (dict(kappa=-2.0), "^kappa: n \\+ kappa must be > 0.*kappa=-2.0"),  # n + λ = 0 exactly (n = 2)
    (dict(kappa=-3.0), "^kappa: n \\+ kappa must be > 0.*kappa=-3.0"),  # n + λ < 0: no Cholesky
    (dict(alpha=1e-9), "^alpha: too small.*alpha=1e-09"),  # n + λ = 2e-18: weights ≈ 1e18
]


@pytest.mark.parametrize("kwargs, match", BAD_MERWE)
def test_merwe_parameters_outside_their_range_are_rejected(kwargs, match):
    # before: NaN estimates (alpha = 0, NaN, n + κ ≤ 0) or weights of 1e18 without a word
    with pytest.raises(ValueError, match=match):
        unscented_kalman_filter(_nonlinear(), Y, **kwargs)
    with pytest.raises(ValueError, match=match):
        unscented_rts_smoother(_nonlinear(), Y, **kwargs)
    with pytest.raises(ValueError, match=match):
        ukf_member(_nonlinear(), **{"alpha": 1.0, "beta": 2.0, "kappa": 0.0, **kwargs})
    with pytest.raises(ValueError, match=match):
        ukf_estimator(_nonlinear(), **kwargs)


@pytest.mark.parametrize("kwargs", [dict(alpha=1e-3), dict(kappa=-2.0 + 1e-7), dict(alpha=1e-3, kappa=1.0)])
def test_small_but_admissible_spread_still_equals_the_kalman_filter(kwargs):
    # the UKF is exact on a linear model for any admissible (α, β, κ); a spread n + λ down to 2e-7
    # must keep that to ~1e-9 (the weights are formed from α²(n + κ) without cancellation)
    ref = kalman_filter(_linear(), Y)
    got = unscented_kalman_filter(_nonlinear(), Y, **kwargs)
    np.testing.assert_allclose(got.means, ref.means, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(got.covs, ref.covs, rtol=1e-6, atol=1e-9)


# 3. IMM -------------------------------------------------------------------------------------------


def _imm():
    return imm([linear_member(F, Q, H, R), linear_member(F, 10 * Q, H, R)], [[0.95, 0.05], [0.05, 0.95]])


def _imm_state(probs=(0.5, 0.5), covs=None):
    return imm_init(np.stack([M0, M0]), np.stack([P0, P0]) if covs is None else covs, np.asarray(probs))


def test_imm_measurement_wider_than_the_members_output_is_rejected():
    # before: y (T, 2) against members with p = 1 broadcast R and H and returned NaN
    y2 = np.concatenate([Y, 2 * Y], axis=1)
    with pytest.raises(ValueError, match=r"^y: expected shape \(T, 1\), got \(10, 2\)"):
        imm_filter(_imm(), _imm_state(), y2)
    with pytest.raises(ValueError, match=r"^y: expected 1 components.*got shape \(2,\)"):
        imm_update(_imm(), _imm_state(), jnp.asarray(y2[0]))


@pytest.mark.parametrize(
    "probs, match",
    [
        ((1.5, -0.5), "^probs: probabilities must be non-negative"),  # before: NaN
        ((1.0, 1.0), "^probs: probabilities must sum to 1"),  # before: silently renormalised
        ((0.6, 0.3), "^probs: probabilities must sum to 1"),
        ((float("nan"), 1.0), "^probs: must be finite"),  # before: NaN
    ],
)
def test_imm_init_probabilities_are_checked(probs, match):
    with pytest.raises(ValueError, match=match):
        _imm_state(probs)


def test_imm_init_covariances_and_hand_built_states_are_checked():
    with pytest.raises(ValueError, match="^covs: must be positive semi-definite"):  # before: NaN
        _imm_state(covs=np.stack([P0, -P0]))
    bad = IMMState(jnp.stack([M0, M0]), jnp.stack([P0, P0]), jnp.array([0.7, 0.7]))
    with pytest.raises(ValueError, match="^probs: probabilities must sum to 1"):
        imm_filter(_imm(), bad, Y)
    three = IMMState(jnp.stack([M0] * 3), jnp.stack([P0] * 3), jnp.ones(3) / 3)
    with pytest.raises(ValueError, match=r"^probs: expected shape \(2,\) for 2 members"):
        imm_filter(_imm(), three, Y)


def test_imm_members_are_checked():
    with pytest.raises(ValueError, match="^R: must be positive semi-definite"):  # before: NaN later
        linear_member(F, Q, H, -R)
    with pytest.raises(ValueError, match=r"^H: expected shape \(any, 2\)"):
        linear_member(F, Q, np.ones((1, 3)), R)
    wide = nonlinear_ssm(_f, lambda p, x: x, Q, np.eye(2), M0, P0, params=jnp.asarray(F))
    with pytest.raises(ValueError, match=r"^members: measurement dimensions differ, got \[1, 2\]"):
        imm([linear_member(F, Q, H, R), ekf_member(wide)], np.eye(2))


def test_float32_transition_matrix_is_row_stochastic_to_its_precision():
    # before: the float32 rows sum to 1 only to ~4e-9 and the fixed 1e-10 tolerance rejected them
    pi32 = np.array([[0.95, 0.05], [0.05, 0.95]], np.float32)
    model = imm([linear_member(F, Q, H, R), linear_member(F, 10 * Q, H, R)], pi32)
    assert model.transition.dtype == jnp.float32
    with pytest.raises(ValueError, match="^transition: probabilities must sum to 1"):
        imm(model.members, np.array([[0.95, 0.0499], [0.05, 0.95]], np.float32))


def test_bank_prior_is_checked():
    models = LinearGaussianSSM(*(np.stack([a, a]) for a in (F, Q, H, R, M0, P0)))
    with pytest.raises(ValueError, match="^prior: probabilities must be non-negative"):  # before: NaN
        bank_filter(models, Y, prior=np.array([1.5, -0.5]))


# 4./5. particle filter ------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [2.5, 0, -3, True, np.float64(np.nan), "64"])
def test_n_particles_must_be_a_positive_integer(n):
    # before: 2.5 ran with 2 particles and True with 1, without a word
    with pytest.raises(ValueError, match="^n_particles: must be a positive integer"):
        bootstrap_filter(particle_model_from_lgssm(_linear()), KEY, Y, n_particles=n)


def test_numpy_and_integral_particle_counts_equal_the_int():
    pm = particle_model_from_lgssm(_linear())
    ref = bootstrap_filter(pm, KEY, Y, n_particles=32)
    for n in (np.int64(32), np.int32(32), 32.0):
        np.testing.assert_array_equal(bootstrap_filter(pm, KEY, Y, n_particles=n).means, ref.means)


def test_zero_measurement_noise_is_rejected_by_the_particle_filter_but_not_by_the_kalman_filter():
    exact = _linear(R=np.zeros((1, 1)))
    # before: every particle weight was NaN and so was every estimate
    with pytest.raises(ValueError, match="^R: must be positive definite for a particle filter's likelihood"):
        particle_model_from_lgssm(exact)
    # the Kalman filter is fine with R = 0 while P0 > 0: it reproduces the measured component exactly
    res = kalman_filter(exact, Y)
    np.testing.assert_allclose(res.means[:, 0], Y[:, 0], atol=1e-12)
    assert np.all(np.isfinite(res.covs))


# 6. Allan variance ----------------------------------------------------------------------------------

SIGNAL = np.random.default_rng(0).standard_normal(256)


@pytest.mark.parametrize(
    "y, m, match",
    [
        (np.where(np.arange(256) == 3, np.nan, SIGNAL), (1, 2), "^y: must be finite"),  # before: NaN
        (SIGNAL + 1j * SIGNAL, (1, 2), "^y: must be real-valued"),  # before: complex "variances"
        (SIGNAL, (1.5, 2), "^m: must be a positive integer, got 1.5"),  # before: truncated to 1
        (SIGNAL, (True, 2), "^m: must be a positive integer, got True"),  # before: taken as 1
        (SIGNAL, (0, 2), "^m: must be a positive integer, got 0"),
    ],
)
def test_allan_bad_inputs(y, m, match):
    with pytest.raises(ValueError, match=match):
        allan_variance(y, 0.1, m)


def test_allan_integral_float_cluster_sizes_equal_the_ints():
    a = allan_variance(SIGNAL, 0.1, np.array([1.0, 4.0, 16.0]))
    b = allan_variance(SIGNAL, 0.1, (1, 4, 16))
    np.testing.assert_array_equal(a.avar, b.avar)


def test_allan_float32_with_offset_matches_float64():
    # before: the float32 cumulative sum of 3e4 samples of 1000 + noise lost the digits of its
    # differences (55 % error at τ = dt, 300 % with 1e5 samples); the Allan variance ignores the
    # offset, so the signal is centred first
    y = (1000.0 + np.random.default_rng(1).standard_normal(30_000)).astype(np.float32)
    sizes = (1, 10, 100)
    got = allan_variance(y, 0.01, sizes)
    ref = allan_variance(y.astype(np.float64), 0.01, sizes)
    assert got.avar.dtype == jnp.float32
    np.testing.assert_allclose(np.asarray(got.avar, float), ref.avar, rtol=1e-2)


# 7. one float dtype at every entry point ------------------------------------------------------------
# kinds: "f64" the reference; "int" integer m0 = 0, P0 = I; "f32" a float32 model (m0 = 0, P0 = I) run
# on the float64 measurements Y


def _cast(arrays, kind):
    """``arrays`` as float32 for kind "f32", else float64; ``(m0, P0) = (0, I)`` appended, integer
    for kind "int"."""
    dtype = jnp.float32 if kind == "f32" else jnp.float64
    init_dtype = int if kind == "int" else dtype
    return [jnp.asarray(a, dtype) for a in arrays] + [jnp.zeros(2, init_dtype), jnp.eye(2, dtype=init_dtype)]


def _lin(kind):
    return lgssm(*_cast((F, Q, H, R), kind))


def _nl(kind):
    q, r, m0, p0 = _cast((Q, R), kind)
    return nonlinear_ssm(_f, _h, q, r, m0, p0, params=jnp.asarray(F, jnp.float32 if kind == "f32" else float))


def _imm_run(kind):
    mems = [linear_member(*_cast((F, s * Q, H, R), kind)[:4]) for s in (1.0, 10.0)]
    m0, p0 = _cast((), kind)
    probs = jnp.array([0.5, 0.5], jnp.float32 if kind == "f32" else float)
    init = imm_init(jnp.stack([m0, m0]), jnp.stack([p0, p0]), probs)
    return imm_filter(imm(mems, np.array([[0.95, 0.05], [0.05, 0.95]])), init, Y).means


def _pf(model):
    return bootstrap_filter(particle_model_from_lgssm(model), KEY, Y, n_particles=64).means


def _shared_gain(model):
    return mean_filter(model, covariance_sequence(model, T), Y).means


ENTRY = {
    "kalman_filter": (lambda k: kalman_filter(k, Y).means, "linear"),
    "rts_smoother": (lambda k: rts_smoother(k, Y).means, "linear"),
    "parallel_kalman_filter": (lambda k: parallel_kalman_filter(k, Y).means, "linear"),
    "parallel_rts_smoother": (lambda k: parallel_rts_smoother(k, Y).means, "linear"),
    "bootstrap_filter": (_pf, "linear"),
    "mean_filter": (_shared_gain, "linear"),
    "extended_kalman_filter": (lambda k: extended_kalman_filter(k, Y).means, "nonlinear"),
    "unscented_kalman_filter": (lambda k: unscented_kalman_filter(k, Y).means, "nonlinear"),
    "imm_filter": (None, "imm"),
}


def _run(entry, kind):
    run, family = ENTRY[entry]
    return {"linear": lambda: run(_lin(kind)), "nonlinear": lambda: run(_nl(kind)), "imm": lambda: _imm_run(kind)}[
        family
    ]()


@pytest.mark.parametrize("kind", ["int", "f32"])
@pytest.mark.parametrize("entry", sorted(ENTRY))
def test_mixed_dtypes_are_cast_to_one_float(entry, kind):
    # before: integer m0/P0 and a float32 model with float64 y died in lax.scan ("carry input and
    # carry output must have equal types"), jacfwd (integer input) or jax.random (integer dtype);
    # the parallel filter and smoother (no scan carry) already promoted and are kept for the rule
    ref = _run(entry, "f64")
    got = _run(entry, kind)
    assert got.dtype == jnp.float64
    if kind == "int":
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12)
    else:  # the model's values were rounded to float32
        np.testing.assert_allclose(got, ref, rtol=1e-5, atol=1e-6)


def test_common_float_rule():
    f32, f64 = jnp.ones(2, jnp.float32), jnp.ones(2)
    ints = jnp.arange(2)
    assert to_common_float((ints, ints))[0][0].dtype == jnp.float64  # integers alone: float64 (x64)
    assert to_common_float((f32, ints))[0][1].dtype == jnp.float32  # float32 kept next to integers
    assert to_common_float((f32, f64))[0][0].dtype == jnp.float64
    (data,), params = to_common_float((f32,), {"w": f64, "index": ints})
    assert data.dtype == jnp.float64 and params["w"].dtype == jnp.float64
    assert params["index"].dtype == ints.dtype  # integer parameters are not data: left alone
    res = kalman_filter(_lin("f32"), Y.astype(np.float32))
    assert res.means.dtype == jnp.float32 and res.covs.dtype == jnp.float32
