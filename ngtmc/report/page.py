"""The HTML report of one run folder (``report.html``), from the template ``report.html.j2``."""
from __future__ import annotations

import datetime as _dt
import json
import math
from pathlib import Path

import numpy as np

from ngtmc.report.loading import _case_list, load_run
from ngtmc.report.numbers import (
    _finite, _pct, _run_speed_entries, case_numbers, fmt, fmt_date, fmt_duration, fmt_u, key_number_rows,
    overrides_text, reference_peaks, run_features, time_split_rows)
from ngtmc.report.figures import (
    _fig_energies, _fig_force, _fig_interpolation, _fig_newton, _fig_speed_error, _fig_step_size, _fig_wf_alpha,
    fig_study)
from ngtmc.report.plot_style import ALPHA_COLORSCALE, FONT, RHO_COLORSCALE, _case_style
from ngtmc.report.mesh_frames import (
    MAX_EDGE_TRIANGLES, MAX_FRAMES, MAX_VERTEX_FRAMES, N_LEVELS, _level_colors, _same_mesh, mesh_payload)
from ngtmc.report.figures3d import MAX_VALUES_3D, is_3d, snapshot_figures_3d


def snapshot_group_label(name: str, snap: dict, cases: list[dict]) -> str:
    """Label of an entry of ``snapshots.npz`` that is not a case: a group ``<case>@<g>`` of the
    snapshots of a case whose mesh changed (adaptive refinement), named after its case, mesh
    number and size (its elements in 2D, the triangles of the solid's surface that the report
    draws in 3D); any other name as it is."""
    base, sep, g = name.rpartition("@")
    label = next((c["label"] for c in cases if c["name"] == base), None) if sep else None
    if label is None or not g.isdigit():
        return name
    tri = snap.get("triangles") if isinstance(snap, dict) else None
    nt = int(np.shape(tri)[0]) if tri is not None and np.ndim(tri) == 2 else None
    vert = snap.get("vertices") if isinstance(snap, dict) else None
    what = "surface triangles" if vert is not None and np.ndim(vert) == 2 and np.shape(vert)[1] == 3 else "elements"
    return f"{label}, mesh {g}" + (f" ({nt} {what})" if nt is not None else "")


def _env():
    import jinja2
    loader = jinja2.FileSystemLoader(str(Path(__file__).resolve().parent.parent / "templates"))
    env = jinja2.Environment(loader=loader, autoescape=jinja2.select_autoescape(["html", "j2"]),
                             trim_blocks=True, lstrip_blocks=True)
    env.filters["fmt"] = fmt
    env.filters["fmt_u"] = fmt_u
    return env


def _script_json(obj) -> str:
    """JSON safe to place inside a <script> element."""
    s = json.dumps(obj, separators=(",", ":"), allow_nan=False, default=_json_default)
    return s.replace("</", "<\\/").replace("<!--", "<\\!--")


def _json_default(o):
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o) if math.isfinite(float(o)) else None
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o)}")


def _clean(obj):
    """Replace NaN/inf by None recursively (JSON has no NaN)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    return obj


def _plotly_js() -> str:
    from plotly.offline import get_plotlyjs
    return get_plotlyjs().replace("</script", "<\\/script")


def _status_banner(status: str) -> dict | None:
    s = (status or "unknown").lower()
    if s == "completed":
        return None
    texts = {
        "failed": "This run FAILED before reaching the end of its load path: the curves and "
                  "numbers below are partial.",
        "running": "This run was still RUNNING when the report was rendered: the curves and "
                   "numbers below are partial.",
        "interrupted": "This run was INTERRUPTED: the curves and numbers below stop where it "
                       "stopped (it can be resumed from its checkpoint).",
    }
    return {"status": s, "text": texts.get(s, f"Run status is '{s}': results may be incomplete.")}


def _parameter_rows(params: dict) -> list[dict]:
    rows = []
    for name, p in (params or {}).items():
        if isinstance(p, dict):
            v, unit, desc = p.get("value"), p.get("unit") or "-", p.get("description") or ""
        else:
            v, unit, desc = p, "-", ""
        if isinstance(v, (list, tuple)):
            vs = ", ".join(fmt(x) for x in v)
        elif isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool):
            vs = fmt(v, 6)
        else:
            vs = str(v)
        rows.append({"name": name, "value": vs, "unit": unit, "description": desc})
    return rows


def _mesh_rows(mesh: dict) -> list[dict]:
    spec = [("n_elements", "elements", "-"), ("n_vertices", "vertices", "-"),
            ("ndof_u", "displacement dofs", "-"), ("ndof_alpha", "phase-field dofs", "-"),
            ("h_min", "smallest element size h_min", "mm"),
            ("h_max", "largest element size h_max", "mm")]
    rows = []
    for key, label, unit in spec:
        if key in mesh:
            rows.append({"label": label, "value": fmt_u(mesh[key], unit)})
    for key, v in mesh.items():
        if key not in dict((s[0], 1) for s in spec) and isinstance(v, (int, float, str)):
            rows.append({"label": key.replace("_", " "), "value": fmt(v)})
    return rows


def _refined_mesh_rows(cases: list[dict]) -> list[dict]:
    """Rows of the mesh table for the cases whose mesh was refined during the run (``mesh_final``
    and ``refinements`` of their metadata): the mesh they ended on."""
    rows = []
    for c in cases:
        m = c.get("mesh_final")
        if not isinstance(m, dict):
            continue
        n = c.get("refinements")
        head = f"{c.get('label') or c.get('name')}, after {n} refinements" if n else f"{c.get('label')}, at the end"
        for key, label in (("n_elements", "elements"), ("ndof_u", "displacement dofs"),
                           ("ndof_alpha", "phase-field dofs")):
            if key in m:
                rows.append({"label": f"{head}: {label}", "value": fmt(m[key])})
        if "h_min" in m:
            rows.append({"label": f"{head}: smallest element size h_min", "value": fmt_u(m["h_min"], "mm")})
    return rows


def thickness_phrase(thickness_mm) -> str:
    """What the forces and energies of a run are for: in 2D (a thickness is recorded) "per mm of
    thickness" when the thickness is 1 mm, else "for the thickness of T mm" (the whole specimen);
    empty in 3D."""
    if thickness_mm is None:
        return ""
    t = float(thickness_mm)
    return "per mm of thickness" if abs(t - 1.0) < 1e-12 else f"for the thickness of {t:g} mm"


def render_report(run_dir, output=None) -> Path:
    """Render the HTML report of one run directory.

    Parameters
    ----------
    run_dir : str or Path
        Run directory (docs/run-directory.md). Only its recorded files are read.
    output : str or Path, optional
        Where to write the page; default ``run_dir / "report.html"``.

    Returns
    -------
    pathlib.Path of the written, self-contained HTML page (plotly.js embedded, no request to
    any other host). Sections: header and parameters, force against displacement with the
    references, key numbers, step history, phase-field snapshots on the deformed mesh (3D: on
    the deformed surface, and in the section plane when recorded; :mod:`.figures3d`), density
    and mesh, energies, speed against error; and what the study declares in its ``REPORT``
    (recorded as ``metadata["report"]``): ``force_log_scale`` (the force also on a log scale),
    ``interpolation`` (the rules gamma(rho) and Gc(rho) over the cases' parameters) and
    ``speed_against_error`` (False: the cases are no variants of one another's settings).
    """
    run_dir = Path(run_dir)
    meta, history, snapshots = load_run(run_dir)
    cases = _case_list(meta)
    styles = _case_style(cases)
    fu = meta.get("force_unit") or "N"
    per_thickness = thickness_phrase(meta.get("thickness_mm"))
    shows = dict(meta.get("report") or {})     # the study's declared flags, never its name
    has_hist = bool(len(history)) and history["load"].notna().any()
    features = run_features(meta, history, snapshots)

    figs: dict[str, dict] = {}
    figs["fig-force"] = _fig_force(meta, history, cases, styles)
    if shows.get("force_log_scale"):
        figs["fig-force-log"] = _fig_force(meta, history, cases, styles, log_y=True)
    figs["fig-step-size"] = _fig_step_size(history, cases, styles)
    if features["fracture"]:
        figs["fig-wf-alpha"] = _fig_wf_alpha(history, cases, styles)
    figs["fig-newton"] = _fig_newton(history, cases, styles)
    figs["fig-energies"] = _fig_energies(history, cases, styles, features)
    study_figures = []  # what the study adds (its figures(p) and its post_results' report_figure entries)
    for k, spec in enumerate(_study_figure_specs(meta)):
        fid = f"fig-study-{k}"
        figs[fid] = fig_study(spec)
        study_figures.append({"id": fid, "title": str(spec.get("title", "")), "caption": str(spec.get("caption", ""))})

    study_tables = _study_tables(meta)

    interp = None
    if shows.get("interpolation"):
        f1, f2, info = _fig_interpolation(meta, cases)
        figs["fig-gamma"] = f1
        if features["fracture"]:       # Gc(rho) matters only where something may break
            figs["fig-gc"] = f2
        interp = dict(info, gc=features["fracture"])

    speed = _run_speed_entries(meta, history, cases) if len(cases) >= 2 else []
    speed_meaningful = len(speed) >= 2 and shows.get("speed_against_error", True)
    if speed_meaningful:
        figs["fig-speed-error"] = _fig_speed_error(
            speed, "Wall time against error in peak force (cases of this run)", "steps")

    # snapshots
    meshes = {}
    mesh_info = []
    snap3d = []  # 3D entries: plotly figures in figs (the 2D mesh payload assumes 2D triangles)
    if snapshots:
        # frame budget: about MAX_VERTEX_FRAMES vertex positions over all cases
        n_vert = sum(int(np.shape(sn.get("vertices", ()))[0]) for sn in snapshots.values()
                     if isinstance(sn, dict) and np.ndim(sn.get("vertices", ())) == 2 and not is_3d(sn))
        frame_cap = max(2, min(MAX_FRAMES, MAX_VERTEX_FRAMES // max(n_vert, 1)))
        n_3d = sum(1 for sn in snapshots.values() if is_3d(sn))
        for c in cases + [{"name": n, "label": snapshot_group_label(n, snapshots[n], cases), "parameters": {}}
                          for n in snapshots if n not in {c["name"] for c in cases}]:
            snap = snapshots.get(c["name"])
            if is_3d(snap):
                v3 = snapshot_figures_3d(snap, c["label"], MAX_FRAMES, MAX_VALUES_3D // n_3d)
                if v3 is not None:
                    k = len(snap3d)
                    surface, section = v3.pop("surface"), v3.pop("section")
                    v3.update(label=c["label"], surface_id=f"snap3d-{k}",
                              section_id=f"section3d-{k}" if section else None)
                    figs[v3["surface_id"]] = surface
                    if section:
                        figs[v3["section_id"]] = section
                    snap3d.append(v3)
                continue
            payload = mesh_payload(snap, frame_cap) if snap else None
            if payload is None:
                continue
            meshes[c["name"]] = payload
            same_as = None
            for prev in mesh_info:
                if _same_mesh(meshes[prev["case"]], payload):
                    same_as = prev
                    break
            if same_as is not None:
                same_as["shared_with"].append(c["label"])
                # the base mesh is sent once: this case refers to the first one holding it
                payload["mesh_of"] = same_as["case"]
                for key in ("xi", "yi", "t", "rho_level"):
                    payload.pop(key)
            mesh_info.append({
                "same_as": same_as["label"] if same_as else None, "shared_with": [],
                "case": c["name"], "label": c["label"], "scale": payload["scale"],
                "n_frames": len(payload["frames"]), "n_recorded": payload["n_recorded"],
                "has_alpha": payload.get("has_alpha", False),
                "fracture": any((fr.get("alpha_max") or 0) > 0 for fr in payload["frames"]),
                "edges": payload["nt"] <= MAX_EDGE_TRIANGLES,
                "nt": payload["nt"], "nv": payload["nv"], "dim": payload["dim"],
                "u_max": payload.get("u_max"), "n_void": payload["n_void"],
                "snap_id": f"snap-{len(mesh_info)}", "mesh_id": f"mesh-{len(mesh_info)}",
                "loads": [fr["load"] for fr in payload["frames"]]})
    mesh_plot_ids = {}
    for mi in mesh_info:
        if mi["n_frames"]:
            mesh_plot_ids[mi["snap_id"]] = {"case": mi["case"], "kind": "alpha",
                                            "label": mi["label"], "scale": fmt(mi["scale"]),
                                            "scale_num": mi["scale"],
                                            "fracture": mi["fracture"]}
        if not mi["same_as"]:
            n_other = len(mi["shared_with"])
            mesh_plot_ids[mi["mesh_id"]] = {
                "case": mi["case"], "kind": "rho", "edges": mi["edges"],
                "label": mi["label"] + (f" (same mesh in {n_other} more case"
                                        f"{'s' if n_other > 1 else ''})" if n_other else "")}

    created = meta.get("created")
    versions = meta.get("versions") or {}
    mesh = meta.get("mesh") or {}
    ref_peaks = reference_peaks(meta)
    case_nums = [dict(case_numbers(meta, history, c["name"]), label=c["label"]) for c in cases]
    for cn in case_nums:
        cn["ref_diffs"] = []
        for rp in ref_peaks:
            d = None
            if _finite(cn.get("peak_force")) and rp["peak"]:
                d = (cn["peak_force"] - rp["peak"]) / abs(rp["peak"]) * 100
            dl = None
            if _finite(cn.get("peak_load")) and rp["at"]:
                dl = (cn["peak_load"] - rp["at"]) / abs(rp["at"]) * 100
            cn["ref_diffs"].append({"force": _pct(d), "load": _pct(dl)})

    ctx = {
        "meta": meta, "study": str(meta.get("study", "")), "title": meta.get("title") or str(meta.get("study", "")),
        "summary": meta.get("summary_text") or "", "resolution": meta.get("resolution") or "–",
        "created": fmt_date(created), "status": meta.get("status"),
        "banner": _status_banner(meta.get("status")),
        "versions": versions, "git_revision": meta.get("git_revision") or "–",
        "parameters": _parameter_rows(meta.get("parameters")), "mesh_rows": _mesh_rows(mesh) + _refined_mesh_rows(cases),
        "n_elements": fmt(mesh.get("n_elements")),
        "ndof": fmt((mesh.get("ndof_u") or 0) + (mesh.get("ndof_alpha") or 0))
        if ("ndof_u" in mesh or "ndof_alpha" in mesh) else "–",
        "ndof_parts": "u + α" if (mesh.get("ndof_alpha") or 0) > 0 else (
            "u" if "ndof_u" in mesh or "ndof_alpha" in mesh else ""),
        "features": features, "overrides": overrides_text(meta),
        "wall_time": fmt_duration(meta.get("wall_time_s")),
        "thickness": fmt_u(meta.get("thickness_mm"), "mm"), "force_unit": fu, "per_thickness": per_thickness,
        "cases": cases, "styles": styles, "has_history": has_hist,
        "n_rows": int(len(history)),
        "references": [r for r in meta.get("references") or [] if isinstance(r, dict)],
        "key_rows": key_number_rows(meta, history), "ref_peaks": ref_peaks,
        "case_nums": case_nums, "interp": interp, "study_figures": study_figures, "study_tables": study_tables,
        "speed": speed, "speed_meaningful": speed_meaningful,
        "time_split": time_split_rows(meta, history, cases),
        "mesh_info": mesh_info, "has_snapshots": bool(mesh_info or snap3d), "snap3d": snap3d,
        "mpi_ranks": (meta.get("mpi") or {}).get("ranks"),
        "fig_ids": list(figs), "mesh_plot_ids": mesh_plot_ids,
        "fig_json": _script_json(_clean(figs)), "mesh_json": _script_json(_clean(meshes)),
        "mesh_plot_json": _script_json(mesh_plot_ids),
        "colors_json": _script_json({"alpha": _level_colors(ALPHA_COLORSCALE, N_LEVELS),
                                     "rho": _level_colors(RHO_COLORSCALE, 11),
                                     "alpha_scale": ALPHA_COLORSCALE,
                                     "rho_scale": RHO_COLORSCALE, "font": FONT}),
        "plotly_js": _plotly_js(),
        "generated": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "run_name": run_dir.resolve().name,
    }
    page = _env().get_template("report.html.j2").render(**ctx)
    out = Path(output) if output is not None else run_dir / "report.html"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(page, encoding="utf-8")
    return out


def _study_figure_specs(meta: dict) -> list[dict]:
    """The figures a study adds: its ``figures(p)`` (metadata ``figures``), then those its
    ``post_results`` puts in entries of ``results`` as ``report_figure`` (a dict or a list of
    them; docs/study-interface.md)."""
    out = [s for s in meta.get("figures") or [] if isinstance(s, dict)]
    for entry in (meta.get("results") or {}).values():
        spec = entry.get("report_figure") if isinstance(entry, dict) else None
        out.extend(s for s in (spec if isinstance(spec, list) else [spec]) if isinstance(s, dict))
    return out


def _study_tables(meta: dict) -> list[dict]:
    """The tables a study's ``post_results`` adds to entries of ``results`` as ``report_table``
    (docs/study-interface.md): title, caption, columns with their units, rows formatted."""
    out = []
    for entry in (meta.get("results") or {}).values():
        spec = entry.get("report_table") if isinstance(entry, dict) else None
        if not isinstance(spec, dict):
            continue
        cols = [c for c in spec.get("columns") or [] if isinstance(c, dict)]
        heads = [f"{c.get('name', '')} [{c['unit']}]" if c.get("unit") else str(c.get("name", "")) for c in cols]
        rows = [[fmt(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else ("-" if v is None else str(v))
                 for v in row] for row in spec.get("rows") or []]
        out.append({"title": str(spec.get("title", "")), "caption": str(spec.get("caption", "")), "heads": heads,
                    "rows": rows})
    return out
