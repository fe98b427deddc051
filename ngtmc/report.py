"""Self-contained HTML reports of ngtmc runs, rendered from the recorded files only.

A run directory (see ``docs/run-directory.md``) holds ``metadata.json``, ``history.csv`` and
optionally ``snapshots.npz``. :func:`render_report` turns one such folder into
``report.html``; :func:`render_index` writes ``index.html`` for a folder of runs, linking every
run and comparing runs of the same study (wall time against error in peak force).

Nothing is re-run and NGSolve is not imported: the report needs numpy, pandas, jinja2 and plotly
only. The pages are fully offline: plotly's JavaScript is embedded once per page and nothing is
requested from any other host.

Units follow the run directory: lengths and displacements in mm, forces in the unit recorded in
``metadata["force_unit"]`` (N/mm per thickness in 2D), energies in N mm, times in s.

Public functions
----------------
- ``load_run(run_dir) -> (metadata: dict, history: pandas.DataFrame, snapshots: dict | None)``
- ``render_report(run_dir, output=None) -> pathlib.Path``
- ``render_index(reports_dir) -> pathlib.Path``
- ``report_main(argv=None) -> int``  (command line: ``ngtmc report RUN_DIR``)
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import sys
import warnings
from pathlib import Path
from typing import Any, Iterable

import numpy as np
import pandas as pd

from .runfiles import HISTORY_UNITS as _HISTORY_UNITS

__all__ = ["load_run", "render_report", "render_index", "report_main",
           "HISTORY_COLUMNS", "gamma_of_rho", "gc_ratio_of_rho"]

#: Columns of ``history.csv`` (docs/run-directory.md) with their units, from the one definition
#: in :mod:`ngtmc.runfiles`; the force is in the run's ``force_unit``.
HISTORY_COLUMNS: dict[str, str] = {"case": "-", **{k: "(force_unit)" if k == "force" else u
                                                   for k, u in _HISTORY_UNITS.items()}}

#: Largest number of phase-field frames shown per case (frames are skipped evenly beyond this).
MAX_FRAMES = 8
#: Budget of vertex positions in all snapshot frames of a page (frames are skipped beyond it).
MAX_VERTEX_FRAMES = 150_000
#: Element edges are drawn in the density/mesh plot up to this many triangles.
MAX_EDGE_TRIANGLES = 30_000
#: Largest number of points drawn per history curve (longer curves are thinned, shape kept).
MAX_POINTS = 400
#: Number of colour levels used to draw per-triangle fields.
N_LEVELS = 16

CASE_COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
               "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"]
REF_COLORS = ["#000000", "#555555", "#8c6d31", "#393b79", "#637939"]
ALPHA_COLORSCALE = [[0.0, "#e4ecf6"], [0.12, "#b9d3ea"], [0.3, "#fee391"], [0.5, "#fdae61"],
                    [0.75, "#e6492d"], [1.0, "#7f0000"]]
RHO_COLORSCALE = [[0.0, "#f7fbff"], [1.0, "#2b5b8a"]]

FONT = ("system-ui, -apple-system, 'Segoe UI', Roboto, 'Helvetica Neue', Arial, "
        "'Liberation Sans', sans-serif")


# --------------------------------------------------------------------------------------------
# material interpolation (Eqs. 17-18), used by the contact_gamma0 report
# --------------------------------------------------------------------------------------------
def gamma_of_rho(rho, gamma0: float = 1e-5):
    """Stiffness interpolation gamma(rho) = gamma0 + (1 - gamma0) rho (dimensionless)."""
    rho = np.asarray(rho, dtype=float)
    return gamma0 + (1.0 - gamma0) * rho


def gc_ratio_of_rho(rho, a: float = 10.0, b: float = 100.0):
    """Fracture toughness interpolation Gc(rho)/Gc0 = a / (1 + exp(b rho)) + rho (dimensionless)."""
    rho = np.asarray(rho, dtype=float)
    return a / (1.0 + np.exp(np.minimum(b * rho, 700.0))) + rho


# --------------------------------------------------------------------------------------------
# loading
# --------------------------------------------------------------------------------------------
def load_run(run_dir) -> tuple[dict, pd.DataFrame, dict | None]:
    """Read a run directory.

    Parameters
    ----------
    run_dir : str or Path
        Folder holding ``metadata.json`` (required), ``history.csv`` and ``snapshots.npz``
        (both optional).

    Returns
    -------
    metadata : dict
        The parsed ``metadata.json``; ``cases``, ``references``, ``targets``, ``results``,
        ``parameters`` and ``mesh`` are filled with empty containers when missing.
    history : pandas.DataFrame
        One row per accepted step with every column of :data:`HISTORY_COLUMNS` (missing
        optional columns are added as NaN; an absent file gives an empty frame). Units: load and
        step_size in mm, force in ``metadata["force_unit"]``, energies in N mm, times in s.
    snapshots : dict or None
        ``{case: {"vertices": (nv, d) mm, "triangles": (nt, 3) int, "rho": (nt,),
        "loads": (k,) mm, "u": (k, nv, d) mm, "alpha": (k, nv)}}`` with whatever keys the
        file holds, or None when ``snapshots.npz`` is absent or unreadable.
    """
    return _load(run_dir, with_snapshots=True)


def _load(run_dir, with_snapshots: bool = True):
    run_dir = Path(run_dir)
    meta_path = run_dir / "metadata.json"
    if not meta_path.is_file():
        raise FileNotFoundError(f"{meta_path} not found: not a run directory")
    meta = json.loads(meta_path.read_text(encoding="utf-8"))
    if not isinstance(meta, dict):
        raise ValueError(f"{meta_path} does not hold a JSON object")
    for key, empty in (("cases", list), ("references", list), ("targets", list),
                       ("results", dict), ("parameters", dict), ("mesh", dict),
                       ("versions", dict), ("units", dict)):
        if not isinstance(meta.get(key), empty().__class__):
            meta[key] = empty()
    meta.setdefault("study", run_dir.name)
    meta.setdefault("status", "unknown")
    # a "running" status whose process is gone is an interrupted (resumable) run
    from .runfiles import effective_status
    meta["status"], note = effective_status(meta)
    if note:
        meta["status_note"] = note
    meta.setdefault("force_unit", meta["units"].get("force", "N"))

    hist_path = run_dir / "history.csv"
    history = pd.DataFrame()
    if hist_path.is_file():
        try:
            history = pd.read_csv(hist_path)
        except (pd.errors.EmptyDataError, pd.errors.ParserError) as exc:
            warnings.warn(f"could not read {hist_path}: {exc}")
            history = pd.DataFrame()
    default_case = meta["cases"][0]["name"] if meta["cases"] and isinstance(
        meta["cases"][0], dict) and "name" in meta["cases"][0] else "main"
    if "case" not in history.columns:
        history["case"] = default_case
    for col in HISTORY_COLUMNS:
        if col not in history.columns:
            history[col] = np.nan
    history["case"] = history["case"].astype(str)
    for col in HISTORY_COLUMNS:
        if col != "case":
            history[col] = pd.to_numeric(history[col], errors="coerce")
    if not meta["cases"]:
        names = list(dict.fromkeys(history["case"].tolist())) or [default_case]
        meta["cases"] = [{"name": n, "label": n, "parameters": {}} for n in names]

    snapshots = None
    snap_path = run_dir / "snapshots.npz"
    if with_snapshots and snap_path.is_file():
        try:
            with np.load(snap_path, allow_pickle=False) as npz:
                snapshots = {}
                for key in npz.files:
                    case, sep, name = key.partition("__")
                    if not sep:
                        continue
                    snapshots.setdefault(case, {})[name] = np.asarray(npz[key])
        except Exception as exc:  # corrupt or truncated file: report without snapshots
            warnings.warn(f"could not read {snap_path}: {exc}")
            snapshots = None
    return meta, history, snapshots


# --------------------------------------------------------------------------------------------
# small helpers
# --------------------------------------------------------------------------------------------
def _finite(x) -> bool:
    try:
        return x is not None and math.isfinite(float(x))
    except (TypeError, ValueError):
        return False


def fmt(x, digits: int = 4) -> str:
    """Format a number compactly (``digits`` significant digits); text passes through."""
    if x is None:
        return "–"
    if isinstance(x, (bool, np.bool_)):
        return str(bool(x))
    if isinstance(x, (int, np.integer)):
        return f"{int(x):d}"
    try:
        v = float(x)
    except (TypeError, ValueError):
        return str(x)
    if not math.isfinite(v):
        return "–"
    if v == 0:
        return "0"
    if v == int(v) and abs(v) < 1e6:
        return f"{int(v):d}"
    a = abs(v)
    if a >= 1e5 or a < 1e-3:
        mant, _, exp = f"{v:.{digits - 1}e}".partition("e")
        if "." in mant:
            mant = mant.rstrip("0").rstrip(".")
        return f"{mant}e{int(exp)}"
    return f"{v:.{digits}g}"


def fmt_u(x, unit: str | None, digits: int = 4) -> str:
    """Number with its unit ("-" means dimensionless and is dropped)."""
    s = fmt(x, digits)
    if s == "–" or not unit or unit in ("-", "1"):
        return s
    return f"{s} {unit}"


def _pct(x) -> str:
    """Signed percentage with one decimal ("–" if missing; no "-0.0")."""
    if not _finite(x):
        return "–"
    x = float(x)
    if abs(x) < 0.05:
        return "0.0 %"
    return f"{x:+.1f} %"


def fmt_duration(seconds) -> str:
    """Wall time in s, with a h/min/s reading for long runs."""
    if not _finite(seconds):
        return "–"
    s = float(seconds)
    out = f"{fmt(s)} s"
    if s >= 60:
        h, rem = divmod(int(round(s)), 3600)
        m, sec = divmod(rem, 60)
        out += f" ({h} h {m} min {sec} s)" if h else f" ({m} min {sec} s)"
    return out


def fmt_date(text) -> str:
    if not text:
        return "–"
    try:
        d = _dt.datetime.fromisoformat(str(text).replace("Z", "+00:00"))
    except ValueError:
        return str(text)
    if d.tzinfo is not None:
        d = d.astimezone(_dt.timezone.utc)
        return d.strftime("%Y-%m-%d %H:%M UTC")
    return d.strftime("%Y-%m-%d %H:%M")


def _rs(values, sig: int = 6) -> list:
    """List of floats rounded to ``sig`` significant digits (NaN/inf become None)."""
    arr = np.asarray(values, dtype=float).ravel()
    out = []
    for v in arr:
        if not math.isfinite(v):
            out.append(None)
        else:
            out.append(float(f"{v:.{sig}g}"))
    return out


_UNIT_PREFIX = {"N": 1.0, "kN": 1e3, "MN": 1e6, "mN": 1e-3}


def unit_factor(from_unit: str | None, to_unit: str | None) -> float | None:
    """Factor converting a force unit (N, kN, N/mm, kN/mm, ...) into another; None if unknown."""
    if not from_unit or not to_unit:
        return None
    a, b = str(from_unit).replace(" ", ""), str(to_unit).replace(" ", "")
    if a == b:
        return 1.0
    pa, _, ra = a.partition("/")
    pb, _, rb = b.partition("/")
    if ra != rb or pa not in _UNIT_PREFIX or pb not in _UNIT_PREFIX:
        return None
    return _UNIT_PREFIX[pa] / _UNIT_PREFIX[pb]


def _case_list(meta: dict) -> list[dict]:
    cases = []
    for i, c in enumerate(meta.get("cases") or []):
        if isinstance(c, dict):
            name = str(c.get("name", f"case{i}"))
            cases.append({"name": name, "label": str(c.get("label") or name),
                          "parameters": c.get("parameters") or {}})
        else:
            cases.append({"name": str(c), "label": str(c), "parameters": {}})
    return cases


def _case_style(cases: list[dict]) -> dict[str, dict]:
    styles = {}
    k = 0
    for c in cases:
        if "classical" in c["name"].lower() or "classical" in c["label"].lower():
            styles[c["name"]] = {"color": "#000000", "dash": "dot"}
        else:
            styles[c["name"]] = {"color": CASE_COLORS[k % len(CASE_COLORS)], "dash": "solid"}
            k += 1
    return styles


def _param_value(params: dict, key: str):
    """Value of a parameter stored either as {"value": v, ...} or plain."""
    if not isinstance(params, dict) or key not in params:
        return None
    v = params[key]
    if isinstance(v, dict):
        v = v.get("value")
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


# --------------------------------------------------------------------------------------------
# plotly figure helpers (figures are plain dicts, serialised once with json)
# --------------------------------------------------------------------------------------------
def _axis(title: str, **kw) -> dict:
    ax = {"title": {"text": title}, "showgrid": True, "gridcolor": "#e6e6e6",
          "exponentformat": "power",
          "zeroline": False, "showline": True, "linecolor": "#444", "mirror": True,
          "ticks": "outside", "automargin": True}
    ax.update(kw)
    return ax


def _layout(title: str, xtitle: str, ytitle: str, height: int = 430, **kw) -> dict:
    lay = {
        "title": {"text": title, "x": 0.01, "xanchor": "left", "font": {"size": 15}},
        "font": {"family": FONT, "size": 12, "color": "#222"},
        "paper_bgcolor": "#ffffff", "plot_bgcolor": "#ffffff",
        "xaxis": _axis(xtitle), "yaxis": _axis(ytitle),
        "height": height, "margin": {"l": 70, "r": 30, "t": 50, "b": 60},
        "legend": {"bgcolor": "rgba(255,255,255,0.85)", "bordercolor": "#ccc", "borderwidth": 1},
        "hovermode": "closest",
    }
    lay.update(kw)
    return lay


def decimate(x, y, max_points: int = MAX_POINTS, log_y: bool = False) -> np.ndarray:
    """Indices of at most about ``max_points`` points keeping the shape of the curve (x, y).

    Points are kept evenly in arc length of the curve normalised by its x and y ranges (log10 of
    y when ``log_y``), so steep drops and spikes survive while long smooth stretches are thinned;
    the first, last, largest and smallest points are always kept.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    n = len(x)
    if n <= max_points:
        return np.arange(n)
    yy = np.log10(np.where(y > 0, y, np.nan)) if log_y else y.copy()
    ok = np.isfinite(x) & np.isfinite(yy)
    if not ok.any():
        return np.unique(np.linspace(0, n - 1, max_points).astype(int))
    xs = np.where(ok, x, np.nan)
    rx = np.nanmax(xs) - np.nanmin(xs) or 1.0
    ry = np.nanmax(np.where(ok, yy, np.nan)) - np.nanmin(np.where(ok, yy, np.nan)) or 1.0
    xn = np.nan_to_num((x - np.nanmin(xs)) / rx)
    yn = np.nan_to_num((yy - np.nanmin(np.where(ok, yy, np.nan))) / ry)
    ds = np.hypot(np.diff(xn), np.diff(yn)) + 1.0 / (4 * max_points)  # small floor: index spread
    s = np.r_[0.0, np.cumsum(ds)]
    cells = np.floor(s / s[-1] * (max_points - 4)).astype(int)
    keep = np.r_[True, cells[1:] != cells[:-1]]
    keep[-1] = True
    for i in (np.nanargmax(np.where(ok, y, np.nan)), np.nanargmin(np.where(ok, y, np.nan))):
        keep[int(i)] = True
    return np.flatnonzero(keep)


def _legend_rows(names: list, width_chars: int = 64) -> int:
    """Rough number of rows a horizontal legend needs for these entry names."""
    rows, used = 1, 0
    for n in names:
        w = len(str(n or "")) + 7
        if used and used + w > width_chars:
            rows, used = rows + 1, 0
        used += w
    return rows


def _legend_below(lay: dict, rows: int = 2) -> dict:
    """Put the legend under the plot (for half-width plots and plots with a right y axis)."""
    lay["legend"].update({"orientation": "h", "x": 0.0, "xanchor": "left", "y": -0.2,
                          "yanchor": "top", "font": {"size": 11}})
    lay["margin"]["b"] = 80 + 20 * rows
    lay["height"] = lay.get("height", 430) + 20 * rows
    return lay


def _log_axis(ax: dict, values) -> dict:
    """Log axis with ticks at whole decades when the data span two decades or more."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v) & (v > 0)]
    ax.update({"type": "log", "exponentformat": "power"})
    if v.size and v.max() / v.min() >= 100:
        decades = math.log10(v.max() / v.min())
        ax["dtick"] = 1 if decades <= 8 else int(math.ceil(decades / 8))
    return ax


def _line(x, y, name, color, dash="solid", width=2.0, mode="lines", yaxis=None,
          legendgroup=None, showlegend=True, sig=5, log_y=False, max_points=None,
          units: tuple[str, str] | None = None, **kw) -> dict:
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    idx = decimate(x, y, max_points or MAX_POINTS, log_y=log_y)
    x, y = x[idx], y[idx]
    tr = {"type": "scatter", "mode": mode, "x": _rs(x, sig), "y": _rs(y, sig), "name": name,
          "line": {"color": color, "dash": dash, "width": width}, "showlegend": showlegend}
    if "markers" in mode:
        tr["marker"] = {"color": color, "size": 6}
    if units:
        ux, uy = (f" {u}" if u and u not in ("-", "1") else "" for u in units)
        tr["hovertemplate"] = f"%{{x:.5g}}{ux}, %{{y:.5g}}{uy}<extra>%{{fullData.name}}</extra>"
    if yaxis:
        tr["yaxis"] = yaxis
    if legendgroup:
        tr["legendgroup"] = legendgroup
    tr.update(kw)
    return tr


def _log_toggle(axis: str = "yaxis", initial: str = "linear") -> list:
    return [{"type": "buttons", "direction": "left", "x": 1.0, "xanchor": "right", "y": 1.13,
             "yanchor": "top", "showactive": True, "active": 0 if initial == "linear" else 1,
             "bgcolor": "#f4f4f4", "bordercolor": "#bbb", "font": {"size": 11},
             "buttons": [{"label": "linear y", "method": "relayout", "args": [{f"{axis}.type": "linear"}]},
                         {"label": "log y", "method": "relayout", "args": [{f"{axis}.type": "log"}]}]}]


def _case_rows(history: pd.DataFrame, case: str) -> pd.DataFrame:
    h = history[history["case"] == case]
    if "step" in h and h["step"].notna().any():
        h = h.sort_values("step", kind="stable")
    return h


# --------------------------------------------------------------------------------------------
# what the run has: the sections and captions follow it
# --------------------------------------------------------------------------------------------
def _any_positive(history: pd.DataFrame, col: str) -> bool:
    if col not in history or not len(history):
        return False
    v = pd.to_numeric(history[col], errors="coerce").to_numpy(dtype=float)
    return bool(np.any(np.nan_to_num(v) > 0))


def run_features(meta: dict, history: pd.DataFrame, snapshots: dict | None = None) -> dict:
    """What a run has, for the sections and captions of its report: ``fracture`` (a phase field),
    ``void`` (a third medium, so a gap closes before contact), ``regulariser``, ``several_cases``,
    ``references``. Taken from ``metadata["features"]`` (recorded by the runner from the scenes)
    where present, else inferred from the recorded files: phase-field dofs in the mesh record (or
    a nonzero W_f or max alpha in the history), void triangles (rho < 1) in the snapshots or a
    gamma0 parameter, a nonzero regularisation energy."""
    rec = meta.get("features") if isinstance(meta.get("features"), dict) else {}
    mesh = meta.get("mesh") or {}
    fracture = rec.get("fracture")
    if fracture is None:
        if "ndof_alpha" in mesh and _finite(mesh.get("ndof_alpha")):
            fracture = float(mesh["ndof_alpha"]) > 0
        else:
            fracture = _any_positive(history, "max_alpha") or _any_positive(history, "fracture_energy")
    void = rec.get("void")
    if void is None:
        rhos = [np.asarray(sn.get("rho")) for sn in (snapshots or {}).values()
                if isinstance(sn, dict) and sn.get("rho") is not None]
        if rhos:
            void = any(r.size and bool(np.any(r < 1.0)) for r in rhos)
        else:
            void = _param_value(meta.get("parameters") or {}, "gamma0") is not None or any(
                _param_value(c.get("parameters") or {}, "gamma0") is not None for c in _case_list(meta))
    regulariser = rec.get("regulariser")
    if regulariser is None:
        regulariser = _any_positive(history, "regularisation_energy")
    refs = [r for r in meta.get("references") or [] if isinstance(r, dict)]
    return {"fracture": bool(fracture), "void": bool(void), "regulariser": bool(regulariser),
            "several_cases": len(_case_list(meta)) > 1, "references": bool(refs)}


def overrides_text(meta: dict) -> str:
    """``"E = 2000 MPa, k_u = 50 1/N"`` from ``metadata["overrides"]`` (units from the parameter
    table), or ``""`` when the run has none."""
    over = meta.get("overrides") if isinstance(meta.get("overrides"), dict) else {}
    params = meta.get("parameters") or {}
    parts = []
    for k, v in over.items():
        unit = (params.get(k) or {}).get("unit") if isinstance(params.get(k), dict) else None
        if isinstance(v, (list, tuple)):
            vs = ", ".join(fmt(x) for x in v)
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            vs = fmt(v, 6)
        else:
            vs = str(v)
        parts.append(f"{k} = {vs}" + (f" {unit}" if unit and unit != "-" else ""))
    return ", ".join(parts)


def physics_key(meta: dict) -> str:
    """Runs with equal keys share their physics and may be compared (they differ at most in mesh
    and step sizes): ``metadata["physics_hash"]`` (hash of the study's physical parameters,
    without the resolution keys) where recorded, else the recorded overrides."""
    if meta.get("physics_hash"):
        return str(meta["physics_hash"])
    over = meta.get("overrides") if isinstance(meta.get("overrides"), dict) else {}
    return "overrides:" + json.dumps(over, sort_keys=True, default=str)


# --------------------------------------------------------------------------------------------
# numbers
# --------------------------------------------------------------------------------------------
def case_numbers(meta: dict, history: pd.DataFrame, case: str) -> dict:
    """Key numbers of one case: peak force (force unit) and its displacement (mm), steps,
    Newton iterations, cut-backs, wall time (s), final W_f (N mm) and max alpha (-).

    Taken from the history when it has the case, else from ``metadata["results"][case]``.
    """
    res = (meta.get("results") or {}).get(case) or {}
    h = _case_rows(history, case)
    out: dict[str, Any] = {"case": case}
    f = h["force"].to_numpy(dtype=float) if len(h) else np.array([])
    if f.size and np.isfinite(f).any():
        i = int(np.nanargmax(f))
        out["peak_force"] = float(f[i])
        out["peak_load"] = float(h["load"].to_numpy(dtype=float)[i])
    else:
        out["peak_force"] = res.get("peak_force")
        out["peak_load"] = res.get("peak_load")
    steps = h["step"].to_numpy(dtype=float) if len(h) else np.array([])
    if steps.size and np.isfinite(steps).any():
        out["steps"] = int(np.nanmax(steps))
    else:
        out["steps"] = res.get("steps")
    for col, key in (("newton_iterations", "newton_iterations"), ("cutbacks", "cutbacks")):
        v = h[col].to_numpy(dtype=float) if len(h) else np.array([])
        out[key] = int(np.nansum(v)) if v.size and np.isfinite(v).any() else res.get(key)
    if _finite(res.get("wall_time_s")):
        out["wall_time_s"] = float(res["wall_time_s"])
    else:
        wt = h["wall_time"].to_numpy(dtype=float) if len(h) else np.array([])
        wt = wt[np.isfinite(wt)]
        if wt.size:
            # wall_time counts from the start of the run: a case's own time is its span, or
            # its last value for the first case
            first_case = history["case"].iloc[0] if len(history) else case
            out["wall_time_s"] = float(wt.max() - (0.0 if case == first_case else wt.min()))
        elif len(meta.get("cases") or []) <= 1 and _finite(meta.get("wall_time_s")):
            out["wall_time_s"] = float(meta["wall_time_s"])
        else:
            out["wall_time_s"] = None
    out["solve_time_s"] = res.get("solve_time_s")
    if out["solve_time_s"] is None and len(h) and h["solve_time"].notna().any():
        out["solve_time_s"] = float(np.nansum(h["solve_time"].to_numpy(dtype=float)))
    for col in ("fracture_energy", "max_alpha"):
        v = h[col].dropna() if len(h) else pd.Series(dtype=float)
        out[f"final_{col}"] = float(v.iloc[-1]) if len(v) else res.get(col)
    return out


def _targets_for(meta: dict, case: str, first_case: str) -> list[dict]:
    out = []
    for t in meta.get("targets") or []:
        if not isinstance(t, dict):
            continue
        tc = t.get("case")
        if tc == case or (tc in (None, "", "*") and case == first_case):
            out.append(t)
    return out


def key_number_rows(meta: dict, history: pd.DataFrame) -> list[dict]:
    """Rows of the key-numbers table: one per (case, target), computed against published."""
    cases = _case_list(meta)
    first = cases[0]["name"] if cases else "main"
    fu = meta.get("force_unit") or "N"
    rows = []
    for c in cases:
        nums = case_numbers(meta, history, c["name"])
        res = (meta.get("results") or {}).get(c["name"]) or {}
        targets = _targets_for(meta, c["name"], first)
        base = {"case": c["label"], "peak_force": fmt_u(nums["peak_force"], fu),
                "peak_load": fmt_u(nums["peak_load"], "mm"), "steps": fmt(nums["steps"]),
                "wall_time": fmt_duration(nums["wall_time_s"])}
        if not targets:
            rows.append({**base, "quantity": "–", "computed": "–", "published": "–",
                         "rel": "–", "tol": "–", "ok": None, "source": "no published target"})
            continue
        for t in targets:
            q = str(t.get("quantity", ""))
            unit = t.get("unit")
            if q in ("peak_force", "peak_load"):
                val = nums.get(q)
                if q == "peak_force" and unit and _finite(val):
                    fac = unit_factor(fu, unit)
                    if fac is not None:
                        val = val * fac
            else:
                val = res.get(q, nums.get(q))
            pub = t.get("value")
            rel = None
            if _finite(val) and _finite(pub) and float(pub) != 0:
                rel = (float(val) - float(pub)) / abs(float(pub))
            tol = t.get("tolerance")
            ok = None
            if rel is not None and _finite(tol):
                ok = abs(rel) <= float(tol)
            rows.append({**base, "quantity": q.replace("_", " "),
                         "computed": fmt_u(val, unit), "published": fmt_u(pub, unit),
                         "rel": _pct(rel * 100 if rel is not None else None),
                         "tol": (f"± {float(tol) * 100:.0f} %" if _finite(tol) else "–"),
                         "ok": ok, "source": str(t.get("source") or "")})
    return rows


def reference_peaks(meta: dict) -> list[dict]:
    """Peak of every reference curve/band (converted to the run's force unit, mm)."""
    fu = meta.get("force_unit") or "N"
    out = []
    for ref in meta.get("references") or []:
        if not isinstance(ref, dict):
            continue
        fac = unit_factor(ref.get("y_unit"), fu)
        note = "" if fac is not None or not ref.get("y_unit") else f" (in {ref.get('y_unit')})"
        fac = fac or 1.0
        x = np.asarray(ref.get("x") or [], dtype=float)
        if ref.get("kind") == "band":
            ys = [("upper", np.asarray(ref.get("y_upper") or [], dtype=float)),
                  ("lower", np.asarray(ref.get("y_lower") or [], dtype=float))]
        else:
            ys = [("", np.asarray(ref.get("y") or [], dtype=float))]
        for tag, y in ys:
            n = min(len(x), len(y))
            if n == 0 or not np.isfinite(y[:n]).any():
                continue
            i = int(np.nanargmax(y[:n]))
            out.append({"label": str(ref.get("label", "reference")) + (f" – {tag} bound" if tag else ""),
                        "peak": float(y[i]) * fac, "at": float(x[i]), "note": note})
    return out


# --------------------------------------------------------------------------------------------
# figures
# --------------------------------------------------------------------------------------------
def _fig_force(meta, history, cases, styles, log_y=False):
    fu = meta.get("force_unit") or "N"
    data = []
    for k, ref in enumerate(r for r in meta.get("references") or [] if isinstance(r, dict)):
        fac = unit_factor(ref.get("y_unit"), fu)
        fac = 1.0 if fac is None else fac
        color = REF_COLORS[k % len(REF_COLORS)]
        label = str(ref.get("label", "reference"))
        x = np.asarray(ref.get("x") or [], dtype=float)
        if ref.get("kind") == "band":
            lo = np.asarray(ref.get("y_lower") or [], dtype=float) * fac
            hi = np.asarray(ref.get("y_upper") or [], dtype=float) * fac
            n = min(len(x), len(lo), len(hi))
            if n == 0:
                continue
            if log_y:
                lo, hi = np.abs(lo), np.abs(hi)
                lo[lo <= 0] = np.nan
                hi[hi <= 0] = np.nan
            data.append(_line(x[:n], hi[:n], label, "rgba(120,120,120,0.6)", width=0.8, units=("mm", fu),
                              legendgroup=f"ref{k}", showlegend=False, hoverinfo="skip"))
            data.append(_line(x[:n], lo[:n], label, "rgba(120,120,120,0.6)", width=0.8, units=("mm", fu),
                              legendgroup=f"ref{k}", fill="tonexty",
                              fillcolor="rgba(150,150,150,0.30)"))
        else:
            y = np.asarray(ref.get("y") or [], dtype=float) * fac
            n = min(len(x), len(y))
            if n == 0:
                continue
            if log_y:
                y = np.abs(y)
                y[y <= 0] = np.nan
            data.append(_line(x[:n], y[:n], label, color, dash="dash", width=2, units=("mm", fu),
                              legendgroup=f"ref{k}"))
    for c in cases:
        h = _case_rows(history, c["name"])
        if log_y and len(h):
            h = h[h["load"] > 0]  # the initial state carries round-off only
        if not len(h):
            continue
        y = h["force"].to_numpy(dtype=float)
        if log_y:
            y = np.abs(y)
            y[y <= 0] = np.nan
        st = styles[c["name"]]
        data.append(_line(h["load"], y, c["label"], st["color"], dash=st["dash"], width=2.2,
                          units=("mm", fu),
                          mode="lines+markers" if len(h) < 40 else "lines"))
    if log_y:
        lay = _layout("|Force| against applied displacement (log scale)",
                      "applied displacement u (mm)", f"|force| |F| ({fu})")
        ys = [v for t in data for v in t["y"] if v is not None]
        _log_axis(lay["yaxis"], ys)
    else:
        lay = _layout("Force against applied displacement", "applied displacement u (mm)",
                      f"force F ({fu})")
    return {"data": data, "layout": lay}


def _fig_step_size(history, cases, styles):
    data = []
    for c in cases:
        h = _case_rows(history, c["name"])
        h = h[h["step"].fillna(1) > 0] if len(h) else h
        if not len(h) or not h["step_size"].notna().any():
            continue
        st = styles[c["name"]]
        data.append(_line(h["load"], h["step_size"].abs(), c["label"], st["color"], dash=st["dash"],
                          mode="lines+markers", width=1.2, log_y=True, units=("mm", "mm"),
                          marker={"color": st["color"], "size": 4}))
    lay = _layout("Step size against displacement (Fig. 10)",
                  "applied displacement u (mm)", "step size |Δu| (mm)")
    _log_axis(lay["yaxis"], [v for t in data for v in t["y"] if v is not None])
    _legend_below(lay, rows=_legend_rows([t["name"] for t in data]))
    return {"data": data, "layout": lay}


def _fig_wf_alpha(history, cases, styles):
    data = []
    for c in cases:
        h = _case_rows(history, c["name"])
        if not len(h):
            continue
        st = styles[c["name"]]
        if h["fracture_energy"].notna().any():
            data.append(_line(h["load"], h["fracture_energy"], f"W_f – {c['label']}",
                              st["color"], dash="solid", legendgroup=c["name"],
                              units=("mm", "N mm")))
        if h["max_alpha"].notna().any():
            data.append(_line(h["load"], h["max_alpha"], f"max α – {c['label']}",
                              st["color"], dash="dot", yaxis="y2", legendgroup=c["name"],
                              units=("mm", "-")))
    lay = _layout("W_f and max α against displacement",
                  "applied displacement u (mm)", "fracture energy W_f (N mm)")
    lay["yaxis2"] = _axis("max α (-)", overlaying="y", side="right", range=[0, 1.05],
                          showgrid=False, mirror=False, tickmode="auto")
    lay["margin"]["r"] = 70
    _legend_below(lay, rows=_legend_rows([t["name"] for t in data]))
    if data and all((v or 0) == 0 for t in data for v in t["y"]):
        lay["annotations"] = [{"text": "no fracture in this run: W_f = 0 and α = 0 throughout",
                               "xref": "paper", "yref": "paper", "x": 0.5, "y": 0.6,
                               "showarrow": False, "font": {"size": 13, "color": "#555"}}]
    return {"data": data, "layout": lay}


def _fig_newton(history, cases, styles):
    data = []
    for c in cases:
        h = _case_rows(history, c["name"])
        h = h[h["step"].fillna(1) > 0] if len(h) else h
        if not len(h):
            continue
        st = styles[c["name"]]
        if h["newton_iterations"].notna().any():
            data.append(_line(h["step"], h["newton_iterations"], f"Newton iterations – {c['label']}",
                              st["color"], width=1.2, mode="lines", legendgroup=c["name"],
                              units=("-", "-")))
        if h["cutbacks"].notna().any():
            hc = h[h["cutbacks"].fillna(0) > 0]
            data.append({"type": "scatter", "mode": "markers", "x": _rs(hc["step"]),
                         "y": _rs(hc["cutbacks"]), "yaxis": "y2", "legendgroup": c["name"],
                         "name": f"cut-backs – {c['label']}",
                         "marker": {"color": st["color"], "symbol": "x", "size": 7}})
    lay = _layout("Newton iterations and cut-backs per accepted step", "accepted step (-)",
                  "Newton iterations per step (-)")
    lay["yaxis"]["rangemode"] = "tozero"
    lay["yaxis2"] = _axis("cut-backs per step (-)", overlaying="y", side="right",
                          showgrid=False, mirror=False, rangemode="tozero", tickmode="linear",
                          tick0=0, dtick=1)
    lay["margin"]["r"] = 70
    _legend_below(lay, rows=_legend_rows([t["name"] for t in data], 140))
    return {"data": data, "layout": lay}


def _fig_energies(history, cases, styles, features: dict | None = None):
    """Elastic energy, and the regularisation energy and W_f where the run has them (``features``
    of :func:`run_features`; None: all three)."""
    data = []
    spec = [("elastic_energy", "elastic", "solid"),
            ("regularisation_energy", "regularisation", "dot"),
            ("fracture_energy", "fracture W_f", "dash")]
    if features is not None:
        spec = [sp for sp in spec if (sp[0] != "regularisation_energy" or features.get("regulariser"))
                and (sp[0] != "fracture_energy" or features.get("fracture"))]
    for c in cases:
        h = _case_rows(history, c["name"])
        if not len(h):
            continue
        st = styles[c["name"]]
        for col, label, dash in spec:
            if h[col].notna().any():
                name = label if len(cases) == 1 else f"{label} – {c['label']}"
                data.append(_line(h["load"], h[col], name, st["color"] if len(cases) > 1 else
                                  {"elastic_energy": "#1f77b4", "regularisation_energy": "#2ca02c",
                                   "fracture_energy": "#d62728"}[col], dash=dash,
                                  legendgroup=c["name"], units=("mm", "N mm")))
    lay = _layout("Energies against applied displacement", "applied displacement u (mm)",
                  "energy (N mm)")
    lay["updatemenus"] = _log_toggle()
    lay["yaxis"]["exponentformat"] = "power"
    return {"data": data, "layout": lay}


def _fig_interpolation(meta, cases):
    params = meta.get("parameters") or {}
    gamma0s = []
    for c in cases:
        g = _param_value(c.get("parameters") or {}, "gamma0")
        if g is not None and g > 0:
            gamma0s.append((c["label"], g))
    if not gamma0s:
        g = _param_value(params, "gamma0")
        gamma0s = [(f"γ0 = {fmt(g if g else 1e-5)}", g if g else 1e-5)]
    a = _param_value(params, "gc_a") or 10.0
    b = _param_value(params, "gc_b") or 100.0
    rho = np.unique(np.concatenate([np.linspace(0, 0.1, 201), np.linspace(0.1, 1, 91)]))
    data = []
    seen = set()
    for k, (label, g) in enumerate(gamma0s):
        if g in seen:
            continue
        seen.add(g)
        color = CASE_COLORS[k % len(CASE_COLORS)]
        data.append(_line(rho, gamma_of_rho(rho, g), f"γ(ρ), γ0 = {fmt(g, 3)}", color, width=2,
                          legendgroup=f"g{k}"))
        data.append({"type": "scatter", "mode": "markers", "x": [0.0], "y": [float(g)],
                     "marker": {"color": color, "size": 9, "symbol": "circle-open",
                                "line": {"width": 2}}, "showlegend": False,
                     "legendgroup": f"g{k}", "name": f"γ(0) = γ0 = {fmt(g, 3)}",
                     "cliponaxis": False})
    lay1 = _layout("γ(ρ) = γ0 + (1 − γ0) ρ (Eq. 17)",
                   "pseudo-density ρ (-)", "γ(ρ) = K/K0 = G/G0 (-)", height=380)
    _log_axis(lay1["yaxis"], [1e-12, 1] if not gamma0s else [min(g for _, g in gamma0s), 1])
    _legend_below(lay1, rows=_legend_rows([t["name"] for t in data if t.get("showlegend", True)]))
    gc = gc_ratio_of_rho(rho, a, b)
    data2 = [_line(rho, gc, f"Gc(ρ)/Gc0, a = {fmt(a)}, b = {fmt(b)}", "#d62728", width=2.2),
             _line([0, 1], [a / 2, a / 2], f"void limit a/2 = {fmt(a / 2)}", "#777", dash="dot",
                   width=1.2)]
    lay2 = _layout("Gc(ρ)/Gc0 = a / (1 + exp(b ρ)) + ρ (Eq. 18)",
                   "pseudo-density ρ (-)", "Gc(ρ) / Gc0 (-)", height=380)
    _legend_below(lay2, rows=1)
    return ({"data": data, "layout": lay1}, {"data": data2, "layout": lay2},
            {"a": a, "b": b, "gamma0s": [g for _, g in gamma0s]})


# --------------------------------------------------------------------------------------------
# snapshots: compact mesh payload, drawn in the browser as filled SVG polygons
# --------------------------------------------------------------------------------------------
def _nice_scale(s: float) -> float:
    if s <= 1:
        return 1.0
    e = math.floor(math.log10(s))
    for m in (1, 2, 5, 10):
        if m * 10 ** e >= s * 0.999:
            return float(m * 10 ** e) if m < 10 else float(10 ** (e + 1))
    return float(10 ** (e + 1))


def deformation_scale(vertices: np.ndarray, u: np.ndarray) -> float:
    """Scale factor for drawing the deformed mesh (dimensionless).

    1 when the largest displacement is already visible (>= 1 % of the domain size, about ten
    pixels on screen), else a round
    number (1, 2, 5 x 10^k) making the largest displacement about 5 % of the domain size.
    """
    v = np.asarray(vertices, dtype=float)
    ext = float(np.max(np.ptp(v[:, :2], axis=0))) if v.size else 0.0
    um = float(np.nanmax(np.linalg.norm(np.asarray(u, dtype=float), axis=-1))) if np.size(u) else 0.0
    if ext <= 0 or um <= 0 or not math.isfinite(um):
        return 1.0
    if um >= 0.01 * ext:
        return 1.0
    return _nice_scale(0.05 * ext / um)


def _frame_indices(k: int, max_frames: int = MAX_FRAMES) -> list[int]:
    if k <= max_frames:
        return list(range(k))
    idx = np.unique(np.round(np.linspace(0, k - 1, max_frames)).astype(int))
    return [int(i) for i in idx]


def mesh_payload(snap: dict, max_frames: int = MAX_FRAMES) -> dict | None:
    """Compact, JSON-ready description of one case's snapshots (None if there is no mesh).

    Coordinates are integers: vertex ``i`` of the undeformed mesh is at
    ``(x0 + q * xi[i], y0 + q * yi[i])`` mm with ``q`` = 1e-4 of the domain size; frame ``f``
    moves it by ``qu * (dx[i], dy[i])`` mm, the displacement already multiplied by the
    deformation ``scale``. Triangles are stored once (``t``, flat, 0-based). Each frame lists only
    the triangles whose phase field (mean of its vertices) is not in the lowest of
    ``N_LEVELS`` colour levels, as pairs ``nz = [triangle, level, ...]``; void triangles
    (``rho_level`` < 5, i.e. rho < 0.5) are drawn grey. At most ``max_frames`` frames are kept,
    evenly spread over the recorded ones, always including the last.
    """
    if not snap or "vertices" not in snap or "triangles" not in snap:
        return None
    V = np.asarray(snap["vertices"], dtype=float)
    T = np.asarray(snap["triangles"])
    if V.ndim != 2 or V.shape[0] == 0 or V.shape[1] < 2 or T.ndim != 2 or T.shape[1] != 3 \
            or T.size == 0 or not np.issubdtype(T.dtype, np.integer):
        return None
    T = T.astype(np.int64)
    if T.max() >= V.shape[0] or T.min() < 0:
        return None
    nt, nv = T.shape[0], V.shape[0]
    x0, y0 = float(V[:, 0].min()), float(V[:, 1].min())
    ext = float(max(np.ptp(V[:, 0]), np.ptp(V[:, 1]))) or 1.0
    q = float(f"{ext * 1e-4:.3g}")
    rho = np.asarray(snap.get("rho", np.ones(nt)), dtype=float).ravel()
    if rho.size != nt:
        rho = np.ones(nt)
    rho = np.nan_to_num(rho, nan=1.0)
    void = rho < 0.5
    out = {"x0": x0, "y0": y0, "q": q,
           "xi": np.round((V[:, 0] - x0) / q).astype(np.int64),
           "yi": np.round((V[:, 1] - y0) / q).astype(np.int64),
           "t": T.ravel(), "rho_level": np.clip(np.round(rho * 10), 0, 10).astype(np.int64),
           "nt": int(nt), "nv": int(nv), "dim": int(V.shape[1]), "frames": [], "scale": 1.0,
           "n_recorded": 0, "extent": ext, "n_void": int(void.sum()), "u_max": None}
    loads = np.asarray(snap.get("loads", []), dtype=float).ravel()
    U = snap.get("u")
    A = snap.get("alpha")
    k = len(loads)
    if U is None or k == 0:
        return out
    U = np.asarray(U, dtype=float)
    if U.ndim == 2 and k == 1:
        U = U[None]
    if U.ndim != 3 or U.shape[0] < k or U.shape[1] != nv or U.shape[2] < 2:
        return out
    if A is not None:
        A = np.asarray(A, dtype=float)
        if A.ndim == 1 and k == 1:
            A = A[None]
        if A.ndim != 2 or A.shape[0] < k or A.shape[1] != nv:
            A = None
    U = np.nan_to_num(U[:k], nan=0.0)
    scale = deformation_scale(V, U)
    um = float(np.max(np.linalg.norm(U, axis=-1))) if U.size else 0.0
    qu = float(f"{max(q, scale * um / 500.0):.3g}")
    out.update({"scale": scale, "n_recorded": k, "u_max": um, "qu": qu,
                "has_alpha": A is not None})
    for i in _frame_indices(k, max_frames):
        fr = {"load": float(f"{loads[i]:.6g}"),
              "dx": np.round(scale * U[i][:, 0] / qu).astype(np.int64),
              "dy": np.round(scale * U[i][:, 1] / qu).astype(np.int64)}
        if A is not None:
            a_tri = np.nan_to_num(A[i][T].mean(axis=1), nan=0.0)
            lev = np.clip(np.floor(a_tri * N_LEVELS), 0, N_LEVELS - 1).astype(np.int64)
            lev[void] = 0
            nz = np.flatnonzero(lev)
            fr["nz"] = np.column_stack([nz, lev[nz]]).ravel()
            fr["alpha_max"] = float(f"{np.nanmax(A[i]):.4g}")
        else:
            fr["nz"] = np.zeros(0, dtype=np.int64)
            fr["alpha_max"] = None
        out["frames"].append(fr)
    return out


def _same_mesh(a: dict, b: dict) -> bool:
    return (a["nv"] == b["nv"] and a["nt"] == b["nt"] and a["x0"] == b["x0"]
            and a["y0"] == b["y0"] and a["q"] == b["q"] and np.array_equal(a["xi"], b["xi"])
            and np.array_equal(a["yi"], b["yi"]) and np.array_equal(a["t"], b["t"])
            and np.array_equal(a["rho_level"], b["rho_level"]))


def _level_colors(colorscale, n: int) -> list[str]:
    from plotly.colors import sample_colorscale, get_colorscale
    cs = get_colorscale(colorscale) if isinstance(colorscale, str) else colorscale
    return sample_colorscale(cs, [(i + 0.5) / n for i in range(n)])


# --------------------------------------------------------------------------------------------
# speed against error
# --------------------------------------------------------------------------------------------
def _published_peak(meta: dict, case: str | None, fu: str) -> float | None:
    cases = _case_list(meta)
    first = cases[0]["name"] if cases else "main"
    cand = _targets_for(meta, case, first) if case else []
    cand = [t for t in cand if t.get("quantity") == "peak_force"]
    if not cand:
        cand = [t for t in meta.get("targets") or []
                if isinstance(t, dict) and t.get("quantity") == "peak_force"]
    for t in cand:
        if _finite(t.get("value")):
            fac = unit_factor(t.get("unit"), fu) if t.get("unit") else 1.0
            return float(t["value"]) * (fac if fac is not None else 1.0)
    return None


def speed_error_rows(entries: list[dict], finest: dict | None = None) -> list[dict]:
    """Add errors to entries {label, wall_time_s, peak_force, size, published}.

    The finest entry is ``finest`` if given, else the one with the largest ``size`` (steps or
    elements); errors in peak force are relative, in %.
    """
    valid = [e for e in entries if _finite(e.get("peak_force"))]
    if not valid:
        return []
    if finest is None or finest not in valid:
        finest = max(valid, key=lambda e: (e.get("size") or 0))
    pf_ref = float(finest["peak_force"])
    for e in entries:
        e["finest"] = e is finest
        pf = e.get("peak_force")
        e["err_finest"] = (abs(float(pf) - pf_ref) / abs(pf_ref) * 100
                           if _finite(pf) and pf_ref != 0 else None)
        pub = e.get("published")
        e["err_published"] = (abs(float(pf) - pub) / abs(pub) * 100
                              if _finite(pf) and _finite(pub) and pub != 0 else None)
    return entries


#: Parts of the time split shown in the report, in order (keys of ngtmc.solver.TIMING_KEYS).
TIME_SPLIT_PARTS = ("assembly", "residual", "factorization", "solve", "line_search", "phase_field", "history", "record")


def time_split_rows(meta: dict, history: pd.DataFrame, cases: list[dict]) -> list[dict]:
    """Per case with a recorded ``time_split_s``: Newton iterations, ms per iteration and the
    share of the case's wall time spent in each part (%), plus the rest (meshing, output, ...)."""
    rows = []
    for c in cases:
        res = (meta.get("results") or {}).get(c["name"]) or {}
        split = res.get("time_split_s")
        nums = case_numbers(meta, history, c["name"])
        wall, its = nums.get("wall_time_s"), nums.get("newton_iterations")
        if not isinstance(split, dict) or not _finite(wall) or not wall or not its:
            continue
        parts = [(k, 100.0 * float(split.get(k, 0.0)) / float(wall)) for k in TIME_SPLIT_PARTS]
        rows.append({"label": c["label"], "newton": int(its), "ms_per_it": 1000.0 * float(wall) / int(its),
                     "wall_time_s": float(wall), "parts": parts, "other": max(0.0, 100.0 - sum(v for _, v in parts))})
    return rows


def _fig_speed_error(entries: list[dict], title: str, size_label: str):
    pts = sorted((e for e in entries if _finite(e.get("wall_time_s"))),
                 key=lambda e: float(e["wall_time_s"]))
    data = []
    for key, name, color, sym in (("err_finest", "error vs finest", "#1f77b4", "circle"),
                                  ("err_published", "error vs published", "#d62728", "diamond")):
        p = [e for e in pts if _finite(e.get(key))]
        if not p:
            continue
        data.append({"type": "scatter", "mode": "markers+text+lines",
                     "x": _rs([e["wall_time_s"] for e in p]), "y": _rs([e[key] for e in p]),
                     "text": [e["label"] for e in p], "textposition": "top center",
                     "cliponaxis": False,
                     "name": name, "line": {"color": color, "width": 1, "dash": "dot"},
                     "marker": {"color": color, "size": 10, "symbol": sym},
                     "hovertemplate": "%{text}<br>wall time %{x} s<br>error %{y:.3g} %<extra></extra>"})
    lay = _layout(title, "wall time (s)", "relative error in peak force (%)")
    times = [float(e["wall_time_s"]) for e in pts if float(e["wall_time_s"]) > 0]
    if times and max(times) / min(times) > 20:
        lay["xaxis"]["type"] = "log"
    lay["yaxis"]["rangemode"] = "tozero"
    return {"data": data, "layout": lay}


def _run_speed_entries(meta, history, cases):
    """Speed/error rows of the cases of one run. The finest case is the one the runner names
    as ``results[case]["reference_case"]`` if any, else the case with most accepted steps."""
    fu = meta.get("force_unit") or "N"
    results = meta.get("results") or {}
    ref = next((r.get("reference_case") for r in results.values()
                if isinstance(r, dict) and r.get("reference_case")), None)
    entries, finest = [], None
    for c in cases:
        nums = case_numbers(meta, history, c["name"])
        if not _finite(nums.get("peak_force")):
            continue
        e = {"label": c["label"], "wall_time_s": nums.get("wall_time_s"),
             "peak_force": nums["peak_force"], "size": nums.get("steps") or 0,
             "size_text": fmt_u(nums.get("steps"), "steps"),
             "published": _published_peak(meta, c["name"], fu)}
        entries.append(e)
        if c["name"] == ref:
            finest = e
    return speed_error_rows(entries, finest)


# --------------------------------------------------------------------------------------------
# rendering
# --------------------------------------------------------------------------------------------
def _env():
    import jinja2
    loader = jinja2.FileSystemLoader(str(Path(__file__).parent / "templates"))
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
    references, key numbers, step history, phase-field snapshots on the deformed mesh, density
    and mesh, energies, speed against error, and for ``contact_gamma0`` the interpolation rules.
    """
    run_dir = Path(run_dir)
    meta, history, snapshots = load_run(run_dir)
    cases = _case_list(meta)
    styles = _case_style(cases)
    fu = meta.get("force_unit") or "N"
    study = str(meta.get("study", ""))
    has_hist = bool(len(history)) and history["load"].notna().any()
    features = run_features(meta, history, snapshots)

    figs: dict[str, dict] = {}
    figs["fig-force"] = _fig_force(meta, history, cases, styles)
    if study == "contact_gamma0":
        figs["fig-force-log"] = _fig_force(meta, history, cases, styles, log_y=True)
    figs["fig-step-size"] = _fig_step_size(history, cases, styles)
    if features["fracture"]:
        figs["fig-wf-alpha"] = _fig_wf_alpha(history, cases, styles)
    figs["fig-newton"] = _fig_newton(history, cases, styles)
    figs["fig-energies"] = _fig_energies(history, cases, styles, features)

    interp = None
    if study == "contact_gamma0":
        f1, f2, info = _fig_interpolation(meta, cases)
        figs["fig-gamma"] = f1
        if features["fracture"]:       # Gc(rho) matters only where something may break
            figs["fig-gc"] = f2
        interp = dict(info, gc=features["fracture"])

    speed = _run_speed_entries(meta, history, cases) if len(cases) >= 2 else []
    speed_meaningful = len(speed) >= 2 and study != "contact_gamma0"
    if speed_meaningful:
        figs["fig-speed-error"] = _fig_speed_error(
            speed, "Wall time against error in peak force (cases of this run)", "steps")

    # snapshots
    meshes = {}
    mesh_info = []
    if snapshots:
        # frame budget: about MAX_VERTEX_FRAMES vertex positions over all cases
        n_vert = sum(int(np.shape(sn.get("vertices", ()))[0]) for sn in snapshots.values()
                     if isinstance(sn, dict) and np.ndim(sn.get("vertices", ())) == 2)
        frame_cap = max(2, min(MAX_FRAMES, MAX_VERTEX_FRAMES // max(n_vert, 1)))
        for c in cases + [{"name": n, "label": n, "parameters": {}}
                          for n in snapshots if n not in {c["name"] for c in cases}]:
            snap = snapshots.get(c["name"])
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
        "meta": meta, "study": study, "title": meta.get("title") or study,
        "summary": meta.get("summary_text") or "", "resolution": meta.get("resolution") or "–",
        "created": fmt_date(created), "status": meta.get("status"),
        "banner": _status_banner(meta.get("status")),
        "versions": versions, "git_revision": meta.get("git_revision") or "–",
        "parameters": _parameter_rows(meta.get("parameters")), "mesh_rows": _mesh_rows(mesh),
        "n_elements": fmt(mesh.get("n_elements")),
        "ndof": fmt((mesh.get("ndof_u") or 0) + (mesh.get("ndof_alpha") or 0))
        if ("ndof_u" in mesh or "ndof_alpha" in mesh) else "–",
        "ndof_parts": "u + α" if (mesh.get("ndof_alpha") or 0) > 0 else (
            "u" if "ndof_u" in mesh or "ndof_alpha" in mesh else ""),
        "features": features, "overrides": overrides_text(meta),
        "wall_time": fmt_duration(meta.get("wall_time_s")),
        "thickness": fmt_u(meta.get("thickness_mm"), "mm"), "force_unit": fu,
        "cases": cases, "styles": styles, "has_history": has_hist,
        "n_rows": int(len(history)),
        "references": [r for r in meta.get("references") or [] if isinstance(r, dict)],
        "key_rows": key_number_rows(meta, history), "ref_peaks": ref_peaks,
        "case_nums": case_nums, "interp": interp,
        "speed": speed, "speed_meaningful": speed_meaningful,
        "time_split": time_split_rows(meta, history, cases),
        "mesh_info": mesh_info, "has_snapshots": bool(mesh_info),
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


def _find_runs(reports_dir: Path) -> list[Path]:
    runs = []
    for p in sorted(reports_dir.rglob("metadata.json")):
        rel = p.relative_to(reports_dir)
        if len(rel.parts) > 3 or any(part.startswith(".") for part in rel.parts):
            continue
        if "checkpoint" in rel.parts:
            continue
        runs.append(p.parent)
    return runs


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


# --------------------------------------------------------------------------------------------
# command line
# --------------------------------------------------------------------------------------------
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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(report_main())
