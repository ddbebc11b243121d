"""Steady-state error of a linear loop: final-value theorem, and the paper's Tables 1–2.

Loop (fuzzy-PID paper, Fig. 1): ``e = g − y``, controller ``C = Nc/Dc``, plant ``P = N/D``, the
disturbance ``f`` enters the plant input as ``u − f``.  Hence

* from the reference: ``E(s) = D·Dc / (D·Dc + N·Nc) · G(s)``;
* from the disturbance: ``E(s) = N·Dc / (D·Dc + N·Nc) · F(s)``;

with ``G, F = A/s`` (constant, ``order = 0``) or ``A/s²`` (ramp of slope ``A``, ``order = 1``).
:func:`final_value_error` applies ``e(∞) = lim s·E(s)`` exactly on the polynomial coefficients
(counting the zeros at the origin), returning ``±inf`` where the error grows without bound.
:func:`paper_table_error` evaluates the closed forms printed in the paper's Tables 1–2 so the two
can be checked against each other and against simulation.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from jaxsim.control.stability_degree import stability_degree

Source = Literal["reference", "disturbance"]


def _lowest_order(p: np.ndarray, tol: float = 0.0) -> tuple[int, float]:
    """(multiplicity of the root at s = 0, lowest non-zero coefficient) for descending ``p``."""
    asc = np.asarray(p, float)[::-1]
    nz = np.flatnonzero(np.abs(asc) > tol)
    if nz.size == 0:
        return len(asc), 0.0
    return int(nz[0]), float(asc[nz[0]])


def final_value_error(num, den, nc, dc, source: Source, order: int, magnitude: float = 1.0) -> float:
    """``e(∞)`` for a constant (``order=0``) or ramp (``order=1``) input of size ``magnitude``.

    Raises ``ValueError`` if the closed loop is not asymptotically stable (no final value).
    """
    if source not in ("reference", "disturbance"):
        raise ValueError(f"source: must be 'reference' or 'disturbance', got {source!r}")
    if order not in (0, 1):
        raise ValueError(f"order: must be 0 (constant) or 1 (ramp), got {order!r}")
    char = np.polyadd(np.polymul(den, dc), np.polymul(num, nc))
    if not stability_degree(char) > 0:
        raise ValueError("controller: closed loop is not asymptotically stable; no steady state")
    numer = np.polymul(den, dc) if source == "reference" else np.polymul(num, dc)
    zeros_at_origin, coeff = _lowest_order(numer)
    char0 = float(np.asarray(char, float)[-1])
    # s·E(s) = magnitude · numer(s) / (s^order · char(s))
    if coeff == 0.0 or magnitude == 0.0:
        return 0.0
    if zeros_at_origin > order:
        return 0.0
    if zeros_at_origin == order:
        return magnitude * coeff / char0
    return float(np.sign(magnitude * coeff / char0) * np.inf)


def paper_table_error(
    plant: Literal["static", "astatic"],
    structure: Literal["P", "PI", "PD"],
    source: Source,
    order: int,
    K: float,
    kp: float,
    ki: float = 0.0,
    magnitude: float = 1.0,
) -> float:
    """The closed forms of the paper's Table 1 (static plant) and Table 2 (astatic plant)."""
    inf = float(np.inf) * np.sign(magnitude) if magnitude else 0.0
    g_or_f = magnitude
    if plant == "static":
        if structure in ("P", "PD"):
            if order == 1:
                return inf
            return g_or_f / (1 + K * kp) if source == "reference" else K * g_or_f / (1 + K * kp)
        if structure == "PI":
            if order == 0:
                return 0.0
            return g_or_f / (K * ki) if source == "reference" else g_or_f / ki
    elif plant == "astatic":
        if structure in ("P", "PD"):
            if source == "reference":
                return 0.0 if order == 0 else g_or_f / (K * kp)
            return g_or_f / kp if order == 0 else inf
        if structure == "PI":
            if source == "disturbance" and order == 1:
                return g_or_f / ki
            return 0.0
    raise ValueError(f"plant/structure: no table entry for plant={plant!r}, structure={structure!r}")
