"""What the benchmarks share that run named studies as a user runs them (``ngtmc run`` in a fresh
process each: ``study_settings``, ``stalls``, ``blas_threads``) or that write a record of their own
(``first_direction``): the run with its command time and the tail of a failure's stderr, the
summary of its history, the git state and the record, a JSON file beside its Markdown table in
``benchmarks/results``."""
from __future__ import annotations

import datetime as _dt
import json
import os
from pathlib import Path
import subprocess
import sys
import time

from .compare_histories import summary
from .harness import _fmt as cell
from .run import _git

__all__ = ["NGTMC", "RESULTS", "cell", "git_state", "git_text", "run_study", "stamp", "summary_of", "time_split_of",
           "write_record"]

RESULTS = Path(__file__).resolve().parent / "results"

#: the command line of ``ngtmc``, as ``python -m ngtmc``
NGTMC = (sys.executable, "-m", "ngtmc")


def stamp() -> str:
    """The UTC time of a record's name, ``YYYYmmddTHHMMSSZ``."""
    return _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%SZ")


def run_study(study: str, resolution: str, folder: Path, threads: int, sets=(), env: dict | None = None,
              launcher=NGTMC, stdout: bool = False) -> dict:
    """``ngtmc run STUDY -r RESOLUTION -o FOLDER --threads N --no-vtk --no-report --quiet`` with
    ``--set`` for each of ``sets`` in a fresh process (``launcher``: the command before ``run``;
    ``env``: variables set on top of this process's). Returns ``command_s`` (s), ``returncode``,
    for a failed run ``stderr_tail``, and with ``stdout`` the run's standard output."""
    cmd = [*launcher, "run", study, "-r", resolution, "-o", str(folder), "--threads", str(threads),
           "--no-vtk", "--no-report", "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, **(env or {})})
    out = {"command_s": time.perf_counter() - t0, "returncode": proc.returncode}
    if proc.returncode != 0:
        out["stderr_tail"] = proc.stderr[-2000:]
    if stdout:
        out["stdout"] = proc.stdout
    return out


def summary_of(folder: Path) -> dict:
    """:func:`benchmarks.compare_histories.summary` of a run folder without its path; {} where the
    run left no history."""
    if not (Path(folder) / "history.csv").exists():
        return {}
    s = summary(folder)
    s.pop("run", None)
    return s


def time_split_of(folder: Path) -> dict | None:
    """The first case's time split (s by part: assembly, solve, line search, ...) from a run
    folder's ``metadata.json``; None where the run left none."""
    meta = Path(folder) / "metadata.json"
    if not meta.exists():
        return None
    return next(iter(json.loads(meta.read_text()).get("results", {}).values()), {}).get("time_split_s")


def git_state() -> dict:
    """The revision and whether the working tree differs from it (untracked files included)."""
    return {"revision": _git("rev-parse", "HEAD"), "dirty": bool(_git("status", "--porcelain"))}


def git_text(record: dict) -> str:
    """``git REVISION`` with `` (dirty)`` where the record's tree was."""
    return f"git {record['git']['revision']}{' (dirty)' if record['git']['dirty'] else ''}"


def write_record(out, name: str, record: dict, lines: list[str], shown: int | None = 6, default=str) -> Path:
    """Write ``NAME.json`` (``record``) and ``NAME.md`` (``lines``) into the folder ``out``, print
    the lines from ``shown`` on (None: none) and where they went; returns the folder."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{name}.json").write_text(json.dumps(record, indent=1, default=default))
    (out / f"{name}.md").write_text("\n".join(lines) + "\n")
    if shown is not None:
        print("\n".join(lines[shown:]))
    print(f"written {out / name}.json and .md")
    return out
