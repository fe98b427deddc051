"""Reusable parts of the speed-against-error benchmarks (``python -m benchmarks.run``).

Units: loads and displacements in mm, forces in N (for the scene's thickness; per mm of thickness
when it is 1 mm), times in s (``*_s``) or ms (``*_ms``), errors in % (``*_pct``) or N.

* :func:`run_variant` runs one Simulation and returns its record (a JSON-able dict) and history;
* :func:`compare` compares a force-load curve with a reference curve;
* :func:`format_table` renders records as a fixed-width or markdown table.

Everything except :func:`run_variant` is pure (numpy/pandas, and the one definition of the peak
of a force-load curve, :func:`ngtmc.study.run_files.peak`) and solves nothing.
"""
from __future__ import annotations

import ast
import copy
import dataclasses
import math
import sys
import time

import numpy as np
import pandas as pd

from ngtmc.simulation import peak, peak_index

__all__ = ["parse_value", "parse_assignments", "merge_options", "pseudo_time", "downsample", "summarise",
           "compare", "timing_split", "table_rows", "format_table", "jsonable", "run_variant", "TABLE_COLUMNS"]

MAX_CURVE_POINTS = 2000

# ====================================================================== option parsing
def parse_value(text: str):
    """``"False"`` -> False, ``"1e-3"`` -> 0.001, ``"monolithic"`` -> ``"monolithic"`` (a Python
    literal via :func:`ast.literal_eval`, else the stripped string)."""
    text = str(text).strip()
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        return text

def parse_assignments(items) -> dict:
    """``["compile=False", "newton.rtol=1e-10"]`` -> ``{"compile": False, "newton.rtol": 1e-10}``.
    Raises ValueError for an item without ``=`` or with an empty key."""
    out = {}
    for item in items or []:
        key, sep, value = str(item).partition("=")
        if not sep or not key.strip():
            raise ValueError(f"expected key=value, got {item!r}")
        out[key.strip()] = parse_value(value)
    return out

def merge_options(case_options: dict, variant_options: dict) -> dict:
    """Keyword arguments for ``ngtmc.Simulation``: a deep copy of the case's options updated with the
    variant's. Keys ``newton.NAME`` are collected into an ``ngtmc.NewtonOptions`` (on top of the case's one, if any)."""
    merged = copy.deepcopy(dict(case_options or {}))
    variant = dict(variant_options or {})
    newton = {k.split(".", 1)[1]: variant.pop(k) for k in list(variant) if k.startswith("newton.")}
    merged.update(copy.deepcopy(variant))
    if newton:
        import ngtmc
        base = merged.get("newton")
        base = dataclasses.asdict(base) if base is not None else {}
        merged["newton"] = ngtmc.NewtonOptions(**{**base, **newton})
    return merged

# ====================================================================== curves
def pseudo_time(load) -> np.ndarray:
    """Accumulated |change of load| (mm) along a history; equals the load for monotonic loading."""
    x = np.asarray(load, dtype=float)
    if x.size == 0:
        return x
    return np.concatenate([[0.0], np.cumsum(np.abs(np.diff(x)))]) + x[0]

def downsample(load, force, n: int = MAX_CURVE_POINTS) -> tuple[list, list]:
    """At most ``n`` points of a force-load curve: always the first and last points, the peak force
    and the load turning points (so :func:`pseudo_time` of the result stays exact), the rest evenly
    spaced in step index. Returns two lists (mm, N)."""
    x = np.asarray(load, dtype=float)
    y = np.asarray(force, dtype=float)
    m = x.size
    if m <= n:
        return x.tolist(), y.tolist()
    fixed = {0, m - 1}
    if peak_index(y) is not None:
        fixed.add(peak_index(y))
    nz = np.flatnonzero(np.diff(x) != 0)
    sd = np.sign(np.diff(x)[nz])
    fixed.update(int(i) for i in nz[:-1][sd[1:] != sd[:-1]] + 1)
    rest = np.setdiff1d(np.arange(m), np.fromiter(fixed, dtype=int))
    k = max(n - len(fixed), 0)
    picked = rest[np.floor(np.linspace(0, rest.size - 1, k) + 0.5).astype(int)] if k and rest.size else []
    idx = np.array(sorted(fixed | {int(i) for i in picked}))
    return x[idx].tolist(), y[idx].tolist()

def summarise(history: pd.DataFrame) -> dict:
    """Key numbers of a history (row 0 = unloaded state): ``steps`` (accepted), ``newton_iterations``
    and ``cutbacks`` (sums), ``peak_force_N`` and its ``peak_load_mm``, ``final_load_mm``,
    ``final_force_N``, and ``history_time_sums_s`` (sums of the per-step ``*_time`` columns, s)."""
    out = {"steps": 0, "newton_iterations": 0, "cutbacks": 0, "peak_force_N": None, "peak_load_mm": None,
           "final_load_mm": None, "final_force_N": None, "history_time_sums_s": {}}
    if history is None or len(history) == 0:
        return out
    out["steps"] = int(history["step"].iloc[-1]) if "step" in history else len(history) - 1
    for col in ("newton_iterations", "cutbacks", "staggered_iterations"):
        if col in history:
            out[col] = int(pd.to_numeric(history[col], errors="coerce").fillna(0).sum())
    f = history["force"].to_numpy(dtype=float)
    out["peak_force_N"], out["peak_load_mm"] = peak(f, history["load"])
    out["final_load_mm"] = float(history["load"].iloc[-1])
    out["final_force_N"] = float(f[-1])
    for col in history.columns:
        if col.endswith("_time") and col != "wall_time":
            out["history_time_sums_s"][col] = float(pd.to_numeric(history[col], errors="coerce").fillna(0).sum())
    return out

def _pct(value, ref):
    if value is None or ref is None or not ref:
        return None
    return 100.0 * (float(value) - float(ref)) / abs(float(ref))

def compare(load, force, ref_load, ref_force) -> dict:
    """Errors of a force-load curve (mm, N) against a reference curve.

    ``peak_force_error_pct`` and ``peak_load_error_pct``: 100 (run - ref) / |ref| of the largest
    force and of the load where it occurs, %. ``max_force_diff_N``: max |F_run - F_ref| over the
    reference's points in the common range, the run's force interpolated linearly onto them (in
    pseudo-time, i.e. accumulated |change of load|, which is the load for monotonic loading), N;
    ``max_force_diff_load_mm`` where it occurs; ``max_force_diff_pct_of_peak`` relative to the
    reference peak, %; ``common_range_mm`` the compared pseudo-time range."""
    x, y = np.asarray(load, dtype=float), np.asarray(force, dtype=float)
    xr, yr = np.asarray(ref_load, dtype=float), np.asarray(ref_force, dtype=float)
    out = {"peak_force_error_pct": None, "peak_load_error_pct": None, "max_force_diff_N": None,
           "max_force_diff_load_mm": None, "max_force_diff_pct_of_peak": None, "common_range_mm": None}
    i, ir = peak_index(y), peak_index(yr)
    if x.size == 0 or xr.size == 0 or i is None or ir is None:
        return out
    out["peak_force_error_pct"] = _pct(y[i], yr[ir])
    out["peak_load_error_pct"] = _pct(x[i], xr[ir])
    t, tr = pseudo_time(x), pseudo_time(xr)
    lo, hi = max(t[0], tr[0]), min(t[-1], tr[-1])
    mask = (tr >= lo - 1e-15) & (tr <= hi + 1e-15) & np.isfinite(yr)
    if hi >= lo and np.any(mask):
        diff = np.abs(np.interp(tr[mask], t, y) - yr[mask])
        j = int(np.nanargmax(diff))
        out["max_force_diff_N"] = float(diff[j])
        out["max_force_diff_load_mm"] = float(xr[mask][j])
        out["max_force_diff_pct_of_peak"] = 100.0 * float(diff[j]) / abs(float(yr[ir])) if yr[ir] else None
        out["common_range_mm"] = [float(lo), float(hi)]
    return out

def timing_split(timings: dict, wall_time_s: float, newton_iterations: int) -> dict:
    """Per category of ``timings`` (s): ``{cat: {"s", "ms_per_newton", "pct_of_wall"}}``; the
    per-iteration and percentage entries are None when there are no iterations or no wall time."""
    out = {}
    for cat, sec in (timings or {}).items():
        sec = float(sec)
        out[cat] = {"s": sec,
                    "ms_per_newton": 1000.0 * sec / newton_iterations if newton_iterations else None,
                    "pct_of_wall": 100.0 * sec / wall_time_s if wall_time_s else None}
    return out

# ====================================================================== table
#: (header, unit/meaning) of the table columns, in order (see docs/performance.md).
TABLE_COLUMNS = [("label", ""), ("dofs", "u + alpha"), ("steps", "accepted"), ("Newton", "iterations"),
                 ("cut-backs", ""), ("wall s", "run"), ("ms/it", "wall per Newton it."), ("asm %", "of wall"),
                 ("fact %", "of wall"), ("peak N", ""), ("at mm", ""), ("peak err %", "vs reference"),
                 ("status", "")]

def _fmt(v, spec):
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)

def table_rows(records) -> list[list[str]]:
    """One list of cell strings per run record (columns of :data:`TABLE_COLUMNS`)."""
    rows = []
    for r in records:
        nd = r.get("ndof") or {}
        dofs = (nd.get("u") or 0) + (nd.get("alpha") or 0) if nd else None
        wall, its = r.get("wall_time_s"), r.get("newton_iterations")
        pct = r.get("time_pct_of_wall") or {}
        err = "ref" if r.get("is_reference") else _fmt((r.get("errors") or {}).get("peak_force_error_pct"), "+.2f")
        status = r.get("status") or "-"
        rows.append([str(r.get("label", "")), _fmt(dofs, "d"), _fmt(r.get("steps"), "d"), _fmt(its, "d"),
                     _fmt(r.get("cutbacks"), "d"), _fmt(wall, ".1f"),
                     _fmt(1000.0 * wall / its if wall is not None and its else None, ".1f"),
                     _fmt(pct.get("assembly"), ".0f"), _fmt(pct.get("factorization"), ".0f"),
                     _fmt(r.get("peak_force_N"), ".3f"), _fmt(r.get("peak_load_mm"), ".5f"), err,
                     "ok" if status == "completed" else status.split(":")[0]])
    return rows

def format_table(records, markdown: bool = False) -> str:
    """The records as a fixed-width text table (``markdown=False``) or a markdown table."""
    head = [h for h, _ in TABLE_COLUMNS]
    rows = table_rows(records)
    widths = [max(len(h), *(len(row[k]) for row in rows)) if rows else len(h) for k, h in enumerate(head)]

    def line(cells):
        return "  ".join(c.ljust(w) if k == 0 else c.rjust(w) for k, (c, w) in enumerate(zip(cells, widths)))
    if markdown:
        out = ["| " + " | ".join(head) + " |", "|" + "|".join(":---" if k == 0 else "---:" for k in range(len(head))) + "|"]
        out += ["| " + " | ".join(row) + " |" for row in rows]
        return "\n".join(out)
    return "\n".join([line(head), line(["-" * w for w in widths])] + [line(row) for row in rows])

def jsonable(x):
    """``x`` in plain JSON types by the run folders' conversion (numpy values, NaN -> None), with
    dataclasses (e.g. NewtonOptions) as dicts naming their type and other objects as their repr."""
    from ngtmc.study import jsonable as _jsonable
    return _jsonable(x, other=_json_other)


def _json_other(x):
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return {"type": type(x).__name__, **jsonable(dataclasses.asdict(x))}
    return repr(x)

# ====================================================================== one run
def run_variant(label: str, build_scene, schedule, control, options: dict, *, du_max_factor: float = 1.0,
                progress_interval: float = 10.0, stream=sys.stderr) -> tuple[dict, pd.DataFrame]:
    """Build the scene (``build_scene()``), the Simulation and run it; return ``(record, history)``.

    ``control`` is used as given (pass a fresh copy); ``du_max_factor`` divides its ``du_max`` (and
    caps ``du_min``) after the Simulation is built (also for the Simulation's default control).
    The record holds: ``setup_scene_s`` (scene and mesh), ``setup_solver_s`` (Simulation and
    Solver construction), ``wall_time_s`` (around ``sim.run()``), ``cpu_time_s`` (CPU time of all
    threads of this process during the run), ``status`` ("completed", "failed: message" or
    "interrupted"), ``ndof`` (dict), ``elements``, ``timings_s`` (what the solver's ``timings``
    accumulated during ``sim.run()``, if it has them, s), ``timing_split``, ``time_pct_of_wall``
    with the source in ``timing_source``, the :func:`summarise` numbers and ``curve`` (load mm,
    force N, at most 2000 points). A KeyboardInterrupt ends the run with status "interrupted" (not
    re-raised).
    """
    import ngtmc
    last = {"t": time.perf_counter()}
    t_run = {"t0": None}

    def progress(row):
        now = time.perf_counter()
        if now - last["t"] >= progress_interval:
            last["t"] = now
            el = now - t_run["t0"] if t_run["t0"] else 0.0
            print(f"[bench] {label}: step {row.get('step')}  load {row.get('load', math.nan):.6g} mm  "
                  f"force {row.get('force', math.nan):.5g} N  {el:.0f} s", file=stream, flush=True)

    opts = dict(options)
    opts["progress"] = progress
    t0 = time.perf_counter()
    scene = build_scene()
    t1 = time.perf_counter()
    sim = ngtmc.Simulation(scene, schedule, control, **opts)
    if du_max_factor != 1.0:
        c = sim.control
        c.du_max = c.du_max / float(du_max_factor)
        c.du_min = min(c.du_min, c.du_max)
    t2 = time.perf_counter()
    nd = dict(getattr(sim.solver, "ndof", {}) or {})
    print(f"[bench] {label}: {sim.solver.mesh.ne} elements, dofs {nd}, set-up {t2 - t0:.1f} s", file=stream, flush=True)
    status = "completed"
    t_run["t0"] = last["t"] = time.perf_counter()
    cpu0 = time.process_time()
    timings0 = dict(getattr(sim.solver, "timings", None) or {})
    try:
        sim.run()
        history = sim.history
    except ngtmc.StepFailure as e:
        status, history = f"failed: {e}", e.history
    except KeyboardInterrupt:
        status, history = "interrupted", sim.history
    except Exception as e:  # a crashing variant must not lose the others
        status, history = f"failed: {type(e).__name__}: {e}", sim.history
    wall = time.perf_counter() - t_run["t0"]
    cpu = time.process_time() - cpu0
    rec = {"label": label, "status": status, "options": jsonable(options),
           "control": jsonable({k: getattr(sim.control, k, None) for k in ("du_max", "k_u", "du_min", "n_s")}),
           "schedule_mm": jsonable(getattr(sim.schedule, "points", None)),
           "setup_scene_s": t1 - t0, "setup_solver_s": t2 - t1, "wall_time_s": wall, "cpu_time_s": cpu,
           "ndof": jsonable(nd), "elements": int(sim.solver.mesh.ne)}
    rec.update(summarise(history))
    counters = sim.counters()
    rec["counters"] = {k: v for k, v in counters.items() if k != "coupled"}
    if "coupled" in counters:
        rec["coupled"] = counters["coupled"]
    timings = dict(getattr(sim.solver, "timings", None) or {})
    timings = {k: float(v) - float(timings0.get(k, 0.0)) for k, v in timings.items()}
    rec["timings_s"] = timings
    rec["timing_split"] = timing_split(timings, wall, rec["newton_iterations"])
    if timings:
        rec["timing_source"] = "solver.timings"
        rec["time_pct_of_wall"] = {k: v["pct_of_wall"] for k, v in rec["timing_split"].items()}
    else:  # older solver: the per-step history columns (solve_time = factorization + solve)
        sums = rec["history_time_sums_s"]
        rec["timing_source"] = "history columns" if sums else None
        rec["time_pct_of_wall"] = {"assembly": 100.0 * sums["assembly_time"] / wall} if "assembly_time" in sums and wall else {}
    cx, cy = downsample(history["load"], history["force"]) if len(history) else ([], [])
    rec["curve"] = {"load_mm": cx, "force_N": cy}
    print(f"[bench] {label}: {status}, {rec['steps']} steps, {rec['newton_iterations']} Newton, {wall:.1f} s, "
          f"peak {_fmt(rec['peak_force_N'], '.4g')} N at {_fmt(rec['peak_load_mm'], '.4g')} mm", file=stream, flush=True)
    return rec, history
