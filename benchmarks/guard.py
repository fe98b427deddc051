"""The J > 0 guard (det F at the guard points, :mod:`ngtmc.discrete.guard`) two ways, side by side:
the sparse matrix of grad u (the default) and NGSolve's interpolation of det F
(``NGTMC_J_GUARD=interpolate``). First the evaluation alone on the study's mesh (ms, best of 7, and
the largest difference of the values), then, with ``--runs``, the whole study run once each way
in fresh processes one after the other (steps, Newton iterations, peak, wall time, line search).

    python -m benchmarks.guard three-point-bending -r quick --threads 1 --runs
    python -m benchmarks.guard three-point-bending -r paper --threads 2 --runs
    python -m benchmarks.guard three-point-bending-3d --set parts=hemisphere --case hemisphere --runs

Record: ``guard-<study>-<resolution>-<UTC time>.json`` / ``.md`` in ``--out`` (default
``benchmarks/results``). Compare times only within one record.
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path
import shlex
import sys
import tempfile
import time

import numpy as np

from .run import machine_info
from .study_process import (RESULTS, cell, git_state, git_text, run_study, stamp, summary_of, time_split_of,
                            write_record)

WAYS = {"matrix": {}, "interpolate": {"NGTMC_J_GUARD": "interpolate"}}


def evaluation(study: str, resolution: str, threads: int, case: str | None = None, sets=()) -> dict:
    """ms per det F evaluation each way on the study's case named ``case`` (default its first),
    at a deformed state (a uniform compression of 1e-3 and a shear), and the largest difference
    of the values; ``sets``: study settings ``key=value``."""
    import ngsolve as ngs
    import ngtmc
    from ngtmc.discrete import guard
    from ngtmc.study import load_study, study_parameters
    ngs.SetNumThreads(threads)
    mod = load_study(study)
    _, p = study_parameters(mod, resolution, overrides=dict(item.split("=", 1) for item in sets))
    cases = mod.cases(p)
    chosen = [c for c in cases if case in (None, c.name)]
    if not chosen:
        raise SystemExit(f"no case {case!r}: {', '.join(c.name for c in cases)}")
    s = ngtmc.Solver(chosen[0].build_scene(), compile=False)
    shift = [0.0] * s.dim
    shift[0] = 1e-3 * (ngs.y if s.dim == 2 else ngs.z)
    shift[-1] = -1e-3 * (ngs.y if s.dim == 2 else ngs.z)
    s.u.Set(ngs.CF(tuple(shift)))
    out = {"case": chosen[0].name, "guard_points": int(s._guard_irs.ndof), "u_dofs": int(s.fes_u.ndof)}
    values = {}
    for way, env in WAYS.items():
        old = os.environ.pop(guard.GUARD_ENV, None)
        os.environ.update(env)
        try:
            s._J_op, s._J_cf = None, None
            t0 = time.perf_counter()
            with ngs.TaskManager():
                values[way] = s.J_values().copy()
                out[f"{way}_first_ms"] = 1e3 * (time.perf_counter() - t0)
                if s._J_op:
                    out["matrix_entries"] = int(s._J_op.matrix.nnz)
                times = []
                for _ in range(7):
                    t0 = time.perf_counter()
                    s.J_values()
                    times.append(time.perf_counter() - t0)
            out[f"{way}_ms"] = 1e3 * min(times)
        finally:
            os.environ.pop(guard.GUARD_ENV, None)
            if old is not None:
                os.environ[guard.GUARD_ENV] = old
    out["max_difference"] = float(np.max(np.abs(values["matrix"] - values["interpolate"])))
    return out


def record_lines(record: dict) -> list[str]:
    """The Markdown table of a record (a run of :func:`main`)."""
    ev, runs = record["evaluation"], record["runs"]
    lines = [f"### The J > 0 guard two ways: {record['study']}, {record['resolution']} ({record['time']})", "",
             f"`{record['command']}`", "",
             f"{git_text(record)}, {record['threads']} NGSolve thread(s), one run at a time", "",
             f"det F at {ev['guard_points']} guard points of case {ev.get('case', 'main')} ({ev['u_dofs']} u dofs), "
             "ms per evaluation (best of 7; the first call, which builds the matrix or the expression, in brackets):", "",
             "| matrix ms | interpolate ms | ratio | largest difference | matrix entries |",
             "|---:|---:|---:|---:|---:|",
             f"| {ev['matrix_ms']:.2f} ({ev['matrix_first_ms']:.0f}) | {ev['interpolate_ms']:.2f} "
             f"({ev['interpolate_first_ms']:.0f}) | {ev['interpolate_ms'] / ev['matrix_ms']:.1f} | "
             f"{ev['max_difference']:.1e} | {cell(ev.get('matrix_entries'), 'd')} |"]
    if runs:
        first = runs[0].get("wall_time_s")
        unit = runs[0].get("force_unit", "N")
        lines += ["", f"| way | steps | Newton | cut-backs | peak ({unit}) | run s | vs matrix | line search s | status |",
                  "|:---|---:|---:|---:|---:|---:|---:|---:|:---|"]
        for r in runs:
            split = r.get("time_split_s") or {}
            ratio = "-" if not (first and r.get("wall_time_s")) else f"{r['wall_time_s'] / first:.2f}"
            lines.append(f"| {r['way']} | {cell(r.get('steps'), 'd')} | {cell(r.get('newton_iterations'), 'd')} | "
                         f"{cell(r.get('cutbacks'), 'd')} | {cell(r.get('peak_force'), '.4f')} | "
                         f"{cell(r.get('wall_time_s'), '.1f')} | {ratio} | {cell(split.get('line_search'), '.1f')} | "
                         f"{'ok' if r['returncode'] == 0 else 'failed'} |")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.guard", description=__doc__.split("\n\n")[0])
    ap.add_argument("study")
    ap.add_argument("--resolution", "-r", default="quick")
    ap.add_argument("--threads", type=int, default=1, help="NGSolve threads")
    ap.add_argument("--runs", action="store_true", help="run the whole study once each way")
    ap.add_argument("--case", help="the case whose mesh the evaluation takes (default the first)")
    ap.add_argument("--set", action="append", default=[], help="study setting key=value of every run")
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args(argv)
    cmd = "python -m benchmarks.guard " + shlex.join(list(sys.argv[1:] if argv is None else argv))
    when = stamp()
    study = args.study.replace("-", "_")
    ev = evaluation(study, args.resolution, args.threads, args.case, args.set)
    print(f"[guard] evaluation: {ev}", flush=True)
    runs, failed = [], False
    if args.runs:
        with tempfile.TemporaryDirectory() as tmp:
            for way, env in WAYS.items():
                folder = Path(tmp) / way
                entry = {"way": way, "env": env, **run_study(args.study, args.resolution, folder, args.threads,
                                                             args.set, env)}
                entry.update(summary_of(folder), time_split_s=time_split_of(folder))
                failed |= entry["returncode"] != 0
                runs.append(entry)
                print(f"[guard] {way}: " + ", ".join(f"{k} {entry.get(k)}" for k in
                                                     ("steps", "newton_iterations", "peak_force", "wall_time_s")), flush=True)
    record = {"command": cmd, "study": study, "resolution": args.resolution, "threads": args.threads,
              "time": when, "git": git_state(), "machine": machine_info(), "evaluation": ev, "runs": runs}
    lines = record_lines(record)
    write_record(args.out, f"guard-{study}-{args.resolution}-{when}", record, lines)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
