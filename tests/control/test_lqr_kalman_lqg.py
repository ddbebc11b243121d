"""lqr/dlqr against python-control, Kalman gains against control.lqe/dlqe, LQG separation, errors."""

import control
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control.kalman_gain import discrete_kalman, kalman_bucy
from jaxsim.control.lqg import feedback_matrix, lqg
from jaxsim.control.lqr import dlqr, lqr

RNG = np.random.default_rng(42)
A = RNG.normal(size=(5, 5))
B = RNG.normal(size=(5, 2))
C = RNG.normal(size=(2, 5))
Q = np.diag([1.0, 2.0, 0.5, 3.0, 1.0])
R = np.array([[1.0, 0.2], [0.2, 0.5]])


def _rel(x, ref):
    return np.linalg.norm(np.asarray(x) - ref) / np.linalg.norm(ref)


def test_lqr_matches_python_control():
    k_ref, s_ref, e_ref = control.lqr(A, B, Q, R)
    res = lqr(A, B, Q, R)
    assert _rel(res.k, k_ref) < 1e-10
    assert _rel(res.p, s_ref) < 1e-10
    np.testing.assert_allclose(
        np.sort_complex(np.linalg.eigvals(A - B @ np.asarray(res.k))), np.sort_complex(e_ref), rtol=1e-9
    )


def test_dlqr_matches_python_control():
    ad = A / np.max(np.abs(np.linalg.eigvals(A))) * 1.1
    k_ref, s_ref, _ = control.dlqr(ad, B, Q, R)
    res = dlqr(ad, B, Q, R)
    assert _rel(res.k, k_ref) < 1e-10
    assert _rel(res.p, s_ref) < 1e-10


def test_kalman_bucy_matches_control_lqe_with_noise_input_matrix():
    g = RNG.normal(size=(5, 3))
    w = np.diag([0.5, 1.0, 2.0])
    v = np.diag([0.1, 0.3])
    l_ref, p_ref, _ = control.lqe(A, g, C, w, v)
    res = kalman_bucy(A, C, w, v, g)
    assert _rel(res.l, l_ref) < 1e-10
    assert _rel(res.p, p_ref) < 1e-10


def test_discrete_kalman_matches_control_dlqe_and_joseph_posterior():
    ad = A / np.max(np.abs(np.linalg.eigvals(A))) * 0.9
    qn, rn = np.eye(5) * 0.2, np.diag([0.1, 0.3])
    l_ref, p_ref, _ = control.dlqe(ad, np.eye(5), C, qn, rn)  # predictor gain L = A K
    res = discrete_kalman(ad, C, qn, rn)
    assert _rel(ad @ np.asarray(res.k), l_ref) < 1e-10
    assert _rel(res.p_prior, p_ref) < 1e-10
    p_post = np.asarray(res.p_post)
    # steady state: the prior is the predicted posterior, and the posterior is PSD
    assert _rel(ad @ p_post @ ad.T + qn, p_ref) < 1e-10
    assert np.linalg.eigvalsh(p_post).min() > 0


def test_lqg_closed_loop_spectrum_is_the_union_of_regulator_and_observer_spectra():
    res = lqg(A, B, C, Q, R, np.eye(5), np.diag([0.1, 0.2]))
    closed = np.linalg.eigvals(np.asarray(feedback_matrix(A, B, C, res.controller)))
    expected = np.concatenate(
        [np.linalg.eigvals(A - B @ np.asarray(res.regulator.k)), np.linalg.eigvals(A - np.asarray(res.observer.l) @ C)]
    )
    np.testing.assert_allclose(np.sort_complex(closed), np.sort_complex(expected), rtol=1e-8, atol=1e-9)
    assert closed.real.max() < 0


def test_lqr_vmaps_over_weights():
    qs = np.stack([Q * s for s in (0.5, 1.0, 2.0)])
    ks = jax.jit(jax.vmap(lambda q: lqr(A, B, q, R).k))(qs)
    for i in range(3):
        assert _rel(ks[i], control.lqr(A, B, qs[i], R)[0]) < 1e-10


def test_unstabilisable_and_undetectable_inputs_raise():
    a = np.diag([1.0, -2.0])
    with pytest.raises(ValueError, match=r"\(a, b\): not stabilisable"):
        lqr(a, np.array([[0.0], [1.0]]), np.eye(2), 1.0)
    with pytest.raises(ValueError, match=r"\(a, c\): not detectable — mode\(s\) 1"):
        kalman_bucy(a, np.array([[0.0, 1.0]]), np.eye(2), np.eye(1))
    with pytest.raises(ValueError, match=r"\(a, c\): not detectable"):
        discrete_kalman(np.diag([1.2, 0.5]), np.array([[0.0, 1.0]]), np.eye(2), np.eye(1))
    osc = np.array([[0.0, 1.0], [-1.0, 0.0]])  # undamped mode, invisible in the cost
    with pytest.raises(ValueError, match=r"\(a, q\): not detectable — .* imaginary axis"):
        lqr(osc, np.array([[0.0], [1.0]]), np.zeros((2, 2)), 1.0)
    with pytest.raises(ValueError, match=r"\(a, w\): not stabilisable from the process noise"):
        kalman_bucy(osc, np.array([[1.0, 0.0]]), np.zeros((2, 2)), np.eye(1))


def test_weight_validation():
    with pytest.raises(ValueError, match="q: must be symmetric positive semi-definite"):
        lqr(A, B, -np.eye(5), R)
    with pytest.raises(ValueError, match="r: must be symmetric positive definite"):
        lqr(A, B, Q, np.diag([1.0, 0.0]))
    with pytest.raises(ValueError, match="v: must be symmetric positive definite"):
        kalman_bucy(A, C, np.eye(5), np.zeros((2, 2)))


def test_traced_failure_is_nan_not_an_exception():
    a = np.diag([1.0, -2.0])
    k = jax.jit(lambda b: lqr(a, b, jnp.eye(2), jnp.eye(1)).k)(jnp.array([[0.0], [1.0]]))
    assert np.all(np.isnan(k))
