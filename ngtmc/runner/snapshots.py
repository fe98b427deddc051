"""Field snapshots of one case of a run: u and alpha at the vertices (and rho per triangle) at the
first accepted step at or past each chosen load, each on the mesh it was taken on, for
``snapshots.npz`` and the ParaView series in ``vtk/`` (format: ``docs/run-directory.md``).
Units: mm for coordinates, loads and displacements.

In 3D the triangles are those of the surface of the solid (the elements with rho >= 1/2;
quadrilateral faces split in two), so that a drawing shows the bodies and not the void around
them; a case with a ``section`` plane also samples alpha on a grid in that plane (the crack
front of a 3D crack).
"""
from __future__ import annotations

from pathlib import Path
import sys

import numpy as np

from ngtmc.study import Case
from ngtmc.runner.vtk import VtkWriter, write_pvd

__all__ = ["Snapshots"]


class Snapshots:
    """Fields of one case at the first accepted step at or past each chosen load.

    The mesh may change during the run (adaptive refinement, :mod:`ngtmc.adapt`): each snapshot
    keeps the mesh it was taken on (:attr:`meshes`, :attr:`mesh_of`), and the files then hold one
    group of snapshots per mesh (:meth:`arrays`)."""

    def __init__(self, case: Case, sim, vtk_dir: Path | None):
        self.case = case
        self.targets = [float(x) for x in case.snapshot_loads]
        self.pending = list(range(len(self.targets)))
        self.loads: list[float] = []
        self.steps: list[int] = []
        self.u: list[np.ndarray] = []
        self.alpha: list[np.ndarray] = []
        #: meshes the snapshots were taken on: dicts of vertices (nv, d) mm, triangles (nt, 3), rho (nt,)
        self.meshes: list[dict] = []
        #: index into :attr:`meshes` of each snapshot
        self.mesh_of: list[int] = []
        #: the :class:`~ngtmc.simulation.loop.Simulation` whose solver's fields are taken (a run refined
        #: by remeshing moves to a new solver, :mod:`ngtmc.adapt.remesh`)
        self.sim = sim
        self.vtk_dir = vtk_dir
        self.dim = sim.solver.mesh.dim
        self._vtk = None
        self._vtk_mesh = None
        #: 3D with Case.section: the sampling grid (dict of plane, axes, coordinates) and alpha on it
        self._section_grid = None
        self.section: list[np.ndarray] = []
        self._current = None   # (mesh key, current_mesh()) of the solver's mesh

    @property
    def solver(self):
        """The simulation's solver now."""
        return self.sim.solver

    def current_mesh(self) -> dict:
        """Vertices (mm), triangles (2D; boundary triangles in 3D) and pseudo-density per triangle
        of the solver's mesh now; made once per mesh (a refinement changes the solver's
        ``mesh_generation``)."""
        key = (id(self.solver.mesh), self.solver.mesh_generation)
        if self._current is None or self._current[0] != key:
            self._current = (key, mesh_drawing(self.solver.mesh, self.solver.rho.vec.FV().NumPy().copy()))
        return self._current[1]

    def _mesh_index(self) -> int:
        """Index of the solver's current mesh in :attr:`meshes` (added if it is new)."""
        if self.meshes and self._is_current(self.meshes[-1]):
            return len(self.meshes) - 1
        self.meshes.append(self.current_mesh())
        return len(self.meshes) - 1

    def _is_current(self, m: dict) -> bool:
        """Whether the mesh drawing ``m`` is that of the solver's mesh now (the one comparison of
        drawings: :meth:`_mesh_index` and :meth:`state`). A refined run's snapshots
        may all lie on an earlier mesh: a checkpoint then keeps their mesh (:meth:`state`), since
        :meth:`restore` of the short format takes the solver's mesh."""
        c = self.current_mesh()
        return m is c or all(m[k].shape == c[k].shape and np.array_equal(m[k], c[k]) for k in c)

    @property
    def changing_mesh(self) -> bool:
        """The snapshots were taken on more than one mesh."""
        return len(self.meshes) > 1

    def restore(self, data: dict, recorded: dict | None = None):
        """Take the snapshots of :meth:`state` (from a checkpoint). ``recorded``: the checkpoint's
        copy of :meth:`arrays` (keys without the ``snaparr__`` prefix), whose mesh is taken where
        a checkpoint of the short format holds snapshots of another mesh than the solver's now
        (written by a version before 2026-12-05, after a refinement, while every snapshot lay on
        the mesh before it). Raises ValueError where no recorded mesh fits them."""
        self.loads = list(np.asarray(data["loads"], dtype=float))
        self.steps = list(np.asarray(data["steps"], dtype=int))
        self.pending = [int(i) for i in np.asarray(data["pending"], dtype=int)]
        k = len(self.loads)
        if "mesh_of" in data:   # one mesh per snapshot group
            self.mesh_of = [int(i) for i in np.asarray(data["mesh_of"], dtype=int)]
            self.meshes = [{f: np.asarray(data[f"{f}__{j}"]) for f in ("vertices", "triangles", "rho")}
                           for j in range(max(self.mesh_of, default=-1) + 1)]
            self.u = [np.asarray(data[f"u__{i}"], dtype=float) for i in range(k)]
            self.alpha = [np.asarray(data[f"alpha__{i}"], dtype=float) for i in range(k)]
        else:
            self.u = list(np.asarray(data["u"], dtype=float))
            self.alpha = list(np.asarray(data["alpha"], dtype=float))
            self.meshes = [self._mesh_of_short_format(recorded)] if k else []
            self.mesh_of = [0] * k
        if "section_alpha" in data:
            self.section = list(np.asarray(data["section_alpha"], dtype=float))

    def _mesh_of_short_format(self, recorded: dict | None) -> dict:
        """The mesh of snapshots restored from the short format (:meth:`restore`): the solver's,
        or, where their number of vertices is not the solver's, the recorded one that fits."""
        mesh = self.current_mesh()
        nv = len(self.alpha[0])
        if nv == len(mesh["vertices"]):
            return mesh
        keys = {f: f"{self.case.name}__{f}" for f in ("vertices", "triangles", "rho")}
        if recorded and all(v in recorded for v in keys.values()) and len(recorded[keys["vertices"]]) == nv:
            return {f: np.asarray(recorded[v]) for f, v in keys.items()}
        raise ValueError(f"case {self.case.name!r}: the checkpoint's snapshots lie on a mesh of {nv} vertices, the "
                         f"run's mesh now has {len(mesh['vertices'])}, and the checkpoint keeps no drawing of "
                         "theirs; start a new run")

    def state(self) -> dict:
        """Arrays of the snapshots taken so far (for a checkpoint; :meth:`restore` reads them)."""
        k = len(self.loads)
        out = {"loads": np.asarray(self.loads, dtype=float), "steps": np.asarray(self.steps, dtype=int),
               "pending": np.asarray(self.pending, dtype=int)}
        if not self.changing_mesh and (not self.meshes or self._is_current(self.meshes[0])):
            out["u"], out["alpha"] = self._stacked()
            if self.section:
                out["section_alpha"] = np.asarray(self.section, dtype=float)
            return out   # the mesh is the solver's (restore takes it from there)
        out["mesh_of"] = np.asarray(self.mesh_of, dtype=int)
        for j, m in enumerate(self.meshes):
            out.update({f"{f}__{j}": v for f, v in m.items()})
        for i in range(k):
            out[f"u__{i}"] = self.u[i]
            out[f"alpha__{i}"] = self.alpha[i]
        if self.section:
            out["section_alpha"] = np.asarray(self.section, dtype=float)
        return out

    def _stacked(self) -> tuple:
        """u (k x vertices x dim, mm) and alpha (k x vertices) of snapshots taken on one mesh."""
        k = len(self.loads)
        nv = len(self.meshes[0]["vertices"]) if self.meshes else 0
        return (np.asarray(self.u, dtype=float).reshape(k, nv, self.dim),
                np.asarray(self.alpha, dtype=float).reshape(k, nv))

    def vertex_fields(self):
        s = self.solver
        nv = s.mesh.nv
        u = np.stack([s.u.components[i].vec.FV().NumPy()[:nv].copy() for i in range(self.dim)], axis=1)
        if s.alpha is not None:
            a = s.alpha.vec.FV().NumPy()[:nv].copy()
        else:
            a = np.zeros(nv)
        return u, a

    def maybe_take(self, prev_load: float, row: dict, final: bool = False):
        load = float(row["load"])
        hit = []
        for i in self.pending:
            x = self.targets[i]
            if (prev_load - x) * (load - x) <= 0.0 and load != prev_load or abs(load - x) <= 1e-12 * max(1.0, abs(x)):
                hit.append(i)
            else:
                break  # targets are taken in the order given
        if hit:
            self.pending = [i for i in self.pending if i not in hit]
        if hit or (final and (not self.steps or self.steps[-1] != int(row["step"]))):
            self.take(row)

    def take(self, row: dict):
        if self.case.section is not None and self.dim == 3:   # the grid does not depend on the mesh
            self.section.append(self.section_values())
        u, a = self.vertex_fields()
        self.mesh_of.append(self._mesh_index())
        self.loads.append(float(row["load"]))
        self.steps.append(int(row["step"]))
        self.u.append(u)
        self.alpha.append(a)
        self.write_vtk(len(self.loads) - 1, float(row["load"]))

    def groups(self) -> list[list[int]]:
        """The snapshots in groups of consecutive ones on the same mesh (one group when the mesh
        never changed)."""
        out: list[list[int]] = []
        for i, j in enumerate(self.mesh_of):
            if out and self.mesh_of[out[-1][-1]] == j:
                out[-1].append(i)
            else:
                out.append([i])
        return out

    def arrays(self, name: str) -> dict:
        """The case's entries of ``snapshots.npz`` (``docs/run-directory.md``): keys
        ``{name}__{field}`` on one mesh; when the mesh changed, one group per mesh, keys
        ``{name}@{g}__{field}`` with g = 1, 2, ... in the order of the loads."""
        groups = self.groups()
        if not self.changing_mesh:
            u, alpha = self._stacked()
            m = self.meshes[0] if self.meshes else self.current_mesh()
            out = {f"{name}__vertices": m["vertices"], f"{name}__triangles": m["triangles"],
                   f"{name}__rho": m["rho"], f"{name}__loads": np.asarray(self.loads, dtype=float),
                   f"{name}__steps": np.asarray(self.steps, dtype=int), f"{name}__u": u, f"{name}__alpha": alpha}
            out.update(self._section_arrays(f"{name}__", range(len(self.loads))))
            return out
        out = {}
        for g, idx in enumerate(groups, start=1):
            m = self.meshes[self.mesh_of[idx[0]]]
            key = f"{name}@{g}__"
            out.update({key + "vertices": m["vertices"], key + "triangles": m["triangles"], key + "rho": m["rho"],
                        key + "loads": np.asarray([self.loads[i] for i in idx], dtype=float),
                        key + "steps": np.asarray([self.steps[i] for i in idx], dtype=int),
                        key + "u": np.asarray([self.u[i] for i in idx], dtype=float),
                        key + "alpha": np.asarray([self.alpha[i] for i in idx], dtype=float)})
            out.update(self._section_arrays(key, idx))
        return out

    def _section_arrays(self, key: str, idx) -> dict:
        """The section entries (3D, ``case.section``) of the snapshots ``idx`` under the prefix
        ``key`` (``{case}__`` or ``{case}@{g}__``); empty without a section for every snapshot."""
        if not self.section or len(self.section) != len(self.loads):
            return {}
        g = self.section_grid()
        return {key + "section_plane": np.asarray([g["axis"], g["at"]], dtype=float), key + "section_c1": g["c1"],
                key + "section_c2": g["c2"],
                key + "section_alpha": np.asarray([self.section[i] for i in idx], dtype=float)}

    def section_grid(self) -> dict:
        """The sampling grid of ``case.section`` (3D): ``axis`` (0, 1, 2 for x, y, z), ``at`` (mm),
        and the coordinates ``c1``, ``c2`` (mm) along the other two axes in their order (y, z
        for an x plane), spanning the fracture regions' bounding box in steps of about 1/200 of
        its larger side."""
        if self._section_grid is None:
            axis_name, at = self.case.section
            axis = "xyz".index(axis_name)
            lo, hi = self.solver.fracture_box()
            others = [i for i in range(3) if i != axis]
            step = max(hi[i] - lo[i] for i in others) / 200.0
            c = [np.linspace(lo[i], hi[i], max(2, int(round((hi[i] - lo[i]) / step)) + 1)) for i in others]
            import re
            s = self.solver
            # 1 in the fracture regions, 0 elsewhere (alpha is defined there only)
            inside = s.mesh.MaterialCF({m: 1.0 for m in set(s.mesh.GetMaterials()) if re.fullmatch(s.regions.fracture_regex, m)},
                                       default=0.0) if s.alpha is not None else None
            self._section_grid = {"axis": axis, "at": float(at), "c1": c[0], "c2": c[1], "others": others,
                                  "fracture": inside}
        return self._section_grid

    def section_values(self) -> np.ndarray:
        """alpha on the section grid (n1, n2), NaN outside the fracture regions and the mesh."""
        g = self.section_grid()
        s = self.solver
        A, B = np.meshgrid(g["c1"], g["c2"], indexing="ij")
        xyz = [None, None, None]
        xyz[g["axis"]] = np.full(A.size, g["at"])
        xyz[g["others"][0]], xyz[g["others"][1]] = A.ravel(), B.ravel()
        out = np.full(A.size, np.nan)
        if s.alpha is None:
            return out.reshape(A.shape)
        mp = s.mesh(*xyz)
        inside = np.nonzero(mp["nr"] >= 0)[0]
        if inside.size:
            sub = mp[inside]
            keep = np.asarray(g["fracture"](sub)).ravel() > 0.5
            vals = np.asarray(s.alpha(sub)).ravel()
            out[inside[keep]] = vals[keep]
        return out.reshape(A.shape)

    def write_vtk(self, k: int, load: float):
        """Write snapshot ``k`` (the solver's current state) as ``vtk/<case>_<k>.vtu`` (fields of
        :mod:`ngtmc.runner.vtk`) and update the series ``vtk/<case>.pvd``."""
        if self.vtk_dir is None:
            return
        try:
            if self._vtk is None or self._vtk_mesh != self.mesh_of[k]:   # one writer per mesh
                self._vtk = VtkWriter(self.solver)
                self._vtk_mesh = self.mesh_of[k]
            self._vtk.write(self.vtk_dir / f"{self.case.name}_{k:04d}.vtu")
            self.write_pvd()
        except Exception as e:  # VTK output is a convenience: never let it kill a run
            print(f"[ngtmc] VTK output failed: {e}", file=sys.stderr)

    def write_pvd(self):
        """The series ``vtk/<case>.pvd`` of the snapshots written so far, the load (mm) as time."""
        if self.vtk_dir is None:
            return
        files = [(load, f"{self.case.name}_{k:04d}.vtu") for k, load in enumerate(self.loads)]
        write_pvd(self.vtk_dir / f"{self.case.name}.pvd", [(load, f) for load, f in files if (self.vtk_dir / f).exists()])


def mesh_drawing(mesh, rho_el: np.ndarray) -> dict:
    """What a snapshot draws of ``mesh`` with the pseudo-density ``rho_el`` per element: vertices
    (nv, d) in mm, triangles (nt, 3) (2D: the elements; 3D: the surface of the solid,
    :func:`solid_surface`) and rho per triangle."""
    ng = mesh.ngmesh
    vertices = np.asarray(ng.Coordinates(), dtype=float)[:mesh.nv, :mesh.dim].copy()
    if mesh.dim == 3:
        tri, rho = solid_surface(mesh, rho_el)
        return {"vertices": vertices, "triangles": tri, "rho": rho}
    tri = ng.Elements2D().NumPy()["nodes"][:, :3].astype(np.int64) - 1
    return {"vertices": vertices, "triangles": tri, "rho": rho_el}


# faces of each volume element type, as local vertex numbers (quadrilaterals as 4)
_FACES = {4: [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)],
          6: [(0, 1, 2), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)],
          8: [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
          5: [(0, 1, 2, 3), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)]}


def solid_surface(mesh, rho: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Surface triangles (n, 3) of the elements of a 3D mesh with rho >= 1/2, and the rho of the
    element each bounds: the faces that belong to exactly one such element, quadrilaterals split
    in two. Units: none (vertex numbers)."""
    import ngsolve as ngs
    seen: dict[tuple, tuple] = {}
    for el in mesh.Elements(ngs.VOL):
        r = float(rho[el.nr])
        if r < 0.5:
            continue
        v = [x.nr for x in el.vertices]
        for f in _FACES[len(v)]:
            face = tuple(v[i] for i in f)
            key = tuple(sorted(face))
            if key in seen:
                seen[key] = None
            else:
                seen[key] = (face, r)
    tri, rr = [], []
    for item in seen.values():
        if item is None:
            continue
        face, r = item
        tri.append(face[:3])
        rr.append(r)
        if len(face) == 4:
            tri.append((face[0], face[2], face[3]))
            rr.append(r)
    return np.asarray(tri, dtype=np.int64).reshape(-1, 3), np.asarray(rr, dtype=float)
