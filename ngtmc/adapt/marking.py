"""Which elements to refine (:func:`mark`) and to what size (:func:`targets`): the indicators of
:class:`~ngtmc.adapt.settings.Adaptivity` on a solver's state, at its history points."""
from __future__ import annotations


import numpy as np

from ngtmc.adapt.settings import Adaptivity
from ngtmc.scene import neighbours, within

__all__ = ["mark", "targets", "at_points", "per_element", "element_regions"]


def per_element(values: np.ndarray, ne: int) -> np.ndarray:
    """Values at the points of an IntegrationRuleSpace as (elements, points per element). The
    space numbers its dofs element by element, the same number of points in each (one element
    type); checked."""
    if values.size % ne:
        raise RuntimeError(f"{values.size} integration-point values do not divide into {ne} elements")
    return values.reshape(ne, values.size // ne)


def at_points(solver, cf) -> np.ndarray:
    """A CoefficientFunction at the solver's history points, (elements, points per element); a
    copy (the scratch vector it is interpolated into is reused)."""
    scratch = solver._scratch_irs
    scratch.Interpolate(cf)
    return per_element(scratch.vec.FV().NumPy().copy(), solver.mesh.ne)


def element_regions(solver) -> tuple[np.ndarray, np.ndarray]:
    """Boolean masks over the elements: in a fracture region (the solver's
    :class:`~ngtmc.scene.regions.Regions`), in the void (rho < 1/2)."""
    return solver.regions.fracture, solver.rho.vec.FV().NumPy() < 0.5


def targets(solver, adapt: Adaptivity) -> np.ndarray:
    """Target size of every element, mm: ``h_crack`` in the fracture regions, ``h_void`` in the
    rest of the void (with the J indicator), inf elsewhere (never refined)."""
    frac, void = element_regions(solver)
    target = np.full(solver.mesh.ne, np.inf)
    if solver.alpha is not None:
        target[frac] = adapt.h_crack
    if adapt.h_void is not None:
        target[void & ~frac] = adapt.h_void
    return target


def mark(solver, adapt: Adaptivity, H: np.ndarray | None = None, remesher=None) -> np.ndarray:
    """Elements to refine (boolean array over the elements) for the solver's current state.

    H: history at the history points (MPa), default the committed one; pass the trial history
    of a step not yet committed. remesher: a run refined by remeshing (:class:`ngtmc.adapt.remesh.Remesher`);
    elements it has already refined to their target (:meth:`~ngtmc.adapt.remesh.Remesher.covered`)
    count as fine whatever their size. See the module docstring for the indicators."""
    mesh = solver.mesh
    ne = mesh.ne
    frac, void = element_regions(solver)
    target = targets(solver, adapt)
    flags = np.zeros(ne, dtype=bool)
    if solver.alpha is not None:
        H = solver.H_committed if H is None else H
        Hc = at_points(solver, solver.Gc / (6.0 * solver.l0))
        Hn = per_element(np.asarray(H), ne)
        al = at_points(solver, solver.alpha)
        crack = ((Hn >= adapt.history_fraction * Hc).any(axis=1) | (al > adapt.alpha_threshold).any(axis=1)) & frac
        flags |= crack
    if adapt.h_void is not None and void.any():
        J = per_element(solver.J_values(), ne)
        flags |= (J < adapt.J_threshold).any(axis=1) & void
    for _ in range(int(adapt.buffer)):
        if not flags.any():
            break
        flags = neighbours(mesh, flags)
    coarse = coarse_elements(solver, adapt, target, remesher)
    if adapt.buffer_length > 0 and (flags & coarse).any():
        # hysteresis: only when the indicator reaches an element still to refine is the zone within
        # buffer_length refined too; the crack then runs about that far before the next refinement
        flags = within(mesh, flags, adapt.buffer_length)
    return flags & coarse


def coarse_elements(solver, adapt: Adaptivity, target: np.ndarray, remesher=None) -> np.ndarray:
    """Elements still to refine (boolean): longest edge above ``target`` (mm, per element) times
    ``size_tolerance``, and, in a remeshed run, not yet covered by the remesher's restrictions
    (:meth:`ngtmc.adapt.remesh.Remesher.covered`)."""
    coarse = solver.h > target * adapt.size_tolerance * (1.0 + 1e-9)
    if remesher is not None:
        coarse &= ~remesher.covered(solver.mesh, target)
    return coarse
