"""Design by gradient: the pieces of density-based topology optimisation around the adjoint of
:mod:`ngtmc.sensitivities` (the recipe of the third-medium-contact literature): a Helmholtz (PDE)
density filter (:class:`HelmholtzFilter`), a Heaviside projection with its derivative
(:func:`project`, :func:`project_derivative`), and the method of moving asymptotes from nlopt
(:func:`mma`, the ``design`` extra: ``pip install ngtmc[design]``). Densities are per element and
dimensionless; lengths in mm."""
from ngtmc.design.filters import HelmholtzFilter
from ngtmc.design.optimiser import OptimisationResult, mma
from ngtmc.design.projection import project, project_derivative

__all__ = ["HelmholtzFilter", "project", "project_derivative", "mma", "OptimisationResult"]
