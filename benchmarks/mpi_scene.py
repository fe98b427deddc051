"""The contact-and-fracture scene of ``tests/test_mpi.py`` and ``benchmarks/mpi.py``, run serially
or on MPI ranks.

A block (region "upper", 0.4 x 0.4 mm) is pushed down through a third-medium gap of 0.05 mm onto
a wider block (region "lower", 1 x 0.4 mm, clamped at the bottom) that may break: the void is
squeezed under the punch, then the lower block cracks from the punch's corners. Units: mm, N, MPa.

Under MPI (``mpiexec -n 3 python -m mpi4py benchmarks/mpi_scene.py OUT.json``; ``-m mpi4py`` aborts
every rank when one raises, instead of leaving the others waiting): every rank builds the scene,
:func:`ngtmc.scene.distributed.distribute` spreads it, and rank 0 writes OUT.json with the history and
the rank-local numbers that the NGSolve traps of :mod:`ngtmc.scene.distributed` are about.
"""
from __future__ import annotations

import json
import sys
import time

import ngsolve as ngs
from netgen.occ import Glue, MoveTo, OCCGeometry, Rectangle, Y

import ngtmc

#: final imposed displacement of the punch, mm, and the steps taken towards it: the step to 0.056 mm
#: fails and is cut back, the peak (about 3.1 N) comes at 0.055 mm, the crack then cuts the block in
#: steps of 1.6e-5 to 3.1e-5 mm (the force down to about 0.02 N at step 24)
LOAD = 0.056
STEPS = 24


def scene() -> ngtmc.Scene:
    low = Rectangle(1.0, 0.4).Face()
    low.faces.name = "lower"
    void = MoveTo(0, 0.4).Rectangle(1.0, 0.05).Face()
    void.faces.name = "void"
    void.faces.maxh = 0.025
    up = MoveTo(0.3, 0.45).Rectangle(0.4, 0.4).Face()
    up.faces.name = "upper"
    shape = Glue([low, void, up])
    shape.edges.Min(Y).name = "bottom"
    shape.edges.Max(Y).name = "top"
    mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.05))
    return ngtmc.Scene(mesh, {"lower": ngtmc.Material(1000.0, 0.3, 0.004, 0.05),
                              "void|upper": ngtmc.Material(1000.0, 0.3)},
                       supports=[ngtmc.Support("bottom", x=True, y=True)],
                       load=ngtmc.DisplacementLoad("top", "-y", hold_tangential=True),
                       density={"void": 0.0}, gamma0=1e-5, fracture_regions="lower",
                       regulariser=ngtmc.Regulariser("void", length=1.0, kbar_r=1e-6),
                       variable_order=True)   # order 2 in the void only: the histories of its tests were measured so


def run(sc: ngtmc.Scene) -> ngtmc.Simulation:
    """STEPS steps of the paper's single-pass scheme with Eq. 20's step control (du_max 0.004 mm)."""
    sim = ngtmc.Simulation(sc, LOAD, ngtmc.AdaptiveStepControl(du_max=0.004, du_min=1e-7))
    for row in sim.steps():
        if row["step"] >= STEPS:
            break
    return sim


def main(out: str):
    import warnings
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    warnings.simplefilter("ignore", ngtmc.ResolutionWarning)
    sc = ngtmc.scene.distributed.distribute(scene(), comm)
    t0 = time.perf_counter()
    sim = run(sc)
    wall = time.perf_counter() - t0
    s = sim.solver
    # the traps, measured on the final state: rank-local numbers gathered on rank 0
    form_energy = s.a_u.Energy(s.u.vec)       # NGSolve: the rank's part
    cf = ngs.InnerProduct(s.u, s.u)
    integral = ngs.Integrate(cf * ngs.dx, s.mesh)   # NGSolve: the rank's part
    integrate_cf = ngs.Integrate(cf, s.mesh)        # NGSolve: summed over ranks
    local = comm.gather({"elements": s.mesh.ne, "form_energy": form_energy, "integral": integral,
                         "integrate_cf": integrate_cf, "timings_s": dict(s.timings)}, root=0)
    summed_energy = s._energy(s.u.vec)             # ngtmc: summed over ranks (a collective call)
    refused = ""
    try:
        ngtmc.Simulation(sc, LOAD, adapt=ngtmc.Adaptivity(h_crack=0.0125))
    except NotImplementedError as e:
        refused = str(e)
    if comm.rank == 0:
        with open(out, "w") as f:
            json.dump({"ranks": comm.size, "wall_time_s": wall, "history": sim.history.to_dict(orient="list"),
                       "summed_energy": summed_energy, "ranks_local": local, "refused": refused}, f)


if __name__ == "__main__":
    main(sys.argv[1])
