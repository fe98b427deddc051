"""The threads of the OpenBLAS libraries in a process during a run, side by side: a named study
run (``ngtmc run``) once per limit, in fresh processes one after the other, with the steps,
Newton iterations, peak, wall time and time split of each.

    python -m benchmarks.blas_threads three-point-bending -r quick --threads 1
    python -m benchmarks.blas_threads three-point-bending -r quick --threads 2 --variant "numpy: libscipy_openblas=1"

A variant is ``"label: key=limit ..."`` with keys of threadpoolctl (an ``internal_api`` such as
``openblas``, or a library ``prefix`` such as ``libscipy_openblas`` for numpy's and
``libopenblas`` for NGSolve's), and ``threads=N`` for the run's NGSolve threads (default
``--threads``); ``"label:"`` sets no limit on top of what the package does
itself (``NGTMC_BLAS_THREADS``, docs/performance.md); ``--env KEY=VALUE`` is set for every run.
Default variants: the package's default, and ``keep`` (NGTMC_BLAS_THREADS=keep: the libraries'
own thread counts). Record: ``<study>-<resolution>-<UTC time>-blas-threads.json`` / ``.md`` in
``--out`` (default ``benchmarks/results``). Compare times only within one record.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
from pathlib import Path
import shlex
import subprocess
import sys
import tempfile
import time

from .compare_histories import summary
from .run import machine_info, _git

RESULTS = Path(__file__).resolve().parent / "results"

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


def parse_variant(text: str) -> tuple[str, dict, dict]:
    """``"label: key=value ..."`` -> (label, threadpoolctl limits, environment); a key in capitals
    (``NGTMC_BLAS_THREADS=keep``) is an environment variable."""
    label, _, rest = text.partition(":")
    if not label.strip():
        raise ValueError(f"variant {text!r} has no label")
    limits, env = {}, {}
    for item in rest.split():
        key, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"variant {label!r}: {item!r} is not key=value")
        if key.isupper():
            env[key] = value
        elif key == "threads":
            env["threads"] = value
        else:
            limits[key] = int(value)
    return label.strip(), limits, env


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
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    runs, failed = [], False
    with tempfile.TemporaryDirectory() as tmp:
        for label, limits, env in variants:
            folder = Path(tmp) / label.replace(" ", "_")
            env = dict(env)
            threads = int(env.pop("threads", args.threads))
            run_cmd = [sys.executable, "-c", LAUNCH.format(limits=limits), "run", args.study, "-r", args.resolution,
                       "-o", str(folder), "--threads", str(threads), "--no-vtk", "--no-report", "--quiet"]
            for s in args.set:
                run_cmd += ["--set", s]
            print(f"[blas] {label}: limits {limits or '-'} env {env or '-'}", flush=True)
            t0 = time.perf_counter()
            proc = subprocess.run(run_cmd, capture_output=True, text=True, env={**os.environ, **env})
            entry = {"label": label, "limits": limits, "env": env, "threads": threads, "command_s": time.perf_counter() - t0,
                     "returncode": proc.returncode}
            if (folder / "history.csv").exists():
                s = summary(folder)
                s.pop("run", None)
                entry.update(s)
                meta = json.loads((folder / "metadata.json").read_text())
                res = next(iter(meta.get("results", {}).values()), {})
                entry["time_split_s"] = res.get("time_split_s")
            if proc.returncode != 0:
                failed = True
                entry["stderr_tail"] = proc.stderr[-2000:]
            runs.append(entry)
            print(f"[blas] {label}: " + ", ".join(f"{k} {entry.get(k)}" for k in
                                                  ("steps", "newton_iterations", "peak_force", "wall_time_s")), flush=True)
    record = {"command": cmd, "study": args.study, "resolution": args.resolution, "threads": args.threads,
              "time": stamp, "git": {"revision": _git("rev-parse", "HEAD"), "dirty": bool(_git("status", "--porcelain"))},
              "machine": machine_info(), "runs": runs}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    name = f"{args.study.replace('-', '_')}-{args.resolution}-{stamp}-blas-threads"
    (out / f"{name}.json").write_text(json.dumps(record, indent=1, default=str))
    first = runs[0].get("wall_time_s")
    lines = [f"### {args.study}, {args.resolution}: OpenBLAS threads side by side ({stamp})", "", f"`{cmd}`", "",
             f"git {record['git']['revision']}{' (dirty)' if record['git']['dirty'] else ''}, one run at a time", "",
             "| label | limits | NGSolve threads | steps | Newton | peak | run s | vs first | line search s | solve s | command s | status |",
             "|:---|:---|---:|---:|---:|---:|---:|---:|---:|---:|---:|:---|"]
    for r in runs:
        def f(k, spec):
            v = r.get(k)
            return "-" if v is None else format(v, spec)
        split = r.get("time_split_s") or {}
        ratio = "-" if not (first and r.get("wall_time_s")) else f"{r['wall_time_s'] / first:.2f}"
        lim = " ".join([f"{k}={v}" for k, v in r["limits"].items()] + [f"{k}={v}" for k, v in r["env"].items()]) or "-"
        lines.append(f"| {r['label']} | {lim} | {r['threads']} | {f('steps', 'd')} | {f('newton_iterations', 'd')} | {f('peak_force', '.4f')} | "
                     f"{f('wall_time_s', '.1f')} | {ratio} | {split.get('line_search', float('nan')):.1f} | "
                     f"{split.get('solve', float('nan')):.1f} | {f('command_s', '.1f')} | "
                     f"{'ok' if r['returncode'] == 0 else 'failed'} |")
    (out / f"{name}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines[6:]))
    print(f"written {out / name}.json and .md")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
