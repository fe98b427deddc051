"""Design by gradient: density-based topology optimisation on the adjoint of
:mod:`ngtmc.sensitivities` (the recipe of the third-medium-contact literature).

* :class:`TopologyOptimisation`: a scene of one's own, its design regions, an objective and a
  volume bound in, the optimised design out (:mod:`ngtmc.design.topology`);
* its links, usable alone: the map from design variables to pseudo-density
  (:class:`DesignDensity`: a Helmholtz (PDE) density filter :class:`HelmholtzFilter`, a Heaviside
  projection :func:`project` with :func:`project_derivative`, SIMP or RAMP :class:`Interpolation`),
  the robust evaluation of one design with its gradient check (:class:`DesignEvaluation`), and
  the method of moving asymptotes from nlopt (:func:`mma`, the ``design`` extra:
  ``pip install ngtmc[design]``).

Densities are per element and dimensionless; lengths in mm."""
from ngtmc.design.density import DesignDensity
from ngtmc.design.evaluation import DesignEvaluation, DesignFailure
from ngtmc.design.filters import HelmholtzFilter
from ngtmc.design.interpolation import Interpolation
from ngtmc.design.optimiser import OptimisationResult, mma
from ngtmc.design.projection import project, project_derivative
from ngtmc.design.topology import TopologyOptimisation, TopologyResult

__all__ = ["TopologyOptimisation", "TopologyResult", "DesignDensity", "DesignEvaluation", "DesignFailure",
           "HelmholtzFilter", "Interpolation", "project", "project_derivative", "mma", "OptimisationResult"]
