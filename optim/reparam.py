"""Re-export of :mod:`jaxsim.problem.reparam` (the reparametrisations moved down to the Problem layer;
``from optim.reparam import Interval`` and ``from optim import Positive`` keep working)."""

from jaxsim.problem.reparam import (  # noqa: F401
    Identity,
    Interval,
    LogInterval,
    Positive,
    Reparam,
    Simplex,
    SortedBreakpoints,
    SPDMatrix,
    apply,
    check_bounds,
    check_domain,
    check_inside,
    invert,
    softplus_inverse,
)
