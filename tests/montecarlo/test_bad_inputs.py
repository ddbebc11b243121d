"""A sweep over a parameter the space does not have used to run, every point identical."""

import jax
import pytest

import jaxsim.montecarlo as mc


def _fn(key, p):
    return {"y": p["a"] + p["k"] * jax.random.normal(key)}


SPACE = {"a": mc.normal(0.0, 1.0), "k": 1.0}


@pytest.mark.parametrize(
    "design",
    [
        mc.grid({"b": (0.0, 1.0, 2)}),
        mc.points(["k", "gain"], [[1.0, 2.0]]),
        mc.latin_hypercube({"K": (0.0, 1.0)}, 2),  # names are case-sensitive
    ],
)
def test_design_parameter_absent_from_the_space_is_rejected(design):
    missing = [n for n in design.names if n not in SPACE][0]
    with pytest.raises(
        ValueError,
        match=rf"^design: parameter '{missing}' is not in the space; "
        r"the space's parameters: a, k",
    ):
        mc.sweep(_fn, SPACE, design, 10, 0)


def test_design_over_a_fixed_parameter_of_the_space_runs():
    res = mc.sweep(_fn, SPACE, mc.points(["k"], [[0.0], [1.0]]), 16, 0, block_size=16)
    assert res.points[0].by_name["y"].mean != res.points[1].by_name["y"].mean
