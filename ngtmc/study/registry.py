"""The study registry: how the library finds a named study, and loads it.

The registry (:data:`STUDIES`, name -> module path, plus the entry points of the group
``ngtmc.studies`` of installed packages) is how the library finds a named study; it never scans
a package for them.

A named study is one literate module, e.g. ``studies/<name>.py`` (``docs/study-interface.md``), that
defines ``NAME``, ``TITLE``, ``SUMMARY``, ``PARAMETERS`` (physics: name -> (value, unit,
description)), ``RESOLUTIONS`` (mesh and step sizes only; at least ``quick``, ``medium``,
``paper``), ``DEFAULT_RESOLUTION``, ``cases(p)``, ``references(p)`` and ``targets(p)``; the studies of
ngtmc also keep ``EXPECTED``, the numbers their quick run is checked against.

>>> from ngtmc.study.registry import list_studies, load_study
>>> "three_point_bending" in list_studies()         # doctest: +SKIP
True
>>> load_study("three-point-bending").NAME            # dashes or underscores  # doctest: +SKIP
'three_point_bending'
"""
from __future__ import annotations

import importlib
import importlib.resources
from types import ModuleType

from ngtmc.study.contract import StudyError, check_contract, normalise_name

__all__ = ["STUDIES", "ENTRY_POINT_GROUP", "registered_studies", "list_studies", "load_study", "load_study_file",
           "data_path"]


def data_path(name: str):
    """Path of a reference file shipped in ``ngtmc/data`` (digitised curves, with their sources in
    the studies that read them)."""
    return importlib.resources.files("ngtmc.data").joinpath(name)


#: The named studies that ship with ngtmc: study name -> module path. The registry is the only
#: place the library learns of them (it never scans a package). Other installed packages add
#: studies through the entry-point group :data:`ENTRY_POINT_GROUP` (see
#: ``docs/study-interface.md``), e.g. in their ``pyproject.toml``::
#:
#:     [project.entry-points."ngtmc.studies"]
#:     my_study = "my_package.my_study"
STUDIES = {
    "c_shape_design": "ngtmc.studies.c_shape_design",
    "contact_gamma0": "ngtmc.studies.contact_gamma0",
    "design_for_contact": "ngtmc.studies.design_for_contact",
    "l_panel": "ngtmc.studies.l_panel",
    "step_control": "ngtmc.studies.step_control",
    "three_point_bending": "ngtmc.studies.three_point_bending",
    "three_point_bending_3d": "ngtmc.studies.three_point_bending_3d",
}

#: Entry-point group through which other packages register studies (name -> module).
ENTRY_POINT_GROUP = "ngtmc.studies"


def registered_studies() -> dict[str, str]:
    """Study name -> module path: :data:`STUDIES`, then the entry points of the group
    ``ngtmc.studies`` of every installed package (names with dashes or underscores; a name of
    :data:`STUDIES` cannot be taken over)."""
    from importlib.metadata import entry_points
    out = dict(STUDIES)
    try:
        eps = entry_points(group=ENTRY_POINT_GROUP)
    except Exception:  # broken metadata of an unrelated package must not hide the studies
        eps = ()
    for ep in eps:
        out.setdefault(normalise_name(ep.name), ep.value.split(":")[0].strip())
    return out


def list_studies() -> list[str]:
    """Names of the registered studies (:func:`registered_studies`), sorted."""
    return sorted(registered_studies())


def load_study_file(path) -> ModuleType:
    """Import a user's study file (a ``.py`` file with the interface of ``docs/study-interface.md``).

    Raises :class:`StudyError` if the file does not exist, cannot be imported or lacks a name."""
    import importlib.util
    import sys
    from pathlib import Path
    f = Path(path)
    if not f.is_file():
        raise StudyError(f"study file {str(path)!r} does not exist")
    modname = "ngtmc_user_study_" + "".join(ch if ch.isalnum() else "_" for ch in f.stem)
    spec = importlib.util.spec_from_file_location(modname, f)
    if spec is None or spec.loader is None:
        raise StudyError(f"study file {str(path)!r} cannot be imported (not a Python file)")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[modname] = mod
    try:
        spec.loader.exec_module(mod)
    except Exception as e:
        sys.modules.pop(modname, None)
        raise StudyError(f"study file {str(path)!r} cannot be imported: {type(e).__name__}: {e}") from e
    check_contract(mod, str(f), shipped={k: m for k, m in registered_studies().items() if not _is_file_of(m, f)})
    return mod


def _is_file_of(module: str, f) -> bool:
    """True when ``f`` is the file of the registered study module ``module`` (a study run from its path)."""
    import importlib.util
    from pathlib import Path
    try:
        spec = importlib.util.find_spec(module)
    except (ImportError, ValueError):
        return False
    return bool(spec and spec.origin) and Path(spec.origin).resolve() == Path(f).resolve()


def load_study(name: str) -> ModuleType:
    """Import the registered study ``name`` (:func:`registered_studies`; dashes or underscores, e.g.
    ``studies/<name>.py`` for the studies of ngtmc). A path to a ``.py`` file
    (a user's own study with the same interface) is imported from that file (:func:`load_study_file`).

    Raises :class:`StudyError` listing the valid names if there is no such study.
    """
    if str(name).endswith(".py") or "/" in str(name) or "\\" in str(name):
        return load_study_file(name)
    key = normalise_name(name)
    registry = registered_studies()
    if key not in registry:
        raise StudyError(f"unknown study {name!r}; valid studies: {', '.join(sorted(registry)) or '(none)'}")
    where = registry[key]
    try:
        mod = importlib.import_module(where)
    except ImportError as e:
        raise StudyError(f"study {key!r} is registered as module {where!r}, which cannot be imported "
                         f"({type(e).__name__}: {e})") from e
    check_contract(mod, getattr(mod, "__file__", None) or where)
    return mod
