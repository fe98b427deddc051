"""The run folder of one run (the format of ``docs/run-directory.md``, schema in
:mod:`ngtmc.study.run_files`): what a run holds in memory (history rows, snapshots, results and metadata
of each case) and how it writes it, ``history.csv``, ``snapshots.npz``, ``metadata.json`` and the
checkpoints of each case (``checkpoint/<case>.npz``, two generations). The case loop and resume
logic that fills it: :mod:`ngtmc.runner.cases`.
"""
from __future__ import annotations

import datetime as _dt
import json
import math
import os
from pathlib import Path
import platform
import sys
import time
import warnings

import numpy as np
import pandas as pd

from ngtmc.study import CheckpointWarning, jsonable, write_atomic, write_json, write_npz
from ngtmc.study import parameters_hash, physics_hash, run_description
from ngtmc.simulation import HISTORY_COLUMNS, force_unit, peak
from ngtmc.scene import region_names
from ngtmc.runner.checkpoints import CheckpointStore
from ngtmc.runner.snapshots import Snapshots
from ngtmc.study import StudyError
from ngtmc.study import Case

__all__ = ["RunFolder", "case_results"]


#: settings of a step control recorded in the metadata (those the control has)
CONTROL_SETTINGS = ("du_max", "k_u", "du_min", "n_s", "newton_target", "growth", "dalpha_target", "du_first")


def _threads():
    try:
        import ngsolve as ngs
        return int(ngs.GetNumThreads())
    except Exception:
        return None


# ====================================================================== metadata pieces
def _mesh_info(solver, serial=None) -> dict:
    """Elements, vertices, dofs and element sizes (mm) of a solver's mesh. ``serial``: for a solver
    on MPI ranks, the serial scene every rank built (its mesh is counted; dofs once over the ranks)."""
    if serial is not None:
        mesh, h = serial.mesh, serial.element_sizes()
        nd = {"u": solver.fes_u.ndofglobal, "alpha": solver.fes_a.ndofglobal if solver.fes_a is not None else 0}
    else:
        mesh = solver.mesh
        h = solver.h if getattr(solver, "h", None) is not None else solver.scene.element_sizes()
        nd = solver.ndof
    return {"n_elements": int(mesh.ne), "n_vertices": int(mesh.nv), "ndof_u": int(nd["u"]),
            "ndof_alpha": int(nd["alpha"]), "h_min": float(np.min(h)), "h_max": float(np.max(h)),
            "displacement_order": (f"{solver.order} in {', '.join(region_names(solver.scene.regulariser.regions))}, 1 elsewhere"
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


# ====================================================================== the folder
class RunFolder:
    """The files of one run of study module ``mod`` at ``resolution`` with parameters ``p`` (after
    ``overrides``) in the folder ``out``: the cases of the study, and per case its history rows,
    snapshot arrays, results and metadata, written atomically. Raises StudyError, before any
    folder exists, when the study cannot build its cases or their names repeat."""

    def __init__(self, mod, resolution, p, out: Path, overrides):
        self.mod = mod
        self.resolution = resolution
        self.p = p
        self.out = out
        self.overrides = dict(overrides or {})
        try:
            self.cases: list[Case] = list(mod.cases(p))
        except (ValueError, TypeError) as e:     # bad parameters, refused before any folder exists
            raise StudyError(f"study {mod.NAME!r} cannot build its cases: {e}") from e
        names = [c.name for c in self.cases]
        if not names:   # a run of nothing is no completed run
            raise StudyError(f"study {mod.NAME!r}: cases() returned no case at resolution {resolution!r}; "
                             "it must return a list of ngtmc.study.registry.Case")
        if len(set(names)) != len(names):
            raise StudyError(f"study {mod.NAME!r}: case names are not unique: {names}")
        bad = [n for n in names if "@" in n or "__" in n or not n]
        if bad:   # snapshots.npz keys are {case}__{field}, and {case}@{g}__{field} for a refined mesh
            raise StudyError(f"study {mod.NAME!r}: case names {bad} may contain neither '@' nor '__' (and not be empty)")
        self.force_unit: str | None = None      # of the first scene built (ngtmc.simulation.history.force_unit)
        self.thickness: float | None = None
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
        self.parallel: dict | None = None     # how the cases were spread over a Dask cluster, if they were
        self.comm = None                      # the MPI communicator of a run on ranks (run_study(mpi=True))
        self.t0 = time.perf_counter()
        self.wall_before = 0.0
        self.created = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
        self.hash = parameters_hash(p, mod)
        self.store = CheckpointStore(out / "checkpoint")

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
            write_npz(self.out / "snapshots.npz", arrays)

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
        figures = list(mod.figures(p)) if hasattr(mod, "figures") else []
        if figures:  # what the study adds to its report (docs/study-interface.md)
            meta["figures"] = figures
        if self.features:
            meta["features"] = dict(self.features)
        if getattr(mod, "REPORT", None):   # what the report shows besides its sections (docs/study-interface.md)
            meta["report"] = dict(mod.REPORT)
        if self.parallel:
            meta["parallel"] = dict(self.parallel)
        if self.comm is not None:
            meta["mpi"] = {"ranks": int(self.comm.size)}
        if self.error:
            meta["error"] = self.error
        return meta

    def study_results(self) -> dict:
        """Per-case results, passed through the study's optional ``post_results(p, history, results)``."""
        results = json.loads(json.dumps(jsonable(self.results)))
        hook = getattr(self.mod, "post_results", None)
        if hook is not None and results:
            try:
                results = hook(self.p, self.history_frame(), results) or results
            except Exception as e:  # a post-processing error must not lose the run's files
                print(f"[ngtmc] {self.mod.NAME}.post_results failed: {type(e).__name__}: {e}", file=sys.stderr)
        return results

    def write_metadata(self):
        write_json(self.out / "metadata.json", self.metadata())

    def write_all(self):
        self.write_history()
        self.write_snapshots()
        self.write_metadata()

    # ------------------------------------------------------------ checkpoints
    def use_rank_checkpoints(self, folder: Path):
        """On MPI ranks (``self.comm``): every rank writes and reads its own checkpoints,
        ``<folder>/<case>.rank<r>of<n>.npz`` (its part of the fields), in the run's folder also
        on the ranks that write nothing else."""
        self.store = CheckpointStore(folder, rank=(self.comm.rank, self.comm.size))

    def save_checkpoint(self, case: Case, state: dict, snaps: Snapshots | None, done: bool,
                        fingerprint: np.ndarray | None = None, snaparr: dict | None = None):
        """Write ``case``'s checkpoint (``checkpoint/<case>.npz``; on MPI ranks each rank's own,
        :meth:`use_rank_checkpoints`, with the ``fingerprint`` of its part of the mesh);
        ``snaparr``: the snapshot arrays of a case computed by its own ``run`` (no ``snaps``)."""
        arrays = {"done": np.array(bool(done)), "rows": np.array(json.dumps(jsonable(state["rows"]))),
                  "results": np.array(json.dumps(jsonable(self.results.get(case.name, {})))),
                  "case_meta": np.array(json.dumps(jsonable(self.case_meta.get(case.name, {})))),
                  "parameters_hash": np.array(self.hash)}
        if not done:
            for k, v in state["solver"].items():
                arrays["solver__" + k] = np.asarray(v)
            for k, v in state.get("arrays", {}).items():  # the Simulation's own arrays (path predictor)
                arrays["state__" + k] = np.asarray(v)
            # everything else of the Simulation's state by name (JSON keeps floats exactly), so the
            # checkpoint does not depend on the layout of that state
            arrays["simulation"] = np.array(json.dumps(jsonable({k: v for k, v in state.items()
                                                                 if k not in ("solver", "rows", "arrays")})))
        if fingerprint is not None:
            arrays["mpi_fingerprint"] = np.asarray(fingerprint, dtype=float)
        if snaps is not None:
            for k, v in snaps.state().items():
                arrays["snap__" + k] = v
            for k, v in snaps.arrays(case.name).items():
                arrays["snaparr__" + k] = v
        for k, v in (snaparr or {}).items():
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
                ck["state"] = {**json.loads(str(d["simulation"])), "solver": solver, "rows": ck["rows"],
                               "arrays": {k[len("state__"):]: v for k, v in d.items() if k.startswith("state__")}}
            else:  # written before 2026-11-24: positional scalars
                sc = d["scalars"]
                ck["state"] = {"solver": solver, "t": float(sc[0]), "step": int(sc[1]), "last_delta_wf": float(sc[2]),
                               "wf_prev": float(sc[3]), "elapsed": float(sc[4]),
                               "control": json.loads(str(d["control"])), "rows": ck["rows"], "arrays": {}}
        ck["mpi_fingerprint"] = d.get("mpi_fingerprint")
        ck["snap"] = {k[len("snap__"):]: v for k, v in d.items() if k.startswith("snap__")}
        ck["snaparr"] = {k[len("snaparr__"):]: v for k, v in d.items() if k.startswith("snaparr__")}
        return ck

    def load_checkpoint(self, case: Case) -> dict | None:
        """The newest readable checkpoint of ``case`` (see CheckpointStore.load), or None; on MPI
        ranks the newest generation that every rank can read. Raises StudyError when it was
        computed with other parameters than this run, or on another number of MPI ranks."""
        other = self.store.other_layouts(case.name)
        if other and not any(f.exists() for f in self.store.files(case.name)):
            n = max(other)
            how = ("a serial run: resume it without --mpi / mpi=True" if n == 0 else
                   f"{n} MPI ranks: resume it with mpiexec -n {n} python -m mpi4py -m ngtmc run ... --mpi --resume")
            raise StudyError(f"cannot resume {self.out}: the checkpoint of case {case.name!r} was written by {how}")
        if self.comm is None:
            ck = self.store.load(case.name, self._decode_checkpoint)
        else:
            ck = self._common_checkpoint(case)
        if ck is not None and ck["parameters_hash"] not in (None, self.hash):
            raise StudyError(f"cannot resume {self.out}: checkpoint of case {case.name!r} was computed with other "
                             f"parameters ({ck['parameters_hash']}) than this run ({self.hash}); start a new run")
        return ck

    def _common_checkpoint(self, case: Case) -> dict | None:
        """On MPI ranks: the newest generation of ``case``'s checkpoint that every rank has (a run
        stopped while the ranks wrote theirs may have left one rank a generation ahead), else None
        (with a warning: the case starts again)."""
        cks = list(self.store.readable(case.name, self._decode_checkpoint))
        keys = [(ck["done"], len(ck["rows"])) for ck in cks]
        every = self.comm.allgather(keys)
        common = [k for k in every[0] if all(k in other for other in every)]
        if not common:
            if any(every):
                warnings.warn(f"case {case.name!r}: the MPI ranks have no checkpoint generation in common; the "
                              "case starts again", CheckpointWarning, stacklevel=2)
            return None
        return cks[keys.index(common[0])]
