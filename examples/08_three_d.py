"""
A small 3D scene: an extruded bar
=================================

:func:`ngtmc.extrude` turns a 2D mesh into a slab of prisms: the regions and the boundary names
of the 2D mesh carry over (a boundary edge becomes a face), and the two new faces are called
``front`` and ``back``. Here a bar of 1 x 0.2 mm, extruded by 0.1 mm, is pulled along its axis by
1e-4 mm, free to contract sideways (held only on one face per direction). In uniaxial stress the
hand value of the force is E A delta / L = 1000 MPa * 0.02 mm^2 * 1e-4 mm / 1 mm = 2e-3 N.
A 3D scene has no ``thickness``: its forces are in N. Units: mm, N, MPa.
"""
import os

import ngsolve as ngs
from netgen.occ import OCCGeometry, Rectangle, X, Y

import ngtmc

SHORT = os.environ.get("NGTMC_EXAMPLE_SHORT") == "1"
L, H, T = 1.0, 0.2, 0.1                                  # mm: length, height, extrusion depth

# %%
# The 2D mesh with its names, then the slab of prisms.
face = Rectangle(L, H).Face()
face.faces.name = "bar"
face.edges.Min(X).name, face.edges.Max(X).name, face.edges.Min(Y).name = "left", "right", "bottom"
mesh2d = ngs.Mesh(OCCGeometry(face, dim=2).GenerateMesh(maxh=0.1 if SHORT else 0.05))
mesh = ngtmc.extrude(mesh2d, T, layers=1 if SHORT else 2)
print(mesh.dim, "D:", mesh.ne, "prisms, boundaries", sorted(set(mesh.GetBoundaries())))

# %%
# Held in x on the left face, in y on the bottom face, in z on the back face; the right face moved.
scene = ngtmc.Scene(mesh, {"bar": ngtmc.Material(E=1000.0, nu=0.3)},          # MPa, -
                    supports=[ngtmc.Support("left", x=True), ngtmc.Support("bottom", y=True),
                              ngtmc.Support("back", z=True)],
                    load=ngtmc.DisplacementLoad("right", "x"))
result = ngtmc.simulate(scene, 1e-4)                                          # mm
force = result.history["force"].iloc[-1]
print(f"force {force:.6e} {result.units['force']}, hand value E A delta / L = {1000.0 * H * T * 1e-4 / L:.6e} N")
