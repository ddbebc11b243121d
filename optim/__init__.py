"""Tuning layer: reparametrisations, gradient tuner, particle-swarm baseline, comparison harness."""
