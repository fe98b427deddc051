"""Snapshots and ParaView files of a case on MPI ranks (``ngtmc run --mpi``): the fields of the
distributed mesh gathered on rank 0, in the numbering of the serial mesh the distribution started
from, so that ``snapshots.npz``, ``vtk/`` and the report are those of a serial run.

NGSolve numbers the vertices and elements of each rank's part of a distributed mesh on its own.
:class:`RankGather` matches them with the serial mesh once per case: a vertex by its coordinates
(the distribution copies them exactly), an element by its set of vertices. Every rank takes part
in every gather (the snapshots are taken at the same accepted steps on all ranks, those steps
being decided from reduced numbers), and only rank 0 keeps the fields and writes the files.

Units: mm for coordinates and displacements.
"""
from __future__ import annotations

import sys

import numpy as np
import ngsolve as ngs

from ngtmc.runner.snapshots import Snapshots, mesh_drawing
from ngtmc.runner.vtk import VtkGeometry, VtkWriter, vtu_bytes, write_vtu

__all__ = ["RankGather", "GatheredSnapshots"]


class RankGather:
    """Vertex and element fields of the ranks of ``comm`` (each on its part ``local_mesh`` of the
    distributed mesh) gathered on rank 0 in the numbering of ``serial_mesh`` (the mesh that was
    distributed; read on rank 0 only). Raises RuntimeError on rank 0 when the parts do not cover
    the serial mesh (every rank calls the constructor, so the others wait in the next gather)."""

    def __init__(self, local_mesh, serial_mesh, comm):
        self.comm = comm
        self.root = comm.rank == 0
        dim = local_mesh.dim
        coords = np.ascontiguousarray(np.asarray(local_mesh.ngmesh.Coordinates(), dtype=float)[:local_mesh.nv, :dim])
        elements = [[v.nr for v in el.vertices] for el in local_mesh.Elements(ngs.VOL)]
        parts = comm.gather((coords, elements), root=0)
        self.vertex_maps: list[np.ndarray] = []
        self.element_maps: list[np.ndarray] = []
        if not self.root:
            return
        self.nv, self.ne = serial_mesh.nv, serial_mesh.ne
        serial = np.ascontiguousarray(np.asarray(serial_mesh.ngmesh.Coordinates(), dtype=float)[:self.nv, :dim])
        vertex_of = {row.tobytes(): i for i, row in enumerate(serial)}
        element_of = {frozenset(v.nr for v in el.vertices): el.nr for el in serial_mesh.Elements(ngs.VOL)}
        seen_v = np.zeros(self.nv, dtype=bool)
        seen_e = np.zeros(self.ne, dtype=bool)
        for rank, (c, els) in enumerate(parts):
            try:
                vm = np.array([vertex_of[row.tobytes()] for row in c], dtype=np.int64)
                em = np.array([element_of[frozenset(int(vm[j]) for j in e)] for e in els], dtype=np.int64)
            except KeyError:
                raise RuntimeError(f"MPI rank {rank}: a vertex or element of its part of the mesh is not in the "
                                   "serial mesh; its fields cannot be gathered") from None
            seen_v[vm] = True
            seen_e[em] = True
            self.vertex_maps.append(vm)
            self.element_maps.append(em)
        if not (seen_e.all() and seen_v.all()):
            raise RuntimeError(f"the ranks' parts of the mesh cover {int(seen_e.sum())} of {self.ne} elements and "
                               f"{int(seen_v.sum())} of {self.nv} vertices of the serial mesh")

    def _gather(self, local: np.ndarray, maps: list[np.ndarray], n: int) -> np.ndarray | None:
        parts = self.comm.gather(np.asarray(local), root=0)
        if not self.root:
            return None
        out = np.zeros((n,) + parts[0].shape[1:], dtype=parts[0].dtype)
        for m, a in zip(maps, parts):
            out[m] = a
        return out

    def vertices(self, local: np.ndarray) -> np.ndarray | None:
        """A vertex field (first axis: this rank's vertices) on rank 0 in the serial numbering,
        else None. A vertex that several ranks share takes one of their values (equal, the field
        being cumulated)."""
        return self._gather(local, self.vertex_maps, getattr(self, "nv", 0))

    def elements(self, local: np.ndarray) -> np.ndarray | None:
        """An element field (first axis: this rank's volume elements) on rank 0 in the serial
        numbering, else None."""
        return self._gather(local, self.element_maps, getattr(self, "ne", 0))


class GatheredSnapshots(Snapshots):
    """:class:`~ngtmc.runner.snapshots.Snapshots` of a case on MPI ranks: every rank calls it alike; the
    fields are gathered on rank 0 (:class:`RankGather`), which keeps them and writes the ParaView
    files on the serial mesh (``serial_scene``, the scene before distribution). ``vtk_dir``:
    rank 0's (the others' is ignored)."""

    def __init__(self, case, sim, vtk_dir, comm, serial_scene):
        self.comm = comm
        self.root = comm.rank == 0
        self.serial_scene = serial_scene
        self.gather = RankGather(sim.solver.mesh, serial_scene.mesh, comm)
        vtk_on = comm.bcast(vtk_dir is not None, root=0)   # a collective decision
        super().__init__(case, sim, vtk_dir if self.root else None)
        self._vtk_on = vtk_on
        self._geometry = None

    def current_mesh(self) -> dict:
        """The serial mesh's drawing with the gathered density on rank 0, an empty one on the
        others; made at the first call, which every rank makes at the same point (a gather)."""
        if self._current is None:
            rho = self.gather.elements(self.solver.rho.vec.FV().NumPy().copy())
            empty = {"vertices": np.zeros((0, self.dim)), "triangles": np.zeros((0, 3), dtype=np.int64),
                     "rho": np.zeros(0)}
            self._current = (None, mesh_drawing(self.serial_scene.mesh, rho) if self.root else empty)
        return self._current[1]

    def vertex_fields(self):
        u, a = (self.gather.vertices(f) for f in super().vertex_fields())
        if not self.root:
            return np.zeros((0, self.dim)), np.zeros(0)
        return u, a

    def section_values(self) -> np.ndarray:
        """alpha on the section grid, each point from the rank whose part of the mesh holds it
        (NaN where none does)."""
        local = super().section_values()
        parts = self.comm.gather(local, root=0)
        if not self.root:
            return local
        out = np.full_like(local, np.nan)
        for p in parts:
            out = np.where(np.isnan(out), p, out)
        return out

    def write_vtk(self, k: int, load: float):
        """Snapshot ``k`` as ``vtk/<case>_<k>.vtu`` on the serial mesh: every rank evaluates the
        fields of :class:`~ngtmc.runner.vtk.VtkWriter` on its part, rank 0 writes them."""
        if not self._vtk_on:
            return
        if self._vtk is None:
            self._vtk = VtkWriter(self.solver, geometry=False)
        point = {name: self.gather.vertices(a) for name, a in self._vtk.point_data().items()}
        cell = {name: self.gather.elements(a) for name, a in self._vtk.cell_data().items()}
        if not self.root:
            return
        try:
            if self._geometry is None:
                self._geometry = VtkGeometry(self.serial_scene.mesh)
            write_vtu(self.vtk_dir / f"{self.case.name}_{k:04d}.vtu", vtu_bytes(self._geometry, point, cell))
            self.write_pvd()
        except Exception as e:  # VTK output is a convenience: never let it kill a run
            print(f"[ngtmc] VTK output failed: {e}", file=sys.stderr)

    def arrays(self, name: str) -> dict:
        """The case's entries of ``snapshots.npz`` on rank 0, {} on the others (every rank calls it:
        the first call may gather the mesh)."""
        self.current_mesh()
        return super().arrays(name) if self.root else {}
