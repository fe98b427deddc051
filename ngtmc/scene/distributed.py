"""One scene on several MPI ranks with NGSolve's own MPI: the distributed mesh, and the
reductions over ranks that the solver's decisions need.

Run a script under ``mpirun -n 3 python script.py`` (the PyPI wheels ``mpi4py`` and ``mpich``,
``pip install ngtmc[mpi]``): every rank builds the same scene, :func:`distribute` hands rank 0's
mesh out to the ranks, and :class:`ngtmc.Simulation` then runs on the distributed scene. NGSolve
gives rank 0 no elements, so 3 ranks compute on 2. The Newton systems are gathered and factorized
on rank 0 (``inverse="masterinverse"``).

What the solver must reduce (measured with NGSolve 6.2.2608, MPICH 5.0.2; each pinned by
``tests/test_mpi.py``):

* ``BilinearForm.Energy`` and ``ngs.Integrate`` of an integral (``cf * dx(...)``) return the
  rank's own part; ``ngs.Integrate(cf, mesh)`` of a coefficient function is summed over ranks;
* vector norms and ``ngs.InnerProduct`` are global; numpy views of vectors are the rank's own
  dofs, shared dofs on several ranks (a residual is "distributed": its parts add up);
* minima and maxima of numpy views, and every yes/no decision taken from them, are rank-local.

:class:`Ranks` is the one place these reductions live; on a serial mesh each of them is the
plain numpy expression the serial code has always used, so serial results do not change.

Supported so far: every scheme (the coupled Newton's systems gathered on rank 0 as well,
:mod:`ngtmc.coupled.linear`), displacement loads on boundaries,
supports, densities given per region, no adaptive refinement, no run folder from ``simulate``
(``out_dir``); the runner writes one from rank 0 (``ngtmc run --mpi``, ``run_study(mpi=True)``:
history, metadata, report and the snapshots gathered on rank 0; each rank checkpoints its part). :func:`check_supported` refuses
the rest clearly.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import ngsolve as ngs
from ngtmc.scene.conditions import DisplacementField, Point, Traction

__all__ = ["Ranks", "distribute", "is_distributed", "check_supported", "refuse_unsupported", "unsupported"]


def is_distributed(mesh) -> bool:
    """True when ``mesh`` (an ngsolve.Mesh) is spread over more than one MPI rank."""
    comm = getattr(mesh, "comm", None)    # not a mesh at all: Scene.check names it
    return comm is not None and comm.size > 1


class Ranks:
    """Reductions over the ranks of a mesh; on a serial mesh the serial numpy expressions."""

    def __init__(self, mesh):
        self.comm = mesh.comm
        #: True when the mesh is distributed over several ranks
        self.parallel = self.comm.size > 1
        self._work = None

    # ------------------------------------------------------------------ scalars
    def sum(self, value: float) -> float:
        """Sum of a rank's part over the ranks."""
        return self.comm.Sum(float(value)) if self.parallel else value

    def max(self, values, empty: float = -math.inf) -> float:
        """Largest entry of a rank's array (or scalar) over all ranks; ``empty`` for no entries."""
        a = np.asarray(values)
        local = float(a.max()) if a.size else empty
        return self.comm.Max(local) if self.parallel else local

    def min(self, values, empty: float = math.inf) -> float:
        """Smallest entry over all ranks; ``empty`` for no entries."""
        a = np.asarray(values)
        local = float(a.min()) if a.size else empty
        return self.comm.Min(local) if self.parallel else local

    def any(self, flag: bool) -> bool:
        """True when ``flag`` is true on some rank."""
        return self.comm.Max(1.0 if flag else 0.0) > 0.5 if self.parallel else bool(flag)

    def all(self, flag: bool) -> bool:
        """True when ``flag`` is true on every rank."""
        return self.comm.Min(1.0 if flag else 0.0) > 0.5 if self.parallel else bool(flag)

    def all_finite(self, values) -> bool:
        """True when every entry of a rank's array is finite, on every rank."""
        return self.all(bool(np.all(np.isfinite(values))))

    # ------------------------------------------------------------------ vectors
    def masked_norm(self, vec, mask: np.ndarray) -> float:
        """Euclidean norm of an NGSolve vector over the dofs where ``mask`` (a rank's numpy bool
        array) is True. Parallel: through a masked copy, whose norm NGSolve forms over ranks with
        each shared dof once."""
        if not self.parallel:
            return float(np.linalg.norm(vec.FV().NumPy()[mask]))
        w = self._scratch(vec)
        w.data = vec
        w.FV().NumPy()[~mask] = 0.0
        return float(w.Norm())

    def dot(self, a, b) -> float:
        """Inner product of two NGSolve vectors (either may be distributed)."""
        if not self.parallel:
            return float(np.dot(a.FV().NumPy(), b.FV().NumPy()))
        return float(ngs.InnerProduct(a, b))

    def dot_array(self, vec, weights: np.ndarray) -> float:
        """Inner product of an NGSolve vector with a rank's numpy array whose shared entries agree
        on every rank (a reaction weight, a Dirichlet field)."""
        if not self.parallel:
            return float(np.dot(vec.FV().NumPy(), weights))
        w = self._scratch(vec)
        w.SetParallelStatus(ngs.PARALLEL_STATUS.CUMULATED)
        w.FV().NumPy()[:] = weights
        return float(ngs.InnerProduct(vec, w))

    def norm_of(self, values: np.ndarray, like, start: int = 0) -> float:
        """Euclidean norm of a rank's numpy array whose shared entries agree on every rank, the
        entries of the dofs ``start`` .. ``start + len(values)`` of vectors like ``like`` (an NGSolve
        vector), each shared dof counted once."""
        if not self.parallel:
            return float(np.linalg.norm(values))
        w = like.CreateVector()
        w.SetParallelStatus(ngs.PARALLEL_STATUS.CUMULATED)
        wN = w.FV().NumPy()
        wN[:] = 0.0
        wN[start:start + len(values)] = values
        return float(w.Norm())

    def cumulated(self, vec, out):
        """``vec`` with each shared dof's full value on every rank (a residual's parts summed):
        ``out`` holds it on a distributed mesh; on a serial one, or when ``vec`` is cumulated
        already, ``vec`` itself is returned."""
        if not self.parallel or vec.GetParallelStatus() == ngs.PARALLEL_STATUS.CUMULATED:
            return vec
        out.data = vec
        out.Cumulate()
        return out

    def count(self, mask: np.ndarray, like) -> int:
        """Number of dofs where a consistent mask (the same on every rank that shares a dof) is
        True, each shared dof counted once (``like``: an NGSolve vector of the space)."""
        if not self.parallel:
            return int(np.count_nonzero(mask))
        w = like.CreateVector()
        w.SetParallelStatus(ngs.PARALLEL_STATUS.CUMULATED)
        w.FV().NumPy()[:] = mask
        return int(round(ngs.InnerProduct(w, w)))

    def union_mask(self, mask: np.ndarray, like) -> np.ndarray:
        """A rank's dof mask made consistent: True on every rank that shares a dof True on one
        (``like``: an NGSolve vector of the space, for its parallel dofs)."""
        if not self.parallel:
            return mask
        w = like.CreateVector()
        w.SetParallelStatus(ngs.PARALLEL_STATUS.DISTRIBUTED)
        w.FV().NumPy()[:] = mask
        w.Cumulate()
        return w.FV().NumPy() > 0.5

    def _scratch(self, vec):
        if self._work is None or len(self._work) != len(vec):
            self._work = vec.CreateVector()
        return self._work


def check_supported(scene, adapt=None, out_dir=None):
    """Raise NotImplementedError for what a distributed scene cannot do yet (module docstring);
    nothing for a serial scene."""
    if is_distributed(scene.mesh):
        refuse_unsupported(scene, adapt, out_dir)


def refuse_unsupported(scene, adapt=None, out_dir=None):
    """Raise NotImplementedError naming what of ``scene`` (and ``adapt``, ``out_dir``) a mesh
    distributed over MPI ranks cannot do yet (:func:`unsupported`), whether or not ``scene`` is
    distributed already (the runner asks before it distributes)."""
    what = unsupported(scene, adapt, out_dir)
    if what:
        raise NotImplementedError("on a mesh distributed over MPI ranks, ngtmc does not support yet: " + "; ".join(what)
                                  + " (docs/parallel.md)")


def unsupported(scene, adapt=None, out_dir=None) -> list:
    """What of ``scene`` (and ``adapt``, ``out_dir``) a distributed mesh cannot do yet, one phrase
    each (empty: all of it can)."""
    from collections.abc import Mapping
    what = []
    if adapt is not None:
        what.append("adaptive refinement (adapt=)")
    if out_dir is not None:
        what.append("a run folder (out_dir=; keep the run in memory and write from rank 0)")
    conds = list(scene.supports) + list(scene.loads)
    if any(isinstance(c.boundary, Point) for c in conds):
        what.append("Point supports and loads (vertex numbers are per rank)")
    if any(isinstance(ld, (Traction, DisplacementField)) for ld in scene.loads):
        what.append("Traction and DisplacementField loads")
    if scene.density is not None and not isinstance(scene.density, Mapping):
        what.append("a density given per element (element numbers are per rank; give it per region)")
    return what


def distribute(scene, comm=None, curve: int | None = None):
    """The scene on a mesh distributed over the ranks of ``comm`` (an mpi4py communicator; default
    COMM_WORLD). Every rank calls it with the same scene; rank 0's mesh is the one handed out
    (NGSolve gives rank 0 no elements). ``curve``: the order to curve the distributed mesh with
    (the distribution does not carry the curvature of a curved mesh). Returns the scene unchanged
    on a single rank."""
    if comm is None:
        from mpi4py import MPI
        comm = MPI.COMM_WORLD
    if comm.size == 1:
        return scene
    refuse_unsupported(scene)
    import netgen.meshing as nm
    if comm.rank == 0:
        ngmesh = scene.mesh.ngmesh.Copy()
        ngmesh.Distribute(comm)
    else:
        ngmesh = nm.Mesh.Receive(comm)
    mesh = ngs.Mesh(ngmesh)
    if curve:
        mesh.Curve(int(curve))
    return dataclasses.replace(scene, mesh=mesh)
