"""The cases of a run on a Dask cluster: ``ngtmc run STUDY --workers N`` (a local cluster of N
processes) or ``--scheduler ADDRESS`` (an existing one); ``run_study(..., workers=N)`` or
``scheduler=ADDRESS``. Needs the extra ``parallel`` (``pip install ngtmc[parallel]``, which
installs ``dask[distributed]``); see ``docs/parallel.md``.

One case per task. A worker computes its case with the serial code (:meth:`_Run.run_case`: the
Simulation, its plugins, its checkpoints ``checkpoint/<case>.npz`` and ParaView series ``vtk/``,
every file written atomically into the shared run folder) and writes none of the files of the
whole run. The main process takes each finished case from its checkpoint, as a resume does
(:meth:`_Run.adopt`), and writes ``history.csv``, ``snapshots.npz`` and ``metadata.json`` after
each one; the report at the end, as in a serial run. The cases are independent: the histories
are those of the serial run.

A case that raises in its worker, or whose worker dies, is recorded as failed (with the steps of
its last checkpoint) while the other cases go on; the run then fails with :class:`CaseFailure`
naming it, and a resume re-runs it (from its checkpoint if it has one).
"""
from __future__ import annotations

import contextlib
import logging
from pathlib import Path
import uuid

import pandas as pd

from ngtmc.discrete import blas_limited
from ngtmc.study import StudyError
from ngtmc.runner.cases import _Run
from ngtmc.runner.folder import case_results

__all__ = ["CaseFailure", "ParallelCases", "EXTRA", "require_dask"]

#: How to install what this module needs.
EXTRA = "pip install ngtmc[parallel]"


class CaseFailure(RuntimeError):
    """Cases of a parallel run failed (the others completed). ``failures``: case -> error."""

    def __init__(self, failures: dict[str, str], n_cases: int):
        self.failures = dict(failures)
        what = "; ".join(f"case {name!r}: {err}" for name, err in self.failures.items())
        head = (f"case {next(iter(self.failures))!r} failed" if len(self.failures) == 1
                else f"{len(self.failures)} of {n_cases} cases failed")
        others = "; the other cases are written" if len(self.failures) < n_cases else ""
        super().__init__(f"{head} ({what}){others}; resume to re-run {'it' if len(self.failures) == 1 else 'them'}")


def require_dask():
    """The module ``distributed``, or StudyError naming the extra to install."""
    try:
        import distributed
    except ImportError as e:
        raise StudyError(f"running the cases in parallel (--workers / --scheduler) needs Dask's distributed "
                         f"scheduler, which is not installed ({e}): {EXTRA}") from e
    return distributed


def check_settings(workers, scheduler):
    """Refuse bad ``workers`` / ``scheduler`` before anything is run; check that Dask is there."""
    if workers is not None and scheduler is not None:
        raise StudyError("give workers (a local cluster) or scheduler (an existing one), not both")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise StudyError(f"workers = {workers!r} is not allowed: give an integer >= 1 (worker processes)")
    if scheduler is not None and not (isinstance(scheduler, str) and scheduler.strip()):
        raise StudyError(f"scheduler = {scheduler!r} is not allowed: give the address of a Dask scheduler, "
                         "e.g. tcp://10.0.0.1:8786")
    require_dask()
    if scheduler is not None:
        _check_reachable(scheduler.strip())


#: Seconds a scheduler has to accept a connection before the run is refused.
SCHEDULER_TIMEOUT = 5.0


def _check_reachable(address: str):
    """Refuse, before any folder exists, a scheduler address that is malformed or where nothing
    accepts a connection within SCHEDULER_TIMEOUT (a bad address hung 60 s and left a failed
    folder). tcp:// addresses (and bare host:port) are tried; other protocols are left to Dask."""
    import socket
    from urllib.parse import urlsplit
    url = urlsplit(address if "://" in address else "tcp://" + address)
    if url.scheme != "tcp":
        return
    try:
        host, port = url.hostname, url.port
    except ValueError:
        host, port = None, None
    if not host or not port:
        raise StudyError(f"scheduler = {address!r} is not an address host:port, e.g. tcp://10.0.0.1:8786")
    try:
        with socket.create_connection((host, port), timeout=SCHEDULER_TIMEOUT):
            pass
    except OSError as e:
        raise StudyError(f"no Dask scheduler answers at {address} ({e.strerror or e}); start one "
                         f"(dask scheduler) or check the address") from None


@contextlib.contextmanager
def _client(workers: int | None, scheduler: str | None):
    """A Client of the scheduler at ``scheduler``, or of a local cluster of ``workers`` processes
    with one thread each, no memory limit and no retry of a case whose worker died."""
    import dask
    distributed = require_dask()
    if scheduler is not None:
        with distributed.Client(scheduler, set_as_default=False) as client:
            yield client
        return
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                      memory_limit=0, dashboard_address=None,
                                      silence_logs=logging.ERROR) as cluster:
            with distributed.Client(cluster, set_as_default=False) as client:
                yield client


def _dumps(obj) -> bytes:
    """``obj`` pickled for the workers. A study loaded from a file is not importable there by its
    module name: it travels by value."""
    import importlib.machinery
    import sys
    import cloudpickle
    mod = obj[0]
    top = mod.__name__.split(".")[0]
    if mod.__name__ in sys.modules and importlib.machinery.PathFinder.find_spec(top) is None \
            and top not in sys.builtin_module_names:
        cloudpickle.register_pickle_by_value(mod)
        try:
            return cloudpickle.dumps(obj)
        finally:
            cloudpickle.unregister_pickle_by_value(mod)
    return cloudpickle.dumps(obj)


class _CaseRun(_Run):
    """One case of a run in a worker: the serial case code, its checkpoints and ParaView files;
    the files of the whole run (history, snapshots, metadata) are the main process's."""

    def write_all(self):
        pass


def compute_case(spec: bytes, name: str, checkpoint: dict | None, threads: int | None) -> dict:
    """In a worker: compute case ``name`` of the run described by ``spec`` with the serial case
    code, continuing from ``checkpoint`` if given. Returns what the checkpoint does not hold (the
    scene's mesh, force unit, thickness and features) and the error of a failed case, or None."""
    import cloudpickle
    import ngsolve as ngs

    mod, resolution, p, out, overrides, settings = cloudpickle.loads(spec)
    run = _CaseRun(mod, resolution, p, Path(out), overrides, **settings)
    k, case = next((k, c) for k, c in enumerate(run.cases) if c.name == name)
    run.validate([case])
    if checkpoint is not None:
        run.resume_from[name] = checkpoint
    if threads:
        ngs.SetNumThreads(int(threads))
    error = None
    try:
        with ngs.TaskManager(), blas_limited():
            run.run_case(k, case, checkpoint is not None)
    except Exception as e:          # recorded in the checkpoint by run_case; the main process reports it
        error = f"{type(e).__name__}: {e}"
    return {"error": error, "mesh": run.mesh, "force_unit": run.force_unit, "thickness": run.thickness,
            "features": dict(run.features)}


def costliest_first(todo: list) -> list:
    """The (index, case) pairs of ``todo`` in the order a cluster starts them: descending
    ``Case.cost``, the study's order among equal costs. With fewer workers than cases, a long case
    started last would finish alone long after the others (step_control quick on 2 workers: its
    longest case, three quarters of the serial time, was third in the study's order)."""
    return sorted(todo, key=lambda kc: -float(getattr(kc[1], "cost", 1.0)))


class ParallelCases:
    """``run_cases`` of :meth:`_Run.run` that computes the cases of ``run`` on a Dask cluster:
    ``workers`` local processes, or the scheduler at ``scheduler``; ``threads``: NGSolve threads per
    worker (None: as the worker has them)."""

    def __init__(self, run, workers: int | None = None, scheduler: str | None = None, threads: int | None = 1):
        check_settings(workers, scheduler)
        self.run, self.workers, self.scheduler, self.threads = run, workers, scheduler, threads
        self.extras: dict[str, dict] = {}
        self.fixed = {"mesh": run.mesh, "force_unit": run.force_unit, "thickness": run.thickness}

    def where(self) -> str:
        return f"the scheduler at {self.scheduler}" if self.scheduler else f"a local cluster of {self.workers} workers"

    def __call__(self, resume: bool):
        run = self.run
        n = len(run.cases)
        todo = []
        for k, case in enumerate(run.cases):
            if run.completed(case):
                run.progress.say(f"case {k + 1}/{n} {case.name}: already complete (checkpoint)")
            else:
                todo.append((k, case))
        if not todo:
            return
        run.parallel = {"workers": self.workers, "scheduler": self.scheduler or "local",
                        "threads_per_worker": self.threads}
        spec = _dumps((run.mod, run.resolution, run.p, str(Path(run.out).resolve()), run.overrides,
                       dict(progress=run.progress_setting, checkpoint_every=run.checkpoint_every,
                            checkpoint_seconds=run.checkpoint_seconds, callbacks=run.callbacks, vtk=run.vtk)))
        failures: dict[str, str] = {}
        pending = dict(todo)
        try:
            with _client(self.workers, self.scheduler) as client:
                from distributed import as_completed
                run.progress.say(f"{len(todo)} case(s) on {self.where()}")
                ordered = costliest_first(todo)
                futures = {client.submit(compute_case, spec, case.name, self._scattered(client, case.name),
                                         self.threads, key=f"ngtmc-{case.name}-{uuid.uuid4().hex[:8]}",
                                         pure=False, priority=len(ordered) - rank): (k, case)
                           for rank, (k, case) in enumerate(ordered)}
                for future in as_completed(futures, loop=client.loop):
                    k, case = futures[future]
                    try:
                        extras = future.result()
                    except Exception as e:   # the worker died (KilledWorker), or the task could not run
                        why = ("its worker process died" if type(e).__name__ == "KilledWorker"
                               else f"it could not be run on the cluster: {e}")
                        extras = {"error": f"{why} ({type(e).__name__})", "lost": True}
                    pending.pop(k)
                    self.take(case, extras)
                    if extras.get("error"):
                        failures[case.name] = extras["error"]
                        run.progress.say(f"case {k + 1}/{n} {case.name}: failed: {extras['error']}")
                    run.write_all()
        except KeyboardInterrupt:
            # the cases still running keep the steps of their last checkpoint
            for k, case in pending.items():
                self.take(case, {"error": "interrupted", "lost": True}, status="interrupted")
            raise
        except Exception as e:
            for k, case in pending.items():
                self.take(case, {"error": f"the cluster failed ({type(e).__name__}: {e})", "lost": True})
            raise
        if failures:
            raise CaseFailure(failures, n)

    def _scattered(self, client, name: str):
        """The checkpoint a resumed case continues from, sent to the cluster as data (a future)
        rather than inside the task (tens of MB at the paper's resolution, which Dask warns
        about on every resume), or None."""
        ck = self.run.resume_from.pop(name, None)
        return None if ck is None else client.scatter([ck], hash=False)[0]

    def take(self, case, extras: dict, status: str = "failed"):
        """Case ``case`` finished in a worker: take it from its checkpoint (as a resume does), with
        ``extras`` from :func:`compute_case`; a case whose worker was lost gets ``status``."""
        run = self.run
        ck = run.load_checkpoint(case)
        if ck is not None:
            run.adopt(case, ck)
        if extras.get("lost"):
            rows = run.rows.get(case.name) or []
            run.results[case.name] = {**case_results(pd.DataFrame(rows)), "status": status,
                                      "error": extras["error"]}
        else:
            self.extras[case.name] = extras
        order = [c.name for c in run.cases]      # in the order of the study, as a serial run has them
        run.results = {name: run.results[name] for name in order if name in run.results}
        run.snaps = {name: run.snaps[name] for name in order if name in run.snaps}
        self.merge()

    def merge(self):
        """The run's mesh, force unit and thickness are those of its first case (in the order of the
        study) as in a serial run; its features those of all cases."""
        first = next((self.extras[c.name] for c in self.run.cases
                      if (self.extras.get(c.name) or {}).get("force_unit") is not None), None)
        if first is not None:
            for key, value in self.fixed.items():
                if value is None:
                    setattr(self.run, key, dict(first[key]) if key == "mesh" else first[key])
        for extras in self.extras.values():
            for key, has in (extras.get("features") or {}).items():
                self.run.features[key] = bool(self.run.features.get(key, False) or has)
