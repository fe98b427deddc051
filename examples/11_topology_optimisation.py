"""
Topology optimisation of a scene of your own
============================================

:class:`ngtmc.design.TopologyOptimisation` optimises the material layout of any scene: name the
regions whose elements are the design variables, the load path, the objective (default: the
external work W over the stroke, N mm, maximised) and the volume bound. The design variables are
smoothed by a Helmholtz filter (radius in mm), sharpened by a Heaviside projection whose
sharpness beta grows stage by stage, penalised by SIMP (rho = xbar^3) and handed to the model as
its pseudo-density; MMA (nlopt, the ``design`` extra) moves them with the exact adjoint gradient.
A forward run that fails is retried with shorter steps; a design that does not run is never
accepted.

Here: a cantilever plate (2 x 1 mm) clamped on its left edge, its right edge moved down by
0.01 mm; half of the plate may be filled. Units: mm, N, MPa; forces per mm of thickness.
"""
import os

import ngsolve as ngs
from netgen.occ import OCCGeometry, Rectangle, X

import ngtmc
from ngtmc.design import Interpolation, TopologyOptimisation

SHORT = os.environ.get("NGTMC_EXAMPLE_SHORT") == "1"

face = Rectangle(2.0, 1.0).Face()
face.faces.name = "plate"
face.edges.Min(X).name, face.edges.Max(X).name = "left", "right"
mesh = ngs.Mesh(OCCGeometry(face, dim=2).GenerateMesh(maxh=0.2 if SHORT else 0.1))
scene = ngtmc.Scene(mesh, {"plate": ngtmc.Material(E=1000.0, nu=0.3)},   # MPa, -
                    supports=[ngtmc.Support("left", x=True, y=True)],
                    load=ngtmc.DisplacementLoad("right", "-y"), gamma0=1e-3)

# %%
# The optimisation: the whole plate is the design region; one load step per forward run.
opt = TopologyOptimisation(scene, design="plate", schedule=0.01, volume_fraction=0.5,
                           filter_radius=0.3, interpolation=Interpolation("simp", 3.0), beta=(1, 2),
                           control=ngtmc.AdaptiveStepControl(du_max=0.01), progress=False)
result = opt.run(evaluations=8 if SHORT else 40)

# %%
# The key numbers: the work gained with the same material, and what it cost.
W0 = result.history[0]["objective"]
split = result.time_split()
print(f"{opt.density.n} design variables, {result.evaluations} evaluations, {result.seconds:.1f} s "
      f"(forward {split['forward_s']:.1f} s, adjoint {split['adjoint_s']:.1f} s)")
print(f"W: {W0:.5e} -> {result.objective:.5e} N mm (x{result.objective / W0:.4f}); "
      f"volume {result.volume:.4f}; failed designs {result.shortened}")
