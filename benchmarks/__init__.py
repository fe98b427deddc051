"""Benchmarks of ngtmc: speed against error of Simulation options on the named studies.

``python -m benchmarks.run`` (any study), ``python -m benchmarks.tpb`` (three_point_bending);
reusable pieces in :mod:`benchmarks.harness`; ``benchmarks/bench_solver.py`` times the solver's
per-iteration costs. See docs/performance.md.
"""
