"""A small 3D study file for tests/test_mpi.py: a void layer squeezed between two blocks, the lower one
may crack (it damages a little); snapshots with a section at x = 0.5 mm. Units: mm, N, MPa."""
import ngsolve as ngs
from netgen.occ import Box, Glue, OCCGeometry, Pnt, Z
import ngtmc
from ngtmc.study import Case

NAME = "mpi_block_3d"
TITLE = "Two blocks squeezing a void layer in 3D (MPI test scene)"
SUMMARY = "A 1 x 1 x 0.9 mm stack: lower block, 0.1 mm void, upper block pushed down 0.09 mm."
PARAMETERS = {"final_load": (0.09, "mm", "final load")}
RESOLUTIONS = {"quick": {}}
DEFAULT_RESOLUTION = "quick"
EXPECTED = {}


def scene():
    lower = Box(Pnt(0, 0, 0), Pnt(1, 1, 0.4)); lower.solids.name = "lower"
    void = Box(Pnt(0, 0, 0.4), Pnt(1, 1, 0.5)); void.solids.name = "void"
    upper = Box(Pnt(0, 0, 0.5), Pnt(1, 1, 0.9)); upper.solids.name = "upper"
    shape = Glue([lower, void, upper])
    shape.faces.Min(Z).name = "bottom"
    shape.faces.Max(Z).name = "top"
    mesh = ngs.Mesh(OCCGeometry(shape).GenerateMesh(maxh=0.35))
    return ngtmc.Scene(mesh, {".*": ngtmc.Material(1000.0, 0.3, Gc=0.01, l0=0.3)}, density={"void": 0.0}, gamma0=1e-5,
                       supports=[ngtmc.Support("bottom", x=True, y=True, z=True)],
                       load=ngtmc.DisplacementLoad("top", "-z", hold_tangential=True), fracture_regions="lower")


def cases(p):
    return [Case("main", "two blocks and a void layer", scene=scene, schedule=ngtmc.Schedule.monotonic(float(p["final_load"])),
                 control=ngtmc.AdaptiveStepControl(du_max=0.015, du_min=1e-6), snapshot_loads=[0.045],
                 section=("x", 0.5))]


def references(p):
    return []


def targets(p):
    return []
