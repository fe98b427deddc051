"""The displacement energy as forms: the wrappers that give a sum of an NGSolve form and another
term the interface the Newton solvers use (Apply, Energy, AssembleLinearization, mat), and the
merging of the energy terms that share a measure.

Units: energies N mm (per mm of thickness in 2D), residuals N.
"""
from __future__ import annotations

import ngsolve as ngs

__all__ = ["merged_terms"]


def merged_terms(terms: list) -> list:
    """The (name, density, regions) terms of :meth:`Solver.energy_terms` with the elastic terms of
    one region set summed into one density, named after the first: their measure is the same
    (:meth:`Solver.energy_measure` depends on the regions only), and one integrand evaluates the
    shared F, J and invariants once. Three-point bending quick, coupled tangent: 40 -> 28 ms for
    the two terms of the fracture regions (one thread)."""
    out, sums = [], {}
    for name, density, regions in terms:
        if out and "regularisation" not in (name, out[-1][0]) and out[-1][2] == regions:
            key = (id(out[-1][1]), id(density))  # the same pair of objects gives the same sum object
            if key not in sums:
                sums[key] = (out[-1][1], density, out[-1][1] + density)
            out[-1] = (out[-1][0], sums[key][2], regions)
        else:
            out.append((name, density, regions))
    return out


class _ExternalWork:
    """The energy form minus the work of the tractions, lambda <f, u>, with the form's interface
    (Apply, Energy, AssembleLinearization, mat). lambda is ``solver._lam_ext``: the load of the
    Newton solve under way, or the current load for a reaction. The tangent is the form's (dead
    loads)."""

    def __init__(self, form, solver):
        self.form, self.solver = form, solver

    @property
    def f(self):
        """The traction vector per unit lambda (the solver's, rebuilt when the mesh changes)."""
        return self.solver._f_ext

    def Apply(self, x, y):
        self.form.Apply(x, y)
        y.data -= self.solver._lam_ext * self.f

    def Energy(self, x) -> float:
        return self.form.Energy(x) - self.solver._lam_ext * ngs.InnerProduct(self.f, x)

    def AssembleLinearization(self, x):
        self.form.AssembleLinearization(x)

    @property
    def mat(self):
        return self.form.mat


class QuadraticPlus:
    """A nonlinear energy form plus a constant quadratic one, 1/2 u.K u, with the interface of an
    NGSolve BilinearForm that the solvers use (Apply, Energy, AssembleLinearization, mat).

    The regulariser of Eq. 3 is quadratic in u, so its tangent K is assembled once (and again
    only when ``key()`` changes: the density or a material parameter): at 35k dofs that saves
    about a fifth of each tangent assembly. K has the sparsity pattern of the form's matrix (a
    zero term on every element sees to that); this is checked."""

    def __init__(self, form, quadratic, key):
        self.form, self.quadratic, self.key = form, quadratic, key
        self.mesh_changed()

    def mesh_changed(self):
        """New vectors for the space's new size; K is assembled again at its next use."""
        self._key = None
        self._zero = ngs.GridFunction(self.quadratic.space).vec
        self._t = self._zero.CreateVector()

    @property
    def K(self):
        """The constant tangent, assembled again when the density or a parameter changed."""
        k = self.key()
        if k != self._key:
            self.quadratic.AssembleLinearization(self._zero)
            self._key = k
        return self.quadratic.mat

    def Apply(self, x, y):
        K = self.K
        self.form.Apply(x, y)
        y.data += K * x

    def Energy(self, x) -> float:
        K = self.K
        self._t.data = K * x
        return self.form.Energy(x) + 0.5 * ngs.InnerProduct(x, self._t)

    def AssembleLinearization(self, x):
        K = self.K
        self.form.AssembleLinearization(x)
        if self.form.mat.nze != K.nze:
            raise RuntimeError("the constant regulariser matrix has another sparsity pattern than the tangent")
        self.form.mat.AsVector().data += K.AsVector()

    @property
    def mat(self):
        return self.form.mat
