"""Analytic steady-state error with fuzzy/linear characteristics: the paper's numbers, Tables 1–2,
and the balance equations the operating point must satisfy (simulation: tests/experiments)."""

import numpy as np
import pytest

from jaxsim.control import fuzzy as fz
from jaxsim.control.fuzzy_steady_state import section_domains, steady_state_error
from jaxsim.control.steady_state import paper_table_error

K = 2.0
STATIC_FC = fz.three_section(0.75, 0.3, 1.2, 1.0)
ASTATIC_FC = fz.three_section(0.2, 0.25, 1.2, 2.0)


def test_paper_operating_points():
    cases = [  # (plant, characteristic, f, expected e to 4 decimals, section, equation)
        ("static", STATIC_FC, 0.0, 0.5556, 1, "(1)"),
        ("static", fz.linear(0.4), 0.0, 0.5556, 1, "(1)"),
        ("static", STATIC_FC, 0.3, 0.8108, 2, "(2)"),
        ("static", fz.linear(0.4), 0.3, 0.8889, 1, "(1)"),
        ("astatic", ASTATIC_FC, 0.2, 0.16, 1, "balance"),
        ("astatic", fz.linear(1.25), 0.2, 0.16, 1, "balance"),
        ("astatic", ASTATIC_FC, 0.7, 0.4571, 2, "balance"),
        ("astatic", fz.linear(1.25), 0.7, 0.56, 1, "balance"),
    ]
    for plant, char, f, expected, section, equation in cases:
        op = steady_state_error(plant, K, char, g=1.0, f=f)
        assert round(op.error, 4) == expected and op.exists
        assert (op.section, op.equation) == (section, equation)
    # the domains of (1) and (2) for the static FC: g/K + f ≤ 0.675, ≤ 1.6 (spec §1.4)
    assert section_domains("static", K, STATIC_FC) == pytest.approx((0.675, 1.6))
    assert section_domains("astatic", K, ASTATIC_FC) == pytest.approx((0.25, 2.0))


@pytest.mark.parametrize("seed", range(12))
def test_linear_characteristics_reproduce_tables_1_and_2(seed):
    rng = np.random.default_rng(seed)
    plant = ["static", "astatic"][seed % 2]
    k, kp, ki = rng.uniform(0.5, 3), rng.uniform(0.2, 2), rng.uniform(0.2, 2)
    for structure in ("P", "PD", "PI"):
        i = fz.linear(ki) if structure == "PI" else None
        for source, order in (("reference", 0), ("reference", 1), ("disturbance", 0), ("disturbance", 1)):
            mag = rng.uniform(0.1, 2.0)
            kw = {
                ("reference", 0): "g",
                ("reference", 1): "g_slope",
                ("disturbance", 0): "f",
                ("disturbance", 1): "f_slope",
            }[(source, order)]
            op = steady_state_error(plant, k, fz.linear(kp), i, **{kw: mag})
            table = paper_table_error(plant, structure, source, order, k, kp, ki, mag)
            if np.isinf(table):
                assert not op.exists and op.error == table
            else:
                assert op.exists and op.error == pytest.approx(table, rel=1e-13, abs=1e-15)


@pytest.mark.parametrize("seed", range(20))
def test_operating_point_satisfies_the_balance_equation(seed):
    rng = np.random.default_rng(seed)
    a, c = np.sort(rng.uniform(0.1, 2.0, 2))
    b = rng.uniform(0.1, 1.5)
    d = b + rng.uniform(0.0, 2.0)
    char = fz.three_section(a, b, c, d)
    k = rng.uniform(0.5, 3.0)
    g, f, kg, kf = rng.uniform(-3, 3), rng.uniform(-2, 2), rng.uniform(-1, 1), rng.uniform(-1, 1)
    F = lambda e: float(char(e))  # noqa: E731
    section_of = lambda e: 1 if abs(e) <= a else (2 if abs(e) <= c else 3)  # noqa: E731

    op = steady_state_error("static", k, char, g=g, f=f)  # e + K F(e) = g + K f
    assert op.exists and op.error + k * F(op.error) == pytest.approx(g + k * f, abs=1e-12)
    assert op.section == section_of(op.error)

    op = steady_state_error("astatic", k, char, g=g, g_slope=kg, f=f)  # F(e) = f + K_g/K
    v = f + kg / k
    assert op.exists == (abs(v) < d)
    if op.exists:
        assert F(op.error) == pytest.approx(v, abs=1e-12) and op.section == section_of(op.error)
    else:
        assert op.error == np.sign(v) * np.inf

    op = steady_state_error("static", k, fz.linear(1.0), char, g=g, g_slope=kg, f=f, f_slope=kf)  # PI
    rate = kg / k + kf
    assert op.channel == "i" and op.exists == (abs(rate) < d)
    if op.exists:
        assert F(op.error) == pytest.approx(rate, abs=1e-12)

    assert steady_state_error("astatic", k, char, char, g=g, f=f).error == 0.0  # PI, constant inputs
    assert not steady_state_error("static", k, char, g=g, g_slope=0.3).exists  # P, ramp: ∞


def test_bad_arguments():
    with pytest.raises(ValueError, match="plant"):
        steady_state_error("integrating", K, STATIC_FC)
    with pytest.raises(ValueError, match="^K:"):
        steady_state_error("static", -1.0, STATIC_FC)
    with pytest.raises(ValueError, match="^p:"):
        steady_state_error("static", K, None)
    with pytest.raises(ValueError, match="characteristic"):
        steady_state_error("static", K, lambda e: e)
    with pytest.raises(ValueError, match="g_slope/f_slope"):
        steady_state_error("static", K, STATIC_FC, g_slope=0.4, f_slope=-0.2)
