"""Speed against error of Simulation options on one case of a named study, in one command.

    python -m benchmarks.run --study three_point_bending --resolution quick --scheme single-pass monolithic --reference
    python -m benchmarks.tpb --resolution paper --scheme monolithic          # tpb = three_point_bending
    python -m benchmarks.tpb --variant "fast: compile='real'" --variant "plain: compile=False" --stop-load 0.08

Every variant runs the same case (a freshly built scene and a fresh copy of its step control) with
``ngtmc.Simulation(scene, schedule, control, **case.options | variant_options)``. ``--reference``
adds a run of the same mesh with ``du_max`` divided by ``--reference-factor`` and the scheme
``--reference-scheme`` ("none": keep the case's); the variants' peak force, its load and the force
curve are compared with it. Writes ``<out>/<study>-<resolution>-<UTC time>.json`` (one record),
``.md`` (the table) and ``-<label>.csv`` (each run's history); prints the table. See
docs/performance.md for the columns. Exit status: 0 all runs completed, 1 a run failed, 2 usage
error, 130 interrupted by Ctrl-C or SIGTERM (the outputs are written first).
"""
from __future__ import annotations

import argparse
import copy
import datetime as _dt
import json
import os
import platform
import re
import shlex
import signal
import subprocess
import sys
from pathlib import Path

from . import harness as H

ROOT = Path(__file__).resolve().parents[1]


def build_parser(study: str | None = None, prog: str = "python -m benchmarks.run") -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog=prog, description=__doc__.splitlines()[0])
    if study is None:
        ap.add_argument("--study", default="three_point_bending", help="study name (default three_point_bending)")
    ap.add_argument("--case", default=None, help="case name (default: the study's first case)")
    ap.add_argument("--resolution", "-r", default=None, help="quick, medium or paper (default: the study's)")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                    help="study parameter override (repeatable), as `ngtmc run --set`")
    ap.add_argument("--option", dest="options", action="append", default=[], metavar="KEY=VALUE",
                    help="Simulation keyword for every run (repeatable; Python literal, else string; "
                         "newton.NAME=value sets a NewtonOptions field)")
    ap.add_argument("--scheme", nargs="+", action="extend", default=[], metavar="SCHEME",
                    help="one variant per scheme (option scheme=SCHEME, label SCHEME)")
    ap.add_argument("--variant", dest="variants", action="append", default=[], metavar='"LABEL: k=v k=v"',
                    help="a named set of Simulation options (repeatable)")
    ap.add_argument("--reference", action="store_true", help="also run the reference (same mesh, tiny steps)")
    ap.add_argument("--reference-factor", type=float, default=10.0, help="du_max divisor of the reference (10)")
    ap.add_argument("--reference-scheme", default="staggered",
                    help="scheme of the reference (default staggered; 'none' keeps the case's options)")
    ap.add_argument("--reference-from", default=None, metavar="PATH",
                    help="reuse the reference run of an earlier JSON record (PATH or PATH#LABEL)")
    ap.add_argument("--stop-load", type=float, default=None, metavar="MM", help="final load of the case, mm")
    ap.add_argument("--threads", type=int, default=1, help="NGSolve threads (default 1)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"), help="output folder (benchmarks/results)")
    ap.add_argument("--progress-interval", type=float, default=10.0, help="seconds between progress lines (10)")
    return ap


def parse_variants(schemes, variants) -> list[tuple[str, dict]]:
    """``--scheme A B`` and ``--variant "label: k=v k=v"`` -> [(label, options)], in that order;
    one ``("default", {})`` when both are empty. The text after the first colon is split before
    each ``key=`` (so values may hold spaces, e.g. ``coupled={'alpha_tol': 1e-4}``); values are
    Python literals, else strings. Raises ValueError on a malformed or repeated label."""
    out = [(str(s), {"scheme": str(s)}) for s in schemes]
    for text in variants:
        label, sep, rest = str(text).partition(":")
        if not sep or not label.strip():
            raise ValueError(f"--variant expects 'LABEL: key=value ...', got {text!r}")
        items = [x for x in re.split(r"\s+(?=[A-Za-z_][\w.]*\s*=)", rest.strip()) if x]
        out.append((label.strip(), H.parse_assignments(items)))
    if not out:
        out = [("default", {})]
    labels = [label for label, _ in out]
    dup = sorted({x for x in labels if labels.count(x) > 1})
    if dup:
        raise ValueError(f"repeated variant label(s): {', '.join(dup)}")
    return out


def apply_stop_load(schedule, stop):
    """The schedule cut at the first point where the load reaches ``stop`` (mm); if it never does,
    its last point is replaced by ``stop``. None leaves the schedule as it is."""
    import ngtmc
    if stop is None:
        return schedule
    pts = [float(x) for x in (schedule.points if isinstance(schedule, ngtmc.Schedule) else [0.0, float(schedule)])]
    for i in range(len(pts) - 1):
        a, b = pts[i], pts[i + 1]
        if min(a, b) <= stop <= max(a, b) and stop != a:
            return ngtmc.Schedule(pts[: i + 1] + [stop])
    return ngtmc.Schedule(pts[:-1] + [stop])


def _git(*args):
    try:
        r = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, timeout=10)
        return r.stdout.strip() if r.returncode == 0 else None
    except Exception:
        return None


def machine_info() -> dict:
    """Platform, CPU count, load average, Python/NGSolve/numpy/pandas versions, git revision."""
    import ngsolve
    import numpy
    import pandas
    info = {"platform": platform.platform(), "machine": platform.machine(), "processor": platform.processor(),
            "cpu_count": os.cpu_count(), "python": platform.python_version(), "ngsolve": ngsolve.__version__,
            "numpy": numpy.__version__, "pandas": pandas.__version__, "git_revision": _git("rev-parse", "HEAD")}
    dirty = _git("status", "--porcelain", "--untracked-files=no")
    info["git_dirty"] = None if dirty is None else bool(dirty)
    if hasattr(os, "getloadavg"):
        info["load_average_at_start"] = list(os.getloadavg())
    return info


def load_reference(spec: str) -> tuple[dict, dict]:
    """``PATH`` or ``PATH#LABEL`` of an earlier record -> (its reference run, the whole record)."""
    path, _, label = spec.partition("#")
    rec = json.loads(Path(path).read_text())
    runs = rec.get("runs", [])
    hits = [r for r in runs if (r.get("label") == label if label else r.get("is_reference"))]
    if len(hits) != 1:
        raise ValueError(f"{path}: {'no run labelled ' + repr(label) if label else 'no (or several) reference runs'}; "
                         f"runs: {', '.join(r.get('label', '?') for r in runs)}")
    ref = copy.deepcopy(hits[0])
    ref.update(is_reference=True, from_record=str(path), errors=None)
    return ref, rec


def _write(out: Path, name: str, record: dict, histories: dict, cmd: str):
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{name}.json").write_text(json.dumps(H.jsonable(record), indent=1) + "\n")
    for label, hist in histories.items():
        hist.to_csv(out / f"{name}-{re.sub(r'[^A-Za-z0-9_.-]+', '_', label)}.csv", index=False)
    ov = " ".join(f"{k}={v}" for k, v in record["overrides"].items()) or "none"
    m = record["machine"]
    lines = [f"### {record['study']}, {record['resolution']}, case {record['case']} ({record['date_utc']})", "",
             f"`{cmd}`", "",
             f"git {m.get('git_revision') or '?'}{' (dirty)' if m.get('git_dirty') else ''}, {record['threads']} "
             f"thread(s), {m.get('cpu_count')} CPUs, {m.get('platform')}; overrides: {ov}; final load "
             f"{record['schedule_mm'][-1]:g} mm; reference: {record['reference']['description']}", "",
             H.format_table(record["runs"], markdown=True), ""]
    bad = [r for r in record["runs"] if r.get("status") != "completed"]
    lines += [f"- {r['label']}: {r.get('status')}" for r in bad] + ([""] if bad else [])
    (out / f"{name}.md").write_text("\n".join(lines))


def main(argv=None, study: str | None = None, prog: str = "benchmarks.run") -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    args = build_parser(study, f"python -m {prog}").parse_args(argv)
    study = study or args.study
    cmd = "python -m " + prog + (" " + shlex.join(argv) if argv else "")
    import inspect

    import ngsolve as ngs
    import ngtmc
    from ngtmc.cli import parse_overrides
    from ngtmc.study import load_study
    from ngtmc.study import StudyError
    from ngtmc.study import study_parameters

    def usage(msg):
        print(f"{prog}: error: {msg}", file=sys.stderr)
        return 2
    try:
        mod = load_study(study)
        overrides = parse_overrides(args.overrides)
        res, p = study_parameters(mod, args.resolution, overrides)
        base = H.parse_assignments(args.options)
        variants = parse_variants(args.scheme, args.variants)
        names = [c.name for c in mod.cases(copy.deepcopy(p))]
        case_name = args.case or names[0]
        if case_name not in names:
            raise ValueError(f"unknown case {case_name!r}; cases: {', '.join(names)}")
        if args.reference and args.reference_from:
            raise ValueError("--reference and --reference-from exclude each other")
        if not args.reference_factor > 0:
            raise ValueError("--reference-factor must be > 0")
    except (StudyError, ValueError) as e:
        return usage(e)

    def fresh_case():
        case = next(c for c in mod.cases(copy.deepcopy(p)) if c.name == case_name)
        if case.run is not None:
            raise ValueError(f"case {case_name!r} is not an ngtmc simulation (it has its own run())")
        return case

    ref_opts = dict(base) if args.reference_scheme.lower() == "none" else {**base, "scheme": args.reference_scheme}
    runs = [(label, {**base, **v}, 1.0, False) for label, v in variants]
    if args.reference:
        if "reference" in [r[0] for r in runs]:
            return usage("the label 'reference' is taken by the reference run")
        runs.append(("reference", ref_opts, float(args.reference_factor), True))
    try:
        case0 = fresh_case()
        schedule = apply_stop_load(case0.schedule, args.stop_load)
        sig = inspect.signature(ngtmc.Simulation).parameters
        if not any(q.kind is q.VAR_KEYWORD for q in sig.values()):
            for label, opts, _, _ in runs:
                bad = sorted(set(H.merge_options(case0.options, opts)) - set(sig))
                if bad:
                    raise ValueError(f"run {label!r}: ngtmc.Simulation does not accept {', '.join(bad)} "
                                     f"(accepted: {', '.join(k for k in sig if k not in ('scene', 'schedule', 'control'))})")
    except (StudyError, ValueError, TypeError) as e:
        return usage(e)

    stamp = _dt.datetime.now(_dt.timezone.utc)
    out = Path(args.out)
    base_name, k = f"{mod.NAME}-{res}-{stamp.strftime('%Y%m%dT%H%M%SZ')}", 1
    name = base_name
    out.mkdir(parents=True, exist_ok=True)
    while True:  # reserve the record's name now: two runs started in the same second must not share it
        try:
            with open(out / f"{name}.json", "x") as f:
                f.write('{"status": "running"}\n')
            break
        except FileExistsError:
            name, k = f"{base_name}-{k}", k + 1
    if args.reference_from:
        try:
            ref_run, ref_rec = load_reference(args.reference_from)
        except (OSError, ValueError) as e:
            return usage(e)
        desc = f"{ref_run['label']} of {args.reference_from}"
        for key, mine in (("study", mod.NAME), ("resolution", res), ("case", case_name), ("parameters", p),
                          ("schedule_mm", [float(x) for x in schedule.points])):
            if H.jsonable(ref_rec.get(key)) != H.jsonable(mine):
                print(f"{prog}: warning: the reference record has another {key}", file=sys.stderr)
    elif args.reference:
        ref_run = None
        desc = (f"du_max / {args.reference_factor:g}, scheme "
                f"{ref_opts.get('scheme', 'of the case') if args.reference_scheme.lower() != 'none' else 'of the case'}")
    else:
        ref_run, desc = None, "none"
    record = {"command": cmd, "date_utc": stamp.isoformat(timespec="seconds"), "machine": machine_info(),
              "threads": args.threads, "study": mod.NAME, "resolution": res, "case": case_name,
              "parameters": p, "overrides": overrides, "stop_load_mm": args.stop_load,
              "schedule_mm": [float(x) for x in schedule.points], "base_options": base,
              "reference": {"description": desc, "factor": args.reference_factor if args.reference else None,
                            "scheme": args.reference_scheme if args.reference else None,
                            "from": args.reference_from},
              "runs": [ref_run] if ref_run else []}
    histories = {}
    ref_curve = (ref_run["curve"]["load_mm"], ref_run["curve"]["force_N"]) if ref_run else None

    def _terminate(signum, frame):  # kill -TERM ends the run as Ctrl-C does: the record is written
        raise KeyboardInterrupt
    signal.signal(signal.SIGTERM, _terminate)
    ngs.SetNumThreads(int(args.threads))
    interrupted = False
    with ngs.TaskManager():
        for label, opts, factor, is_ref in runs:
            case = fresh_case()
            rec, hist = H.run_variant(label, case.build_scene, copy.deepcopy(schedule), copy.deepcopy(case.control),
                                      H.merge_options(case.options, opts), du_max_factor=factor,
                                      progress_interval=args.progress_interval)
            rec["variant_options"] = opts
            rec["is_reference"] = is_ref
            rec["errors"] = None
            ref_rec = next((r for r in record["runs"] if r.get("is_reference")), None)
            if ref_rec and not is_ref and (ref_rec.get("ndof"), ref_rec.get("elements")) != (rec["ndof"], rec["elements"]):
                rec["reference_mesh_differs"] = True
                print(f"{prog}: warning: {label} has {rec['elements']} elements and dofs {rec['ndof']}, the reference "
                      f"{ref_rec.get('elements')} and {ref_rec.get('ndof')}", file=sys.stderr)
            rec["csv"] = f"{name}-{re.sub(r'[^A-Za-z0-9_.-]+', '_', label)}.csv"
            record["runs"].append(rec)
            histories[label] = hist
            if rec["is_reference"]:
                ref_curve = (hist["load"].to_numpy(), hist["force"].to_numpy())
            for r in record["runs"]:
                if not r.get("is_reference"):
                    r["errors"] = H.compare(*_curve(r, histories), *ref_curve) if ref_curve else None
            if hasattr(os, "getloadavg"):
                record["machine"]["load_average_at_end"] = list(os.getloadavg())
            _write(out, name, record, {label: hist}, cmd)
            if rec["status"] == "interrupted":
                interrupted = True
                break
    print(H.format_table(record["runs"]))
    print(f"written {out / name}.json, .md and -<label>.csv", file=sys.stderr)
    if interrupted:
        return 130
    return 0 if all(r.get("status") == "completed" for r in record["runs"]) else 1


def _curve(rec, histories):
    """Full history of a run of this invocation, else its stored (downsampled) curve."""
    h = histories.get(rec["label"])
    if h is not None:
        return h["load"].to_numpy(), h["force"].to_numpy()
    return rec["curve"]["load_mm"], rec["curve"]["force_N"]


if __name__ == "__main__":
    sys.exit(main())
