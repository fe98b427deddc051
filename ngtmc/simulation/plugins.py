"""Outputs of a run as small objects ("plugins") on the accepted steps.

:meth:`ngtmc.Simulation.steps` yields the history row of each accepted step; a plugin is called
as ``plugin(simulation, row)`` on each (``Simulation.run(callbacks=...)`` does the same), and
``plugin.finish(status)`` once at the end of what it serves ("completed", "failed" or
"interrupted"). The outputs of a run folder are such plugins, used in the same way by a named
study (:func:`ngtmc.run_study`) and by a user's own scene (``ngtmc.simulate(..., out_dir=...)``):

* :class:`Progress`: the one progress printer (also behind ``Simulation(progress=True)``): step,
  load (mm), step size (mm), force with its unit, Newton iterations, cut-backs, the elements of
  a mesh refined during the run, the share of the load path done and an estimate of the time left
  from the recent pace;
* :class:`RowCallbacks`: user functions ``f(simulation, row)``, the row carrying its ``case``.

The outputs of a run folder (snapshots, checkpoints, the report) are plugins of the runner:
:mod:`ngtmc.runner.outputs`.

The history itself is the Simulation's list of rows; the run writes it with its checkpoints.
"""
from __future__ import annotations

from collections import deque
import math
import sys
import time
from typing import Callable, Sequence

__all__ = ["emit", "Plugin", "Progress", "RowCallbacks"]


class Plugin:
    """Base of the outputs: ``step(sim, row)`` after every accepted step, ``finish(status)`` at the
    end ("completed", "failed" or "interrupted")."""

    def step(self, sim, row: dict):  # pragma: no cover - overridden
        pass

    def finish(self, status: str):
        pass

    def __call__(self, sim, row: dict):
        self.step(sim, row)


def emit(text: str):
    """Print a line on stderr. Where stderr is a pipe whose reader has gone (``ngtmc run ... 2>&1 |
    head -3``), the line is dropped and stderr goes to the null device for the rest of the process:
    a closed pipe ends the printing, never the run (it used to be recorded as failed)."""
    try:
        print(text, file=sys.stderr, flush=True)
    except BrokenPipeError:
        import os
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stderr.fileno())
        os.close(null)


class Progress(Plugin):
    """Progress line on stderr about every ``interval`` seconds and at the last step.

    ``prefix`` starts each line (e.g. ``"[ngtmc]"`` or ``"[ngtmc three_point_bending] case 1/5
    main:"``); ``unit`` is the force unit of the run (:func:`force_unit`). Every line gives the
    step, load, force, elapsed time and the share of the load path reached: the furthest share so
    far, so that it never goes back (path following turns the load back in a snap-back; the
    line then says so).

    The time left is an estimate from the pace (load path per second of wall time) over the last
    ``window`` seconds, so shrinking steps after a crack starts slow it down instead of being
    averaged away; it is labelled as an estimate, and left out (said so) where it cannot be made
    honestly: in a scene that may crack, before the crack has formed (max alpha < CRACK_ALPHA:
    the pace before the peak said 1/10 of the time left on the quick three-point bending) and
    while it runs (the dissipated energy grew by more than CRACK_RUNNING of its value within the
    window: the steps then shrink and grow again in ways the pace cannot foresee), while the
    load turns back, and while it exceeds 20 times the time so far (steps
    of a crack running at almost constant load). Its measured error on the quick studies:
    ``benchmarks/progress_estimate.py``. ``enabled`` may be a callable, which then receives
    each row instead.
    """

    #: The crack runs (no estimate) while the dissipated energy grows by more than this share of
    #: its value within the pace window.
    CRACK_RUNNING = 0.01
    #: ... once a crack has formed: AT-2 damages diffusely from the first step, below this.
    CRACK_ALPHA = 0.95

    def __init__(self, enabled: bool | Callable = True, prefix: str = "[ngtmc]", unit: str = "N",
                 interval: float = 5.0, window: float = 60.0, case: str | None = None):
        self.enabled = enabled
        self.prefix = prefix
        self.unit = unit
        self.interval = float(interval)
        self.window = float(window)
        self.case = case
        self.last = -1e9
        self.pace: deque = deque()     # (elapsed wall time s, pseudo-time of the load path)
        self.dissipation: deque = deque()   # (elapsed wall time s, dissipated energy N mm)
        self.furthest = 0.0            # the largest share of the load path reached

    def say(self, text: str):
        if self.enabled is True:
            emit(f"{self.prefix} {text}")

    def _windowed(self, entries: deque, elapsed: float, value: float) -> tuple[float, float]:
        """Append ``(elapsed, value)`` to ``entries``, drop what lies before the last ``window``
        seconds, and return the oldest entry kept."""
        entries.append((elapsed, value))
        while len(entries) > 2 and elapsed - entries[1][0] >= self.window:
            entries.popleft()
        return entries[0]

    def time_left(self, elapsed: float, t: float, total: float) -> tuple[float, float] | None:
        """``(seconds left, seconds of the pace window)`` from the recent pace, or None."""
        e0, t0 = self._windowed(self.pace, elapsed, t)
        if elapsed - e0 <= 0 or t - t0 <= 0 or total <= 0 or t >= total:
            return None
        return (total - t) * (elapsed - e0) / (t - t0), elapsed - e0

    def crack_running(self, elapsed: float, row: dict) -> bool:
        """True while the dissipated energy of the row grew by more than CRACK_RUNNING of its value
        within the pace window."""
        d, a = row.get("dissipated_energy"), row.get("max_alpha")
        if d is None or not math.isfinite(float(d)):
            return False
        _, d0 = self._windowed(self.dissipation, elapsed, float(d))
        cracked = a is not None and float(a) >= self.CRACK_ALPHA
        return cracked and float(d) > 0 and float(d) - d0 > self.CRACK_RUNNING * float(d)

    def observe(self, sim, row: dict) -> tuple:
        """Take in an accepted step (every step, printed or not): the pace, the dissipation and the
        furthest share of the load path. Returns (elapsed s, share of the path, whether the load
        turned back, the time left or None, whether the crack runs)."""
        total = sim.schedule.total_time
        frac = sim.t / total if total > 0 else 1.0
        back = frac < self.furthest - 1e-12
        self.furthest = max(self.furthest, frac)
        el = float(row.get("wall_time", 0.0) or 0.0)
        return el, frac, back, self.time_left(el, sim.t, total), self.crack_running(el, row)

    def line(self, sim, row: dict) -> str:
        el, frac, back, left, running = self.observe(sim, row)
        eta = ""
        cracks = getattr(sim.solver, "alpha", None) is not None
        alpha_max = row.get("max_alpha")
        if back:
            eta = ", the load turns back (snap-back): no estimate of the time left"
        elif cracks and (alpha_max is None or alpha_max < self.CRACK_ALPHA) and self.furthest < 1.0:
            eta = ", no estimate of the time left before the crack has run (its steps cannot be foreseen)"
        elif running and self.furthest < 1.0:
            eta = ", no estimate of the time left while the crack runs"
        elif left is not None and frac < 1.0:
            if left[0] > 20.0 * max(el, 60.0):
                # tiny steps (a crack running at almost constant load): the recent pace says
                # nothing about the rest of the path, where the steps grow again
                eta = ", no estimate of the time left while the steps are this short"
            else:
                eta = f", about {left[0]:.0f} s left (estimate from the pace of the last {left[1]:.0f} s)"
        alpha = row.get("max_alpha")
        alpha = f"  max alpha {alpha:.3f}" if alpha is not None and getattr(sim.solver, "alpha", None) is not None else ""
        mesh = f"  {row['elements']} elements" if "elements" in row else ""   # adaptive refinement
        return (f"{self.prefix} step {row['step']:5d}  load {row['load']:.6g} mm  du {row['step_size']:.2e} mm  "
                f"force {row['force']:.5g} {self.unit}{alpha}  Newton {row['newton_iterations']}  "
                f"cut-backs {row['cutbacks']}{mesh}  {100 * self.furthest:5.1f} % of the load path  {el:.0f} s{eta}")

    def step(self, sim, row: dict):
        if not self.enabled:
            return
        if callable(self.enabled) and not isinstance(self.enabled, bool):
            self.enabled(dict(row, case=self.case) if self.case is not None else row)
            return
        now = time.perf_counter()
        if now - self.last < self.interval and not sim.finished:
            self.observe(sim, row)      # the pace, the dissipation and the furthest share need every step
            return
        self.last = now
        emit(self.line(sim, row))


class RowCallbacks(Plugin):
    """User functions ``f(simulation, row)``; the row carries ``case``."""

    def __init__(self, functions: Sequence[Callable], case: str):
        self.functions = list(functions)
        self.case = case

    def step(self, sim, row: dict):
        for f in self.functions:
            f(sim, dict(row, case=self.case))
