"""Test-suite ordering for the two xdist workers of ``pytest -n 2 --dist loadfile``.

xdist hands out whole test files. By default it orders them by their number of tests, so the few
files whose module fixture runs a study at quick resolution (one test function each, minutes of
solving) came last and ran one after the other at the end: CI took 1026 s on 2026-12-02 with
those four files at 346, 277, 190 and 188 s. Here the files with the most solving go first, in
the order of their measured cost (CI durations of 2026-12-02, setup and calls), so that the two
workers start with them and the many short files fill in behind; ``--no-loadscope-reorder`` in
``pyproject.toml`` keeps this order. The order changes no result, only the wall time.
"""
from __future__ import annotations

#: test files by measured cost, largest first (s, setup and calls, CI on 2026-12-03 unless stated)
COSTLY_FIRST = (
    "test_tpb_fidelity.py",                  # 422 with three variant runs, about 340 with two
    "test_tpb_miehe.py",                     # 258
    "test_study_l_panel.py",                 # 140 + ...
    "test_study_three_point_bending.py",     # 110 + ...
    "test_study_step_control.py",            # 74 + ...
    "test_study_three_point_bending_3d.py",  # 34 + 23 + ...
    "test_monolithic.py",
    "test_sensitivities.py",
    "test_report_3d.py",
    "test_adapt.py",
    "test_mpi.py",
    "test_study_contact_gamma0.py",
)


def pytest_collection_modifyitems(session, config, items):
    rank = {name: i for i, name in enumerate(COSTLY_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(COSTLY_FIRST)))  # stable: file order kept otherwise
