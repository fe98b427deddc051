"""The corridor of :class:`ngtmc.adapt.Adaptivity` (``corridor``, a half width in mm): once the
crack runs, the path ahead of its front refined at once, so that the crack does not run into
coarse elements one refinement (and one settle) at a time.

:func:`corridor_due` decides when (from the history alone), :func:`corridor` which elements, in
the direction :func:`_crack_direction` gives. :class:`~ngtmc.simulation.Simulation` adds them to
the marked elements of :func:`ngtmc.adapt.mark`. Measured in docs/adaptivity.md ("A corridor
along the crack's path" and the sections after it). Units: mm.
"""
from __future__ import annotations

import numpy as np
import ngsolve as ngs

from .adapt import Adaptivity, _at_points, _centroids, _coarse, _element_regions, targets
from .materials import deformation_gradient

__all__ = ["corridor", "corridor_due", "CORRIDOR_DROP"]


#: the crack runs (:func:`corridor`) once the force has fallen below this fraction of its peak
CORRIDOR_DROP = 0.95


def corridor_due(rows: list[dict], refinements: list[tuple]) -> bool:
    """Whether a refinement now adds the :func:`corridor`: the crack runs (the last force of the
    history ``rows``, N or N/mm, below :data:`CORRIDOR_DROP` of the largest) and none of the
    ``refinements`` ((step, record), :attr:`ngtmc.simulation.Simulation.refinements`) came after
    the first row below it after that peak. Not the first row below a running maximum: the
    force's round-off about zero before contact falls below it. The history alone decides, so a
    resumed run decides as the uninterrupted one."""
    f = np.array([float(r["force"]) for r in rows])
    if not f.size or not f.max() > 0 or not f[-1] < CORRIDOR_DROP * f.max():
        return False
    peak = int(np.argmax(f))
    first = peak + int(np.argmax(f[peak:] < CORRIDOR_DROP * f[peak]))
    step = int(rows[first].get("step", first))
    return not any(s > step for s, _ in refinements)


def corridor(solver, adapt: Adaptivity, marked: np.ndarray, remesher=None) -> np.ndarray:
    """Elements to refine besides ``marked`` (:func:`ngtmc.adapt.mark`) where the crack runs: those of the
    fracture regions, still coarser than their target, whose centroid lies within
    ``adapt.corridor`` (mm) of the line through the centroid of the crack's front (the marked
    elements of the fracture regions) in the crack's direction, from ``adapt.corridor`` behind
    the front on (boolean over the elements). The direction (:func:`_crack_direction`): the ray
    from the centroid of the damaged elements (alpha > 1/2 at a history point) through the front,
    without its component along the front's largest principal strain. Empty where nothing is
    damaged or no fracture element is marked. The caller decides when
    (:func:`corridor_due`).

    Why: every refinement next to a running crack puts its state past the refined mesh's
    equilibrium at its load, even when the state is carried exactly (docs/adaptivity.md); a
    straight corridor refined once takes those refinements out of the crack run where the path
    keeps its direction. Where it turns, the indicator goes on refining as without it."""
    out = np.zeros(solver.mesh.ne, dtype=bool)
    w = float(adapt.corridor)
    if not w > 0 or solver.alpha is None:
        return out
    frac, _ = _element_regions(solver)
    front = marked & frac
    damaged = (_at_points(solver, solver.alpha) > 0.5).any(axis=1) & frac
    if not front.any() or not damaged.any():
        return out
    c = _centroids(solver.mesh)
    tip = c[front].mean(axis=0)
    d = _crack_direction(solver, front, tip - c[damaged].mean(axis=0))
    if d is None:
        return out
    rel = c - tip
    along = rel @ d
    across = np.linalg.norm(rel - along[:, None] * d, axis=1)
    coarse = _coarse(solver, adapt, targets(solver, adapt), remesher)
    return frac & coarse & (along >= -w) & (across <= w) & ~marked


def _crack_direction(solver, front: np.ndarray, ray: np.ndarray) -> np.ndarray | None:
    """Unit direction in which the crack runs: ``ray`` (from the damaged zone to the front, mm)
    without its component along the largest principal direction of the Green-Lagrange strain
    averaged over the ``front`` elements, weighted by their areas (a crack opens across its
    largest principal stretch; in 3D the direction lies in the crack's plane); the ray itself
    where the front does not open (no positive principal strain) or opens alike in every
    direction. None where no length is left.

    Why not the ray itself: the front's centroid lies where the mesh is still coarse, off the
    crack's line. In the paper-resolution three-point bending the ray leaned 8.0 degrees off the
    vertical crack (this direction: 1.2 degrees); the corridor then left the crack's one side
    coarse near the beam's top, where four more refinements, each settled, followed
    (docs/adaptivity.md, "The corridor's direction")."""
    length = float(np.linalg.norm(ray))
    if not length > 0:
        return None
    mesh, dim = solver.mesh, solver.mesh.dim
    F = deformation_gradient(solver.u)
    E = 0.5 * (F.trans * F - ngs.Id(dim))
    volume = ngs.Integrate(ngs.CoefficientFunction(1.0), mesh, element_wise=True).NumPy()[front]
    mean = np.empty((dim, dim))
    for i in range(dim):
        for j in range(i, dim):
            e = _at_points(solver, E[i, j])[front].mean(axis=1)
            mean[i, j] = mean[j, i] = np.average(e, weights=volume)
    w, v = np.linalg.eigh(mean)
    if not (w[-1] > 0 and w[-1] - w[-2] > 1e-9 * np.abs(w).max()):
        return ray / length   # no opening, or no distinct direction of it: the ray as it is
    opening = v[:, -1]
    d = ray - (ray @ opening) * opening
    n = float(np.linalg.norm(d))
    return d / n if n > 1e-12 * length else None
