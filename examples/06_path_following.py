"""
Path following through a snap-back
==================================

The notched bar of the previous example, solved with ``scheme="path-following"``: the monolithic
Newton on the displacement and the phase field together, with the load itself an unknown while
the crack grows. Each such step prescribes the energy the crack dissipates (about Gc l0 per
step) instead of the load. When the crack runs unstably, the equilibrium path turns back: the
load *decreases* while the force drops (a snap-back), which load control cannot follow (it jumps
down at one load, see the previous example). Units: mm, N, MPa; forces per mm of thickness.
"""
import os

import numpy as np
import ngsolve as ngs
from netgen.occ import Glue, MoveTo, OCCGeometry, Rectangle, X, Y

import ngtmc

SHORT = os.environ.get("NGTMC_EXAMPLE_SHORT") == "1"
l0 = 0.1                                                 # mm
h_band = l0 / 2 if SHORT else l0 / 4                     # mm

bar = Rectangle(2.0, 0.5).Face() - MoveTo(0.995, -0.01).Rectangle(0.01, 0.11).Face()
band = MoveTo(0.9, 0.0).Rectangle(0.2, 0.5).Face()
ligament, rest = bar * band, bar - band
ligament.faces.name, rest.faces.name = "band", "bar"
ligament.faces.maxh = h_band
shape = Glue([rest, ligament])
shape.edges.Min(X).name = "left"
shape.edges.Max(X).name = "right"
shape.vertices.Min(X + Y).name = "corner"
mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.2))
scene = ngtmc.Scene(mesh, {".*": ngtmc.Material(E=210e3, nu=0.3, Gc=2.7, l0=l0)},   # MPa, -, N/mm, mm
                    supports=[ngtmc.Support("left", x=True), ngtmc.Support(ngtmc.Point("corner"), y=True)],
                    load=ngtmc.DisplacementLoad("right", "x"),
                    fracture_regions="band")

# %%
# The same load path to 0.012 mm, now with path following. On a mesh this small a direct solver
# (UMFPACK) is the fastest for the coupled systems; the default block solver pays off on large ones.
control = ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=100.0, du_min=1e-7)        # mm, 1/N, mm
result = ngtmc.simulate(scene, 0.012, control, scheme="path-following",
                        coupled={"linear_solver": "umfpack"}, newton=ngtmc.NewtonOptions(linear_solver="umfpack"))
history = result.history
print(history[["load", "force", "max_alpha", "newton_iterations"]].to_string(index=False))

# %%
# Where the load went back: the accepted steps with a smaller load than the step before.
back = np.diff(history["load"].to_numpy()) < 0
print(f"{len(history) - 1} steps, {back.sum()} of them with the load going back (the snap-back)")
print(f"peak force {result.peak_force:.1f} N/mm at {result.peak_load:.5f} mm")
