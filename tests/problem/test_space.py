"""ParamSpace: search coordinates and reparametrisations from one declaration, their round trips,
the box, and clear errors for bad declarations."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.problem import Param, ParamSpace, Sorted
from jaxsim.problem.reparam import Interval, LogInterval, SortedBreakpoints, apply, invert

SPACE = ParamSpace(
    kp=Param(lo=0.0, hi=50.0, init=1.0),
    ki=Param(lo=1e-3, hi=20.0, init=0.5, log=True),
    q=Param(lo=1e-2, hi=1e4, init=np.array([1.0, 10.0, 100.0]), log=True),
    e=Sorted(lo=0.05, hi=1.5, init=(0.75, 1.2), min_gap=0.02),
)


def test_box_names_and_init_in_search_coordinates():
    lo, hi = SPACE.box
    np.testing.assert_allclose(lo, [0.0, np.log(1e-3)] + [np.log(1e-2)] * 3 + [0.05, 0.05], rtol=1e-15)
    np.testing.assert_allclose(hi, [50.0, np.log(20.0)] + [np.log(1e4)] * 3 + [1.5, 1.5], rtol=1e-15)
    assert SPACE.names == ("kp", "ki", "q[0]", "q[1]", "q[2]", "Δe[0]", "Δe[1]") and SPACE.dim == 7
    z0 = np.asarray(SPACE.to_search(SPACE.init))
    np.testing.assert_allclose(z0, [1.0, np.log(0.5), 0.0, np.log(10.0), np.log(100.0), 0.75, 0.45], rtol=1e-14)
    assert SPACE.init["kp"].shape == () and SPACE.init["q"].shape == (3,) and SPACE.init["e"].dtype == jnp.float64


def test_search_round_trip_jit_and_vmap():
    rng = np.random.default_rng(0)
    lo, hi = SPACE.box
    z = jnp.asarray(lo + (hi - lo) * rng.random((16, SPACE.dim)))
    params = jax.jit(jax.vmap(SPACE.from_search))(z)
    back = jax.vmap(SPACE.to_search)(params)
    np.testing.assert_allclose(back, z, rtol=1e-12, atol=1e-14)
    # every box point is admissible: inside the value bounds, breakpoints increasing with the gaps
    assert np.all((params["kp"] >= 0) & (params["kp"] <= 50))
    assert np.all((params["q"] >= 1e-2 * (1 - 1e-12)) & (params["q"] <= 1e4 * (1 + 1e-12)))
    gaps = np.diff(np.concatenate([np.zeros((16, 1)), params["e"]], axis=1), axis=1)
    assert np.all(gaps >= 0.05 - 1e-12) and np.all(gaps <= 1.5 + 1e-12)
    np.testing.assert_allclose(SPACE.from_search(SPACE.to_search(SPACE.init))["ki"], 0.5, rtol=1e-15)


def test_reparam_maps_unconstrained_steps_inside_the_declaration():
    r = SPACE.reparam
    assert isinstance(r["kp"], Interval) and isinstance(r["ki"], LogInterval) and isinstance(r["e"], SortedBreakpoints)
    u0 = invert(r, SPACE.init)
    back = apply(r, u0)
    for name in SPACE.keys:
        np.testing.assert_allclose(back[name], SPACE.init[name], rtol=1e-12)
    # large unconstrained moves stay admissible
    far = jax.tree_util.tree_map(lambda u: u + 12.0 * jnp.sign(jnp.cos(7.0 * (u + 1.0))), u0)
    x = apply(r, far)
    assert 0.0 < float(x["kp"]) < 50.0 and 1e-3 < float(x["ki"]) < 20.0
    assert np.all(np.diff(np.concatenate([[0.0], np.asarray(x["e"])])) > 0.02)
    # the log interval is uniform in log x: sigmoid(0) is the geometric mean of the bounds
    assert float(LogInterval(1e-3, 20.0).forward(0.0)) == pytest.approx(np.sqrt(1e-3 * 20.0), rel=1e-13)


def test_flat_values_and_labels():
    space = ParamSpace(
        gains=Param(lo=(0, 0, 0), hi=(20, 20, 2), init=(10, 10, 1), labels=("kp", "ki", "kd")),
        e=Sorted(lo=0.1, hi=1.0, init=(0.5, 0.9)),
    )
    assert space.names == ("kp", "ki", "kd", "Δe[0]", "Δe[1]")
    assert space.flat(space.init) == {"kp": 10.0, "ki": 10.0, "kd": 1.0, "e[0]": 0.5, "e[1]": 0.9}


@pytest.mark.parametrize(
    "decl, match",
    [
        (Param(lo=0.0, hi=1.0, init=1.0), r"x.init: must lie strictly inside"),
        (Param(lo=1.0, hi=1.0, init=1.0), r"x: need lo < hi"),
        (Param(lo=0.0, hi=10.0, init=1.0, log=True), r"x.lo: a log-scaled parameter needs lo > 0"),
        (Param(lo=0.0, hi=float("inf"), init=1.0), r"x.hi: must be finite"),
        (Param(lo=(0, 0), hi=(1, 1, 1), init=(0.5, 0.5)), r"x: lo \(2,\) and hi \(3,\) do not broadcast"),
        (Param(lo=0.0, hi=1.0, init=(0.5, 0.5), labels=("a",)), r"x.labels: need 2 labels"),
        (Sorted(lo=0.1, hi=1.0, init=(0.5, 0.4)), r"x.init: must increase from origin"),
        (Sorted(lo=0.1, hi=1.0, init=(0.5, 2.0)), r"x.init: its increments \[0.5, 1.5\] must lie in"),
        (Sorted(lo=0.01, hi=1.0, init=(0.5, 0.9), min_gap=0.05), r"x.lo: the increments' lower bounds"),
        (Sorted(lo=0.1, hi=1.0, init=0.5), r"x.init: a Sorted parameter is a vector"),
    ],
)
def test_bad_declarations_are_refused_naming_the_parameter(decl, match):
    with pytest.raises(ValueError, match=match):
        ParamSpace(x=decl)


def test_bad_use_of_a_space():
    with pytest.raises(ValueError, match="declare at least one parameter"):
        ParamSpace()
    with pytest.raises(ValueError, match="y: expected a Param or Sorted"):
        ParamSpace(y=(0.0, 1.0))
    with pytest.raises(ValueError, match=r"z: expected shape \(7,\)"):
        SPACE.from_search(jnp.zeros(6))
    with pytest.raises(ValueError, match="params: missing e"):
        SPACE.to_search({k: v for k, v in SPACE.init.items() if k != "e"})


def test_init_is_a_fresh_dict_of_the_declared_values_every_time():
    space = ParamSpace(kp=Param(lo=0.1, hi=10.0, init=2.0), w=Param(lo=0.0, hi=5.0, init=np.array([1.0, 3.0])))
    first = space.init
    first["kp"] = jnp.asarray(99.0)  # a caller editing its copy
    second = space.init
    assert second is not first and set(second) == {"kp", "w"}
    np.testing.assert_array_equal(second["kp"], 2.0)
    np.testing.assert_array_equal(second["w"], [1.0, 3.0])
    assert second["w"].dtype == jnp.float64
