"""The phase field and the history of :class:`ngtmc.discrete.solver.Solver`: the linear phase-field solve
with the history fixed (step 1 of the paper's scheme), Psi_plus at the history points, the history
update H_n = max(H_{n-1}, Psi_plus(u_n)) (step 3), and the fracture energy W_f of Eq. 19.

:class:`PhaseFieldHistory` is a base of :class:`ngtmc.discrete.solver.Solver`, on whose spaces, fields and
material coefficients it works; the equations are in :mod:`ngtmc.model.fracture` and :mod:`ngtmc.model.splits`.

Units: mm, N, MPa (history and energy densities in MPa, W_f in N mm per mm of thickness in 2D).
"""
from __future__ import annotations

import time

import numpy as np
import ngsolve as ngs

from ngtmc.model import fracture
from ngtmc.model import splits
from ngtmc.discrete.spaces import bilinear_form, rules
from ngtmc.model import deformation_gradient, psi_dev, psi_plus, psi_vol

__all__ = ["PhaseFieldHistory", "history_pieces", "phase_field_piece"]


class PhaseFieldHistory:
    """Phase-field solve, history and fracture energy (a base of :class:`ngtmc.discrete.solver.Solver`)."""

    def _build_phase_field(self):
        a_t, b_t = self.fes_a.TnT()
        dxf = ngs.dx(definedon=self.mesh.Materials(self.regions.fracture_regex))
        dxHf = ngs.dx(definedon=self.mesh.Materials(self.regions.fracture_regex), intrules=self.irs.GetIntegrationRules())
        self.a_alpha = bilinear_form(self.fes_a, symmetric=True)
        self.f_alpha = ngs.LinearForm(self.fes_a)
        bil, lin = fracture.alpha_driving_form(a_t, b_t, self.H, self.Gc, self.l0, dxHf, dxf)
        self.a_alpha += bil
        self.f_alpha += lin
        self._inv_alpha = None

    def solve_phase_field(self, H_values: np.ndarray | None = None) -> int:
        """Solve the linear phase-field equation for alpha with the history fixed (step 1).

        H_values: history at the quadrature points (MPa), default the committed H_{n-1}. The
        solution is projected onto [alpha_{n-1}, 1] (irreversibility; and the consistent P1
        reaction term is not an M-matrix, so unprojected alpha may overshoot 1). Returns the number
        of projected dofs. Returns 0 when the scene has no phase field."""
        if self.alpha is None:
            return 0
        t0 = time.perf_counter()
        self._r_valid = False
        self.H.vec.FV().NumPy()[:] = self.H_committed if H_values is None else H_values
        self.a_alpha.Assemble()
        self.f_alpha.Assemble()
        if self._inv_alpha is None or self.ranks.parallel:  # NGSolve's masterinverse has no Update
            self._inv_alpha = self.a_alpha.mat.Inverse(self.fes_a.FreeDofs(), inverse=self._inverse("sparsecholesky"))
        else:
            self._inv_alpha.Update()
        self.alpha.vec.data = self._inv_alpha * self.f_alpha.vec
        a = self.alpha.vec.FV().NumPy()
        projected = self.ranks.count((a < self.alpha_committed) | (a > 1.0), self.alpha.vec)
        a[:] = np.clip(np.maximum(a, self.alpha_committed), 0.0, 1.0)
        self.timings["phase_field"] += time.perf_counter() - t0
        return projected

    def crack_driving_density(self, F) -> ngs.CoefficientFunction:
        """Psi_plus of the scene's split (:mod:`ngtmc.model.splits`; default the paper's Eq. 6), MPa:
        what the history H_n = max(H_{n-1}, Psi_plus(u_n)) of Eq. 7 takes in, for every
        formulation. F: deformation gradient (CF of a GridFunction or a trial function)."""
        sc = self.scene
        if sc.split == splits.DEFAULT_SPLIT:
            return psi_plus(F, self.K, self.G)
        return splits.split_energy(sc.split, F, self.K, self.G)[0]

    def degraded_density(self, F) -> ngs.CoefficientFunction:
        """The energy density that g(alpha) multiplies in the fracture regions, MPa: Psi_bar of
        Eq. 2 in the hybrid formulation, the split's Psi_plus in the anisotropic one."""
        if self.scene.formulation == "anisotropic":
            return splits.split_energy(self.scene.split, F, self.K, self.G)[0]
        return psi_vol(F, self.K) + psi_dev(F, self.G)

    def psi_plus_values(self) -> np.ndarray:
        """Psi_plus(u) of the scene's split (Eq. 6 by default) at the history quadrature points,
        MPa (a copy)."""
        cf = self._psi_plus_cf
        if cf is None:   # one object, compiled once (symbolically: 30 against 21 ms on the quick L-panel)
            cf = self._psi_plus_cf = self.crack_driving_density(deformation_gradient(self.u)).Compile()
        self._scratch_irs.Interpolate(cf)
        return self._scratch_irs.vec.FV().NumPy().copy()

    def trial_history(self) -> np.ndarray:
        """max(H_{n-1}, Psi_plus(u)) at the quadrature points (Eq. 7), MPa; not committed."""
        t0 = time.perf_counter()
        H = np.maximum(self.H_committed, self.psi_plus_values())
        self.timings["history"] += time.perf_counter() - t0
        return H

    def update_history(self, H_trial: np.ndarray | None = None):
        """Commit H_n = max(H_{n-1}, Psi_plus(u_n)) and alpha_n (step 3). ``H_trial``: the
        already computed :meth:`trial_history` of the current u, to avoid computing it twice."""
        self.H_committed = self.trial_history() if H_trial is None else H_trial
        self.H.vec.FV().NumPy()[:] = self.H_committed
        if self.alpha is not None:
            self.alpha_committed = self.alpha.vec.FV().NumPy().copy()

    def fracture_energy_per_thickness(self) -> float:
        """W_f of Eq. 19, N mm per mm of thickness in 2D (N mm in 3D): int Gc (alpha^2/l0 + l0 |grad alpha|^2)."""
        if self.alpha is None:
            return 0.0
        dens = fracture.fracture_energy_density(self.alpha, self.Gc, self.l0)
        return float(ngs.Integrate(dens, self.mesh, definedon=self.mesh.Materials(self.regions.fracture_regex), order=2))

    def max_alpha(self) -> float:
        return self.ranks.max(self.alpha.vec.FV().NumPy()) if self.alpha is not None else 0.0


def history_pieces(s, u, a, b) -> list:
    """(CF, measure) pairs that turn the alpha-derivative of the degraded elastic energy,
    g'(alpha) Psi_d b, into g'(alpha) H_n(u) b with H_n = max(H_{n-1}, Psi_plus(u)) at the history
    points (Eq. 7 inside the step): one integrand where the elastic terms live at the history
    points (:meth:`~ngtmc.discrete.solver.Solver.elastic_rule_is_history_rule`), else two. ``u``, ``a``:
    displacement and phase field (trial functions or GridFunctions), ``b`` the phase-field test
    function or weight; ``s`` the solver (its ``H`` holds H_{n-1}). Integrands in MPa per unit
    alpha. The one owner of this part of R_alpha: the coupled form and the adjoint
    (:mod:`ngtmc.sensitivities.coupled`) both use it."""
    F = deformation_gradient(u)
    pp = s.crack_driving_density(F)
    H_n = ngs.IfPos(pp - s.H, pp, s.H)
    dg = -2.0 * (1.0 - a)  # g'(alpha) of AT-2; the residual stiffness is a constant
    dxH = ngs.dx(definedon=s.mesh.Materials(s.regions.fracture_regex), intrules=s.irs.GetIntegrationRules())
    if s.elastic_rule_is_history_rule():
        return [(dg * (H_n - s.degraded_density(F)) * b, dxH)]
    return [(dg * H_n * b, dxH), (-dg * s.degraded_density(F) * b, s.energy_measure("elastic_vol", s.regions.fracture_regex))]


def phase_field_piece(s, a, b) -> tuple:
    """(CF, measure) of the phase-field operator of R_alpha, Gc (alpha beta / l0 + l0 grad alpha .
    grad beta) over the fracture regions (Eq. 16), in N/mm^2 per unit alpha; exact for P1 with the
    rule of order 2."""
    cf = s.Gc / s.l0 * a * b + s.Gc * s.l0 * ngs.InnerProduct(ngs.Grad(a), ngs.Grad(b))
    return cf, ngs.dx(definedon=s.mesh.Materials(s.regions.fracture_regex), intrules=rules(s.mesh, 2))
