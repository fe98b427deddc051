"""
Crack only: a notched bar in tension
====================================

A bar of 2 x 0.5 mm with an edge notch at mid-length (0.1 mm deep) is pulled along its axis. No
void, no contact: only the AT-2 phase field, allowed in a band around the notch
(``fracture_regions``), where the mesh is fine enough to resolve the length scale l0. The force
rises linearly, the crack starts at the notch tip and runs through the ligament: the force
drops to zero. Units: mm, N, MPa; plane strain, forces per mm of thickness.
"""
import os

import ngsolve as ngs
from netgen.occ import Glue, MoveTo, OCCGeometry, Rectangle, X, Y

import ngtmc

SHORT = os.environ.get("NGTMC_EXAMPLE_SHORT") == "1"
l0 = 0.05                                                # mm, the phase field's length scale
h_band = l0 / 2 if SHORT else l0 / 4                     # mm, element size in the band

# %%
# The bar with its notch (a slit 0.01 mm wide), and a band of 0.2 mm around it that may crack.
bar = Rectangle(2.0, 0.5).Face() - MoveTo(0.995, -0.01).Rectangle(0.01, 0.11).Face()
band = MoveTo(0.9, 0.0).Rectangle(0.2, 0.5).Face()
ligament, rest = bar * band, bar - band
ligament.faces.name, rest.faces.name = "band", "bar"
ligament.faces.maxh = h_band
shape = Glue([rest, ligament])
shape.edges.Min(X).name = "left"
shape.edges.Max(X).name = "right"
shape.vertices.Min(X + Y).name = "corner"                # the bottom left corner
mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.2))
print(mesh.ne, "elements")

scene = ngtmc.Scene(mesh, {".*": ngtmc.Material(E=210e3, nu=0.3, Gc=2.7, l0=l0)},   # MPa, -, N/mm, mm
                    supports=[ngtmc.Support("left", x=True), ngtmc.Support(ngtmc.Point("corner"), y=True)],
                    load=ngtmc.DisplacementLoad("right", "x"),
                    fracture_regions="band")

# %%
# Pull the right end by 0.012 mm; the step control shortens the steps while the crack grows.
control = ngtmc.AdaptiveStepControl(du_max=1e-3 if SHORT else 5e-4, k_u=100.0, du_min=1e-7)   # mm, 1/N, mm
result = ngtmc.simulate(scene, 0.012, control)
history = result.history
print(history[["load", "force", "max_alpha"]].iloc[::4].to_string(index=False))

# %%
# The key number: the peak force. After it the bar is broken (max alpha = 1, force ~ 0).
print(f"peak force {result.peak_force:.1f} N/mm at {result.peak_load:.5f} mm; "
      f"final force {history['force'].iloc[-1]:.2f} N/mm, {len(history) - 1} steps")
