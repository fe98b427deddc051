"""
A scene of your own: contact, then a crack
==========================================

The scene of the README: a notched beam (2 x 0.4 mm) on end supports is pushed down by a block
through a 0.05 mm layer of third medium ("void"). The void closes, contact carries the load into
the beam, and a crack grows from the notch. This is the README's mesh and load path; the short
mode (``NGTMC_EXAMPLE_SHORT=1``, the tests) takes a coarser mesh and stops just past the peak.
Units: mm, N, MPa; 2D plane strain, forces per mm of thickness.
"""
import os

import ngsolve as ngs
from netgen.occ import Glue, MoveTo, OCCGeometry, Rectangle, X, Y

import ngtmc

SHORT = os.environ.get("NGTMC_EXAMPLE_SHORT") == "1"   # the test suite's short mode
h_ligament = 0.04 if SHORT else 0.02                    # mm, element size where the crack grows

# %%
# Geometry (mm): the ligament above the notch is the only region that may crack; the void layer
# between the beam and the pusher is the third medium.
beam = Rectangle(2.0, 0.4).Face() - MoveTo(0.99, 0.0).Rectangle(0.02, 0.1).Face()
band = MoveTo(0.9, 0.0).Rectangle(0.2, 0.3).Face()
ligament, beam = beam * band, beam - band
ligament.faces.name, beam.faces.name = "ligament", "beam"
ligament.faces.maxh = h_ligament
void = MoveTo(0.0, 0.4).Rectangle(2.0, 0.05).Face()
void.faces.name, void.faces.maxh = "void", 0.025 if not SHORT else 0.05
pusher = MoveTo(0.85, 0.45).Rectangle(0.3, 0.15).Face()
pusher.faces.name = "pusher"
shape = Glue([beam, ligament, void, pusher])
shape.edges.Max(Y).name = "top"
shape.edges.Min(X).name = "left"
shape.edges.Max(X).name = "right"
mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.08 if not SHORT else 0.12))
print(mesh.ne, "elements")

# %%
# The scene: one material everywhere, density 0 in the void, the pusher's top edge moved down.
scene = ngtmc.Scene(
    mesh,
    materials={".*": ngtmc.Material(E=20.8e3, nu=0.3, Gc=0.54, l0=0.04)},  # MPa, -, N/mm, mm
    density={"void": 0.0},                                                 # the third medium
    supports=[ngtmc.Support("left", x=True, y=True), ngtmc.Support("right", y=True)],
    load=ngtmc.DisplacementLoad("top", direction="-y", hold_tangential=True),
    fracture_regions="ligament",
    regulariser=ngtmc.Regulariser("void", length=2.0, kbar_r=1e-6),
    gamma0=1e-4,
    thickness=1.0,                                                         # mm
)

# %%
# Load it to 0.075 mm (short mode: 0.069 mm, just past the peak) with the adaptive step control:
# steps of at most du_max (mm), shortened where the crack dissipates energy (k_u, 1/N).
control = ngtmc.AdaptiveStepControl(du_max=2.5e-3 if not SHORT else 5e-3, k_u=1000.0, du_min=1e-8)
result = ngtmc.simulate(scene, ngtmc.Schedule([0.0, 0.069 if SHORT else 0.075]), control)
history = result.history          # one row per accepted step: load (mm), force (N/mm), ...
print(history[["load", "force", "max_alpha", "newton_iterations"]].iloc[::5].to_string(index=False))

# %%
# The key number: the peak force, reached as the crack starts to run.
print(f"peak force {result.peak_force:.3f} {result.units['force']} at {result.peak_load:.4f} mm")
