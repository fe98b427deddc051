"""A study file (docs/study-interface.md) of the MPI test scene of ``benchmarks/mpi_scene.py``: a
punch pushed through a 0.05 mm third-medium gap onto a block that cracks from the punch's
corners. ``tests/test_mpi.py`` runs it with ``ngtmc run`` serially and on 3 MPI ranks and compares
the run folders' histories:

    ngtmc run benchmarks/mpi_study.py -o OUT
    mpiexec -n 3 python -m mpi4py -m ngtmc run benchmarks/mpi_study.py --mpi -o OUT_MPI

The default is the paper's single-pass scheme, which goes through the peak and the crack; with
``--set scheme=path-following`` (the coupled Newton with dissipation control) the tests stop at
``--set final_load=0.053`` mm, where the damage grows before the peak: further on, path following
passes the snap-back of the crack and fails at 0.0551 mm, 98.5 % of the load path, where the punch
squeezes the block's broken elements (min J 6.4e-11; docs/performance.md, "Known limit").

Units: mm, N, MPa; forces per mm of thickness.
"""
from __future__ import annotations

import sys
from pathlib import Path

import ngtmc
from ngtmc.study import Case
from ngtmc.study import SOLVER_PARAMETERS, simulation_options

sys.path.insert(0, str(Path(__file__).resolve().parent))
import mpi_scene  # noqa: E402

NAME = "mpi_block"
TITLE = "Punch through a third-medium gap onto a block that cracks (MPI test scene)"
SUMMARY = ("A 0.4 x 0.4 mm punch is pushed down through a 0.05 mm void onto a 1 x 0.4 mm block clamped at "
           "its bottom: the void is squeezed, the force peaks at about 3.1 N/mm near 0.055 mm, and a crack cuts "
           "the block from the punch's corners. The scene of the MPI tests (benchmarks/mpi_scene.py).")
PARAMETERS = {
    "final_load": (0.056, "mm", "imposed displacement of the punch's top at the end (past the peak and the crack)"),
    **SOLVER_PARAMETERS,
}
RESOLUTIONS = {"quick": {"du_max": 0.004}, "medium": {"du_max": 0.002}, "paper": {"du_max": 0.001}}
RESOLUTION_PARAMETERS = {"du_max": ("mm", "largest load increment of Eq. 20")}
DEFAULT_RESOLUTION = "quick"
EXPECTED: dict = {}


def cases(p: dict) -> list[Case]:
    return [Case(name="main", label="punch onto a cracking block", scene=mpi_scene.scene,
                 schedule=ngtmc.Schedule.monotonic(float(p["final_load"])),
                 control=ngtmc.AdaptiveStepControl(du_max=float(p["du_max"]), du_min=1e-7),
                 options=simulation_options(p))]


def references(p: dict) -> list[dict]:
    return []


def targets(p: dict) -> list[dict]:
    return []
