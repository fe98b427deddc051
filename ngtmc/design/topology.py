"""Topology optimisation of a scene of one's own (:class:`TopologyOptimisation`): the elements of
the design regions carry one variable each, filtered, projected and interpolated into the model's
pseudo-density (:class:`~ngtmc.design.density.DesignDensity`; solid where rho = 1, third medium
where rho = 0, the model's gamma(rho) and Gc(rho) in between), an objective of
:mod:`ngtmc.sensitivities` (default: the external work over the stroke, maximised) under a bound on
the physical volume, by MMA (:func:`~ngtmc.design.optimiser.mma`) with beta continuation: one MMA
run per value of ``beta``, each from the design the last one ended with, lowered by a constant
where the sharper projection took its volume over the bound (MMA starts each stage feasible).

A design whose forward run fails after its retries (:class:`~ngtmc.design.evaluation.DesignEvaluation`)
is never accepted: MMA starts again from the last design that ran, with its first move halved
(``shortened`` counts these restarts); below a move of 1e-3 the optimisation stops with
:class:`~ngtmc.design.evaluation.DesignFailure`.

    opt = TopologyOptimisation(scene, design="design", schedule=0.3, volume_fraction=0.5,
                               filter_radius=0.15)
    result = opt.run(evaluations=100)
    result.objective, result.volume, result.xbar      # N mm, -, per design element

Units: mm, N, MPa; the objective in its own unit (N mm for the external work)."""
from __future__ import annotations

from dataclasses import dataclass, field
import math
import sys
import time

import numpy as np

from ngtmc import sensitivities as sens
from ngtmc.design.density import DesignDensity
from ngtmc.design.evaluation import DesignEvaluation, DesignFailure
from ngtmc.design.interpolation import Interpolation
from ngtmc.design.optimiser import mma
from ngtmc.design.projection import project
from ngtmc.scene import Scene

__all__ = ["TopologyOptimisation", "TopologyResult"]

#: below this first move (in units of x) a design that keeps failing stops the optimisation
SMALLEST_STEP = 1e-3


@dataclass
class TopologyResult:
    """Outcome of :meth:`TopologyOptimisation.run`: the final design ``x`` (per design element),
    its physical density ``xbar`` and the model's pseudo-density ``rho`` (per element of the
    mesh), its ``objective`` (in the objective's unit, as maximised or minimised) and ``volume``
    fraction, ``evaluations`` (forward runs with their adjoint), ``history`` (one dict per
    evaluation: evaluation, stage, beta, objective, volume, forward_s, adjoint_s,
    newton_iterations, steps, attempts), ``designs`` (evaluation -> xbar, at the starts and ends
    of the stages and in between), ``failures`` (every failed forward attempt, recovered or not),
    ``shortened`` (MMA restarts after a design that did not run), ``seconds`` (wall time, s),
    per stage nlopt's ``status`` and ``stage_x``, the design variables at the end of each stage."""

    x: np.ndarray
    xbar: np.ndarray
    rho: np.ndarray
    objective: float
    volume: float
    evaluations: int
    history: list
    designs: dict
    failures: list
    shortened: int
    seconds: float
    status: list = field(default_factory=list)
    stage_x: list = field(default_factory=list)

    def time_split(self) -> dict:
        """Seconds of forward runs, of adjoint sweeps and of the rest, and the adjoint's cost in
        forward runs (adjoint s / forward s)."""
        fwd = float(sum(r["forward_s"] for r in self.history))
        adj = float(sum(r["adjoint_s"] for r in self.history))
        return {"forward_s": fwd, "adjoint_s": adj, "other_s": max(self.seconds - fwd - adj, 0.0),
                "adjoint_per_forward": adj / fwd if fwd > 0 else math.nan}


def _entry(r: dict, evaluation: int, stage: int) -> dict:
    """The history entry of an evaluation ``r`` of :meth:`DesignEvaluation.evaluate`."""
    return {"evaluation": evaluation, "stage": stage, "beta": r["beta"], "objective": r["value"],
            **{k: r[k] for k in ("volume", "forward_s", "adjoint_s", "newton_iterations", "steps", "attempts")}}


class TopologyOptimisation:
    """Topology optimisation of ``scene`` over the regions ``design`` (see the module docstring).

    schedule : Schedule or float
        The load path (a float: from 0 to that imposed displacement, mm).
    objective : ngtmc.sensitivities.Objective
        Default :class:`~ngtmc.sensitivities.ExternalWork` (N mm), maximised.
    maximise : bool
        Maximise the objective (default) or minimise it.
    volume_fraction : float
        Bound on the physical volume of the design regions, as a fraction of their volume (0, 1].
    filter_radius : float
        Helmholtz filter radius, mm (> 0): the smallest feature is about this size.
    interpolation : Interpolation
        Default SIMP with p = 3.
    beta : sequence of float
        The projection's sharpness, one MMA run per value (continuation), default (1, 2, 4, 8).
    eta : float
        Projection threshold in (0, 1).
    control, newton, retries, options
        Of the forward runs (:class:`~ngtmc.design.evaluation.DesignEvaluation`).
    initial_step : float
        MMA's first move (units of x), halved at each restart after a failed design.
    progress : bool
        A line per evaluation on stderr.
    """

    def __init__(self, scene: Scene, design, schedule, objective=None, maximise: bool = True,
                 volume_fraction: float = 0.5, filter_radius: float = 0.1, interpolation: Interpolation | None = None,
                 beta=(1.0, 2.0, 4.0, 8.0), eta: float = 0.5, control=None, newton=None, retries: int = 2,
                 initial_step: float = 0.2, progress: bool = True, **options):
        vf = float(volume_fraction)
        if not (0.0 < vf <= 1.0):
            raise ValueError(f"TopologyOptimisation: volume_fraction = {volume_fraction!r} must lie in (0, 1]")
        self.betas = [float(b) for b in np.atleast_1d(beta)]
        if not self.betas:
            raise ValueError("TopologyOptimisation: beta is empty (give at least one value)")
        for b in self.betas:   # each value checked by the projection
            project(0.5, b, eta)
        self.density = DesignDensity(scene, design, filter_radius, interpolation, self.betas[0], eta)
        self.objective = objective if objective is not None else sens.ExternalWork()
        self.evaluation = DesignEvaluation(scene, self.density, schedule, self.objective, control, newton, retries,
                                           **options)
        self.volume_fraction, self.maximise = vf, bool(maximise)
        if not (math.isfinite(float(initial_step)) and float(initial_step) > 0):
            raise ValueError(f"TopologyOptimisation: initial_step = {initial_step!r} must be a finite number > 0")
        self.initial_step, self.progress = float(initial_step), bool(progress)

    def _say(self, text: str):
        if self.progress:
            print(f"[ngtmc design] {text}", file=sys.stderr, flush=True)

    def _feasible(self, x):
        """``x``, or where its physical volume exceeds the bound (a sharper projection moves it),
        ``x`` lowered by the smallest constant that brings the volume to the bound (clipped to
        [0, 1]; bisection): MMA starts a stage from a feasible design. Started from a design 1.6 %
        over the bound, nlopt's MMA was measured to slide to an empty design and stay there."""
        dens, vf = self.density, self.volume_fraction
        if dens.volume(x) <= vf:
            return x
        lo, hi = 0.0, 1.0
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if dens.volume(np.clip(x - mid, 0.0, 1.0)) <= vf else (mid, hi)
        return np.clip(x - hi, 0.0, 1.0)

    def _evaluate_first(self, x, stage):
        """The first design of a stage run (MMA's first call then finds it cached)."""
        try:
            return self.evaluation.evaluate(x, record=False)
        except DesignFailure as e:
            raise DesignFailure(f"stage {stage}: its first design did not run: {e}", e.attempts) from e

    def run(self, evaluations: int = 100, x0=None, frames: int = 6, callback=None) -> TopologyResult:
        """Optimise with at most ``evaluations`` forward runs (with their adjoints) in all, split
        evenly over the values of beta, from ``x0`` (default: uniform at the volume bound).
        ``designs`` keeps about ``frames`` designs besides the stage ends. ``callback(record)``
        after every evaluation."""
        total = int(evaluations)
        if total < len(self.betas):
            raise ValueError(f"TopologyOptimisation.run: evaluations = {evaluations!r} must be at least one per "
                             f"value of beta ({len(self.betas)})")
        dens, ev = self.density, self.evaluation
        x = np.full(dens.n, self.volume_fraction) if x0 is None else dens.check(x0).copy()
        sign = -1.0 if self.maximise else 1.0
        history: list[dict] = []
        designs: dict = {0: dens.physical(x)}
        every = max(1, total // max(int(frames), 1))
        status, shortened, t0, stage_x = [], 0, time.perf_counter(), []
        last = {"x": x.copy()}
        budgets = [total // len(self.betas)] * len(self.betas)
        budgets[-1] += total - sum(budgets)
        for stage, (beta, budget) in enumerate(zip(self.betas, budgets), start=1):
            dens.beta = beta
            x = self._feasible(x)
            step = self.initial_step
            designs.setdefault(len(history), dens.physical(x))

            # MMA's moves depend on the size of the gradients: scaled so that the largest entry of
            # each gradient at the stage's first design is 1 (the first evaluation of the stage)
            first = self._evaluate_first(x, stage)
            scale_f = 1.0 / max(float(np.max(np.abs(first["gradient"]))), 1e-300)
            scale_c = 1.0 / max(float(np.max(np.abs(dens.volume_gradient(x)))), 1e-300)

            def objective(xs, stage=stage, beta=beta):
                r = ev.evaluate(xs)
                rec = _entry(r, len(history) + 1, stage)
                history.append(rec)
                last["x"] = np.array(xs)
                if len(history) % every == 0:
                    designs[len(history)] = dens.physical(xs)
                self._say(f"evaluation {len(history)}/{total} (beta {beta:g}): J = {r['value']:.6g}, volume "
                          f"{r['volume']:.4f}, forward {r['forward_s']:.1f} s, adjoint {r['adjoint_s']:.1f} s")
                if callback is not None:
                    callback(rec)
                return sign * scale_f * r["value"], sign * scale_f * r["gradient"]

            def volume(xs):
                return scale_c * (dens.volume(xs) - self.volume_fraction), scale_c * dens.volume_gradient(xs)

            while budget > 0:
                before = len(history)
                try:
                    res = mma(objective, x, 0.0, 1.0, [volume], max_evaluations=budget, initial_step=step)
                    x = np.clip(res.x, 0.0, 1.0)
                    status.append(res.status)
                    budget = 0
                except DesignFailure as e:
                    shortened += 1
                    budget -= len(history) - before + 1
                    x, step = last["x"].copy(), step / 2
                    self._say(f"{e}; MMA starts again from the last design that ran, first move {step:g}")
                    if step < SMALLEST_STEP:
                        raise DesignFailure(f"{e} (and at every shorter move down to {SMALLEST_STEP:g})",
                                            e.attempts) from e
            designs[len(history)] = dens.physical(x)
            stage_x.append(x.copy())
        final = ev.evaluate(x)
        history.append(_entry(final, len(history) + 1, len(self.betas)))
        return TopologyResult(x=x, xbar=dens.physical(x), rho=dens.rho(x), objective=final["value"],
                              volume=final["volume"], evaluations=len(history), history=history, designs=designs,
                              failures=list(ev.failures), shortened=shortened, seconds=time.perf_counter() - t0,
                              status=status, stage_x=stage_x)
