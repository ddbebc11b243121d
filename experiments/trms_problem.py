"""The TRMS tuning problem of the ``trms_lqr_tuning`` study.

Defined in the library, :mod:`jaxsim.problem.trms` (the ``jaxsim_trms`` env uses it too, and the
library never imports a study); re-exported here for the study and its users.
"""

from jaxsim.problem.trms import N_Q, N_R, N_THETA, N_W, PERTURBED, Breakdown, Scenario, TRMSTuning

__all__ = ["N_Q", "N_R", "N_THETA", "N_W", "PERTURBED", "Breakdown", "Scenario", "TRMSTuning"]
