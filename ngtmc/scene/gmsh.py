"""Meshes from gmsh files, every format gmsh writes (2.2 and 4.x, ASCII and binary), read through
meshio, a well-kept reader (``pip install "ngtmc[gmsh]"``), and checked for what they would lose.

Physical groups name the scene: a physical surface (2D) or volume (3D) becomes a region, a
physical curve (2D) or surface (3D) a boundary. Coordinates are read as mm. Refused, each with a
message naming it: cells of the body in no physical group (they would be dropped: half a body and
a force of 0), second-order cells, a file with no body cells. A physical group without a name
gets the name ``physical<tag>`` (said in a warning).
"""
from __future__ import annotations

from pathlib import Path
import warnings

import numpy as np

__all__ = ["read_gmsh"]

#: meshio cell type -> (dimension, netgen's order of gmsh's corner nodes)
_CELLS = {
    "line": (1, [0, 1]),
    "triangle": (2, [0, 1, 2]),
    "quad": (2, [0, 1, 2, 3]),
    "tetra": (3, [0, 1, 2, 3]),
    "hexahedron": (3, [0, 1, 5, 4, 3, 2, 6, 7]),
    "wedge": (3, [0, 2, 1, 3, 5, 4]),
    "pyramid": (3, [3, 2, 1, 0, 4]),
}
_HIGHER = ("line3", "triangle6", "quad8", "quad9", "tetra10", "hexahedron20", "hexahedron27", "wedge15",
           "wedge18", "pyramid13", "pyramid14")


def read_gmsh(path):
    """The gmsh mesh file ``path`` as an ``ngsolve.Mesh`` whose regions and boundaries are the
    file's physical groups (module docstring). Raises ValueError naming the file and what it
    cannot take; ImportError when meshio is not installed."""
    try:
        import meshio
    except ImportError as e:
        raise ImportError('ngtmc.read_gmsh needs meshio: pip install "ngtmc[gmsh]" (or pip install meshio)') from e
    import netgen.meshing as nm
    import ngsolve as ngs

    f = Path(path)
    if not f.is_file():
        raise ValueError(f"read_gmsh: {str(path)!r} does not exist")
    try:
        m = meshio.read(f, file_format="gmsh")
    except (Exception, SystemExit) as e:    # meshio's reader exits on some malformed files
        raise ValueError(f"read_gmsh: {f} cannot be read as a gmsh file ({type(e).__name__}: {e})") from e
    higher = sorted({b.type for b in m.cells if b.type in _HIGHER})
    if higher:
        raise ValueError(f"read_gmsh: {f} has second-order cells ({', '.join(higher)}); export a first-order "
                         "mesh (gmsh -order 1) and curve it in netgen (mesh.Curve(2)) if needed")
    blocks = [(b.type, b.data) for b in m.cells if b.type in _CELLS]
    dim = max((_CELLS[t][0] for t, _ in blocks), default=0)
    if dim < 2:
        raise ValueError(f"read_gmsh: {f} has no triangles, quadrilaterals or volume cells: no body to read")
    tags = m.cell_data.get("gmsh:physical")
    names = {(int(v[1]), int(v[0])): k for k, v in (m.field_data or {}).items()}   # (dim, tag) -> name
    unnamed = set()

    def name_of(d, tag):
        if (d, tag) not in names:
            names[(d, tag)] = f"physical{tag}"
            unnamed.add(names[(d, tag)])
        return names[(d, tag)]

    ngm = nm.Mesh(dim=dim)
    pts = np.asarray(m.points, dtype=float)
    pnums = [ngm.Add(nm.MeshPoint(nm.Pnt(*(list(p[:3]) + [0.0] * (3 - len(p[:3])))))) for p in pts]
    regions, boundaries = {}, {}
    dropped = {}
    for i, b in enumerate(m.cells):
        if b.type not in _CELLS:
            continue
        d, order = _CELLS[b.type]
        if d < dim - 1:
            continue              # points of the file (and edges in 3D) name nothing here
        phys = np.asarray(tags[i]).ravel() if tags is not None else np.zeros(len(b.data), dtype=int)
        for cell, tag in zip(b.data, phys):
            tag = int(tag)
            if tag <= 0:
                dropped[b.type] = dropped.get(b.type, 0) + 1
                continue
            if d == dim:
                if tag not in regions:
                    regions[tag] = ngm.AddRegion(name_of(d, tag), dim=dim)
                verts = [pnums[cell[k]] for k in order]
                ngm.Add(nm.Element2D(regions[tag], verts) if dim == 2 else nm.Element3D(regions[tag], verts))
            else:
                if tag not in boundaries:
                    boundaries[tag] = ngm.AddRegion(name_of(d, tag), dim=dim - 1)
                verts = [pnums[cell[k]] for k in order]
                ngm.Add(nm.Element1D(verts, index=boundaries[tag]) if dim == 2 else nm.Element2D(boundaries[tag], verts))
    body = {t: n for t, n in dropped.items() if _CELLS[t][0] == dim}
    if body:
        raise ValueError(f"read_gmsh: {f}: {', '.join(f'{n} {t} cells' for t, n in body.items())} belong to no "
                         f"physical {'surface' if dim == 2 else 'volume'}: they would be dropped from the body. Add "
                         "them to a physical group (gmsh: Physical Surface/Volume)")
    if not regions:
        raise ValueError(f"read_gmsh: {f} has no physical {'surface' if dim == 2 else 'volume'}: name the body's "
                         "regions with physical groups")
    if unnamed:
        warnings.warn(f"read_gmsh: {f}: physical groups without a name are called {sorted(unnamed)}",
                      UserWarning, stacklevel=2)
    return ngs.Mesh(ngm)
