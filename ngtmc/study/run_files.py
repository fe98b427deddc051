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

import io
import json
import math
import os
from pathlib import Path
import platform
import socket
import subprocess
import tempfile
import warnings

import numpy as np
from ngtmc.version import __version__

__all__ = ["SCHEMA_VERSION", "CheckpointWarning", "write_atomic", "write_json", "write_npz", "jsonable", "UNITS",
           "versions", "git_revision", "process_info", "process_alive", "effective_status", "read_metadata"]

#: Version of the run-folder format (``schema_version`` in metadata.json; absent means 1).
SCHEMA_VERSION = 2

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
    here = Path(__file__).resolve().parents[1]     # the package folder ngtmc/
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
