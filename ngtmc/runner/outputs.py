"""The outputs of a run folder, as plugins on the accepted steps (:mod:`ngtmc.simulation.plugins`):

* :class:`SnapshotOutput`: fields at the chosen loads (``snapshots.npz`` and ``vtk/``);
* :class:`CheckpointOutput`: a checkpoint and the run's files every so many steps or seconds;
* :class:`ReportOutput`: ``report.html``, rendered from the run folder when the run ends.
"""
from __future__ import annotations

import time
from typing import Callable

import ngtmc.report
from ngtmc.simulation import Plugin, emit

__all__ = ["SnapshotOutput", "CheckpointOutput", "ReportOutput"]


class SnapshotOutput(Plugin):
    """Takes the fields (:class:`ngtmc.runner.snapshots.Snapshots`) at the first accepted step at or past
    each chosen load, and at the last step."""

    def __init__(self, snaps, prev_load: float):
        self.snaps = snaps
        self.prev_load = float(prev_load)

    def step(self, sim, row: dict):
        self.snaps.maybe_take(self.prev_load, row, final=sim.finished)
        self.prev_load = float(row["load"])


class CheckpointOutput(Plugin):
    """Keeps the state of the last accepted step, and every ``every`` steps or ``seconds`` seconds
    calls ``save(state)`` (a checkpoint and the run's files); on the MPI ranks of ``comm``, at the
    steps where rank 0's clock says so."""

    def __init__(self, sim, save: Callable[[dict], None], every: int, seconds: float, comm=None):
        self.save = save
        self.comm = comm  # MPI ranks save together, when rank 0 says so
        self.every = int(every)
        self.seconds = float(seconds)
        self.state = sim.get_state()
        self.at_step = sim.step
        self.at_time = time.perf_counter()

    def step(self, sim, row: dict):
        self.state = sim.get_state()
        now = time.perf_counter()
        due = sim.step - self.at_step >= self.every or now - self.at_time >= self.seconds
        if self.comm is not None:
            due = self.comm.bcast(due, root=0)
        if due:
            self.save(self.state)
            self.at_step, self.at_time = sim.step, time.perf_counter()


class ReportOutput(Plugin):
    """``report.html`` of the run folder ``out`` (:func:`ngtmc.report.render_report`), rendered once
    when the run ends, from the files of the folder; nothing per step. A run that did not complete
    still gets its report (with a status banner). ``strict``: a report of a completed run that
    cannot be rendered raises; otherwise, and always for a run that did not complete, the reason is
    printed on stderr. ``path``: the report, once rendered."""

    def __init__(self, out, strict: bool = False):
        self.out = out
        self.strict = bool(strict)
        self.path = None

    def finish(self, status: str):
        strict = self.strict and status == "completed"
        try:
            self.path = ngtmc.report.render_report(self.out)
        except Exception as e:
            if strict:
                raise
            emit(f"[ngtmc] report not rendered: {type(e).__name__}: {e}")
        return self.path
