"""The discrete system of one scene: fields, energies, Newton solver, phase-field solve, history.

One load step of the paper's scheme (Sect. "Numerical implementation") is, with H_{n-1} fixed:

1. :meth:`Solver.solve_phase_field`: a linear SPD solve for alpha_n from H_{n-1};
2. :meth:`Solver.solve_displacement`: Newton for u_n with alpha_n fixed (energy line search, a guard
   against J <= 0 / NaN energy, a descent check with a shifted tangent when the tangent is
   indefinite, and the Dirichlet increment carried by the Newton increment);
3. :meth:`Solver.update_history`: H_n = max(H_{n-1}, Psi_plus(u_n)) at the quadrature points.

:mod:`ngtmc.simulation.loop` drives these through a load schedule. Four parts of :class:`Solver` live in
modules of their own, as its bases: the displacement energy, its rules and forms
(:mod:`ngtmc.discrete.displacement_energy`), the displacement Newton (:mod:`ngtmc.discrete.newton`),
the boundary conditions and reactions (:mod:`ngtmc.discrete.boundary_conditions`), and the phase field and
history (:mod:`ngtmc.discrete.phase_field`); the form wrappers are :mod:`ngtmc.discrete.energy_forms`.

Units: mm, N, MPa. Forces and energies returned by this module are for the scene thickness in 2D.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import ngsolve as ngs
from ngsolve.comp import IntegrationRuleSpace

from ngtmc.model import deformation_gradient, gamma_interpolation, gc_interpolation
from ngtmc.discrete.boundary_conditions import BoundaryConditions
from ngtmc.discrete.displacement_energy import DisplacementEnergy
from ngtmc.discrete.energy_forms import _ExternalWork
from ngtmc.discrete.guard import gradient_at_points
from ngtmc.discrete.phase_field import PhaseFieldHistory
from ngtmc.discrete.newton import DISPLACEMENT_RTOL, NewtonOptions, NewtonResult
from ngtmc.scene import Ranks
from ngtmc.discrete.spaces import lower_order_outside
from ngtmc.scene import Point, Support, Traction
from ngtmc.scene import matches, regex, vertices_of
from ngtmc.scene import Scene

__all__ = ["Solver", "NewtonResult", "NewtonOptions", "TIMING_KEYS", "DISPLACEMENT_RTOL"]

#: Mesh size (elements) from which compile="auto" generates C++ code for the energies.
AUTO_REAL_COMPILE_ELEMENTS = 5000
#: Displacement dofs from which compile="auto" generates C++ code for the energies, whatever the
#: number of elements: a 3D element costs several times a triangle (the quick 3D slab: 2613
#: prisms, 15357 dofs, assembly 0.84 s compiled symbolically, 0.37 s as C++; docs/performance.md).
AUTO_REAL_COMPILE_DOFS = 10000

#: Parts of the solution procedure timed in ``Solver.timings`` (seconds, accumulated): tangent
#: assembly, residual evaluation, factorization, triangular solves, line search (trial energies,
#: residuals and J guard), phase-field solve, history update, and recording of a step's row.
TIMING_KEYS = ("assembly", "residual", "factorization", "solve", "line_search", "phase_field", "history", "record")


def _newton_options(newton) -> NewtonOptions:
    """A copy of ``newton`` (a NewtonOptions, a dict of its fields, or None for the defaults), so
    that the object passed in comes back unchanged; TypeError naming an unknown field."""
    if newton is None:
        return NewtonOptions()
    if isinstance(newton, dict):
        fields = [f.name for f in dataclasses.fields(NewtonOptions)]
        unknown = [k for k in newton if k not in fields]
        if unknown:
            raise TypeError(f"newton: unknown option(s) {unknown}; NewtonOptions takes {', '.join(fields)}")
        return NewtonOptions(**newton)
    if not isinstance(newton, NewtonOptions):
        raise TypeError(f"newton must be an ngtmc.NewtonOptions (or a dict of its fields), got {type(newton).__name__}")
    return dataclasses.replace(newton)


class Solver(BoundaryConditions, DisplacementEnergy, PhaseFieldHistory):
    """Fields and solvers of a :class:`~ngtmc.scene.scene.Scene`.

    Attributes worth knowing: ``u`` (displacement GridFunction, mm), ``alpha`` (phase field
    GridFunction or None), ``rho`` (pseudo-density, L2 order 0 GridFunction: the design field),
    ``H`` (history on an IntegrationRuleSpace, MPa), ``load`` (current imposed displacement, mm).

    ``compile``: True compiles the energy expressions symbolically, "real" generates
    and compiles C++ code for them (about 3x faster assembly and residuals; 3-10 s of
    compilation per energy expression, 5 expressions for the quick three-point bending, about
    1.5 s each when an earlier process compiled them (:mod:`ngtmc.discrete.cxx_cache`), so worth it for
    runs of more than a minute; falls back to True with
    a warning where no C++ compiler is available), False evaluates them uncompiled, "auto" (default)
    chooses "real" on meshes of at least AUTO_REAL_COMPILE_ELEMENTS elements or
    AUTO_REAL_COMPILE_DOFS displacement dofs, and True below.

    ``refine_to``: for a run that refines the crack's path as it goes, its target size h_crack
    (mm, :class:`ngtmc.Adaptivity`): the resolution warning of :meth:`Scene.check` then judges
    that size, not the initial mesh.
    """

    def __init__(self, scene: Scene, newton: NewtonOptions | None = None, compile: bool | str = "auto",
                 refine_to: float | None = None):
        scene.check(refine_to)
        self.scene = scene
        # a copy: the options object passed in comes back unchanged (atol is filled in below)
        self.newton = _newton_options(newton)
        self.mesh = mesh = scene.mesh
        #: the scene's regions on the mesh (:class:`~ngtmc.scene.regions.Regions`), built again after a refinement
        self.regions = scene.regions()
        #: reductions over MPI ranks (:mod:`ngtmc.scene.distributed`; the serial expressions on a serial mesh)
        self.ranks = Ranks(mesh)
        self.dim = d = mesh.dim
        self.order = p = scene.displacement_order
        self._compiled = {}  # id(cf) -> (cf, compiled) of _maybe_compile
        self.thickness = float(scene.thickness) if d == 2 else 1.0

        # ------------------------------------------------------------ spaces
        dirichlet = [[] for _ in range(d)]
        point_held = []   # (vertex, component) held or prescribed at single vertices
        for cond in list(scene.supports) + [ld for ld in scene.loads if not isinstance(ld, Traction)]:
            comps = cond.components() if isinstance(cond, Support) else cond.held_components(d)
            for c in comps:
                if isinstance(cond.boundary, Point):
                    point_held.append((cond.boundary.vertex(mesh), c))
                else:
                    dirichlet[c].append(cond.boundary)
        kw = {}
        for c, key in zip(range(d), ("dirichletx", "dirichlety", "dirichletz")):
            if dirichlet[c]:
                kw[key] = regex(dirichlet[c])
        self.fes_u = ngs.VectorH1(mesh, order=p, **kw)
        self._variable_order = p >= 2 and scene.order is None and scene.variable_order and scene.regulariser is not None
        self._point_held = point_held   # (vertex, component): vertices keep their numbers in a refinement
        #: number of times the mesh changed under this solver (:meth:`mesh_changed`, adaptive refinement)
        self.mesh_generation = 0
        self._apply_orders()
        if not (compile in ("auto", "real") or isinstance(compile, bool)):
            raise ValueError(f"compile = {compile!r} is not one of 'auto', 'real', True, False")
        if compile == "auto":  # C++ code generation pays off on larger meshes only
            ndof_u = self.fes_u.ParallelDofs().ndofglobal if self.ranks.parallel else self.fes_u.ndof
            big = self.ranks.sum(mesh.ne) >= AUTO_REAL_COMPILE_ELEMENTS or ndof_u >= AUTO_REAL_COMPILE_DOFS
            compile = "real" if big else True
        self._compile = compile
        self.u = ngs.GridFunction(self.fes_u, name="displacement")
        self._free_dofs()

        self.rho = ngs.GridFunction(ngs.L2(mesh, order=0), name="density")
        self.rho.vec.FV().NumPy()[:] = self.regions.density

        # loads: the Dirichlet values of each displacement load at a given lambda, their reaction
        # weights d u_D / d lambda, and the external work of the tractions
        self.load = 0.0
        self._lam_ext = 0.0
        self._build_loads()

        # ------------------------------------------------------------ material fields
        regions = self.regions.names
        mat_of = self.regions.materials
        # one ngsolve.Parameter per distinct Material, so that derivatives with respect to E, nu,
        # Gc and l0 can be formed symbolically (cf.Diff(parameter)) for sensitivities
        self.material_parameters = {}
        for m in mat_of.values():
            if id(m) not in self.material_parameters:
                self.material_parameters[id(m)] = {k: ngs.Parameter(getattr(m, k)) for k in ("E", "nu", "Gc", "l0")}
        par = {r: self.material_parameters[id(m)] for r, m in mat_of.items()}
        self.E0 = mesh.MaterialCF({r: q["E"] for r, q in par.items()})
        self.K0 = mesh.MaterialCF({r: q["E"] / (3 * (1 - 2 * q["nu"])) for r, q in par.items()})
        self.G0 = mesh.MaterialCF({r: q["E"] / (2 * (1 + q["nu"])) for r, q in par.items()})
        self.Gc0 = mesh.MaterialCF({r: q["Gc"] for r, q in par.items()})
        self.l0 = mesh.MaterialCF({r: q["l0"] for r, q in par.items()})
        self.gamma0 = ngs.Parameter(scene.gamma0)
        self.gamma = gamma_interpolation(self.rho, self.gamma0)
        self.K = self.K0 * self.gamma
        self.G = self.G0 * self.gamma
        self.Gc = self.Gc0 * gc_interpolation(self.rho, scene.gc_a, scene.gc_b)
        self.E_max = max(m.E for m in mat_of.values())
        lo, hi = self._box(np.asarray(mesh.ngmesh.Coordinates()))
        self.length_scale = float(np.linalg.norm(hi - lo))
        if self.newton.atol is None:
            self.newton.atol = 1e-12 * self.E_max * self.length_scale ** (d - 1)

        frac = list(self.regions.fracture_names)
        self.fracture_regions = frac
        others = sorted(r for r in set(regions) if not any(matches(f, r) for f in frac))
        # regions whose elements carry the full order p (all of them unless the order varies)
        high = set(regions) if p >= 2 else set()
        if self._variable_order:
            high = {r for r in regions if matches(self.regions.regulariser_regex, r)}
        self._high_re = regex(sorted(r for r in others if r in high))
        self._low_re = regex(sorted(r for r in others if r not in high))
        # the history lives at the order of the fracture regions' displacement
        frac_high = bool(frac) and any(r in high for r in regions if matches(self.regions.fracture_regex, r))
        p_hist = p if (frac_high or not self._variable_order) else 1

        # ------------------------------------------------------------ history and phase field
        # history points: the rule of order 2 p_hist, p_hist the displacement order of the
        # fracture regions; the J > 0 guard uses the rule of order 2p (6 points on a triangle
        # for p = 2) wherever the order is p
        self.irs = IntegrationRuleSpace(mesh, order=p_hist)
        self._guard_irs = self.irs if p_hist == p else IntegrationRuleSpace(mesh, order=p)
        self.dx_H = ngs.dx(intrules=self.irs.GetIntegrationRules())
        self.H = ngs.GridFunction(self.irs, name="history")
        self._scratch_irs = ngs.GridFunction(self.irs)
        self._scratch_guard = ngs.GridFunction(self._guard_irs)
        self.H_committed = np.zeros(self.irs.ndof)
        self._psi_plus_cf = None   # Psi_plus(u), compiled at its first use (psi_plus_values)
        self._J_cf = None          # det F of u, built at its first use (J_values)
        self._J_op = None          # grad u at the guard points (ngtmc.discrete.guard), likewise
        if frac:
            self.fes_a = ngs.H1(mesh, order=1, definedon=mesh.Materials(self.regions.fracture_regex))
            self.alpha = ngs.GridFunction(self.fes_a, name="alpha")
            self.alpha_committed = np.zeros(self.fes_a.ndof)
            self._build_phase_field()
        else:
            self.fes_a = None
            self.alpha = None
            self.alpha_committed = None

        # ------------------------------------------------------------ displacement energy
        self._quadratic_forms = []   # the QuadraticPlus wrappers of _energy_form, for mesh_changed
        # the integrands of a_u by recorded energy (elastic_energy, regularisation_energy): the
        # forms of energies() are made of the same compiled objects (no compilation of their own)
        self._energy_parts = {}
        self._energy_forms = None
        self.a_u = self._energy_form(self.fes_u.TrialFunction(), parts=self._energy_parts)
        if self._tractions:
            self.a_u = _ExternalWork(self.a_u, self)
        self._a_shift = None
        self._mesh_data(loads=False)  # the loads are built above (the tractions decide the form)
        #: accumulated seconds per part of the solution procedure (see TIMING_KEYS)
        self.timings = dict.fromkeys(TIMING_KEYS, 0.0)
        #: relative residual at which the displacement Newton and the coupled Newton accept an
        #: iterate whose residual no longer falls (None: never; the adjoint's recordings), and the
        #: displacement solves so accepted
        self.floor_rtol = self.newton.floor_rtol
        self.floor_accepts = 0
        #: line searches of the displacement Newton whose energy could not resolve the step
        #: (round-off, ngtmc.discrete.energy_search.NOISE_FRACTION), so that its residual decided
        self.energy_noise_switches = 0

    # ================================================================= mesh-dependent data
    def _apply_orders(self):
        """Order 1 outside the regulariser's regions when the order varies per element
        (:func:`~ngtmc.discrete.spaces.lower_order_outside`); after a refinement every node is set
        again (NGSolve gives new nodes the full order). NGSolve trap: right after a refinement,
        orders set before the space's next Update are undone by it (the three-point bending kept
        order 2 on every edge: 17026 instead of 9866 u dofs), so a refined space is updated, its
        orders set, and updated again."""
        if not self._variable_order:
            return
        refined = self.mesh_generation > 0
        if refined:
            self.fes_u.Update()
        lower_order_outside(self.fes_u, self.mesh, self.regions.regulariser_regex,
                            order=self.order if refined else None)
        if refined:
            self.fes_u.Update()

    def _free_dofs(self):
        """Free-dof mask of the displacement: the space's Dirichlet boundaries, and the vertex
        conditions (Point supports and loads), which are ours, not the space's."""
        self.free = self.fes_u.FreeDofs()
        if self._point_held:
            self.free = ngs.BitArray(self.free)
            for v, c in self._point_held:
                self.free.Clear(self._vertex_dof(v, c))
        self._free_np = np.array(list(self.free), dtype=bool)
        self._dir_np = ~self._free_np

    def _mesh_data(self, loads: bool = True):
        """Everything besides the spaces and forms that depends on the mesh: element sizes, the
        loads' dofs and fields, work vectors, factorizations (dropped)."""
        self.h = self.regions.sizes
        if loads:
            self._build_loads()
        self._inv = None
        self._inv_alpha = None
        self._J_op = None   # grad u at the guard points, built at the next J_values
        self._r = self.u.vec.CreateVector()
        self._du = self.u.vec.CreateVector()
        self._w = self.u.vec.CreateVector()
        self._tmp = self.u.vec.CreateVector()
        self._u0 = self.u.vec.CreateVector()
        self._r_valid = False  # True while self._r holds the residual of the current u
        self._energy_forms = None
        for q in self._quadratic_forms:
            q.mesh_changed()

    def mesh_changed(self):
        """Bring the solver to its (refined) mesh: NGSolve has already updated the spaces and
        prolongated the GridFunctions (``autoupdate``); here the per-node orders, the free-dof
        mask, the pseudo-density (from ``scene.element_density()``, which the caller updates for
        a density given per element), the loads, the constant regulariser matrix, the
        factorizations and work vectors follow. The values of ``u``, ``alpha`` and the history,
        and their committed copies, are the caller's to transfer (:mod:`ngtmc.adapt`); the
        committed arrays are resized here only when their length no longer fits (zeros)."""
        self.mesh_generation += 1
        self.regions = self.scene.regions()
        self._apply_orders()
        self.u.Update()
        self._free_dofs()
        self.rho.vec.FV().NumPy()[:] = self.regions.density
        self._mesh_data()
        if self.H_committed.size != self.irs.ndof:
            self.H_committed = np.zeros(self.irs.ndof)
        if self.alpha is not None and self.alpha_committed.size != self.fes_a.ndof:
            self.alpha_committed = np.zeros(self.fes_a.ndof)

    # ================================================================= J and the fracture box
    def J_values(self) -> np.ndarray:
        """det F at the guard quadrature points (dimensionless), element by element
        (:mod:`ngtmc.discrete.guard`); an array the caller must not keep past the next call."""
        if self._J_op is None:   # the sparse matrix of grad u at the points (ngtmc.discrete.guard), once per mesh
            self._J_op = gradient_at_points(self.fes_u, self._guard_irs, self.dim, self.ranks.parallel) or False
        if self._J_op:
            return self._J_op.det_F(self.u.vec.FV().NumPy())
        if self._J_cf is None:   # built once: building it took about as long as evaluating it
            self._J_cf = ngs.Det(deformation_gradient(self.u))
        self._scratch_guard.Interpolate(self._J_cf)
        return self._scratch_guard.vec.FV().NumPy()

    @property
    def displacement_rtol(self) -> float:
        """Relative residual tolerance of the displacement Newton: ``NewtonOptions.rtol``, or
        DISPLACEMENT_RTOL where that is None."""
        return self.newton.rtol if self.newton.rtol is not None else DISPLACEMENT_RTOL

    def min_J(self) -> float:
        """Smallest det F at the guard quadrature points, dimensionless."""
        return self.ranks.min(self.J_values())

    def fracture_box(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners (mm) of the bounding box of the vertices of the fracture
        regions (of the whole mesh when the scene has none)."""
        mesh = self.mesh
        pts = np.asarray(mesh.ngmesh.Coordinates())[:mesh.nv]
        if self.alpha is not None:
            pts = pts[sorted(vertices_of(mesh, self.regions.fracture_regex))]
        return self._box(pts)

    def _box(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners (mm) of the bounding box of points (rows), over all ranks."""
        if not self.ranks.parallel:
            return pts.min(axis=0), pts.max(axis=0)
        pts = pts.reshape(-1, self.dim) if pts.size else np.zeros((0, self.dim))
        return (np.array([self.ranks.min(pts[:, i]) for i in range(self.dim)]),
                np.array([self.ranks.max(pts[:, i]) for i in range(self.dim)]))

    # ================================================================= state
    def get_state(self) -> dict:
        """Copy of everything needed to restart from this point (numpy arrays)."""
        st = {"u": self.u.vec.FV().NumPy().copy(), "H": self.H_committed.copy(), "load": np.array(self.load)}
        if self.alpha is not None:
            st["alpha"] = self.alpha.vec.FV().NumPy().copy()
            st["alpha_committed"] = self.alpha_committed.copy()
        return st

    def set_state(self, st: dict):
        """Restore a state returned by :meth:`get_state`."""
        self._r_valid = False
        self.u.vec.FV().NumPy()[:] = st["u"]
        self.H_committed = np.array(st["H"], dtype=float).copy()
        self.H.vec.FV().NumPy()[:] = self.H_committed
        self.load = float(st["load"])
        if self.alpha is not None:
            self.alpha.vec.FV().NumPy()[:] = st["alpha"]
            self.alpha_committed = np.array(st["alpha_committed"], dtype=float).copy()

    @property
    def ndof(self) -> dict:
        return {"u": self.fes_u.ndof, "alpha": self.fes_a.ndof if self.fes_a is not None else 0,
                "history_points": self.irs.ndof}
