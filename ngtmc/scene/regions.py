"""Region and boundary names: a scene names them by regular expressions (``"beam|band"``, ``".*"``),
matched against the whole name of each mesh region or boundary. The one owner of how a name
specification splits and matches, and of the vertices a name covers; the scene, its checks, the
solver and the runner use it."""
from __future__ import annotations

from dataclasses import dataclass
import re

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["region_names", "matches", "regex", "vertices_of", "box_diagonal", "element_vertices", "PRISM_EDGES",
           "coordinates", "centroids", "neighbours", "within", "element_sizes", "Regions"]


def region_names(spec) -> list[str]:
    """The names (patterns) of a specification: a string with alternatives joined by "|", a
    sequence of such strings, or None (no name)."""
    if spec is None:
        return []
    if isinstance(spec, str):
        return [s for s in spec.split("|") if s]
    return [s for item in spec for s in region_names(item)]


def regex(names) -> str:
    """One pattern matching any of ``names``."""
    return "|".join(names)


def matches(pattern: str, name: str) -> bool:
    """True where the pattern matches the whole region or boundary name."""
    return re.fullmatch(pattern, name) is not None


def vertices_of(mesh, pattern: str, vb=None) -> set:
    """Vertex numbers of the elements of ``mesh`` whose region (``vb`` = ngsolve.VOL, the default)
    or boundary (ngsolve.BND) name matches ``pattern``."""
    import ngsolve as ngs
    return {v.nr for el in mesh.Elements(ngs.VOL if vb is None else vb) if matches(pattern, el.mat)
            for v in el.vertices}


def box_diagonal(points) -> float:
    """Length of the diagonal of the bounding box of ``points`` (rows, mm); 0 for none."""
    import numpy as np
    pts = np.asarray(points, dtype=float)
    return float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))) if pts.size else 0.0


def element_vertices(mesh) -> np.ndarray:
    """Vertex numbers (0-based, NGSolve's) of every volume element of ``mesh``, in the order of
    the elements' numbers: array (mesh.ne, 3) of triangles in 2D, (mesh.ne, 4) of tetrahedra in
    3D, (mesh.ne, 6) of prisms (a mesh of prisms only, :func:`ngtmc.extrude`: the bottom triangle,
    then the top one); the first four vertices of the elements of other 3D meshes."""
    ng = mesh.ngmesh
    if mesh.dim == 2:
        return ng.Elements2D().NumPy()["nodes"][:, :3].astype(int) - 1
    nodes = ng.Elements3D().NumPy()["nodes"].astype(int) - 1   # as wide as the widest element
    if nodes.shape[1] == 6 and nodes.size and nodes[:, 4:].min() >= 0:   # prisms only (no padding)
        return nodes
    return nodes[:, :4]


#: the edges of a prism by its vertices (:func:`element_vertices`): the two triangles, then the
#: three vertical edges (its quadrilateral faces' diagonals are not edges)
PRISM_EDGES = ((0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5))


def coordinates(mesh) -> np.ndarray:
    """Vertex coordinates, (nv, dim), mm."""
    return np.asarray(mesh.ngmesh.Coordinates())[:, :mesh.dim]


def centroids(mesh) -> np.ndarray:
    """Centroid of every element, (ne, dim), mm."""
    return coordinates(mesh)[element_vertices(mesh)].mean(axis=1)


def neighbours(mesh, flags: np.ndarray) -> np.ndarray:
    """Elements sharing a vertex with a flagged element (the flagged ones included)."""
    nodes = element_vertices(mesh)
    hit = np.zeros(mesh.nv, dtype=bool)
    hit[nodes[flags].ravel()] = True
    return hit[nodes].any(axis=1)


def within(mesh, flags: np.ndarray, distance: float) -> np.ndarray:
    """Elements whose centroid lies within ``distance`` (mm) of a flagged element's centroid (the
    flagged ones included)."""
    c = centroids(mesh)
    d, _ = cKDTree(c[flags]).query(c, distance_upper_bound=distance)
    return flags | np.isfinite(d)


def element_sizes(mesh) -> np.ndarray:
    """Longest edge of every element, mm (array of length mesh.ne). A prism's quadrilateral faces
    have no diagonal edge (:data:`PRISM_EDGES`)."""
    pts = np.asarray(mesh.ngmesh.Coordinates())
    nodes = element_vertices(mesh)
    h = np.zeros(len(nodes))
    k = nodes.shape[1]
    pairs = PRISM_EDGES if k == 6 else [(i, j) for i in range(k) for j in range(i + 1, k)]
    for i, j in pairs:
        h = np.maximum(h, np.linalg.norm(pts[nodes[:, i]] - pts[nodes[:, j]], axis=1))
    return h


@dataclass(frozen=True, eq=False)
class Regions:
    """The regions of a scene on one mesh, built once per mesh (:meth:`ngtmc.Scene.regions`): what
    the solver, the refinement and the outputs read instead of matching names again.

    ``names``: the region name of each region number (``mesh.GetMaterials()``); ``index``: the
    region number of every element; ``density``: the pseudo-density of every element
    (dimensionless); ``materials``: region name -> :class:`~ngtmc.Material`; ``fracture_names``
    and ``fracture_regex``: the regions that may break, as the scene names them and as one
    pattern ("" where none may); ``fracture``: per element, in such a region;
    ``regulariser_regex``: the regions the contact regulariser covers ("" without one);
    ``sizes``: the longest edge of every element, mm."""

    names: tuple
    index: np.ndarray
    density: np.ndarray
    materials: dict
    fracture_names: tuple
    fracture_regex: str
    fracture: np.ndarray
    regulariser_regex: str
    sizes: np.ndarray
