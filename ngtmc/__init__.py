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
import importlib.util as _importlib_util
from pathlib import Path as _Path
import sys as _sys


class _SourceTreeStudies:
    """Finds the subpackage ``ngtmc.studies`` in the folder ``studies/`` beside this package.

    The studies live in ``studies/`` at the top of the repository and install as ``ngtmc.studies``
    (``package-dir`` in pyproject.toml). A wheel holds them in ``ngtmc/studies``; a source tree
    (run with ``PYTHONPATH=<tree>`` or installed editable) has them beside ``ngtmc/``, and this
    finder imports them from there, from the same tree as the ``ngtmc`` being imported."""

    folder = _Path(__file__).resolve().parent.parent / "studies"

    @classmethod
    def find_spec(cls, fullname, path=None, target=None):
        if fullname != "ngtmc.studies":
            return None
        return _importlib_util.spec_from_file_location(fullname, cls.folder / "__init__.py",
                                                       submodule_search_locations=[str(cls.folder)])


if (not (_Path(__file__).resolve().parent / "studies").is_dir()
        and (_SourceTreeStudies.folder / "__init__.py").is_file()
        and _SourceTreeStudies not in _sys.meta_path):
    _sys.meta_path.insert(0, _SourceTreeStudies)

from ngtmc.model import Material  # noqa: E402
from ngtmc.scene import DisplacementField, DisplacementLoad, Point, Support, Traction  # noqa: E402
from ngtmc.scene import Regulariser, Scene  # noqa: E402
from ngtmc.scene import ElementWarning, ResolutionWarning
from ngtmc.scene import ScaleWarning  # noqa: E402
from ngtmc.scene import read_gmsh  # noqa: E402
from ngtmc.simulation import HISTORY_UNITS  # noqa: E402
from ngtmc.simulation import Simulation, SimulationResult, StepFailure  # noqa: E402
from ngtmc.discrete import NewtonOptions, Solver  # noqa: E402
from ngtmc.stepping import AdaptiveStepControl, Schedule  # noqa: E402
from ngtmc.adapt import Adaptivity  # noqa: E402
from ngtmc.scene import extrude  # noqa: E402
from ngtmc.scene import distributed  # noqa: E402  (the module, public since 0.1)
from ngtmc.scene import distribute  # noqa: E402

from ngtmc.version import __version__  # noqa: E402

__all__ = [
    "Material", "Scene", "Support", "DisplacementLoad", "DisplacementField", "Traction", "Point", "Regulariser",
    "ResolutionWarning", "ElementWarning", "ScaleWarning",
    "Solver", "NewtonOptions", "Simulation", "SimulationResult", "StepFailure", "simulate",
    "HISTORY_UNITS", "Schedule", "AdaptiveStepControl", "Adaptivity", "extrude", "distributed", "distribute",
    "read_gmsh",
    "__version__",
]

from ngtmc.study import list_studies, load_study  # noqa: E402
from ngtmc.study import Case
from ngtmc.runner import run_study, simulate  # noqa: E402

__all__ += ["Case", "list_studies", "load_study", "run_study"]

from ngtmc import sensitivities  # noqa: E402
from ngtmc.sensitivities import differentiate, gradient, record_path  # noqa: E402

__all__ += ["sensitivities", "differentiate", "gradient", "record_path"]
