"""Extrusion of a 2D mesh into a slab of prisms: the 3D twin of a 2D scene.

    >>> import ngtmc
    >>> slab = ngtmc.extrude(mesh2d, thickness=0.03)      # doctest: +SKIP
    >>> twin = plane_strain_slab(scene2d, 0.03)            # doctest: +SKIP

Each triangle becomes a column of ``layers`` prisms (each quadrilateral a column of hexahedra)
between z = 0 and z = ``thickness`` (mm). The regions keep their names; each named boundary
segment of the 2D mesh becomes a face of quadrilaterals with the same name, and the two faces of
the slab are named ``front`` (z = 0) and ``back`` (z = thickness). Unnamed interfaces between
regions are not kept as faces. With u_z held on ``front`` and ``back`` the slab is in plane
strain, so a 3D run can be checked against the 2D run of the same mesh (studies/three_point_bending_3d.py).

The elements are straight-sided: a curved 2D mesh (``mesh.Curve``) loses its curvature, so
compare with the 2D mesh made straight again (``mesh.Curve(1)``).

Every boundary face records the region on each side (netgen's face descriptors), which NGSolve
needs to know which vertices belong to a region: a space ``definedon`` some regions then has no
dofs on the others' vertices (tests/test_extrude.py).
"""
from __future__ import annotations

import numpy as np
import ngsolve as ngs
from ngtmc.scene.conditions import Support

__all__ = ["extrude", "plane_strain_slab"]


def extrude(mesh, thickness: float, layers: int = 1, front: str = "front", back: str = "back") -> ngs.Mesh:
    """The slab of ``mesh`` (2D, mm) extruded by ``thickness`` (mm) in ``layers`` element layers
    along z: prisms from triangles, hexahedra from quadrilaterals (see the module docstring)."""
    from netgen.meshing import Element2D, Element3D, FaceDescriptor, MeshPoint, Pnt, PointId
    from netgen.meshing import Mesh as NgMesh

    if mesh.dim != 2:
        raise ValueError(f"extrude needs a 2D mesh; this one has dimension {mesh.dim}")
    if not (np.isfinite(thickness) and thickness > 0):
        raise ValueError(f"thickness must be a positive length in mm; got {thickness!r}")
    if int(layers) != layers or layers < 1:
        raise ValueError(f"layers must be a positive integer; got {layers!r}")
    layers = int(layers)
    m2 = mesh.ngmesh
    xy = np.asarray(m2.Coordinates(), dtype=float)[:, :2]
    nv = len(xy)
    out = NgMesh(dim=3)
    for z in np.linspace(0.0, float(thickness), layers + 1):
        for x, y in xy:
            out.Add(MeshPoint(Pnt(float(x), float(y), float(z))))
    regions = m2.GetRegionNames(dim=2)
    for i, name in enumerate(regions, start=1):
        out.SetMaterial(i, name)
    names = m2.GetRegionNames(dim=1)
    faces = {}

    def face(name: str, inside: int, outside: int) -> int:
        key = (name, inside, outside)
        if key not in faces:
            faces[key] = out.Add(FaceDescriptor(bc=len(faces) + 1, domin=inside, domout=outside, surfnr=len(faces) + 1))
            out.SetBCName(faces[key] - 1, name)
        return faces[key]

    def pid(v: int, k: int):
        return PointId(k * nv + v + 1)

    # the elements on each side of every edge, to give each face its regions
    sides: dict[tuple[int, int], list[int]] = {}
    for el in m2.Elements2D():
        v = [p.nr - 1 for p in el.vertices]
        for k in range(layers):
            out.Add(Element3D(el.index, [pid(i, k) for i in v] + [pid(i, k + 1) for i in v]))
        out.Add(Element2D(face(front, el.index, 0), [pid(i, 0) for i in v[::-1]]))
        out.Add(Element2D(face(back, el.index, 0), [pid(i, layers) for i in v]))
        for a, b in zip(v, v[1:] + v[:1]):
            sides.setdefault((min(a, b), max(a, b)), []).append(el.index)
    for seg in m2.Elements1D():
        a, b = [p.nr - 1 for p in seg.vertices]
        name = names[seg.index - 1] if 0 < seg.index <= len(names) else "default"
        adjacent = sides.get((min(a, b), max(a, b)), [])
        if len(adjacent) > 1 and name == "default":
            continue  # an unnamed interface between regions
        inside = adjacent[0] if adjacent else 0
        outside = adjacent[1] if len(adjacent) > 1 else 0
        for k in range(layers):
            out.Add(Element2D(face(name, inside, outside), [pid(a, k), pid(b, k), pid(b, k + 1), pid(a, k + 1)]))
    return ngs.Mesh(out)


def plane_strain_slab(scene, thickness: float, layers: int = 1, name: str | None = None):
    """The 3D twin of a 2D ``scene``: its mesh extruded by ``thickness`` (mm, :func:`extrude`),
    u_z held on ``front`` and ``back`` (plane strain), everything else as in ``scene``. Its
    forces and energies are those of the 2D scene for a thickness of ``thickness``."""
    import dataclasses
    if scene.mesh.dim != 2:
        raise ValueError(f"plane_strain_slab needs a 2D scene; this one has dimension {scene.mesh.dim}")
    return dataclasses.replace(scene, mesh=extrude(scene.mesh, thickness, layers), thickness=None,
                               supports=list(scene.supports) + [Support("front", z=True), Support("back", z=True)],
                               name=name or scene.name)
