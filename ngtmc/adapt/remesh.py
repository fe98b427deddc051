"""Refinement by remeshing: a new mesh generated from the scene's geometry, fine where marked.

NGSolve's bisection (:mod:`ngtmc.adapt`) keeps the mesh nested but degrades the shape of the
elements it splits (median shape quality 0.81-0.87 against 0.99 for generated elements), and a
crack runs on bisected elements at 1.4-2.7 times the Newton iterations of generated elements of
the same size (docs/adaptivity.md). ``Adaptivity(remesh_maxh=...)`` refines instead by meshing the
geometry again with Netgen:

* every refinement adds **size restrictions**: a lattice of points of spacing h over each marked
  element, each restricting Netgen's local mesh size to h (``MeshingParameters.RestrictH``); the
  restrictions are kept for the whole run, so a zone once refined stays fine (no coarsening);
* the new mesh is generated from the geometry of the scene's mesh
  (``mesh.ngmesh.GetGeometry()``) with the global ``maxh`` the scene's mesh was generated with
  and all restrictions so far. Netgen is deterministic: without restrictions it gives the
  initial mesh again, vertex for vertex, and the same restrictions give the same mesh, which is
  how a checkpointed run is resumed (:meth:`ngtmc.simulation.state.RunState.set_state`);
* an element counts as refined when a restriction point of its target size or finer lies within
  that size of its centroid (Netgen's elements may exceed their size a little, so a size test
  alone would mark them again and again).

The state is carried across the two meshes, which are not nested (:func:`transfer`):

* u by NGSolve's ``Set`` of the old field (evaluated across meshes), exact for fields the new space
  can represent; where it folds an element of the new mesh (a squeezed void), halved until it
  does not (:func:`_admissible`);
* alpha by nodal interpolation: the old P1 field evaluated at every new vertex, from inside one
  of the vertex's new fracture elements (region boundaries are geometry edges, so they lie on
  each other in both meshes);
* the history H: each new history point takes the old element's linear fit through its points,
  clipped to their range (exact for a linear H; a homogeneous H stays as it is), and in the old
  elements being refined the old element's largest value (``history="max"``, the default: there
  the damage never heals, as with bisection); ``history="linear"`` takes the fit everywhere.
  The largest value everywhere was tried and dropped: it widens a steep H profile by one old
  element at every remesh, and the remeshed notched plate (then without the equilibration
  below) failed after 8 steps where the fit went through.

The simulation then (:func:`remesh_step`) solves u of the carried states at their alpha, brings the
state before the step to equilibrium on the new mesh (:mod:`ngtmc.adapt.carried_state`) and solves the
step again there at the load the old mesh's step reached (path following too:
:meth:`ngtmc.stepping.path.DissipationPath.resolve` with ``at_load``).

The remeshed run's meshes have no parent relation, so :mod:`ngtmc.sensitivities` refuses such a
run as it refuses a bisected one. Units: mm.
"""
from __future__ import annotations

from collections.abc import Mapping
import dataclasses

import numpy as np
import ngsolve as ngs

from ngtmc.adapt.marking import element_regions
from ngtmc.scene import centroids, coordinates
from ngtmc.scene import element_vertices
from ngtmc.adapt.marking import targets
from ngtmc.adapt.record import RefinementRecord
from ngtmc.adapt.carried_state import balance, equilibrate
from ngtmc.coupled import CoupledNewton
from ngtmc.discrete import Solver
from ngtmc.adapt.settings import HISTORY_TRANSFERS  # how the history is carried to a new mesh

__all__ = ["Remesher", "transfer", "locate", "history_points", "move", "remesh_step"]


def locate(mesh, xy: np.ndarray) -> np.ndarray:
    """Element number (0-based) of ``mesh`` containing each point of ``xy`` (n, 2), mm. A point
    that no element contains (a curved boundary drawn a little differently by two meshes) gets
    the element with the nearest centroid."""
    xy = np.asarray(xy, dtype=float)
    if xy.size == 0:
        return np.zeros(0, dtype=np.int64)
    nr = np.asarray(mesh(xy[:, 0].copy(), xy[:, 1].copy())["nr"], dtype=np.int64)
    lost = nr < 0
    if lost.any():
        from scipy.spatial import cKDTree
        _, nr[lost] = cKDTree(centroids(mesh)).query(xy[lost])
    return nr


class Remesher:
    """The size restrictions of a remeshed run and the mesh they give (module docstring).

    maxh: the global size the scene's mesh was generated with, mm (its regions' own sizes are part
    of the geometry; :class:`ngtmc.adapt.Adaptivity` checks the number). The restrictions are rows
    (x, y, h), mm."""

    def __init__(self, mesh, maxh: float):
        geo = mesh.ngmesh.GetGeometry()
        if geo is None or not hasattr(geo, "GenerateMesh"):
            raise ValueError("remeshing (Adaptivity remesh_maxh) needs a mesh generated from a Netgen geometry "
                             "(netgen.occ.OCCGeometry or netgen.geom2d.SplineGeometry); this mesh has none")
        self.geometry = geo
        self.maxh = float(maxh)
        self.curve_order = mesh.GetCurveOrder()
        self.restrictions = np.zeros((0, 3))
        again = self.mesh()
        if (again.ne, again.nv) != (mesh.ne, mesh.nv):
            raise ValueError(f"Adaptivity remesh_maxh = {maxh:g} mm: the geometry meshed with it has {again.ne} elements "
                             f"and {again.nv} vertices, the scene's mesh {mesh.ne} and {mesh.nv}; give the maxh the "
                             "scene's mesh was generated with (its regions' own sizes are in the geometry)")

    def covered(self, mesh, targets: np.ndarray) -> np.ndarray:
        """Elements already refined to their target (boolean over the elements): a restriction of
        at most the target lies within the target of the element's centroid."""
        out = np.zeros(mesh.ne, dtype=bool)
        if not len(self.restrictions):
            return out
        from scipy.spatial import cKDTree
        c = centroids(mesh)
        for h in np.unique(targets[np.isfinite(targets)]):
            pts = self.restrictions[self.restrictions[:, 2] <= h * (1 + 1e-9), :2]
            if not len(pts):
                continue
            sel = targets == h
            d, _ = cKDTree(pts).query(c[sel], distance_upper_bound=h)
            out[np.flatnonzero(sel)[np.isfinite(d)]] = True
        return out

    def add(self, mesh, marked: np.ndarray, targets: np.ndarray, within=None) -> np.ndarray:
        """Add the restrictions of the marked elements (a lattice of spacing ``targets[e]`` over
        each; with ``within``, a function of points (n, 2), mm, to booleans, only its lattice
        points where it is True); return the rows added."""
        xy = coordinates(mesh)
        nodes = element_vertices(mesh)
        rows = []
        for e in np.flatnonzero(marked):
            h = float(targets[e])
            a, b, c = xy[nodes[e]]
            n = max(1, int(np.ceil(max(np.linalg.norm(b - a), np.linalg.norm(c - a), np.linalg.norm(c - b)) / h)))
            i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
            keep = i + j <= n
            s, t = i[keep] / n, j[keep] / n
            p = a + s[:, None] * (b - a) + t[:, None] * (c - a)
            rows.append(np.column_stack([p, np.full(len(p), h)]))
        if not rows:
            return np.zeros((0, 3))
        new = np.vstack(rows)
        if within is not None:
            new = new[np.asarray(within(new[:, :2]), dtype=bool)]
            if not len(new):
                return np.zeros((0, 3))
        # one point per cell of half the finest size: lattices of neighbours share their edges
        key = np.round(new[:, :2] / (0.5 * new[:, 2:].min())).astype(np.int64)
        _, first = np.unique(key, axis=0, return_index=True)
        new = new[np.sort(first)]
        self.restrictions = np.vstack([self.restrictions, new])
        return new

    def mesh(self, restrictions: np.ndarray | None = None):
        """The mesh of the geometry with ``maxh`` and the restrictions (default: all so far),
        curved at the scene mesh's order."""
        from netgen.meshing import MeshingParameters
        rows = self.restrictions if restrictions is None else np.asarray(restrictions, dtype=float)
        mp = MeshingParameters(maxh=self.maxh)
        for x, y, h in rows:
            mp.RestrictH(x=float(x), y=float(y), z=0.0, h=float(h))
        mesh = ngs.Mesh(self.geometry.GenerateMesh(mp))
        if self.curve_order > 1:
            mesh.Curve(self.curve_order)
        return mesh


def scene_on(scene, old_mesh, new_mesh):
    """The scene on ``new_mesh``: a density given per element follows the old element that
    contains each new element's centroid; densities per region follow the region names."""
    density = scene.density
    if density is not None and not isinstance(density, Mapping):
        density = np.asarray(density, dtype=float)[locate(old_mesh, centroids(new_mesh))]
    return dataclasses.replace(scene, mesh=new_mesh, density=density)


def history_points(solver) -> np.ndarray:
    """Coordinates (points, 2) of the solver's history points, element by element, mm."""
    g = solver._scratch_irs
    out = []
    for cf in (ngs.x, ngs.y):
        g.Interpolate(cf)
        out.append(g.vec.FV().NumPy().copy())
    return np.column_stack(out)


def _history(old, H_old: np.ndarray, where: np.ndarray, xy_new: np.ndarray, xy_old: np.ndarray,
             refined: np.ndarray | None) -> np.ndarray:
    """H at the new points (module docstring): ``where`` the old element of each new point; in the
    old elements flagged ``refined`` the element's largest value, elsewhere its linear fit."""
    ne = old.mesh.ne
    Hp = np.asarray(H_old, dtype=float).reshape(ne, -1)
    val = _linear_fit(Hp, where, xy_new, xy_old.reshape(ne, -1, 2))
    if refined is not None:
        up = refined[where]
        val[up] = Hp.max(axis=1)[where[up]]
    return val


def _linear_fit(Hp, where, xy_new, xy_old):
    """The old element's least-squares plane through its points, at the new points, clipped to
    the range of the element's values."""
    P = xy_old[where]                                # the old element's points, (n, k, 2)
    V = Hp[where]                                    # their values, (n, k)
    # least-squares plane through the old element's points (batched normal equations)
    A = np.concatenate([np.ones(P.shape[:2] + (1,)), P - P.mean(axis=1, keepdims=True)], axis=2)
    AtA = np.einsum("nki,nkj->nij", A, A)
    Atv = np.einsum("nki,nk->ni", A, V)
    c = np.linalg.solve(AtA, Atv[..., None])[..., 0]
    q = xy_new - P.mean(axis=1)
    val = c[:, 0] + c[:, 1] * q[:, 0] + c[:, 2] * q[:, 1]
    return np.clip(val, V.min(axis=1), V.max(axis=1))


#: halvings of a carried u that inverts an element of the new mesh (:func:`_admissible`)
RETREATS = 10


def _admissible(new, u: np.ndarray) -> np.ndarray:
    """The carried displacement dofs ``u`` of the solver ``new``, halved (at most RETREATS times)
    until det F > 0 at every guard point of the new mesh. Why: in a void squeezed to J of about
    0.004 under the indenter (the paper-resolution three-point bending with the void refined,
    2026-12-04), the field set on a different mesh folded elements (min J -0.009), and every step
    from there failed with a residual that is not finite. A halved u is no equilibrium, but an
    admissible start: the displacement Newton carries the boundary values back to the load."""
    x = new.u.vec.FV().NumPy()
    keep = x.copy()
    factor = 1.0
    for _ in range(RETREATS):
        x[:] = factor * u
        if new.min_J() > 0.0:
            break
        factor *= 0.5
    else:
        factor = 0.0
    x[:] = keep
    return factor * u


def transfer(old, new, states=(), history: str = "max", refined: np.ndarray | None = None) -> list[dict]:
    """Carry the solver ``old``'s fields, and further states of
    :meth:`~ngtmc.discrete.solver.Solver.get_state` (some may hold only ``u`` and ``alpha``), to the solver
    ``new`` on another mesh of the same geometry (module docstring); ``refined``: the old elements
    being refined (boolean), where ``history="max"`` takes the largest value. The fields of ``new`` are set
    to ``old``'s (u, alpha, committed alpha, history, load); returns the states on the new mesh."""
    if history not in HISTORY_TRANSFERS:
        raise ValueError(f"history transfer {history!r} is not one of {', '.join(map(repr, HISTORY_TRANSFERS))}")
    states = [old.get_state()] + list(states)
    u_old = ngs.GridFunction(old.fes_u)
    u_new = ngs.GridFunction(new.fes_u)
    out = [dict() for _ in states]
    for st, o in zip(states, out):
        u_old.vec.FV().NumPy()[:] = st["u"]
        u_new.Set(u_old)
        o["u"] = _admissible(new, u_new.vec.FV().NumPy())
        if "load" in st:
            o["load"] = np.array(st["load"])
    if old.alpha is not None:
        # each new vertex of a fracture element, seen from inside that element
        frac = np.flatnonzero(element_regions(new)[0])
        nodes = element_vertices(new.mesh)
        xy = coordinates(new.mesh)
        owner = np.full(new.mesh.nv, -1)
        owner[nodes[frac].ravel()] = np.repeat(frac, 3)
        verts = np.flatnonzero(owner >= 0)
        cen = xy[nodes[owner[verts]]].mean(axis=1)
        probe = xy[verts] + 1e-6 * (cen - xy[verts])
        pts = old.mesh(probe[:, 0].copy(), probe[:, 1].copy())
        lost = np.asarray(pts["nr"]) < 0
        a_old = ngs.GridFunction(old.fes_a)
        for st, o in zip(states, out):
            for key in ("alpha", "alpha_committed"):
                if key not in st:
                    continue
                a_old.vec.FV().NumPy()[:] = st[key]
                vals = np.zeros(new.fes_a.ndof)
                got = np.asarray(a_old(pts)).ravel()
                if lost.any():   # outside the old mesh's curved boundary: the nearest old vertex
                    from scipy.spatial import cKDTree
                    _, near = cKDTree(coordinates(old.mesh)).query(probe[lost])
                    got[lost] = np.asarray(st[key])[near]
                vals[verts] = got
                o[key] = vals
    if any("H" in st for st in states):
        xy_new = history_points(new)
        xy_old = history_points(old)
        where = locate(old.mesh, xy_new)
        for st, o in zip(states, out):
            if "H" in st:
                o["H"] = _history(old, st["H"], where, xy_new, xy_old, refined if history == "max" else None)
    first, rest = out[0], out[1:]
    new.set_state(first)
    return rest


#: what a run keeps of its solver and coupled Newton through a move to a new mesh: counters, the
#: time split and the residual floor setting
_SOLVER_CARRIED = ("floor_accepts", "energy_noise_switches", "timings", "floor_rtol")
_COUPLED_CARRIED = ("floor_accepts", "floor_worst", "levenberg_steps", "relaxations", "relax")


def move(sim, mesh, states=None, refined=None) -> list[dict]:
    """Bring the simulation ``sim`` to ``mesh`` (a mesh of the same geometry): a new solver on the
    scene on that mesh, and the coupled Newton and the path rule with it; the run's counters and
    time split go on. With ``states`` (a list, possibly empty), the solver's fields and those
    states are carried over (:func:`transfer`) and returned on the new mesh; without, the new
    solver's fields are zero (a resume sets them)."""
    old = sim.solver
    scene = scene_on(old.scene, old.mesh, mesh)
    new = Solver(scene, **sim._solver_options)
    rest = transfer(old, new, states, sim.adapt.history_transfer, refined) if states is not None else []
    for k in _SOLVER_CARRIED:
        if hasattr(old, k):
            setattr(new, k, getattr(old, k))
    new.mesh_generation = old.mesh_generation + 1
    sim.solver, sim.scene = new, scene
    if sim.coupled is not None:
        c_old = sim.coupled
        sim.coupled = c = CoupledNewton(new, **sim._coupled_options)
        for k in _COUPLED_CARRIED:
            if hasattr(c_old, k):
                setattr(c, k, getattr(c_old, k))
        if sim._path is not None:
            sim._path.coupled = c
            sim._path.sizing.solver = new
    return rest


def remesh_step(sim, marked: np.ndarray, states: list, clip: tuple | None = None) -> tuple:
    """One refinement of a remeshed run (:class:`~ngtmc.simulation.loop.Simulation` with
    ``Adaptivity(remesh_maxh=...)``): restrictions for the marked elements, the new mesh, the
    simulation moved to it with its state and ``states``. ``clip``: (elements, within), the
    marked elements whose restrictions are kept to the points where ``within`` holds (the
    corridor's strip, :func:`ngtmc.adapt.corridor.corridor`). Returns (record, states on the new
    mesh); the record's elements are the marked ones of the old mesh (a resume restores the
    restrictions, :meth:`ngtmc.simulation.state.RunState.set_state`)."""
    s = sim.solver
    ne_old, dofs_old = s.mesh.ne, s.fes_u.ndof
    t = targets(s, sim.adapt)
    if clip is None:
        sim._remesher.add(s.mesh, marked, t)
    else:
        sim._remesher.add(s.mesh, marked & ~clip[0], t)
        sim._remesher.add(s.mesh, marked & clip[0], t, within=clip[1])
    states = move(sim, sim._remesher.mesh(), states, refined=marked)
    s = sim.solver
    if s.alpha is not None:   # u of the step's and the saved state balanced at their carried alpha
        balance(s, s.get_state(), in_place=True)
        states[0] = balance(s, states[0])
    states[0], found = equilibrate(sim, states[0])   # may settle it below its load (the path follows it)
    record = RefinementRecord(int(marked.sum()), ne_old, sim.solver.mesh.ne, dofs_old, sim.solver.fes_u.ndof,
                              np.flatnonzero(marked).astype(np.int64), equilibrium=found)
    return record, states
