"""Tuning and robustness problems at library level (layer above plants, control and estimation;
below optim, montecarlo, envs and the studies): :mod:`~.trms` — the TRMS tracking problem."""
