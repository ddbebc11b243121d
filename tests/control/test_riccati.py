"""CARE/DARE against SciPy on the CAREX/DAREX benchmarks and on 1,000 random systems each.

Criterion (the issue's): relative difference ≤ 1e-9 where SciPy is accurate — judged by SciPy's
own relative residual (≤ 1e-12) — and the problem is well conditioned (estimated condition number
× eps ≤ 1e-10).  A case that differs by more is *reported* (a ``UserWarning`` with the numbers,
shown in pytest's warnings summary), is asserted to be one of those exceptions, and must still
have a residual no worse than SciPy's.
"""

import warnings

import jax
import numpy as np
import pytest
import scipy.linalg as sl

from jaxsim.control.riccati import solve_continuous_are, solve_discrete_are
from tests.control.riccati_benchmarks import OUTSIDE_SCOPE, carex, darex
from tests.control.riccati_oracle import (
    care_relative_residual,
    condition_estimate,
    dare_relative_residual,
)

EPS = np.finfo(float).eps
CAREX = carex()
DAREX = darex()


def _check_or_report(label, diff, res_ref, res, kappa_fn):
    """Hold ``diff`` to 1e-9 where SciPy is accurate and the problem well conditioned; otherwise
    return a report line (and require our residual to be no worse than SciPy's)."""
    if diff <= 1e-9:
        return None
    kappa = kappa_fn() if res_ref <= 1e-12 else float("nan")  # the estimate is only needed here
    line = (f"{label}: rel. diff vs SciPy {diff:.2e}, residual SciPy {res_ref:.1e} ours {res:.1e}, "
            f"condition estimate {kappa:.1e}")
    assert not (res_ref <= 1e-12 and kappa * EPS <= 1e-10), "should have agreed to 1e-9: " + line
    assert res <= max(10 * res_ref, 1e-13), line
    return line


def _compare(name, a, b, q, r, discrete):
    ours_fn = solve_discrete_are if discrete else solve_continuous_are
    ref_fn = sl.solve_discrete_are if discrete else sl.solve_continuous_are
    residual = dare_relative_residual if discrete else care_relative_residual
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sl.LinAlgWarning)
        x_ref = ref_fn(a, b, q, r)
    x = np.asarray(ours_fn(a, b, q, r))
    diff = np.linalg.norm(x - x_ref) / np.linalg.norm(x_ref)
    line = _check_or_report(f"{name} (n={a.shape[0]})", diff, residual(x_ref, a, b, q, r),
                            residual(x, a, b, q, r),
                            lambda: condition_estimate(x_ref, a, b, q, r, discrete))
    if line:
        warnings.warn("reported, not held to 1e-9 — " + line, UserWarning)


@pytest.mark.parametrize("name", [k for k in CAREX if k != "carex20"])
def test_care_carex_against_scipy(name):
    _compare(name, *CAREX[name], discrete=False)


@pytest.mark.slow
def test_care_carex20_n421_against_scipy():
    _compare("carex20", *CAREX["carex20"], discrete=False)


@pytest.mark.parametrize("name", list(DAREX))
def test_dare_darex_against_scipy(name):
    _compare(name, *DAREX[name], discrete=True)


@pytest.mark.parametrize("name", list(OUTSIDE_SCOPE))
def test_singular_r_is_rejected_with_a_clear_error(name):
    with pytest.raises(ValueError, match="r: must be symmetric positive definite"):
        solve_discrete_are(*OUTSIDE_SCOPE[name])


def _random_systems(rng, count, n, m, discrete):
    a = rng.normal(size=(count, n, n))
    if discrete:  # spectral radii spread over [0.5, 1.5]: stable and unstable plants
        rho = np.max(np.abs(np.linalg.eigvals(a)), axis=1)
        a = a / rho[:, None, None] * rng.uniform(0.5, 1.5, size=(count, 1, 1))
    b = rng.normal(size=(count, n, m))
    mq = rng.normal(size=(count, n, n))
    mr = rng.normal(size=(count, m, m))
    q = mq @ mq.transpose(0, 2, 1) / n + 0.1 * np.eye(n)
    r = mr @ mr.transpose(0, 2, 1) / m + 0.1 * np.eye(m)
    return a, b, q, r


@pytest.mark.parametrize("discrete", [False, True], ids=["care", "dare"])
def test_1000_random_stabilisable_systems_against_scipy(discrete):
    rng = np.random.default_rng(2024)
    solver = jax.jit(jax.vmap(solve_discrete_are if discrete else solve_continuous_are))
    ref_fn = sl.solve_discrete_are if discrete else sl.solve_continuous_are
    residual = dare_relative_residual if discrete else care_relative_residual
    reported = []
    for n, m in [(2, 1), (4, 2), (6, 3), (8, 2)]:  # 4 × 250 = 1,000 systems, random sizes and weights
        a, b, q, r = _random_systems(rng, 250, n, m, discrete)
        x = np.asarray(solver(a, b, q, r))
        for i in range(250):
            x_ref = ref_fn(a[i], b[i], q[i], r[i])
            diff = np.linalg.norm(x[i] - x_ref) / np.linalg.norm(x_ref)
            assert np.isfinite(diff), (n, m, i)
            line = _check_or_report(
                f"n={n} m={m} #{i}", diff, residual(x_ref, a[i], b[i], q[i], r[i]),
                residual(x[i], a[i], b[i], q[i], r[i]),
                lambda: condition_estimate(x_ref, a[i], b[i], q[i], r[i], discrete))  # noqa: B023
            if line:
                reported.append(line)
    if reported:
        warnings.warn(f"{len(reported)} of 1000 random systems reported: " + "; ".join(reported), UserWarning)
    assert len(reported) <= 10  # random well-scaled systems: essentially all are held to 1e-9


def test_unstabilisable_pair_raises_and_traced_solve_gives_nan():
    a = np.diag([1.0, -1.0])  # the unstable mode is not reached by b
    b = np.array([[0.0], [1.0]])
    with pytest.raises(ValueError, match=r"\(a, b\): not stabilisable — mode\(s\) 1"):
        solve_continuous_are(a, b, np.eye(2), np.eye(1))
    with pytest.raises(ValueError, match="not stabilisable"):
        solve_discrete_are(np.diag([1.5, 0.5]), b, np.eye(2), np.eye(1))
    x = jax.jit(solve_continuous_are)(a, b, np.eye(2), np.eye(1))
    assert np.all(np.isnan(x))


def test_no_stabilising_solution_raises():
    # (A, Q) has an unobservable mode on the imaginary axis: the Hamiltonian has eigenvalues ±i.
    a = np.array([[0.0, 1.0], [-1.0, 0.0]])
    b = np.array([[0.0], [1.0]])
    with pytest.raises(ValueError, match="no stabilising solution"):
        solve_continuous_are(a, b, np.zeros((2, 2)), np.eye(1))


def test_input_validation_names_the_argument():
    eye = np.eye(2)
    with pytest.raises(ValueError, match="q: must be symmetric"):
        solve_continuous_are(eye, eye, np.array([[1.0, 2.0], [0.0, 1.0]]), eye)
    with pytest.raises(ValueError, match="r: expected shape"):
        solve_continuous_are(eye, eye, eye, np.eye(3))
    with pytest.raises(ValueError, match="b: expected 2 rows"):
        solve_discrete_are(eye, np.ones((3, 1)), eye, 1.0)
    with pytest.raises(ValueError, match="a: must be finite"):
        solve_continuous_are(np.full((2, 2), np.inf), eye, eye, eye)
