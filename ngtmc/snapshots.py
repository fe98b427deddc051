"""Field snapshots of one case of a run: u and alpha at the vertices (and rho per triangle) at the
first accepted step at or past each chosen load, for ``snapshots.npz`` and the ParaView series in
``vtk/`` (format: ``docs/run-directory.md``). Units: mm for coordinates, loads and displacements.
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
    """Fields of one case at the first accepted step at or past each chosen load."""

    def __init__(self, case: Case, solver, vtk_dir: Path | None):
        self.case = case
        self.targets = [float(x) for x in case.snapshot_loads]
        self.pending = list(range(len(self.targets)))
        self.loads: list[float] = []
        self.steps: list[int] = []
        self.u: list[np.ndarray] = []
        self.alpha: list[np.ndarray] = []
        self.solver = solver
        self.vtk_dir = vtk_dir
        mesh = solver.mesh
        self.nv = mesh.nv
        self.dim = mesh.dim
        ng = mesh.ngmesh
        self.vertices = np.asarray(ng.Coordinates(), dtype=float)[:, :self.dim].copy()
        if self.dim == 2:
            tri = ng.Elements2D().NumPy()["nodes"][:, :3].astype(np.int64) - 1
        else:
            # boundary triangles of the 3D mesh
            tri = ng.Elements2D().NumPy()["nodes"][:, :3].astype(np.int64) - 1
        self.triangles = tri
        rho = solver.rho.vec.FV().NumPy().copy()
        self.rho = rho if self.dim == 2 else np.ones(len(tri))
        self._vtk = None

    def restore(self, data: dict):
        self.loads = list(np.asarray(data["loads"], dtype=float))
        self.steps = list(np.asarray(data["steps"], dtype=int))
        self.u = list(np.asarray(data["u"], dtype=float))
        self.alpha = list(np.asarray(data["alpha"], dtype=float))
        self.pending = [int(i) for i in np.asarray(data["pending"], dtype=int)]

    def state(self) -> dict:
        k = len(self.loads)
        return {"loads": np.asarray(self.loads, dtype=float), "steps": np.asarray(self.steps, dtype=int),
                "u": np.asarray(self.u, dtype=float).reshape(k, self.nv, self.dim),
                "alpha": np.asarray(self.alpha, dtype=float).reshape(k, self.nv),
                "pending": np.asarray(self.pending, dtype=int)}

    def vertex_fields(self):
        s = self.solver
        u = np.stack([s.u.components[i].vec.FV().NumPy()[:self.nv].copy() for i in range(self.dim)], axis=1)
        if s.alpha is not None:
            a = s.alpha.vec.FV().NumPy()[:self.nv].copy()
        else:
            a = np.zeros(self.nv)
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
        self.loads.append(float(row["load"]))
        self.steps.append(int(row["step"]))
        self.u.append(u)
        self.alpha.append(a)
        self.write_vtk(len(self.loads) - 1, float(row["load"]))

    def arrays(self, name: str) -> dict:
        st = self.state()
        return {f"{name}__vertices": self.vertices, f"{name}__triangles": self.triangles,
                f"{name}__rho": self.rho, f"{name}__loads": st["loads"], f"{name}__steps": st["steps"],
                f"{name}__u": st["u"], f"{name}__alpha": st["alpha"]}

    def write_vtk(self, k: int, load: float):
        """Write snapshot ``k`` (the solver's current state) as ``vtk/<case>_<k>.vtu`` (fields of
        :mod:`ngtmc.vtk`) and update the series ``vtk/<case>.pvd``."""
        if self.vtk_dir is None:
            return
        try:
            if self._vtk is None:
                self._vtk = VtkWriter(self.solver)
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
