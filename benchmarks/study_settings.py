"""A named study run with several sets of study settings (``--set``), one after the other in one
command, as a new user runs it (``ngtmc run``): steps, Newton iterations, cut-backs, peak and
wall time of each, side by side, the peak compared with the first set's.

    python -m benchmarks.study_settings three-point-bending --resolution quick --threads 1 \\
        --variant "band:" \\
        --variant "remeshed: h_band=0.06 h_crack=0.015" \\
        --variant "bisected: h_band=0.06 h_crack=0.015 amr_remesh_maxh=0"

Each variant runs in a fresh process (``python -m ngtmc run NAME -r R --set ... --no-vtk
--no-report``) in a temporary folder; the record ``<study>-<resolution>-<UTC time>-settings.json``
/ ``.md`` goes to ``--out`` (default ``benchmarks/results``). Wall times are those of the runs'
histories (the cases' steps, set-up excluded) and of the whole command (set-up included); compare
them only within one record. Exit status 1 when a run failed.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
from pathlib import Path
import shlex
import subprocess
import sys
import tempfile
import time

from .compare_histories import summary
from .run import machine_info, _git

RESULTS = Path(__file__).resolve().parent / "results"


def parse_variant(text: str) -> tuple[str, list[str]]:
    """``"label: key=value key=value"`` -> (label, ["key=value", ...])."""
    label, _, rest = text.partition(":")
    if not label.strip():
        raise ValueError(f"variant {text!r} has no label (\"label: key=value ...\")")
    sets = rest.split()
    for s in sets:
        if "=" not in s:
            raise ValueError(f"variant {label!r}: {s!r} is not key=value")
    return label.strip(), sets


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.study_settings", description=__doc__.split("\n\n")[0])
    ap.add_argument("study")
    ap.add_argument("--resolution", "-r", default="quick")
    ap.add_argument("--variant", action="append", required=True, help='"label: key=value ..." (repeatable)')
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args(argv)
    try:
        variants = [parse_variant(v) for v in args.variant]
    except ValueError as e:
        ap.error(str(e))
    cmd = "python -m benchmarks.study_settings " + shlex.join(list(sys.argv[1:] if argv is None else argv))
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    runs, failed = [], False
    with tempfile.TemporaryDirectory() as tmp:
        for label, sets in variants:
            folder = Path(tmp) / label
            run_cmd = [sys.executable, "-m", "ngtmc", "run", args.study, "-r", args.resolution, "-o", str(folder),
                       "--threads", str(args.threads), "--no-vtk", "--no-report", "--quiet"]
            for s in sets:
                run_cmd += ["--set", s]
            print(f"[settings] {label}: {shlex.join(run_cmd[1:])}", flush=True)
            t0 = time.perf_counter()
            proc = subprocess.run(run_cmd, capture_output=True, text=True)
            wall = time.perf_counter() - t0
            entry = {"label": label, "settings": sets, "command_s": wall, "returncode": proc.returncode}
            if (folder / "history.csv").exists():
                s = summary(folder)
                s.pop("run", None)
                entry.update(s)
            if proc.returncode != 0:
                failed = True
                entry["stderr_tail"] = proc.stderr[-2000:]
            runs.append(entry)
            print(f"[settings] {label}: " + ", ".join(f"{k} {entry.get(k)}" for k in
                                                      ("steps", "newton_iterations", "cutbacks", "peak_force",
                                                       "wall_time_s", "command_s")), flush=True)
    ref = runs[0].get("peak_force")
    for r in runs:
        p = r.get("peak_force")
        r["peak_vs_first_pct"] = None if (p is None or not ref) else 100.0 * (p - ref) / abs(ref)
    record = {"command": cmd, "study": args.study, "resolution": args.resolution, "threads": args.threads,
              "time": stamp, "git": {"revision": _git("rev-parse", "HEAD"), "dirty": bool(_git("status", "--porcelain"))},
              "machine": machine_info(), "runs": runs}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    name = f"{args.study.replace('-', '_')}-{args.resolution}-{stamp}-settings"
    (out / f"{name}.json").write_text(json.dumps(record, indent=1, default=str))
    unit = runs[0].get("force_unit", "N")
    lines = [f"### {args.study}, {args.resolution}: study settings side by side ({stamp})", "",
             f"`{cmd}`", "", f"git {record['git']['revision']}{' (dirty)' if record['git']['dirty'] else ''}, "
             f"{args.threads} thread(s) per run, one run at a time", "",
             f"| label | settings | steps | Newton | cut-backs | peak {unit} | at mm | peak vs first % | run s | command s | status |",
             "|:---|:---|---:|---:|---:|---:|---:|---:|---:|---:|:---|"]
    for r in runs:
        def f(k, spec):
            v = r.get(k)
            return "-" if v is None else format(v, spec)
        lines.append(f"| {r['label']} | {' '.join(r['settings']) or '(defaults)'} | {f('steps', 'd')} | "
                     f"{f('newton_iterations', 'd')} | {f('cutbacks', 'd')} | {f('peak_force', '.3f')} | "
                     f"{f('peak_load_mm', '.5f')} | {f('peak_vs_first_pct', '+.2f')} | {f('wall_time_s', '.1f')} | "
                     f"{f('command_s', '.1f')} | {'ok' if r['returncode'] == 0 else 'failed'} |")
    (out / f"{name}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines[6:]))
    print(f"written {out / name}.json and .md")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
