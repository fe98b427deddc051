"""
A small design loop: steepest descent on the densities
======================================================

The gradients of :mod:`ngtmc.sensitivities` drive a design. A cantilever plate (2 x 1 mm),
clamped on its left edge, has its right edge moved down by 0.01 mm. Its material is
spread over the elements as a pseudo-density rho in [0.05, 1] (stiffness gamma(rho) = gamma0 +
(1 - gamma0) rho), half the plate's area in all. The design makes the plate as stiff as it can
with that much material: it maximises the external work W (N mm) of the prescribed displacement,
i.e. descends on J = -W, each step moving the densities against dJ/drho, projected so that the
material stays the same, and clipped to the bounds. Units: mm, N, MPa; forces per mm of thickness.
"""
import os

import numpy as np
import ngsolve as ngs
from netgen.occ import OCCGeometry, Rectangle, X

import ngtmc
from ngtmc import sensitivities as sens

SHORT = os.environ.get("NGTMC_EXAMPLE_SHORT") == "1"
iterations = 3 if SHORT else 8
rho_min, volume = 0.05, 0.5                               # bounds and area fraction of the design

face = Rectangle(2.0, 1.0).Face()
face.faces.name = "plate"
face.edges.Min(X).name, face.edges.Max(X).name = "left", "right"
mesh = ngs.Mesh(OCCGeometry(face, dim=2).GenerateMesh(maxh=0.25 if SHORT else 0.15))
area = np.array([ngs.Integrate(1, mesh, element_wise=True)]).ravel()        # mm^2 per element


def scene_of(rho):
    return ngtmc.Scene(mesh, {"plate": ngtmc.Material(E=1000.0, nu=0.3)}, density=rho,   # MPa, -
                       supports=[ngtmc.Support("left", x=True, y=True)],
                       load=ngtmc.DisplacementLoad("right", "-y"), gamma0=1e-3)


def with_volume(rho):
    """Shift rho by the constant that restores the material (area fraction ``volume``), clipped."""
    lo, hi = -1.0, 1.0
    for _ in range(60):                                   # bisection on the shift
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if area @ np.clip(rho + mid, rho_min, 1) < volume * area.sum() else (lo, mid)
    return np.clip(rho + 0.5 * (lo + hi), rho_min, 1.0)


# %%
# Steepest descent on J = -W: a step of at most 0.2 in any density, then the volume restored.
objective = -1.0 * sens.ExternalWork()                    # J = -W, N mm
rho = np.full(mesh.ne, volume)
history = []
for k in range(iterations + 1):
    g, path = sens.differentiate(scene_of(rho), 0.01, objective, wrt=("rho",))      # 0.01 mm in one step
    history.append(-g["value"])
    print(f"iteration {k}: W = {-g['value']:.5e} N mm, material {area @ rho / area.sum():.3f} of the area")
    if k < iterations:
        step = g["rho"] / area                            # dJ/drho per unit area: the steepest direction
        rho = with_volume(rho - 0.2 * step / np.abs(step).max())

# %%
# The key number: how much stiffer the design became with the same material.
print(f"W grew by the factor {history[-1] / history[0]:.5f} in {iterations} steps")
