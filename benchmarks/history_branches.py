"""How many history points change branch between the coupled Newton's residual evaluations: is a
long solve one whose iterate cycles at the kink of H_n = max(H_{n-1}, Psi_plus) (Eq. 7)?

Runs a study as a user runs it (``ngtmc run``, a fresh process) with ``NGTMC_DEBUG_COUPLED=1``,
whose per-evaluation line of :class:`ngtmc.coupled.iteration.Iteration` gives the number of
history points where Psi_plus wins (``branch``) and how many changed branch since the evaluation
before (``changed``; -1 at a solve's first). Counts the evaluations of the solves of at least
``--min-evaluations`` (default 10) by how many points changed:

    python -m benchmarks.history_branches STUDY [-r quick] [--set KEY=VALUE ...] [--threads 1]

Writes ``history-branches-<study>-<resolution>-<UTC time>.json`` / ``.md`` to ``--out`` (default
``benchmarks/results``). A few points that change at every evaluation of a long solve is the
kink's cycle; none, or many, is something else.
"""
from __future__ import annotations

import argparse
import re
import tempfile
from pathlib import Path

from .study_process import RESULTS, git_state, git_text, run_study, stamp, summary_of, write_record

__all__ = ["solves", "bins", "BINS", "main"]

_LINE = re.compile(r"coupled it (\d+) .*? branch (\d+) changed (-?\d+)")

#: (label, lowest, highest) of the changed-point counts
BINS = (("none", 0, 0), ("1 to 3", 1, 3), ("4 to 9", 4, 9), ("10 or more", 10, None))


def solves(text: str) -> list[list[int]]:
    """The changed-point counts of each coupled solve in the debug output ``text``, one list per
    solve in order (a solve starts at ``coupled it 1``; its first count is -1)."""
    out: list[list[int]] = []
    for m in _LINE.finditer(text):
        if int(m.group(1)) == 1 or not out:
            out.append([])
        out[-1].append(int(m.group(3)))
    return out


def bins(counts: list[list[int]], min_evaluations: int = 10) -> dict:
    """Of the solves with at least ``min_evaluations`` evaluations: how many, their evaluations,
    those evaluations by changed-point count (:data:`BINS`, the solves' first evaluations apart)
    and the largest count."""
    long = [c for c in counts if len(c) >= min_evaluations]
    later = [k for c in long for k in c[1:]]
    table = {label: sum(1 for k in later if k >= lo and (hi is None or k <= hi)) for label, lo, hi in BINS}
    return {"solves": len(counts), "evaluations": sum(len(c) for c in counts), "long_solves": len(long),
            "long_evaluations": sum(len(c) for c in long), "by_changed_points": table,
            "largest_change": max(later, default=0)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.history_branches", description=__doc__.splitlines()[0])
    ap.add_argument("study")
    ap.add_argument("-r", "--resolution", default="quick")
    ap.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--min-evaluations", type=int, default=10)
    ap.add_argument("--out", default=str(RESULTS))
    a = ap.parse_args(argv)
    when = stamp()
    with tempfile.TemporaryDirectory(prefix="history-branches-") as tmp:
        folder = Path(tmp) / "run"
        run = run_study(a.study, a.resolution, folder, a.threads, a.sets, env={"NGTMC_DEBUG_COUPLED": "1"}, stdout=True)
        summary = summary_of(folder)
    counts = bins(solves(run.pop("stdout")), a.min_evaluations)
    name = Path(a.study).stem
    command = " ".join(["python -m benchmarks.history_branches", a.study, "-r", a.resolution,
                        *[f"--set {s}" for s in a.sets], f"--threads {a.threads}"])
    record = {"command": command, "git": git_state(), "study": a.study, "resolution": a.resolution, "run": run,
              "summary": summary, "min_evaluations": a.min_evaluations, **counts}
    lines = [f"### History branches: {name}, {a.resolution} ({when})", "", f"`{command}`", "", git_text(record), "",
             f"Run: {summary.get('steps', '-')} steps, {summary.get('newton_iterations', '-')} Newton iterations, "
             f"exit status {run['returncode']}. {counts['solves']} coupled solves, {counts['evaluations']} residual "
             f"evaluations; {counts['long_solves']} solves of {a.min_evaluations} or more evaluations, "
             f"{counts['long_evaluations']} evaluations:", "",
             "| history points that changed branch since the evaluation before | evaluations |", "|:---|---:|",
             f"| (first of a solve) | {counts['long_solves']} |",
             *[f"| {label} | {n} |" for label, n in counts["by_changed_points"].items()], "",
             f"The largest change: {counts['largest_change']} points."]
    write_record(a.out, f"history-branches-{name}-{a.resolution}-{when}", record, lines)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
