"""Two run folders' histories compared column by column: the evidence that a change which should
not move the results did not.

    python -m benchmarks.compare_histories RUN_A RUN_B [--label-a A] [--label-b B] [--out benchmarks/results]

Every column of ``history.csv`` but the times (``wall_time``, ``solve_time``, ``assembly_time``)
must be equal, value for value (NaN equal to NaN). Prints the table and, with ``--out``, writes a
record ``compare-<date>.md`` / ``.json`` there (commits, steps, Newton iterations, cut-backs, peak,
wall time of each). Exit status 1 when a column differs.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
from pathlib import Path
import shlex
import sys

import numpy as np
import pandas as pd

TIMES = ("wall_time", "solve_time", "assembly_time")


def summary(run: Path) -> dict:
    """Steps, Newton iterations, cut-backs, peak (force unit, mm), wall time (s) and commit of a run folder."""
    from ngtmc.simulation import peak
    h = pd.read_csv(run / "history.csv")
    meta = json.loads((run / "metadata.json").read_text()) if (run / "metadata.json").exists() else {}
    f, x = peak(h["force"], h["load"])
    return {"run": str(run), "commit": meta.get("git_revision"), "rows": int(len(h)), "steps": int(h["step"].iloc[-1]),
            "newton_iterations": int(h["newton_iterations"].sum()), "cutbacks": int(h["cutbacks"].sum()),
            "peak_force": f, "peak_load_mm": x, "force_unit": meta.get("force_unit", "N"),
            "wall_time_s": float(h["wall_time"].iloc[-1])}


def differing_columns(a: pd.DataFrame, b: pd.DataFrame) -> list[str]:
    """The columns (times excluded) whose values differ, or that only one history has."""
    out = sorted(set(a.columns) ^ set(b.columns))
    if len(a) != len(b):
        return out + ["(rows)"]
    for c in a.columns:
        if c in TIMES or c not in b.columns:
            continue
        x, y = a[c].to_numpy(), b[c].to_numpy()
        same = np.array_equal(x, y, equal_nan=True) if x.dtype.kind == "f" and y.dtype.kind == "f" else (a[c] == b[c]).all()
        if not same:
            out.append(c)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.compare_histories", description=__doc__.split("\n\n")[0])
    ap.add_argument("a", type=Path)
    ap.add_argument("b", type=Path)
    ap.add_argument("--label-a", default="before")
    ap.add_argument("--label-b", default="after")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args(argv)
    ha, hb = pd.read_csv(args.a / "history.csv"), pd.read_csv(args.b / "history.csv")
    diff = differing_columns(ha, hb)
    rows = [(args.label_a, summary(args.a)), (args.label_b, summary(args.b))]
    lines = ["| run | commit | steps | Newton | cut-backs | peak | at mm | wall s |", "|:---|:---|---:|---:|---:|---:|---:|---:|"]
    for label, s in rows:
        lines.append(f"| {label} | {s['commit']} | {s['steps']} | {s['newton_iterations']} | {s['cutbacks']} | "
                     f"{s['peak_force']:.6g} {s['force_unit']} | {s['peak_load_mm']:.6g} | {s['wall_time_s']:.1f} |")
    verdict = ("every column but the times equal, value for value" if not diff
               else f"columns that differ: {', '.join(diff)}")
    text = "\n".join(lines) + f"\n\n{verdict} ({len(ha.columns)} columns, {len(ha)} rows)\n"
    print(text)
    if args.out is not None:
        stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%SZ")
        args.out.mkdir(parents=True, exist_ok=True)
        cmd = "python -m benchmarks.compare_histories " + shlex.join(sys.argv[1:] if argv is None else argv)
        (args.out / f"compare-{stamp}.md").write_text(f"### Histories compared ({stamp})\n\n`{cmd}`\n\n{text}")
        (args.out / f"compare-{stamp}.json").write_text(json.dumps(
            {"command": cmd, "date": stamp, "runs": dict(rows), "differing_columns": diff}, indent=1, default=str))
    return 1 if diff else 0


if __name__ == "__main__":
    sys.exit(main())
