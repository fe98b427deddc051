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
from pathlib import Path
import shlex
import sys
import tempfile

from .run import machine_info
from .study_process import RESULTS, cell, git_state, git_text, run_study, stamp, summary_of, write_record


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
    when = stamp()
    runs, failed = [], False
    with tempfile.TemporaryDirectory() as tmp:
        for label, sets in variants:
            folder = Path(tmp) / label
            print(f"[settings] {label}: {' '.join(sets) or '(defaults)'}", flush=True)
            entry = {"label": label, "settings": sets,
                     **run_study(args.study, args.resolution, folder, args.threads, sets)}
            entry.update(summary_of(folder))
            failed |= entry["returncode"] != 0
            runs.append(entry)
            print(f"[settings] {label}: " + ", ".join(f"{k} {entry.get(k)}" for k in
                                                      ("steps", "newton_iterations", "cutbacks", "peak_force",
                                                       "wall_time_s", "command_s")), flush=True)
    ref = runs[0].get("peak_force")
    for r in runs:
        p = r.get("peak_force")
        r["peak_vs_first_pct"] = None if (p is None or not ref) else 100.0 * (p - ref) / abs(ref)
    record = {"command": cmd, "study": args.study, "resolution": args.resolution, "threads": args.threads,
              "time": when, "git": git_state(), "machine": machine_info(), "runs": runs}
    unit = runs[0].get("force_unit", "N")
    lines = [f"### {args.study}, {args.resolution}: study settings side by side ({when})", "",
             f"`{cmd}`", "", f"{git_text(record)}, {args.threads} thread(s) per run, one run at a time", "",
             f"| label | settings | steps | Newton | cut-backs | peak {unit} | at mm | peak vs first % | run s | command s | status |",
             "|:---|:---|---:|---:|---:|---:|---:|---:|---:|---:|:---|"]
    for r in runs:
        lines.append(f"| {r['label']} | {' '.join(r['settings']) or '(defaults)'} | {cell(r.get('steps'), 'd')} | "
                     f"{cell(r.get('newton_iterations'), 'd')} | {cell(r.get('cutbacks'), 'd')} | "
                     f"{cell(r.get('peak_force'), '.3f')} | {cell(r.get('peak_load_mm'), '.5f')} | "
                     f"{cell(r.get('peak_vs_first_pct'), '+.2f')} | {cell(r.get('wall_time_s'), '.1f')} | "
                     f"{cell(r.get('command_s'), '.1f')} | {'ok' if r['returncode'] == 0 else 'failed'} |")
    write_record(args.out, f"{args.study.replace('-', '_')}-{args.resolution}-{when}-settings", record, lines)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
