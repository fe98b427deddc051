"""The index page of a folder of runs (``index.html``): every run with its overrides, and runs
of the same physics compared by wall time against error in peak force."""
from __future__ import annotations

import datetime as _dt
from pathlib import Path

from ngtmc.report.loading import _case_list, _find_runs, _load
from ngtmc.report.numbers import (
    _finite, _published_peak, case_numbers, fmt, fmt_date, fmt_duration, fmt_u, overrides_text,
    physics_key, speed_error_rows)
from ngtmc.report.figures import _fig_speed_error
from ngtmc.report.page import _clean, _env, _plotly_js, _script_json


def render_index(reports_dir) -> Path:
    """Write ``reports_dir/index.html`` linking every run folder holding a metadata.json.

    Runs are grouped by study, each with its overrides; runs of the same physics (equal
    :func:`physics_key`: the same physical parameters, differing only in mesh and step sizes) are
    compared by wall time (s) against the relative error in peak force (%), relative to the finest
    run of that group (the one with most mesh elements) and to the published value (the
    ``peak_force`` target). Runs with other physics are never compared with each other.
    Returns the path of the written page.
    """
    reports_dir = Path(reports_dir)
    reports_dir.mkdir(parents=True, exist_ok=True)
    groups: dict[str, list[dict]] = {}
    for run in _find_runs(reports_dir):
        try:
            meta, history, _ = _load(run, with_snapshots=False)
        except Exception as exc:  # unreadable metadata: list it, do not fail the index
            groups.setdefault("(unreadable)", []).append({
                "name": str(run.relative_to(reports_dir)), "error": str(exc), "link": None,
                "meta_link": (run.relative_to(reports_dir) / "metadata.json").as_posix()})
            continue
        cases = _case_list(meta)
        first = cases[0]["name"] if cases else "main"
        nums = case_numbers(meta, history, first)
        fu = meta.get("force_unit") or "N"
        mesh = meta.get("mesh") or {}
        rel = run.relative_to(reports_dir)
        link = (rel / "report.html").as_posix() if (run / "report.html").is_file() else None
        wall = meta.get("wall_time_s")
        if not _finite(wall):
            wall = nums.get("wall_time_s")
        groups.setdefault(str(meta.get("study", "?")), []).append({
            "name": rel.as_posix(), "title": meta.get("title") or meta.get("study"),
            "resolution": meta.get("resolution") or "–", "created": fmt_date(meta.get("created")),
            "created_raw": str(meta.get("created") or ""),
            "status": meta.get("status") or "unknown", "link": link,
            "meta_link": (rel / "metadata.json").as_posix(),
            "n_elements": mesh.get("n_elements"), "elements": fmt(mesh.get("n_elements")),
            "dofs": fmt((mesh.get("ndof_u") or 0) + (mesh.get("ndof_alpha") or 0))
            if ("ndof_u" in mesh or "ndof_alpha" in mesh) else "–",
            "wall_time_s": wall, "wall": fmt_duration(wall),
            "peak_force": nums.get("peak_force"), "peak": fmt_u(nums.get("peak_force"), fu),
            "peak_load": fmt_u(nums.get("peak_load"), "mm"), "case_label": cases[0]["label"] if cases else first,
            "published": _published_peak(meta, first, fu), "force_unit": fu,
            "n_cases": len(cases), "steps": nums.get("steps"),
            "overrides": overrides_text(meta), "physics": physics_key(meta)})
    figs = {}
    studies = []
    for study in sorted(groups):
        runs = sorted(groups[study], key=lambda r: r.get("created_raw", ""), reverse=True)
        comps = []
        valid = [r for r in runs if "error" not in r and _finite(r.get("peak_force"))
                 and r.get("status") == "completed"]
        # only runs with the same physics are compared (same physical parameters, or the same
        # overrides for runs that do not record them): they differ in mesh and step sizes only
        by_physics: dict[str, list[dict]] = {}
        for r in valid:
            by_physics.setdefault(r["physics"], []).append(r)
        for group in by_physics.values():
            units = {r["force_unit"] for r in group}
            if len(group) < 2 or len(units) != 1:
                continue
            entries = [{"label": f"{r['resolution']} ({r['elements']} el.)",
                        "wall_time_s": r["wall_time_s"], "peak_force": r["peak_force"],
                        "size": (r.get("n_elements") or 0, r.get("steps") or 0),
                        "published": r["published"],
                        "name": r["name"], "size_text": f"{r['elements']} elements",
                        "peak": r["peak"], "wall": r["wall"]} for r in group]
            speed_error_rows(entries)
            fid = f"fig-speed-{len(figs)}"
            physics = group[0]["overrides"] or "the study's own parameters"
            figs[fid] = _fig_speed_error(entries, f"{study} ({physics}): wall time against error in peak force",
                                         "elements")
            comps.append({"fig_id": fid, "rows": entries, "physics": physics,
                          "force_unit": group[0]["force_unit"]})
        comp = comps[0] if comps else None
        studies.append({"study": study, "runs": runs, "comp": comp, "comps": comps,
                        "anchor": "study-" + "".join(ch if ch.isalnum() else "-" for ch in study)})
    ctx = {"studies": studies, "fig_json": _script_json(_clean(figs)), "fig_ids": list(figs),
           "plotly_js": _plotly_js() if figs else "",
           "generated": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
           "n_runs": sum(len(s["runs"]) for s in studies), "folder": reports_dir.resolve().name}
    page = _env().get_template("index.html.j2").render(**ctx)
    out = reports_dir / "index.html"
    out.write_text(page, encoding="utf-8")
    return out
