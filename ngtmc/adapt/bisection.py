"""Refinement by NGSolve's bisection during a run, with the exact transfer of the state to the refined mesh.

:func:`refine` bisects the elements that :func:`ngtmc.adapt.mark` marked (``mesh.SetRefinementFlag``,
``mesh.Refine()``), brings the solver to the new mesh (:meth:`~ngtmc.discrete.solver.Solver.mesh_changed`)
and carries its state over:

* u: exactly. NGSolve's prolongation of a space with per-node orders is not exact for order 2
  (only the vertex part is; 0.026 error on a quadratic field, measured), so u is carried through
  a uniform-order space with ``hoprolongation=True`` (exact on triangles and tetrahedra) and set back.
  NGSolve has no ``hoprolongation`` on prisms of order 2 (it raises "H1Ho prism dual shapes only
  implemented for order==1"), and their plain prolongation loses the quadratic part (0.021 on a
  quadratic field, measured); so on prisms u is set on a copy of the mesh before the bisection and
  set back from it across the two meshes afterwards, exact because the refined space holds the
  old one (6e-15, measured; the prisms of :func:`ngtmc.extrude` are straight-sided, so the copy
  has the same geometry; tests/test_adapt_prisms.py);
* alpha (P1) by NGSolve's prolongation, exact: a bisection puts the new vertex at an edge midpoint
  where the P1 field is the mean of the edge's ends (on a curved boundary the new vertex is moved
  onto the geometry and keeps that value);
* the history H without loss: an element that was not refined keeps its values; every child of a
  refined element takes, at each of its points, the largest value of its parent's points. Damage
  never heals through a transfer (the value at a child's point is at least the parent's value at
  any of the parent's points, so at least any field interpolated from them within the parent's
  range); a homogeneous H stays exactly as it is;
* the pseudo-density: an element given per element (array) follows its parent; a density given
  per region follows the region names, which children keep.

Curved geometry stays curved: the mesh is curved again at its order after each refinement.

A run is resumed on its refined mesh by :func:`replay`: the elements marked in each refinement
are recorded (:class:`~ngtmc.adapt.RefinementRecord`), and NGSolve's bisection of the same marks
on the same initial mesh gives the same mesh and dof numbering again.

The settings and the marking are in :mod:`ngtmc.adapt` (which re-exports :func:`refine`,
:func:`replay` and :func:`transfer_history`).

Units: mm.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import ngsolve as ngs

from ngtmc.adapt.marking import per_element
from ngtmc.adapt.record import RefinementRecord
from ngtmc.scene import element_vertices

__all__ = ["refine", "replay", "transfer_history"]


def _ancestors(mesh, ne_old: int, before=None) -> np.ndarray:
    """For every element of the refined mesh, the element of the mesh before the refinement that
    contains it. A refined element keeps its number for one child; the others are appended, each
    with a parent (possibly itself appended in the same refinement). With ``before`` (a copy of
    the mesh before the refinement, for prisms, whose parents NGSolve does not record: it gave
    parent numbers that overflowed, measured) the element of ``before`` that holds each new
    element's centroid, which lies inside its ancestor."""
    ne = mesh.ne
    if before is not None:
        c = np.asarray(mesh.ngmesh.Coordinates())[element_vertices(mesh)].mean(axis=1)
        anc = np.asarray(before(c[:, 0], c[:, 1], c[:, 2])["nr"], dtype=np.int64)
        if np.any(anc < 0) or np.any(anc >= ne_old) or np.any(anc[:ne_old] != np.arange(ne_old)):
            raise RuntimeError("a refined element's centroid was not found in the mesh before the refinement")
        return anc
    anc = np.arange(ne)
    parent = np.array([mesh.GetParentElement(ngs.ElementId(ngs.VOL, i)).nr for i in range(ne_old, ne)], dtype=np.int64)
    anc[ne_old:] = parent
    for _ in range(64):
        deep = anc[ne_old:] >= ne_old
        if not deep.any():
            return anc
        anc[ne_old:][deep] = anc[anc[ne_old:][deep]]
    raise RuntimeError("the parent chain of a refinement did not end in an element of the previous mesh")


def transfer_history(H_old: np.ndarray, ancestors: np.ndarray, ne_old: int, npts_new: int) -> np.ndarray:
    """The history on the refined mesh without loss: an element not refined keeps its values, every
    child of a refined element gets the largest value of its parent's points at all its points."""
    Hp = per_element(np.asarray(H_old, dtype=float), ne_old)
    if Hp.shape[1] != npts_new:
        raise RuntimeError("the history rule changed its number of points in a refinement")
    refined = np.zeros(ne_old, dtype=bool)
    refined[ancestors[ne_old:]] = True
    out = np.empty((ancestors.size, npts_new))
    out[:ne_old] = Hp
    out[:ne_old][refined] = Hp[refined].max(axis=1, keepdims=True)
    out[ne_old:] = Hp[ancestors[ne_old:]].max(axis=1, keepdims=True)
    return out.ravel()


def _prisms(mesh) -> bool:
    """Whether ``mesh`` is a mesh of prisms (:func:`ngtmc.scene.scene.element_vertices` gives them six
    vertices; :func:`ngtmc.adapt.check_solver` admits no other 3D mesh with prisms)."""
    return mesh.dim == 3 and element_vertices(mesh).shape[1] == 6


def _carrier_space(solver):
    """The uniform-order space through which u is carried to a refined mesh, made once per solver
    on the mesh's first level and kept: an ``hoprolongation`` space prolongates exactly only if
    it has existed since the first level of the mesh (one made on an already refined mesh gave an
    error of 0.086 on a quadratic field, silently; tests/test_adapt.py)."""
    aux = getattr(solver, "_adapt_carrier", None)
    if aux is None:
        if solver.mesh.levels != 1:
            raise ValueError("adaptive refinement needs a mesh that has not been refined by NGSolve before the run "
                             f"(this one has {solver.mesh.levels} levels): start from adapt.private_scene(scene), "
                             "which works on a copy of the mesh")
        p = solver.order
        aux = ngs.VectorH1(solver.mesh, order=p, hoprolongation=p >= 2)
        solver._adapt_carrier = aux
    return aux


def refine(solver, marked: np.ndarray, states=()) -> tuple[RefinementRecord, list]:
    """Refine the marked elements of the solver's mesh and carry the solver's state over.

    The solver's fields (u, alpha, committed alpha and history) are transferred in place (see the
    module docstring); ``states``: further states of :meth:`~ngtmc.discrete.solver.Solver.get_state` (for
    example the one before the step) to transfer, returned as new dicts in the same order; a state
    may hold only some of the fields (``u`` at least; ``alpha``, ``alpha_committed``, ``H``,
    ``load``), for example a predictor's (u, alpha). Returns (record, transferred states)."""
    mesh = solver.mesh
    ne_old = mesh.ne
    dofs_old = solver.fes_u.ndof
    marked = np.asarray(marked, dtype=bool)
    if marked.shape != (ne_old,):
        raise ValueError(f"marked has shape {marked.shape}; the mesh has {ne_old} elements")
    before = ngs.Mesh(mesh.ngmesh.Copy()) if _prisms(mesh) else None
    aux = _carrier_space(solver) if before is None else ngs.VectorH1(before, order=solver.order)
    tmp_u = ngs.GridFunction(solver.fes_u)

    def carry_u(values):
        tmp_u.vec.FV().NumPy()[:] = values
        g = ngs.GridFunction(aux)
        g.Set(tmp_u)
        return g

    u_carriers = [carry_u(solver.u.vec.FV().NumPy())] + [carry_u(st["u"]) for st in states]
    a_carriers = {}
    if solver.alpha is not None:
        def carry_a(values):
            g = ngs.GridFunction(solver.fes_a)
            g.vec.FV().NumPy()[:] = values
            return g
        a_carriers[-1, "alpha_committed"] = carry_a(solver.alpha_committed)
        for k, st in enumerate(states):
            for key in ("alpha", "alpha_committed"):
                if key in st:
                    a_carriers[k, key] = carry_a(st[key])
    H_old = [solver.H_committed] + [st["H"] for st in states if "H" in st]

    anc = _refine_mesh(solver, marked, before)

    npts = solver.irs.ndof // mesh.ne
    new_H = [transfer_history(h, anc, ne_old, npts) for h in H_old]

    def back_u(g):
        t = ngs.GridFunction(solver.fes_u)
        t.Set(g)
        return t.vec.FV().NumPy().copy()

    new_u = [back_u(g) for g in u_carriers]
    solver.u.vec.FV().NumPy()[:] = new_u[0]
    solver.H_committed = new_H[0]
    solver.H.vec.FV().NumPy()[:] = new_H[0]
    out = []
    if solver.alpha is not None:
        solver.alpha_committed = a_carriers[-1, "alpha_committed"].vec.FV().NumPy().copy()
    H_next = iter(new_H[1:])
    for k, st in enumerate(states):
        new = {"u": new_u[k + 1]}
        if "H" in st:
            new["H"] = next(H_next)
        if "load" in st:
            new["load"] = np.array(st["load"])
        for key in ("alpha", "alpha_committed"):
            if (k, key) in a_carriers:
                new[key] = a_carriers[k, key].vec.FV().NumPy().copy()
        out.append(new)
    record = RefinementRecord(int(marked.sum()), ne_old, mesh.ne, dofs_old, solver.fes_u.ndof,
                              np.flatnonzero(marked).astype(np.int64))
    return record, out


def _refine_mesh(solver, marked: np.ndarray, before=None) -> np.ndarray:
    """Bisect the marked elements of the solver's mesh (NGSolve), curve it again at its order, let
    a density given per element follow the parents, and bring the solver to the new mesh
    (:meth:`~ngtmc.discrete.solver.Solver.mesh_changed`). Returns the ancestor of every new element in the
    mesh before (:func:`_ancestors`). The one place where a run's mesh is refined."""
    mesh = solver.mesh
    ne_old = mesh.ne
    scene = solver.scene
    per_element_density = scene.density is not None and not isinstance(scene.density, Mapping)
    rho_old = solver.rho.vec.FV().NumPy().copy()
    curve = mesh.GetCurveOrder()
    for el in mesh.Elements(ngs.VOL):
        mesh.SetRefinementFlag(el, bool(marked[el.nr]))
    if before is None and _prisms(mesh):
        before = ngs.Mesh(mesh.ngmesh.Copy())
    mesh.Refine()
    if curve > 1:
        mesh.Curve(curve)
    anc = _ancestors(mesh, ne_old, before)
    if per_element_density:
        scene.density = rho_old[anc]
    solver.mesh_changed()
    return anc


def replay(solver, elements: list) -> None:
    """Refine the solver's mesh as a run did: ``elements[k]`` are the numbers of the elements
    marked in its k-th refinement (:attr:`RefinementRecord.elements`). The mesh must be the run's
    initial one (a fresh solver of the same scene); NGSolve's bisection is deterministic, so the
    mesh, its element numbers and the dof numbering come out as in the run, and a state of the run
    (:meth:`~ngtmc.discrete.solver.Solver.get_state`) fits. Field values are not transferred: the caller
    sets the state afterwards. Raises ValueError when the marks do not fit the mesh."""
    if not _prisms(solver.mesh):
        _carrier_space(solver)   # made on the first level, as in the run, for the refinements to come
    for k, idx in enumerate(elements):
        idx = np.asarray(idx, dtype=np.int64)
        ne = solver.mesh.ne
        if idx.size and (idx.min() < 0 or idx.max() >= ne):
            raise ValueError(f"refinement {k + 1} of the recorded run marks element {int(idx.max())}, but the mesh "
                             f"has {ne} elements: the recorded refinements do not belong to this mesh")
        marked = np.zeros(ne, dtype=bool)
        marked[idx] = True
        _refine_mesh(solver, marked)
