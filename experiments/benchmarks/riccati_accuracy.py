"""SciPy's CAREX/DAREX benchmark cases: our residual against SciPy's own accuracy targets.

    python -m experiments.benchmarks.riccati_accuracy [--skip-large]

For every real case of SciPy's Riccati test suite (the CAREX/DAREX collections of Benner, Laub &
Mehrmann, data in ``tests/control/riccati_benchmarks.py``; run from the repository root) prints the
decimals to which the residual matrix vanishes — ``−log10 max|Res_ij|`` with ``Res`` formed as
SciPy's tests form it — for our solution and for SciPy's, beside SciPy's target (its
``min_decimal`` / ``max_tol``; "—" where SciPy marks the case a known failure and we are held to
SciPy's own residual instead).  Also prints whether the closed loop is marginal.  Not a timing
benchmark: accuracy only.
"""

from __future__ import annotations

import argparse
import math
import warnings

import numpy as np
import scipy.linalg as sl

import jaxsim  # noqa: F401  (float64)
from jaxsim.control.riccati import (
    MarginalStabilityWarning,
    riccati_diagnostics,
    solve_continuous_are,
    solve_discrete_are,
)


def _decimals(res: np.ndarray) -> float:
    worst = float(np.max(np.abs(res)))
    return math.inf if worst == 0 else -math.log10(worst)


def rows(skip_large: bool = False) -> list[dict]:
    from tests.control.riccati_benchmarks import SCIPY_ATOL, carex, darex
    from tests.control.riccati_oracle import scipy_care_residual, scipy_dare_residual

    out = []
    for discrete, cases in ((False, carex()), (True, darex())):
        ours_fn, ref_fn = (
            (solve_discrete_are, sl.solve_discrete_are) if discrete else (solve_continuous_are, sl.solve_continuous_are)
        )
        residual = scipy_dare_residual if discrete else scipy_care_residual
        for name, (a, b, q, r) in cases.items():
            if skip_large and a.shape[0] > 200:
                continue
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", MarginalStabilityWarning)
                x = np.asarray(ours_fn(a, b, q, r))
            ours = _decimals(residual(x, a, b, q, r))
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", sl.LinAlgWarning)
                    theirs = _decimals(residual(ref_fn(a, b, q, r), a, b, q, r))
            except np.linalg.LinAlgError:
                theirs = float("nan")  # SciPy finds no solution
            target = SCIPY_ATOL[name]
            target_dec = None if target is None else -math.log10(target / 1.5)
            ok = (
                (ours >= target_dec - 1e-9)
                if target_dec is not None
                else (not ours < theirs if not math.isnan(theirs) else math.isfinite(ours))
            )
            marginal = bool(riccati_diagnostics(x, a, b, q, r, discrete=discrete).marginal)
            out.append(
                dict(case=name, n=a.shape[0], target=target_dec, ours=ours, scipy=theirs, met=ok, marginal=marginal)
            )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--skip-large", action="store_true", help="skip CAREX 20 (n = 421, slow)")
    args = parser.parse_args()
    fmt = lambda v: "—" if v is None else ("inf" if math.isinf(v) else ("fails" if math.isnan(v) else f"{v:.1f}"))  # noqa: E731
    print(f"{'case':9s} {'n':>4s} {'SciPy target':>12s} {'ours':>6s} {'SciPy':>6s}  met  marginal")
    table = rows(args.skip_large)
    for row in table:
        print(
            f"{row['case']:9s} {row['n']:4d} {fmt(row['target']):>12s} {fmt(row['ours']):>6s} "
            f"{fmt(row['scipy']):>6s}  {'yes' if row['met'] else 'NO ':3s}  {'yes' if row['marginal'] else ''}"
        )
    print(
        f"{sum(r['met'] for r in table)} of {len(table)} cases meet SciPy's target "
        "(decimals: −log10 of the largest residual entry)"
    )


if __name__ == "__main__":
    main()
