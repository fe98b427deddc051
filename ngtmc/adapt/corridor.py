"""The corridor of :class:`ngtmc.adapt.Adaptivity` (``corridor``, a half width in mm): once the
crack runs, the path ahead of its front refined at once, so that the crack does not run into
coarse elements one refinement (and one settle) at a time.

:func:`corridor_due` decides when (from the history alone), :func:`strip` where (a strip along
the crack's line, in the direction :func:`_crack_direction` gives), :func:`corridor` which
elements. :class:`~ngtmc.simulation.loop.Simulation` adds them to the marked elements of
:func:`ngtmc.adapt.mark`; a remeshed run keeps their restrictions to the strip. Measured in
docs/adaptivity.md ("A corridor along the crack's path" and the sections after it). Units: mm.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ngsolve as ngs

from ngtmc.adapt.marking import at_points, coarse_elements, element_regions, targets
from ngtmc.adapt.settings import Adaptivity
from ngtmc.scene import centroids, coordinates
from ngtmc.model import deformation_gradient
from ngtmc.scene import element_vertices

__all__ = ["corridor_elements", "corridor_due", "strip", "Strip", "CORRIDOR_DROP"]


#: the crack runs (:func:`corridor`) once the force has fallen below this fraction of its peak
CORRIDOR_DROP = 0.95


def corridor_due(rows: list[dict], refinements: list[tuple]) -> bool:
    """Whether a refinement now adds the :func:`corridor`: the crack runs (the last force of the
    history ``rows``, N or N/mm, below :data:`CORRIDOR_DROP` of the largest) and none of the
    ``refinements`` ((step, record), :attr:`ngtmc.simulation.loop.Simulation.refinements`) came after
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


@dataclass(frozen=True)
class Strip:
    """The corridor's strip: the points within ``half_width`` (mm) of the line through ``origin``
    (mm) along the unit vector ``direction``, from ``half_width`` behind ``origin`` on."""

    origin: np.ndarray
    direction: np.ndarray
    half_width: float

    def contains(self, points: np.ndarray) -> np.ndarray:
        """Whether each of ``points`` (n, dim), mm, lies in the strip."""
        rel = np.asarray(points, dtype=float)[:, :len(self.origin)] - self.origin
        along = rel @ self.direction
        across = np.linalg.norm(rel - along[:, None] * self.direction, axis=1)
        return (along >= -self.half_width) & (across <= self.half_width)


def strip(solver, adapt: Adaptivity, marked: np.ndarray) -> Strip | None:
    """The :class:`Strip` of half width ``adapt.corridor`` (mm) ahead of the crack's front (the
    ``marked`` elements of the fracture regions, :func:`ngtmc.adapt.mark`), or None where nothing
    is damaged, no fracture element is marked or the width is 0. Its line: through the centroid
    of the front, in the direction :func:`_crack_direction` gives (the ray from the centroid of
    the damaged elements, alpha > 1/2 at a history point, through the front, without its
    component along the front's largest principal strain); where the front opens, moved across
    the crack (along that strain's direction) onto the damaged elements within 2
    ``adapt.corridor`` of the front's centroid along the line (:func:`_on_the_crack`)."""
    if adapt.corridor == "auto":
        raise ValueError("Adaptivity corridor 'auto' is resolved for a run first: adapt.resolved(solver)")
    w = float(adapt.corridor)
    if not w > 0 or solver.alpha is None:
        return None
    frac, _ = element_regions(solver)
    front = marked & frac
    damaged = (at_points(solver, solver.alpha) > 0.5).any(axis=1) & frac
    if not front.any() or not damaged.any():
        return None
    c = centroids(solver.mesh)
    tip = c[front].mean(axis=0)
    d, opening = _crack_direction(solver, front, tip - c[damaged].mean(axis=0))
    if d is None:
        return None
    if opening is not None:
        tip = _on_the_crack(solver.mesh, tip, opening, damaged & (np.abs((c - tip) @ d) <= 2.0 * w))
    return Strip(tip, d, w)


def corridor_elements(solver, adapt: Adaptivity, marked: np.ndarray, remesher=None, line: Strip | None = None) -> np.ndarray:
    """Elements to refine besides ``marked`` (:func:`ngtmc.adapt.mark`) where the crack runs: those
    of the fracture regions, still coarser than their target and not marked, in the :func:`strip`
    ``line`` (default: the strip of ``marked``) (boolean over the elements). By bisection
    (``remesher`` None) an element whose centroid lies in the strip, refined whole; remeshed
    (:class:`ngtmc.adapt.remesh.Remesher`), an element with its centroid or a vertex in it, whose
    restrictions :func:`ngtmc.adapt.remesh.remesh_step` then keeps to the strip (``line.contains``), so
    that the refined zone is the strip, not the coarse elements across its edges. Empty where
    there is no strip. The caller decides when (:func:`corridor_due`).

    Why: every refinement next to a running crack puts its state past the refined mesh's
    equilibrium at its load, even when the state is carried exactly (docs/adaptivity.md); a
    straight corridor refined once takes those refinements out of the crack run where the path
    keeps its direction. Where it turns, the indicator goes on refining as without it."""
    out = np.zeros(solver.mesh.ne, dtype=bool)
    line = strip(solver, adapt, marked) if line is None else line
    if line is None:
        return out
    mesh = solver.mesh
    inside = line.contains(centroids(mesh))
    if remesher is not None:
        inside |= line.contains(coordinates(mesh))[element_vertices(mesh)].any(axis=1)
    frac, _ = element_regions(solver)
    coarse = coarse_elements(solver, adapt, targets(solver, adapt), remesher)
    return frac & coarse & inside & ~marked


def _areas(mesh) -> np.ndarray:
    """Area (2D, mm^2) or volume (3D, mm^3) of every element."""
    return ngs.Integrate(ngs.CoefficientFunction(1.0), mesh, element_wise=True).NumPy()


def _on_the_crack(mesh, tip: np.ndarray, opening: np.ndarray, near: np.ndarray) -> np.ndarray:
    """``tip`` (mm) moved along the unit vector ``opening`` (across the crack) onto the area-weighted
    centroid of the ``near`` elements (the damaged ones next to the front); ``tip`` itself where
    there are none.

    Why: the front's centroid lies where the mesh is still coarse, off the crack's line. In the
    paper-resolution three-point bending with the direction mended, the corridor of 0.15 mm ran
    parallel to the crack but beside it (its fine elements at x = 3.89 to 4.20 mm, the crack at
    x = 3.99 to 4.02 mm); with the line moved, the front's centroid at x = 4.012 mm gave the
    line's origin at 4.002 mm (docs/adaptivity.md, "A corridor along the crack's path")."""
    if not near.any():
        return tip
    m = np.average(centroids(mesh)[near], axis=0, weights=_areas(mesh)[near])
    return tip + ((m - tip) @ opening) * opening


def _crack_direction(solver, front: np.ndarray, ray: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(unit direction in which the crack runs, unit direction in which it opens or None). The
    direction: ``ray`` (from the damaged zone to the front, mm) without its component along the
    largest principal direction of the Green-Lagrange strain averaged over the ``front``
    elements, weighted by their areas (a crack opens across its largest principal stretch, the
    opening direction; in 3D the direction lies in the crack's plane); the ray itself, and no
    opening, where the front does not open (no positive principal strain) or opens alike in every
    direction. None where no length is left.

    Why not the ray itself: the front's centroid lies where the mesh is still coarse, off the
    crack's line. In the paper-resolution three-point bending the ray leaned 8.0 degrees off the
    vertical crack (this direction: 1.2 degrees); the corridor then left the crack's one side
    coarse near the beam's top, where four more refinements, each settled, followed
    (docs/adaptivity.md, "The corridor's direction")."""
    length = float(np.linalg.norm(ray))
    if not length > 0:
        return None, None
    mesh, dim = solver.mesh, solver.mesh.dim
    F = deformation_gradient(solver.u)
    E = 0.5 * (F.trans * F - ngs.Id(dim))
    volume = _areas(mesh)[front]
    mean = np.empty((dim, dim))
    for i in range(dim):
        for j in range(i, dim):
            e = at_points(solver, E[i, j])[front].mean(axis=1)
            mean[i, j] = mean[j, i] = np.average(e, weights=volume)
    w, v = np.linalg.eigh(mean)
    if not (w[-1] > 0 and w[-1] - w[-2] > 1e-9 * np.abs(w).max()):
        return ray / length, None   # no opening, or no distinct direction of it: the ray as it is
    opening = v[:, -1]
    d = ray - (ray @ opening) * opening
    n = float(np.linalg.norm(d))
    return (d / n, opening) if n > 1e-12 * length else (None, None)
