"""
A mesh from gmsh
================

A mesh made with gmsh enters through :func:`ngtmc.read_gmsh`, its **physical groups** becoming
the region and boundary names of the scene. Here the ``.msh`` file (gmsh format 2.2) is
written with meshio (``pip install "ngtmc[gmsh]"``), so that the example needs no gmsh: a 1 x 1 mm
square of n x n x 2 triangles, physical groups ``plate`` (surface), ``left``, ``right``,
``bottom`` (curves). Stretched by 1e-4 mm, held in x on the left and in y at the bottom, it is
in plane-strain uniaxial stress: the hand value of the force is
E / (1 - nu^2) * strain * height = 1000 / 0.91 * 1e-4 = 0.10989 N per mm of thickness.
"""
import os
import tempfile
from pathlib import Path

import meshio
import numpy as np

import ngtmc

SHORT = os.environ.get("NGTMC_EXAMPLE_SHORT") == "1"
n = 4 if SHORT else 16                                   # cells per side

# %%
# Nodes, triangles and boundary lines of the square (mm), each with its physical tag.
nodes = np.array([(i / n, j / n, 0.0) for j in range(n + 1) for i in range(n + 1)])
node = lambda i, j: j * (n + 1) + i                      # noqa: E731
triangles = []
for j in range(n):
    for i in range(n):
        a, b, c, d = node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)
        triangles += [(a, b, c), (a, c, d)]
left = [(node(0, k), node(0, k + 1)) for k in range(n)]
right = [(node(n, k), node(n, k + 1)) for k in range(n)]
bottom = [(node(k, 0), node(k + 1, 0)) for k in range(n)]
cells = [("triangle", np.array(triangles))] + [("line", np.array(e)) for e in (left, right, bottom)]
tags = [np.full(len(c), t) for (_, c), t in zip(cells, (1, 2, 3, 4))]
msh = meshio.Mesh(nodes, cells, cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                  field_data={"plate": np.array([1, 2]), "left": np.array([2, 1]),     # name: [tag, dim]
                              "right": np.array([3, 1]), "bottom": np.array([4, 1])})
path = Path(tempfile.mkdtemp()) / "plate.msh"
meshio.write(path, msh, file_format="gmsh22", binary=False)   # as gmsh -format msh22 writes it

# %%
# Read it: the physical groups are the names of the scene.
mesh = ngtmc.read_gmsh(path)
print("regions", mesh.GetMaterials(), "boundaries", sorted(set(mesh.GetBoundaries())), mesh.ne, "elements")
scene = ngtmc.Scene(mesh, {"plate": ngtmc.Material(E=1000.0, nu=0.3)},   # MPa, -
                    supports=[ngtmc.Support("left", x=True), ngtmc.Support("bottom", y=True)],
                    load=ngtmc.DisplacementLoad("right", "x"))
force = ngtmc.simulate(scene, 1e-4).history["force"].iloc[-1]           # 1e-4 mm
print(f"force {force:.5f} N/mm, hand value {1000 / 0.91 * 1e-4:.5f} N/mm")
