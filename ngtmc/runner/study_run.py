"""Run a named study into a run folder: :func:`run_study`, the checks before a run, the claim of
the folder and the run of its cases (in this process, on MPI ranks or on a Dask cluster)."""
from __future__ import annotations

import contextlib
import datetime as _dt
import os
import shutil
import tempfile
from pathlib import Path
from types import ModuleType
from typing import Callable, Sequence

import numpy as np

from ngtmc.discrete import blas_limited
from ngtmc.runner.outputs import ReportOutput
from ngtmc.study import effective_status, read_metadata
from ngtmc.study import resume_parameters, typed_overrides
from ngtmc.study import load_study
from ngtmc.study import StudyError
from ngtmc.study import study_parameters
from ngtmc.runner.cases import _Run
from ngtmc.runner.claim import FolderClaim
from ngtmc.runner.parallel import ParallelCases, check_settings
from ngtmc.scene import Scene
from ngtmc.simulation import emit

__all__ = ["run_study", "execute", "default_output", "case_threads", "AUTO_TWO_THREADS_ELEMENTS",
           "AUTO_TWO_THREADS_ELEMENTS_3D"]


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


#: A serial case runs with two NGSolve threads only from this many elements in its mesh. Alone,
#: with numpy's BLAS on one thread (ngtmc.discrete.blas_threads), a second thread pays on the
#: quick meshes too (quick three-point bending 44.2 against 63.3 s); but two runs side by side
#: with two threads each on the 2-core machine were more than ten times slower than with one
#: each (docs/performance.md, "What makes an iteration cheap"), and test suites, benchmarks and
#: studies are often run side by side: small meshes keep one thread, ``--threads 2`` asks for two.
AUTO_TWO_THREADS_ELEMENTS = 20000

#: The same threshold for 3D meshes, whose tangents have several times the nonzeros per row.
#: Measured 2026-12-02 on the quarter hemisphere of the 3D study at quick (10896 tetrahedra,
#: 19536 displacement dofs, the same 59 steps and 461 Newton iterations): the peak reached after
#: 146 s with one thread and 91 s with two, 0.08 mm after 453 and 319 s (docs/three-d.md).
AUTO_TWO_THREADS_ELEMENTS_3D = 10000


def case_threads(case) -> int:
    """NGSolve threads of a serial case with ``threads="auto"``: 2 if its (already built) scene's
    mesh has at least AUTO_TWO_THREADS_ELEMENTS elements (AUTO_TWO_THREADS_ELEMENTS_3D in 3D),
    else 1 (also for a case whose scene is not built)."""
    scene = getattr(case, "scene", None)
    if not isinstance(scene, Scene):
        return 1
    limit = AUTO_TWO_THREADS_ELEMENTS_3D if scene.mesh.dim == 3 else AUTO_TWO_THREADS_ELEMENTS
    return 2 if scene.mesh.ne >= limit else 1


def run_study(name: str | ModuleType, resolution: str | None = None, output: str | Path | None = None,
              overrides: dict | None = None, report: bool | None = None, resume: bool = False,
              progress: bool | Callable = True, *, threads: int | str | None = "auto", checkpoint_every: int = 25,
              checkpoint_seconds: float = 30.0, vtk: bool = True,
              callbacks: Sequence[Callable] = (), workers: int | None = None,
              scheduler: str | None = None, mpi: bool = False) -> Path:
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
    threads : int, None or "auto"
        ``ngsolve.SetNumThreads`` (an integer >= 1); the run is inside ``ngsolve.TaskManager()``.
        None: leave as is. "auto" (default): per case, :func:`case_threads` (2 from
        AUTO_TWO_THREADS_ELEMENTS elements, AUTO_TWO_THREADS_ELEMENTS_3D in 3D, else 1; each case in
        its own TaskManager, the count recorded in the case's metadata), or 1 per worker when the
        cases run on a cluster.
    checkpoint_every, checkpoint_seconds : checkpoint period in accepted steps and seconds.
    vtk : bool
        Write the ParaView series into ``vtk/``.
    callbacks : functions f(simulation, row) called after every accepted step (row includes ``case``).
        With ``workers`` or ``scheduler`` they (and a callable ``progress``) run in the worker
        processes: they must pickle, and what they change stays there.
    workers : int, optional
        Compute the cases in parallel, one per task, on a local Dask cluster of this many worker
        processes (one thread each; ``threads`` NGSolve threads each). Needs the extra
        ``parallel`` (``pip install ngtmc[parallel]``). The files and the report are those of a
        serial run; a failed case fails only itself (:class:`ngtmc.runner.parallel.CaseFailure`
        after the others are written), and ``resume=True`` re-runs it. See docs/parallel.md.
    scheduler : str, optional
        Address of an existing Dask scheduler to send the cases to instead (its workers must see
        the run folder and import ngtmc and the study).
    mpi : bool
        Every case on one mesh distributed over the MPI ranks this process belongs to
        (``mpiexec -n 3 python -m mpi4py -m ngtmc run ... --mpi``; :mod:`ngtmc.scene.distributed`, the
        extra ``mpi``). Every rank calls this; rank 0 writes the run folder and the report
        (history, metadata, and the snapshots and ParaView series of the fields gathered from the
        ranks, :mod:`ngtmc.runner.rank_snapshots`), and every rank its
        checkpoints, ``checkpoint/<case>.rank<r>of<n>.npz``, so ``resume=True`` continues on the
        same number of ranks. The conditions :func:`ngtmc.scene.distributed.check_supported` refuses are
        refused before anything is solved. See docs/parallel.md.

    Raises StepFailure (after writing the history and metadata with status "failed") when a step
    fails at the minimum increment, and StudyError, before any folder is created or anything
    solved, for bad input (unknown study, resolution or override, ill-typed or out-of-range
    values, a bad scene, threads < 1) or a resume that would mix parameters.
    """
    return execute(name, resolution, output, overrides, report, resume, progress, threads, checkpoint_every,
                    checkpoint_seconds, vtk, callbacks, workers=workers, scheduler=scheduler, mpi=mpi).out


def _mpi_world(parallel: bool):
    """COMM_WORLD for ``mpi=True``; StudyError where MPI cannot run this (checked on every rank
    alike, so that all of them stop)."""
    if parallel:
        raise StudyError("mpi=True / --mpi runs one case at a time on all ranks: it does not combine with "
                         "workers / scheduler (--workers, --scheduler)")
    try:
        from mpi4py import MPI
    except ImportError:
        raise StudyError("mpi=True / --mpi needs mpi4py and an MPI: pip install ngtmc[mpi] "
                         "(docs/parallel.md)") from None
    comm = MPI.COMM_WORLD
    if comm.size < 2:
        raise StudyError("mpi=True / --mpi but this process is the only MPI rank: start it with "
                         "mpiexec -n 3 python -m mpi4py -m ngtmc run ... --mpi (NGSolve gives rank 0 no "
                         "elements, so 3 ranks compute on 2)")
    return comm


def execute(name, resolution, output, overrides, report, resume, progress, threads, checkpoint_every,
             checkpoint_seconds, vtk, callbacks, *, workers=None, scheduler=None, mpi=False) -> "_Run":
    """The work of :func:`run_study`; returns the finished run (its folder ``out``, and the
    Simulation of each case computed in this process in ``simulations``)."""
    parallel = workers is not None or scheduler is not None
    comm = _mpi_world(parallel) if mpi else None
    root = comm is None or comm.rank == 0
    if not root:  # the other ranks compute, rank 0 reports and writes
        progress, report, vtk = False, False, False
    if parallel:
        check_settings(workers, scheduler)     # Dask installed, settings sane: before anything else
    auto = threads == "auto"
    if auto:  # a serial run's count follows its mesh size, known after validate() below
        threads = 1 if parallel else None
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
    # one run per folder: claimed before anything is written or checked (FolderClaim)
    with (FolderClaim(out, note=_say) if root else contextlib.nullcontext()):
        if not resume and out.exists() and (out / "history.csv").exists():
            old = read_metadata(out) or {}
            status, note = effective_status(old) if old else ("unknown", None)
            raise StudyError(f"{out} holds a run already (status {status}{': ' + note if note else ''}): choose "
                             "another output, or resume=True / --resume to continue it")
        return _claimed(mod, res, p, out, typed, comm, root, meta, resume, report, progress, threads, auto,
                        parallel, workers, scheduler, checkpoint_every, checkpoint_seconds, callbacks, vtk)


def _say(message: str):
    """A line of the run's own (before its progress printer exists), on stderr."""
    emit(f"[ngtmc] {message}")


def _claimed(mod, res, p, out, typed, comm, root, meta, resume, report, progress, threads, auto, parallel,
             workers, scheduler, checkpoint_every, checkpoint_seconds, callbacks, vtk) -> "_Run":
    """The rest of :func:`execute`, in a folder this run has claimed."""
    with _rank_folder(out, comm) as rank_out:
        run = _Run(mod, res, p, rank_out, typed, progress, checkpoint_every, checkpoint_seconds, callbacks, vtk,
                   comm=comm)
        if comm is not None:
            run.use_rank_checkpoints(out / "checkpoint")
        out = rank_out
        if resume:
            if meta is not None and meta.get("status") == "running":
                run.progress.say(f"{out}: {effective_status(meta)[1] or 'recorded as running'}")
            run.prepare_resume(meta)
        run.validate()     # bad input is refused here, before any folder is created or any step solved
        import ngsolve as ngs
        per_case = auto and not parallel and comm is None
        if per_case:   # each case's count follows its mesh (run_cases enters a TaskManager per case)
            run.case_threads = case_threads
        if comm is not None:
            threads = 1  # one thread per rank
        if threads:
            ngs.SetNumThreads(int(threads))
        run.progress.say(f"resolution {res!r}, output {out}")
        # outputs of the whole run (those of each case: _Run.run_case)
        outputs = [ReportOutput(out, strict=bool(report))] if (report or report is None) else []
        run_cases = None
        if parallel:
            run_cases = ParallelCases(run, workers, scheduler, threads)
        try:
            with _terminate_as_interrupt(), (contextlib.nullcontext() if per_case else ngs.TaskManager()), blas_limited():
                run.run(resume, meta, run_cases)
        except BaseException:
            # a failed or interrupted run still gets its report (with a status banner): nothing is lost
            for plugin in outputs:
                plugin.finish("interrupted" if run.status == "interrupted" else "failed")
            raise
        run.progress.say(f"finished in {run.wall_time():.0f} s: {out}")
        for plugin in outputs:
            plugin.finish(run.status)
        return run


@contextlib.contextmanager
def _rank_folder(out: Path, comm):
    """The folder this process writes the run into: ``out``, except on the MPI ranks other than 0
    (``mpi=True``), which compute only: there a scratch folder, removed afterwards."""
    if comm is None or comm.rank == 0:
        yield out
        return
    scratch = Path(tempfile.mkdtemp(prefix=f"ngtmc-rank{comm.rank}-"))
    try:
        yield scratch
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


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
