"""Command line of the reports, ``python -m ngtmc.report RUN_DIR [RUN_DIR ...] [-o OUTPUT] [--index]``
(the same renderers as ``ngtmc report``)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Iterable

from ngtmc.report.loading import _find_runs
from ngtmc.report.page import render_report
from ngtmc.report.index import render_index


def report_main(argv: Iterable[str] | None = None) -> int:
    """Command line ``ngtmc report RUN_DIR [RUN_DIR ...] [-o OUTPUT] [--index]``.

    Renders ``report.html`` in each run directory. A directory without metadata.json but with
    run folders below it gets an ``index.html`` (also with ``--index`` on a reports folder, in
    which case the runs below it are rendered first). Returns the exit status (0 on success).
    """
    ap = argparse.ArgumentParser(prog="ngtmc report",
                                 description="Render the HTML report of recorded ngtmc runs "
                                             "(nothing is re-run).")
    ap.add_argument("run_dirs", nargs="+", metavar="RUN_DIR",
                    help="run directory (with metadata.json) or a reports folder")
    ap.add_argument("-o", "--output", help="output file (single RUN_DIR only); "
                                           "default RUN_DIR/report.html")
    ap.add_argument("--index", action="store_true",
                    help="treat RUN_DIR as a reports folder: render every run below it and "
                         "write index.html")
    args = ap.parse_args(list(argv) if argv is not None else None)
    if args.output and len(args.run_dirs) > 1:
        ap.error("--output needs exactly one RUN_DIR")
    status = 0
    for d in args.run_dirs:
        p = Path(d)
        if (p / "metadata.json").is_file() and not args.index:
            out = render_report(p, args.output)
            print(f"report written: {out}")
        elif p.is_dir() and _find_runs(p):
            for run in _find_runs(p):
                try:
                    out = render_report(run)
                    print(f"report written: {out}")
                except Exception as exc:
                    print(f"could not render {run}: {exc}", file=sys.stderr)
                    status = 1
            out = render_index(p)
            print(f"index written: {out}")
        else:
            print(f"{p}: no metadata.json here or below", file=sys.stderr)
            status = 2
    return status
