"""Bad input to the python-control vocabulary: a ``ValueError`` whose message starts with the argument's
name (python-control itself accepts several of these silently or fails deep inside NumPy)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxsim.lti as lt
import jaxsim.lti.compat as jc
from jaxsim.core.system import Plant

A = np.array([[0.0, 1.0], [-2.0, -3.0]])
B = np.array([[0.0], [1.0]])
C = np.array([[1.0, 0.0]])
G = lt.ss(A, B, C, 0.0)
NONLINEAR = Plant(
    params=None,
    dynamics=lambda p, x, u, t: -(x**3) + u,
    output=lambda p, x: x,
    n_states=1,
    n_inputs=1,
    n_outputs=1,
    name="cubic",
)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: lt.tf([1.0, 2.0, 3.0], [1.0, 1.0]), r"^num: the transfer function is not proper"),
        (lambda: lt.tf([1.0], [0.0, 0.0]), r"^den: the denominator polynomial is zero"),
        (lambda: lt.tf([np.nan], [1.0, 1.0]), r"^num: must be finite"),
        (lambda: lt.tf([1.0], [1.0, np.inf]), r"^den: must be finite"),
        (lambda: lt.tf([[1.0], [2.0]], [1.0, 1.0]), r"^num: nested coefficient lists"),
        (lambda: lt.tf([1.0 + 1j], [1.0, 1.0]), r"^num: must be real-valued"),
        (lambda: lt.tf([], [1.0, 1.0]), r"^num: needs at least one coefficient"),
        (lambda: lt.zpk([-1.0 + 1j], [-1.0, -2.0], 1.0), r"^zeros: complex roots must come in conjugate pairs"),
        (lambda: lt.zpk([-1.0, -2.0], [-1.0], 1.0), r"^zeros: more zeros \(2\) than poles \(1\)"),
        (lambda: lt.zpk([], [-1.0], [1.0, 2.0]), r"^gain: expected a scalar"),
        (lambda: lt.ss(np.ones((2, 3)), B, C, 0.0), r"^A: expected a square matrix"),
        (lambda: lt.ss(A, np.ones((3, 1)), C, 0.0), r"^B: expected shape \(2, ·\)"),
        (lambda: lt.ss(A, B, np.ones((1, 3)), 0.0), r"^C: expected shape \(·, 2\)"),
        (lambda: lt.ss(A, B, C, np.ones((2, 2))), r"^D: expected shape \(1, 1\)"),
        (lambda: lt.ss(A * np.nan, B, C, 0.0), r"^A: must be finite"),
        (lambda: lt.ss(A, B, C, 0.0, dt=-0.1), r"^dt: "),
        (lambda: lt.ss(A, B, C, 0.0, dt=True), r"^dt: "),
    ],
)
def test_construction(call, message):
    with pytest.raises(ValueError, match=message):
        call()


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: lt.c2d(G, 0.1, "zero-order"), r"^method: unknown c2d method 'zero-order'"),
        (lambda: lt.c2d(G, 0.0), r"^Ts: must be positive"),
        (lambda: lt.c2d(G, np.nan), r"^Ts: must be positive and finite"),
        (lambda: lt.c2d(lt.c2d(G, 0.1), 0.1), r"^sysc: already a discrete-time system"),
        (lambda: lt.c2d(G, 0.1, "gbt"), r"^alpha: the gbt method needs alpha"),
        (lambda: lt.c2d(G, 0.1, "zoh", prewarp_frequency=1.0), r"^prewarp_frequency: only the tustin"),
        (lambda: lt.c2d(G, 0.1, "tustin", prewarp_frequency=100.0), r"^prewarp_frequency: must be below the Nyquist"),
        (lambda: lt.c2d(lt.ss(A, np.eye(2), np.eye(2), 0.0), 0.1, "matched"), r"^sysc: the matched method is for SISO"),
        (lambda: lt.c2d(lt.tf([1.0], [1.0, 0.0]), 0.1, "matched"), r"^sysc: the matched method matches the DC gain"),
        (lambda: lt.c2d(NONLINEAR, 0.1), r"^sysc: plant 'cubic' is not an LTI plant"),
    ],
)
def test_discretisation(call, message):
    with pytest.raises(ValueError, match=message):
        call()


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: lt.feedback(G, 1.0, sign=0), r"^sign: must be -1"),
        (lambda: lt.feedback(G, np.ones((2, 2))), r"^sys2: must map the 1 outputs of sys1 to its 1 inputs"),
        (lambda: lt.feedback(G, lt.c2d(G, 0.1)), r"^sys2: cannot combine systems with different time bases"),
        (
            lambda: lt.feedback(lt.tf([1.0, 0.0], [1.0, 1.0]), 1.0, sign=1),
            r"^sys2: the feedback loop is algebraically ill-posed",
        ),
        (lambda: lt.series(lt.ss(A, B, np.eye(2), 0.0), G), r"^sys2: has 1 inputs but sys1 has 2 outputs"),
        (lambda: lt.parallel(G, lt.ss(A, np.eye(2), C, 0.0)), r"^sys2: has 1 outputs and 2 inputs"),
        (lambda: lt.series(G, "gain"), r"^sys2: expected an LTI system or a gain"),
    ],
)
def test_interconnection(call, message):
    with pytest.raises(ValueError, match=message):
        call()


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: lt.place(A, B, [-1.0 + 1j, -2.0]), r"^p: complex poles must come in conjugate pairs"),
        (lambda: lt.place(A, B, [-1.0]), r"^p: expected 2 poles"),
        (lambda: lt.place(A, B, [-1.0, -1.0]), r"^p: a pole repeated 2 times cannot be placed with rank\(B\) = 1"),
        (
            lambda: lt.place(np.diag([-1.0, -2.0]), np.array([[1.0], [0.0]]), [-3.0, -4.0]),
            r"^A: \(A, B\) is not controllable",
        ),
        (lambda: lt.place(A, np.array([[1.0, 2.0], [1.0, 2.0]]), [-3.0, -4.0]), r"^B: must have full column rank"),
        (lambda: lt.place(A, B, [np.nan, -1.0]), r"^p: must be finite"),
        (lambda: lt.acker(A, np.eye(2), [-1.0, -2.0]), r"^B: acker is for a single input"),
        (lambda: lt.ctrb(A, np.ones((3, 1))), r"^B: expected shape \(2, m\)"),
        (lambda: lt.obsv(A, np.ones((1, 3))), r"^C: expected shape \(p, 2\)"),
        (lambda: lt.zero(lt.ss(A, np.eye(2), C, 0.0)), r"^sys: zero\(\) needs a square system"),
        (lambda: lt.zero(lt.ss(A, B, np.zeros((1, 2)), 0.0)), r"^sys: an output has an identically zero transfer row"),
        (lambda: lt.pole(NONLINEAR), r"^sys: plant 'cubic' is not an LTI plant"),
    ],
)
def test_structure_and_placement(call, message):
    with pytest.raises(ValueError, match=message):
        call()


T = np.linspace(0.0, 1.0, 11)


@pytest.mark.parametrize(
    "call, message",
    [
        (
            lambda: lt.step_response(G, np.array([0.0, 0.1, 0.3])),
            r"^T: time points must be increasing and equally spaced",
        ),
        (lambda: lt.step_response(G, np.array([0.0, np.nan])), r"^T: must be finite"),
        (lambda: lt.step_response(G, np.ones((2, 2))), r"^T: expected a 1-D array"),
        (
            lambda: lt.step_response(lt.c2d(G, 0.1), np.linspace(0, 1, 21)),
            r"^T: a discrete system with dt=0.1 needs time points spaced by dt",
        ),
        (
            lambda: lt.forced_response(G, T, np.ones((2, 11))),
            r"^U: expected a scalar, \(11,\) for a single input, or \(1, 11\)",
        ),
        (lambda: lt.forced_response(G, T, np.full(11, np.nan)), r"^U: must be finite"),
        (lambda: lt.forced_response(G, T, 0.0, np.ones(3)), r"^X0: expected a scalar or shape \(2,\)"),
        (lambda: lt.forced_response(G, T, 0.0, hold="cubic"), r"^hold: expected one of"),
        (lambda: lt.forced_response(G, None, np.ones(11)), r"^T: the time points are required"),
        (lambda: lt.forced_response(NONLINEAR, T, 1.0, substeps=0), r"^substeps: must be a positive integer"),
        (lambda: lt.step_response(G, T, input=1), r"^input: expected an index in \[0, 1\)"),
        (lambda: lt.impulse_response(NONLINEAR, T), r"^sys: impulse_response needs an LTI system"),
        (
            lambda: jax.jit(lambda a: lt.step_response(lt.ss(a, B, C, 0.0)).outputs)(A),
            r"^T: required when the system is traced",
        ),
        (lambda: lt.step_info(np.ones(5)), r"^T: required with step-response samples"),
        (lambda: lt.step_info(np.ones(5), np.arange(4.0)), r"^T: expected shape \(5,\)"),
    ],
)
def test_time_responses(call, message):
    with pytest.raises(ValueError, match=message):
        call()


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: lt.frequency_response(G, [-1.0, 1.0]), r"^omega: frequencies must be non-negative"),
        (lambda: lt.frequency_response(G, [[1.0]]), r"^omega: expected a 1-D array"),
        (lambda: lt.frequency_response(G, [np.nan]), r"^omega: must be finite"),
        (
            lambda: jax.jit(lambda a: lt.bode(lt.ss(a, B, C, 0.0)).magnitude)(A),
            r"^omega: required when the system is traced",
        ),
        (lambda: lt.margin(lt.ss(A, np.eye(2), np.eye(2), 0.0)), r"^sys: margins need a SISO loop"),
        (lambda: lt.stability_margins(G, epsw=-1.0), r"^epsw: must be a non-negative frequency"),
        (lambda: lt.margin(G, n_grid=0), r"^n_grid: must be a positive integer"),
    ],
)
def test_frequency_domain(call, message):
    with pytest.raises(ValueError, match=message):
        call()


Q, R = np.eye(2), np.eye(1)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: jc.lqr(A, B, Q, R, np.ones((3, 1))), r"^N: expected shape \(2, 1\)"),
        (lambda: jc.lqe(A, np.eye(2), C, Q, R, np.ones((2, 1))), r"^NN: the cross-covariance"),
        (lambda: jc.care(A, B, Q, R, stabilizing=False), r"^stabilizing: only the stabilising solution"),
        (lambda: jc.care(A, B, Q, R, E=np.zeros((2, 2))), r"^E: must be invertible"),
        (lambda: jc.dare(A / 4, B, Q, R, E=np.eye(3)), r"^E: expected shape \(2, 2\)"),
        (lambda: jc.dlqr(G, Q, R), r"^sys: dlqr needs a discrete-time system"),
        (lambda: jc.lqr(A, B), r"^sys: lqr expects a system or 4\+ matrices"),
    ],
)
def test_design(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_traced_bad_values_propagate_nan_as_documented():
    """Under ``jit`` the values cannot be checked: a zero leading denominator coefficient gives NaN."""
    out = jax.jit(lambda den: lt.dcgain(lt.tf(jnp.array([1.0]), den)))(jnp.array([0.0, 1.0, 1.0]))
    assert not np.isfinite(float(out))
