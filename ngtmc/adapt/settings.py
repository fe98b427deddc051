"""Adaptive mesh refinement during a run: refine where the crack is, or is about to be.

    sim = Simulation(scene, schedule, control, adapt=Adaptivity(h_crack=l0 / 4))

After every accepted load step, :class:`~ngtmc.simulation.loop.Simulation` asks :func:`mark` which
elements to refine, refines them by NGSolve's bisection (:func:`~ngtmc.adapt.bisection.refine`), and
solves the same step again on the refined mesh, from the state before the step with the refined
solution as predictor (predictor-corrector), until nothing is marked. There is no coarsening.

Marked (and larger than their target size) are the elements

* of the fracture regions where alpha exceeds ``alpha_threshold`` at a history point, or where
  the history H reaches ``history_fraction`` of the level H_c = Gc(rho) / (6 l0) at which AT-2
  reaches its peak stress (alpha = 1/4 under homogeneous tension: "about to break"); target size
  ``h_crack``;
* of the void (rho < 1/2) where J falls below ``J_threshold`` at a quadrature point (a squeezed
  third medium, under an indenter); target size ``h_void`` (None: no J indicator);
* and ``buffer`` layers of neighbours (sharing a vertex) of those, with the target of their own
  region, so that a crack tip that moves within a step stays on the fine mesh;
* with ``buffer_length`` (a lookahead), when any of those is still to be refined, also every
  element whose centroid lies within that distance of theirs: a hysteresis, so that a running
  crack moves about that far before the next refinement (without it, a crack that moves by a
  fraction of an element per step triggers a refinement, and a re-solve, at almost every step);
* with ``corridor`` (a half width; by default "auto", :data:`CORRIDOR_L0` times the fracture
  regions' mean l0 on a 2D mesh), at the first refinement after the crack
  starts to run (the force below ``CORRIDOR_DROP`` of its peak), also the fracture elements in
  the strip of that half width along the crack's line ahead of its front
  (:mod:`ngtmc.adapt.corridor`): the path ahead refined at once. Every refinement next to a
  running crack moves its discrete equilibrium (the refined mesh resolves AT-2's damage profile
  differently), so that the state is settled below its load (:mod:`ngtmc.adapt.carried_state`) and the
  path climbs back: the quick three-point bending's remeshed crack run then takes one such
  refinement instead of 18 (124-149 s against 400 s); at the paper's resolution, none after the
  corridor, and the whole curve in 14 % less time than the band run's (docs/adaptivity.md, "A
  corridor along the crack's path" and the sections after it).

Path following: a refined step is solved again as the same kind of step, a dissipation step of
the same dD (its load may land elsewhere) or a displacement step to the same load, from the
refined solution (:meth:`ngtmc.stepping.path.DissipationPath.resolve`); the secant predictor restarts
from the state before the step.

``Adaptivity(remesh_maxh=...)`` refines by meshing the geometry again instead of bisecting
(:mod:`ngtmc.adapt.remesh`, generated element shapes, the state carried across non-nested meshes).

Limits of this phase: triangles (2D), tetrahedra and prisms (3D) by bisection, a prism across
its triangles only (an extruded slab keeps its layers); remeshing is 2D only; the adjoint of
:mod:`ngtmc.sensitivities` refuses a run whose mesh changed.

The bisection and the transfer of the state to the refined mesh live in :mod:`ngtmc.adapt.bisection`.

Units: mm.
"""
from __future__ import annotations

from collections.abc import Mapping
import dataclasses
from dataclasses import dataclass
import math

import numpy as np
import ngsolve as ngs

from ngtmc.discrete import Dissipation
from ngtmc.model import check_number
from ngtmc.scene import coordinates, element_vertices

__all__ = ["Adaptivity", "CORRIDOR_L0", "HISTORY_TRANSFERS", "private_scene", "check_solver"]

#: How the history variable H is carried to a refined mesh (``Adaptivity(history_transfer=...)``):
#: the largest value of the coarse points (``"max"``) or linear interpolation (``"linear"``).
HISTORY_TRANSFERS = ("max", "linear")


#: The corridor's half width of ``Adaptivity(corridor="auto")`` (the default) in units of the
#: fracture regions' mean l0; AT-2's damage profile exp(-|x| / l0) falls to 0.02 there. Measured
#: (docs/adaptivity.md, "The corridor by default"), remeshed runs with and without it side by
#: side: the sheared plate (a curved crack; 0.2 mm) 283 s against 370 s, 686 against 909 Newton
#: iterations, its crack 0.74 h from the uniform mesh's on average against 1.08 h; the quick
#: L-panel (4.75 mm) 114 s against 127 s, the same steps and crack (0.68 h from the band's); the
#: quick three-point bending (0.12 mm) 83 steps and 445 iterations against 115 and 935; at the
#: paper's resolution (0.12 mm) the whole curve in 14, 9.6, 14.0 and 14.0 % less time than the
#: pre-refined band run (four pairs; wider strips were slower than it). 3.3 l0 (0.1 mm) was too
#: narrow there: the tail's damage (alpha > 0.1) spreads over 0.21 mm, and refinements outside the
#: strip, each with its settle, put the run behind.
CORRIDOR_L0 = 4.0

#: ``buffer_length="auto"`` (the lookahead of a refinement) is the larger of LOOKAHEAD_L0 times
#: the fracture regions' mean l0 and LOOKAHEAD_H times h_crack, on a 2D mesh with a phase field;
#: none in 3D (never measured there): it must cover the crack advance of the next steps (a
#: dissipation step advances it by about l0) and more than a few fine elements. Measured, each
#: against the band run side by side (docs/adaptivity.md, "What refinement gains now"): the quick
#: three-point bending remeshed from 0.06 to 0.015 mm (l0 = 0.03 mm) with 0.06 mm took 83 steps
#: and 456 Newton iterations, peak -0.27 %, 0.85 of the band run's wall time; with none, 114,
#: 808 and -2.6 % (the crack ran off the fine mesh before the peak); with one coarse element
#: (the median longest edge of the marked elements), 108, 678 and -0.43 %. The quick L-panel
#: remeshed from 5 to 2 mm (l0 = 1.19 mm) with 6 mm took 196 steps and 332 iterations in 144 s,
#: with 2.4 mm 197, 368 and 342 s (a remesh every few steps).
LOOKAHEAD_L0 = 2.0
LOOKAHEAD_H = 3.0


@dataclass(frozen=True)
class Adaptivity:
    """Refinement during a run (see the module docstring).

    h_crack: target element size in the fracture regions, mm (> 0; e.g. l0 / 4); elements of at
    most this size (longest edge) are not refined. alpha_threshold: alpha above which an element
    is refined (dimensionless, in (0, 1)). history_fraction: fraction of H_c = Gc / (6 l0) above
    which an element is refined (in (0, 1]). h_void: target size in the void for the J indicator,
    mm (None: no refinement of the void). J_threshold: J below which a void element is refined
    (in (0, 1)). buffer: layers of neighbours refined with a marked element (>= 0). buffer_length:
    elements whose centroid is within this distance (mm, >= 0) of a marked element's are refined
    too (0: none, the default; a lookahead ahead of the crack tip), or "auto": the larger of
    :data:`LOOKAHEAD_L0` l0 and :data:`LOOKAHEAD_H` h_crack on a 2D mesh with a phase field, none
    in 3D (:meth:`resolved`). corridor: half width, mm (>= 0; 0: none),
    of the corridor refined ahead of a running crack (:mod:`ngtmc.adapt.corridor`), or "auto" (the
    default): :data:`CORRIDOR_L0` times the fracture regions' mean l0 on a 2D mesh, none in 3D
    (:meth:`resolved`; :class:`~ngtmc.simulation.loop.Simulation` resolves it). max_rounds:
    refinement rounds (each followed by a re-solve) after one step at most (>= 1).
    size_tolerance: an element is refined while its longest edge exceeds size_tolerance times its
    target (>= 1). NGSolve's refinement halves an element's size (its first level of a Netgen
    mesh about 0.6x), so with 1 (a strict bound) the sizes end between half the target and the
    target: the quick three-point bending's crack path, refined from 0.06 mm to h_crack = 0.015
    mm, ended at a median longest edge of 0.0079 mm, twice as fine as the band of the same
    nominal size (0.0157 mm; docs/adaptivity.md). sqrt(2) ends between 0.71 and 1.41 times the
    target, centred on it.

    remesh_maxh: refine by generating a new mesh from the geometry (:mod:`ngtmc.adapt.remesh`) instead
    of NGSolve's bisection: the global size, mm, the scene's mesh was generated with (None:
    bisection). history_transfer: with remeshing, how H is carried to the new mesh, "max" (the
    old element's largest value; never heals) or "linear" (the old element's linear fit).

    Defaults measured on the notched plate of benchmarks/adaptivity.py (docs/adaptivity.md):
    alpha 0.2 / H_c 1.0 gave the pre-refined band's peak to 0.4 % with 71 % of its dofs at the
    peak; alpha 0.1 / 0.75 H_c refined most of the plate before the peak (58k dofs against 4k).
    """

    h_crack: float
    alpha_threshold: float = 0.2
    history_fraction: float = 1.0
    h_void: float | None = None
    J_threshold: float = 0.5
    buffer: int = 1
    max_rounds: int = 10
    buffer_length: float | str = 0.0
    corridor: float | str = "auto"
    size_tolerance: float = 1.0
    remesh_maxh: float | None = None
    history_transfer: str = "max"

    def __post_init__(self):
        check_number("Adaptivity h_crack", self.h_crack, "mm")
        if not (math.isfinite(self.h_crack) and self.h_crack > 0):
            raise ValueError(f"Adaptivity h_crack = {self.h_crack!r} mm must be finite and > 0")
        if self.h_void is not None:
            check_number("Adaptivity h_void", self.h_void, "mm")
            if not (math.isfinite(self.h_void) and self.h_void > 0):
                raise ValueError(f"Adaptivity h_void = {self.h_void!r} mm must be finite and > 0 (or None)")
        for name, lo, hi in (("alpha_threshold", 0.0, 1.0), ("J_threshold", 0.0, 1.0)):
            v = getattr(self, name)
            if not (lo < v < hi):
                raise ValueError(f"Adaptivity {name} = {v!r} is outside the allowed range ({lo:g}, {hi:g})")
        if not (0.0 < self.history_fraction <= 1.0):
            raise ValueError(f"Adaptivity history_fraction = {self.history_fraction!r} is outside (0, 1]")
        if int(self.buffer) != self.buffer or self.buffer < 0:
            raise ValueError(f"Adaptivity buffer = {self.buffer!r} must be an integer >= 0")
        _check_auto_or_length("buffer_length", self.buffer_length, "a distance")
        _check_auto_or_length("corridor", self.corridor, "a half width")
        check_number("Adaptivity size_tolerance", self.size_tolerance, "-")
        if not (math.isfinite(self.size_tolerance) and self.size_tolerance >= 1.0):
            raise ValueError(f"Adaptivity size_tolerance = {self.size_tolerance!r} must be finite and >= 1")
        if self.remesh_maxh is not None:
            check_number("Adaptivity remesh_maxh", self.remesh_maxh, "mm")
            if not (math.isfinite(self.remesh_maxh) and self.remesh_maxh > 0):
                raise ValueError(f"Adaptivity remesh_maxh = {self.remesh_maxh!r} mm must be finite and > 0 (or None)")
        if self.history_transfer not in HISTORY_TRANSFERS:
            raise ValueError(f"Adaptivity history_transfer = {self.history_transfer!r} is not one of "
                             f"{', '.join(map(repr, HISTORY_TRANSFERS))}")
        if int(self.max_rounds) != self.max_rounds or self.max_rounds < 1:
            raise ValueError(f"Adaptivity max_rounds = {self.max_rounds!r} must be an integer >= 1")

    def resolved(self, solver) -> "Adaptivity":
        """These settings for the run of ``solver`` (:class:`~ngtmc.discrete.solver.Solver`), with a
        ``corridor`` of "auto" replaced by its half width in mm: :data:`CORRIDOR_L0` times the mean
        l0 of the fracture regions on a 2D mesh; 0 (none) in 3D, where the corridor is a tube
        about a line, not the surface a crack runs in, and was never measured, and on a scene
        without a phase field; and a ``buffer_length`` of "auto" by the larger of
        :data:`LOOKAHEAD_L0` times that l0 and :data:`LOOKAHEAD_H` times ``h_crack`` in 2D (mm),
        0 in 3D and without a phase field."""
        import dataclasses
        l0 = (Dissipation(solver).fracture_mean(solver.l0)
              if solver.mesh.dim == 2 and solver.alpha is not None else None)
        out = self
        if out.corridor == "auto":
            out = dataclasses.replace(out, corridor=CORRIDOR_L0 * l0 if l0 is not None else 0.0)
        if out.buffer_length == "auto":
            out = dataclasses.replace(out, buffer_length=max(LOOKAHEAD_L0 * l0, LOOKAHEAD_H * out.h_crack)
                                      if l0 is not None else 0.0)
        return out

    def smallest_size(self) -> float:
        """The smallest longest edge a refined element may keep, mm: the smaller of ``h_crack`` and
        ``h_void`` times ``size_tolerance``. A prism is never bisected along its height, so a
        slab's prisms must be no taller (:func:`check_solver`)."""
        return min(h for h in (self.h_crack, self.h_void) if h is not None) * self.size_tolerance


def _check_auto_or_length(name: str, value, what: str):
    """ValueError unless ``value`` (a setting of :class:`Adaptivity`) is "auto" or a finite length
    >= 0 in mm; ``what`` names the length in the message."""
    if isinstance(value, str):
        if value != "auto":
            raise ValueError(f"Adaptivity {name} = {value!r}: {what} in mm (>= 0; 0: none) or 'auto'")
        return
    check_number(f"Adaptivity {name}", value, "mm")
    if not (math.isfinite(value) and value >= 0):
        raise ValueError(f"Adaptivity {name} = {value!r} mm must be finite and >= 0 (or 'auto')")


def private_scene(scene):
    """The scene on a copy of its mesh (curved at the same order; a density array copied), for a
    run that refines its mesh without changing the caller's scene or mesh."""
    mesh = scene.mesh
    copy = ngs.Mesh(mesh.ngmesh.Copy())
    if mesh.GetCurveOrder() > 1:
        copy.Curve(mesh.GetCurveOrder())
    density = scene.density
    if density is not None and not isinstance(density, Mapping):
        density = np.array(density, dtype=float, copy=True)
    return dataclasses.replace(scene, mesh=copy, density=density)


def check_solver(solver, remesh: bool = False, adapt: Adaptivity | None = None):
    """ValueError when the solver's scene cannot be refined by this module: bisection needs
    triangles (2D), tetrahedra or prisms (3D; tests/test_adapt.py, tests/test_adapt_3d.py,
    tests/test_adapt_prisms.py); remeshing (``remesh``, :mod:`ngtmc.adapt.remesh`) is 2D only. NGSolve
    bisects a prism across its triangles only, never along its height: with ``adapt``, a slab
    whose prisms are taller than the smallest size they are to reach is refused (its marked
    prisms would never reach their target)."""
    mesh = solver.mesh
    if remesh and mesh.dim != 2:
        raise ValueError("refinement by remeshing (Adaptivity remesh_maxh) is implemented for 2D meshes only; "
                         "a 3D mesh of tetrahedra or prisms is refined by bisection (remesh_maxh=None)")
    types = {el.type for el in mesh.Elements(ngs.VOL)}
    if not (types == {ngs.ET.TRIG} if mesh.dim == 2 else types in ({ngs.ET.TET}, {ngs.ET.PRISM})):
        raise ValueError("adaptive refinement (Adaptivity) needs a mesh of triangles (2D), or of tetrahedra or of "
                         "prisms (3D), one kind only (bisection)")
    if adapt is not None and types == {ngs.ET.PRISM}:
        nodes = element_vertices(mesh)
        xyz = coordinates(mesh)
        height = float(np.max(np.linalg.norm(xyz[nodes[:, 3:]] - xyz[nodes[:, :3]], axis=2)))
        smallest = adapt.smallest_size()
        if height > smallest * (1.0 + 1e-9):
            raise ValueError(f"the prisms are up to {height:.4g} mm tall, more than the smallest size they are to "
                             f"be refined to ({smallest:.4g} mm: h_crack or h_void times size_tolerance); NGSolve "
                             "bisects prisms across their triangles only: extrude the slab in more layers or "
                             "make it thinner")
