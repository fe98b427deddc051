"""Region and boundary names: a scene names them by regular expressions (``"beam|band"``, ``".*"``),
matched against the whole name of each mesh region or boundary. The one owner of how a name
specification splits and matches, and of the vertices a name covers; the scene, its checks, the
solver and the runner use it."""
from __future__ import annotations

import re

__all__ = ["region_names", "matches", "regex", "vertices_of", "box_diagonal"]


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
