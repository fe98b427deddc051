"""The energy the phase field has dissipated, D = W_f / c_w = 1/2 alpha^T M alpha (Eq. 19 with
c_w = 2 of AT-2), M the matrix of the phase-field operator of Eq. 16 over the fracture regions
(:func:`ngtmc.discrete.phase_field.phase_field_piece`, its one owner). Path following closes its steps with D
(:mod:`ngtmc.stepping.path`), the coupled Newton differentiates it, and the adjoint of path following
needs its gradient M alpha (:mod:`ngtmc.sensitivities.coupled`).

On a distributed mesh, :meth:`Dissipation.gradient` is each rank's part of M alpha and
:meth:`Dissipation.dot` sums the products over the ranks.

Units: N mm per mm of thickness in 2D (N mm in 3D); alpha dimensionless.
"""
from __future__ import annotations

import numpy as np
import ngsolve as ngs
from ngtmc.discrete.phase_field import phase_field_piece

__all__ = ["Dissipation"]


class Dissipation:
    """D(alpha) = 1/2 alpha^T M alpha of a :class:`~ngtmc.discrete.solver.Solver`'s phase field. M is
    assembled on first use and again when the design or a material parameter changes
    (``Solver._design_key``) or after :meth:`reset` (a refined mesh)."""

    def __init__(self, solver):
        self.s = solver
        self._form = None
        self._key = None

    def reset(self):
        """Forget M (the mesh changed)."""
        self._form = None

    def _assemble(self):
        s = self.s
        key = s._design_key()
        if self._form is not None and self._key == key:
            return
        a, b = s.fes_a.TnT()
        cf, measure = phase_field_piece(s, a, b)
        M = ngs.BilinearForm(s.fes_a, symmetric=True)
        M += cf * measure
        M.Assemble()
        self._form, self._key = M, key
        self._x = M.mat.CreateColVector()
        if s.ranks.parallel:  # filled from numpy with alpha values that agree on every rank
            self._x.SetParallelStatus(ngs.PARALLEL_STATUS.CUMULATED)
        self._y = M.mat.CreateColVector()

    def value(self, alpha: np.ndarray | None = None) -> float:
        """D of the solver's alpha, or of the dof values ``alpha`` (N mm per mm of thickness in 2D)."""
        a = self.s.alpha.vec.FV().NumPy() if alpha is None else alpha
        return 0.5 * self.dot(a, self.gradient(a))

    def gradient(self, alpha: np.ndarray) -> np.ndarray:
        """M alpha = dD/dalpha (N mm per unit alpha, per thickness in 2D); on a distributed mesh
        this rank's part of it (sum products with :meth:`dot`)."""
        self._assemble()
        self._x.FV().NumPy()[:] = alpha
        self._y.data = self._form.mat * self._x
        return self._y.FV().NumPy().copy()

    def dot(self, a: np.ndarray, grad: np.ndarray) -> float:
        """a . grad for an alpha-like array ``a`` (equal on every rank that shares a dof) and a
        :meth:`gradient` ``grad``, summed over the ranks."""
        return self.s.ranks.sum(float(a @ grad))

    def fracture_mean(self, cf) -> float:
        """Mean of the coefficient ``cf`` over the fracture regions (area or volume weighted)."""
        s = self.s
        frac = s.mesh.Materials(s.regions.fracture_regex)
        area = ngs.Integrate(ngs.CoefficientFunction(1.0), s.mesh, definedon=frac)
        return float(ngs.Integrate(cf, s.mesh, definedon=frac)) / float(area)

    def reference_toughness(self) -> float:
        """Mean Gc over the fracture regions, N/mm: converts a crack advance (mm) into a
        dissipation increment (N mm per mm of thickness)."""
        return self.fracture_mean(self.s.Gc)
