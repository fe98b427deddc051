"""Field snapshots of one case of a run: u and alpha at the vertices (and rho per triangle) at the
first accepted step at or past each chosen load, each on the mesh it was taken on, for
``snapshots.npz`` and the ParaView series in ``vtk/`` (format: ``docs/run-directory.md``).
Units: mm for coordinates, loads and displacements.
"""
from __future__ import annotations

from pathlib import Path
import sys

import numpy as np

from .runfiles import write_atomic
from .study import Case
from .vtk import VtkWriter, write_pvd

__all__ = ["Snapshots"]


class Snapshots:
    """Fields of one case at the first accepted step at or past each chosen load.

    The mesh may change during the run (adaptive refinement, :mod:`ngtmc.adapt`): each snapshot
    keeps the mesh it was taken on (:attr:`meshes`, :attr:`mesh_of`), and the files then hold one
    group of snapshots per mesh (:meth:`arrays`)."""

    def __init__(self, case: Case, solver, vtk_dir: Path | None):
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
        self.solver = solver
        self.vtk_dir = vtk_dir
        self.dim = solver.mesh.dim
        self._vtk = None
        self._vtk_mesh = None

    def current_mesh(self) -> dict:
        """Vertices (mm), triangles (2D; boundary triangles in 3D) and pseudo-density per triangle
        of the solver's mesh now."""
        mesh = self.solver.mesh
        ng = mesh.ngmesh
        vertices = np.asarray(ng.Coordinates(), dtype=float)[:mesh.nv, :self.dim].copy()
        tri = ng.Elements2D().NumPy()["nodes"][:, :3].astype(np.int64) - 1
        rho = self.solver.rho.vec.FV().NumPy().copy() if self.dim == 2 else np.ones(len(tri))
        return {"vertices": vertices, "triangles": tri, "rho": rho}

    def _mesh_index(self) -> int:
        """Index of the solver's current mesh in :attr:`meshes` (added if it is new)."""
        m = self.current_mesh()
        if self.meshes:
            last = self.meshes[-1]
            if all(last[k].shape == m[k].shape and np.array_equal(last[k], m[k]) for k in m):
                return len(self.meshes) - 1
        self.meshes.append(m)
        return len(self.meshes) - 1

    @property
    def changing_mesh(self) -> bool:
        """The snapshots were taken on more than one mesh."""
        return len(self.meshes) > 1

    def restore(self, data: dict):
        """Take the snapshots of :meth:`state` (from a checkpoint)."""
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
            self.meshes = [self.current_mesh()] if k else []
            self.mesh_of = [0] * k

    def state(self) -> dict:
        """Arrays of the snapshots taken so far (for a checkpoint; :meth:`restore` reads them)."""
        k = len(self.loads)
        out = {"loads": np.asarray(self.loads, dtype=float), "steps": np.asarray(self.steps, dtype=int),
               "pending": np.asarray(self.pending, dtype=int)}
        if not self.changing_mesh:
            nv = len(self.meshes[0]["vertices"]) if self.meshes else 0
            out.update({"u": np.asarray(self.u, dtype=float).reshape(k, nv, self.dim),
                        "alpha": np.asarray(self.alpha, dtype=float).reshape(k, nv)})
            return out   # the mesh is the solver's (restore takes it from there)
        out["mesh_of"] = np.asarray(self.mesh_of, dtype=int)
        for j, m in enumerate(self.meshes):
            out.update({f"{f}__{j}": v for f, v in m.items()})
        for i in range(k):
            out[f"u__{i}"] = self.u[i]
            out[f"alpha__{i}"] = self.alpha[i]
        return out

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
            st = self.state()
            m = self.meshes[0] if self.meshes else self.current_mesh()
            return {f"{name}__vertices": m["vertices"], f"{name}__triangles": m["triangles"],
                    f"{name}__rho": m["rho"], f"{name}__loads": st["loads"], f"{name}__steps": st["steps"],
                    f"{name}__u": st["u"], f"{name}__alpha": st["alpha"]}
        out = {}
        for g, idx in enumerate(groups, start=1):
            m = self.meshes[self.mesh_of[idx[0]]]
            key = f"{name}@{g}__"
            out.update({key + "vertices": m["vertices"], key + "triangles": m["triangles"], key + "rho": m["rho"],
                        key + "loads": np.asarray([self.loads[i] for i in idx], dtype=float),
                        key + "steps": np.asarray([self.steps[i] for i in idx], dtype=int),
                        key + "u": np.asarray([self.u[i] for i in idx], dtype=float),
                        key + "alpha": np.asarray([self.alpha[i] for i in idx], dtype=float)})
        return out

    def write_vtk(self, k: int, load: float):
        """Write snapshot ``k`` (the solver's current state) as ``vtk/<case>_<k>.vtu`` (fields of
        :mod:`ngtmc.vtk`) and update the series ``vtk/<case>.pvd``."""
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
