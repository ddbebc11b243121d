"""Maximum-stability-degree design: the paper's gains computed, optimality checked numerically."""

import numpy as np
import pytest

from jaxsim.control.stability_degree import (
    characteristic_polynomial,
    max_stability_degree,
    stability_degree,
)
from jaxsim.plants.second_order import (
    AstaticParams,
    StaticParams,
    astatic_transfer_function,
    static_transfer_function,
)

STATIC = tuple(np.asarray(v) for v in static_transfer_function(StaticParams()))
ASTATIC = tuple(np.asarray(v) for v in astatic_transfer_function(AstaticParams()))


def test_p_control_static_plant_gives_the_paper_gain_and_double_pole():
    d = max_stability_degree(*STATIC, "P")
    assert d.gains["kp"] == pytest.approx(0.4, rel=1e-12)  # paper line 488: K_mds = 0.4
    assert d.degree == pytest.approx(6.0, rel=1e-12)
    np.testing.assert_allclose(np.sort(d.poles.real), [-6.0, -6.0], rtol=1e-6)


def test_p_control_astatic_plant_gives_the_paper_gain_and_double_pole():
    d = max_stability_degree(*ASTATIC, "P")
    assert d.gains["kp"] == pytest.approx(1.25, rel=1e-12)  # paper line 619: K_mds = 1.25
    assert d.degree == pytest.approx(5.0, rel=1e-12)
    np.testing.assert_allclose(d.poles.real, [-5.0, -5.0], rtol=1e-6)


def test_pi_triple_root_design_on_the_astatic_plant():
    d = max_stability_degree(*ASTATIC, "PI")
    T, K = 0.1, 2.0  # closed form for 0.1 s^3 + s^2 + 2Kp s + 2Ki = 0.1 (s + 1/(3T))^3
    assert d.method == "coalesced"
    assert d.degree == pytest.approx(1 / (3 * T), rel=1e-12)
    assert d.gains["kp"] == pytest.approx(1 / (3 * T * K), rel=1e-12)
    assert d.gains["ki"] == pytest.approx(1 / (27 * T**2 * K), rel=1e-12)
    np.testing.assert_allclose(d.char_poly, 0.1 * np.poly([-1 / (3 * T)] * 3), rtol=1e-12)


@pytest.mark.parametrize(
    "plant, structure, tf",
    [
        (STATIC, "P", 0.0),
        (ASTATIC, "P", 0.0),
        (STATIC, "PI", 0.0),
        (ASTATIC, "PI", 0.0),
        (STATIC, "PD", 0.05),
        (ASTATIC, "PD", 0.05),
        (STATIC, "PID", 0.05),
    ],
)
def test_no_nearby_gain_has_a_larger_stability_degree(plant, structure, tf):
    d = max_stability_degree(*plant, structure, tf=tf)
    k0 = np.array(list(d.gains.values()))
    rng = np.random.default_rng(0)
    for _ in range(300):
        k = k0 * (1 + rng.normal(scale=0.05, size=k0.shape))
        eta = stability_degree(characteristic_polynomial(*plant, structure, k, tf))
        assert eta <= d.degree * (1 + 1e-4)
    # and the independent multi-start search did not beat the coalesced design
    assert d.search_degree <= d.degree * (1 + 1e-4)


def test_unbounded_designs_and_bad_structures_are_rejected():
    with pytest.raises(ValueError, match="unbounded"):
        max_stability_degree(*STATIC, "PD")  # ideal PD places both poles
    with pytest.raises(ValueError, match="structure"):
        max_stability_degree(*STATIC, "PIDD")
    with pytest.raises(ValueError, match="fixed"):
        max_stability_degree(*STATIC, "P", fixed={"ki": 1.0})
    with pytest.raises(ValueError, match="tf"):
        max_stability_degree(*STATIC, "PD", tf=-1.0)


def test_fixed_gain_reduces_the_design():
    d = max_stability_degree(*STATIC, "PI", fixed={"ki": 0.5})
    assert d.gains["ki"] == 0.5
    assert d.degree > 0
