"""Rule bases as integer arrays.

A rule base of ``R`` rules over ``n`` inputs is

* ``antecedents`` ``(R, n)``: for rule ``r`` and input ``i`` the index of the input term the rule
  tests, or ``-1`` when the rule does not look at that input;
* ``consequents`` ``(R,)``: the index of the output term (Mamdani, Larsen, Tsukamoto) or of the
  output function (Sugeno) the rule fires;
* ``connective``: ``"and"`` (the system's t-norm joins a rule's tests) or ``"or"`` (its s-norm).

The rule structure is discrete, so it is static metadata of a fuzzy system (hashable tuples; part
of the jit cache key); rule *weights* are array leaves of :class:`~.inference.FuzzySystem`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np


@dataclass(frozen=True)
class RuleBase:
    """Validated rule base (build it with :func:`rule_base` or :func:`grid_rule_base`)."""

    antecedents: tuple[tuple[int, ...], ...]
    consequents: tuple[int, ...]
    connective: str = "and"

    @property
    def n_rules(self) -> int:
        return len(self.consequents)

    @property
    def n_inputs(self) -> int:
        return len(self.antecedents[0])

    def antecedent_array(self) -> np.ndarray:
        """``(R, n)`` int array."""
        return np.asarray(self.antecedents, dtype=np.int32).reshape(self.n_rules, self.n_inputs)

    def consequent_array(self) -> np.ndarray:
        """``(R,)`` int array."""
        return np.asarray(self.consequents, dtype=np.int32)

    def check_ranges(self, n_input_terms: Sequence[int], n_outputs: int) -> None:
        """Raise ``ValueError`` if an index is out of range for the given variable sizes."""
        ant = self.antecedent_array()
        if len(n_input_terms) != self.n_inputs:
            raise ValueError(f"inputs: the rule base has {self.n_inputs} inputs, the system {len(n_input_terms)}")
        for i, n_terms in enumerate(n_input_terms):
            bad = np.flatnonzero((ant[:, i] < -1) | (ant[:, i] >= n_terms))
            if bad.size:
                r = int(bad[0])
                raise ValueError(
                    f"antecedents: rule {r} uses term {int(ant[r, i])} of input {i}, which has "
                    f"{n_terms} terms (valid: 0..{n_terms - 1}, or -1 for 'not used')"
                )
        cons = self.consequent_array()
        bad = np.flatnonzero((cons < 0) | (cons >= n_outputs))
        if bad.size:
            r = int(bad[0])
            raise ValueError(
                f"consequents: rule {r} fires output {int(cons[r])}, but there are {n_outputs} "
                f"(valid: 0..{n_outputs - 1})"
            )


def _as_int_array(name: str, x: Any, ndim: int) -> np.ndarray:
    arr = np.asarray(x)
    if arr.size == 0:
        raise ValueError(f"{name}: empty rule base (need at least one rule)")
    if arr.ndim != ndim:
        raise ValueError(f"{name}: expected a {ndim}-D array, got shape {arr.shape}")
    if arr.dtype.kind not in "iu":
        as_int = np.round(arr.astype(float))
        if not np.all(np.isfinite(arr.astype(float))) or np.any(as_int != arr):
            raise ValueError(f"{name}: term indices must be integers, got {arr.tolist()}")
        arr = as_int
    return arr.astype(np.int64)


def rule_base(antecedents: Any, consequents: Any, connective: str = "and") -> RuleBase:
    """A :class:`RuleBase` from ``antecedents`` ``(R, n)`` and ``consequents`` ``(R,)``.

    Ranges against the variables are checked when the rule base joins a fuzzy system.

    Raises:
        ValueError: empty rule base, non-integer indices, mismatched lengths, index < −1, unknown
            connective.
    """
    ant = _as_int_array("antecedents", antecedents, 2)
    cons = _as_int_array("consequents", consequents, 1)
    if ant.shape[1] < 1:
        raise ValueError(f"antecedents: need at least one input column, got shape {ant.shape}")
    if ant.shape[0] != cons.shape[0]:
        raise ValueError(f"consequents: {cons.shape[0]} consequents for {ant.shape[0]} rules (antecedent rows)")
    if np.any(ant < -1):
        raise ValueError(f"antecedents: indices must be ≥ −1 (−1 = input not used), got min {ant.min()}")
    if np.any(cons < 0):
        raise ValueError(f"consequents: indices must be ≥ 0, got min {cons.min()}")
    if connective not in ("and", "or"):
        raise ValueError(f"connective: must be 'and' or 'or', got {connective!r}")
    return RuleBase(
        antecedents=tuple(tuple(int(v) for v in row) for row in ant),
        consequents=tuple(int(v) for v in cons),
        connective=connective,
    )


def grid_rule_base(table: Any) -> RuleBase:
    """The complete AND rule base of a rule table: one rule per cell.

    ``table`` has one axis per input (shape ``(T_1, …, T_n)``); cell ``(j_1, …, j_n)`` holds the
    consequent of the rule "input 1 is term j_1 and … and input n is term j_n".  A 7×7 table gives
    the classic 49-rule two-input controller.
    """
    tab = np.asarray(table)
    if tab.size == 0:
        raise ValueError("table: empty rule base (need at least one rule)")
    idx = np.stack(np.meshgrid(*(np.arange(s) for s in tab.shape), indexing="ij"), -1)
    return rule_base(idx.reshape(-1, tab.ndim), tab.reshape(-1), "and")
