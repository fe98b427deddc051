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
when a run is interrupted or fails; each case keeps two generations. ``run_study(...,
resume=True)`` continues from them and gives the same history as an uninterrupted run (wall and
solve times aside). A resume takes the recorded overrides and refuses other ones, skips an
unreadable checkpoint (named in a warning) for the older generation, and never rewrites the rows
of a completed case (see :mod:`ngtmc.runfiles`).

The outputs (snapshots and VTK, checkpoints, progress, user callbacks, the report) are the plugins
of :mod:`ngtmc.plugins`, on the accepted steps that ``Simulation.steps()`` yields. A user's own scene goes
through the same run: :func:`run_scene` (``ngtmc.simulate(..., out_dir=...)``) wraps it in a
one-case study (:func:`scene_study`).

A failed run (:class:`ngtmc.StepFailure`) still writes its history and metadata, with status
``"failed"`` and the error message, and then re-raises. An interrupted run (KeyboardInterrupt)
gets status ``"interrupted"``.
"""
from __future__ import annotations

import datetime as _dt
import json
import math
import os
from pathlib import Path
import platform
import subprocess
import sys
import time
from types import ModuleType
from typing import Callable, Sequence

import numpy as np
import pandas as pd

from .runfiles import (HISTORY_UNITS, SCHEMA_VERSION, UNITS, CheckpointStore, effective_status, jsonable, peak,
                       git_revision, parameter_table, physics_hash, run_description, versions,
                       parameters_hash, process_info, read_metadata, resume_parameters, typed_overrides,
                       write_atomic, write_json, write_npz)
from .plugins import CheckpointOutput, Progress, ReportOutput, RowCallbacks, SnapshotOutput, force_unit
from .scene import _names
from .snapshots import Snapshots
from .study import Case, StudyError, load_study, normalise_name, study_parameters

__all__ = ["run_study", "run_scene", "scene_study", "default_output", "HISTORY_COLUMNS", "case_results",
           "write_atomic"]

#: Columns of history.csv, in order: ``case``, then the Simulation's history columns
#: (:data:`ngtmc.runfiles.HISTORY_UNITS`, their units).
HISTORY_COLUMNS = ["case", *HISTORY_UNITS]

# the metadata pieces live in ngtmc.runfiles (the run-folder schema); kept here for their callers
_UNITS = UNITS
_versions, _git_revision, _parameter_table = versions, git_revision, parameter_table
_jsonable = jsonable            # kept for the callers of the former private names
_write_json = write_json
_write_npz = write_npz


# ====================================================================== metadata pieces
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
    pf, pl = peak(rows["force"], rows["load"])
    out = {"peak_force": math.nan if pf is None else pf, "peak_load": math.nan if pl is None else pl,
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
        try:
            self.cases: list[Case] = list(mod.cases(p))
        except (ValueError, TypeError) as e:     # bad parameters, refused before any folder exists
            raise StudyError(f"study {mod.NAME!r} cannot build its cases: {e}") from e
        names = [c.name for c in self.cases]
        if len(set(names)) != len(names):
            raise StudyError(f"study {mod.NAME!r}: case names are not unique: {names}")
        self.progress_setting = progress
        self.progress = Progress(progress, f"[ngtmc {mod.NAME}]")
        self.force_unit: str | None = None      # of the first scene built (ngtmc.plugins.force_unit)
        self.thickness: float | None = None
        self.simulations: dict = {}             # case -> the Simulation that computed it in this process
        self.features: dict = {}                # what the scenes have (fracture, void, regulariser), for the report
        #: hash of the physical parameters alone (PARAMETERS, not the resolution's mesh and step sizes):
        #: runs with equal physics_hash differ only in resolution (the index compares only those)
        self.physics_hash = physics_hash(mod, p)
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
        self.hash = parameters_hash(p)
        self.store = CheckpointStore(out / "checkpoint")
        self.resume_from: dict[str, dict] = {}   # case -> checkpoint to continue from (see prepare_resume)

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
        dim = 2 if self.mesh is None else self.mesh.get("dim", 2)
        thickness = self.thickness if self.force_unit is not None else (
            float(p.get("thickness", 1.0)) if dim == 2 else None)
        meta = {
            **run_description(mod, p, self.resolution, self.overrides),
            "created": self.created,
            "status": self.status,
            "thickness_mm": thickness,
            "force_unit": self.force_unit or force_unit(dim, thickness),
            "mesh": {k: v for k, v in (self.mesh or {}).items() if k != "dim"},
            "wall_time_s": self.wall_time(),
            "cases": [dict(name=c.name, label=c.label, parameters=c.parameters, **self.case_meta.get(c.name, {}))
                      for c in self.cases],
            "references": list(mod.references(p)) if hasattr(mod, "references") else [],
            "targets": list(mod.targets(p)) if hasattr(mod, "targets") else [],
            "results": self.study_results(),
            "cpu_time_s": time.process_time(),
            "host": {"platform": platform.platform(), "cpu_count": os.cpu_count(),
                     "threads": _threads()},
        }
        if self.features:
            meta["features"] = dict(self.features)
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
    def save_checkpoint(self, case: Case, state: dict, snaps: Snapshots | None, done: bool):
        arrays = {"done": np.array(bool(done)), "rows": np.array(json.dumps(jsonable(state["rows"]))),
                  "results": np.array(json.dumps(jsonable(self.results.get(case.name, {})))),
                  "case_meta": np.array(json.dumps(jsonable(self.case_meta.get(case.name, {})))),
                  "parameters_hash": np.array(self.hash)}
        if not done:
            for k, v in state["solver"].items():
                arrays["solver__" + k] = np.asarray(v)
            # everything else of the Simulation's state by name (JSON keeps floats exactly), so the
            # checkpoint does not depend on the layout of that state
            arrays["simulation"] = np.array(json.dumps(jsonable({k: v for k, v in state.items()
                                                                 if k not in ("solver", "rows")})))
        if snaps is not None:
            for k, v in snaps.state().items():
                arrays["snap__" + k] = v
            for k, v in snaps.arrays(case.name).items():
                arrays["snaparr__" + k] = v
        self.store.save(case.name, arrays)

    @staticmethod
    def _decode_checkpoint(d: dict) -> dict:
        ck = {"done": bool(d["done"]), "rows": json.loads(str(d["rows"])),
              "results": json.loads(str(d["results"])), "case_meta": json.loads(str(d["case_meta"])),
              "parameters_hash": str(d["parameters_hash"]) if "parameters_hash" in d else None}
        if not ck["done"]:
            solver = {k[len("solver__"):]: v for k, v in d.items() if k.startswith("solver__")}
            if "simulation" in d:
                ck["state"] = {**json.loads(str(d["simulation"])), "solver": solver, "rows": ck["rows"]}
            else:  # written before 2026-11-24: positional scalars
                sc = d["scalars"]
                ck["state"] = {"solver": solver, "t": float(sc[0]), "step": int(sc[1]), "last_delta_wf": float(sc[2]),
                               "wf_prev": float(sc[3]), "elapsed": float(sc[4]),
                               "control": json.loads(str(d["control"])), "rows": ck["rows"]}
        ck["snap"] = {k[len("snap__"):]: v for k, v in d.items() if k.startswith("snap__")}
        ck["snaparr"] = {k[len("snaparr__"):]: v for k, v in d.items() if k.startswith("snaparr__")}
        return ck

    def load_checkpoint(self, case: Case) -> dict | None:
        """The newest readable checkpoint of ``case`` (see CheckpointStore.load), or None. Raises
        StudyError when it was computed with other parameters than this run."""
        ck = self.store.load(case.name, self._decode_checkpoint)
        if ck is not None and ck["parameters_hash"] not in (None, self.hash):
            raise StudyError(f"cannot resume {self.out}: checkpoint of case {case.name!r} was computed with other "
                             f"parameters ({ck['parameters_hash']}) than this run ({self.hash}); start a new run")
        return ck

    def _adopt_completed(self, case: Case, ck: dict):
        self.rows[case.name] = ck["rows"]
        self.results[case.name] = ck["results"]
        self.case_meta[case.name] = ck["case_meta"]
        if ck["snaparr"]:
            self.snaps[case.name] = ck["snaparr"]
        if self.mesh is None and ck["case_meta"].get("mesh"):
            self.mesh = dict(ck["case_meta"]["mesh"])

    def prepare_resume(self, meta: dict | None):
        """Read every case's checkpoint before anything is solved or written: completed cases are
        taken over, interrupted ones continue from their state. A case without a readable
        checkpoint that the recorded metadata calls completed is taken from history.csv (and
        snapshots.npz); any other case without one is re-run from the start."""
        recorded = (meta or {}).get("results") or {}
        old_hist = old_snaps = None
        for case in self.cases:
            ck = self.load_checkpoint(case)
            if ck is not None and ck["done"]:
                self._adopt_completed(case, ck)
            elif ck is not None:
                self.resume_from[case.name] = ck
                # kept in the files until the case goes on, so that no failure before then loses them
                self.rows[case.name] = ck["rows"]
                self.results[case.name] = ck["results"]
                self.case_meta[case.name] = ck["case_meta"]
                if ck["snaparr"]:
                    self.snaps[case.name] = ck["snaparr"]
            elif (recorded.get(case.name) or {}).get("status") == "completed":
                if old_hist is None:
                    old_hist, old_snaps = self._recorded_files()
                rows = old_hist[old_hist["case"].astype(str) == case.name] if len(old_hist) else old_hist
                if len(rows):
                    cm = next((dict(c) for c in meta.get("cases", []) if c.get("name") == case.name), {})
                    for k in ("name", "label", "parameters"):
                        cm.pop(k, None)
                    ck = {"rows": [{k: v for k, v in r.items() if not (isinstance(v, float) and np.isnan(v))}
                                   for r in rows.drop(columns="case").to_dict("records")],
                          "results": recorded[case.name], "case_meta": cm,
                          "snaparr": {k: v for k, v in old_snaps.items() if k.startswith(case.name + "__")}}
                    self._adopt_completed(case, ck)
                    self.save_checkpoint(case, {"rows": ck["rows"]}, None, done=True)
                    self.progress.say(f"case {case.name}: no readable checkpoint; its completed results are "
                                      "taken from history.csv and metadata.json")

    def _recorded_files(self):
        try:
            hist = pd.read_csv(self.out / "history.csv")
        except Exception:
            hist = pd.DataFrame()
        snaps = {}
        try:
            with np.load(self.out / "snapshots.npz", allow_pickle=False) as z:
                snaps = {k: z[k] for k in z.files}
        except Exception:
            pass
        return hist, snaps

    def validate(self):
        """Check every case still to be computed (scene, schedule, control, options) before any folder
        is created or any step solved; raise StudyError naming the case and the parameter."""
        import inspect
        from .simulation import Simulation
        from .stepping import AdaptiveStepControl, Schedule
        allowed = set(inspect.signature(Simulation.__init__).parameters) - {"self", "scene", "schedule", "control"}
        for case in self.cases:
            if case.name in self.results or case.run is not None:
                continue
            try:
                if case.control is not None and not isinstance(case.control, AdaptiveStepControl):
                    raise TypeError(f"control must be an ngtmc.AdaptiveStepControl or None, got "
                                    f"{type(case.control).__name__} {case.control!r}")
                if not isinstance(case.schedule, Schedule):
                    case.schedule = Schedule.monotonic(float(case.schedule))
                bad = sorted(set(case.options or {}) - allowed)
                if bad:
                    raise TypeError(f"unknown Simulation options {bad}; allowed: {', '.join(sorted(allowed))}")
                case.build_scene().check()
            except (ValueError, TypeError) as e:
                raise StudyError(f"study {self.mod.NAME!r}, case {case.name!r}: {e}") from e

    # ------------------------------------------------------------ one case
    def run_case(self, k: int, case: Case, resume: bool):
        import ngsolve as ngs
        from .simulation import Simulation, StepFailure

        ck = self.resume_from.pop(case.name, None)
        if case.name in self.results and self.results[case.name].get("status") == "completed":
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
        if self.force_unit is None:
            self.force_unit = sim.force_unit
            self.thickness = scene.thickness
        for key, has in (("fracture", scene.has_fracture), ("void", scene.has_void),
                         ("regulariser", scene.regulariser is not None)):
            self.features[key] = bool(self.features.get(key, False) or has)
        if case.control is not None:
            cm["control"] = {a: getattr(case.control, a) for a in _CONTROL_SETTINGS if hasattr(case.control, a)}
        cm["schedule"] = [float(x) for x in sim.schedule.points]
        cm["options"] = {k_: v for k_, v in (case.options or {}).items() if isinstance(v, (int, float, str, bool))}
        self.case_meta[case.name] = cm
        self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: {mesh_info['n_elements']} elements, "
                          f"{mesh_info['ndof_u']} displacement dofs, {mesh_info['ndof_alpha']} phase-field dofs "
                          f"(set-up {build_time:.1f} s)")
        vtk_dir = self.out / "vtk" if self.vtk else None
        snaps = Snapshots(case, sim.solver, vtk_dir)
        if ck is not None:
            sim.set_state(ck["state"])
            if ck["snap"]:
                snaps.restore(ck["snap"])
                snaps.write_pvd()
            self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: resuming from step {sim.step} "
                              f"(load {sim.solver.load:.6g} mm)")
        self.rows[case.name] = sim.rows
        self.simulations[case.name] = sim

        def save(state):
            self.snaps[case.name] = snaps.arrays(case.name)
            cm["cpu_time_s"] = time.process_time() - cpu0
            self.save_checkpoint(case, state, snaps, done=False)
            self.write_all()

        checkpoints = CheckpointOutput(sim, save, self.checkpoint_every, self.checkpoint_seconds)
        plugins = [SnapshotOutput(snaps, float(sim.rows[-1]["load"])),
                   Progress(self.progress_setting, f"[ngtmc {self.mod.NAME}] case {k + 1}/{len(self.cases)} "
                            f"{case.name}:", sim.force_unit, case=case.name),
                   checkpoints, RowCallbacks(self.callbacks, case.name)]
        last = checkpoints     # .state: the state of the last accepted step

        def finish(status, error=None):
            for plugin in plugins:
                plugin.finish(status)
            state = last.state
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
            for row in sim.steps():       # the accepted steps, each through the case's plugins
                for plugin in plugins:
                    plugin(sim, row)
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
        last.state = sim.get_state()
        finish("completed")
        r = self.results[case.name]
        self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: done, {r['steps']} steps, "
                          f"peak force {r['peak_force']:.5g} {sim.force_unit} at {r['peak_load']:.5g} mm, {r.get('wall_time_s', 0):.0f} s")
        self.write_all()

    # ------------------------------------------------------------ whole run
    def run(self, resume: bool, meta: dict | None = None):
        """Compute every case not taken over by :meth:`prepare_resume`; ``meta``: the recorded
        metadata of the run to resume (its creation date and wall time carry over)."""
        if resume and meta:
            if isinstance(meta.get("features"), dict):
                self.features.update({k: bool(v) for k, v in meta["features"].items()})
            try:
                self.wall_before = float(meta.get("wall_time_s") or 0.0)
                self.created = meta.get("created", self.created)
            except (TypeError, ValueError):
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


#: settings of a step control recorded in the metadata (those the control has)
_CONTROL_SETTINGS = ("du_max", "k_u", "du_min", "n_s", "newton_target", "growth", "dalpha_target", "du_first")


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
        strings are converted to the type of the default. Unknown keys and values of the wrong type
        raise StudyError. With ``resume=True``: None takes the recorded overrides, and overrides
        that differ from them raise StudyError listing the differences (``key: recorded -> given``).
    report : bool, optional
        Render ``report.html`` with :func:`ngtmc.report.render_report` at the end. None: try and only
        warn if it fails; True: fail if it fails; False: do not.
    resume : bool
        Continue from the checkpoints in ``output``.
    progress : bool or callable
        True prints a progress line about every 5 s on stderr; a callable receives each history row
        (with its ``case``).
    threads : int or None
        ``ngsolve.SetNumThreads`` (an integer >= 1); the run is inside ``ngsolve.TaskManager()``.
        None: leave as is.
    checkpoint_every, checkpoint_seconds : checkpoint period in accepted steps and seconds.
    vtk : bool
        Write the ParaView series into ``vtk/``.
    callbacks : functions f(simulation, row) called after every accepted step (row includes ``case``).

    Raises StepFailure (after writing the history and metadata with status "failed") when a step
    fails at the minimum increment, and StudyError, before any folder is created or anything
    solved, for bad input (unknown study, resolution or override, ill-typed or out-of-range
    values, a bad scene, threads < 1) or a resume that would mix parameters.
    """
    return _execute(name, resolution, output, overrides, report, resume, progress, threads, checkpoint_every,
                    checkpoint_seconds, vtk, callbacks).out


def _execute(name, resolution, output, overrides, report, resume, progress, threads, checkpoint_every,
             checkpoint_seconds, vtk, callbacks) -> "_Run":
    """The work of :func:`run_study`; returns the finished run (its folder ``out``, and the
    Simulation of each case computed in this process in ``simulations``)."""
    if threads is not None and (isinstance(threads, bool) or not isinstance(threads, (int, np.integer))
                                or threads < 1):
        raise StudyError(f"threads = {threads!r} is not allowed: give an integer >= 1 (NGSolve threads), "
                         "or None to leave the thread count as it is")
    mod = name if isinstance(name, ModuleType) else load_study(name)
    meta = None
    if resume:
        if output is None:
            output = _latest_run(mod.NAME, resolution or getattr(mod, "DEFAULT_RESOLUTION", "quick"))
            if output is None:
                raise StudyError(f"resume=True but no run folder reports/{mod.NAME}-"
                                 f"{resolution or getattr(mod, 'DEFAULT_RESOLUTION', 'quick')}* with a checkpoint "
                                 "exists; give output=")
        out = Path(output)
        if not (out / "checkpoint").is_dir():
            raise StudyError(f"resume=True but {out} has no checkpoint/ folder")
        meta = read_metadata(out)
        if meta is not None:
            status, note = effective_status(meta)
            proc = meta.get("process") or {}
            if status == "running" and note and "alive" in note and proc.get("pid") != os.getpid():
                raise StudyError(f"cannot resume {out}: it is still running ({note})")
        res, typed, p = resume_parameters(meta, mod, resolution, overrides, out)
    else:
        res, p = study_parameters(mod, resolution, overrides)
        typed = typed_overrides(p, overrides)
        out = Path(output) if output is not None else default_output(mod.NAME, res)
        if out.exists() and (out / "history.csv").exists():
            old = read_metadata(out) or {}
            status, note = effective_status(old) if old else ("unknown", None)
            raise StudyError(f"{out} holds a run already (status {status}{': ' + note if note else ''}): choose "
                             "another output, or resume=True / --resume to continue it")
    run = _Run(mod, res, p, out, typed, progress, checkpoint_every, checkpoint_seconds, callbacks, vtk)
    if resume:
        if meta is not None and meta.get("status") == "running":
            run.progress.say(f"{out}: {effective_status(meta)[1] or 'recorded as running'}")
        run.prepare_resume(meta)
    run.validate()     # bad input is refused here, before any folder is created or any step solved
    import ngsolve as ngs
    if threads:
        ngs.SetNumThreads(int(threads))
    run.progress.say(f"resolution {res!r}, output {out}")
    # outputs of the whole run (those of each case: _Run.run_case)
    outputs = [ReportOutput(out, strict=bool(report))] if (report or report is None) else []
    try:
        with _terminate_as_interrupt(), ngs.TaskManager():
            run.run(resume, meta)
    except BaseException:
        # a failed or interrupted run still gets its report (with a status banner): nothing is lost
        for plugin in outputs:
            plugin.finish("interrupted" if run.status == "interrupted" else "failed")
        raise
    run.progress.say(f"finished in {run.wall_time():.0f} s: {out}")
    for plugin in outputs:
        plugin.finish(run.status)
    return run


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


# ====================================================================== a user's own scene
def _value_text(v) -> str:
    """A reproducible text for a field or traction: a callable by its qualified name, a
    CoefficientFunction by its expression, a vector by its numbers (no memory addresses)."""
    if callable(v) and hasattr(v, "__qualname__"):
        return f"{getattr(v, '__module__', '')}.{v.__qualname__}"
    if isinstance(v, (list, tuple, np.ndarray)):
        return str([float(x) for x in np.ravel(v)])
    return " ".join(str(v).split())


def _load_text(ld) -> str:
    """One load of a scene as recorded in a user scene's parameters."""
    text = f"{type(ld).__name__} {ld.label!r} on {ld.boundary}"
    if hasattr(ld, "direction"):
        text += f": {ld.direction}" + (", tangential held" if ld.hold_tangential else "")
    if hasattr(ld, "field"):
        text += f": components {ld.components or 'all'}, field {_value_text(ld.field)}"
    if hasattr(ld, "traction"):
        text += f": traction {_value_text(ld.traction)} MPa per unit lambda"
    return text


def _scene_parameters(scene, schedule, control, options: dict) -> dict:
    """PARAMETERS (name -> (value, unit, description)) describing a scene, its schedule, step control
    and options: what the run folder records, and what a resume compares."""
    import dataclasses
    import hashlib
    out = {}
    for region, m in scene.materials.items():
        out[f"{region}.E"] = (float(m.E), "MPa", f"Young's modulus in region {region!r}")
        out[f"{region}.nu"] = (float(m.nu), "-", f"Poisson's ratio in region {region!r}")
        if scene.has_fracture:
            out[f"{region}.Gc"] = (float(m.Gc), "N/mm", f"critical energy release rate in region {region!r}")
            out[f"{region}.l0"] = (float(m.l0), "mm", f"phase-field length scale in region {region!r}")
    out["fracture_regions"] = (", ".join(scene.fracture_region_names) or "none", "-",
                               "regions where the phase field lives (regular expressions)")
    if scene.has_fracture:
        out["split"] = (str(scene.split), "-", "tension/compression split of the elastic energy")
        out["formulation"] = (str(scene.formulation), "-", "where the split acts")
    if isinstance(scene.density, dict) or hasattr(scene.density, "items"):
        for region, v in scene.density.items():
            out[f"rho.{region}"] = (float(v), "-", f"pseudo-density in region {region!r} (1 solid, 0 void)")
    elif scene.density is not None:
        rho = np.asarray(scene.density, dtype=float).ravel()
        out["rho"] = (f"{rho.size} values, sha256:{hashlib.sha256(rho.tobytes()).hexdigest()[:16]}", "-",
                      "pseudo-density per element (1 solid, 0 void)")
    if scene.has_void:
        out["gamma0"] = (float(scene.gamma0), "-", "void stiffness ratio (Eq. 17)")
    if scene.has_fracture and scene.has_void:
        out["gc_a"] = (float(scene.gc_a), "-", "toughness interpolation parameter a (Eq. 18)")
        out["gc_b"] = (float(scene.gc_b), "-", "toughness interpolation parameter b (Eq. 18)")
    out["residual_stiffness"] = (float(scene.residual_stiffness), "-", "added to the degradation g(alpha)")
    if scene.regulariser is not None:
        r = scene.regulariser
        out["regulariser_regions"] = (", ".join(_names(r.regions)), "-", "regions of the contact regulariser")
        out["regulariser_length"] = (float(r.length), "mm", "characteristic length L of the regulariser")
        out["kbar_r"] = (float(r.kbar_r), "-", "regulariser factor")
        out["regulariser_damping"] = (str(r.damping), "-", "damping of the regulariser")
    if scene.dim == 2:
        out["thickness"] = (float(scene.thickness), "mm", "out-of-plane thickness (plane strain)")
    out["displacement_order"] = (int(scene.displacement_order), "-", "polynomial order of the displacement")
    mesh = scene.mesh
    coords = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    out["mesh"] = (f"{mesh.ne} elements, {mesh.nv} vertices, sha256:"
                   f"{hashlib.sha256(coords.tobytes()).hexdigest()[:16]}", "-", "the mesh (vertex coordinates hashed)")
    out["supports"] = ("; ".join(f"{s.boundary}: " + "".join(a for a in "xyz" if getattr(s, a, False))
                                 for s in scene.supports), "-", "held boundaries and components")
    out["load"] = ("; ".join(_load_text(ld) for ld in scene.loads), "-", "loads: kind, name, where, what")
    if len(scene.loads) > 1:
        out["force_from"] = (str(scene.force_load.label), "-", "load behind the force column")
    out["schedule"] = ([float(x) for x in schedule.points], "mm", "load schedule (turning points)")
    if control is not None:
        for a in _CONTROL_SETTINGS:
            v = getattr(control, a, None)
            if v is not None:
                out[f"control.{a}"] = (v, {"du_max": "mm", "du_min": "mm", "du_first": "mm", "k_u": "1/N"}.get(a, "-"),
                                       f"step control {type(control).__name__}: {a}")
    for k, v in options.items():
        if isinstance(v, (int, float, str, bool)):
            out[f"option.{k}"] = (v, "-", f"Simulation option {k}")
    return out


def scene_study(scene, schedule, control=None, *, name: str | None = None, title: str | None = None,
                summary: str | None = None, snapshot_loads: Sequence[float] | None = None,
                references: Sequence[dict] = (), targets: Sequence[dict] = (), **options) -> ModuleType:
    """A one-case study module (the interface of ``docs/study-interface.md``) around a user's own
    scene, so that the runner writes its run folder as for a named study.

    ``name`` defaults to ``scene.name``; ``snapshot_loads`` (mm) default to 8 loads evenly along the
    schedule; ``references`` and ``targets`` in the metadata format; ``options``: keyword arguments
    of :class:`ngtmc.Simulation` (e.g. ``scheme``). PARAMETERS describe the scene, schedule and
    control (materials, densities, mesh, ...), so a resume with another scene is refused.
    """
    from .stepping import Schedule
    if not isinstance(schedule, Schedule):
        from .materials import check_number
        check_number("schedule (a Schedule, or the final load)", schedule, "mm")
        schedule = Schedule.monotonic(float(schedule))
    if snapshot_loads is None:
        total = schedule.total_time
        snapshot_loads = [float(schedule.load(t)) for t in np.linspace(0.0, total, 9)[1:]]
    study_name = normalise_name(name or getattr(scene, "name", None) or "scene")
    mod = ModuleType(f"ngtmc_scene_{study_name}")
    mod.NAME = study_name
    mod.TITLE = title or f"Scene {study_name}"
    mod.SUMMARY = summary or (f"Scene {study_name!r} ({scene.dim}D, {scene.mesh.ne} elements"
                              f"{', with fracture' if scene.has_fracture else ''}"
                              f"{', with a third medium (void)' if scene.has_void else ''}), loaded along "
                              f"{[float(x) for x in schedule.points]} mm.")
    mod.PARAMETERS = _scene_parameters(scene, schedule, control, options)
    mod.RESOLUTIONS = {"custom": {}}
    mod.DEFAULT_RESOLUTION = "custom"
    case = Case(name="main", label=getattr(scene, "name", None) or study_name, scene=scene, schedule=schedule,
                control=control, options=dict(options), snapshot_loads=list(snapshot_loads))
    mod.cases = lambda p: [case]
    mod.references = lambda p: list(references)
    mod.targets = lambda p: list(targets)
    return mod


def run_scene(scene, schedule, control=None, out_dir: str | Path | None = None, *, resume: bool = False,
              report: bool | None = None, progress: bool | Callable = False, vtk: bool = True,
              threads: int | None = None, checkpoint_every: int = 25, checkpoint_seconds: float = 30.0,
              callbacks: Sequence[Callable] = (), name: str | None = None, title: str | None = None,
              summary: str | None = None, snapshot_loads: Sequence[float] | None = None,
              references: Sequence[dict] = (), targets: Sequence[dict] = (), **options):
    """Run a user's own scene into the run folder ``out_dir``, with the machinery of a named study
    (history.csv, metadata.json, snapshots.npz, vtk/, checkpoint/, report.html); see
    :func:`scene_study` and :func:`run_study`. Returns the :class:`ngtmc.SimulationResult`, its
    ``run_dir`` set. ``ngtmc.simulate(..., out_dir=...)`` calls this."""
    from .simulation import HISTORY_UNITS, SimulationResult
    if out_dir is None:
        raise StudyError("run_scene needs out_dir, the run folder to write")
    mod = scene_study(scene, schedule, control, name=name, title=title, summary=summary,
                      snapshot_loads=snapshot_loads, references=references, targets=targets, **options)
    run = _execute(mod, None, out_dir, None, report, resume, progress, threads, checkpoint_every,
                   checkpoint_seconds, vtk, callbacks)
    sim = run.simulations.get("main")
    rows = run.rows.get("main") or []
    units = sim.units if sim is not None else dict(HISTORY_UNITS, force=run.force_unit or
                                                   (read_metadata(run.out) or {}).get("force_unit", "N"))
    history = pd.DataFrame(rows).reindex(columns=list(units))
    return SimulationResult(history, units, sim.solver if sim is not None else None,
                            float(run.results.get("main", {}).get("wall_time_s") or run.wall_time()),
                            run_dir=run.out)
