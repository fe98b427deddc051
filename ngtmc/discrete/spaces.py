"""How a scene is discretised beyond its mesh: the displacement order per element, the
integration rules of the energy terms, and how their expressions are compiled.

"Model only what a scene needs", per element: the Hessian regulariser needs order-2 displacements,
the rest of a scene does not (:func:`lower_order_outside`). The rules themselves are chosen by
:meth:`ngtmc.discrete.solver.Solver.energy_measure`, the one owner of the integration rules.
"""
from __future__ import annotations

import re

import ngsolve as ngs

from ngtmc.discrete import cxx_cache
__all__ = ["real_compile", "rules", "term_rules", "RULE_EXACTNESS", "lower_order_outside", "bilinear_form"]

_REAL_COMPILE_FAILED = []


def real_compile(cf):
    """C++ code generation for a CoefficientFunction (``Compile(realcompile=True)``): about 3x
    faster assembly, about 3-5 s of compilation per expression. Needs NGSolve's ``ngscxx`` (it
    ships in the wheel, next to the Python executable) and a C++ compiler with the Python
    headers. Returns None, after one warning per process, when that fails. The object files are
    kept between processes (:mod:`ngtmc.discrete.cxx_cache`): a compilation seen before costs about 1 s."""
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
    os.environ["PATH"] = os.pathsep.join(cxx_cache.activate(path))
    try:
        return cf.Compile(realcompile=True, wait=True)
    except Exception as err:  # NgException "problem calling compiler"
        _REAL_COMPILE_FAILED.append(str(err))
        warnings.warn(f"compile='real' is not available here ({err}); the energies are compiled symbolically "
                      "instead (same results, slower assembly)", RuntimeWarning, stacklevel=3)
        return None


def element_types(mesh) -> tuple:
    """The volume element types of the mesh's dimension (NGSolve's ``ET``)."""
    return (ngs.TRIG, ngs.QUAD) if mesh.dim == 2 else (ngs.TET, ngs.HEX, ngs.PRISM, ngs.PYRAMID)


def rules(mesh, order) -> dict:
    """Integration rules for every element type of the mesh's dimension: of the given order, or of
    the order per element type where ``order`` is a dict (ET -> order)."""
    return {et: ngs.IntegrationRule(et, order[et] if isinstance(order, dict) else order)
            for et in element_types(mesh)}


_SIMPLICES = (ngs.TRIG, ngs.TET)

#: On which elements the rule of each :func:`term_rules` term is exact ("exact") and where it is
#: only converged ("converged": a rational or non-polynomial integrand, checked against a rule of
#: much higher order in tests/test_verification.py). Straight means affine: a straight simplex,
#: a parallelogram or parallelepiped, a prism with parallel triangles; "curved" is a mesh with
#: ``mesh.Curve(k)``, k >= 2, and any non-affine quadrilateral or hexahedron.
RULE_EXACTNESS = {
    "regularisation": "exact on straight (affine) triangles, tetrahedra, quadrilaterals, hexahedra and prisms "
                      "(order 2(p - 2) on simplices, where the Hessian of a degree-p field has degree p - 2; "
                      "order 2p on tensor-product and prism elements, where it has degree p in each "
                      "variable); converged on non-affine quadrilaterals and hexahedra (order 2p: 2e-8 relative on "
                      "a skewed square, p = 2), on curved elements (order 2p + 2: 2e-9 on a curved triangle mesh, "
                      "3e-5 on a curved quad-dominated one) and on pyramids (order 2p + 2, rational shape functions)",
    "elastic_p1": "exact on straight simplices for the undegraded energy (one point: F is constant; g(alpha) "
                  "of a fracture region varies over the element and is sampled there); straight prisms: the "
                  "triangle's centroid times two Gauss points along the axis (exact where F is constant through "
                  "the thickness, as in a plane-strain slab); converged on quadrilaterals, "
                  "hexahedra, pyramids and curved elements (order 2, the full rule of the history "
                  "points, 2e-5 to 6e-4 relative on the skewed and curved meshes of the tests: one point "
                  "there would leave the hourglass modes of a quadrilateral without stiffness)",
    "elastic": "converged on every element (order 2p, the history and J-guard points; the hyperelastic "
               "density is not a polynomial)",
}


def _prism_centroid_line():
    """The rule of an order-1 prism: the triangle's centroid times two Gauss points along the
    prism's axis. F of an order-1 prism is linear along the axis and, in a plane-strain slab
    (:func:`ngtmc.extrude`, u_z held), constant: there it is the triangle's one point, so the slab
    reproduces its 2D twin; the rank is full (no zero-energy mode)."""
    import math
    g = 0.5 / math.sqrt(3.0)
    return ngs.IntegrationRule([(1 / 3, 1 / 3, 0.5 - g), (1 / 3, 1 / 3, 0.5 + g)], [0.25, 0.25])


def term_rules(mesh, term: str, p: int) -> dict:
    """Integration rules (ET -> rule) of the displacement energy term ``term`` for displacement
    order ``p`` on ``mesh``: "regularisation" (the Hessian regulariser) or "elastic_p1" (an
    elastic term on order-1 elements); where each is exact: :data:`RULE_EXACTNESS`. The one owner
    of these choices; :meth:`ngtmc.discrete.solver.Solver.energy_measure` picks the term.

    A rule chosen for speed (one point on a straight triangle, where the Hessian of a P2 field is
    constant) is only used where it is exact: on a quadrilateral (netgen's ``quad_dominated``) the
    one-point rule moved the contact corner of a self-contact scene by 15 %."""
    curved = mesh.GetCurveOrder() > 1
    if term == "regularisation":
        orders = {et: 2 * p + 2 if curved else (max(2 * p - 4, 0) if et in _SIMPLICES else 2 * p)
                  for et in element_types(mesh)}
        if ngs.PYRAMID in orders:
            orders[ngs.PYRAMID] = 2 * p + 2
        return rules(mesh, orders)
    if term == "elastic_p1":
        out = rules(mesh, {et: 0 if (et in _SIMPLICES and not curved) else 2 for et in element_types(mesh)})
        if mesh.dim == 3 and not curved:
            out[ngs.PRISM] = _prism_centroid_line()
        return out
    raise ValueError(f"term_rules: unknown term {term!r} (one of 'regularisation', 'elastic_p1')")


def bilinear_form(fes, **flags):
    """``ngs.BilinearForm(fes, **flags)`` that keeps the matrix of the finest mesh only.

    NGSolve keeps one matrix per mesh level by default (for multigrid): after each
    ``mesh.Refine()`` the next assembly allocates a new matrix and the old ones stay alive (about
    32 MB per refinement at 116k dofs, measured). The flag ``nonmultilevel`` drops them; NGSolve
    prints a warning that the flag is undocumented (it is read: tests/test_adapt.py), which is
    kept off the console (stderr). Every form that lives through an adaptive run is made here."""
    with _quiet_stderr():
        return ngs.BilinearForm(fes, nonmultilevel=True, **flags)


class _quiet_stderr:
    """Keep what a block writes to stderr (NGSolve's flag warnings, from C++ or Python) off the
    console: file descriptor 2 goes to /dev/null for the block."""

    def __enter__(self):
        import contextlib
        import io
        import os
        import sys
        sys.stderr.flush()
        self._saved = os.dup(2)
        self._null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(self._null, 2)
        self._cm = contextlib.redirect_stderr(io.StringIO())
        self._cm.__enter__()

    def __exit__(self, *exc):
        import os
        self._cm.__exit__(*exc)
        os.dup2(self._saved, 2)
        os.close(self._saved)
        os.close(self._null)
        return False


def lower_order_outside(fes, mesh, regions: str, order: int | None = None):
    """Set order 1 on every node (edge, face, cell) of ``fes`` that belongs to no element of
    ``regions`` (regex); the elements there keep the full order on all their nodes, so the
    space stays conforming. "Model only what a scene needs", per element: the Hessian regulariser
    needs order 2, the rest of the scene does not.

    ``order``: also set this order explicitly on the nodes that keep the full order. Needed after
    a refinement: NGSolve does not carry the per-node orders over to the refined mesh (the space
    comes back with the full order on new nodes), so every node is set again."""
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
        elif order is not None:
            fes.SetOrder(ngs.NodeId(ngs.EDGE, e), order)
    if d == 3:
        for f in range(mesh.nface):
            if f not in keep[ngs.FACE]:
                fes.SetOrder(ngs.NodeId(ngs.FACE, f), 1)
            elif order is not None:
                fes.SetOrder(ngs.NodeId(ngs.FACE, f), order)
    inner = ngs.FACE if d == 2 else ngs.CELL
    for el in mesh.Elements(ngs.VOL):
        if not re.fullmatch(regions, el.mat):
            fes.SetOrder(ngs.NodeId(inner, el.nr), 1)
        elif order is not None:
            fes.SetOrder(ngs.NodeId(inner, el.nr), order)
    fes.Update()
