"""
Refinement along a crack nobody drew
====================================

A square plate (1 x 1 mm) with a slit from its left edge to its centre is sheared: the bottom is
clamped, the top moved to the right. The crack leaves the slit's tip curving down towards the
bottom right corner, so no band of fine elements can be placed along it beforehand. The mesh
starts coarse everywhere; ``adapt=ngtmc.Adaptivity(h_crack=...)`` refines it during the run where
the phase field (or the history of the crack driving force) announces the crack. Units: mm, N,
MPa; plane strain, forces per mm of thickness.
"""
import os

import ngsolve as ngs
from netgen.occ import MoveTo, OCCGeometry, Rectangle, Y

import ngtmc

SHORT = os.environ.get("NGTMC_EXAMPLE_SHORT") == "1"
l0 = 0.1                                                 # mm, the phase field's length scale
maxh = 0.2                                               # mm, the starting mesh: coarser than l0
stop = 0.009 if SHORT else 0.0125                        # mm, short: just past the peak

# %%
# The plate with its slit (0.01 mm wide), one region that may crack everywhere.
plate = Rectangle(1.0, 1.0).Face() - MoveTo(-0.01, 0.495).Rectangle(0.51, 0.01).Face()
plate.faces.name = "plate"
plate.edges.Min(Y).name = "bottom"
plate.edges.Max(Y).name = "top"
mesh = ngs.Mesh(OCCGeometry(plate, dim=2).GenerateMesh(maxh=maxh))
scene = ngtmc.Scene(mesh, {"plate": ngtmc.Material(E=210e3, nu=0.3, Gc=2.7, l0=l0)},   # MPa, -, N/mm, mm
                    supports=[ngtmc.Support("bottom", x=True, y=True)],
                    load=ngtmc.DisplacementLoad("top", "x", hold_tangential=True),
                    fracture_regions="plate")

# %%
# Shear the top by 0.0125 mm (the crack runs to the right edge), refining to elements of l0 / 2
# where the crack is or is about to be.
control = ngtmc.AdaptiveStepControl(du_max=1e-3, k_u=20.0, du_min=1e-7)         # mm, 1/N, mm
result = ngtmc.simulate(scene, stop, control, adapt=ngtmc.Adaptivity(h_crack=l0 / 2))
history = result.history          # gains the columns "elements" and "dofs"
print(history[["load", "force", "max_alpha", "elements"]].iloc[::4].to_string(index=False))

# %%
# The key numbers: the mesh grew only along the crack, and the peak force.
print(f"elements {history['elements'].iloc[0]} -> {result.solver.mesh.ne}")
print(f"peak force {result.peak_force:.1f} N/mm at {result.peak_load:.5f} mm")
