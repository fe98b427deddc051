"""The cases of a study serially and on a local Dask cluster, in one command.

    python -m benchmarks.parallel step-control --resolution quick
    python -m benchmarks.parallel step-control --resolution quick --workers 2 --set k_u_values=0,1000

Runs ``ngtmc.run_study`` twice into fresh run folders (under ``--keep DIR``, else a temporary
folder): once serially, the cases one after the other in this process with ``--threads`` NGSolve
threads, and once with ``workers=--workers`` (one case per worker process, ``--threads`` NGSolve
threads per worker). Prints the wall times, their ratio and whether the histories are identical
(every column but the times, compared exactly), and writes ``<out>/parallel-<study>-<resolution>-
<UTC time>.json`` (the record) and ``.md`` (the table). Needs the extra ``parallel``
(``pip install ngtmc[parallel]``). Exit status: 0 both runs completed with identical histories,
1 a run failed or the histories differ, 2 usage error.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import shlex
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from .run import ROOT, machine_info

TIME_COLUMNS = ("wall_time", "solve_time", "assembly_time")


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.parallel", description=__doc__.splitlines()[0])
    ap.add_argument("study", help="study name (dashes or underscores) or study file")
    ap.add_argument("--resolution", "-r", default=None, help="quick, medium or paper (default: the study's)")
    ap.add_argument("--workers", type=int, default=2, help="worker processes of the parallel run (default 2)")
    ap.add_argument("--threads", type=int, default=1,
                    help="NGSolve threads of the serial run and of each worker (default 1)")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                    help="override a study parameter in both runs (repeatable)")
    ap.add_argument("--keep", default=None, metavar="DIR", help="write the two run folders into DIR (kept)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"), help="folder of the record")
    ap.add_argument("--quiet", "-q", action="store_true", help="no progress lines of the runs")
    return ap


def compare_histories(a: pd.DataFrame, b: pd.DataFrame) -> dict:
    """Exact comparison of two history.csv tables without their time columns."""
    a = a.drop(columns=[c for c in TIME_COLUMNS if c in a.columns])
    b = b.drop(columns=[c for c in TIME_COLUMNS if c in b.columns])
    out = {"rows": [len(a), len(b)], "columns_equal": list(a.columns) == list(b.columns)}
    if not out["columns_equal"] or len(a) != len(b):
        return {**out, "identical": False}
    num = a.select_dtypes("number").columns
    diff = (a[num] - b[num]).abs().to_numpy(dtype=float)
    out["max_abs_difference"] = float(np.nanmax(diff)) if diff.size else 0.0
    out["identical"] = bool(a.equals(b))
    return out


def _one(label, run, out, **kw) -> dict:
    meta_path = out / "metadata.json"
    t0 = time.perf_counter()
    error = None
    try:
        run(output=out, **kw)
    except Exception as e:   # recorded, the other run still goes
        error = f"{type(e).__name__}: {e}"
    wall = time.perf_counter() - t0
    meta = json.loads(meta_path.read_text()) if meta_path.exists() else {}
    cases = {name: {k: r.get(k) for k in ("status", "steps", "newton_iterations", "wall_time_s", "cpu_time_s",
                                          "peak_force")}
             for name, r in (meta.get("results") or {}).items()}
    return {"label": label, "wall_s": wall, "status": meta.get("status", "failed"), "error": error,
            "cases": cases, "folder": str(out)}


def markdown(rec: dict) -> str:
    s, p = rec["serial"], rec["parallel"]
    lines = [f"### {rec['study']}, {rec['resolution']}: serial against {rec['workers']} workers ({rec['created']})",
             "", f"`{rec['command']}`", "",
             f"git {rec['machine'].get('git_revision') or '?'}, {rec['machine'].get('cpu_count')} CPUs, load average "
             f"at start {rec['machine'].get('load_average_at_start')}, {rec['threads']} NGSolve thread(s) per case; "
             f"histories identical (all columns but the times): **{rec['histories']['identical']}**", "",
             "| case | steps | Newton | serial wall s | parallel wall s | serial CPU s | parallel CPU s |",
             "|:---|---:|---:|---:|---:|---:|---:|"]
    for name, c in s["cases"].items():
        q = p["cases"].get(name, {})
        f = lambda v: "-" if v is None else f"{v:.1f}"   # noqa: E731
        lines.append(f"| {name} | {c.get('steps')} | {c.get('newton_iterations')} | {f(c.get('wall_time_s'))} | "
                     f"{f(q.get('wall_time_s'))} | {f(c.get('cpu_time_s'))} | {f(q.get('cpu_time_s'))} |")
    lines += ["", f"whole run: serial {s['wall_s']:.1f} s, parallel {p['wall_s']:.1f} s, "
                  f"serial / parallel = **{rec['speedup']:.2f}**", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    from ngtmc.cli import parse_overrides
    from ngtmc.runner import run_study
    from ngtmc.runner.parallel import check_settings
    from ngtmc.study import load_study, load_study_file
    from ngtmc.study import StudyError
    try:
        overrides = parse_overrides(args.overrides)
        mod = load_study_file(args.study) if args.study.endswith(".py") else load_study(args.study)
        check_settings(args.workers, None)
    except (StudyError, ValueError) as e:
        print(f"{ap.prog}: error: {e}", file=sys.stderr)
        return 2
    res = args.resolution or getattr(mod, "DEFAULT_RESOLUTION", "quick")
    base = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="ngtmc-parallel-"))
    stamp = _dt.datetime.now(_dt.timezone.utc)
    tag = f"{mod.NAME}-{res}-{stamp.strftime('%Y%m%dT%H%M%SZ')}"
    common = dict(resolution=res, overrides=overrides, report=False, vtk=False, progress=not args.quiet)
    machine = machine_info()
    serial = _one("serial", lambda **kw: run_study(mod, **kw), base / f"{tag}-serial", threads=args.threads, **common)
    par = _one(f"{args.workers} workers", lambda **kw: run_study(mod, **kw), base / f"{tag}-parallel",
               threads=args.threads, workers=args.workers, **common)
    try:
        hist = compare_histories(pd.read_csv(Path(serial["folder"]) / "history.csv"),
                                 pd.read_csv(Path(par["folder"]) / "history.csv"))
    except OSError as e:
        hist = {"identical": False, "error": str(e)}
    rec = {"study": mod.NAME, "resolution": res, "overrides": overrides, "workers": args.workers,
           "threads": args.threads, "created": stamp.isoformat(timespec="seconds"),
           "command": "python -m benchmarks.parallel " + " ".join(shlex.quote(a) for a in
                                                                 (sys.argv[1:] if argv is None else argv)),
           "machine": machine, "serial": serial, "parallel": par, "histories": hist,
           "speedup": serial["wall_s"] / par["wall_s"] if par["wall_s"] > 0 else None}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"parallel-{tag}.json").write_text(json.dumps(rec, indent=2, default=str) + "\n")
    (out / f"parallel-{tag}.md").write_text(markdown(rec))
    print(markdown(rec))
    print(f"record: {out / f'parallel-{tag}.json'}")
    ok = serial["status"] == par["status"] == "completed" and hist.get("identical")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
