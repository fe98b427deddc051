"""How a scene is discretised beyond its mesh: the displacement order per element, the
integration rules of the energy terms, and how their expressions are compiled.

"Model only what a scene needs", per element: the Hessian regulariser needs order-2 displacements,
the rest of a scene does not (:func:`lower_order_outside`). The rules themselves are chosen by
:meth:`ngtmc.solver.Solver.energy_measure`, the one owner of the integration rules.
"""
from __future__ import annotations

import re

import ngsolve as ngs

__all__ = ["real_compile", "rules", "lower_order_outside"]

_REAL_COMPILE_FAILED = []


def real_compile(cf):
    """C++ code generation for a CoefficientFunction (``Compile(realcompile=True)``): about 3x
    faster assembly, about 3-5 s of compilation per expression. Needs NGSolve's ``ngscxx`` (it
    ships in the wheel, next to the Python executable) and a C++ compiler with the Python
    headers. Returns None, after one warning per process, when that fails."""
    if _REAL_COMPILE_FAILED:
        return None
    import os
    import sys
    import sysconfig
    import warnings
    path = os.environ.get("PATH", "").split(os.pathsep)
    for folder in (sysconfig.get_path("scripts"), os.path.dirname(sys.executable)):
        if folder and folder not in path:
            path.insert(0, folder)
    os.environ["PATH"] = os.pathsep.join(path)
    try:
        return cf.Compile(realcompile=True, wait=True)
    except Exception as err:  # NgException "problem calling compiler"
        _REAL_COMPILE_FAILED.append(str(err))
        warnings.warn(f"compile='real' is not available here ({err}); the energies are compiled symbolically "
                      "instead (same results, slower assembly)", RuntimeWarning, stacklevel=3)
        return None


def rules(mesh, order: int) -> dict:
    """Integration rules of the given order for every element type of the mesh's dimension."""
    types = (ngs.TRIG, ngs.QUAD) if mesh.dim == 2 else (ngs.TET, ngs.HEX, ngs.PRISM, ngs.PYRAMID)
    return {et: ngs.IntegrationRule(et, order) for et in types}


def lower_order_outside(fes, mesh, regions: str):
    """Set order 1 on every node (edge, face, cell) of ``fes`` that belongs to no element of
    ``regions`` (regex); the elements there keep the full order on all their nodes, so the
    space stays conforming. "Model only what a scene needs", per element: the Hessian regulariser
    needs order 2, the rest of the scene does not."""
    keep = {ngs.EDGE: set(), ngs.FACE: set()}
    d = mesh.dim
    for el in mesh.Elements(ngs.VOL):
        if re.fullmatch(regions, el.mat):
            keep[ngs.EDGE].update(e.nr for e in el.edges)
            if d == 3:
                keep[ngs.FACE].update(f.nr for f in el.faces)
    for e in range(mesh.nedge):
        if e not in keep[ngs.EDGE]:
            fes.SetOrder(ngs.NodeId(ngs.EDGE, e), 1)
    if d == 3:
        for f in range(mesh.nface):
            if f not in keep[ngs.FACE]:
                fes.SetOrder(ngs.NodeId(ngs.FACE, f), 1)
    inner = ngs.FACE if d == 2 else ngs.CELL
    for el in mesh.Elements(ngs.VOL):
        if not re.fullmatch(regions, el.mat):
            fes.SetOrder(ngs.NodeId(inner, el.nr), 1)
    fes.Update()
