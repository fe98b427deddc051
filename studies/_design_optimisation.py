"""The optimisation of the design-for-contact study (``studies/design_for_contact.py``, whose
docstring states the problem and the measured results): the filtered pad densities
(:func:`density_filter`), the objective and its adjoint gradient (:class:`DesignProblem`), the
sequential linear programming (:func:`optimise`) and the run folder of an optimisation
(:func:`run`: history, designs, optimisation.csv and .html, snapshots, metadata, report).

The scene, its load path and its parameters are the study's: they are taken from the study module
when needed. Units: mm, N, MPa; forces and energies per mm of thickness.

The file name starts with an underscore: it is a helper, not a study.
"""
from __future__ import annotations

import time
from pathlib import Path as _FsPath

import numpy as np
import pandas as pd
import ngsolve as ngs

import ngtmc
from ngtmc import sensitivities as sens
from ngtmc.simulation import force_unit
from ngtmc.study import write_atomic, write_json, write_npz
from ngtmc.study import run_description


def _study():
    """The study module (its scene, load path, parameters and description)."""
    from ngtmc.studies import design_for_contact
    return design_for_contact


def _pad_mask(mesh) -> np.ndarray:
    mats = mesh.GetMaterials()
    return np.array([mats[el.index] == "pad" for el in mesh.Elements(ngs.VOL)])


def _centroids_and_areas(mesh):
    pts = np.asarray(mesh.ngmesh.Coordinates())
    tri = mesh.ngmesh.Elements2D().NumPy()["nodes"][:, :3].astype(int) - 1
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    area = 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    return (a + b + c) / 3.0, area


def density_filter(centroids: np.ndarray, areas: np.ndarray, radius: float) -> np.ndarray:
    """Filter matrix W (rows sum to 1): rho = W x with hat weights max(0, r - |c_i - c_j|) |e_j|."""
    d = np.linalg.norm(centroids[:, None, :] - centroids[None, :, :], axis=2)
    w = np.maximum(0.0, radius - d) * areas[None, :]
    return w / w.sum(axis=1, keepdims=True)


class DesignProblem:
    """W(x) and dW/dx for the filtered pad densities x (one per pad element).

    ``evaluate(x) -> (W, dW/dx, path)``; caches the last design."""

    def __init__(self, p: dict, mesh: ngs.Mesh | None = None):
        self.p = p
        _study().check_parameters(p)
        self.mesh = mesh if mesh is not None else _study().build_mesh(p)
        self.mask = _pad_mask(self.mesh)
        cen, area = _centroids_and_areas(self.mesh)
        self.centroids, self.areas = cen, area
        self.filter = density_filter(cen[self.mask], area[self.mask], p["filter_radius"])
        self.pad_area = float(area[self.mask].sum())
        self.objective = sens.ExternalWork()
        self._cache = {}
        self.evaluations = []
        self.failure = None
        self.rejected = 0

    def rho(self, x):
        rho = np.where(self.mask, 0.0, 1.0)
        rho[self.mask] = self.filter @ np.asarray(x, dtype=float)
        return rho

    def volume(self, x):
        """Filler volume fraction of the pad, sum |e| rho_e / |pad|."""
        return float(self.areas[self.mask] @ (self.filter @ x)) / self.pad_area

    def volume_gradient(self):
        return self.filter.T @ self.areas[self.mask] / self.pad_area

    def evaluate(self, x):
        key = np.asarray(x, dtype=float).tobytes()
        if key in self._cache:
            return self._cache[key]
        t0 = time.perf_counter()
        S = _study()
        scene = S.build_scene(self.p, mesh=self.mesh, rho=self.rho(x))
        path = sens.record_path(scene, S.schedule(self.p), S.control(self.p), newton=S.newton_options())
        g = sens.gradient(path, self.objective, wrt=("rho",))
        dWdx = self.filter.T @ g["rho"][self.mask]
        out = (g["value"], dWdx, path)
        self._cache = {key: out}
        self.evaluations.append({"W": g["value"], "forward_time": path.forward_time, "gradient_time": g["time"],
                                 "wall": time.perf_counter() - t0})
        return out


def optimise(p: dict, iterations: int | None = None, callback=None):
    """Sequential linear programming with an adaptive move limit; returns (problem, log).

    Each iteration solves the linear program (scipy.optimize.linprog, HiGHS)

        maximise dW/dx . y   s.t.   volume(y) <= v_f,   max(0, x - m) <= y <= min(1, x + m)

    (the volume is linear in x), runs the forward path and the adjoint of the candidate y, and
    accepts it if W increased; otherwise, or if the forward run fails (Newton at the minimum step,
    which a trial design may provoke when its crack runs), the move limit m is halved and the LP
    solved again. After an accepted step m grows by 1.5 (up to ``move_limit``). ``log`` holds one
    dict per accepted iteration (x, W, volume, path, time); ``problem.rejected`` counts rejected
    trials and ``problem.failure`` the last failure message."""
    from scipy.optimize import linprog

    prob = DesignProblem(p)
    n = int(prob.mask.sum())
    x = np.full(n, float(p["initial_fill"]))
    W, g, path = prob.evaluate(x)
    log = [{"iteration": 0, "x": x.copy(), "W": W, "volume": prob.volume(x), "path": path, "time": time.perf_counter()}]
    vg = prob.volume_gradient()
    m_max = float(p["move_limit"])
    m = m_max
    prob.rejected = 0
    for _ in range(int(iterations or p["iterations"])):
        accepted = False
        while m >= m_max / 64:
            lo, hi = np.maximum(0.0, x - m), np.minimum(1.0, x + m)
            lp = linprog(-g, A_ub=vg[None, :], b_ub=[p["volume_fraction"]], bounds=list(zip(lo, hi)), method="highs")
            y = np.clip(lp.x, lo, hi) if lp.success else x
            try:
                Wy, gy, py = prob.evaluate(y)
            except (ngtmc.StepFailure, RuntimeError) as e:
                prob.failure = str(e)
                Wy = -np.inf
            if Wy > W:
                x, W, g, path = y, Wy, gy, py
                m = min(1.5 * m, m_max)
                accepted = True
                break
            prob.rejected += 1
            m /= 2
        if not accepted:
            break
        log.append({"iteration": len(log), "x": x.copy(), "W": W, "volume": prob.volume(x), "path": path,
                    "time": time.perf_counter()})
        if callback:
            callback(log[-1])
    return prob, log


def _vertex_fields(path, n):
    """u (nv, 2) and alpha (nv,) at the mesh vertices for state n of a path (alpha 0 without a
    phase field, and off the regions that may break)."""
    path.activate(n)
    s = path.solver
    mesh = s.mesh
    pts = np.asarray(mesh.ngmesh.Coordinates())
    nv = mesh.nv
    u = np.column_stack([s.u.components[i].vec.FV().NumPy()[:nv] for i in range(2)])
    a = np.zeros(nv) if s.alpha is None else np.asarray(s.alpha(mesh(pts[:, 0], pts[:, 1]))).ravel()
    return u, np.clip(np.nan_to_num(a), 0.0, 1.0)


def path_snapshot(path, rho=None, frames: int = 4) -> dict:
    """The fields of a recorded path (2D) at ``frames`` evenly spaced states, the last one
    included, in the run-directory snapshot format: vertices, triangles, rho (default the path's),
    loads (mm), u (mm) and alpha at the vertices."""
    mesh = path.solver.mesh
    pts = np.asarray(mesh.ngmesh.Coordinates())
    tri = mesh.ngmesh.Elements2D().NumPy()["nodes"][:, :3].astype(int) - 1
    idx = sorted({int(round(i)) for i in np.linspace(1, path.n_steps, frames)})
    us, als = zip(*[_vertex_fields(path, n) for n in idx])
    path.activate()
    return {"vertices": pts, "triangles": tri, "rho": np.asarray(path.rho if rho is None else rho),
            "loads": path.loads[idx], "u": np.array(us), "alpha": np.array(als)}


def write_snapshots(out, cases: dict, n_frames: int = 4):
    """snapshots.npz in the run-directory format for {case: path} (frames at evenly spaced states)."""
    arrays = {}
    for case, path in cases.items():
        arrays.update({f"{case}__{k}": v for k, v in path_snapshot(path, frames=n_frames).items()})
    write_npz(_FsPath(out) / "snapshots.npz", arrays)


def write_optimisation_page(out) -> _FsPath | None:
    """optimisation.html (self-contained, plotly): objective against iteration, the pad design at the
    saved iterations, force against displacement of the initial and final designs. Returns its
    path, or None if plotly is missing."""
    try:
        import plotly.graph_objects as go
        from plotly.subplots import make_subplots
    except ImportError:  # pragma: no cover
        return None
    out = _FsPath(out)
    opt = pd.read_csv(out / "optimisation.csv")
    hist = pd.read_csv(out / "history.csv")
    des = np.load(out / "designs.npz")
    k = len(des["iterations"])
    fig = make_subplots(rows=2 + k, cols=1, row_heights=[0.3, 0.3] + [0.4 / k] * k, vertical_spacing=0.06,
                        subplot_titles=["objective W (external work, N mm) against iteration",
                                        "force against displacement (N per mm thickness)"]
                        + [f"pad density, iteration {int(i)} (W = {w:.4g} N mm)" for i, w in
                           zip(des["iterations"], des["objective"])])
    fig.add_trace(go.Scatter(x=opt["iteration"], y=opt["objective_W"], mode="lines+markers", name="W"), row=1, col=1)
    for case in ("initial", "final"):
        h = hist[hist["case"] == case]
        fig.add_trace(go.Scatter(x=h["load"], y=h["force"], mode="lines+markers", name=f"{case} design"), row=2, col=1)
    mask = des["pad_mask"]
    c = des["centroids"][mask]
    vmax = float(max(des["rho"][:, mask].max(), 1e-12))
    for j in range(k):
        fig.add_trace(go.Scatter(x=c[:, 0], y=c[:, 1], mode="markers", showlegend=False,
                                 marker=dict(color=des["rho"][j][mask], cmin=0, cmax=vmax, colorscale="Viridis", size=9,
                                             symbol="square", showscale=(j == 0),
                                             colorbar=dict(title="rho", len=0.35, y=0.2))), row=3 + j, col=1)
    fig.update_xaxes(title_text="iteration", row=1, col=1)
    fig.update_xaxes(title_text="imposed displacement (mm)", row=2, col=1)
    fig.update_layout(height=450 + 250 * k, width=900, title=_study().TITLE)
    page = out / "optimisation.html"
    fig.write_html(page, include_plotlyjs=True, full_html=True)
    return page


def _history_rows(case: str, path) -> pd.DataFrame:
    h = path.history.copy()
    h.insert(0, "case", case)
    return h


def run_metadata(p: dict, resolution: str, overrides: dict | None, mesh: dict, cases: list[dict], results: dict,
                 wall_time_s: float) -> dict:
    """metadata.json of an optimisation run in the run-folder schema of ``ngtmc.study.run_files``: the
    common description of a run (:func:`ngtmc.study.parameters.run_description`: schema version, versions,
    units, every parameter with its unit, overrides, parameter hashes, process), then this run's
    mesh (elements, vertices, design elements), cases, results and wall time (s)."""
    S = _study()
    return {
        **run_description(S, p, resolution, overrides),
        "created": pd.Timestamp.now(tz="UTC").isoformat(), "status": "completed",
        "thickness_mm": p["thickness"], "force_unit": force_unit(2, p["thickness"]),
        "resolution_values": S.RESOLUTIONS[resolution],
        "mesh": mesh, "wall_time_s": wall_time_s, "cases": cases,
        "references": S.references(p), "targets": S.targets(p), "results": results,
        "notes": "optimisation study: cases() gives only the initial design; run() writes optimisation.csv and designs.npz",
    }


def run(out_dir, resolution: str | None = None, overrides: dict | None = None, report: bool = True) -> _FsPath:
    """Run the optimisation and write the run folder (see the module docstring): metadata.json,
    history.csv (cases initial and final), snapshots.npz, optimisation.csv, designs.npz,
    optimisation.html (objective against iteration, designs, force curves) and report.html (the
    package's report of the two force curves, if it renders). Returns its path."""
    from ngtmc import runner

    S = _study()
    resolution = resolution or S.DEFAULT_RESOLUTION
    out = _FsPath(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    p = S._params(resolution, **(overrides or {}))
    t0 = time.perf_counter()
    prob, log = optimise(p)
    first, last = log[0], max(log, key=lambda r: r["W"] if r["volume"] <= p["volume_fraction"] + 1e-6 else -np.inf)
    hist = pd.concat([_history_rows("initial", first["path"]), _history_rows("final", last["path"])], ignore_index=True)
    cols = [c for c in runner.HISTORY_COLUMNS if c in hist.columns]
    write_atomic(out / "history.csv", hist[cols].to_csv(index=False))
    opt = pd.DataFrame({"iteration": [r["iteration"] for r in log], "objective_W": [r["W"] for r in log],
                        "volume_fraction": [r["volume"] for r in log],
                        "wall_time": [r["time"] - t0 for r in log]})
    write_atomic(out / "optimisation.csv", opt.to_csv(index=False))
    keep = sorted({0, len(log) // 2, len(log) - 1, last["iteration"]})
    write_npz(out / "designs.npz", {"centroids": prob.centroids, "areas": prob.areas, "pad_mask": prob.mask,
                                    "iterations": np.array(keep), "rho": np.array([prob.rho(log[i]["x"]) for i in keep]),
                                    "objective": np.array([log[i]["W"] for i in keep])})
    ev = pd.DataFrame(prob.evaluations)
    results = {
        "initial": runner.case_results(_history_rows("initial", first["path"])),
        "final": runner.case_results(_history_rows("final", last["path"])),
        "optimisation": {"W_initial": first["W"], "W_final": last["W"],
                         "improvement": last["W"] / first["W"] - 1.0, "iterations": len(log) - 1,
                         "evaluations": len(prob.evaluations), "rejected_trials": prob.rejected,
                         "last_failure": prob.failure,
                         "mean_forward_time_s": float(ev["forward_time"].mean()),
                         "mean_gradient_time_s": float(ev["gradient_time"].mean())},
    }
    mesh = {"n_elements": prob.mesh.ne, "n_vertices": prob.mesh.nv, "n_design": int(prob.mask.sum())}
    cases = [{"name": "initial", "label": "initial design", "parameters": {}},
             {"name": "final", "label": f"optimised design (iteration {last['iteration']})", "parameters": {}}]
    write_json(out / "metadata.json", run_metadata(p, resolution, overrides, mesh, cases, results,
                                                   time.perf_counter() - t0))
    write_snapshots(out, {"initial": first["path"], "final": last["path"]})
    write_optimisation_page(out)
    if report:
        try:
            from ngtmc.report import render_report
            render_report(out)
        except Exception as e:  # the report is optional; the run's files are complete
            print(f"[design_for_contact] report not rendered: {type(e).__name__}: {e}")
    return out
