"""The files of a run folder that make a run safe to resume (format: ``docs/run-directory.md``).

* Atomic writes: every file goes through a temporary file in the same folder and ``os.replace``,
  so a crash never leaves a truncated history, metadata or checkpoint behind.
* The physics of a run: :func:`parameters_hash` of the resolved parameters (physics, resolution
  and solver settings), recorded in ``metadata.json`` and in every checkpoint, and
  :func:`resume_parameters`, which refuses to resume a run with other parameters than it started
  with (``--resume`` without ``--set`` takes the recorded overrides).
* Checkpoints in two generations (:class:`ngtmc.runner.checkpoints.CheckpointStore`):
  ``checkpoint/<case>.npz`` and the one before it, ``checkpoint/<case>.prev.npz``. A file that
  cannot be read is named in a :class:`CheckpointWarning`, moved aside to ``<file>.corrupt`` and
  the older generation is used.
* A stale ``"running"`` status (the process that wrote it is gone): :func:`effective_status`.
"""
from __future__ import annotations

import hashlib
import io
import json
import math
import os
from pathlib import Path
import platform
import socket
import subprocess
import sys
import tempfile
import warnings

import numpy as np

__all__ = ["SCHEMA_VERSION", "HISTORY_UNITS", "history_units", "CheckpointWarning", "write_atomic", "write_json", "write_npz",
           "jsonable", "peak", "peak_index", "UNITS", "versions", "git_revision", "parameter_table", "physics_hash",
           "run_description", "parameters_hash", "process_info", "process_alive", "effective_status", "read_metadata",
           "resume_parameters"]

#: Version of the run-folder format (``schema_version`` in metadata.json; absent means 1).
SCHEMA_VERSION = 2

#: Columns of a Simulation's history, in order, with their units (``history.csv`` has a ``case``
#: column first). In 2D, force and energies are for the scene thickness: the force of a study run
#: with thickness 1 mm is in N per mm (``force_unit`` in metadata.json). The one definition used
#: by :data:`ngtmc.HISTORY_UNITS`, :data:`ngtmc.runner.HISTORY_COLUMNS` and the report. A scene
#: with several loads or a traction adds columns after these by the rule of :func:`history_units`.
HISTORY_UNITS = {
    "step": "-",
    "load": "mm",
    "force": "N",
    "fracture_energy": "N mm",
    "dissipated_energy": "N mm",
    "elastic_energy": "N mm",
    "regularisation_energy": "N mm",
    "max_alpha": "-",
    "min_J": "-",
    "newton_iterations": "-",
    "staggered_iterations": "-",
    "cutbacks": "-",
    "alpha_projected": "-",
    "step_size": "mm",
    "wall_time": "s",
    "solve_time": "s",
    "assembly_time": "s",
    "residual": "N",            # free-dof residual norm of the accepted state (docs/run-directory.md)
    "floor_accepts": "-",       # solves of the step accepted at NewtonOptions.floor_rtol, not rtol
}



def history_units(loads: dict | None = None) -> dict:
    """Columns of the history of a scene, with units: :data:`HISTORY_UNITS`, then the columns of
    its loads by the one rule for extra columns. ``loads``: load name -> kind (class name,
    "DisplacementLoad", "DisplacementField" or "Traction"), in the scene's order.

    * two or more loads: ``force_<name>`` (N) for every load (``force`` stays the force of
      ``Scene.force_from``);
    * every ``Traction`` load: ``displacement_<name>`` (mm), its work-conjugate displacement.

    A scene with one displacement load has exactly :data:`HISTORY_UNITS`."""
    out = dict(HISTORY_UNITS)
    loads = dict(loads or {})
    if len(loads) > 1:
        out.update({f"force_{n}": "N" for n in loads})
    out.update({f"displacement_{n}": "mm" for n, kind in loads.items() if kind == "Traction"})
    return out


def peak_index(force) -> int | None:
    """Row of the peak of a force column: the largest finite force (the first row where it occurs
    when it occurs more than once; NaN and infinite forces are skipped), or None when no force is
    finite. The one definition of "the peak" in ngtmc: the runner's results, the report, the
    benchmarks and :class:`ngtmc.SimulationResult` use it (through :func:`peak`)."""
    f = np.asarray(force, dtype=float).ravel()
    finite = np.isfinite(f)
    if not finite.any():
        return None
    return int(np.argmax(np.where(finite, f, -np.inf)))


def peak(force, load) -> tuple[float, float] | tuple[None, None]:
    """The peak of a force-load curve: ``(peak force, load at it)`` as floats, in the units of the
    inputs (force unit, mm), at the row of :func:`peak_index`; ``(None, None)`` when no force is
    finite. ``force`` and ``load``: one value per row. A curve loaded mostly in the negative
    direction has its peak at its most negative force (not the 0 N of its start)."""
    f = np.asarray(force, dtype=float).ravel()
    x = np.asarray(load, dtype=float).ravel()
    if f.size != x.size:
        raise ValueError(f"peak: {f.size} forces but {x.size} loads; give one load per force")
    xs = x[np.isfinite(x)]
    negative = xs.size and -xs.min() > xs.max()
    i = peak_index(-f if negative else f)
    if i is None:
        return None, None
    return float(f[i]), float(x[i])


_UMASK = os.umask(0)
os.umask(_UMASK)


class CheckpointWarning(UserWarning):
    """A checkpoint file could not be read; it was moved aside and an older generation (or a re-run
    of that case) is used instead."""


# ====================================================================== atomic file output
def write_atomic(path, data: bytes | str):
    """Write ``data`` to ``path`` through a temporary file in the same folder and ``os.replace``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix="." + path.name + ".", suffix=".tmp")
    try:
        os.chmod(tmp, 0o666 & ~_UMASK)     # mkstemp creates 0600; give the file the usual permissions
        with os.fdopen(fd, "wb") as f:
            f.write(data.encode() if isinstance(data, str) else data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def jsonable(x, other=str):
    """Plain JSON types; non-finite floats become null; any other object becomes ``other(x)``."""
    if isinstance(x, dict):
        return {str(k): jsonable(v, other) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v, other) for v in x]
    if isinstance(x, np.ndarray):
        return [jsonable(v, other) for v in x.tolist()]
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (float, np.floating)):
        x = float(x)
        return x if math.isfinite(x) else None
    if x is None or isinstance(x, (int, str)):
        return x
    return other(x)


def write_json(path, obj):
    """``obj`` as indented JSON (through :func:`jsonable`), written atomically."""
    write_atomic(path, json.dumps(jsonable(obj), indent=2, allow_nan=False) + "\n")


def write_npz(path, arrays: dict):
    """Compressed ``.npz`` of ``arrays``, written atomically."""
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    write_atomic(path, buf.getvalue())


# ====================================================================== metadata
#: Units of the quantities of a run folder (``units`` in metadata.json).
UNITS = {"length": "mm", "force": "N", "stress": "MPa", "energy": "N mm", "time": "s"}


def versions() -> dict:
    """Versions of ngtmc, Python and the libraries that computed a run."""
    import pandas as pd

    from . import __version__
    v = {"ngtmc": __version__, "python": platform.python_version(), "numpy": np.__version__, "pandas": pd.__version__}
    try:
        import ngsolve
        v["ngsolve"] = ngsolve.__version__
    except Exception:  # pragma: no cover
        pass
    try:
        import netgen
        v["netgen"] = getattr(netgen, "__version__", None) or getattr(netgen, "version", None)
    except Exception:  # pragma: no cover
        pass
    try:
        import scipy
        v["scipy"] = scipy.__version__
    except Exception:  # pragma: no cover
        pass
    return {k: str(val) for k, val in v.items() if val is not None}


def git_revision() -> str | None:
    """Short git revision of the ngtmc source (``-dirty`` with uncommitted changes), or None."""
    here = Path(__file__).resolve().parent
    try:
        rev = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], cwd=here, capture_output=True,
                             text=True, timeout=10)
        if rev.returncode != 0:
            return None
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", "."],
                               cwd=here.parent, capture_output=True, text=True, timeout=10)
        suffix = "-dirty" if dirty.returncode == 0 and dirty.stdout.strip() else ""
        return rev.stdout.strip() + suffix
    except Exception:
        return None


def _guess_unit(key: str) -> str:
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
        unit, desc = res_desc.get(k, (_guess_unit(k), "mesh or step size (set by the resolution)"))
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
    or their origin. Settings without effect in ``p`` (:func:`ngtmc.study.effective_parameters`,
    which needs ``mod`` for the settings a study added later) are left out."""
    from .study import effective_parameters
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
    :class:`ngtmc.study.StudyError` listing the differences (``key: recorded -> given``), as do
    parameters that the study's code now resolves differently from the recorded values.
    Returns ``(resolution, overrides, p)``.
    """
    from .study import DEFAULT_CHANGED, StudyError, effective_parameters, study_parameters
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
    changed = {k: old for k, old in DEFAULT_CHANGED.items()
               if k in p and k not in rec_over and k not in (overrides or {})}
    if recorded:
        p.update({k: recorded.get(k, old) for k, old in changed.items()})
    elif (changed and meta.get("parameters_hash") and meta["parameters_hash"] != parameters_hash(p, mod)
          and meta["parameters_hash"] == parameters_hash({**p, **changed}, mod)):
        p.update(changed)
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
def process_info() -> dict:
    """``{"pid": ..., "host": ...}`` of this process (recorded in metadata.json to spot stale runs)."""
    return {"pid": os.getpid(), "host": socket.gethostname()}


def process_alive(pid) -> bool:
    """True when a process of id ``pid`` exists on this host (False for a pid that is not one)."""
    try:
        os.kill(int(pid), 0)
    except (OSError, ValueError, TypeError) as e:   # PermissionError: it exists, owned by someone else
        return isinstance(e, PermissionError)
    return True


def effective_status(meta: dict) -> tuple[str, str | None]:
    """``(status, note)`` of a run from its metadata: a ``"running"`` status whose process (recorded
    pid on this same host) no longer exists is reported as ``"interrupted"`` (resumable), with a
    note saying why. Any other status is returned as recorded."""
    status = str(meta.get("status") or "unknown")
    proc = meta.get("process") or {}
    if status != "running" or not proc.get("pid") or not proc.get("host"):
        return status, None
    if proc["host"] != socket.gethostname():
        return status, f"started on host {proc['host']}, whose processes cannot be checked from here"
    if process_alive(proc["pid"]):
        return status, f"process {proc['pid']} on {proc['host']} is alive"
    return "interrupted", (f"recorded as running, but its process {proc['pid']} on {proc['host']} is gone "
                           "(killed); resumable from its checkpoint")


def read_metadata(out: Path) -> dict | None:
    """The parsed ``metadata.json`` of a run folder, or None (with a warning when it is unreadable)."""
    f = Path(out) / "metadata.json"
    if not f.exists():
        return None
    try:
        meta = json.loads(f.read_text())
        return meta if isinstance(meta, dict) else None
    except Exception as e:
        warnings.warn(f"{f} cannot be read ({type(e).__name__}: {e}); resuming from the checkpoints alone",
                      CheckpointWarning, stacklevel=2)
        return None
