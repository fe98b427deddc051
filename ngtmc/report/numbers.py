"""Numbers of the reports: formatting with units, what a run has (features, overrides, physics),
key numbers, peaks against targets and references, speed against error, where the time went."""
from __future__ import annotations

import datetime as _dt
import json
import math
from typing import Any

import numpy as np
import pandas as pd

from ngtmc.simulation import peak
from ngtmc.report.loading import _case_list, _case_rows, _param_value


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


def case_numbers(meta: dict, history: pd.DataFrame, case: str) -> dict:
    """Key numbers of one case: peak force (force unit) and its displacement (mm), steps, Newton
    iterations, cut-backs, floor acceptances, the largest residual of an accepted state (force
    unit), wall time (s), final W_f (N mm) and max alpha (-).

    Taken from the history when it has the case, else from ``metadata["results"][case]``.
    """
    res = (meta.get("results") or {}).get(case) or {}
    h = _case_rows(history, case)
    out: dict[str, Any] = {"case": case}
    pf, pl = peak(h["force"], h["load"]) if len(h) else (None, None)
    if pf is not None:
        out["peak_force"], out["peak_load"] = pf, pl
    else:
        out["peak_force"] = res.get("peak_force")
        out["peak_load"] = res.get("peak_load")
    steps = h["step"].to_numpy(dtype=float) if len(h) else np.array([])
    if steps.size and np.isfinite(steps).any():
        out["steps"] = int(np.nanmax(steps))
    else:
        out["steps"] = res.get("steps")
    for col in ("newton_iterations", "cutbacks", "floor_accepts"):   # floor_accepts: None in runs before 0.2
        v = h[col].to_numpy(dtype=float) if len(h) and col in h else np.array([])
        out[col] = int(np.nansum(v)) if v.size and np.isfinite(v).any() else res.get(col)
    out["max_residual"] = float(h["residual"].max()) if "residual" in h and h["residual"].notna().any() else None
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
            py, px = peak(y[:n], x[:n])
            if py is None:
                continue
            out.append({"label": str(ref.get("label", "reference")) + (f" – {tag} bound" if tag else ""),
                        "peak": py * fac, "at": px, "note": note})
    return out


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


#: Parts of the time split shown in the report, in order (keys of ngtmc.discrete.solver.TIMING_KEYS).
TIME_SPLIT_PARTS = ("assembly", "residual", "factorization", "solve", "line_search", "phase_field", "history", "record")


def time_split_rows(meta: dict, history: pd.DataFrame, cases: list[dict]) -> list[dict]:
    """Per case with a recorded ``time_split_s``: Newton iterations, ms per iteration, the NGSolve
    threads it ran with (None where not recorded) and the share of the case's wall time spent in
    each part (%), plus the rest (meshing, output, ...)."""
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
                     "threads": c.get("threads"),
                     "wall_time_s": float(wall), "parts": parts, "other": max(0.0, 100.0 - sum(v for _, v in parts))})
    return rows


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
