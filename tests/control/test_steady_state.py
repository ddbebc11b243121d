"""The paper's Tables 1–2 against the final-value theorem on random loops."""

import numpy as np
import pytest

from jaxsim.control.pid import pid_transfer_function
from jaxsim.control.stability_degree import characteristic_polynomial, stability_degree
from jaxsim.control.steady_state import final_value_error, paper_table_error

INPUTS = [("reference", 0), ("reference", 1), ("disturbance", 0), ("disturbance", 1)]


def _plant(kind, K, T1, T2):
    if kind == "static":
        return np.array([K]), np.array([T1 * T2, T1 + T2, 1.0])
    return np.array([K]), np.array([T1, 1.0, 0.0])


@pytest.mark.parametrize("seed", range(40))
def test_tables_equal_the_final_value_theorem(seed):
    rng = np.random.default_rng(seed)
    kind = ["static", "astatic"][seed % 2]
    structure = ["P", "PI", "PD"][seed % 3]
    K, T1, T2 = rng.uniform(0.5, 3.0), rng.uniform(0.05, 0.5), rng.uniform(0.05, 0.5)
    num, den = _plant(kind, K, T1, T2)
    while True:
        kp, ki, kd = (
            rng.uniform(0.1, 2.0),
            rng.uniform(0.1, 2.0) * (structure == "PI"),
            rng.uniform(0.01, 0.2) * (structure == "PD"),
        )
        gains = {"P": [kp], "PI": [kp, ki], "PD": [kp, kd]}[structure]
        if stability_degree(characteristic_polynomial(num, den, structure, gains, 0.02)) > 0:
            break
    nc, dc = pid_transfer_function(kp, ki, kd, 0.02)
    for source, order in INPUTS:
        mag = rng.uniform(0.1, 2.0)
        fvt = final_value_error(num, den, nc, dc, source, order, mag)
        table = paper_table_error(kind, structure, source, order, K, kp, ki, mag)
        if np.isinf(table):
            assert fvt == table
        else:
            assert fvt == pytest.approx(table, rel=1e-12, abs=1e-15)


def test_paper_numbers_linear_controller():
    # static plant, K_mds = 0.4: g = 1 → 0.5556; f = 0.3 adds 0.3333 → 0.8889 (paper: 0.56, 0.89)
    assert paper_table_error("static", "P", "reference", 0, 2.0, 0.4, magnitude=1.0) == pytest.approx(5 / 9)
    total = 5 / 9 + paper_table_error("static", "P", "disturbance", 0, 2.0, 0.4, magnitude=0.3)
    assert total == pytest.approx(0.8889, abs=5e-5)
    # astatic plant, K_mds = 1.25: f = 0.2 → 0.16, f = 0.7 → 0.56
    assert paper_table_error("astatic", "P", "disturbance", 0, 2.0, 1.25, magnitude=0.2) == pytest.approx(0.16)
    assert paper_table_error("astatic", "P", "disturbance", 0, 2.0, 1.25, magnitude=0.7) == pytest.approx(0.56)


def test_unstable_loop_and_bad_arguments():
    num, den = np.array([2.0]), np.array([0.1, 1.0, 0.0])
    with pytest.raises(ValueError, match="not asymptotically stable"):
        final_value_error(num, den, np.array([-1.0]), np.array([1.0]), "reference", 0)
    with pytest.raises(ValueError, match="source"):
        final_value_error(num, den, np.array([1.0]), np.array([1.0]), "noise", 0)
    with pytest.raises(ValueError, match="order"):
        final_value_error(num, den, np.array([1.0]), np.array([1.0]), "reference", 2)
