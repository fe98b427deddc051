"""A named study through ``ngtmc run``, serially and on MPI ranks, side by side in one command.

    python -m benchmarks.mpi_run                                   # three-point bending, quick, 2 and 3 ranks
    python -m benchmarks.mpi_run --study l-panel --set load_cases=monotonic --ranks 3

Each run is the user's command: ``ngtmc run STUDY --no-report --no-vtk`` in one process, then
``mpiexec -n N python -m mpi4py -m ngtmc run STUDY --mpi --no-report`` for each N of ``--ranks``
(NGSolve gives rank 0 no elements: N ranks compute on N - 1, and the Newton systems are gathered
and factorized on rank 0). One thread per process. Printed and recorded per run: wall time of the
command and of the case, steps, Newton iterations, cut-backs, the time split of the case (rank
0's on MPI ranks), peak memory of the case (rank 0's), the peak force, and the largest difference
of the force history from the serial run's. Runs one after the other, so the ratios hold on a
shared machine only if nothing else runs. Writes ``<out>/mpi_run-<study>-<UTC time>.json`` and
``.md``. Units: s, MB, N (per mm of thickness in 2D), mm.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from .mpi import _launcher
from .run import ROOT, machine_info


def _one(cmd: list[str], out: Path) -> dict:
    env = dict(os.environ, OMP_NUM_THREADS="1")
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
    meta = json.loads((out / "metadata.json").read_text())
    hist = pd.read_csv(out / "history.csv")
    rows = []
    for name, r in meta["results"].items():
        rows.append({"case": name, "case_wall_s": r["wall_time_s"], "steps": r["steps"],
                     "newton_iterations": r["newton_iterations"], "cutbacks": r["cutbacks"],
                     "peak_force": r.get("peak_force"), "peak_memory_mb": r.get("peak_memory_mb"),
                     "time_split_s": r.get("time_split_s", {})})
    return {"command_wall_s": wall, "cases": rows, "history": hist}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.mpi_run", description=__doc__.splitlines()[0])
    ap.add_argument("--study", default="three-point-bending")
    ap.add_argument("--resolution", "-r", default="quick")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--ranks", type=int, nargs="+", default=[2, 3])
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    args = ap.parse_args(argv)
    sets = [a for kv in args.overrides for a in ("--set", kv)]
    base = [sys.executable, "-m", "ngtmc", "run", args.study, "-r", args.resolution, "--no-report", "-q", *sets]
    runs = {}
    with tempfile.TemporaryDirectory(prefix="ngtmc-mpi-run-") as tmp:
        out = Path(tmp) / "serial"
        runs["serial"] = _one([*base, "--no-vtk", "--threads", "1", "-o", str(out)], out)
        launcher = _launcher()
        for n in args.ranks:
            out = Path(tmp) / f"ranks{n}"
            runs[f"{n} ranks"] = _one([launcher, "-n", str(n), sys.executable, "-m", "mpi4py", *base[1:], "--mpi",
                                       "-o", str(out)], out)
    ref = runs["serial"]["history"]
    lines = [f"# `ngtmc run {args.study} -r {args.resolution} {' '.join(sets)}` serially and on MPI ranks", "",
             "| run | command s | case s | steps | Newton | cut-backs | assembly s | factorization s | solve s | "
             "line search s | peak memory MB (rank 0) | peak force | max force difference |",
             "|:---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    record = {"study": args.study, "resolution": args.resolution, "overrides": args.overrides,
              "machine": machine_info(), "runs": {}}
    for label, r in runs.items():
        h = r["history"]
        diff = float(np.max(np.abs(h["force"].to_numpy() - ref["force"].to_numpy()))) if len(h) == len(ref) else None
        for c in r["cases"]:
            ts = c["time_split_s"]
            lines.append(f"| {label} ({c['case']}) | {r['command_wall_s']:.1f} | {c['case_wall_s']:.1f} | {c['steps']} | "
                         f"{c['newton_iterations']} | {c['cutbacks']} | {ts.get('assembly', 0):.1f} | "
                         f"{ts.get('factorization', 0):.1f} | {ts.get('solve', 0):.1f} | {ts.get('line_search', 0):.1f} | "
                         f"{c['peak_memory_mb'] or 0:.0f} | {c['peak_force']:.6g} | "
                         f"{'different steps' if diff is None else f'{diff:.2e}'} |")
        record["runs"][label] = {"command_wall_s": r["command_wall_s"], "cases": r["cases"], "max_force_difference": diff}
    text = "\n".join(lines)
    print(text)
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    dest = Path(args.out)
    dest.mkdir(parents=True, exist_ok=True)
    stem = dest / f"mpi_run-{args.study}-{args.resolution}-{stamp}"
    stem.with_suffix(".json").write_text(json.dumps(record, indent=1, default=str))
    stem.with_suffix(".md").write_text(text + "\n")
    print(f"recorded: {stem}.json, .md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
