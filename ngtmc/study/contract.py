"""The contract of a study module (``docs/study-interface.md``), checked when the study is loaded:
its names and forms, so that a study file that breaks it is refused with a message naming what
and where, never run with a foreign error or filed under another study's name."""
from __future__ import annotations

from types import ModuleType

__all__ = ["StudyError", "check_contract", "normalise_name"]


class StudyError(ValueError):
    """Unknown study name, unknown resolution or unknown override, or a study module that breaks
    its contract."""


def normalise_name(name: str) -> str:
    """``"three-point-bending"`` -> ``"three_point_bending"``."""
    return str(name).strip().replace("-", "_").lower()


def check_contract(mod: ModuleType, where: str, shipped: dict | None = None):
    """Raise :class:`ngtmc.study.registry.StudyError` unless ``mod`` has NAME (a non-empty string; for a
    user's study file, ``shipped`` given: not the name of a registered study), PARAMETERS (a dict
    of name -> (default, unit, description)), RESOLUTIONS (a dict of name -> dict of
    settings), a callable ``cases`` and a valid ADDED_AT_DEFAULT."""
    missing = [a for a in ("NAME", "PARAMETERS", "RESOLUTIONS", "cases") if not hasattr(mod, a)]
    if missing:
        raise StudyError(f"study module {where} lacks {', '.join(missing)} (see docs/study-interface.md)")
    if not isinstance(mod.NAME, str) or not mod.NAME.strip():
        raise StudyError(f"study module {where}: NAME must be a non-empty string, got {mod.NAME!r}")
    if shipped is not None and normalise_name(mod.NAME) in shipped:
        raise StudyError(f"study file {where}: NAME = {mod.NAME!r} is the name of a study of ngtmc "
                         f"({shipped[normalise_name(mod.NAME)]}); give your study a name of its own, so that its "
                         "runs are not filed as that study's")
    if not isinstance(mod.PARAMETERS, dict):
        raise StudyError(f"study module {where}: PARAMETERS must be a dict of name -> (default, unit, "
                         f"description), got {type(mod.PARAMETERS).__name__}")
    for key, value in mod.PARAMETERS.items():
        if not (isinstance(value, (tuple, list)) and len(value) == 3 and isinstance(value[1], str)
                and isinstance(value[2], str)):
            raise StudyError(f"study module {where}: PARAMETERS[{key!r}] = {value!r} must be a tuple "
                             "(default, unit, description), e.g. (20.8e3, 'MPa', \"Young's modulus\")")
    if not isinstance(mod.RESOLUTIONS, dict) or not mod.RESOLUTIONS or \
            not all(isinstance(v, dict) for v in mod.RESOLUTIONS.values()):
        raise StudyError(f"study module {where}: RESOLUTIONS must be a non-empty dict of resolution name -> "
                         f"dict of settings, e.g. {{'quick': {{'maxh': 0.1}}}}; got {mod.RESOLUTIONS!r}")
    if not callable(mod.cases):
        raise StudyError(f"study module {where}: cases must be a function of the parameters returning the "
                         "list of ngtmc.study.registry.Case")
    added = getattr(mod, "ADDED_AT_DEFAULT", ())
    unknown = [n for n in added if n not in mod.PARAMETERS] if not isinstance(added, str) else [added]
    if isinstance(added, str) or unknown:
        raise StudyError(f"study module {where}: ADDED_AT_DEFAULT must be a tuple of names of its PARAMETERS; "
                         f"not parameters: {unknown or added!r}")
