"""How honest is the progress line's estimate of the time left? (``python -m benchmarks.progress_estimate
[STUDY ...]``; default the three-point bending and the contact study at quick, a few minutes.)

Each named study runs at its quick resolution with the progress line on; every line it prints is
recorded with its elapsed time and its estimate (or none). When the case ends, the true time left
at each line is known, and the error of each estimate is estimate / true - 1. The record gives
per study: the lines, how many carried an estimate, and the median and largest |error| of those.

Writes ``benchmarks/results/progress_estimate-<UTC stamp>.json`` and ``.md``.
"""
from __future__ import annotations

import json
import platform
import re
import subprocess
import sys
import tempfile
import warnings
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import pandas as pd

from ngtmc.simulation import plugins
from ngtmc.runner import run_study

RESULTS = Path(__file__).resolve().parent / "results"
DEFAULT = ("three-point-bending", "contact-gamma0")


def measure(study: str) -> dict:
    lines = []
    line = plugins.Progress.line

    def recording(self, sim, row):
        text = line(self, sim, row)
        m = re.search(r"about (\d+) s left", text)
        lines.append({"prefix": self.prefix, "elapsed_s": float(row.get("wall_time", 0.0) or 0.0),
                      "estimate_s": float(m.group(1)) if m else None, "text": text})
        return text

    plugins.Progress.line = recording
    try:
        with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = run_study(study, "quick", Path(tmp) / "run", report=False, vtk=False, progress=True)
            hist = pd.read_csv(Path(out) / "history.csv")
    finally:
        plugins.Progress.line = line
    ends = hist.groupby("case")["wall_time"].max().to_dict()
    errors, with_est = [], 0
    for rec in lines:
        case = next((c for c in ends if f" {c}:" in rec["prefix"] or rec["prefix"].endswith(c)), None)
        if case is None and len(ends) == 1:
            case = next(iter(ends))
        if case is None or rec["estimate_s"] is None:
            continue
        true_left = ends[case] - rec["elapsed_s"]
        if true_left <= 1.0:      # the last second: nothing left to estimate
            continue
        with_est += 1
        errors.append(rec["estimate_s"] / true_left - 1.0)
    err = np.abs(np.array(errors)) if errors else np.array([np.nan])
    return {"study": study, "resolution": "quick", "lines": len(lines), "lines_with_estimate": with_est,
            "median_abs_error": float(np.nanmedian(err)), "max_abs_error": float(np.nanmax(err)),
            "errors": [float(e) for e in errors], "case_wall_s": {k: float(v) for k, v in ends.items()},
            "without_estimate": [r["text"].split(" s", 1)[-1][:90] for r in lines if r["estimate_s"] is None][:5]}


def main(studies=None):
    studies = list(studies or DEFAULT)
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    recs = [measure(s) for s in studies]
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=Path(__file__).parent).stdout.strip()
    record = {"benchmark": "progress_estimate", "date_utc": stamp, "commit": commit, "machine": platform.node(),
              "studies": recs}
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"progress_estimate-{stamp}.json"
    path.write_text(json.dumps(record, indent=1))
    rows = ["# progress estimate of the time left (" + stamp + ", commit " + commit + ")", "",
            "| study | lines | with an estimate | median abs error | largest abs error | case wall time (s) |",
            "|---|---|---|---|---|---|"]
    for r in recs:
        rows.append(f"| {r['study']} quick | {r['lines']} | {r['lines_with_estimate']} | "
                    f"{100 * r['median_abs_error']:.0f} % | {100 * r['max_abs_error']:.0f} % | "
                    f"{', '.join(f'{k} {v:.0f}' for k, v in r['case_wall_s'].items())} |")
    path.with_suffix(".md").write_text("\n".join(rows) + "\n")
    print("\n".join(rows))
    print(f"record: {path}")


if __name__ == "__main__":
    main(sys.argv[1:])
