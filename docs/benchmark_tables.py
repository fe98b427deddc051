"""The tables of ``docs/benchmarks.md``, generated from the records of ``benchmarks/results`` when
the site is built: the latest record of each run label per study, resolution and case (the study
benchmarks of ``benchmarks/run.py``), and the latest record of every other benchmark. Each row
names its command, commit, date and machine and links its record; nothing is typed by hand."""
from __future__ import annotations

import json
import re
from pathlib import Path

RESULTS = Path(__file__).resolve().parents[1] / "benchmarks" / "results"


def _records() -> list[tuple[Path, dict]]:
    out = []
    for path in sorted(RESULTS.glob("*.json")):
        try:
            rec = json.loads(path.read_text())
        except (OSError, ValueError):
            continue
        if isinstance(rec, dict):
            out.append((path, rec))
    return out


def _commit(rec: dict) -> str:
    machine = rec.get("machine") if isinstance(rec.get("machine"), dict) else {}
    rev = rec.get("commit") or machine.get("git_revision") or rec.get("git_revision") or ""
    dirty = "-dirty" if machine.get("git_dirty") else ""
    return (str(rev)[:10] + dirty) if rev else "-"


def _machine(rec: dict) -> str:
    m = rec.get("machine") if isinstance(rec.get("machine"), dict) else {}
    cpus = m.get("cpu_count")
    return f"{cpus} CPUs" if cpus else "-"


def _date(rec: dict, path: Path) -> str:
    """YYYY-MM-DD of the record (its date field, else the time stamp in its file name)."""
    for text in (str(rec.get("date_utc") or rec.get("date") or ""), path.stem):
        m = re.search(r"(20\d\d)-?(\d\d)-?(\d\d)", text)
        if m:
            return "-".join(m.groups())
    return "-"


def _link(path: Path) -> str:
    md = path.with_suffix(".md")
    return f"[record](../benchmarks/results/{md.name})" if md.is_file() else f"`benchmarks/results/{path.name}`"


def _num(x, fmt="{:.4g}") -> str:
    return "-" if x is None else fmt.format(x)


def study_tables() -> str:
    """One table per study, resolution and case: the latest record of each run label."""
    latest: dict[tuple, dict] = {}
    for path, rec in _records():
        runs = rec.get("runs")
        if not isinstance(runs, list) or "study" not in rec:
            continue
        key0 = (rec["study"], rec.get("resolution", ""), rec.get("case", ""))
        for run in runs:
            key = key0 + (run.get("label", ""),)
            if key not in latest or (rec.get("date_utc") or "") >= (latest[key]["rec"].get("date_utc") or ""):
                latest[key] = {"rec": rec, "run": run, "path": path}
    groups: dict[tuple, list] = {}
    for key, item in latest.items():
        groups.setdefault(key[:3], []).append(item)
    out = []
    for (study, res, case), items in sorted(groups.items()):
        out.append(f"### {study}, {res}, case {case}\n")
        out.append("| run | date | commit | machine, threads | steps | Newton | cut-backs | wall [s] | peak [N, per mm of thickness in 2D] | at [mm] | status | record |")
        out.append("|:---|:---|:---|:---|---:|---:|---:|---:|---:|---:|:---|:---|")
        for it in sorted(items, key=lambda i: (i["rec"].get("date_utc") or ""), reverse=True):
            rec, run, path = it["rec"], it["run"], it["path"]
            out.append(f"| {run.get('label', '') or '-'} | {_date(rec, path)} | {_commit(rec)} | "
                       f"{_machine(rec)}, {rec.get('threads', '-')} | {run.get('steps', '-')} | "
                       f"{run.get('newton_iterations', '-')} | {run.get('cutbacks', '-')} | "
                       f"{_num(run.get('wall_time_s'), '{:.1f}')} | {_num(run.get('peak_force_N'), '{:.5g}')} | "
                       f"{_num(run.get('peak_load_mm'), '{:.5g}')} | {run.get('status', '-')} | {_link(path)} |")
        out.append("")
    return "\n".join(out)


def other_table() -> str:
    """The latest record of every benchmark that is not a study run."""
    latest: dict[str, tuple[Path, dict]] = {}
    for path, rec in _records():
        if isinstance(rec.get("runs"), list) and "study" in rec:
            continue
        name = rec.get("benchmark") or re.sub(r"-\d{8}T\d{6}Z.*$", "", path.stem)   # the stem before its time stamp
        if name not in latest or path.name >= latest[name][0].name:
            latest[name] = (path, rec)
    out = ["| benchmark | date | commit | machine | command | record |", "|:---|:---|:---|:---|:---|:---|"]
    for name, (path, rec) in sorted(latest.items()):
        cmd = rec.get("command") or f"python -m benchmarks.{name.split('-')[0]}"
        out.append(f"| {name} | {_date(rec, path)} | {_commit(rec)} | {_machine(rec)} | `{cmd}` | {_link(path)} |")
    return "\n".join(out) + "\n"


def block() -> str:
    return ("## Study runs\n\n" + study_tables() + "\n## Other benchmarks\n\n" + other_table())
