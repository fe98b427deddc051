"""Monolithic Newton solve of one load step on (u, alpha) together.

With the history of the step inside the iteration, the discrete equations of step n are (Eq. 16
with Eq. 7 evaluated at the current u, hybrid AT-2, g = (1 - alpha)^2 + k, c_w = 2)

    R_u     = int g(alpha) P(F) : grad v  +  int k_r (Hu : Hv - 1/d Lu . Lv) I_void        = 0
    R_alpha = int ( g'(alpha) H_n(u) + Gc alpha / l0 ) beta + Gc l0 grad alpha . grad beta  = 0
    H_n(u)  = max(H_{n-1}, Psi_plus(u))                 at the history points
    alpha_{n-1} <= alpha <= 1                           (irreversibility, and the P1 bound)

so damage is not lagged by one step: the step ends in the state the paper's single-pass scheme
reaches only as its steps shrink to zero. The tangent is not symmetric (the hybrid split drives
alpha with Psi_plus, the displacement sees g(alpha) Psi_bar), so it is factorized with UMFPACK.

Psi_plus is that of ``Scene.split``; with ``Scene.formulation == "anisotropic"`` R_u degrades only
Psi_plus (the energy g(alpha) Psi_plus + Psi_minus of :mod:`ngtmc.model.splits`): the monolithic scheme
uses the scene's pair.

The bounds on alpha are complementarity conditions, solved by a semi-smooth Newton method on
mid(alpha - alpha_{n-1}, c R_alpha, alpha - 1) = 0 (c the inverse lumped (Gc/l0) mass of the
dof): a dof is held on its bound where that is the median, else its equation R_alpha = 0 is
solved. Iterates may leave the bounds (the P1 phase-field operator is no M-matrix, so a projected
step would undo the Newton step); the converged state satisfies them. Newton steps are damped by a backtracking line search on a
scaled residual norm (the hybrid system has no energy) with the guard of the displacement solver:
finite residual and J > 0 at every history point. The iteration of one solve is
:class:`ngtmc.coupled.iteration.Iteration`; this module holds the forms, the scales and the
settings that outlive it.

Units: mm, N, MPa; residual norms of the displacement equation in N (per scene thickness in 2D).
"""
from __future__ import annotations

import numpy as np
import ngsolve as ngs

from ngtmc.coupled.linear import LINEAR_SOLVERS, CoupledLinearSolver
from ngtmc.discrete import Dissipation
from ngtmc.discrete import bilinear_form
from ngtmc.discrete import QuadraticPlus, merged_terms
from ngtmc.discrete import NewtonResult
from ngtmc.discrete import meets
from ngtmc.discrete import history_pieces, phase_field_piece

__all__ = ["CoupledNewton", "LINEAR_SOLVERS"]

from ngtmc.coupled.iteration import Iteration
from ngtmc.coupled.settings import BORDERED, COUPLED_RTOL, FACTOR_REUSE, RELAX_DISSIPATION, WEAK_STOP


class CoupledNewton:
    """Newton on (u, alpha) for a :class:`~ngtmc.discrete.solver.Solver` with a phase field.

    The solver's ``u``, ``alpha`` and committed history ``H_committed`` / ``alpha_committed`` are
    read and written; nothing is committed here (the caller commits the history when it accepts
    the step). Convergence: the displacement residual below ``NewtonOptions.rtol`` (None, the
    default: COUPLED_RTOL) times the reaction scale plus its atol, and the phase-field
    complementarity residual below ``alpha_tol`` (None, the default: the same as that rtol) times
    the residual of a uniform unit alpha (dimensionless); ``max_iterations``: per attempt;
    ``linear_solver``, ``gmres_rtol``, ``gmres_maxsteps``, ``factor_reuse``, ``bordered``: of the linear solves
    (:class:`~ngtmc.coupled.linear.CoupledLinearSolver`); ``relax_dissipation``: whether solves under
    dissipation control relax the displacement where they stall (RELAX_DISSIPATION)."""

    def __init__(self, solver, alpha_tol: float | None = None, max_iterations: int = 15, linear_solver: str = "block-gmres",
                 gmres_rtol: float = 1e-8, gmres_maxsteps: int = 100, weak_stop: bool = WEAK_STOP,
                 factor_reuse: bool = FACTOR_REUSE, bordered: bool = BORDERED,
                 relax_dissipation: bool = RELAX_DISSIPATION):
        if solver.alpha is None:
            raise ValueError("CoupledNewton needs a scene with fracture regions (no phase field to couple)")
        if solver._tractions:
            raise ValueError("the monolithic scheme does not handle Traction loads (force control); use "
                             "scheme='single-pass' or 'staggered', or a displacement load")
        CoupledLinearSolver.check(linear_solver, gmres_rtol)  # before the (costly) form
        if not (isinstance(factor_reuse, bool) or factor_reuse == "auto"):
            raise ValueError(f"coupled factor_reuse = {factor_reuse!r} must be True, False or 'auto' (3D meshes only)")
        if not isinstance(bordered, bool):
            raise ValueError(f"coupled bordered = {bordered!r} must be True or False")
        self.bordered = bordered
        if not isinstance(relax_dissipation, bool):
            raise ValueError(f"coupled relax_dissipation = {relax_dissipation!r} must be True or False")
        #: solves under dissipation control relax the displacement too (RELAX_DISSIPATION)
        self.relax_dissipation = relax_dissipation
        #: keep block-GMRES's u-u factor while it pays (:data:`ngtmc.coupled.settings.FACTOR_REUSE`)
        self.factor_reuse = solver.mesh.dim == 3 if factor_reuse == "auto" else factor_reuse
        #: solves accepted at the residual floor (the solver's ``floor_rtol``, shared with the
        #: displacement Newton; None: never, as in the adjoint's recordings), and their largest
        #: relative residual
        self.floor_accepts = 0
        #: Newton iterations that took a Levenberg step (LEVENBERG_SHIFTS)
        self.levenberg_steps = 0
        #: displacement relaxations at fixed alpha (``solve`` docstring), and whether they are
        #: allowed (the adjoint's recording switches them off: a relaxation may reach another of
        #: two nearby equilibria, so the replays of a finite-difference check need not follow it)
        self.relaxations = 0
        self.relax = True
        self.floor_worst = 0.0
        #: the dissipated energy D of path following (:mod:`ngtmc.discrete.dissipation`)
        self.D = Dissipation(solver)
        self.load_solved = None
        self.s = s = solver
        #: relative residual tolerance of the displacement part: NewtonOptions.rtol, else COUPLED_RTOL
        self.rtol = float(s.newton.rtol) if s.newton.rtol is not None else COUPLED_RTOL
        self.alpha_tol = float(alpha_tol) if alpha_tol is not None else self.rtol
        self.max_iterations = int(max_iterations)
        if not isinstance(weak_stop, bool):
            raise ValueError(f"coupled weak_stop = {weak_stop!r} must be True or False")
        #: an iteration whose Newton step was weak (below WEAK_STEP) and that no Levenberg step
        #: improved ends the attempt as stalled (WEAK_STOP)
        self.weak_stop = weak_stop
        self.linear_solver = linear_solver
        self._gmres = (gmres_rtol, gmres_maxsteps)
        self.X = ngs.FESpace([s.fes_u, s.fes_a])
        self.x = ngs.GridFunction(self.X)
        self.form = self._build_form()
        self._mesh_data()

    def mesh_changed(self):
        """Follow the solver to its refined mesh (:mod:`ngtmc.adapt`, after
        :meth:`ngtmc.discrete.solver.Solver.mesh_changed`): the compound space and its GridFunction, the
        free-dof mask, the work vectors, the linear solver, the scales of the alpha residual and the
        dissipation matrix follow. The residual and tangent forms are kept (NGSolve updates them
        with the space), so their integrands are not compiled again: a new CoupledNewton cost about
        25 s of C++ compilation on the quick three-point bending."""
        self.X.Update()
        self.x.Update()
        self.form.mesh_changed()
        self.D.reset()
        self._mesh_data()

    def _mesh_data(self):
        """What depends on the mesh and the dofs, beside the forms: free dofs, work vectors, the
        linear solver, the scales of the alpha residual and of the complementarity function."""
        s = self.s
        self.nu = s.fes_u.ndof
        if self.X.ndof != self.nu + s.fes_a.ndof:
            raise RuntimeError(f"the coupled space has {self.X.ndof} dofs, its parts {self.nu} + {s.fes_a.ndof}")
        self._free_base = np.array(list(self.X.FreeDofs()), dtype=bool)
        self._free_base[:self.nu] = s._free_np  # vertex conditions live in the solver's mask
        #: factorizations of the assembled tangent (:mod:`ngtmc.coupled.linear`)
        self.lin = CoupledLinearSolver(self.form, self.nu, self.linear_solver, *self._gmres, ranks=s.ranks,
                                       factor_reuse=self.factor_reuse, bordered=self.bordered)
        self._r = self.x.vec.CreateVector()
        self._rc = self.x.vec.CreateVector()  # MPI: a residual with its ranks' parts summed
        self._dx = self.x.vec.CreateVector()
        self._w = self.x.vec.CreateVector()
        if s.ranks.parallel:  # filled from numpy with values that agree on every rank
            self._w.SetParallelStatus(ngs.PARALLEL_STATUS.CUMULATED)
        self._tmp = self.x.vec.CreateVector()
        self._x0 = self.x.vec.CreateVector()
        # scale of the alpha residual: (Gc / l0) times the lumped mass, for alpha of order one
        b = s.fes_a.TestFunction()
        lump = ngs.LinearForm(s.fes_a)
        lump += s.Gc / s.l0 * b * ngs.dx(definedon=s.mesh.Materials(s.regions.fracture_regex))
        lump.Assemble()
        if s.ranks.parallel:
            lump.vec.Cumulate()
        d = lump.vec.FV().NumPy().copy()
        self.alpha_residual_scale = s.ranks.norm_of(d, lump.vec)
        # scale of the complementarity function: alpha - bound against R_alpha / d (dimensionless)
        self._ncp_scale = 1.0 / np.maximum(d, 1e-300 * max(s.ranks.max(d), 1e-300))

    def _build_form(self):
        """The coupled residual form (non-symmetric). The degraded elastic energy enters as a
        Variation on (u, alpha), which gives R_u and the alpha-residual g'(alpha) Psi_d, Psi_d the
        degraded density (Psi_bar in the hybrid formulation, the split's Psi_plus in the
        anisotropic one); Psi_d is replaced there by H_n(u) (the term at the history points),
        with Psi_plus of the scene's split. So the monolithic scheme follows ``Scene.split`` and
        ``Scene.formulation``.

        The terms with a constant tangent, the phase-field operator (Gc/l0 alpha beta + Gc l0
        grad alpha . grad beta) and the Hessian regulariser (quadratic in u), are assembled once
        into a constant matrix K that is added to each tangent and whose K x is added to each
        residual (:class:`~ngtmc.discrete.energy_forms.QuadraticPlus`, again only when the density or a material
        parameter changes). Elastic terms of one region set are one integrand
        (:func:`~ngtmc.discrete.energy_forms.merged_terms`), and the replacement of Psi_d by H_n is one term where
        both live at the same points. Three-point bending quick, one thread: tangent assembly
        100 -> 45 ms, residual 22 -> 10 ms (docs/performance.md)."""
        s = self.s
        (u, a), (_, b) = self.X.TnT()
        A = bilinear_form(self.X, symmetric=False)
        # MPI: the constant-tangent wrapper adds the ranks' local matrices; the terms are folded in
        K = A if s.ranks.parallel else bilinear_form(self.X, symmetric=False)
        for name, density, regions in merged_terms(s.energy_terms(u, alpha=a)):
            if name == "regularisation" and s.scene.regulariser.damping == "none":
                # quadratic in u: constant tangent, assembled once (not worth a compilation)
                K += ngs.Variation(density * s.energy_measure(name, regions))
            else:
                A += ngs.Variation(s._maybe_compile(density) * s.energy_measure(name, regions))
        for cf, measure in history_pieces(s, u, a, b):
            A += s._maybe_compile(cf) * measure
        cf, measure = phase_field_piece(s, a, b)
        K += cf * measure
        if K is A:
            return A
        # a zero term on every element gives K the sparsity pattern of the tangent
        K += ngs.Variation(ngs.Parameter(0.0) * (ngs.InnerProduct(u, u) + a * a) * ngs.dx)
        return QuadraticPlus(A, K, s._design_key)

    # ------------------------------------------------------------------ state transfer
    def _gather(self):
        xN = self.x.vec.FV().NumPy()
        xN[:self.nu] = self.s.u.vec.FV().NumPy()
        xN[self.nu:] = self.s.alpha.vec.FV().NumPy()

    def _scatter(self):
        xN = self.x.vec.FV().NumPy()
        self.s.u.vec.FV().NumPy()[:] = xN[:self.nu]
        self.s.alpha.vec.FV().NumPy()[:] = xN[self.nu:]

    # ------------------------------------------------------------------ solve
    def solve(self, load: float, alpha_upper: np.ndarray | None = None, dissipation: float | None = None,
              load_bounds: tuple[float, float] | None = None) -> NewtonResult:
        """Solve step ``load`` (imposed displacement, mm) from the current (u, alpha).

        ``alpha_upper``: upper bounds of alpha per dof (default 1). A bound below 1 caps the damage
        increment of a sub-step (see :meth:`ngtmc.stepping.schemes.StepSchemes._attempt_monolithic`);
        after a converged solve, :attr:`cap_binding` tells whether a cap below 1 is active (the
        crack wants to grow further at this load). On success the solver holds the converged u and
        alpha (H not committed). On failure it holds the last iterate; the caller restores its
        saved state.

        ``dissipation`` (N mm per mm of thickness in 2D): path following. The load becomes an
        unknown, and the step is closed by the constraint D(alpha) - D(alpha_{n-1}) =
        ``dissipation`` (dissipation control, :attr:`D`); ``load`` is the first
        guess, and the current u must hold the boundary values of ``load``. Each Newton step is
        the bordered solution of the linearised equations: two solves with one factorization,
        x = a + dlambda b, with b the response to a unit load change, and dlambda from the
        linearised constraint. The converged load is :attr:`load_solved` (mm); it may be below
        the load of the last step (a snap-back). ``load_bounds`` (mm): the load must stay in this
        interval (else the solve fails)."""
        return Iteration(self, load, alpha_upper, dissipation, load_bounds).run()

    def _converged(self, res_u, res_a, g, reac, rtol, tol_a, scale_g, g_rtol: float = 1e-6) -> bool:
        """Convergence test: displacement residual (N) below ``rtol`` times the iterate's reaction
        on the dofs the loads move ``reac`` (:func:`ngtmc.discrete.newton.meets`; no residual
        of the step) plus
        the solver's atol, complementarity residual below ``tol_a``, and (path following, with
        ``scale_g`` the dissipation step) the constraint to ``g_rtol`` of the step (1e-6; at the
        residual floor FLOOR_RTOL: the quick L-panel's crack run, path following, stalled with
        the constraint at 3e-8 N mm = 4e-6 of a dissipation step of 0.0066 N mm (1/1600 of its
        base after cut-backs), the active set of alpha = alpha_n changing by a few dofs per
        iteration, both residuals met; it failed at the minimum increment there)."""
        s = self.s
        return (meets(res_u, reac, rtol, s.newton.atol) and res_a <= tol_a
                and (scale_g is None or abs(g) <= g_rtol * scale_g))


    @property
    def gmres_iterations(self) -> list:
        """GMRES iterations of each block-GMRES solve (diagnostics)."""
        return self.lin.gmres_iterations
