"""Fuzzy inference systems: Mamdani, Larsen, Sugeno (zero and first order) and Tsukamoto.

A :class:`FuzzySystem` is a pytree: its leaves are the membership-function parameters of every
input, the output's parameters (output-term MFs and grid, Sugeno coefficients) and the rule
weights, so ``jax.grad`` of a loss of ``evaluate(fis, x)`` differentiates every MF parameter and
``jax.vmap(evaluate, in_axes=(0, None))`` runs a batch of systems of the same structure.  The rule
base and the choice of norms, implication and defuzzifier are static (see :mod:`.rules`).

Evaluation of ``x`` (shape ``(n,)``):

1. fuzzification: ``μ_{i,j} = input_i.term_j(x_i)``;
2. rule strengths: ``w_r = weight_r · T_i μ_{i, ant(r,i)}`` (AND rules: the t-norm ``and_norm``; OR
   rules: the s-norm ``or_norm``; inputs a rule does not test are skipped);
3. the output:

   * **Mamdani / Larsen** (:class:`MamdaniOutput`): activation of output term ``t``
     ``α_t = S_{r: cons(r)=t} w_r`` (``accumulation`` s-norm), the output set
     ``max_t I(α_t, μ_t(z))`` with ``I = min`` (Mamdani) or product (Larsen) on the output grid,
     then a defuzzifier (:mod:`.defuzzify`); this is scikit-fuzzy's control-API semantics;
   * **Sugeno** (:class:`SugenoOutput`): ``Σ w_r z_r / Σ w_r`` with ``z_r`` the rule's output
     function: a constant (zero order) or ``c_0 + Σ_i c_i x_i`` (first order);
   * **Tsukamoto** (:class:`TsukamotoOutput`): each rule's output is the point where its monotone
     output MF reaches ``w_r``, ``z_r = μ_{cons(r)}^{-1}(w_r)``, combined as ``Σ w_r z_r / Σ w_r``.

If no rule fires (``Σ w_r = 0``), Sugeno and Tsukamoto return 0 (simpful's convention), Mamdani the
defuzzifier's fallback (the middle of the output grid).

Inputs: ``x`` must have shape ``(n,)`` (``ValueError`` naming ``x`` otherwise, under ``jit`` too:
the shape is static).  A NaN or infinite entry raises ``ValueError`` when ``x`` is concrete; inside
``jit``/``vmap`` :func:`evaluate` returns NaN for it (it no longer falls back to "no rule fired").
"""

from __future__ import annotations

from typing import Any, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control.fuzzy.defuzzify import DEFUZZIFIERS, IMPLICATIONS, centroid_clipped_unimodal, implied_set
from jaxsim.control.fuzzy.membership import Terms
from jaxsim.control.fuzzy.membership import terms as make_terms
from jaxsim.control.fuzzy.norms import check_snorm, check_tnorm, snorm_reduce, tnorm_reduce
from jaxsim.control.fuzzy.rules import RuleBase
from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.validation import check_finite, check_shape, is_concrete

UNIMODAL_KINDS = ("triangular", "trapezoidal", "gaussian", "bell", "sigmoid")


@pytree_dataclass
class MamdaniOutput:
    """Output terms sampled on ``grid`` ``(N,)``; ``implication`` "min" (Mamdani) or "product" (Larsen)."""

    grid: Any
    terms: Terms
    implication: str = static_field(default="min")
    defuzzifier: str = static_field(default="centroid")

    @property
    def n_outputs(self) -> int:
        return self.terms.n_terms


@pytree_dataclass
class SugenoOutput:
    """Output functions: ``coefficients`` ``(M, 1)`` constants, or ``(M, n + 1)`` rows ``[c_0, c_1..c_n]``."""

    coefficients: Any

    @property
    def n_outputs(self) -> int:
        return int(jnp.shape(self.coefficients)[0])


@pytree_dataclass
class TsukamotoOutput:
    """Monotone output terms (strictly monotone ``piecewise_linear`` or ``sigmoid``)."""

    terms: Terms

    @property
    def n_outputs(self) -> int:
        return self.terms.n_terms


@pytree_dataclass
class FuzzySystem:
    """A fuzzy inference system (build it with :func:`mamdani`, :func:`larsen`, :func:`sugeno`, :func:`tsukamoto`)."""

    inputs: tuple
    output: Any
    weights: Any
    rules: RuleBase = static_field()
    and_norm: str = static_field(default="min")
    or_norm: str = static_field(default="max")
    accumulation: str = static_field(default="max")

    @property
    def n_inputs(self) -> int:
        return len(self.inputs)

    def __call__(self, e: Any) -> jax.Array:
        """Single-input systems only: the static characteristic ``u(e)``, element-wise over ``e``."""
        if self.n_inputs != 1:
            raise ValueError(f"e: calling a system element-wise needs 1 input, this one has {self.n_inputs}")
        e = jnp.asarray(e)
        flat = jax.vmap(lambda v: evaluate(self, v[None]))(e.reshape(-1))
        return flat.reshape(e.shape)


def firing_strengths(fis: FuzzySystem, x: Any) -> jax.Array:
    """Rule strengths ``w`` ``(R,)`` for the input ``x`` ``(n,)`` (weights included)."""
    x = jnp.asarray(x)
    check_shape("x", x, (fis.n_inputs,))
    ant = fis.rules.antecedent_array()
    used = ant >= 0  # static: inputs a rule does not test are skipped
    mu_r = jnp.stack([var(x[i])[np.maximum(ant[:, i], 0)] for i, var in enumerate(fis.inputs)], axis=1)
    if fis.rules.connective == "and":
        strength = tnorm_reduce(fis.and_norm, jnp.where(used, mu_r, 1.0), axis=1)
    else:
        strength = snorm_reduce(fis.or_norm, jnp.where(used, mu_r, 0.0), axis=1)
    return jnp.asarray(fis.weights) * strength


def _weighted_mean(w: jax.Array, z: jax.Array) -> jax.Array:
    den = jnp.sum(w)
    ok = den > 0
    return jnp.where(ok, jnp.sum(w * z) / jnp.where(ok, den, 1.0), 0.0)


def term_activations(fis: FuzzySystem, w: jax.Array) -> jax.Array:
    """Accumulate rule strengths ``w`` ``(R,)`` into output-term activations ``α`` ``(T,)``."""
    cons = fis.rules.consequent_array()
    groups = [np.flatnonzero(cons == t) for t in range(fis.output.n_outputs)]  # static
    return jnp.stack([snorm_reduce(fis.accumulation, w[g]) for g in groups])


def output_set(fis: FuzzySystem, x: Any) -> tuple[jax.Array, jax.Array]:
    """Mamdani/Larsen: the implied and aggregated output set as points ``(xs, mu)``."""
    out = fis.output
    if not isinstance(out, MamdaniOutput):
        raise ValueError("fis: output_set needs a Mamdani or Larsen system")
    alpha = term_activations(fis, firing_strengths(fis, x))
    grid = jnp.asarray(out.grid)
    term_mf = out.terms(grid).T  # (T, N)
    return implied_set(out.implication, grid, term_mf, alpha, unimodal=out.terms.kind in UNIMODAL_KINDS)


def _tsukamoto_inverse(t: Terms, cons: np.ndarray, w: jax.Array) -> jax.Array:
    p = jnp.asarray(t.params)[cons]  # (R, P)
    if t.kind == "sigmoid":
        center, slope = p[:, 0], p[:, 1]
        eps = jnp.finfo(w.dtype).eps
        wc = jnp.clip(w, eps, 1.0 - eps)
        return center + (jnp.log(wc) - jnp.log1p(-wc)) / slope
    k = p.shape[1] // 2
    xs, ys = p[:, :k], p[:, k:]
    increasing = ys[:, -1] > ys[:, 0]
    up = jax.vmap(jnp.interp)(w, ys, xs)
    down = jax.vmap(jnp.interp)(w, ys[:, ::-1], xs[:, ::-1])
    return jnp.where(increasing, up, down)


def evaluate(fis: FuzzySystem, x: Any) -> jax.Array:
    """Crisp output (scalar) of ``fis`` for the input vector ``x`` ``(n,)``.

    Raises ``ValueError`` naming ``x`` for a shape other than ``(n,)``, or (concrete ``x``) a NaN or
    infinite entry.  Traced (``jit``/``vmap``): a non-finite entry gives a NaN output.
    """
    x = jnp.asarray(x)
    check_shape("x", x, (fis.n_inputs,))
    check_finite("x", x)
    return _evaluate(fis, x)


@jax.jit
def _evaluate(fis: FuzzySystem, x: jax.Array) -> jax.Array:
    # one compiled program per system structure (run eagerly: ~130 single-operation compilations, 2.5 s)
    return jnp.where(jnp.all(jnp.isfinite(x)), _crisp_output(fis, x), jnp.nan)


def _crisp_output(fis: FuzzySystem, x: jax.Array) -> jax.Array:
    out = fis.output
    if isinstance(out, MamdaniOutput):
        if out.defuzzifier == "centroid" and out.implication == "min" and out.terms.kind in UNIMODAL_KINDS:
            alpha = term_activations(fis, firing_strengths(fis, x))
            grid = jnp.asarray(out.grid)
            return centroid_clipped_unimodal(grid, out.terms(grid).T, alpha)  # same value, faster
        xs, mu = output_set(fis, x)
        return DEFUZZIFIERS[out.defuzzifier](xs, mu)
    w = firing_strengths(fis, x)
    cons = fis.rules.consequent_array()
    if isinstance(out, SugenoOutput):
        c = jnp.asarray(out.coefficients)
        z = c[:, 0] + (c[:, 1:] @ x if c.shape[1] > 1 else 0.0)  # (M,)
        return _weighted_mean(w, z[cons])
    if isinstance(out, TsukamotoOutput):
        return _weighted_mean(w, _tsukamoto_inverse(out.terms, cons, w))
    raise ValueError(f"fis: unknown output type {type(out).__name__}")


def evaluate_batch(fis: FuzzySystem, xs: Any, batch_size: int = 1024) -> jax.Array:
    """``evaluate`` over a batch ``xs`` ``(B, n)`` → ``(B,)``: ``vmap`` over chunks of ``batch_size``.

    Same values as ``jax.vmap(evaluate, in_axes=(None, 0))``; chunking keeps the per-chunk
    intermediates (terms × grid per input) in cache, several times faster for large ``B`` on CPU.
    """
    return jax.lax.map(lambda x: evaluate(fis, x), jnp.asarray(xs), batch_size=batch_size)


# --------------------------------------------------------------------------------------------
# Constructors (the public boundary: every argument is checked here, not on pytree unflatten).


def _as_terms(name: str, t: Any) -> Terms:
    if isinstance(t, Terms):
        return make_terms(t.kind, t.params)
    if isinstance(t, tuple) and len(t) == 2 and isinstance(t[0], str):
        return make_terms(t[0], t[1])
    raise ValueError(f"{name}: expected Terms or a (kind, params) pair, got {type(t).__name__}")


def _build(
    inputs: Sequence[Any], output: Any, rules: RuleBase, weights: Any, and_norm: str, or_norm: str, accumulation: str
) -> FuzzySystem:
    if not isinstance(rules, RuleBase):
        raise ValueError(f"rules: expected a RuleBase (see fuzzy.rule_base), got {type(rules).__name__}")
    if len(inputs) == 0:
        raise ValueError("inputs: need at least one input variable")
    ins = tuple(_as_terms(f"inputs[{i}]", t) for i, t in enumerate(inputs))
    check_tnorm("and_norm", and_norm)
    check_snorm("or_norm", or_norm)
    check_snorm("accumulation", accumulation)
    rules.check_ranges([t.n_terms for t in ins], output.n_outputs)
    w = jnp.ones(rules.n_rules) if weights is None else jnp.asarray(weights, float)
    if w.shape != (rules.n_rules,):
        raise ValueError(f"weights: expected shape ({rules.n_rules},), got {w.shape}")
    check_finite("weights", w)
    if is_concrete(w) and np.any((np.asarray(w) < 0) | (np.asarray(w) > 1)):  # NumPy: safe inside jit
        raise ValueError(f"weights: rule weights must lie in [0, 1], got {np.asarray(w).tolist()}")
    return FuzzySystem(ins, output, w, rules, and_norm, or_norm, accumulation)


def mamdani(
    inputs: Sequence[Any],
    output_grid: Any,
    output_terms: Any,
    rules: RuleBase,
    *,
    implication: str = "min",
    defuzzifier: str = "centroid",
    weights: Any = None,
    and_norm: str = "min",
    or_norm: str = "max",
    accumulation: str = "max",
) -> FuzzySystem:
    """A Mamdani system (``implication="product"`` gives Larsen's).

    Args:
        inputs: one :class:`Terms` (or ``(kind, params)``) per input.
        output_grid: ``(N,)`` increasing grid of the output universe (N ≥ 2).
        output_terms: output terms (``Terms`` or ``(kind, params)``), sampled on the grid.
        rules: the :class:`~.rules.RuleBase`.
        implication: "min" or "product".
        defuzzifier: "centroid", "bisector", "mom", "som" or "lom".
        weights: ``(R,)`` rule weights in [0, 1] (default 1).
        and_norm, or_norm: t-norm / s-norm joining a rule's tests; accumulation: s-norm combining
            the rules that fire the same output term.
    """
    if implication not in IMPLICATIONS:
        raise ValueError(f"implication: must be one of {sorted(IMPLICATIONS)}, got {implication!r}")
    if defuzzifier not in DEFUZZIFIERS:
        raise ValueError(f"defuzzifier: must be one of {sorted(DEFUZZIFIERS)}, got {defuzzifier!r}")
    grid = jnp.asarray(output_grid, float)
    if grid.ndim != 1 or grid.shape[0] < 2:
        raise ValueError(f"output_grid: expected shape (N,) with N ≥ 2, got {grid.shape}")
    check_finite("output_grid", grid)
    if is_concrete(grid) and np.any(np.diff(np.asarray(grid)) <= 0):
        raise ValueError("output_grid: must be strictly increasing")
    out = MamdaniOutput(grid, _as_terms("output_terms", output_terms), implication, defuzzifier)
    return _build(inputs, out, rules, weights, and_norm, or_norm, accumulation)


def larsen(inputs: Sequence[Any], output_grid: Any, output_terms: Any, rules: RuleBase, **kwargs: Any) -> FuzzySystem:
    """A Larsen system: :func:`mamdani` with product implication."""
    return mamdani(inputs, output_grid, output_terms, rules, implication="product", **kwargs)


def sugeno(
    inputs: Sequence[Any],
    coefficients: Any,
    rules: RuleBase,
    *,
    weights: Any = None,
    and_norm: str = "min",
    or_norm: str = "max",
) -> FuzzySystem:
    """A Sugeno system: ``coefficients`` ``(M,)``/``(M, 1)`` (zero order) or ``(M, n + 1)`` (first order)."""
    c = jnp.asarray(coefficients, float)
    c = c[:, None] if c.ndim == 1 else c
    n = len(inputs)
    if c.ndim != 2 or c.shape[1] not in (1, n + 1) or c.shape[0] < 1:
        raise ValueError(f"coefficients: expected shape (M,), (M, 1) or (M, {n + 1}), got {jnp.shape(coefficients)}")
    check_finite("coefficients", c)
    return _build(inputs, SugenoOutput(c), rules, weights, and_norm, or_norm, "max")


def tsukamoto(
    inputs: Sequence[Any],
    output_terms: Any,
    rules: RuleBase,
    *,
    weights: Any = None,
    and_norm: str = "min",
    or_norm: str = "max",
) -> FuzzySystem:
    """A Tsukamoto system with strictly monotone output terms (``piecewise_linear`` or ``sigmoid``)."""
    t = _as_terms("output_terms", output_terms)
    if t.kind not in ("piecewise_linear", "sigmoid"):
        raise ValueError(f"output_terms: Tsukamoto needs monotone terms (piecewise_linear or sigmoid), got {t.kind!r}")
    if is_concrete(t.params):
        p = np.asarray(t.params)
        if t.kind == "sigmoid" and np.any(p[:, 1] == 0):
            raise ValueError("output_terms: a sigmoid with slope 0 is not invertible")
        if t.kind == "piecewise_linear":
            ys = p[:, p.shape[1] // 2 :]
            d = np.diff(ys, axis=1)
            if not np.all((d > 0).all(axis=1) | (d < 0).all(axis=1)):
                raise ValueError("output_terms: Tsukamoto terms must be strictly monotone (y strictly up or down)")
    return _build(inputs, TsukamotoOutput(t), rules, weights, and_norm, or_norm, "max")
