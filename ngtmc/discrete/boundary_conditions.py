"""The displacement's boundary conditions and reactions: which dofs each support and load
prescribes, their values at a load factor, and the force each load carries.

:class:`BoundaryConditions` is a base of :class:`ngtmc.discrete.solver.Solver`: it works on the solver's
displacement space ``fes_u``, mesh, scene and free-dof masks (``_dir_np``), and is built by
:meth:`_build_loads` once the space exists (again after a refinement).

Units: displacements mm, load factor lambda mm (or the scene's load unit), forces N (for the
scene thickness in 2D).
"""
from __future__ import annotations

import re

import numpy as np
import ngsolve as ngs

from ngtmc.scene import DisplacementLoad, Point, Traction

__all__ = ["BoundaryConditions"]


class BoundaryConditions:
    """Dirichlet dofs, load values and reactions of :class:`ngtmc.discrete.solver.Solver` (a base class)."""

    def _vertex_dof(self, v: int, c: int) -> int:
        """The dof of displacement component ``c`` at vertex ``v``."""
        return int(self.fes_u.GetDofNrs(ngs.NodeId(ngs.VERTEX, v))[c])

    def _boundary_dofs(self, boundary: str, c: int) -> np.ndarray:
        """Boolean mask of the dofs of component ``c`` on the boundaries matching ``boundary``."""
        mask = np.zeros(self.fes_u.ndof, dtype=bool)
        rng = self.fes_u.Range(c)
        for el in self.fes_u.Elements(ngs.BND):
            if re.fullmatch(boundary, el.mat):
                dofs = np.array([k for k in el.dofs if k >= 0], dtype=int)
                mask[dofs[(dofs >= rng.start) & (dofs < rng.stop)]] = True
        # a distributed mesh: a rank may share a dof of the boundary without its boundary element
        return self.ranks.union_mask(mask, self.u.vec)

    def _build_loads(self):
        """Per load: the dofs it prescribes (mask), its unit field (linear loads) and its traction form."""
        sc, d, mesh = self.scene, self.dim, self.mesh
        self._loads = []
        self._tractions = False
        self._f_ext = None
        self._aux = None
        for ld in sc.loads:
            b = ld.boundary
            rec = {"load": ld, "name": ld.label, "kind": type(ld).__name__}
            if isinstance(ld, Traction):
                self._tractions = True
                t = ld.vector(d)
                v = self.fes_u.TestFunction()
                f = ngs.LinearForm(self.fes_u)
                f += ngs.InnerProduct(t, v) * ngs.ds(definedon=mesh.Boundaries(b))
                f.Assemble()
                rec["f"] = f.vec.FV().NumPy().copy()
                total = np.array([ngs.Integrate(t[i], mesh, definedon=mesh.Boundaries(b)) for i in range(d)])
                norm = float(np.linalg.norm(total))
                if norm == 0.0:  # self-balanced traction: scale by int |t| ds instead
                    norm = float(ngs.Integrate(ngs.Norm(t), mesh, definedon=mesh.Boundaries(b)))
                rec["total"] = norm
                self._loads.append(rec)
                continue
            comps = ld.held_components(d)
            mask = np.zeros(self.fes_u.ndof, dtype=bool)
            if isinstance(b, Point):
                vx = b.vertex(mesh)
                rec["vertex"] = vx
                for c in comps:
                    mask[self._vertex_dof(vx, c)] = True
            else:
                for c in comps:
                    mask |= self._boundary_dofs(b, c)
            rec["mask"] = mask & self._dir_np
            # the dofs the load moves (a DisplacementLoad's held tangential components excluded)
            if isinstance(ld, DisplacementLoad):
                moving = np.zeros(self.fes_u.ndof, dtype=bool)
                if isinstance(b, Point):
                    moving[self._vertex_dof(vx, ld.component)] = True
                else:
                    moving |= self._boundary_dofs(b, ld.component)
                rec["moving"] = moving & self._dir_np
            else:
                rec["moving"] = rec["mask"]
            gf = ngs.GridFunction(self.fes_u)
            if isinstance(ld, DisplacementLoad):
                if isinstance(b, Point):
                    gf.vec.FV().NumPy()[self._vertex_dof(rec["vertex"], ld.component)] = ld.sign
                else:  # as before fields existed: the direction sign on the loaded component
                    gf.components[ld.component].Set(ld.sign, definedon=mesh.Boundaries(b))
                rec["unit"] = gf.vec.FV().NumPy().copy()
            elif not ld.is_callable:
                self._set_field(gf, rec, ld.field)
                rec["unit"] = np.where(rec["mask"], gf.vec.FV().NumPy(), 0.0)
            else:
                rec["unit"] = None  # evaluated at each lambda
            self._loads.append(rec)
        if self._tractions:
            self._f_ext = self.u.vec.CreateVector()
            self._f_ext.FV().NumPy()[:] = sum(r["f"] for r in self._loads if "f" in r)
        #: the dofs that the displacement loads move: their residual is the reaction that sets the
        #: equilibrium scale of the Newton solvers (:meth:`equilibrium_scale`)
        self._moved_np = np.zeros(self.fes_u.ndof, dtype=bool)
        for rec in self._loads:
            if "moving" in rec:
                self._moved_np |= rec["moving"]

    def _set_field(self, gf, rec, cf):
        """Write the vector CF ``cf`` into the prescribed components of ``gf`` on the load's boundary or vertex."""
        ld, mesh, d = rec["load"], self.mesh, self.dim
        if "vertex" in rec:
            x = np.asarray(mesh.ngmesh.Coordinates())[rec["vertex"], :d]
            val = np.asarray(cf(mesh(*x))).ravel()
            for c in ld.held_components(d):
                gf.vec.FV().NumPy()[self._vertex_dof(rec["vertex"], c)] = val[c]
            return
        for c in ld.held_components(d):
            gf.components[c].Set(cf[c], definedon=mesh.Boundaries(ld.boundary))

    def _callable_values(self, rec, lam: float) -> np.ndarray:
        """Dirichlet values (full dof vector, zero off the load's dofs) of a callable field at ``lam``:
        interpolated at the boundary's vertices and edge midpoints (order 2), then projected."""
        ld, mesh, d = rec["load"], self.mesh, self.dim
        gf = ngs.GridFunction(self.fes_u)
        if "vertex" in rec:
            x = np.asarray(mesh.ngmesh.Coordinates())[[rec["vertex"]], :d]
            val = ld.values(x, lam, d)[:, 0]
            for c in ld.held_components(d):
                gf.vec.FV().NumPy()[self._vertex_dof(rec["vertex"], c)] = val[c]
            return np.where(rec["mask"], gf.vec.FV().NumPy(), 0.0)
        if "aux" not in rec:
            rec["aux"] = self._aux_interpolation(ld.boundary)
        h, vdofs, vpts, edofs, eends, epts, bubble = rec["aux"]
        fv = ld.values(vpts, lam, d)
        fe = ld.values(epts, lam, d) if len(epts) else np.zeros((d, 0))
        aux = ngs.GridFunction(h)
        a = aux.vec.FV().NumPy()
        cfs = []
        for c in range(d):
            a[:] = 0.0
            a[vdofs] = fv[c]
            if len(edofs):
                a[edofs] = (fe[c] - 0.5 * (a[eends[:, 0]] + a[eends[:, 1]])) / bubble
            g = ngs.GridFunction(h)
            g.vec.data = aux.vec
            cfs.append(g)
        self._set_field(gf, rec, ngs.CF(tuple(cfs)))
        return np.where(rec["mask"], gf.vec.FV().NumPy(), 0.0)

    def _aux_interpolation(self, boundary: str):
        """Order-2 H1 space and the vertex / edge-midpoint data of a boundary for callable fields."""
        mesh, d = self.mesh, self.dim
        h = ngs.H1(mesh, order=2)
        coords = np.asarray(mesh.ngmesh.Coordinates())[:, :d]
        vs, es = set(), set()
        for el in mesh.Elements(ngs.BND):
            if re.fullmatch(boundary, el.mat):
                vs.update(v.nr for v in el.vertices)
                es.update(e.nr for e in el.edges)
        vs, es = sorted(vs), sorted(es)
        vdofs = np.array([h.GetDofNrs(ngs.NodeId(ngs.VERTEX, v))[0] for v in vs], dtype=int)
        edofs = np.array([h.GetDofNrs(ngs.NodeId(ngs.EDGE, e))[0] for e in es], dtype=int)
        ends = np.array([[v.nr for v in mesh.edges[e].vertices] for e in es], dtype=int).reshape(-1, 2)
        eends = np.array([[h.GetDofNrs(ngs.NodeId(ngs.VERTEX, v))[0] for v in pair] for pair in ends],
                         dtype=int).reshape(-1, 2)
        epts = 0.5 * (coords[ends[:, 0]] + coords[ends[:, 1]]) if len(es) else np.zeros((0, d))
        bubble = 1.0
        if len(es):  # value of the order-2 edge bubble at its midpoint (-1/8 for NGSolve's basis)
            g = ngs.GridFunction(h)
            g.vec.FV().NumPy()[edofs[0]] = 1.0
            bubble = float(g(mesh(*epts[0])))
        return h, vdofs, coords[vs], edofs, eends, epts, bubble

    def load_values(self, rec, lam: float) -> np.ndarray:
        """Dirichlet values (mm) of one displacement load at ``lam``, on its dofs (zero elsewhere)."""
        if rec["unit"] is not None:
            return lam * rec["unit"]
        return self._callable_values(rec, lam)

    def dirichlet_target(self, lam: float) -> np.ndarray:
        """Values of every Dirichlet dof at load ``lam`` (mm): 0 for supports, each displacement load's
        field on its dofs (a vertex shared by two loads takes the later load's value)."""
        target = np.zeros(self.fes_u.ndof)
        for rec in self._loads:
            if "mask" in rec:
                target[rec["mask"]] = self.load_values(rec, lam)[rec["mask"]]
        return target

    def _record_of(self, name: str | None):
        name = self.scene.force_load.label if name is None else name
        for rec in self._loads:
            if rec["name"] == name:
                return rec
        raise KeyError(f"no load named {name!r}; the loads are {[r['name'] for r in self._loads]}")

    def reaction_weight(self, name: str | None = None, lam: float | None = None) -> np.ndarray:
        """d u_D / d lambda of the displacement load ``name`` (default the scene's force load) at load
        ``lam`` (default the current load), dimensionless: the vector whose product with the residual
        is that load's reaction. Zero for a traction load."""
        rec = self._record_of(name)
        if "mask" not in rec:
            return np.zeros(self.fes_u.ndof)
        if rec["unit"] is not None:
            return rec["unit"]
        lam = self.load if lam is None else float(lam)
        dl = 1e-6 * max(1.0, abs(lam))
        return (self._callable_values(rec, lam + dl) - self._callable_values(rec, lam - dl)) / (2 * dl)

    # ================================================================= reaction
    def reaction(self, reuse_residual: bool = False) -> float:
        """Reaction of the force load (``Scene.force_from``, default the first load), N (for the scene
        thickness): see :meth:`reactions`."""
        return self.reactions(reuse_residual)[self.scene.force_load.label]

    def reactions(self, reuse_residual: bool = False) -> dict:
        """Force of every load, by name, N (for the scene thickness in 2D).

        A displacement load: <r(u), d u_D / d lambda> with r the residual of the displacement
        equation (for the uniform load, the GridFunction equal to the direction sign on the loaded
        component of the loaded boundary; correct for any order, unlike summing residual
        entries); positive when the structure resists the imposed motion. A traction load: the
        applied force lambda |int t ds|. ``reuse_residual=True`` reuses the residual of the last
        converged Newton solve (valid only if neither u nor alpha changed since)."""
        if not (reuse_residual and self._r_valid):
            self._lam_ext = self.load
            self.a_u.Apply(self.u.vec, self._r)
        out = {}
        for rec in self._loads:
            if "f" in rec:
                out[rec["name"]] = self.load * rec["total"] * self.thickness
            else:
                out[rec["name"]] = self.ranks.dot_array(self._r, self.reaction_weight(rec["name"])) * self.thickness
        return out

    def residual_norm(self, after_reactions: bool = False) -> float:
        """Norm of the displacement equation's residual on the free dofs at the current state, N
        per unit thickness in 2D: the equilibrium that the Newton tolerance states
        (``NewtonOptions``). ``after_reactions``: reuse the residual that :meth:`reactions` has
        just formed for the current state."""
        if not after_reactions:
            self._lam_ext = self.load
            self.a_u.Apply(self.u.vec, self._r)
        return self.ranks.masked_norm(self._r, self._free_np)

    def reaction_vector(self) -> np.ndarray:
        """The nodal reactions of the current state: the residual of the displacement equation on
        the Dirichlet dofs (supports, loads, vertex conditions), zero on the free dofs, N (for the
        scene thickness in 2D), one entry per displacement dof of ``fes_u`` (NGSolve's order: all
        x components, then y (then z) for the vertex dofs' VectorH1 layout). A copy."""
        self._lam_ext = self.load
        self.a_u.Apply(self.u.vec, self._r)
        out = self._r.FV().NumPy().copy() * self.thickness
        out[self._free_np] = 0.0
        return out

    def load_displacements(self) -> dict:
        """Work-conjugate displacement of every traction load, by name, mm: int t.u ds / |int t ds|."""
        uN = self.u.vec.FV().NumPy()
        return {r["name"]: float(np.dot(r["f"], uN)) / r["total"] for r in self._loads if "f" in r}

    def equilibrium_scale(self, r, load: float) -> float:
        """The force scale (N) of :func:`meets` for this solver's iterate, whose residual is ``r``
        (an NGSolve vector), at the load ``load`` (mm): the norm of the reactions on the dofs that
        the displacement loads move, or of the tractions applied at ``load`` (force control) where
        that is larger. The supports' reactions are left out: a plane-strain slab's held u_z carry
        reactions that its 2D twin has no dofs for, and the two would converge differently."""
        scale = self.ranks.masked_norm(r, self._moved_np)
        if self._tractions:
            scale = max(scale, abs(load) * self.ranks.masked_norm(self._f_ext, self._free_np))
        return scale
