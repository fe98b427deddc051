"""Command line: ``ngtmc run NAME``, ``ngtmc list``, ``ngtmc show NAME``, ``ngtmc report RUN_DIR``.

    ngtmc --version
    ngtmc list
    ngtmc show three-point-bending
    ngtmc run three-point-bending --resolution medium --set k_u=50 --set du_max=1e-3
    ngtmc run three-point-bending --output reports/tpb --resume
    ngtmc run step-control --workers 2
    ngtmc run path/to/my_study.py --resolution quick
    ngtmc report reports/three_point_bending-quick
    ngtmc report --index runs

Exit status: 0 on success, 1 when a run failed (its history and metadata are written with status
"failed"), 2 for usage errors (unknown study, resolution or override), 130 when interrupted.
"""
from __future__ import annotations

import argparse
import sys

__all__ = ["main", "build_parser", "parse_overrides", "show_study", "run_script"]


def parse_overrides(items) -> dict:
    """``["k_u=50", "du_max=1e-3"]`` -> ``{"k_u": "50", "du_max": "1e-3"}`` (values converted later
    to the type of each default)."""
    out = {}
    for item in items or []:
        if "=" not in item:
            raise ValueError(f"--set expects key=value, got {item!r}")
        k, v = item.split("=", 1)
        k = k.strip()
        if not k:
            raise ValueError(f"--set expects key=value, got {item!r}")
        out[k] = v.strip()
    return out


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="ngtmc", description="Third-medium contact and phase-field fracture: "
                                 "run the paper's validation studies and render their reports.")
    from ngtmc.version import __version__
    ap.add_argument("--version", action="version", version=f"ngtmc {__version__}")
    sub = ap.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", help="run a named study, or a study file of your own, into a run folder")
    r.add_argument("name", help="study name (dashes or underscores; see `ngtmc list`), or the path of a study "
                               "file (.py, the interface of docs/study-interface.md)")
    r.add_argument("--resolution", "-r", default=None, help="quick (default), medium, paper, ...")
    r.add_argument("--output", "-o", default=None, help="run folder (default reports/<study>-<resolution>)")
    r.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a parameter (repeatable), e.g. --set k_u=50 --set gamma0=1e-5")
    r.add_argument("--resume", action="store_true", help="continue an interrupted or failed run from its checkpoint")
    r.add_argument("--no-report", action="store_true", help="do not render report.html")
    r.add_argument("--no-vtk", action="store_true", help="do not write the ParaView series")
    r.add_argument("--threads", type=int, default=None,
                   help="NGSolve threads (default: per case, 1, or 2 for meshes of 20000 elements or more, 10000 in 3D; per worker with --workers or --scheduler, default 1)")
    r.add_argument("--workers", type=int, default=None, metavar="N",
                   help="run the cases in parallel on a local Dask cluster of N worker processes "
                        "(needs pip install ngtmc[parallel]; docs/parallel.md)")
    r.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="send the cases to the Dask scheduler at ADDRESS (e.g. tcp://host:8786) instead")
    r.add_argument("--mpi", action="store_true",
                   help="each case on one mesh distributed over the MPI ranks: mpiexec -n 3 python -m mpi4py "
                        "-m ngtmc run NAME --mpi (needs pip install ngtmc[mpi]; rank 0 writes the run folder "
                        "with the fields gathered, each rank its checkpoints; docs/parallel.md)")
    r.add_argument("--quiet", "-q", action="store_true", help="no progress lines")

    sub.add_parser("list", help="list the studies with their resolutions")

    sh = sub.add_parser("show", help="a study's parameters (defaults, units) and resolutions")
    sh.add_argument("name", help="study name (dashes or underscores; see `ngtmc list`)")

    rep = sub.add_parser("report", help="render report.html of a run folder, or an index of run folders")
    rep.add_argument("run_dir", nargs="?", help="run folder")
    rep.add_argument("--index", metavar="DIR", default=None, help="render an index page of the runs in DIR")
    return ap


def _cmd_list() -> int:
    from ngtmc.study import list_studies, load_study
    for name in list_studies():
        try:
            mod = load_study(name)
            res = ", ".join(mod.RESOLUTIONS)
        except Exception as e:  # a broken study must not hide the others
            print(f"{name.replace('_', '-'):24s} (cannot be loaded: {type(e).__name__}: {e})")
            continue
        print(f"{name.replace('_', '-'):24s} {getattr(mod, 'TITLE', '')}  [resolutions: {res}; "
              f"default {getattr(mod, 'DEFAULT_RESOLUTION', 'quick')}]")
    return 0


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, (list, tuple)):
        return ",".join(_fmt(x) for x in v)
    return str(v)


def show_study(name: str) -> str:
    """Text describing a study: title, summary, every parameter with its default and unit (mm, N,
    MPa, ...) and description, and the mesh and step sizes of each resolution."""
    import textwrap
    from ngtmc.study import guess_unit
    from ngtmc.study import load_study
    mod = load_study(name)
    lines = [f"{mod.NAME.replace('_', '-')}: {getattr(mod, 'TITLE', '')}"]
    summary = " ".join(str(getattr(mod, "SUMMARY", "")).split())
    if summary:
        lines += textwrap.wrap(summary, 100, initial_indent="  ", subsequent_indent="  ")
    rows = [(k, _fmt(v[0]), v[1], v[2]) for k, v in mod.PARAMETERS.items()]
    w = [max([len(r[i]) for r in rows] + [len(h)]) for i, h in enumerate(("parameter", "default", "unit"))]
    lines += ["", "Parameters (change with --set KEY=VALUE):",
              f"  {'parameter':{w[0]}}  {'default':{w[1]}}  {'unit':{w[2]}}  description"]
    lines += [f"  {k:{w[0]}}  {v:{w[1]}}  {u:{w[2]}}  {d}" for k, v, u, d in rows]
    res = mod.RESOLUTIONS
    keys = list(dict.fromkeys(k for r in res.values() for k in r))
    info = getattr(mod, "RESOLUTION_PARAMETERS", {})
    cols = list(res)
    table = [(k, info.get(k, (guess_unit(k), ""))[0], [_fmt(res[r].get(k, "-")) for r in cols],
              info.get(k, ("", ""))[1]) for k in keys]
    wk = max([len(t[0]) for t in table] + [3])
    wu = max([len(t[1]) for t in table] + [4])
    wc = [max([len(t[2][i]) for t in table] + [len(c)]) for i, c in enumerate(cols)]
    default = getattr(mod, "DEFAULT_RESOLUTION", "quick")
    lines += ["", f"Resolutions (mesh and step sizes; --resolution NAME, default {default}):",
              f"  {'key':{wk}}  {'unit':{wu}}  " + "  ".join(f"{c:{wc[i]}}" for i, c in enumerate(cols))
              + "  description"]
    for k, u, vals, d in table:
        lines.append(f"  {k:{wk}}  {u:{wu}}  " + "  ".join(f"{v:{wc[i]}}" for i, v in enumerate(vals)) + f"  {d}")
    return "\n".join(lines)


def _cmd_show(args) -> int:
    from ngtmc.study import StudyError
    try:
        print(show_study(args.name))
    except StudyError as e:
        print(f"ngtmc: error: {e}", file=sys.stderr)
        return 2
    return 0


def _cmd_run(args) -> int:
    from ngtmc.runner import run_study
    from ngtmc.study import StudyError
    try:
        overrides = parse_overrides(args.overrides)
    except ValueError as e:
        print(f"ngtmc: error: {e}", file=sys.stderr)
        return 2
    rank, comm = 0, None
    if args.mpi:
        try:
            from mpi4py import MPI
            comm = MPI.COMM_WORLD
            rank = comm.rank
        except ImportError:
            pass  # run_study says what is missing

    def say(*a, **k):
        """Print on rank 0 only; on MPI ranks every rank then waits (at most MPI_SETTLE_S) for the
        others, so that a rank's exit, which makes mpi4py abort the job, cannot cut rank 0's
        message off (seen: the refusal of a case printed nothing, rank 2 had aborted first)."""
        if rank == 0:
            print(*a, **k)
            sys.stdout.flush()
            sys.stderr.flush()
        if comm is not None and comm.size > 1:
            _settle(comm)
    try:
        out = run_study(args.name, resolution=args.resolution, output=args.output, overrides=overrides,
                        report=False if args.no_report else None, resume=args.resume,
                        progress=not args.quiet, threads="auto" if args.threads is None else args.threads,
                        vtk=not args.no_vtk, workers=args.workers, scheduler=args.scheduler, mpi=args.mpi)
    except StudyError as e:
        say(f"ngtmc: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        say("ngtmc: interrupted; resume with --resume", file=sys.stderr)
        return 130
    except Exception as e:
        say(f"ngtmc: run failed: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    report = out / "report.html"
    say(f"report: {report.resolve()}" if report.exists() else out)
    return 0


#: Longest wait of an MPI rank for the others before it exits (s): ranks that all exit pass at
#: once; one whose fellows still compute (a failure on one rank only) does not hang.
MPI_SETTLE_S = 10.0


def _settle(comm):
    """Wait until every rank of ``comm`` arrived here, or MPI_SETTLE_S passed."""
    import time
    req = comm.Ibarrier()
    t0 = time.monotonic()
    while not req.Test():
        if time.monotonic() - t0 > MPI_SETTLE_S:
            return
        time.sleep(0.01)


def _cmd_report(args) -> int:
    if not args.run_dir and not args.index:
        print("ngtmc report: give a run folder, or --index DIR", file=sys.stderr)
        return 2
    try:
        from ngtmc import report as _report
    except ImportError as e:
        print(f"ngtmc report: the report module ngtmc.report is not available ({e})", file=sys.stderr)
        return 1
    fn_name = "render_index" if args.index else "render_report"
    fn = getattr(_report, fn_name, None)
    if fn is None:
        print(f"ngtmc report: ngtmc.report has no {fn_name}() (the report module is incomplete)", file=sys.stderr)
        return 1
    target = args.index if args.index else args.run_dir
    try:
        path = fn(target)
    except Exception as e:
        print(f"ngtmc report: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    if path is not None:
        print(path)
    return 0


def run_script(name: str, argv=None) -> int:
    """A study file run as a script: ``python studies/NAME.py [options]`` is ``ngtmc run NAME
    [options]`` (the options of ``ngtmc run``; ``argv`` defaults to ``sys.argv[1:]``)."""
    return main(["run", name, *(sys.argv[1:] if argv is None else argv)])


def main(argv=None) -> int:
    try:
        return _main(argv)
    except BrokenPipeError:  # output piped into a program that stopped reading (``ngtmc list | head``)
        import os
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


def _main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    if args.command == "list":
        return _cmd_list()
    if args.command == "show":
        return _cmd_show(args)
    if args.command == "run":
        return _cmd_run(args)
    if args.command == "report":
        return _cmd_report(args)
    return 2  # pragma: no cover


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
