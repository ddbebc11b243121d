"""Side-by-side timings against peer libraries (run as ``python -m experiments.benchmarks.NAME``)."""
