"""Reading a run folder (``docs/run-directory.md``) for the reports: metadata, history and snapshots."""
from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from ngtmc.simulation import HISTORY_UNITS as _HISTORY_UNITS
from ngtmc.study import effective_status


#: Columns of ``history.csv`` (docs/run-directory.md) with their units, from the one definition
#: in :mod:`ngtmc.study.run_files`; the force is in the run's ``force_unit``.
HISTORY_COLUMNS: dict[str, str] = {"case": "-", **{k: "(force_unit)" if k == "force" else u
                                                   for k, u in _HISTORY_UNITS.items()}}


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


def _case_list(meta: dict) -> list[dict]:
    cases = []
    for i, c in enumerate(meta.get("cases") or []):
        if isinstance(c, dict):
            name = str(c.get("name", f"case{i}"))
            cases.append({"name": name, "label": str(c.get("label") or name),
                          "parameters": c.get("parameters") or {},
                          **{k: c[k] for k in ("mesh_final", "refinements") if k in c}})
        else:
            cases.append({"name": str(c), "label": str(c), "parameters": {}})
    return cases


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


def _case_rows(history: pd.DataFrame, case: str) -> pd.DataFrame:
    h = history[history["case"] == case]
    if "step" in h and h["step"].notna().any():
        h = h.sort_values("step", kind="stable")
    return h


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
