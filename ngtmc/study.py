"""Named studies: the :class:`Case` dataclass and the study registry.

The registry (:data:`STUDIES`, name -> module path, plus the entry points of the group
``ngtmc.studies`` of installed packages) is how the library finds a named study; it never scans
a package for them.

A named study is one literate module, e.g. ``studies/<name>.py`` (``docs/study-interface.md``), that
defines ``NAME``, ``TITLE``, ``SUMMARY``, ``PARAMETERS`` (physics: name -> (value, unit,
description)), ``RESOLUTIONS`` (mesh and step sizes only; at least ``quick``, ``medium``,
``paper``), ``DEFAULT_RESOLUTION``, ``cases(p)``, ``references(p)`` and ``targets(p)``; the studies of
ngtmc also keep ``EXPECTED``, the numbers their quick run is checked against.

>>> from ngtmc.study import list_studies, load_study
>>> "three_point_bending" in list_studies()         # doctest: +SKIP
True
>>> load_study("three-point-bending").NAME            # dashes or underscores  # doctest: +SKIP
'three_point_bending'
"""
from __future__ import annotations

from dataclasses import dataclass, field
import importlib
from types import ModuleType
from typing import Any, Callable

import numpy as np

from .study_contract import StudyError, check_contract, normalise_name

__all__ = ["Case", "StudyError", "STUDIES", "ENTRY_POINT_GROUP", "registered_studies", "list_studies", "load_study", "load_study_file", "normalise_name", "study_parameters",
           "SOLVER_PARAMETERS", "simulation_options", "data_path"]


def data_path(name: str):
    """Path of a reference file shipped in ``ngtmc/data`` (digitised curves, with their sources in
    the studies that read them)."""
    from importlib.resources import files
    return files("ngtmc.data").joinpath(name)

#: Solver settings a study exposes next to its physics (``**SOLVER_PARAMETERS`` in PARAMETERS):
#: name -> (default, unit, description). They change cost and, for ``scheme``, the time
#: discretisation, never the model.
SOLVER_PARAMETERS = {
    "scheme": ("single-pass", "-", "solution scheme of a load step: 'single-pass' (paper), 'staggered', 'monolithic' or "
                                   "'path-following' (monolithic with dissipation control where the crack grows)"),
    "compile": ("auto", "-", "energy expressions: 'real' (generated C++, about 3x faster assembly, about 3.4 s to compile per expression; "
                             "falls back to 'symbolic' without a C++ compiler), 'symbolic', 'none', or 'auto' "
                             "('real' on meshes of 5000 elements or 10000 displacement dofs or more)"),
    "h_crack": (0.0, "mm", "adaptive refinement during the run (ngtmc.Adaptivity): target element size where the crack "
                           "is or is about to be, for example l0/4; 0: none (the mesh as the resolution gives it)"),
    "amr_lookahead": (0.0, "mm", "with h_crack: elements within this distance of those the indicator marks are refined "
                                 "too (Adaptivity.buffer_length), so that a running crack tip stays on the fine mesh "
                                 "for several steps"),
    "amr_corridor": ("auto", "mm", "with h_crack: half width of a corridor refined along the crack's path ahead of "
                                   "its front at the first refinement after the crack starts to run (the force below 0.95 of its peak; "
                                   "Adaptivity.corridor), so that the crack runs with fewer refinements; 'auto': 4 l0 "
                                   "(ngtmc.adapt.CORRIDOR_L0) in 2D, none in 3D; 0: none"),
    "amr_h_void": (0.0, "mm", "with h_crack: target element size in the void where it is squeezed (J < 0.5; "
                              "Adaptivity.h_void); 0: the void is not refined"),
    "amr_size_tolerance": (1.0, "-", "with h_crack: elements are refined while their longest edge exceeds this times "
                                     "their target (Adaptivity.size_tolerance; 1: the target is a strict bound, and "
                                     "sizes end between half the target and the target; 1.41: centred on it)"),
    "amr_remesh_maxh": (0.0, "mm", "with h_crack: refine by generating a new mesh from the geometry (ngtmc.remesh) "
                                   "instead of NGSolve's bisection; the global maxh the study's mesh is generated with "
                                   "(checked: the geometry meshed with it must give the study's mesh again); 0: bisection"),
    "amr_history_fraction": (1.0, "-", "with h_crack: elements whose history H reaches this fraction of H_c = Gc / (6 l0) "
                                       "(the level at which AT-2 peaks; Adaptivity.history_fraction) are refined, in "
                                       "(0, 1]; lower refines earlier, before the crack starts"),
    "amr_buffer": (1, "-", "with h_crack: layers of neighbours (sharing a vertex) refined with each element the "
                           "indicator marks (Adaptivity.buffer, an integer >= 0)"),
    "stop_after_drop": (0.0, "-", "stop each case once its force has fallen below this fraction of its peak, after "
                                  "the peak (the crack has run; Simulation.stop_after_drop); 0: the whole schedule"),
}
_COMPILE = {"real": "real", "symbolic": True, "none": False, "auto": "auto"}

#: Solver settings without any effect while adaptive refinement is off (h_crack = 0), with their
#: values then: they are left out of the parameter hashes and of the comparison of a resumed run
#: with its record (:func:`effective_parameters`), so that runs recorded before they existed still
#: resume and compare.
INERT_WITHOUT_REFINEMENT = {"h_crack": 0.0, "amr_lookahead": 0.0, "amr_corridor": 0.0, "amr_h_void": 0.0, "amr_size_tolerance": 1.0,
                            "amr_remesh_maxh": 0.0, "amr_history_fraction": 1.0, "amr_buffer": 1}


#: Settings added after runs were recorded, at the value those runs had in effect: left out of the
#: hashes and comparisons at that value, so that the runs still resume and compare. A study adds
#: its own by naming them in a tuple ``ADDED_AT_DEFAULT`` of its module; their value is then
#: the default of its PARAMETERS (:func:`added_at_default`).
ADDED_AT_DEFAULT = {"amr_size_tolerance": 1.0, "stop_after_drop": 0.0, "amr_remesh_maxh": 0.0, "amr_corridor": 0.0,
                    "amr_history_fraction": 1.0, "amr_buffer": 1}


#: Settings whose default changed after runs were recorded, with the default those runs had: a
#: resumed run whose record does not name the setting, or names it at that old default, goes on
#: with it (:func:`ngtmc.runfiles.resume_parameters`), not with the new default. amr_corridor:
#: 0 (none) until 2026-12-06, "auto" (4 l0 in 2D) since.
DEFAULT_CHANGED = {"amr_corridor": 0.0}


def added_at_default(mod=None) -> dict:
    """:data:`ADDED_AT_DEFAULT` and, for the study module ``mod``, the parameters its
    ``ADDED_AT_DEFAULT`` names, at their defaults in its PARAMETERS ({name: value})."""
    out = dict(ADDED_AT_DEFAULT)
    names = getattr(mod, "ADDED_AT_DEFAULT", ()) if mod is not None else ()
    for name in names:
        out[name] = mod.PARAMETERS[name][0]
    return out


def effective_parameters(p: dict, mod=None) -> dict:
    """``p`` without the settings that have no effect in it (:data:`INERT_WITHOUT_REFINEMENT`,
    when ``h_crack`` is 0 or absent) and those at the value of :func:`added_at_default` (of the
    study module ``mod``, where given)."""
    try:
        off = float(p.get("h_crack", 0.0) or 0.0) == 0.0
    except (TypeError, ValueError):
        off = False
    added = added_at_default(mod)

    def at_default(k, v):
        try:
            return k in added and float(v) == added[k]
        except (TypeError, ValueError):
            return False
    return {k: v for k, v in p.items() if not ((off and k in INERT_WITHOUT_REFINEMENT) or at_default(k, v))}


def simulation_options(p: dict) -> dict:
    """Keyword arguments of :class:`ngtmc.Simulation` from the solver settings in ``p``
    (see SOLVER_PARAMETERS); raises StudyError on an unknown value."""
    from .simulation import SCHEMES
    scheme = p.get("scheme", SOLVER_PARAMETERS["scheme"][0])
    compile_ = p.get("compile", SOLVER_PARAMETERS["compile"][0])
    if scheme not in SCHEMES:
        raise StudyError(f"scheme = {scheme!r} is not one of {', '.join(SCHEMES)}")
    if compile_ not in _COMPILE:
        raise StudyError(f"compile = {compile_!r} is not one of {', '.join(_COMPILE)}")
    out = {"scheme": scheme, "compile": _COMPILE[compile_]}
    drop = p.get("stop_after_drop", SOLVER_PARAMETERS["stop_after_drop"][0])
    if not (isinstance(drop, (int, float)) and not isinstance(drop, bool) and drop == 0):
        from .simulation import check_stop_after_drop
        try:
            check_stop_after_drop(drop)
        except (TypeError, ValueError) as e:
            raise StudyError(f"{e}; as a study setting, 0 runs the whole schedule") from None
        out["stop_after_drop"] = float(drop)
    h_crack = p.get("h_crack", SOLVER_PARAMETERS["h_crack"][0])
    try:
        h_crack = float(h_crack)
    except (TypeError, ValueError):
        raise StudyError(f"h_crack = {h_crack!r} must be a length in mm (0: no adaptive refinement)") from None
    if h_crack < 0 or h_crack != h_crack:
        raise StudyError(f"h_crack = {h_crack!r} mm must be >= 0 (0: no adaptive refinement)")
    corridor = p.get("amr_corridor", SOLVER_PARAMETERS["amr_corridor"][0])
    if isinstance(corridor, str) and corridor != "auto":   # checked whether refinement is on or not
        raise StudyError(f"amr_corridor = {corridor!r} must be 'auto' or a half width in mm (0: none)")
    if h_crack > 0:
        from .adapt import Adaptivity
        try:
            h_void = float(p.get("amr_h_void", 0.0))
            maxh = float(p.get("amr_remesh_maxh", 0.0))
            corridor = p.get("amr_corridor", SOLVER_PARAMETERS["amr_corridor"][0])
            out["adapt"] = Adaptivity(h_crack=h_crack, buffer_length=float(p.get("amr_lookahead", 0.0)),
                                      corridor=corridor if isinstance(corridor, str) else float(corridor),
                                      h_void=h_void if h_void > 0 else None,
                                      size_tolerance=float(p.get("amr_size_tolerance", 1.0)),
                                      history_fraction=float(p.get("amr_history_fraction", 1.0)),
                                      buffer=p.get("amr_buffer", 1),
                                      remesh_maxh=maxh if maxh > 0 else None)
        except (TypeError, ValueError) as e:
            raise StudyError(str(e)) from None
    return out


@dataclass
class Case:
    """One load path of a study run.

    name: case name used in ``history.csv`` and ``metadata.json`` (e.g. ``"main"``).
    label: human-readable label for the report legend.
    scene: an :class:`ngtmc.Scene`, or a zero-argument callable building it (built lazily by the
        runner, so listing the cases of a study is cheap).
    schedule: :class:`ngtmc.Schedule` or a final load in mm.
    control: :class:`ngtmc.AdaptiveStepControl` or None (the Simulation default).
    options: keyword arguments for :class:`ngtmc.Simulation` (e.g. ``scheme="monolithic"``).
    snapshot_loads: loads (mm) at which fields are saved; the runner saves the first accepted step
        at or past each load.
    parameters: case-specific values (e.g. ``{"gamma0": 1e-5}``) recorded in the metadata.
    run: optional ``run(case, out_dir) -> pandas.DataFrame`` for a case that is not an ngtmc
        simulation (e.g. a classical penalty-contact reference); the DataFrame has at least the
        columns ``load`` and ``force``.
    cost: expected cost relative to the study's other cases (dimensionless, default 1): on a
        cluster the costliest cases start first, so that the last one to finish is not a long one
        started late; a serial run keeps the study's order.
    section: 3D only, a plane ``(axis, coordinate)`` such as ``("x", 4.0)`` (mm) through which each
        snapshot also samples alpha on a grid (the crack plane: the report draws the crack front
        there; :mod:`ngtmc.snapshots`). None: no section.
    """

    name: str
    label: str = ""
    scene: Any = None
    schedule: Any = None
    control: Any = None
    options: dict = field(default_factory=dict)
    snapshot_loads: list = field(default_factory=list)
    parameters: dict = field(default_factory=dict)
    run: Callable | None = None
    cost: float = 1.0
    section: tuple | None = None

    def __post_init__(self):
        if not self.label:
            self.label = self.name
        if self.section is not None:
            axis, at = self.section
            if axis not in ("x", "y", "z") or not np.isfinite(float(at)):
                raise StudyError(f"case {self.name!r}: section = {self.section!r} must be (axis, coordinate in mm) with "
                                 "axis 'x', 'y' or 'z'")
        if not (isinstance(self.cost, (int, float)) and not isinstance(self.cost, bool) and self.cost > 0
                and self.cost < float("inf")):
            raise ValueError(f"case {self.name!r}: cost = {self.cost!r} must be a finite number > 0")

    def build_scene(self):
        """The scene, building it if ``scene`` is a callable."""
        from .scene import Scene
        if self.scene is None:
            raise ValueError(f"case {self.name!r} has no scene")
        if isinstance(self.scene, Scene):
            return self.scene
        if callable(self.scene):
            self.scene = self.scene()
        return self.scene




#: The named studies that ship with ngtmc: study name -> module path. The registry is the only
#: place the library learns of them (it never scans a package). Other installed packages add
#: studies through the entry-point group :data:`ENTRY_POINT_GROUP` (see
#: ``docs/study-interface.md``), e.g. in their ``pyproject.toml``::
#:
#:     [project.entry-points."ngtmc.studies"]
#:     my_study = "my_package.my_study"
STUDIES = {
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


def _type_name(like) -> str:
    if isinstance(like, bool):
        return "a boolean (true/false, yes/no, 1/0)"
    if isinstance(like, int):
        return "a number (integer)"
    if isinstance(like, float):
        return "a number"
    if isinstance(like, str):
        return "a string"
    if isinstance(like, (list, tuple)):
        return f"a comma-separated list of {_type_name(like[0] if len(like) else 0.0)}s"
    return "a value"


def _coerce(value, like, key: str = "value", unit: str = ""):
    """Convert an override to the type of the default ``like``; StudyError naming ``key`` and the
    expected type if it cannot be (strings from the command line are parsed). A default of
    "auto" takes "auto" (or another word the setting names) or a number (``amr_corridor``)."""
    what = f"{key} expects {_type_name(like)}{f' ({unit})' if unit and unit != '-' else ''}"
    if like == "auto":
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (str, int, float, np.integer, np.floating)):
            raise StudyError(f"override {key} = {value!r}: {key} expects 'auto' or a number"
                             f"{f' ({unit})' if unit and unit != '-' else ''}, got {type(value).__name__}")
        if isinstance(value, str):
            try:
                return float(value)
            except ValueError:
                return value
        return float(value)
    if isinstance(like, str):
        if not isinstance(value, str):
            raise StudyError(f"override {key} = {value!r}: {what}, got {type(value).__name__}")
        return value
    if isinstance(like, bool):
        if isinstance(value, (bool, np.bool_)):
            return bool(value)
        v = str(value).strip().lower()
        if v in ("1", "true", "yes", "on"):
            return True
        if v in ("0", "false", "no", "off"):
            return False
        raise StudyError(f"override {key} = {value!r}: {what}")
    if isinstance(like, (int, float)):
        if isinstance(value, str):
            try:
                value = float(value) if isinstance(like, float) else _int_or_float(value)
            except ValueError:
                raise StudyError(f"override {key} = {value!r}: {what}") from None
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise StudyError(f"override {key} = {value!r}: {what}, got {type(value).__name__}")
        return float(value) if isinstance(like, float) else value
    if isinstance(like, (list, tuple)):
        elem = like[0] if len(like) else 0.0
        parts = ([s.strip() for s in value.replace(";", ",").split(",") if s.strip()] if isinstance(value, str)
                 else value)
        if not isinstance(parts, (list, tuple, np.ndarray)):
            raise StudyError(f"override {key} = {value!r}: {what}")
        return [_coerce(s, elem, key, unit) for s in parts]
    # unknown default type (e.g. None): try a number, else keep the string
    if isinstance(value, str):
        for conv in (int, float):
            try:
                return conv(value)
            except ValueError:
                pass
    return value


def _int_or_float(text: str):
    try:
        return int(text)
    except ValueError:
        return float(text)


def study_parameters(mod: ModuleType, resolution: str | None = None, overrides: dict | None = None) -> tuple[str, dict]:
    """Resolve the plain parameter dict ``p`` for ``cases(p)`` of a study module.

    ``p`` = PARAMETERS values, then RESOLUTIONS[resolution], then ``overrides``. Override values
    given as strings (the command line) are converted to the type of the default. Unknown
    resolutions and unknown override keys raise :class:`StudyError` listing the valid ones.
    Returns ``(resolution, p)``.
    """
    resolutions = mod.RESOLUTIONS
    res = resolution or getattr(mod, "DEFAULT_RESOLUTION", "quick")
    if res not in resolutions:
        raise StudyError(f"unknown resolution {res!r} for study {mod.NAME!r}; valid: {', '.join(resolutions)}")
    p = {k: v[0] for k, v in mod.PARAMETERS.items()}
    p.update(resolutions[res])
    valid = sorted(set(p) | {k for r in resolutions.values() for k in r})
    for k, v in (overrides or {}).items():
        if k not in valid:
            raise StudyError(f"unknown override {k!r} for study {mod.NAME!r}; valid keys: {', '.join(valid)}")
        unit = mod.PARAMETERS[k][1] if k in mod.PARAMETERS else getattr(mod, "RESOLUTION_PARAMETERS", {}).get(k, ("",))[0]
        p[k] = _coerce(v, p.get(k), k, unit)
    return res, p
