"""The case loop of a run: resume (what the checkpoints and the recorded files of a run folder
allow to take over), validation of every case before anything is solved, and each case through
:meth:`ngtmc.Simulation.steps` and the plugins of :mod:`ngtmc.simulation.plugins`, into its
:class:`ngtmc.runner.folder.RunFolder`.
"""
from __future__ import annotations

import time
import warnings

import numpy as np
import pandas as pd

from ngtmc.discrete import blas_limited
from ngtmc.simulation import Progress, RowCallbacks, force_unit
from ngtmc.runner.outputs import CheckpointOutput, SnapshotOutput
from ngtmc.scene import ResolutionWarning
from ngtmc.runner.snapshots import Snapshots
from ngtmc.study import StudyError
from ngtmc.study import Case
from ngtmc.runner.folder import CONTROL_SETTINGS, RunFolder, _mesh_info, _threads, case_results
from ngtmc.runner.rank_snapshots import GatheredSnapshots
from ngtmc.scene import distribute, refuse_unsupported
from ngtmc.simulation import Simulation, StepFailure
from ngtmc.stepping import AdaptiveStepControl, Schedule

__all__ = ["_Run"]


class _Run(RunFolder):
    """One run: its folder (:class:`RunFolder`), its progress and per-step outputs, and the loop
    over its cases (:meth:`run`)."""

    def __init__(self, mod, resolution, p, out, overrides, progress, checkpoint_every, checkpoint_seconds,
                 callbacks, vtk, comm=None):
        super().__init__(mod, resolution, p, out, overrides)
        #: the MPI communicator whose ranks share each case's mesh (``run_study(mpi=True)``), else None
        self.comm = comm
        self.checkpoint_every = int(checkpoint_every)
        self.checkpoint_seconds = float(checkpoint_seconds)
        self.callbacks = list(callbacks or [])
        self.vtk = vtk
        self.progress_setting = progress
        self.progress = Progress(progress, f"[ngtmc {mod.NAME}]")
        self.simulations: dict = {}             # case -> the Simulation that computed it in this process
        self.resume_from: dict[str, dict] = {}   # case -> checkpoint to continue from (see prepare_resume)
        #: case -> NGSolve threads for that case, each case then in its own TaskManager (threads="auto"
        #: of a serial run: :func:`ngtmc.runner.study_run.case_threads`); None: the caller's setting for all
        self.case_threads = None

    # ------------------------------------------------------------ resume
    def adopt(self, case: Case, ck: dict):
        """Take the rows, results, case metadata and snapshots of ``case`` from its checkpoint ``ck``."""
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
        if meta is None:
            warnings.warn(f"{self.out / 'metadata.json'} is missing or unreadable: the run resumes from its "
                          "checkpoints alone, its wall time from the latest one they recorded", UserWarning,
                          stacklevel=3)
        old_hist = old_snaps = None
        for case in self.cases:
            ck = self.load_checkpoint(case)
            if ck is not None and ck["done"]:
                self.adopt(case, ck)
                self._warn_missing_vtk(case)
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
                          "snaparr": {k: v for k, v in old_snaps.items()
                                      if k.startswith((case.name + "__", case.name + "@"))}}
                    self.adopt(case, ck)
                    self.save_checkpoint(case, {"rows": ck["rows"]}, None, done=True)
                    self.progress.say(f"case {case.name}: no readable checkpoint; its completed results are "
                                      "taken from history.csv and metadata.json")

    def _warn_missing_vtk(self, case):
        """A completed case taken over on resume: warn naming each ParaView file its series lists
        that is not on disk (a run that failed while writing them, a disk that was full)."""
        import re
        pvd = self.out / "vtk" / f"{case.name}.pvd"
        if not self.vtk or not pvd.is_file():
            return
        missing = [f for f in re.findall(r'file="([^"]+)"', pvd.read_text()) if not (pvd.parent / f).is_file()]
        if missing:
            warnings.warn(f"case {case.name} is completed, but its ParaView series {pvd} lists files that are not "
                          f"there: {', '.join(missing)} (run the case again into a new folder to have them)",
                          UserWarning, stacklevel=3)

    def _recorded_files(self):
        run_folder = self.store.folder.parent  # also on the MPI ranks that write into a scratch folder
        try:
            hist = pd.read_csv(run_folder / "history.csv")
        except Exception:
            hist = pd.DataFrame()
        snaps = {}
        try:
            with np.load(run_folder / "snapshots.npz", allow_pickle=False) as z:
                snaps = {k: z[k] for k in z.files}
        except Exception:
            pass
        return hist, snaps

    def validate(self, cases=None):
        """Check every case still to be computed (scene, schedule, control, options) before any folder
        is created or any step solved; raise StudyError naming the case and the parameter.
        ``cases``: only these (default: all of the run)."""
        import inspect
        allowed = set(inspect.signature(Simulation.__init__).parameters) - {"self", "scene", "schedule", "control"}
        for case in self.cases if cases is None else cases:
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
                scene = case.build_scene()
                adapt = (case.options or {}).get("adapt")
                with warnings.catch_warnings():  # errors here; its warnings once, from the case's Solver
                    warnings.simplefilter("ignore", ResolutionWarning)
                    scene.check(getattr(adapt, "h_crack", None))
                if self.comm is not None:  # what the distributed scene will refuse, refused before anything runs
                    refuse_unsupported(scene, adapt)
            except (ValueError, TypeError, NotImplementedError) as e:
                raise StudyError(f"study {self.mod.NAME!r}, case {case.name!r}: {e}") from e

    # ------------------------------------------------------------ one case
    def completed(self, case: Case) -> bool:
        """The case is complete (computed, or taken over by :meth:`prepare_resume`)."""
        return (self.results.get(case.name) or {}).get("status") == "completed"

    def adopt_scene(self, scene, mesh_info: dict) -> dict:
        """The run's mesh (the first case's), force unit, thickness and features from a case's
        ``scene`` and the ``mesh_info`` of its solver; returns the case's own mesh entry."""
        if self.mesh is None:
            self.mesh = dict(mesh_info, dim=scene.dim)
        if self.force_unit is None:
            self.force_unit = force_unit(scene.dim, scene.thickness)
            self.thickness = scene.thickness
        for key, has in (("fracture", scene.has_fracture), ("void", scene.has_void),
                         ("regulariser", scene.regulariser is not None)):
            self.features[key] = bool(self.features.get(key, False) or has)
        return dict(mesh_info)

    def run_own(self, k: int, case: Case):
        """A case computed by its own ``run(case, out_dir)``: its DataFrame is the history; its
        ``attrs`` may add results, snapshots and the solver of its final run (docs/study-interface.md)."""
        self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: {case.label}")
        t0 = time.perf_counter()
        df = case.run(case, self.out)
        extra = dict(getattr(df, "attrs", None) or {})
        if extra:
            df.attrs.clear()
        df = pd.DataFrame(df).copy()
        if extra.get("solver") is not None:
            solver = extra["solver"]
            self.case_meta[case.name] = {"mesh": self.adopt_scene(solver.scene, _mesh_info(solver))}
        if "step" not in df:
            df["step"] = np.arange(len(df))
        if "wall_time" not in df:
            df["wall_time"] = np.nan
            df.loc[df.index[-1], "wall_time"] = time.perf_counter() - t0
        self.rows[case.name] = df.to_dict("records")
        res = case_results(df)
        res.update(extra.get("results") or {})
        res["wall_time_s"] = time.perf_counter() - t0     # the whole case, not a run inside it
        res["status"] = "completed"
        self.results[case.name] = res
        snaparr = {f"{case.name}__{k_}": np.asarray(v) for k_, v in (extra.get("snapshots") or {}).items()}
        if snaparr:
            self.snaps[case.name] = snaparr
        self.save_checkpoint(case, {"rows": self.rows[case.name]}, None, done=True, snaparr=snaparr)
        self.write_all()

    def run_case(self, k: int, case: Case, resume: bool):

        ck = self.resume_from.pop(case.name, None)
        if self.completed(case):
            self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: already complete (checkpoint)")
            return

        if case.run is not None:
            self.run_own(k, case)
            return

        self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: building the scene ({case.label})")
        cpu0 = time.process_time() - float((ck or {}).get("case_meta", {}).get("cpu_time_s", 0.0))
        t_build = time.perf_counter()
        scene = serial = case.build_scene()
        if self.comm is not None:
            scene = distribute(serial, self.comm, curve=serial.mesh.GetCurveOrder())
        sim = Simulation(scene, case.schedule, case.control, progress=False, **(case.options or {}))
        build_time = time.perf_counter() - t_build
        mesh_info = _mesh_info(sim.solver, serial if self.comm is not None else None)
        cm = {"mesh": self.adopt_scene(scene, mesh_info), "setup_time_s": build_time, "threads": _threads()}
        # the control the run uses (path following bounds its displacement steps by its own du_max)
        cm["control"] = {a: getattr(sim.control, a) for a in CONTROL_SETTINGS if hasattr(sim.control, a)}
        cm["schedule"] = [float(x) for x in sim.schedule.points]
        cm["options"] = {k_: v for k_, v in (case.options or {}).items() if isinstance(v, (int, float, str, bool))}
        self.case_meta[case.name] = cm
        self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: {mesh_info['n_elements']} elements, "
                          f"{mesh_info['ndof_u']} displacement dofs, {mesh_info['ndof_alpha']} phase-field dofs "
                          f"(set-up {build_time:.1f} s)")
        vtk_dir = self.out / "vtk" if self.vtk else None
        if self.comm is None:
            snaps = Snapshots(case, sim, vtk_dir)
        else:  # the fields gathered on rank 0 in the serial mesh's numbering; each rank checkpoints its part
            snaps = GatheredSnapshots(case, sim, vtk_dir, self.comm, serial)
        fingerprint = _rank_fingerprint(sim.solver) if self.comm is not None else None
        if ck is not None and fingerprint is not None:
            same = ck.get("mpi_fingerprint") is not None and np.array_equal(ck["mpi_fingerprint"], fingerprint)
            if not all(self.comm.allgather(same)):
                raise StudyError(f"cannot resume case {case.name!r}: its mesh is distributed over the MPI ranks "
                                 "otherwise than when its checkpoints were written (another NGSolve, or another "
                                 "mesh); start a new run")
        if ck is not None:
            sim.set_state(ck["state"])
            if ck["snap"]:
                snaps.restore(ck["snap"], recorded=ck["snaparr"])
                snaps.write_pvd()
            self.progress.say(f"case {k + 1}/{len(self.cases)} {case.name}: resuming from step {sim.step} "
                              f"(load {sim.solver.load:.6g} mm)")
        self.rows[case.name] = sim.rows
        self.simulations[case.name] = sim

        def save(state):
            self.snaps[case.name] = snaps.arrays(case.name)
            cm["cpu_time_s"] = time.process_time() - cpu0
            self.save_checkpoint(case, state, snaps, done=False, fingerprint=fingerprint)
            self.write_all()

        checkpoints = CheckpointOutput(sim, save, self.checkpoint_every, self.checkpoint_seconds, comm=self.comm)
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
            # where the time went (s) since this process started the case (see ngtmc.discrete.solver.TIMING_KEYS)
            res["time_split_s"] = {k: float(v) for k, v in sim.solver.timings.items()}
            res["peak_memory_mb"] = peak_memory_mb()
            res["counters"] = sim.counters()
            if sim.refinements:   # adaptive refinement: the mesh the case ended on
                cm["mesh_final"] = {k_: v for k_, v in _mesh_info(sim.solver).items() if k_ != "displacement_order"}
                cm["refinements"] = len(sim.refinements)
            if error:
                res["error"] = error
            self.results[case.name] = res
            self.snaps[case.name] = snaps.arrays(case.name)
            self.save_checkpoint(case, state, snaps, done=(status == "completed"), fingerprint=fingerprint)

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
                          f"peak force {r['peak_force']:.5g} {sim.force_unit} at {r['peak_load']:.5g} mm, {r.get('wall_time_s', 0):.0f} s, "
                          f"peak memory {r['peak_memory_mb']:.0f} MB")
        self.write_all()

    # ------------------------------------------------------------ whole run
    def run_cases(self, resume: bool):
        """Compute the cases one after the other in this process (the first failure stops the run)."""
        for k, case in enumerate(self.cases):
            n = self.case_threads(case) if self.case_threads is not None else None
            if n is None:   # the caller's TaskManager (or none)
                self.run_case(k, case, resume)
                continue
            import ngsolve as ngs
            ngs.SetNumThreads(int(n))
            with ngs.TaskManager(), blas_limited():
                self.run_case(k, case, resume)

    def run(self, resume: bool, meta: dict | None = None, run_cases=None):
        """Compute every case not taken over by :meth:`prepare_resume`; ``meta``: the recorded
        metadata of the run to resume (its creation date and wall time carry over).
        ``run_cases(resume)`` computes the cases (default :meth:`run_cases`, serially; the cases on a
        Dask cluster: :mod:`ngtmc.runner.parallel`); the status and files of the run are kept here."""
        if resume and meta:
            if isinstance(meta.get("features"), dict):
                self.features.update({k: bool(v) for k, v in meta["features"].items()})
            try:
                self.wall_before = float(meta.get("wall_time_s") or 0.0)
                self.created = meta.get("created", self.created)
            except (TypeError, ValueError):
                pass
        elif resume:   # metadata.json lost: the time so far is the latest wall time the checkpoints recorded
            times = [float(r.get("wall_time", 0.0) or 0.0) for rows in self.rows.values() for r in rows]
            self.wall_before = max([t for t in times if t == t] + [0.0])
        self.out.mkdir(parents=True, exist_ok=True)
        self.write_metadata()
        try:
            (run_cases or self.run_cases)(resume)
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


def peak_memory_mb() -> float:
    """Peak resident memory of this process so far, MB (the largest resident set of the process
    that ran the case: in a serial run of several cases, the peak over the cases run so far)."""
    import resource
    import sys
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return float(rss) / (1024.0 ** 2 if sys.platform == "darwin" else 1024.0)


def _rank_fingerprint(solver) -> np.ndarray:
    """This MPI rank's part of the mesh, as a resume compares it: its element, vertex and dof
    counts and the sums of its vertices' coordinates (mm)."""
    mesh = solver.mesh
    coords = np.asarray(mesh.ngmesh.Coordinates(), dtype=float).reshape(-1, mesh.dim)
    return np.concatenate([[mesh.ne, mesh.nv, solver.fes_u.ndof, solver.fes_a.ndof if solver.fes_a is not None else 0],
                           coords.sum(axis=0)])
