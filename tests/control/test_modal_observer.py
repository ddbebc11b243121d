"""Modal controller + internal-model observer (jaxsim.control.modal_observer) on the geared stabiliser:
Butterworth coefficients vs the poles' polynomial, gains vs SciPy's place_poles, the separation principle,
a gradient vs finite differences, the disturbance rejection zero at the model's frequencies."""

import jax
import numpy as np
import pytest
import scipy.signal

from jaxsim.control import modal_observer as mo
from jaxsim.plants import geared_stabiliser as gs
from jaxsim.problem import geared_stabiliser as gp

P = gs.StabiliserParams()
A, B, C = (np.asarray(m) for m in gs.linear_model(P))
W0 = float(gs.natural_frequency(P))
OM = 2 * np.pi / 8


@pytest.fixture(scope="module")
def design():
    return jax.jit(mo.modal_design)(A, B, C, OM, W0, 10.0)


@pytest.mark.parametrize("n", [1, 4, 7])
def test_butterworth_coefficients_are_the_poles_polynomial(n):
    poles = np.asarray(jax.jit(mo.butterworth_poles, static_argnums=0)(n, 1.0))
    assert np.allclose(np.abs(poles), 1.0) and np.all(poles.real < 0)
    assert np.allclose(mo.butterworth_coefficients(n), np.poly(poles).real, atol=1e-12)


def test_gains_match_scipy_place_poles_and_the_separation_principle(design):
    k_ref = scipy.signal.place_poles(A, B, np.asarray(mo.butterworth_poles(4, W0))).gain_matrix
    assert np.asarray(design.K) == pytest.approx(k_ref, rel=1e-8)
    cl = np.asarray(mo.closed_loop_matrix(design, A, B, C))
    want = np.concatenate([mo.butterworth_poles(4, W0), mo.butterworth_poles(7, 10 * W0)])
    got = np.linalg.eigvals(cl)
    # each wanted pole has a computed eigenvalue within 1e-6 relative (sorted matching)
    for p in want:
        assert np.min(np.abs(got - p)) < 1e-6 * abs(p)


def test_concrete_model_path_equals_the_traced_path(design):
    # a concrete model (A, B, C, Ω) takes the NumPy reference-scale path; jit traces them all
    def f(r):
        return mo.modal_design(A, B, C, OM, r, 10.0)

    concrete = jax.jit(f)(W0)
    assert np.asarray(concrete.K) == pytest.approx(np.asarray(design.K), rel=1e-9)
    assert np.asarray(concrete.L) == pytest.approx(np.asarray(design.L), rel=1e-7)


def test_gain_gradient_matches_finite_differences():
    def f(r):
        d = mo.modal_design(A, B, C, OM, r * W0, 10.0)
        return d.K[0, 1] + 1e-6 * d.L[2, 0]

    g = float(jax.jit(jax.grad(f))(1.2))
    h = 1e-6
    fj = jax.jit(f)
    fd = (float(fj(1.2 + h)) - float(fj(1.2 - h))) / (2 * h)
    assert g == pytest.approx(fd, rel=1e-5)


def test_error_response_vanishes_at_the_internal_model_frequencies(design):
    g = np.asarray(jax.jit(gp.error_response)(design, P, np.array([0.0, OM, 3 * OM])))
    assert g[0] < 1e-14 and g[1] < 1e-14 * g[2] and g[2] > 1e-9


def test_bad_inputs_name_the_argument():
    with pytest.raises(ValueError, match="n:"):
        mo.butterworth_poles(0, 1.0)
    with pytest.raises(ValueError, match="B, C"):
        mo.augmented(A, B.T, C, OM)
    with pytest.raises(ValueError, match="coeffs"):
        mo.scaled_acker(A, B, mo.butterworth_coefficients(3), 1.0)
