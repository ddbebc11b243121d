"""Bad inputs to control kernels that used to give silent garbage (all-NaN solutions, a finite
fuzzy output for a NaN input, a design for a zero plant): each raises a ``ValueError`` naming the
argument on concrete input, and propagates NaN under ``jit`` where documented."""

import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg as sl

from jaxsim.control import fuzzy as fz
from jaxsim.control.lyapunov import solve_continuous_lyapunov, solve_discrete_lyapunov
from jaxsim.control.stability_degree import max_stability_degree
from jaxsim.control.sylvester import solve_sylvester


def _rotated(block: np.ndarray, seed: int = 0) -> np.ndarray:
    """``Q block Qᵀ`` with a random orthogonal ``Q``: same spectrum, no exact zeros left."""
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=block.shape))
    return q @ block @ q.T


CENTER = _rotated(np.array([[0.0, 2.0, 0.0], [-2.0, 0.0, 0.0], [0.0, 0.0, -1.0]]))  # λ = ±2i, −1


def _rel(x, ref):
    return np.linalg.norm(np.asarray(x) - ref) / np.linalg.norm(ref)


ROTATION = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])  # λ = e^{±0.3i}


# --- Lyapunov / Stein / Sylvester with no unique solution ------------------------------------


@pytest.mark.parametrize(
    "a",
    [
        np.zeros((2, 2)),  # every eigenvalue 0
        np.array([[0.0, 1.0], [-1.0, 0.0]]),  # λ = ±i
        CENTER,  # λ = ±2i after a rotation (no exact zeros)
        np.diag([-1.0, 0.0, -2.0]),  # a zero eigenvalue: λ_i + λ_i = 0
    ],
)
def test_singular_continuous_lyapunov_raises(a):
    # Was: an all-NaN X without a word.
    with pytest.raises(
        ValueError,
        match=r"^a: the continuous Lyapunov equation .* is singular: "
        r"eigenvalues λ_i = .* and λ_j = .* of a give \|λ_i \+ λ_j\| = ",
    ):
        solve_continuous_lyapunov(a, np.eye(a.shape[0]))


@pytest.mark.parametrize("a", [np.diag([2.0, 0.5]), ROTATION, np.eye(2), _rotated(np.diag([-1.0, 0.3]), 1)])
def test_singular_stein_equation_raises(a):
    with pytest.raises(
        ValueError,
        match=r"^a: the discrete Lyapunov \(Stein\) equation .* is singular: "
        r".*λ_i·λ_j",
    ):
        solve_discrete_lyapunov(a, np.eye(2))


def test_singular_sylvester_raises_naming_both_spectra():
    a, b = np.array([[1.0, 2.0], [0.0, 3.0]]), np.array([[-3.0]])
    with pytest.raises(
        ValueError,
        match=r"^a, b: the Sylvester equation .* is singular: λ_i = 3.* of a and "
        r"μ_j = -3.* of b",
    ):
        solve_sylvester(a, b, np.ones((2, 1)))


def test_nearly_singular_but_regular_equations_still_solve():
    # λ = 1e-6 ± i: λ_1 + λ_2 = 2e-6, far above the round-off tolerance; condition ≈ 1e6.
    a = _rotated(np.array([[1e-6, 1.0], [-1.0, 1e-6]]))
    q = np.eye(2)
    x = np.asarray(solve_continuous_lyapunov(a, q))
    assert _rel(x, sl.solve_continuous_lyapunov(a, q)) < 1e-8
    s = 0.999 * ROTATION  # |λ|² = 0.998
    assert _rel(solve_discrete_lyapunov(s, q), sl.solve_discrete_lyapunov(s, q)) < 1e-10


def test_singular_equations_under_jit_give_nan():
    regular = np.array([[-1.0, 2.0, 0.0], [0.0, -3.0, 1.0], [0.0, 0.0, -0.5]])
    q = np.eye(3)
    batch = jnp.stack([jnp.asarray(CENTER), jnp.asarray(regular)])
    x = np.asarray(jax.jit(jax.vmap(solve_continuous_lyapunov, in_axes=(0, None)))(batch, q))
    assert np.all(np.isnan(x[0]))
    np.testing.assert_allclose(x[1], sl.solve_continuous_lyapunov(regular, q), rtol=1e-12)
    assert np.all(np.isnan(np.asarray(jax.jit(solve_discrete_lyapunov)(ROTATION, np.eye(2)))))
    y = jax.jit(solve_sylvester)(np.array([[1.0, 2.0], [0.0, 3.0]]), np.array([[-3.0]]), np.ones((2, 1)))
    assert np.all(np.isnan(np.asarray(y)))


# --- maximum stability degree of a zero plant -------------------------------------------------


@pytest.mark.parametrize("num", [[0.0], [0.0, 0.0, 0.0]])
def test_zero_numerator_is_rejected(num):
    # Was: a "design" kp = 0 with the open-loop poles, degree 1, reported as coalesced.
    with pytest.raises(ValueError, match=r"^num: .*identically zero"):
        max_stability_degree(num, [1.0, 2.0, 1.0], "P")


def test_zero_denominator_is_rejected():
    with pytest.raises(ValueError, match=r"^den: .*identically zero"):
        max_stability_degree([1.0], [0.0, 0.0], "P")


# --- fuzzy inference of a NaN or wrongly sized input ------------------------------------------

TRI = fz.terms("triangular", [[-2.0, -1.0, 0.0], [-1.0, 0.0, 1.0], [0.0, 1.0, 2.0]])
SUGENO = fz.sugeno([TRI], [-1.0, 0.0, 1.0], fz.rule_base([[0], [1], [2]], [0, 1, 2]))
MAMDANI = fz.mamdani(
    [TRI, TRI], jnp.linspace(-2.0, 2.0, 41), TRI, fz.grid_rule_base(np.array([[0, 0, 1], [0, 1, 2], [1, 2, 2]]))
)
BISECTOR = fz.mamdani(
    [TRI], jnp.linspace(-2.0, 2.0, 41), TRI, fz.rule_base([[0], [1], [2]], [0, 1, 2]), defuzzifier="bisector"
)
TSUKAMOTO = fz.tsukamoto([TRI], fz.terms("sigmoid", [[-1.0, 4.0], [1.0, 4.0]]), fz.rule_base([[0], [2]], [0, 1]))
SYSTEMS = {"sugeno": SUGENO, "mamdani": MAMDANI, "bisector": BISECTOR, "tsukamoto": TSUKAMOTO}


@pytest.mark.parametrize("name", SYSTEMS)
def test_nan_input_is_rejected(name):
    fis = SYSTEMS[name]
    x = jnp.full(fis.n_inputs, jnp.nan)  # was: full membership everywhere and a finite output
    with pytest.raises(ValueError, match=r"^x: must be finite"):
        fz.evaluate(fis, x)


@pytest.mark.parametrize("name", SYSTEMS)
def test_nan_input_under_jit_propagates_nan(name):
    fis = SYSTEMS[name]
    x = jnp.zeros(fis.n_inputs).at[0].set(jnp.nan)
    assert np.isnan(float(jax.jit(fz.evaluate)(fis, x)))
    assert np.isfinite(float(jax.jit(fz.evaluate)(fis, jnp.zeros(fis.n_inputs) + 0.3)))


@pytest.mark.parametrize(
    "fis, x, want",
    [
        (SUGENO, jnp.array([0.5, 3.0]), 1),  # was: the extra entry ignored
        (MAMDANI, jnp.array([0.5]), 2),  # was: the missing entry read out of bounds (clamped)
        (MAMDANI, jnp.array([[0.5, 0.5]]), 2),
    ],
)
def test_input_of_the_wrong_length_is_rejected(fis, x, want):
    with pytest.raises(ValueError, match="^" + re.escape(f"x: expected shape ({want},), got {tuple(x.shape)}")):
        fz.evaluate(fis, x)
    with pytest.raises(ValueError, match=r"^x: expected shape"):
        jax.jit(fz.evaluate)(fis, x)  # a static shape: checked under jit too
