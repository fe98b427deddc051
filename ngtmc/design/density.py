"""The map from design variables to the model's pseudo-density, one link after the other, with
its chain rule (the recipe of density-based topology optimisation):

    x (one per design element, in [0, 1])
      -> xtilde = F y             Helmholtz filter (:class:`~ngtmc.design.filters.HelmholtzFilter`)
                                  of y = x on the design elements, the scene's own density elsewhere
      -> xbar = P_beta(xtilde)    Heaviside projection (:func:`~ngtmc.design.projection.project`)
      -> rho = I(xbar)            penalised interpolation (:class:`~ngtmc.design.interpolation.Interpolation`),
                                  clipped to [0, 1] (the filter's round-off can leave xbar at -1e-14)

``xbar`` is the physical density: what the volume bound counts and what the report draws. The
elements outside the design regions keep the scene's density and enter the filter with it, so a
design element beside a fixed solid sees that solid. Lengths in mm; densities dimensionless."""
from __future__ import annotations

import numpy as np

from ngtmc.design.filters import HelmholtzFilter
from ngtmc.design.interpolation import Interpolation
from ngtmc.design.projection import project, project_derivative
from ngtmc.scene import Scene, matches, regex, region_names

__all__ = ["DesignDensity"]


class DesignDensity:
    """The design of ``scene`` on the regions named by ``design`` (region names, regular
    expressions as everywhere in ngtmc): filter radius ``filter_radius`` (mm), projection
    threshold ``eta`` and sharpness ``beta`` (which a continuation raises: set the attribute),
    ``interpolation`` (an :class:`Interpolation`).

    ``mask``: per element of the mesh, True on a design element; ``n``: the number of design
    variables; ``areas``: the design elements' areas (volumes in 3D), mm^2 (mm^3)."""

    def __init__(self, scene: Scene, design, filter_radius: float, interpolation: Interpolation | None = None,
                 beta: float = 1.0, eta: float = 0.5):
        regions = scene.regions()
        pattern = regex(region_names(design))
        numbers = [i for i, name in enumerate(regions.names) if matches(pattern, name)]
        if not numbers:
            raise ValueError(f"DesignDensity: no region of the mesh matches the design regions {design!r}; "
                             f"the mesh has {', '.join(sorted(set(regions.names)))}")
        self.scene = scene
        self.mask = np.isin(regions.index, numbers)
        self.n = int(self.mask.sum())
        self.fixed = np.asarray(regions.density, dtype=float).copy()
        self.filter = HelmholtzFilter(scene.mesh, filter_radius)
        self.areas = self.filter.areas[self.mask]
        self.interpolation = interpolation or Interpolation()
        self.beta, self.eta = float(beta), float(eta)
        project(0.5, self.beta, self.eta)          # checks beta and eta

    def check(self, x) -> np.ndarray:
        x = np.asarray(x, dtype=float).ravel()
        if x.shape != (self.n,):
            raise ValueError(f"DesignDensity: {x.size} design variables given; the design regions have {self.n} "
                             "elements (one variable per element)")
        if not np.all(np.isfinite(x)):
            raise ValueError("DesignDensity: a design variable is not finite")
        return x

    def filtered(self, x) -> np.ndarray:
        """xtilde on the design elements."""
        y = self.fixed.copy()
        y[self.mask] = self.check(x)
        return self.filter.filter(y)[self.mask]

    def physical(self, x) -> np.ndarray:
        """xbar on the design elements (what the volume counts)."""
        return project(self.filtered(x), self.beta, self.eta)

    def rho(self, x) -> np.ndarray:
        """The model's pseudo-density of every element of the mesh."""
        rho = self.fixed.copy()
        rho[self.mask] = np.clip(self.interpolation(self.physical(x)), 0.0, 1.0)   # round-off of the filter
        return rho

    def chain(self, x, g_rho=None, g_xbar=None) -> np.ndarray:
        """dJ/dx of a function J of the design, from its gradient ``g_rho`` with respect to the
        pseudo-density of every element (the adjoint's ``g["rho"]``) and/or ``g_xbar`` with
        respect to the physical density of the design elements."""
        xt = self.filtered(x)
        xb = project(xt, self.beta, self.eta)
        g = np.zeros(self.n)
        if g_rho is not None:
            inside = (xb >= 0.0) & (xb <= 1.0)        # rho is clipped to [0, 1] outside
            g += np.where(inside, self.interpolation.derivative(xb), 0.0) * np.asarray(g_rho, dtype=float)[self.mask]
        if g_xbar is not None:
            g += np.asarray(g_xbar, dtype=float)
        full = np.zeros(self.mask.size)
        full[self.mask] = project_derivative(xt, self.beta, self.eta) * g
        return self.filter.transpose(full)[self.mask]

    def volume(self, x) -> float:
        """The physical volume fraction of the design regions, sum |e| xbar_e / sum |e|."""
        return float(self.areas @ self.physical(x) / self.areas.sum())

    def volume_gradient(self, x) -> np.ndarray:
        return self.chain(x, g_xbar=self.areas / self.areas.sum())
