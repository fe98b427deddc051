"""Synthetic run directories for the report tests, written exactly per docs/run-directory.md.

The numbers imitate the three-point bending scene (an indenter crosses a gap of 0.05 mm, the beam
then loads up to a peak near 0.096 mm and breaks) on a tiny triangulated 8 x 2 mm rectangle with
a void strip along the top edge. Nothing here needs NGSolve.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd

GAP = 0.05          # mm
PEAK_LOAD = 0.096   # mm
PEAK_FORCE = 42.0   # N/mm


def rectangle_mesh(nx: int = 16, ny: int = 5, lx: float = 8.0, ly: float = 2.0):
    """Vertices (nv, 2) in mm and triangles (nt, 3) of a structured rectangle mesh."""
    xs, ys = np.linspace(0, lx, nx + 1), np.linspace(0, ly, ny + 1)
    X, Y = np.meshgrid(xs, ys)
    vertices = np.column_stack([X.ravel(), Y.ravel()])
    tris = []
    for j in range(ny):
        for i in range(nx):
            a = j * (nx + 1) + i
            b, c, d = a + 1, a + nx + 1, a + nx + 2
            if (i + j) % 2:
                tris += [[a, b, d], [a, d, c]]
            else:
                tris += [[a, b, c], [b, d, c]]
    return vertices, np.array(tris, dtype=np.int64)


def force_curve(load: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """Synthetic force (N/mm): tiny before the gap closes, linear rise to the peak, sudden drop."""
    load = np.asarray(load, dtype=float)
    k = PEAK_FORCE / (PEAK_LOAD - GAP)
    f = np.where(load < GAP, 1e-5 * k * load, k * (load - GAP))
    after = load > PEAK_LOAD
    f = np.where(after, PEAK_FORCE * (0.25 + 0.1 * np.exp(-(load - PEAK_LOAD) / 0.01)), f)
    return f * scale


def step_loads(du_max: float, final: float = 0.15) -> tuple[np.ndarray, np.ndarray]:
    """Adaptive-looking load path: steps shrink by orders of magnitude after the peak."""
    loads, sizes = [0.0], [0.0]
    u = 0.0
    while u < final - 1e-12:
        if PEAK_LOAD - 0.004 < u < PEAK_LOAD + 0.01:
            du = du_max * 10 ** (-2.0 * np.exp(-((u - PEAK_LOAD) / 0.004) ** 2))
        else:
            du = du_max
        du = min(du, final - u)
        u += du
        loads.append(u)
        sizes.append(du)
    return np.array(loads), np.array(sizes)


def case_history(case: str, du_max: float, t0: float = 0.0, force_scale: float = 1.0,
                 drop_columns=()) -> pd.DataFrame:
    loads, sizes = step_loads(du_max)
    n = len(loads)
    force = force_curve(loads, force_scale)
    crack = 1.0 / (1.0 + np.exp(-(loads - PEAK_LOAD) / 0.002))
    wf = 0.0054 * 2 * 1.6 * crack + 1e-5 * loads
    el = np.where(loads > GAP, 0.5 * force * (loads - GAP), 1e-6 * loads ** 2) * (1 - 0.7 * crack)
    newton = np.where(loads < GAP, 3, np.where(crack > 0.05, 6, 4)).astype(int)
    newton[0] = 0
    cut = np.zeros(n, dtype=int)
    cut[np.argmin(np.abs(loads - PEAK_LOAD))] = 2
    cut[np.argmin(np.abs(loads - GAP))] = 1
    wall = t0 + np.cumsum(np.r_[0.0, np.full(n - 1, 0.05)])
    df = pd.DataFrame({
        "case": case, "step": np.arange(n), "load": loads, "force": force,
        "fracture_energy": wf, "elastic_energy": el,
        "regularisation_energy": 1e-4 * el + 1e-9 * loads,
        "max_alpha": np.maximum.accumulate(np.clip(0.05 * loads / PEAK_LOAD + crack, 0, 1)),
        "min_J": np.where(loads > GAP, 0.02, 1 - loads),
        "newton_iterations": newton, "staggered_iterations": np.ones(n, dtype=int),
        "cutbacks": cut, "step_size": sizes, "wall_time": wall,
        "solve_time": np.full(n, 0.01),
    })
    return df.drop(columns=list(drop_columns))


def case_snapshots(vertices, triangles, loads_at, gap_top: float = 1.6):
    """rho (nt,), u (k, nv, 2) mm, alpha (k, nv) for snapshot loads ``loads_at`` (mm)."""
    cent = vertices[triangles].mean(axis=1)
    rho = np.where(cent[:, 1] > gap_top, 0.0, 1.0)
    x, y = vertices[:, 0], vertices[:, 1]
    us, alphas = [], []
    for lo in loads_at:
        bend = -max(lo - GAP, 0.0) * np.sin(np.pi * x / 8.0)
        ind = -lo * np.exp(-((x - 4.0) / 0.8) ** 2) * (y > gap_top)
        uy = bend + ind
        ux = 0.002 * lo * (x - 4.0) * (y - 1.0)
        us.append(np.column_stack([ux, uy]))
        crack = min(1.0, max(0.0, (lo - 0.08) / 0.03))
        height = 0.4 + 1.2 * crack
        a = np.exp(-((x - 4.0) / 0.35) ** 2) * (y <= height) * min(1.0, 0.2 + crack)
        alphas.append(np.clip(a * (y <= gap_top), 0, 1))
    return rho, np.array(us), np.array(alphas)


def write_run(path, study: str = "three_point_bending", cases=None, status: str = "completed",
              with_snapshots: bool = True, with_references: bool = True,
              with_targets: bool = True, with_results: bool = True, drop_columns=(),
              n_elements: int | None = None, wall_time_s: float | None = None,
              force_scale: float = 1.0, resolution: str = "quick",
              mesh_n: tuple[int, int] = (16, 5), fracture: bool | None = None,
              overrides: dict | None = None, physics_hash: str | None = None) -> Path:
    """Write a synthetic run directory and return its path.

    ``cases``: list of (name, label, du_max_mm, case_parameters). Default: two step settings
    ("coarse" with du_max = 2e-3 mm and "fine" with 1e-3 mm) so that the speed-against-error
    section has data. For ``study == "contact_gamma0"`` the default is three gamma0 values plus
    a classical-contact case.

    ``fracture``: whether the scene has a phase field (default: True except for contact_gamma0,
    whose beams cannot break); without it W_f, max alpha and the alpha snapshots are zero and the
    mesh has no phase-field dofs. ``overrides`` and ``physics_hash`` go into the metadata.
    """
    if fracture is None:
        fracture = study != "contact_gamma0"
    path = Path(path)
    path.mkdir(parents=True, exist_ok=True)
    if cases is None:
        if study == "contact_gamma0":
            cases = [("g1e-4", "γ0 = 1e-4", 2e-3, {"gamma0": 1e-4}),
                     ("g1e-5", "γ0 = 1e-5", 2e-3, {"gamma0": 1e-5}),
                     ("g1e-6", "γ0 = 1e-6", 2e-3, {"gamma0": 1e-6}),
                     ("classical", "classical contact (penalty)", 2e-3, {})]
        else:
            cases = [("coarse", "du_max = 2e-3 mm", 2e-3, {"du_max": 2e-3}),
                     ("fine", "du_max = 1e-3 mm", 1e-3, {"du_max": 1e-3})]
    vertices, triangles = rectangle_mesh(*mesh_n)
    frames, t0, results = [], 0.0, {}
    npz = {}
    for k, (name, label, du, cpar) in enumerate(cases):
        fs = force_scale * (1.0 + 0.02 * k)
        h = case_history(name, du, t0=t0, force_scale=fs, drop_columns=drop_columns)
        if not fracture:
            for col in ("fracture_energy", "max_alpha"):
                if col in h:
                    h[col] = 0.0
        if study == "contact_gamma0" and "gamma0" in cpar:
            pre = h["load"] < GAP
            h.loc[pre, "force"] = h.loc[pre, "force"] * cpar["gamma0"] / 1e-5
        frames.append(h)
        t0 = float(h["wall_time"].iloc[-1]) if "wall_time" in h else t0 + 1.0
        i = int(h["force"].idxmax())
        results[name] = {"peak_force": float(h["force"].max()), "peak_load": float(h["load"][i]),
                         "steps": int(h["step"].max()), "newton_iterations": int(h.get(
                             "newton_iterations", pd.Series([0])).sum()),
                         "wall_time_s": float(h["wall_time"].iloc[-1] - h["wall_time"].iloc[0])
                         if "wall_time" in h else None,
                         "solve_time_s": 0.01 * len(h)}
        snap_loads = np.array([0.0, 0.03, 0.06, 0.09, 0.1, 0.12, 0.15])
        rho, u, alpha = case_snapshots(vertices, triangles, snap_loads)
        npz[f"{name}__vertices"] = vertices
        npz[f"{name}__triangles"] = triangles
        npz[f"{name}__rho"] = rho
        npz[f"{name}__loads"] = snap_loads
        npz[f"{name}__u"] = u
        npz[f"{name}__alpha"] = alpha if fracture else np.zeros_like(alpha)
    history = pd.concat(frames, ignore_index=True)
    history.to_csv(path / "history.csv", index=False)
    if with_snapshots:
        np.savez_compressed(path / "snapshots.npz", **npz)

    ref_x = np.linspace(0, 0.09, 10) + GAP
    meta = {
        "study": study,
        # what the study declares for its report (studies/contact_gamma0.py REPORT)
        **({"report": {"force_log_scale": True, "interpolation": True, "speed_against_error": False}}
           if study == "contact_gamma0" else {}),
        "title": {"three_point_bending": "Three-point bending with an indenter",
                  "contact_gamma0": "Contact through the third medium: effect of gamma0"}.get(
                      study, study.replace("_", " ")),
        "summary_text": "Synthetic run written by tests/report_fixtures.py: the numbers imitate "
                        "the study but come from closed-form curves, not from a simulation.",
        "resolution": resolution,
        "created": "2026-11-22T05:00:00+00:00",
        "status": status,
        "versions": {"ngtmc": "0.1.0", "ngsolve": "6.2.2608", "python": "3.11.7",
                     "numpy": np.__version__},
        "git_revision": "abc1234",
        "units": {"length": "mm", "force": "N", "stress": "MPa", "energy": "N mm", "time": "s"},
        "thickness_mm": 1.0,
        "force_unit": "N/mm",
        "parameters": {
            "E": {"value": 20800.0, "unit": "MPa", "description": "Young's modulus"},
            "nu": {"value": 0.3, "unit": "-", "description": "Poisson's ratio"},
            "Gc": {"value": 0.54, "unit": "N/mm", "description": "critical energy release rate"},
            "l0": {"value": 0.03, "unit": "mm", "description": "phase-field length scale"},
            "gamma0": {"value": 5e-6, "unit": "-", "description": "void stiffness ratio"},
            "gap": {"value": GAP, "unit": "mm", "description": "indenter gap l_h"},
        },
        "mesh": {"n_elements": int(n_elements if n_elements is not None else len(triangles)),
                 "n_vertices": int(len(vertices)), "ndof_u": 2 * len(vertices) * 4,
                 "ndof_alpha": int(len(vertices)) if fracture else 0, "h_min": 0.0075, "h_max": 0.5},
        "wall_time_s": float(wall_time_s if wall_time_s is not None else t0),
        "cases": [{"name": n, "label": lab, "parameters": p} for n, lab, _, p in cases],
    }
    if overrides is not None:
        meta["overrides"] = dict(overrides)
    if physics_hash is not None:
        meta["physics_hash"] = physics_hash
    if with_references:
        meta["references"] = [
            {"label": "Ambati et al. 2015, Fig. 22 (shifted by the gap)", "source": "synthetic",
             "kind": "curve", "x": ref_x.tolist(),
             "y": (force_curve(ref_x, 1.0) / 1000 * 1.05).tolist(),
             "x_unit": "mm", "y_unit": "kN/mm"},
            {"label": "Experiments (band)", "source": "synthetic", "kind": "band",
             "x": ref_x.tolist(), "y_lower": (force_curve(ref_x) * 0.9).tolist(),
             "y_upper": (force_curve(ref_x) * 1.1).tolist(), "x_unit": "mm", "y_unit": "N/mm"},
        ]
    if with_targets:
        first = cases[0][0]
        meta["targets"] = [
            {"case": first, "quantity": "peak_force", "value": PEAK_FORCE, "unit": "N/mm",
             "source": "Ambati 2015", "tolerance": 0.15},
            {"case": first, "quantity": "peak_load", "value": PEAK_LOAD, "unit": "mm",
             "source": "Ambati 2015 + gap", "tolerance": 0.10},
        ]
        if len(cases) > 1:
            meta["targets"].append({"case": cases[1][0], "quantity": "peak_force",
                                    "value": 0.042, "unit": "kN/mm", "source": "Ambati 2015",
                                    "tolerance": 0.01})
    if with_results:
        meta["results"] = results
    (path / "metadata.json").write_text(json.dumps(meta, indent=2), encoding="utf-8")
    return path


def page_json(page: str, block: str) -> dict:
    """The JSON data block ``block`` ("fig-data", "mesh-data") of a rendered report page."""
    m = re.search(rf'<script type="application/json" id="{block}">(.*?)</script>', page, re.S)
    assert m, f"{block} block missing"
    return json.loads(m.group(1))
