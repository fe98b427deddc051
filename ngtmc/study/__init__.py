"""Named studies: the registry that finds them (:mod:`ngtmc.study.registry`), the contract a study
module keeps (:mod:`ngtmc.study.contract`), a study's load paths (:class:`Case`), the solver settings
every study exposes (:mod:`ngtmc.study.solver_settings`), a run's parameters, hashes and resume
(:mod:`ngtmc.study.parameters`), the files of a run folder
(:mod:`ngtmc.study.run_files`) and the measured records of the studies (:mod:`ngtmc.study.measured`)."""
from ngtmc.study.case import Case
from ngtmc.study.contract import StudyError, normalise_name
from ngtmc.study.solver_settings import SOLVER_PARAMETERS, simulation_options
from ngtmc.study.parameters import study_parameters
from ngtmc.study.registry import (
    STUDIES, data_path, list_studies, load_study, load_study_file, registered_studies,
)

from ngtmc.study.parameters import (
    guess_unit, parameter_table, parameters_hash, physics_hash, resume_parameters, run_description,
    typed_overrides,
)
from ngtmc.study.run_files import (
    CheckpointWarning, UNITS, effective_status, git_revision, jsonable, process_alive, process_info,
    read_metadata, versions, write_atomic, write_json, write_npz,
)

__all__ = ["Case", "StudyError", "normalise_name", "SOLVER_PARAMETERS", "simulation_options", "study_parameters",
           "STUDIES", "data_path", "list_studies", "load_study", "load_study_file", "registered_studies", "records"]
__all__ += [
    'CheckpointWarning', 'UNITS', 'effective_status', 'git_revision', 'guess_unit', 'jsonable',
    'parameter_table', 'parameters_hash', 'physics_hash', 'process_alive', 'process_info',
    'read_metadata', 'resume_parameters', 'run_description', 'typed_overrides', 'versions',
    'write_atomic', 'write_json', 'write_npz',
]


def __getattr__(name):
    """``records`` (:func:`ngtmc.study.measured.records`) on first use: imported here, the module
    would be loaded before ``python -m ngtmc.study.measured`` runs it, and runpy warns."""
    if name == "records":
        from ngtmc.study.measured import records
        return records
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
