"""The threads of the OpenBLAS libraries in a process during a run, side by side: a named study
run (``ngtmc run``) once per limit, in fresh processes one after the other, with the steps,
Newton iterations, peak, wall time and time split of each.

    python -m benchmarks.blas_threads three-point-bending -r quick --threads 1
    python -m benchmarks.blas_threads three-point-bending -r quick --threads 2 --variant "numpy: libscipy_openblas=1"

A variant is ``"label: key=value ..."``: a library ``prefix`` of threadpoolctl with its thread
limit (``libscipy_openblas`` for numpy's OpenBLAS, ``libopenblas`` for NGSolve's; an
``internal_api`` such as ``openblas`` as a key limited nothing, measured), an environment
variable in capitals (``NGTMC_BLAS_THREADS=keep``), or ``threads=N`` for the run's NGSolve threads
(default ``--threads``); ``"label:"`` sets no limit on top of what the package does itself
(``NGTMC_BLAS_THREADS``, docs/performance.md). ``--set KEY=VALUE`` is a study setting of every run.
Default variants: the package's default, and ``keep`` (NGTMC_BLAS_THREADS=keep: the libraries'
own thread counts). Record: ``<study>-<resolution>-<UTC time>-blas-threads.json`` / ``.md`` in
``--out`` (default ``benchmarks/results``). Compare times only within one record.
"""
from __future__ import annotations

import argparse
from pathlib import Path
import shlex
import sys
import tempfile

from .run import machine_info
from .study_process import (RESULTS, cell, git_state, git_text, run_study, stamp, summary_of, time_split_of,
                            write_record)
from .study_settings import parse_variant as labelled_settings

DEFAULT_VARIANTS = ["package default:", "keep: NGTMC_BLAS_THREADS=keep"]

LAUNCH = """
import sys
import numpy, ngsolve
limits = {limits!r}
if limits:
    from threadpoolctl import threadpool_limits
    threadpool_limits(limits=limits)
from ngtmc.cli import main
sys.exit(main(sys.argv[1:]))
"""


def parse_variant(text: str) -> tuple[str, dict, dict, int | None]:
    """``"label: key=value ..."`` -> (label, threadpoolctl limits, environment, NGSolve threads or
    None); a key in capitals (``NGTMC_BLAS_THREADS=keep``) is an environment variable, ``threads``
    the run's NGSolve threads."""
    label, sets = labelled_settings(text)
    limits, env, threads = {}, {}, None
    for item in sets:
        key, _, value = item.partition("=")
        if key.isupper():
            env[key] = value
        elif key == "threads":
            threads = int(value)
        else:
            limits[key] = int(value)
    return label, limits, env, threads


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.blas_threads", description=__doc__.split("\n\n")[0])
    ap.add_argument("study")
    ap.add_argument("--resolution", "-r", default="quick")
    ap.add_argument("--threads", type=int, default=1, help="NGSolve threads of each run")
    ap.add_argument("--variant", action="append", help='"label: key=limit ..." (repeatable)')
    ap.add_argument("--set", action="append", default=[], help="study setting key=value of every run")
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args(argv)
    try:
        variants = [parse_variant(v) for v in (args.variant or DEFAULT_VARIANTS)]
    except ValueError as e:
        ap.error(str(e))
    cmd = "python -m benchmarks.blas_threads " + shlex.join(list(sys.argv[1:] if argv is None else argv))
    when = stamp()
    runs, failed = [], False
    with tempfile.TemporaryDirectory() as tmp:
        for label, limits, env, threads in variants:
            folder = Path(tmp) / label.replace(" ", "_")
            threads = args.threads if threads is None else threads
            print(f"[blas] {label}: limits {limits or '-'} env {env or '-'} threads {threads}", flush=True)
            entry = {"label": label, "limits": limits, "env": env, "threads": threads,
                     **run_study(args.study, args.resolution, folder, threads, args.set, env,
                                 launcher=(sys.executable, "-c", LAUNCH.format(limits=limits)))}
            entry.update(summary_of(folder), time_split_s=time_split_of(folder))
            failed |= entry["returncode"] != 0
            runs.append(entry)
            print(f"[blas] {label}: " + ", ".join(f"{k} {entry.get(k)}" for k in
                                                  ("steps", "newton_iterations", "peak_force", "wall_time_s")), flush=True)
    record = {"command": cmd, "study": args.study, "resolution": args.resolution, "threads": args.threads,
              "time": when, "git": git_state(), "machine": machine_info(), "runs": runs}
    first = runs[0].get("wall_time_s")
    lines = [f"### {args.study}, {args.resolution}: OpenBLAS threads side by side ({when})", "", f"`{cmd}`", "",
             f"{git_text(record)}, one run at a time", "",
             "| label | limits | NGSolve threads | steps | Newton | peak | run s | vs first | line search s | solve s | command s | status |",
             "|:---|:---|---:|---:|---:|---:|---:|---:|---:|---:|---:|:---|"]
    for r in runs:
        split = r.get("time_split_s") or {}
        ratio = "-" if not (first and r.get("wall_time_s")) else f"{r['wall_time_s'] / first:.2f}"
        lim = " ".join([f"{k}={v}" for k, v in r["limits"].items()] + [f"{k}={v}" for k, v in r["env"].items()]) or "-"
        lines.append(f"| {r['label']} | {lim} | {r['threads']} | {cell(r.get('steps'), 'd')} | "
                     f"{cell(r.get('newton_iterations'), 'd')} | {cell(r.get('peak_force'), '.4f')} | "
                     f"{cell(r.get('wall_time_s'), '.1f')} | {ratio} | {cell(split.get('line_search'), '.1f')} | "
                     f"{cell(split.get('solve'), '.1f')} | {cell(r.get('command_s'), '.1f')} | "
                     f"{'ok' if r['returncode'] == 0 else 'failed'} |")
    write_record(args.out, f"{args.study.replace('-', '_')}-{args.resolution}-{when}-blas-threads", record, lines)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
