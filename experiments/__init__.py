"""Studies reproducing the seed papers' systems, and the ``python -m experiments`` CLI."""
