"""
Topology optimisation: filter, projection and MMA
=================================================

The cantilever plate of the design loop (2 x 1 mm, clamped on the left, its right edge moved down
by 0.01 mm), designed with the recipe of the topology-optimisation literature from
:mod:`ngtmc.design`: the design variables x (one per element, in [0, 1]) are smoothed by a
Helmholtz filter of radius 0.3 mm, sharpened by a Heaviside projection (beta = 2), and mapped to
the pseudo-density rho = 0.01 + 0.99 project(F x); MMA (nlopt) maximises the external work W
(N mm) with the projected densities filling at most half of the plate's area. The gradients are the adjoint's
(:mod:`ngtmc.sensitivities`) carried back through the projection and the filter by the chain
rule. Units: mm, N, MPa; forces per mm of thickness.
"""
import os

import numpy as np
import ngsolve as ngs
from netgen.occ import OCCGeometry, Rectangle, X

import ngtmc
from ngtmc import sensitivities as sens
from ngtmc.design import HelmholtzFilter, mma, project, project_derivative

SHORT = os.environ.get("NGTMC_EXAMPLE_SHORT") == "1"
evaluations = 6 if SHORT else 15
volume, beta = 0.5, 2.0                                  # area fraction, projection sharpness

face = Rectangle(2.0, 1.0).Face()
face.faces.name = "plate"
face.edges.Min(X).name, face.edges.Max(X).name = "left", "right"
mesh = ngs.Mesh(OCCGeometry(face, dim=2).GenerateMesh(maxh=0.25 if SHORT else 0.15))
F = HelmholtzFilter(mesh, radius=0.3)                    # mm
share = F.areas / F.areas.sum()                          # each element's share of the plate's area


def density(x):
    return 0.01 + 0.99 * project(F.filter(x), beta)


def chain(x, g_rho):
    """d/dx of a function of rho(x), from its gradient g_rho with respect to rho."""
    return F.transpose(0.99 * project_derivative(F.filter(x), beta) * g_rho)


def work(x):
    """J = -W and dJ/dx: one forward run with its adjoint."""
    scene = ngtmc.Scene(mesh, {"plate": ngtmc.Material(E=1000.0, nu=0.3)}, density=density(x),
                        supports=[ngtmc.Support("left", x=True, y=True)],
                        load=ngtmc.DisplacementLoad("right", "-y"), gamma0=1e-3)
    g, _ = sens.differentiate(scene, 0.01, -1.0 * sens.ExternalWork(), wrt=("rho",))   # 0.01 mm in one step
    return g["value"], chain(x, g["rho"])


def material(x):
    """g = (area fraction filled by the projected densities) - volume <= 0."""
    return share @ project(F.filter(x), beta) - volume, F.transpose(project_derivative(F.filter(x), beta) * share)


# %%
# MMA from a uniform design at the volume bound (project(1/2) = 1/2).
x0 = np.full(mesh.ne, volume)
seen = []
result = mma(work, x0, 0.0, 1.0, [material], max_evaluations=evaluations,
             callback=lambda x, J, rec: seen.append(J) or print(f"evaluation {len(seen)}: W = {-J:.5e} N mm"))

# %%
# The key number: how much stiffer the design became with the same material.
W0, W = -result.history[0]["objective"], -result.objective
print(f"{mesh.ne} design variables, {result.evaluations} evaluations ({result.status}), {result.seconds:.1f} s")
print(f"W grew by the factor {W / W0:.5f}; projected material {share @ project(F.filter(result.x), beta):.4f} "
      "of the area")
