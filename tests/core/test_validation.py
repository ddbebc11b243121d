"""The one set of boundary validators (jaxsim.core.validation): integer checks shared by the tuners and
the Monte-Carlo engine, and the Riccati solvers' symmetric/definite checks (SciPy's rule as oracle)."""

import numpy as np
import pytest
import scipy.linalg

from jaxsim.control import riccati
from jaxsim.core import validation as v
from jaxsim.montecarlo import engine
from optim import results


def test_integer_check_accepts_integers_and_integral_floats_exactly():
    assert v.check_int("n", 3) == 3
    assert v.check_int("n", np.int64(7)) == 7
    assert v.check_int("n", 4.0) == 4 and v.check_int("n", 1e6) == 1_000_000
    assert v.check_int("n", 2**60 + 1) == 2**60 + 1  # no detour through float
    assert v.check_int("k", 0, 0, 3) == 0 and v.check_int("k", 3, 0, 3) == 3


@pytest.mark.parametrize(
    "args, message",
    [
        (("n", True), "^n: must be a positive integer, got True"),
        (("n", 2.5), "^n: must be a positive integer, got 2.5"),
        (("n", float("inf")), "^n: must be a positive integer, got inf"),
        (("n", 0), "^n: must be a positive integer, got 0"),
        (("n", np.ones(2)), "^n: must be a positive integer"),
        (("k", 2.5, 0, 3), "^k: must be an integer, got 2.5"),
        (("k", 4, 0, 3), r"^k: must be in \[0, 3\], got 4"),
        (("m", 1, 2), "^m: must be an integer ≥ 2, got 1"),
    ],
)
def test_integer_check_rejects_with_the_argument_name(args, message):
    with pytest.raises(ValueError, match=message):
        v.check_int(*args)


def test_one_integer_check_everywhere():
    assert results.check_int is v.check_int and engine.check_int is v.check_int
    assert v.check_positive_int("n", 5.0) == 5


def _scipy_says_symmetric(q: np.ndarray) -> bool:
    try:
        scipy.linalg.solve_continuous_are(-np.eye(2), np.eye(2), q, np.eye(2))
    except ValueError as err:
        assert "symmetric" in str(err)
        return False
    return True


@pytest.mark.parametrize("asym", [0.0, 1e-15, 1e-14, 3e-14, 1e-13, 1e-6])
def test_symmetry_rule_is_scipys(asym):
    q = np.array([[2.0, 0.3], [0.3, 1.0]])
    q[0, 1] += asym
    accepted = True
    try:
        v.check_symmetric("q", q)
    except ValueError as err:
        assert str(err).startswith("q: must be symmetric")
        accepted = False
    assert accepted == _scipy_says_symmetric(q)


def test_definite_checks_and_riccati_uses_them():
    v.check_positive_definite("r", np.diag([1.0, 1e-6]))
    with pytest.raises(ValueError, match="^r: must be symmetric positive definite"):
        v.check_positive_definite("r", np.diag([1.0, 0.0]))
    v.check_positive_semidefinite("q", np.diag([1.0, 0.0]))
    with pytest.raises(ValueError, match="^q: must be symmetric positive semi-definite"):
        v.check_positive_semidefinite("q", np.diag([1.0, -1e-9]))
    assert riccati.check_symmetric is v.check_symmetric
    assert riccati.check_positive_definite is v.check_positive_definite
    assert riccati.check_positive_semidefinite is v.check_positive_semidefinite
