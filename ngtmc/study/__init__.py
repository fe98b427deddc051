"""Named studies: the registry that finds them (:mod:`ngtmc.study.registry`), the contract a study
module keeps (:mod:`ngtmc.study.contract`), a study's load paths (:class:`Case`), a run's parameters,
hashes and resume (:mod:`ngtmc.study.parameters`), the files of a run folder
(:mod:`ngtmc.study.run_files`) and the measured records of the studies (:mod:`ngtmc.study.records`)."""
from ngtmc.study.case import Case
from ngtmc.study.contract import StudyError, normalise_name
from ngtmc.study.parameters import SOLVER_PARAMETERS, simulation_options, study_parameters
from ngtmc.study.registry import STUDIES, data_path, list_studies, load_study, load_study_file, registered_studies

__all__ = ["Case", "StudyError", "normalise_name", "SOLVER_PARAMETERS", "simulation_options", "study_parameters",
           "STUDIES", "data_path", "list_studies", "load_study", "load_study_file", "registered_studies"]
