"""The measured records of the studies: one JSON file per study, ``studies/records/<study>.json``
(package data of ``ngtmc.studies``), read by :func:`records` and written by :func:`add_record`.

A record file is ``{"study": NAME, "units": {...}, "records": {KEY: RECORD}}``; every record has
the fields of :data:`FIELDS`:

* ``command``: how to reproduce the run (``ngtmc run ...``; null where not recorded);
* ``date`` (``YYYY-MM-DD``) and ``commit`` (the run's ``git_revision``): null where not known;
* ``machine``: where and beside what it ran (wall times depend on it); ``note``: what it shows;
* ``figures``: the measured numbers, in the units of the file's ``units`` map or of their key
  (``_s`` seconds, ``_mb`` MB). Records are measurements, not inputs: no value sets a parameter.

A record made from a run folder (:func:`record_from_run`) has the run's figures per case::

    python -m ngtmc.study.measured RUN_DIR KEY [--note TEXT]    # adds it to its study's file
"""
from __future__ import annotations

import argparse
import importlib.resources
import json
import math
from pathlib import Path
import sys

import numpy as np
import pandas as pd

from ngtmc.study.run_files import write_atomic

__all__ = ["FIELDS", "records", "record_file", "record_from_run", "add_record", "main"]

#: The fields of every record.
FIELDS = ("command", "date", "commit", "machine", "note", "figures")

#: Units of a file made by :func:`add_record` (those of a run folder, ``docs/run-directory.md``).
RUN_UNITS = {"length": "mm", "force": "N (per mm of thickness in 2D: force_unit of the run)", "stress": "MPa",
             "energy": "N mm", "time": "s"}


def record_file(study: str):
    """The record file of ``study`` (``ngtmc.studies/records/<study>.json``; a ``Traversable``, a
    :class:`pathlib.Path` from a source tree), whether it exists or not."""
    name = str(study).strip().replace("-", "_")
    return importlib.resources.files("ngtmc.studies") / "records" / f"{name}.json"


def _read(path, study: str) -> dict:
    try:
        text = path.read_text()
    except (FileNotFoundError, NotADirectoryError):
        raise FileNotFoundError(f"no measured records of study {study!r}: {path} does not exist (records of a run "
                                "are added with: python -m ngtmc.study.measured RUN_DIR KEY)") from None
    try:
        data = json.loads(text)
    except ValueError as e:
        raise ValueError(f"the record file {path} is not valid JSON: {e}") from None
    if not isinstance(data, dict) or not isinstance(data.get("records"), dict):
        raise ValueError(f"the record file {path} has no object 'records'")
    return data


def records(study: str) -> dict:
    """The measured records of ``study`` (name with dashes or underscores): record key -> record
    (:data:`FIELDS`), read from ``studies/records/<study>.json``. A new dict on every call."""
    return _read(record_file(study), study)["records"]


# ---------------------------------------------------------------------- a record from a run folder
def _number(x):
    """A plain int or float (None for NaN, infinities and missing values)."""
    if x is None:
        return None
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    try:
        x = float(x)
    except (TypeError, ValueError):
        return x
    return x if math.isfinite(x) else None


def _peak(force, load):
    """(peak force, its load): the largest finite force, first row where it occurs; a curve loaded
    mostly in the negative direction peaks at its most negative force (ngtmc's definition)."""
    f, x = np.asarray(force, dtype=float), np.asarray(load, dtype=float)
    ok = np.isfinite(f)
    if not ok.any():
        return None, None
    xs = x[np.isfinite(x)]
    sign = -1.0 if xs.size and -xs.min() > xs.max() else 1.0
    i = int(np.argmax(np.where(ok, sign * f, -np.inf)))
    return float(f[i]), float(x[i])


def _case_figures(h: pd.DataFrame) -> dict:
    h = h.sort_values("step") if "step" in h else h
    out = {}
    if "step" in h and len(h):
        out["steps"] = int(h["step"].max())
    for col in ("newton_iterations", "cutbacks"):
        if col in h:
            out[col] = int(pd.to_numeric(h[col], errors="coerce").fillna(0).sum())
    if {"force", "load"} <= set(h.columns) and len(h):
        out["peak_force"], out["peak_load"] = _peak(h["force"], h["load"])
        out["final_load"], out["final_force"] = _number(h["load"].iloc[-1]), _number(h["force"].iloc[-1])
    if "wall_time" in h and len(h):
        out["wall_time_s"] = _number(h["wall_time"].iloc[-1])
    return out


def _command(meta: dict) -> str | None:
    """The ``ngtmc run`` command of a run: study, resolution and overrides of its metadata."""
    study = meta.get("study")
    if not study:
        return None
    words = ["ngtmc", "run", str(study).replace("_", "-")]
    if meta.get("resolution"):
        words += ["--resolution", str(meta["resolution"])]
    for key, value in sorted((meta.get("overrides") or {}).items()):
        if isinstance(value, (list, tuple)):
            value = ",".join(map(str, value))
        elif isinstance(value, bool):
            value = str(value).lower()
        words += ["--set", f"{key}={value}"]
    return " ".join(words)


def _machine(meta: dict) -> str | None:
    host, proc = meta.get("host") or {}, meta.get("process") or {}
    parts = [str(host["platform"])] if host.get("platform") else []
    if host.get("cpu_count"):
        parts.append(f"{host['cpu_count']} CPUs")
    if host.get("threads"):
        parts.append(f"{host['threads']} thread(s)")
    if proc.get("host"):
        parts.append(f"host {proc['host']}")
    return ", ".join(parts) or None


def record_from_run(run_dir, note: str = "") -> dict:
    """A record (:data:`FIELDS`) of the run folder ``run_dir`` from its ``metadata.json`` and
    ``history.csv``: the ``ngtmc run`` command (study, resolution, overrides), the date it started,
    its commit (``git_revision``), the machine, and as figures the run's status, wall time (s),
    mesh size and per case (``cases``) steps, Newton iterations, cut-backs, peak force and its
    load, final load and force and wall time (s). The history gives the numbers; the run's results
    give a case's status and threads and, where recorded, its peak (the same definition), and
    under ``results`` every other number of the case's results (in the units of the run)."""
    run_dir = Path(run_dir)
    meta_file = run_dir / "metadata.json"
    if not meta_file.is_file():
        raise FileNotFoundError(f"{meta_file} does not exist: {run_dir} is not a run folder")
    meta = json.loads(meta_file.read_text())
    hist_file = run_dir / "history.csv"
    hist = pd.read_csv(hist_file) if hist_file.is_file() else pd.DataFrame()
    results = meta.get("results") or {}
    listed = [c.get("name") for c in meta.get("cases") or [] if isinstance(c, dict) and c.get("name")]
    names = listed or list(results)      # the cases (not the entries a study's post_results adds)
    if "case" in hist:
        names += [c for c in dict.fromkeys(hist["case"].astype(str)) if c not in names]
    threads = {c.get("name"): c.get("threads") for c in meta.get("cases") or [] if isinstance(c, dict)}
    cases = {}
    for name in names:
        h = hist[hist["case"].astype(str) == name] if "case" in hist else hist
        fig = _case_figures(h)
        res = results.get(name) or {}
        for key in ("peak_force", "peak_load", "wall_time_s"):   # the case's own (a run inside it has its own)
            if res.get(key) is not None:
                fig[key] = _number(res[key])
        for key in ("status",):
            if res.get(key) is not None:
                fig[key] = res[key]
        if threads.get(name) is not None:
            fig["threads"] = int(threads[name])
        # the other numbers the case's results hold (a case with its own run, e.g. an optimisation)
        more = {k: _number(v) for k, v in sorted(res.items()) if k not in fig
                and isinstance(v, (int, float)) and not isinstance(v, bool)}
        if more:
            fig["results"] = more
        cases[name] = fig
    mesh = meta.get("mesh") or {}
    figures = {"status": meta.get("status"), "wall_time_s": _number(meta.get("wall_time_s")),
               **{k: _number(mesh[k]) for k in ("n_elements", "ndof_u", "ndof_alpha") if k in mesh},
               "cases": cases}
    created = meta.get("created")
    return {"command": _command(meta), "date": str(created)[:10] if created else None,
            "commit": meta.get("git_revision"), "machine": _machine(meta), "note": str(note),
            "figures": figures}


# ---------------------------------------------------------------------- writing
def add_record(study: str, key: str, record: dict, path=None) -> Path:
    """Write ``record`` (:data:`FIELDS`) as ``key`` into the record file of ``study`` (``path``:
    another file, e.g. in a test), creating the file if needed; sorted keys, indent 1, written
    atomically. An existing record of that key is replaced. Returns the file."""
    missing = [f for f in FIELDS if f not in record]
    if missing:
        raise ValueError(f"add_record: the record {key!r} lacks {', '.join(missing)} (fields: {', '.join(FIELDS)})")
    name = str(study).strip().replace("-", "_")
    path = Path(path) if path is not None else Path(str(record_file(name)))
    data = _read(path, name) if path.exists() else {"study": name, "units": dict(RUN_UNITS), "records": {}}
    data["records"][str(key)] = record
    write_atomic(path, json.dumps(data, sort_keys=True, indent=1, allow_nan=False) + "\n")
    return path


def main(argv=None) -> int:
    """``python -m ngtmc.study.measured RUN_DIR KEY [--note TEXT]``."""
    ap = argparse.ArgumentParser(prog="python -m ngtmc.study.measured",
                                 description="Add the record of a run folder to its study's record file "
                                             "(studies/records/<study>.json).")
    ap.add_argument("run_dir", help="the run folder (with metadata.json and history.csv)")
    ap.add_argument("key", help="the record's key, e.g. quick_path_following")
    ap.add_argument("--note", default="", help="what the run shows, and beside what it ran")
    args = ap.parse_args(argv)
    try:
        rec = record_from_run(args.run_dir, note=args.note)
        study = json.loads((Path(args.run_dir) / "metadata.json").read_text()).get("study")
        if not study:
            raise ValueError(f"{args.run_dir}/metadata.json names no study")
        path = add_record(study, args.key, rec)
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(f"{path}: record {args.key!r} of {args.run_dir}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
