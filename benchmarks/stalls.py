"""Stalls across the named studies: every study run as a new user runs it (``ngtmc run NAME -r
R``), and for each case the steps, the Newton iterations over all attempts, the most any one step
needed and the steps that needed more than ``--limit`` (default 20, the target of no stall).

    python -m benchmarks.stalls --resolution quick
    python -m benchmarks.stalls three-point-bending l-panel --resolution quick --limit 20
    python -m benchmarks.stalls --from RUN_FOLDER [RUN_FOLDER ...]     # tabulate earlier runs

Each study runs in a fresh process (``--no-vtk --no-report --quiet``) in a temporary folder, one
after the other; every ``history.csv`` under its folder counts (a design study writes one per
forward run it keeps). A step's Newton count is that of its history row: the iterations of all
its attempts, cut-backs and refinements included. The record ``stalls-<resolution>-<UTC
time>.json`` / ``.md`` goes to ``--out`` (default ``benchmarks/results``). Exit status 1 when a
run failed, 0 otherwise: a step over the limit is a finding, not a failure of the tool.
"""
from __future__ import annotations

import argparse
from pathlib import Path
import shlex
import sys
import tempfile

import pandas as pd

from .run import machine_info
from .study_process import RESULTS, cell, git_state, git_text, run_study, stamp, write_record

#: a step that needs more Newton iterations than this stalls (the target of no stall)
LIMIT = 20


def studies() -> list[str]:
    """The command-line names of the registered studies."""
    from ngtmc.study.registry import list_studies
    return sorted(n.replace("_", "-") for n in list_studies())


def tabulate(folder: Path, limit: int = LIMIT, label: str | None = None) -> list[dict]:
    """One row per case of every ``history.csv`` under ``folder``: steps, Newton iterations,
    cut-backs, the largest Newton count of a step and where, the steps over ``limit``."""
    rows = []
    for path in sorted(Path(folder).rglob("history.csv")):
        h = pd.read_csv(path)
        if "case" not in h:
            h["case"] = "main"
        where = str(path.parent.relative_to(folder)) if path.parent != Path(folder) else ""
        for case, g in h.groupby("case", sort=False):
            g = g[g["step"] > 0] if "step" in g else g
            n = g["newton_iterations"].fillna(0).astype(int)
            worst = int(n.idxmax()) if len(n) else None
            over = g[n > limit]
            rows.append({
                "study": label or Path(folder).name, "run": where, "case": str(case), "steps": int(len(g)),
                "newton_iterations": int(n.sum()),
                "cutbacks": int(g["cutbacks"].fillna(0).sum()) if "cutbacks" in g else None,
                "max_step_newton": int(n.max()) if len(n) else 0,
                "max_step": None if worst is None else int(g.loc[worst, "step"]),
                "max_step_load_mm": None if worst is None else float(g.loc[worst, "load"]),
                "steps_over_limit": int(len(over)),
                "over_limit": [[int(r["step"]), float(r["load"]), int(r["newton_iterations"])] for _, r in over.iterrows()],
            })
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.stalls", description=__doc__.split("\n\n")[0])
    ap.add_argument("studies", nargs="*", help="study names (default: all registered)")
    ap.add_argument("--resolution", "-r", default="quick")
    ap.add_argument("--limit", type=int, default=LIMIT, help="a step over this many Newton iterations stalls")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--from", dest="folders", nargs="+", help="tabulate these run folders instead of running")
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args(argv)
    if args.limit < 1:
        ap.error(f"--limit {args.limit} must be at least 1")
    cmd = "python -m benchmarks.stalls " + shlex.join(list(sys.argv[1:] if argv is None else argv))
    when = stamp()
    runs, failed = [], False
    if args.folders:
        for f in args.folders:
            if not Path(f).is_dir():
                ap.error(f"--from {f}: no such folder")
            runs.append({"study": Path(f).name, "returncode": 0, "command_s": None,
                         "cases": tabulate(Path(f), args.limit)})
    else:
        known = studies()
        names = args.studies or known
        for n in names:
            if n.replace("_", "-") not in known:
                ap.error(f"unknown study {n!r}; known: {', '.join(known)}")
        with tempfile.TemporaryDirectory() as tmp:
            for name in names:
                folder = Path(tmp) / name
                print(f"[stalls] ngtmc run {name} -r {args.resolution}", flush=True)
                entry = {"study": name, **run_study(name, args.resolution, folder, args.threads)}
                entry["cases"] = tabulate(folder, args.limit, name) if folder.is_dir() else []
                failed |= entry["returncode"] != 0
                runs.append(entry)
                for c in entry["cases"]:
                    print(f"[stalls] {name} {c['run']} {c['case']}: {c['steps']} steps, {c['newton_iterations']} "
                          f"Newton, at most {c['max_step_newton']} in a step, {c['steps_over_limit']} over "
                          f"{args.limit}", flush=True)
    record = {"command": cmd, "resolution": args.resolution, "limit": args.limit, "threads": args.threads,
              "time": when, "git": git_state(), "machine": machine_info(), "runs": runs}
    lines = [f"### Stalls across the studies, {args.resolution} ({when})", "", f"`{cmd}`", "",
             f"{git_text(record)}, {args.threads} "
             f"thread(s), one run at a time. A step stalls when it needs more than {args.limit} Newton "
             "iterations over all its attempts.", "",
             f"| study | run | case | steps | Newton | cut-backs | most in a step | at step (load mm) | steps over {args.limit} | command s | status |",
             "|:---|:---|:---|---:|---:|---:|---:|:---|---:|---:|:---|"]
    for r in runs:
        status = "ok" if r["returncode"] == 0 else "failed"
        cs = cell(r["command_s"], ".0f")
        if not r["cases"]:
            lines.append(f"| {r['study']} | - | - | - | - | - | - | - | - | {cs} | {status} |")
        for c in r["cases"]:
            at = "-" if c["max_step"] is None else f"{c['max_step']} ({c['max_step_load_mm']:.5g})"
            lines.append(f"| {c['study']} | {c['run'] or '.'} | {c['case']} | {c['steps']} | {c['newton_iterations']} | "
                         f"{c['cutbacks'] if c['cutbacks'] is not None else '-'} | {c['max_step_newton']} | {at} | "
                         f"{c['steps_over_limit']} | {cs} | {status} |")
    write_record(args.out, f"stalls-{args.resolution}-{when}", record, lines)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
