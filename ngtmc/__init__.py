"""ngtmc: third-medium contact and phase-field fracture on NGSolve.

Structures that touch themselves and break, in one variational model: bodies embedded in a very
soft hyperelastic "void" that stiffens as it is squeezed (third-medium contact), unified with AT-2
phase-field fracture (hybrid formulation with a history variable), driven by an adaptive
displacement control, and differentiable with respect to the material layout.

Unit system: mm, N, MPa (N/mm^2); energies in N mm. In 2D (plane strain) forces and energies are
for the scene's thickness in mm.

Model: Ciceri, Aveline, Thillaithevan, Hewson, Santer, "A differentiable variational model for
structural self-contact and fracture", Engineering with Computers (2026).
"""
from .materials import Material
from .scene import DisplacementField, DisplacementLoad, Point, Regulariser, ResolutionWarning, Scene, Support, Traction
from .simulation import HISTORY_UNITS, Simulation, SimulationResult, StepFailure, simulate
from .solver import NewtonOptions, Solver
from .stepping import AdaptiveStepControl, Schedule

__version__ = "0.1.0"

__all__ = [
    "Material", "Scene", "Support", "DisplacementLoad", "DisplacementField", "Traction", "Point", "Regulariser",
    "ResolutionWarning",
    "Solver", "NewtonOptions", "Simulation", "SimulationResult", "StepFailure", "simulate",
    "HISTORY_UNITS", "Schedule", "AdaptiveStepControl", "__version__",
]

from .study import Case, list_studies, load_study  # noqa: E402
from .runner import run_study  # noqa: E402

__all__ += ["Case", "list_studies", "load_study", "run_study"]

from . import sensitivities  # noqa: E402
from .sensitivities import differentiate, gradient, record_path  # noqa: E402

__all__ += ["sensitivities", "differentiate", "gradient", "record_path"]
