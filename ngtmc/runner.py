"""Run a named study into a run folder (the format of ``docs/run-directory.md``).

    >>> import ngtmc
    >>> run_dir = ngtmc.run_study("three_point_bending", resolution="quick")   # doctest: +SKIP

One folder per run holds ``metadata.json``, ``history.csv`` (one row per accepted step, per case),
``snapshots.npz`` (u, alpha at the vertices and rho per triangle at chosen loads), ``vtk/``
(ParaView series), ``checkpoint/`` (to resume) and, if the report module is available,
``report.html``.

Every file is written to a temporary file and moved into place with ``os.replace``, so a crash never
leaves a truncated history or metadata behind. Checkpoints (``checkpoint/<case>.npz``: the
Simulation state, the history rows and the snapshots of that case) are written every
``checkpoint_every`` accepted steps or ``checkpoint_seconds`` seconds, whichever comes first, and
when a run is interrupted or fails. ``run_study(..., resume=True)`` continues from them and gives
the same history as an uninterrupted run (wall and solve times aside).

A failed run (:class:`ngtmc.StepFailure`) still writes its history and metadata, with status
``"failed"`` and the error message, and then re-raises. An interrupted run (KeyboardInterrupt)
gets status ``"interrupted"``.
"""
from __future__ import annotations

import datetime as _dt
import io
import json
import math
import os
from pathlib import Path
import platform
import subprocess
import sys
import tempfile
import time
from types import ModuleType
from typing import Callable, Sequence

import numpy as np
import pandas as pd

from .scene import _names
from .study import Case, StudyError, load_study, normalise_name, study_parameters
from .vtk import VtkWriter, write_pvd

__all__ = ["run_study", "default_output", "HISTORY_COLUMNS", "case_results", "write_atomic"]

#: Columns of history.csv, in order (``case`` first, then the Simulation's history columns).
HISTORY_COLUMNS = ["case", "step", "load", "force", "fracture_energy", "dissipated_energy", "elastic_energy",
                   "regularisation_energy", "max_alpha", "min_J", "newton_iterations", "staggered_iterations",
                   "cutbacks", "alpha_projected", "step_size", "wall_time", "solve_time", "assembly_time"]

_UMASK = os.umask(0)
os.umask(_UMASK)

_UNITS = {"length": "mm", "force": "N", "stress": "MPa", "energy": "N mm", "time": "s"}


# ====================================================================== atomic file output
def write_atomic(path, data: bytes | str):
    """Write ``data`` to ``path`` through a temporary file in the same folder and ``os.replace``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix="." + path.name + ".", suffix=".tmp")
    try:
        os.chmod(tmp, 0o666 & ~_UMASK)     # mkstemp creates 0600; give the file the usual permissions
        with os.fdopen(fd, "wb") as f:
            f.write(data.encode() if isinstance(data, str) else data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _write_json(path, obj):
    write_atomic(path, json.dumps(_jsonable(obj), indent=2, allow_nan=False) + "\n")


def _write_npz(path, arrays: dict):
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    write_atomic(path, buf.getvalue())


def _jsonable(x, other=str):
    """Plain JSON types; non-finite floats become null; any other object becomes ``other(x)``."""
    if isinstance(x, dict):
        return {str(k): _jsonable(v, other) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v, other) for v in x]
    if isinstance(x, np.ndarray):
        return [_jsonable(v, other) for v in x.tolist()]
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (float, np.floating)):
        x = float(x)
        return x if math.isfinite(x) else None
    if x is None or isinstance(x, (int, str)):
        return x
    return other(x)


# ====================================================================== metadata pieces
def _versions() -> dict:
    from . import __version__
    v = {"ngtmc": __version__, "python": platform.python_version(), "numpy": np.__version__, "pandas": pd.__version__}
    try:
        import ngsolve
        v["ngsolve"] = ngsolve.__version__
    except Exception:  # pragma: no cover
        pass
    try:
        import netgen
        v["netgen"] = getattr(netgen, "__version__", None) or getattr(netgen, "version", None)
    except Exception:  # pragma: no cover
        pass
    try:
        import scipy
        v["scipy"] = scipy.__version__
    except Exception:  # pragma: no cover
        pass
    return {k: str(val) for k, val in v.items() if val is not None}


def _git_revision() -> str | None:
    here = Path(__file__).resolve().parent
    try:
        rev = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], cwd=here, capture_output=True,
                             text=True, timeout=10)
        if rev.returncode != 0:
            return None
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", "."],
                               cwd=here.parent, capture_output=True, text=True, timeout=10)
        suffix = "-dirty" if dirty.returncode == 0 and dirty.stdout.strip() else ""
        return rev.stdout.strip() + suffix
    except Exception:
        return None


def _guess_unit(key: str) -> str:
    if key == "h" or key.startswith("h_") or key.startswith("du_") or key.endswith("_load"):
        return "mm"
    return "-"


def _parameter_table(mod: ModuleType, p: dict) -> dict:
    """Every parameter with value, unit, description: PARAMETERS, resolution keys, then anything else."""
    res_desc = getattr(mod, "RESOLUTION_PARAMETERS", {})
    out = {}
    for k, (_, unit, desc) in mod.PARAMETERS.items():
        out[k] = {"value": p.get(k), "unit": unit, "description": desc}
    for k, v in p.items():
        if k in out:
            continue
        unit, desc = res_desc.get(k, (_guess_unit(k), "mesh or step size (set by the resolution)"))
        out[k] = {"value": v, "unit": unit, "description": desc}
    return out


def _mesh_info(solver) -> dict:
    mesh = solver.mesh
    h = solver.h if getattr(solver, "h", None) is not None else solver.scene.element_sizes()
    nd = solver.ndof
    return {"n_elements": int(mesh.ne), "n_vertices": int(mesh.nv), "ndof_u": int(nd["u"]),
            "ndof_alpha": int(nd["alpha"]), "h_min": float(np.min(h)), "h_max": float(np.max(h)),
            "displacement_order": (f"{solver.order} in {', '.join(_names(solver.scene.regulariser.regions))}, 1 elsewhere"
                                   if solver._variable_order else int(solver.order))}


def case_results(rows: pd.DataFrame) -> dict:
    """Key numbers of one case's history: peak force and its load, steps, Newton iterations, times."""
    if rows is None or len(rows) == 0:
        return {"peak_force": None, "peak_load": None, "steps": 0}
    f = rows["force"].to_numpy(dtype=float)
    i = int(np.nanargmax(f)) if np.any(np.isfinite(f)) else 0
    out = {"peak_force": float(f[i]), "peak_load": float(rows["load"].iloc[i]),
           "steps": int(rows["step"].max()) if "step" in rows else len(rows) - 1,
           "final_load": float(rows["load"].iloc[-1])}
    for col, key in (("newton_iterations", "newton_iterations"), ("cutbacks", "cutbacks")):
        if col in rows and rows[col].notna().any():
            out[key] = int(rows[col].fillna(0).sum())
    if "wall_time" in rows and rows["wall_time"].notna().any():
        out["wall_time_s"] = float(rows["wall_time"].max())
    if "solve_time" in rows and rows["solve_time"].notna().any():
        out["solve_time_s"] = float(rows["solve_time"].fillna(0).sum())
    if "step_size" in rows and len(rows) > 1:
        ds = rows["step_size"].iloc[1:].to_numpy(dtype=float)
        ds = ds[ds > 0]
        if ds.size:
            out["min_step_size"] = float(ds.min())
    return out


def default_output(study: str, resolution: str, base: str | Path = "reports") -> Path:
    """``reports/<study>-<resolution>``; if that folder holds a run already, a time-stamped sibling."""
    d = Path(base) / f"{study}-{resolution}"
    if d.exists() and any(d.iterdir()):
        stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S")
        d = Path(base) / f"{study}-{resolution}-{stamp}"
        k = 1
        while d.exists():
            k += 1
            d = Path(base) / f"{study}-{resolution}-{stamp}-{k}"
    return d


def _latest_run(study: str, resolution: str, base: str | Path = "reports") -> Path | None:
    base = Path(base)
    if not base.is_dir():
        return None
    cands = [d for d in base.glob(f"{study}-{resolution}*") if (d / "checkpoint").is_dir()]
    return max(cands, key=lambda d: d.stat().st_mtime) if cands else None


# ====================================================================== progress
class _Progress:
    """Progress line on stderr about every ``interval`` seconds (and at the end of each case)."""

    def __init__(self, enabled, study: str, n_cases: int, interval: float = 5.0):
        self.enabled = enabled
        self.study = study
        self.n_cases = n_cases
        self.interval = interval
        self.last = -1e9

    def say(self, text: str):
        if self.enabled:
            print(f"[ngtmc {self.study}] {text}", file=sys.stderr, flush=True)

    def step(self, k: int, case: str, sim, row: dict, force_print: bool = False):
        if not self.enabled:
            return
        if callable(self.enabled) and not isinstance(self.enabled, bool):
            self.enabled(dict(row, case=case))
            return
        now = time.perf_counter()
        if not force_print and now - self.last < self.interval:
            return
        self.last = now
        total = sim.schedule.total_time
        frac = sim.t / total if total > 0 else 1.0
        el = float(row.get("wall_time", 0.0))
        eta = ""
        if 0.02 < frac < 1.0 and el > 0:
            eta = f", about {el * (1 - frac) / frac:.0f} s left in this case at this pace"
        print(f"[ngtmc {self.study}] case {k + 1}/{self.n_cases} {case}: step {row['step']:5d}  "
              f"load {row['load']:.6g} mm  du {row['step_size']:.2e} mm  force {row['force']:.5g}  "
              f"Newton {row['newton_iterations']}  cut-backs {row['cutbacks']}  {100 * frac:5.1f} %  "
              f"{el:.0f} s{eta}", file=sys.stderr, flush=True)


# ====================================================================== snapshots
class _Snapshots:
    """Fields of one case at the first accepted step at or past each chosen load."""

    def __init__(self, case: Case, solver, vtk_dir: Path | None):
        self.case = case
        self.targets = [float(x) for x in case.snapshot_loads]
        self.pending = list(range(len(self.targets)))
        self.loads: list[float] = []
        self.steps: list[int] = []
        self.u: list[np.ndarray] = []
        self.alpha: list[np.ndarray] = []
        self.solver = solver
        self.vtk_dir = vtk_dir
        mesh = solver.mesh
        self.nv = mesh.nv
        self.dim = mesh.dim
        ng = mesh.ngmesh
        self.vertices = np.asarray(ng.Coordinates(), dtype=float)[:, :self.dim].copy()
        if self.dim == 2:
            tri = ng.Elements2D().NumPy()["nodes"][:, :3].astype(np.int64) - 1
        else:
            # boundary triangles of the 3D mesh
            tri = ng.Elements2D().NumPy()["nodes"][:, :3].astype(np.int64) - 1
        self.triangles = tri
        rho = solver.rho.vec.FV().NumPy().copy()
        self.rho = rho if self.dim == 2 else np.ones(len(tri))
        self._vtk = None

    def restore(self, data: dict):
        self.loads = list(np.asarray(data["loads"], dtype=float))
        self.steps = list(np.asarray(data["steps"], dtype=int))
        self.u = list(np.asarray(data["u"], dtype=float))
        self.alpha = list(np.asarray(data["alpha"], dtype=float))
        self.pending = [int(i) for i in np.asarray(data["pending"], dtype=int)]

    def state(self) -> dict:
        k = len(self.loads)
        return {"loads": np.asarray(self.loads, dtype=float), "steps": np.asarray(self.steps, dtype=int),
                "u": np.asarray(self.u, dtype=float).reshape(k, self.nv, self.dim),
                "alpha": np.asarray(self.alpha, dtype=float).reshape(k, self.nv),
                "pending": np.asarray(self.pending, dtype=int)}

    def vertex_fields(self):
        s = self.solver
        u = np.stack([s.u.components[i].vec.FV().NumPy()[:self.nv].copy() for i in range(self.dim)], axis=1)
        if s.alpha is not None:
            a = s.alpha.vec.FV().NumPy()[:self.nv].copy()
        else:
            a = np.zeros(self.nv)
        return u, a

    def maybe_take(self, prev_load: float, row: dict, final: bool = False):
        load = float(row["load"])
        hit = []
        for i in self.pending:
            x = self.targets[i]
            if (prev_load - x) * (load - x) <= 0.0 and load != prev_load or abs(load - x) <= 1e-12 * max(1.0, abs(x)):
                hit.append(i)
            else:
                break  # targets are taken in the order given
        if hit:
            self.pending = [i for i in self.pending if i not in hit]
        if hit or (final and (not self.steps or self.steps[-1] != int(row["step"]))):
            self.take(row)

    def take(self, row: dict):
        u, a = self.vertex_fields()
        self.loads.append(float(row["load"]))
        self.steps.append(int(row["step"]))
        self.u.append(u)
        self.alpha.append(a)
        self.write_vtk(len(self.loads) - 1, float(row["load"]))

    def arrays(self, name: str) -> dict:
        st = self.state()
        return {f"{name}__vertices": self.vertices, f"{name}__triangles": self.triangles,
                f"{name}__rho": self.rho, f"{name}__loads": st["loads"], f"{name}__steps": st["steps"],
                f"{name}__u": st["u"], f"{name}__alpha": st["alpha"]}

    def write_vtk(self, k: int, load: float):
        """Write snapshot ``k`` (the solver's current state) as ``vtk/<case>_<k>.vtu`` (fields of
        :mod:`ngtmc.vtk`) and update the series ``vtk/<case>.pvd``."""
        if self.vtk_dir is None:
            return
        try:
            if self._vtk is None:
                self._vtk = VtkWriter(self.solver)
            self._vtk.write(self.vtk_dir / f"{self.case.name}_{k:04d}.vtu")
            self.write_pvd()
        except Exception as e:  # VTK output is a convenience: never let it kill a run
            print(f"[ngtmc] VTK output failed: {e}", file=sys.stderr)

    def write_pvd(self):
        """The series ``vtk/<case>.pvd`` of the snapshots written so far, the load (mm) as time."""
        if self.vtk_dir is None:
            return
        files = [(load, f"{self.case.name}_{k:04d}.vtu") for k, load in enumerate(self.loads)]
        write_pvd(self.vtk_dir / f"{self.case.name}.pvd", [(load, f) for load, f in files if (self.vtk_dir / f).exists()])


# ====================================================================== the run
class _Run:
    def __init__(self, mod, resolution, p, out: Path, overrides, progress, checkpoint_every, checkpoint_seconds,
                 callbacks, vtk):
        self.mod = mod
        self.resolution = resolution
        self.p = p
        self.out = out
        self.overrides = dict(overrides or {})
        self.checkpoint_every = int(checkpoint_every)
        self.checkpoint_seconds = float(checkpoint_seconds)
        self.callbacks = list(callbacks or [])
        self.vtk = vtk
        self.cases: list[Case] = list(mod.cases(p))
        names = [c.name for c in self.cases]
        if len(set(names)) != len(names):
            raise StudyError(f"study {mod.NAME!r}: case names are not unique: {names}")
        self.progress = _Progress(progress, mod.NAME, len(self.cases))
        self.rows: dict[str, list[dict]] = {}
        self.snaps: dict[str, dict] = {}      # case -> arrays for snapshots.npz
        self.results: dict[str, dict] = {}
        self.case_meta: dict[str, dict] = {}
        self.mesh = None
        self.status = "running"
        self.error = None
        self.t0 = time.perf_counter()
        self.wall_before = 0.0
        self.created = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")

    # ------------------------------------------------------------ files
    @property
    def ckpt_dir(self) -> Path:
        return self.out / "checkpoint"

    def wall_time(self) -> float:
        return self.wall_before + time.perf_counter() - self.t0

    def history_frame(self) -> pd.DataFrame:
        frames = []
        for c in self.cases:
            rows = self.rows.get(c.name)
            if rows:
                df = pd.DataFrame(rows)
                df.insert(0, "case", c.name)
                frames.append(df)
        if not frames:
            return pd.DataFrame(columns=HISTORY_COLUMNS)
        df = pd.concat(frames, ignore_index=True)
        cols = [c for c in HISTORY_COLUMNS if c in df.columns] + [c for c in df.columns if c not in HISTORY_COLUMNS]
        for c in HISTORY_COLUMNS:
            if c not in df.columns:
                df[c] = np.nan
        return df[[c for c in HISTORY_COLUMNS] + [c for c in cols if c not in HISTORY_COLUMNS]]

    def write_history(self):
        write_atomic(self.out / "history.csv", self.history_frame().to_csv(index=False, float_format="%.10g"))

    def write_snapshots(self):
        arrays = {}
        for name, a in self.snaps.items():
            arrays.update(a)
        if arrays:
            _write_npz(self.out / "snapshots.npz", arrays)

    def metadata(self) -> dict:
        mod, p = self.mod, self.p
        thickness = float(p.get("thickness", 1.0))
        dim = 2 if self.mesh is None else self.mesh.get("dim", 2)
        meta = {
            "study": mod.NAME,
            "title": getattr(mod, "TITLE", mod.NAME),
            "summary_text": getattr(mod, "SUMMARY", ""),
            "resolution": self.resolution,
            "created": self.created,
            "status": self.status,
            "versions": _versions(),
            "git_revision": _git_revision(),
            "units": dict(_UNITS),
            "thickness_mm": thickness,
            "force_unit": "N/mm" if dim == 2 else "N",
            "parameters": _parameter_table(mod, p),
            "overrides": self.overrides,
            "mesh": {k: v for k, v in (self.mesh or {}).items() if k != "dim"},
            "wall_time_s": self.wall_time(),
            "cases": [dict(name=c.name, label=c.label, parameters=c.parameters, **self.case_meta.get(c.name, {}))
                      for c in self.cases],
            "references": list(mod.references(p)) if hasattr(mod, "references") else [],
            "targets": list(mod.targets(p)) if hasattr(mod, "targets") else [],
            "results": self.study_results(),
            "cpu_time_s": time.process_time(),
            "command": " ".join(sys.argv) if sys.argv and sys.argv[0] else None,
            "host": {"platform": platform.platform(), "cpu_count": os.cpu_count(),
                     "threads": _threads()},
        }
        if self.error:
            meta["error"] = self.error
        return meta

    def study_results(self) -> dict:
        """Per-case results, passed through the study's optional ``post_results(p, history, results)``."""
        results = json.loads(json.dumps(_jsonable(self.results)))
        hook = getattr(self.mod, "post_results", None)
        if hook is not None and results:
            try:
                results = hook(self.p, self.history_frame(), results) or results
            except Exception as e:  # a post-processing error must not lose the run's files
                print(f"[ngtmc] {self.mod.NAME}.post_results failed: {type(e).__name__}: {e}", file=sys.stderr)
        return results

    def write_metadata(self):
        _write_json(self.out / "metadata.json", self.metadata())

    def write_all(self):
        self.write_history()
        self.write_snapshots()
        self.write_metadata()

    # ------------------------------------------------------------ checkpoints
    def save_checkpoint(self, case: Case, state: dict, snaps: _Snapshots | None, done: bool):
        arrays = {"done": np.array(bool(done)), "rows": np.array(json.dumps(_jsonable(state["rows"]))),
                  "results": np.array(json.dumps(_jsonable(self.results.get(case.name, {})))),
                  "case_meta": np.array(json.dumps(_jsonable(self.case_meta.get(case.name, {}))))}
        if not done:
            for k, v in state["solver"].items():
                arrays["solver__" + k] = np.asarray(v)
            arrays["scalars"] = np.array([state["t"], state["step"], state["last_delta_wf"], state["wf_prev"],
                                          state["elapsed"]], dtype=float)
            arrays["control"] = np.array(json.dumps(state["control"]))
        if snaps is not None:
            for k, v in snaps.state().items():
                arrays["snap__" + k] = v
            for k, v in snaps.arrays(case.name).items():
                arrays["snaparr__" + k] = v
        _write_npz(self.ckpt_dir / f"{case.name}.npz", arrays)

    def load_checkpoint(self, case: Case) -> dict | None:
        f = self.ckpt_dir / f"{case.name}.npz"
        if not f.exists():
            return None
        with np.load(f, allow_pickle=False) as z:
            d = {k: z[k] for k in z.files}
        ck = {"done": bool(d["done"]), "rows": json.loads(str(d["rows"])),
              "results": json.loads(str(d["results"])), "case_meta": json.loads(str(d["case_meta"]))}
        if not ck["done"]:
            sc = d["scalars"]
            ck["state"] = {"solver": {k[len("solver__"):]: v for k, v in d.items() if k.startswith("solver__")},
                           "t": float(sc[0]), "step": int(sc[1]), "last_delta_wf": float(sc[2]),
                           "wf_prev": float(sc[3]), "elapsed": float(sc[4]),
                           "control": json.loads(str(d["control"])), "rows": ck["rows"]}
        ck["snap"] = {k[len("snap__"):]: v for k, v in d.items() if k.startswith("snap__")}
        ck["snaparr"] = {k[len("snaparr__"):]: v for k, v in d.items() if k.startswith("snaparr__")}
        return ck

    # ------------------------------------------------------------ one case
    def run_case(self, k: int, case: Case, resume: bool):
        import ngsolve as ngs
        from .simulation import Simulation, StepFailure

        ck = self.load_checkpoint(case) if resume else None
        if ck is not None and ck["done"]:
            self.rows[case.name] = ck["rows"]
            self.results[case.name] = ck["results"]
            self.case_meta[case.name] = ck["case_meta"]
            if ck["snaparr"]:
                self.snaps[case.name] = ck["snaparr"]
            if self.mesh is None and ck["case_meta"].get("mesh"):
                self.mesh = dict(ck["case_meta"]["mesh"])
            self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: already complete (checkpoint)")
            return

        if case.run is not None:
            self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: {case.label}")
            t0 = time.perf_counter()
            df = case.run(case, self.out)
            df = pd.DataFrame(df).copy()
            if "step" not in df:
                df["step"] = np.arange(len(df))
            if "wall_time" not in df:
                df["wall_time"] = np.nan
                df.loc[df.index[-1], "wall_time"] = time.perf_counter() - t0
            self.rows[case.name] = df.to_dict("records")
            res = case_results(df)
            res.setdefault("wall_time_s", time.perf_counter() - t0)
            res["status"] = "completed"
            self.results[case.name] = res
            self.save_checkpoint(case, {"rows": self.rows[case.name]}, None, done=True)
            self.write_all()
            return

        self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: building the scene ({case.label})")
        cpu0 = time.process_time() - float((ck or {}).get("case_meta", {}).get("cpu_time_s", 0.0))
        t_build = time.perf_counter()
        scene = case.build_scene()
        sim = Simulation(scene, case.schedule, case.control, progress=False, **(case.options or {}))
        build_time = time.perf_counter() - t_build
        mesh_info = _mesh_info(sim.solver)
        mesh_info["dim"] = scene.dim
        if self.mesh is None:
            self.mesh = dict(mesh_info)
        cm = {"mesh": {k_: v for k_, v in mesh_info.items() if k_ != "dim"}, "setup_time_s": build_time}
        if case.control is not None:
            cm["control"] = {"du_max": case.control.du_max, "k_u": case.control.k_u, "du_min": case.control.du_min,
                             "n_s": case.control.n_s}
        cm["schedule"] = [float(x) for x in sim.schedule.points]
        cm["options"] = {k_: v for k_, v in (case.options or {}).items() if isinstance(v, (int, float, str, bool))}
        self.case_meta[case.name] = cm
        self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: {mesh_info['n_elements']} elements, "
                          f"{mesh_info['ndof_u']} displacement dofs, {mesh_info['ndof_alpha']} phase-field dofs "
                          f"(set-up {build_time:.1f} s)")
        vtk_dir = self.out / "vtk" if self.vtk else None
        snaps = _Snapshots(case, sim.solver, vtk_dir)
        if ck is not None:
            sim.set_state(ck["state"])
            if ck["snap"]:
                snaps.restore(ck["snap"])
                snaps.write_pvd()
            self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: resuming from step {sim.step} "
                              f"(load {sim.solver.load:.6g} mm)")
        self.rows[case.name] = sim.rows
        last = {"state": sim.get_state(), "ck_step": sim.step, "ck_time": time.perf_counter(),
                "prev_load": float(sim.rows[-1]["load"])}

        def after_step(s, row):
            snaps.maybe_take(last["prev_load"], row, final=s.finished)
            last["prev_load"] = float(row["load"])
            last["state"] = s.get_state()
            self.progress.step(k, case.name, s, row, force_print=s.finished)
            now = time.perf_counter()
            if (s.step - last["ck_step"] >= self.checkpoint_every or now - last["ck_time"] >= self.checkpoint_seconds):
                self.snaps[case.name] = snaps.arrays(case.name)
                cm["cpu_time_s"] = time.process_time() - cpu0
                self.save_checkpoint(case, last["state"], snaps, done=False)
                self.write_all()
                last["ck_step"], last["ck_time"] = s.step, time.perf_counter()
            for cb in self.callbacks:
                cb(s, dict(row, case=case.name))

        def finish(status, error=None):
            state = last["state"]
            self.rows[case.name] = [dict(r) for r in state["rows"]]
            res = case_results(pd.DataFrame(self.rows[case.name]))
            res["status"] = status
            # CPU time of all threads of this process (wall time inflates when the machine is shared)
            res["cpu_time_s"] = cm["cpu_time_s"] = time.process_time() - cpu0
            # where the time went (s) since this process started the case (see ngtmc.solver.TIMING_KEYS)
            res["time_split_s"] = {k: float(v) for k, v in sim.solver.timings.items()}
            if error:
                res["error"] = error
            self.results[case.name] = res
            self.snaps[case.name] = snaps.arrays(case.name)
            self.save_checkpoint(case, state, snaps, done=(status == "completed"))

        try:
            sim.run(callbacks=[after_step])
        except StepFailure as e:
            finish("failed", str(e))
            raise
        except KeyboardInterrupt:
            finish("interrupted", "interrupted")
            raise
        except Exception as e:
            finish("failed", f"{type(e).__name__}: {e}")
            raise
        if not snaps.steps or snaps.steps[-1] != sim.step:
            snaps.take(sim.rows[-1])
        last["state"] = sim.get_state()
        finish("completed")
        r = self.results[case.name]
        self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: done, {r['steps']} steps, "
                          f"peak force {r['peak_force']:.5g} at {r['peak_load']:.5g} mm, {r.get('wall_time_s', 0):.0f} s")
        self.write_all()

    # ------------------------------------------------------------ whole run
    def run(self, resume: bool):
        if resume:
            meta_f = self.out / "metadata.json"
            if meta_f.exists():
                try:
                    old = json.loads(meta_f.read_text())
                    self.wall_before = float(old.get("wall_time_s") or 0.0)
                    self.created = old.get("created", self.created)
                except Exception:
                    pass
        self.out.mkdir(parents=True, exist_ok=True)
        self.write_metadata()
        try:
            for k, case in enumerate(self.cases):
                self.run_case(k, case, resume)
        except KeyboardInterrupt:
            self.status = "interrupted"
            self.error = "interrupted by the user (resume with resume=True / --resume)"
            self.write_all()
            raise
        except BaseException as e:
            self.status = "failed"
            self.error = f"{type(e).__name__}: {e}"
            self.write_all()
            raise
        self.status = "completed"
        self.write_all()


def _threads():
    try:
        import ngsolve as ngs
        return int(ngs.GetNumThreads())
    except Exception:
        return None


def run_study(name: str | ModuleType, resolution: str | None = None, output: str | Path | None = None,
              overrides: dict | None = None, report: bool | None = None, resume: bool = False,
              progress: bool | Callable = True, *, threads: int | None = 2, checkpoint_every: int = 25,
              checkpoint_seconds: float = 30.0, vtk: bool = True,
              callbacks: Sequence[Callable] = ()) -> Path:
    """Run a named study and return the path of its run folder.

    Parameters
    ----------
    name : str or module
        Study name (dashes or underscores, see :func:`ngtmc.list_studies`), or a study module.
    resolution : str, optional
        One of the study's RESOLUTIONS (default: its DEFAULT_RESOLUTION, normally ``"quick"``).
    output : path, optional
        Run folder. Default ``reports/<study>-<resolution>`` (time-stamped if it exists already); with
        ``resume=True`` and no output, the latest ``reports/<study>-<resolution>*`` with a checkpoint.
    overrides : dict, optional
        Any parameter of the study (PARAMETERS or resolution keys, e.g. ``{"k_u": 50, "du_max": 1e-3}``);
        strings are converted to the type of the default. Unknown keys raise StudyError.
    report : bool, optional
        Render ``report.html`` with :func:`ngtmc.report.render_report` at the end. None: try and only
        warn if it fails; True: fail if it fails; False: do not.
    resume : bool
        Continue from the checkpoints in ``output``.
    progress : bool or callable
        True prints a progress line about every 5 s on stderr; a callable receives each history row
        (with its ``case``).
    threads : int or None
        ``ngsolve.SetNumThreads``; the run is inside ``ngsolve.TaskManager()``. None: leave as is.
    checkpoint_every, checkpoint_seconds : checkpoint period in accepted steps and seconds.
    vtk : bool
        Write the ParaView series into ``vtk/``.
    callbacks : functions f(simulation, row) called after every accepted step (row includes ``case``).

    Raises StepFailure (after writing the history and metadata with status "failed") when a step
    fails at the minimum increment.
    """
    mod = name if isinstance(name, ModuleType) else load_study(name)
    res, p = study_parameters(mod, resolution, overrides)
    if output is None:
        if resume:
            output = _latest_run(mod.NAME, res)
            if output is None:
                raise StudyError(f"resume=True but no run folder reports/{mod.NAME}-{res}* with a checkpoint exists; "
                                 "give output=")
        else:
            output = default_output(mod.NAME, res)
    out = Path(output)
    if resume and not (out / "checkpoint").is_dir():
        raise StudyError(f"resume=True but {out} has no checkpoint/ folder")
    if not resume and out.exists() and (out / "history.csv").exists():
        raise StudyError(f"{out} holds a run already: choose another output, or resume=True to continue it")
    run = _Run(mod, res, p, out, overrides, progress, checkpoint_every, checkpoint_seconds, callbacks, vtk)
    import ngsolve as ngs
    if threads:
        ngs.SetNumThreads(int(threads))
    run.progress.say(f"resolution {res!r}, output {out}")
    try:
        with _terminate_as_interrupt(), ngs.TaskManager():
            run.run(resume)
    except BaseException:
        # a failed or interrupted run still gets its report (with a status banner): nothing is lost
        if report or report is None:
            _render(out, strict=False)
        raise
    run.progress.say(f"finished in {run.wall_time():.0f} s: {out}")
    if report or report is None:
        _render(out, strict=bool(report))
    return out


class _terminate_as_interrupt:
    """Within the block, SIGTERM raises KeyboardInterrupt (so a killed run is recorded as
    "interrupted" with a checkpoint at its last accepted step). Main thread only."""

    def __enter__(self):
        import signal
        import threading
        self.old = None
        if threading.current_thread() is threading.main_thread():
            def handler(signum, frame):
                raise KeyboardInterrupt(f"signal {signum}")
            try:
                self.old = signal.signal(signal.SIGTERM, handler)
            except (ValueError, OSError):  # pragma: no cover
                self.old = None
        return self

    def __exit__(self, *exc):
        if self.old is not None:
            import signal
            signal.signal(signal.SIGTERM, self.old)
        return False


def _render(out: Path, strict: bool):
    try:
        from .report import render_report
    except ImportError as e:
        msg = f"report not rendered: ngtmc.report.render_report is not available ({e})"
        if strict:
            raise RuntimeError(msg) from e
        print(f"[ngtmc] {msg}", file=sys.stderr)
        return None
    try:
        return render_report(out)
    except Exception as e:
        if strict:
            raise
        print(f"[ngtmc] report not rendered: {type(e).__name__}: {e}", file=sys.stderr)
        return None
