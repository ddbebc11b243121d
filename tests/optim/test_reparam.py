"""Reparametrisations: round trips, constraints kept under arbitrary unconstrained steps, bad input."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from optim.reparam import (
    Identity,
    Interval,
    Positive,
    Simplex,
    SortedBreakpoints,
    SPDMatrix,
    apply,
    check_domain,
    invert,
)

FAST = settings(max_examples=40, deadline=None, derandomize=True)  # reproducible in CI
moderate = st.floats(-15.0, 15.0, allow_nan=False)


def vec(n, elements=moderate):
    return hnp.arrays(np.float64, n, elements=elements)


def satisfies(r, x) -> bool:
    """The constraint, written out independently of the reparametrisation's own check()."""
    x = np.asarray(x)
    if isinstance(r, Positive):
        return bool(np.all(x > r.floor))
    if isinstance(r, Interval):
        return bool(np.all((x > r.lo) & (x < r.hi)))
    if isinstance(r, SortedBreakpoints):
        gaps = np.diff(np.concatenate([[r.lo], x]))
        return bool(np.all(gaps >= r.min_gap * (1 - 1e-12)) and np.all(gaps > 0))
    if isinstance(r, SPDMatrix):
        return bool(np.allclose(x, x.T) and np.linalg.eigvalsh(x).min() > r.eps * (1 - 1e-9))
    if isinstance(r, Simplex):
        return bool(np.all(x > 0) and abs(x.sum() - 1) < 1e-12)
    return True


CASES = [  # (reparam, size of u)
    (Positive(), 4),
    (Positive(method="exp", floor=-2.0), 4),
    (Interval(jnp.array([-1.0, 0.0, 5.0]), jnp.array([1.0, 0.5, 50.0])), 3),
    (SortedBreakpoints(lo=0.2, min_gap=0.05), 5),
    (SortedBreakpoints(), 4),
    (SPDMatrix(3), 6),
    (SPDMatrix(3, eps=1e-3), 6),
    (Simplex(4), 3),
    (Simplex(3, full=True), 3),
]
IDS = [f"{type(r).__name__}{i}" for i, (r, _) in enumerate(CASES)]


@pytest.mark.parametrize("r,n", CASES, ids=IDS)
@FAST
@given(data=st.data())
def test_u_to_x_to_u_round_trip(r, n, data):
    # Cholesky loses ~cond(X)·eps; keep SPD draws well conditioned (|u| ≤ 4 → cond ≲ 1e5)
    u = data.draw(vec(n, st.floats(-4.0, 4.0) if isinstance(r, SPDMatrix) else moderate))
    x = r.forward(u)
    x_again = r.forward(r.inverse(x))
    np.testing.assert_allclose(x_again, x, rtol=1e-9, atol=1e-12)
    if not (isinstance(r, Simplex) and r.full):  # softmax(u) is shift-invariant: no unique u
        np.testing.assert_allclose(r.inverse(x), u, rtol=1e-6, atol=1e-6)


def _valid_x(r, draw):
    """A point of r's domain built directly from its definition (not through forward())."""
    if isinstance(r, Positive):
        return r.floor + draw(vec(4, st.floats(1e-3, 1e3)))
    if isinstance(r, Interval):
        p = draw(vec(3, st.floats(0.01, 0.99)))
        return np.asarray(r.lo) + (np.asarray(r.hi) - np.asarray(r.lo)) * p
    if isinstance(r, SortedBreakpoints):
        n = 5 if r.min_gap else 4
        return r.lo + np.cumsum(r.min_gap + draw(vec(n, st.floats(1e-3, 10.0))))
    if isinstance(r, SPDMatrix):
        a = draw(hnp.arrays(np.float64, (r.n, r.n), elements=st.floats(-3, 3)))
        return a @ a.T + 0.1 * np.eye(r.n)
    if isinstance(r, Simplex):
        w = draw(vec(r.n, st.floats(1e-3, 1.0)))
        return w / w.sum()
    raise AssertionError(r)


@pytest.mark.parametrize("r,n", CASES, ids=IDS)
@FAST
@given(data=st.data())
def test_x_to_u_to_x_round_trip(r, n, data):
    x = _valid_x(r, data.draw)
    assert satisfies(r, x)
    r.check("x", x)  # no error inside the domain
    np.testing.assert_allclose(r.forward(r.inverse(x)), x, rtol=1e-9, atol=1e-11)


@pytest.mark.parametrize("r,n", CASES, ids=IDS)
@FAST
@given(data=st.data())
def test_constraint_holds_along_random_unconstrained_walks(r, n, data):
    u = data.draw(vec(n, st.floats(-3, 3)))
    steps = data.draw(hnp.arrays(np.float64, (12, n), elements=st.floats(-4.0, 4.0)))
    # |u| ≤ 25 keeps sigmoid/softplus off their float limits; L Lᵀ without an eigenvalue floor is
    # numerically singular for extreme u (module docstring), so that case walks in |u| ≤ 3
    box = 3.0 if isinstance(r, SPDMatrix) and not r.eps else 25.0
    for step in steps:  # a random walk: any step in u-space stays admissible
        u = np.clip(u + step, -box, box)
        assert satisfies(r, r.forward(u)), (u, r.forward(u))


@pytest.mark.parametrize("r,n", CASES, ids=IDS)
def test_constraint_holds_under_large_gradient_steps(r, n):
    """Plain gradient descent with an absurd learning rate on a loss that pushes outward."""
    target = jax.random.normal(jax.random.PRNGKey(1), jnp.shape(r.forward(jnp.zeros(n)))) * 100

    def loss(u):
        return jnp.sum((r.forward(u) - target) ** 2)

    u = jnp.zeros(n)
    box = 3.0 if isinstance(r, SPDMatrix) and not r.eps else 25.0
    for _ in range(15):
        g = jax.grad(loss)(u)
        u = jnp.clip(u - 0.5 * g / (1e-12 + jnp.linalg.norm(g)) * 10.0, -box, box)
        assert satisfies(r, r.forward(u))


def test_sorted_breakpoints_min_gap_holds_even_for_extreme_u():
    r = SortedBreakpoints(lo=-1.0, min_gap=0.1)
    x = np.asarray(r.forward(jnp.array([-800.0, -50.0, 0.0, 700.0])))
    assert x[0] >= -1.0 + 0.1 - 1e-12 and np.all(np.diff(x) >= 0.1 - 1e-12)


def test_spd_forward_is_the_cholesky_product():
    u = jnp.array([0.3, -1.2, 2.0, 0.5, 0.7, -0.4])
    low = np.zeros((3, 3))
    sp = np.log1p(np.exp(np.asarray(u)))
    low[0, 0], low[1, 0], low[1, 1], low[2, 0], low[2, 1], low[2, 2] = sp[0], u[1], sp[2], u[3], u[4], sp[5]
    np.testing.assert_allclose(SPDMatrix(3).forward(u), low @ low.T, rtol=1e-13)


def test_simplex_bijection_matches_closed_form():
    u = jnp.array([0.5, -1.0])
    e = np.exp([0.5, -1.0, 0.0])
    np.testing.assert_allclose(Simplex(3).forward(u), e / e.sum(), rtol=1e-14)
    # the (n,) form is softmax(u) itself, shift-invariant
    np.testing.assert_allclose(Simplex(3).forward(jnp.array([1.5, 0.0, 1.0])), e / e.sum(), rtol=1e-14)
    with pytest.raises(ValueError, match="u"):
        Simplex(3).forward(jnp.ones(4))


def test_apply_invert_over_pytrees_with_prefixes_and_none():
    reparams = {"gains": Positive(), "breaks": SortedBreakpoints(min_gap=0.1), "free": None}
    x = {
        "gains": {"kp": jnp.array(2.0), "ki": jnp.array([0.5, 3.0])},
        "breaks": jnp.array([0.3, 0.6, 1.5]),
        "free": jnp.array([-4.0, 7.0]),
    }
    u = invert(reparams, x)
    np.testing.assert_allclose(u["free"], x["free"])
    back = apply(reparams, u)
    for a, b in zip(jax.tree_util.tree_leaves(back), jax.tree_util.tree_leaves(x)):
        np.testing.assert_allclose(a, b, rtol=1e-12)
    # works under jit/vmap/grad with bounds as traced leaves
    f = jax.jit(lambda r, uu: apply(r, uu))
    np.testing.assert_allclose(f(Interval(0.0, 2.0), jnp.zeros(3)), jnp.ones(3))
    g = jax.grad(lambda lo: jnp.sum(Interval(lo, 2.0).forward(jnp.zeros(2))))(0.0)
    assert float(g) == pytest.approx(1.0)  # x = lo + (2 − lo)/2  → ∂/∂lo summed over 2 = 1
    with pytest.raises(ValueError, match="reparam"):
        apply({"a": Positive()}, {"b": jnp.ones(2)})


def test_bad_input_names_the_argument():
    with pytest.raises(ValueError, match="lo/hi"):
        Interval(1.0, 1.0)
    with pytest.raises(ValueError, match="lo/hi"):
        Interval(jnp.array([0.0, 2.0]), jnp.array([1.0, 1.0]))
    with pytest.raises(ValueError, match="min_gap"):
        SortedBreakpoints(min_gap=-0.1)
    with pytest.raises(ValueError, match="method"):
        Positive(method="square")
    with pytest.raises(ValueError, match="n"):
        Simplex(1)
    with pytest.raises(ValueError, match=r"params0\['b'\]"):
        check_domain({"a": Positive(), "b": Interval(0.0, 1.0)}, {"a": jnp.ones(2), "b": jnp.array(1.5)})
    with pytest.raises(ValueError, match="breakpoints"):
        check_domain(SortedBreakpoints(), jnp.array([0.5, 0.4]))
    with pytest.raises(ValueError, match="positive definite"):
        check_domain(SPDMatrix(2), jnp.array([[1.0, 2.0], [2.0, 1.0]]))
    with pytest.raises(ValueError, match="summing to 1"):
        check_domain(Simplex(3), jnp.array([0.2, 0.2, 0.2]))
    assert np.allclose(Identity().inverse(jnp.ones(2)), 1.0)
