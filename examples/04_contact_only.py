"""
Contact only: two blocks close a gap
====================================

Two blocks of 1 x 0.4 mm are separated by a 0.05 mm layer of third medium (``density`` 0). The
lower block is clamped at its bottom, the upper one pushed down on its top edge. While the gap
is open the force is that of the very soft void alone (gamma0 = 1e-5 of the solid's stiffness);
once the void is squeezed shut it stiffens and the blocks press on each other: the force rises
steeply. Nothing may break (no ``fracture_regions``). Units: mm, N, MPa, forces per mm of
thickness.
"""
import os

import ngsolve as ngs
from netgen.occ import Glue, MoveTo, OCCGeometry, Rectangle, Y

import ngtmc

SHORT = os.environ.get("NGTMC_EXAMPLE_SHORT") == "1"
gap = 0.05                                               # mm

# %%
# Lower block, void layer, upper block; the void gets finer elements.
lower = Rectangle(1.0, 0.4).Face()
lower.faces.name = "lower"
void = MoveTo(0.0, 0.4).Rectangle(1.0, gap).Face()
void.faces.name, void.faces.maxh = "void", 0.04 if SHORT else 0.02
upper = MoveTo(0.0, 0.4 + gap).Rectangle(1.0, 0.4).Face()
upper.faces.name = "upper"
shape = Glue([lower, void, upper])
shape.edges.Min(Y).name = "bottom"
shape.edges.Max(Y).name = "top"
mesh = ngs.Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.1 if SHORT else 0.05))

scene = ngtmc.Scene(mesh, {".*": ngtmc.Material(E=1000.0, nu=0.3)},          # MPa, -
                    supports=[ngtmc.Support("bottom", x=True, y=True)],
                    load=ngtmc.DisplacementLoad("top", "-y", hold_tangential=True),
                    density={"void": 0.0}, gamma0=1e-5,
                    regulariser=ngtmc.Regulariser("void", length=1.0, kbar_r=1e-6))

# %%
# Push the top down by 0.06 mm: more than the gap.
control = ngtmc.AdaptiveStepControl(du_max=0.005, du_min=1e-6)              # mm
history = ngtmc.simulate(scene, 0.06, control).history
print(history[["load", "force", "min_J", "newton_iterations"]].to_string(index=False))

# %%
# The force before contact (load half the gap) against the force at the end.
open_force = float(history.loc[(history["load"] - gap / 2).abs().idxmin(), "force"])
final_force = float(history["force"].iloc[-1])
print(f"force with the gap half closed {open_force:.4f} N/mm; at 0.06 mm {final_force:.3f} N/mm")
