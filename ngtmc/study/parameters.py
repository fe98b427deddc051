"""A study run's parameters: one owner of what a run is. The resolved parameters of a study at a
resolution with ``--set`` overrides (:func:`study_parameters`; the solver settings every study
exposes and the keywords they give a Simulation are :mod:`ngtmc.study.solver_settings`), their table with units for the metadata and the report
(:func:`parameter_table`), their hashes (:func:`physics_hash`, :func:`parameters_hash`) and the
check that a resume continues the same run (:func:`resume_parameters`)."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path
import sys
from types import ModuleType

import numpy as np

from ngtmc.study.contract import StudyError
from ngtmc.study.solver_settings import SOLVER_PARAMETERS, simulation_options
from ngtmc.study.run_files import SCHEMA_VERSION, UNITS, git_revision, jsonable, process_info, versions

__all__ = ["SOLVER_PARAMETERS", "INERT_WITHOUT_REFINEMENT", "ADDED_AT_DEFAULT", "DEFAULT_CHANGED", "added_at_default",
           "effective_parameters", "simulation_options", "study_parameters", "guess_unit", "parameter_table",
           "physics_hash", "run_description", "parameters_hash", "resume_parameters", "typed_overrides"]


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
#: with it (:func:`ngtmc.study.parameters.resume_parameters`), not with the new default. amr_corridor:
#: 0 (none) until 2026-12-06, "auto" (4 l0 in 2D) since; amr_remesh_maxh: 0 (bisection) and
#: amr_lookahead: 0 (none) until 2026-12-07, "auto" (remeshing where the study states its mesh's
#: maxh; a lookahead of the larger of 2 l0 and 3 h_crack in 2D) since.
DEFAULT_CHANGED = {"amr_corridor": 0.0, "amr_remesh_maxh": 0.0, "amr_lookahead": 0.0}


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


def guess_unit(key: str) -> str:
    if key == "h" or key.startswith("h_") or key.startswith("du_") or key.endswith("_load"):
        return "mm"
    return "-"


def parameter_table(mod, p: dict) -> dict:
    """Every parameter with value, unit, description: PARAMETERS, resolution keys, then anything else."""
    res_desc = getattr(mod, "RESOLUTION_PARAMETERS", {})
    out = {}
    for k, (_, unit, desc) in mod.PARAMETERS.items():
        out[k] = {"value": p.get(k), "unit": unit, "description": desc}
    for k, v in p.items():
        if k in out:
            continue
        unit, desc = res_desc.get(k, (guess_unit(k), "mesh or step size (set by the resolution)"))
        out[k] = {"value": v, "unit": unit, "description": desc}
    return out


def physics_hash(mod, p: dict) -> str:
    """:func:`parameters_hash` of the physics alone (the study's PARAMETERS): runs with equal
    physics hashes differ only in resolution, and the report index compares only those."""
    return parameters_hash({k: p[k] for k in getattr(mod, "PARAMETERS", {}) if k in p}, mod)  # (effective ones only)


def run_description(mod, p: dict, resolution: str | None, overrides: dict | None) -> dict:
    """The fields of ``metadata.json`` that say what a run of study ``mod`` computed and with what:
    study, title, summary_text, schema_version, resolution, versions, git_revision, units,
    parameters (value, unit, description of every resolved parameter ``p``), overrides,
    parameters_hash, physics_hash, command and process. The runner and every study that writes
    its own files (``studies/design_for_contact.py``) start their metadata from it."""
    return {
        "study": mod.NAME,
        "title": getattr(mod, "TITLE", mod.NAME),
        "summary_text": getattr(mod, "SUMMARY", ""),
        "schema_version": SCHEMA_VERSION,
        "resolution": resolution,
        "versions": versions(),
        "git_revision": git_revision(),
        "units": dict(UNITS),
        "parameters": parameter_table(mod, p),
        "overrides": dict(overrides or {}),
        "parameters_hash": parameters_hash(p, mod),
        "physics_hash": physics_hash(mod, p),
        "command": " ".join(sys.argv) if sys.argv and sys.argv[0] else None,
        "process": process_info(),
    }


# ====================================================================== the physics of a run
def parameters_hash(p: dict, mod=None) -> str:
    """``"sha256:<hex>"`` of the resolved parameters ``p`` (physics, resolution and solver settings)
    of the study module ``mod`` in canonical JSON: equal for equal parameters, whatever their order
    or their origin. Settings without effect in ``p`` (:func:`ngtmc.study.parameters.effective_parameters`,
    which needs ``mod`` for the settings a study added later) are left out."""
    text = json.dumps(jsonable(effective_parameters(p, mod)), sort_keys=True, separators=(",", ":"))
    return "sha256:" + hashlib.sha256(text.encode()).hexdigest()


def _show(v) -> str:
    return "(not set)" if v is _MISSING else json.dumps(v)


_MISSING = object()


def _differences(recorded: dict, given: dict) -> list[str]:
    """``["key: recorded -> given", ...]`` for every key whose JSON value differs."""
    out = []
    for k in sorted(set(recorded) | set(given)):
        a, b = recorded.get(k, _MISSING), given.get(k, _MISSING)
        a = a if a is _MISSING else jsonable(a)
        b = b if b is _MISSING else jsonable(b)
        if a != b:
            out.append(f"{k}: {_show(a)} -> {_show(b)}")
    return out


def resume_parameters(meta: dict | None, mod, resolution: str | None, overrides: dict | None, out: Path):
    """Resolution, overrides and parameters of a run to resume; refuse to mix physics.

    ``meta`` is the run's recorded metadata (None when unreadable: the given options are used and
    the checkpoints' parameter hashes guard the resume). Without overrides the recorded ones are
    taken; overrides or a resolution that differ from the recorded ones raise
    :class:`ngtmc.study.registry.StudyError` listing the differences (``key: recorded -> given``), as do
    parameters that the study's code now resolves differently from the recorded values.
    Returns ``(resolution, overrides, p)``.
    """
    if not meta:
        res, p = study_parameters(mod, resolution, overrides)
        return res, typed_overrides(p, overrides), p
    rec_res = meta.get("resolution")
    if resolution is not None and rec_res is not None and resolution != rec_res:
        raise StudyError(f"cannot resume {out}: it was started at another resolution (resolution: "
                         f"{rec_res!r} -> {resolution!r}); resume without a resolution, or start a new run")
    res = rec_res or resolution
    rec_over = meta.get("overrides") or {}
    res, p = study_parameters(mod, res, rec_over)
    recorded = {k: v.get("value") for k, v in (meta.get("parameters") or {}).items() if isinstance(v, dict)}
    # settings whose default changed since: the run goes on with the value it was recorded at (the
    # old default where its record does not name it; with a hash only, where that hash says so)
    try:
        refining = float(p.get("h_crack", 0.0) or 0.0) > 0.0
    except (TypeError, ValueError):
        refining = True
    changed = {k: old for k, old in DEFAULT_CHANGED.items()
               if k in p and k not in rec_over and k not in (overrides or {})
               and (refining or k not in INERT_WITHOUT_REFINEMENT)}   # without refinement they change nothing
    if recorded:
        p.update({k: recorded.get(k, old) for k, old in changed.items()})
    elif changed and meta.get("parameters_hash") and meta["parameters_hash"] != parameters_hash(p, mod):
        # the old defaults the run was recorded with: the subset of them whose hash is the record's
        # (a run recorded between two changes has the newer default of the first one)
        names = sorted(changed)
        for mask in range(1, 2 ** len(names)):
            old = {k: changed[k] for i, k in enumerate(names) if mask >> i & 1}
            if meta["parameters_hash"] == parameters_hash({**p, **old}, mod):
                p.update(old)
                break
    rec_typed = typed_overrides(p, rec_over)
    if overrides:
        _, p_given = study_parameters(mod, res, overrides)
        diff = _differences(rec_typed, typed_overrides(p_given, overrides))
        if diff:
            raise StudyError(f"cannot resume {out} with other overrides than it was started with; differences "
                             f"(key: recorded -> given): {'; '.join(diff)}. Resume without --set to continue with "
                             "the recorded overrides, or start a new run in another folder")
    if recorded:
        diff = _differences(effective_parameters(recorded, mod), effective_parameters(p, mod))
        if diff:
            raise StudyError(f"cannot resume {out}: the study {mod.NAME!r} now resolves other parameters than the "
                             f"run recorded (key: recorded -> now): {'; '.join(diff)}. Start a new run")
    elif meta.get("parameters_hash") and meta["parameters_hash"] != parameters_hash(p, mod):
        raise StudyError(f"cannot resume {out}: its parameters hash differs from this run's; start a new run")
    return res, rec_typed, p


def typed_overrides(p: dict, overrides: dict | None) -> dict:
    """The overrides with the values they resolved to in ``p`` (strings converted to numbers)."""
    return {k: p[k] for k in (overrides or {})}


# ====================================================================== process and status
