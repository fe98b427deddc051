"""det F at the guard quadrature points: the J > 0 guard of every line search and predictor, and
the per-element J of the refinement's marking.

The gradient of u at a quadrature point is linear in u's coefficients, so one sparse matrix
holds it for the whole mesh: row (i, j, point) of :class:`GradientAtPoints` gives du_i/dx_j at
that point, the points in the order of the guard's ``IntegrationRuleSpace`` (element by element,
as NGSolve's ``Interpolate`` fills it). det F = det(I + grad u) is then one sparse product and a
few array operations. Measured (``python -m benchmarks.guard``): on the quick three-point bending
(51384 points, one thread) 0.67 against 7.46 ms for ``Interpolate`` of det F, at the paper's
resolution (179628 points, two threads) 3.26 against 16.88 ms; the values agree to 5e-15.

The matrix is built from a mixed form (the points' weights divided out), once per mesh, where
its size stays below GUARD_MAX_ENTRIES; elsewhere (and on a mesh distributed over MPI ranks, or
with ``NGTMC_J_GUARD=interpolate``) det F is interpolated as before. Dimensionless.
"""
from __future__ import annotations

import os

import ngsolve as ngs
import numpy as np
import scipy.sparse as sp

from ngtmc.discrete.sparse import to_scipy

__all__ = ["GradientAtPoints", "gradient_at_points", "estimated_entries", "counted_entries", "GUARD_MAX_ENTRIES",
           "GUARD_ENV"]

#: Largest number of stored entries (guard points x dim^2 x the dofs of one displacement
#: component on their element) for which the matrix is built: 12 bytes each, so at most about
#: 120 MB. The paper three-point bending needs 2.3 million, the quick 3D hemisphere 6.3 million;
#: the paper 3D hemisphere would need 37 million (counted) and interpolates.
GUARD_MAX_ENTRIES = 10_000_000

#: environment variable: ``interpolate`` makes every solver interpolate det F (the way before the
#: matrix; for comparisons, ``python -m benchmarks.guard``)
GUARD_ENV = "NGTMC_J_GUARD"


class GradientAtPoints:
    """grad u at the points of the integration-rule space ``points`` for the vector H1 space
    ``fes_u`` (``dim`` components): :meth:`gradient` and :meth:`det_F` of a coefficient vector."""

    def __init__(self, fes_u, points, dim: int):
        self.dim = dim
        self.n = points.ndof
        u, v = fes_u.TrialFunction(), points.TestFunction()
        dxp = ngs.dx(intrules=points.GetIntegrationRules())
        mass = ngs.BilinearForm(points, diagonal=True)
        mass += points.TrialFunction() * v * dxp
        mass.Assemble()
        weight = np.array(mass.mat.AsVector().FV().NumPy())   # quadrature weight x |det Jacobian|
        blocks = []
        for i in range(dim):
            for j in range(dim):
                b = ngs.BilinearForm(trialspace=fes_u, testspace=points)
                b += ngs.Grad(u)[i, j] * v * dxp
                b.Assemble()
                block = to_scipy(b.mat, (self.n, fes_u.ndof))
                block.eliminate_zeros()   # NGSolve stores every component's dofs in each block
                blocks.append(block)
        #: rows (i, j, point) of du_i/dx_j, dimensionless
        self.matrix = (sp.diags(np.tile(1.0 / weight, dim * dim)) @ sp.vstack(blocks)).tocsr()

    def gradient(self, u: np.ndarray) -> np.ndarray:
        """grad u at the points, shape (dim, dim, points): [i, j] = du_i/dx_j."""
        return (self.matrix @ u).reshape(self.dim, self.dim, self.n)

    def det_F(self, u: np.ndarray) -> np.ndarray:
        """det(I + grad u) at the points."""
        g = self.gradient(u)
        if self.dim == 2:
            return (1.0 + g[0, 0]) * (1.0 + g[1, 1]) - g[0, 1] * g[1, 0]
        a, b, c = 1.0 + g[0, 0], g[0, 1], g[0, 2]
        d, e, f = g[1, 0], 1.0 + g[1, 1], g[1, 2]
        p, q, r = g[2, 0], g[2, 1], 1.0 + g[2, 2]
        return a * (e * r - f * q) - b * (d * r - f * p) + c * (d * q - e * p)


def estimated_entries(fes_u, points, dim: int) -> int:
    """Upper bound of the stored entries of :class:`GradientAtPoints`, without a loop: per row the
    dofs of one component on a quadrilateral or hexahedron of the space's full order, the largest
    element of its dimension."""
    return int(points.ndof) * dim * dim * (int(fes_u.globalorder) + 1) ** dim


def counted_entries(fes_u, points, dim: int) -> int:
    """Upper bound of the stored entries of :class:`GradientAtPoints`, counted element by element
    (a loop over the elements: where the order varies per element most of them hold far fewer
    dofs than :func:`estimated_entries` assumes); the matrix holds fewer where a shape function's
    derivative vanishes at a point (an edge parallel to an axis). Building it holds one block of
    dim times its own entries besides (NGSolve's mixed form stores the other components' dofs
    as zeros)."""
    per_type = {et: len(rule) for et, rule in points.GetIntegrationRules().items()}
    total = sum(len(el.dofs) * per_type[el.type] for el in fes_u.Elements(ngs.VOL))
    return total * dim   # len(el.dofs) / dim per row, dim^2 rows per point


def gradient_at_points(fes_u, points, dim: int, parallel: bool) -> GradientAtPoints | None:
    """The matrix of grad u at ``points``, or None where det F is to be interpolated instead: a
    mesh distributed over ranks, ``NGTMC_J_GUARD=interpolate``, or an estimated size above
    GUARD_MAX_ENTRIES."""
    setting = os.environ.get(GUARD_ENV, "").strip().lower()
    if setting not in ("", "matrix", "interpolate"):
        raise ValueError(f"{GUARD_ENV}={setting!r}: expected 'matrix' or 'interpolate'")
    if parallel or setting == "interpolate":
        return None
    if (estimated_entries(fes_u, points, dim) > GUARD_MAX_ENTRIES
            and counted_entries(fes_u, points, dim) > GUARD_MAX_ENTRIES):
        return None
    return GradientAtPoints(fes_u, points, dim)
