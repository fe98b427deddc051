"""The Helmholtz (PDE) density filter of element densities (Lazarov and Sigmund 2011):

    -r^2 Laplace(u) + u = rho    in the mesh, grad(u) . n = 0 on its boundary,

solved in H1 (order 1) with rho piecewise constant, and the filtered density of an element is the
mean of u over it (its L2 projection onto constants). As a matrix, x_f = F x with
F = D^-1 B^T K^-1 B: B the coupling of H1 test functions to element constants, K the filter's
stiffness, D the element areas (volumes in 3D). F maps constants to themselves; its transpose
carries a gradient with respect to the filtered densities back to the design variables:
dJ/dx = F^T dJ/dx_f. The filter radius ``radius`` (mm) is r = radius / (2 sqrt 3), the length
over which a density filter of that radius smooths (Lazarov and Sigmund's rule)."""
from __future__ import annotations

import math

import numpy as np
import ngsolve as ngs
import scipy.sparse.linalg as spla

from ngtmc.discrete import to_scipy

__all__ = ["HelmholtzFilter"]


class HelmholtzFilter:
    """The filter of :mod:`ngtmc.design.filters` on ``mesh`` (2D or 3D, any element type NGSolve
    meshes), of radius ``radius`` (mm, > 0). ``filter(x)``: the filtered element densities of the
    element densities ``x`` (array of length ``mesh.ne``); ``transpose(g)``: F^T g. The filter's
    matrix is factorized once (scipy's sparse LU)."""

    def __init__(self, mesh, radius: float):
        radius = float(radius)
        if not (math.isfinite(radius) and radius > 0.0):
            raise ValueError(f"HelmholtzFilter: radius = {radius!r} mm must be a finite number > 0")
        self.mesh, self.radius = mesh, radius
        r = radius / (2.0 * math.sqrt(3.0))
        V = ngs.H1(mesh, order=1)
        Q = ngs.L2(mesh, order=0)
        u, v = V.TnT()
        p, q = Q.TnT()
        k = ngs.BilinearForm(V, symmetric=True)
        k += (r * r * ngs.InnerProduct(ngs.Grad(u), ngs.Grad(v)) + u * v) * ngs.dx
        k.Assemble()
        b = ngs.BilinearForm(trialspace=Q, testspace=V)
        b += p * v * ngs.dx
        b.Assemble()
        ne, nv = Q.ndof, V.ndof
        if ne != mesh.ne:
            raise ValueError(f"HelmholtzFilter: {ne} element constants for {mesh.ne} elements")
        self._K = spla.splu(to_scipy(k.mat, (nv, nv)).tocsc())
        self._B = to_scipy(b.mat, (nv, ne))
        #: element areas (volumes in 3D), mm^2 (mm^3): B^T 1 summed over the element's nodes
        self.areas = np.asarray(self._B.sum(axis=0)).ravel()

    def filter(self, x) -> np.ndarray:
        """F x: the filtered element densities (dimensionless) of ``x`` (one per element)."""
        x = self._check(x)
        return (self._B.T @ self._K.solve(self._B @ x)) / self.areas

    def transpose(self, g) -> np.ndarray:
        """F^T g: the gradient with respect to the design densities of a gradient ``g`` with
        respect to the filtered ones."""
        g = self._check(g)
        return self._B.T @ self._K.solve(self._B @ (g / self.areas))

    def _check(self, x) -> np.ndarray:
        x = np.asarray(x, dtype=float).ravel()
        if x.shape != (self.mesh.ne,):
            raise ValueError(f"HelmholtzFilter: {x.size} values for {self.mesh.ne} elements (one per element)")
        return x
