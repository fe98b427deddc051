"""One design, evaluated: the forward run of a scene with the design's density, the objective and
its adjoint gradient with respect to the design variables (:class:`DesignEvaluation`), robust on
every design an optimiser visits, and the check of that gradient against central differences
(:meth:`DesignEvaluation.gradient_check`).

A forward run first replays the load steps of the last successful run with the new density
(:func:`ngtmc.sensitivities.replay`: the solver is reused, the steps are those the objective was
taken over). Where that fails (Newton does not converge at a step), the design is run again from
the start with the adaptive step control, which may cut steps back, then with steps halved
``retries`` times. Every failed attempt is counted and kept (``failures``); a design none of whose
attempts succeeds raises :class:`DesignFailure`: a failed run is never an objective value.
Units: mm, N, MPa; an objective in its own unit (N mm for the external work)."""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ngtmc import sensitivities as sens
from ngtmc.design.density import DesignDensity
from ngtmc.discrete import NewtonOptions
from ngtmc.scene import Scene
from ngtmc.simulation import StepFailure
from ngtmc.stepping import AdaptiveStepControl, Schedule

__all__ = ["DesignEvaluation", "DesignFailure"]

try:  # NGSolve's own exception type, where it has one
    from ngsolve import NgException as _NgException
except ImportError:  # pragma: no cover
    _NgException = RuntimeError

#: what a failed forward run raises (Newton failure, a step at the minimum increment, a singular
#: factorization, an inverted element)
_RUN_ERRORS = (RuntimeError, StepFailure, ArithmeticError, np.linalg.LinAlgError, _NgException)


class DesignFailure(RuntimeError):
    """No attempt of a design's forward run succeeded; ``attempts`` lists (what, message)."""

    def __init__(self, message: str, attempts: list):
        super().__init__(message)
        self.attempts = attempts


class DesignEvaluation:
    """J(x) and dJ/dx for the design variables x of ``density`` (a :class:`DesignDensity` of
    ``scene``): ``scene`` run through ``schedule`` with ``control`` (default constant steps of a
    tenth of the stroke) and ``newton``, the objective ``objective`` (an
    :class:`ngtmc.sensitivities.Objective`) and its adjoint.

    ``evaluate(x)`` returns a dict with ``value`` (J), ``gradient`` (dJ/dx), ``path``, the times
    ``forward_s`` and ``adjoint_s`` (s), ``newton_iterations``, ``steps`` and ``attempts`` (failed
    attempts before the one that succeeded). ``records`` keeps one such dict per evaluation
    (without path and gradient); ``failures`` every failed attempt. The same design at the same
    beta twice in a row is run once. ``options`` go to
    :func:`ngtmc.sensitivities.record_path` (for example ``scheme``)."""

    def __init__(self, scene: Scene, density: DesignDensity, schedule, objective, control=None,
                 newton: NewtonOptions | None = None, retries: int = 2, **options):
        self.scene, self.density, self.objective = scene, density, objective
        self.schedule = schedule if isinstance(schedule, Schedule) else Schedule([0.0, float(schedule)])
        stroke = float(np.max(np.abs(self.schedule.points)))
        self.control = control or AdaptiveStepControl(du_max=stroke / 10, k_u=0.0, du_min=stroke / 640)
        self.newton = newton or NewtonOptions(rtol=1e-10)
        if int(retries) < 0:
            raise ValueError(f"DesignEvaluation: retries = {retries!r} must be >= 0")
        self.retries, self.options = int(retries), options
        self.records: list[dict] = []
        self.failures: list[dict] = []
        self._path = None
        self._last = None

    def _finite(self, path) -> bool:
        return bool(np.all(np.isfinite(path.forces)))

    def forward(self, x):
        """The forward path of design ``x`` (see the module docstring) and its failed attempts."""
        rho = self.density.rho(x)
        attempts = []
        if self._path is not None:
            try:
                path = sens.replay(self._path, rho=rho)
                if self._finite(path):
                    return path, attempts
                attempts.append(("replay of the last steps", "a force that is not finite"))
            except _RUN_ERRORS as e:
                attempts.append(("replay of the last steps", f"{type(e).__name__}: {e}"))
        c = self.control
        for k in range(self.retries + 1):
            ctrl = c if k == 0 else dataclasses.replace(c, du_max=c.du_max / 2 ** k, du_min=c.du_min / 2 ** k)
            what = f"run with du_max = {ctrl.du_max:.4g} mm"
            try:
                path = sens.record_path(dataclasses.replace(self.scene, density=rho), self.schedule, ctrl,
                                        newton=self.newton, **self.options)
                if self._finite(path):
                    return path, attempts
                attempts.append((what, "a force that is not finite"))
            except _RUN_ERRORS as e:
                attempts.append((what, f"{type(e).__name__}: {e}"))
        raise DesignFailure(f"design evaluation {len(self.records) + 1}: every forward run failed "
                            f"({len(attempts)} attempts; the last: {attempts[-1][1]})", attempts)

    def evaluate(self, x, record: bool = True) -> dict:
        """The design ``x`` run, its objective and gradient (see the class); ``record``: keep it
        in ``records`` (False for the runs of a gradient check)."""
        x = self.density.check(x)
        key = (x.tobytes(), self.density.beta)
        if self._last is not None and self._last[0] == key:   # the same design again: its result
            rec = self._last[1]
            if record and rec["evaluation"] is None:
                rec = dict(rec, evaluation=len(self.records) + 1)
                self.records.append({k: v for k, v in rec.items() if k not in ("gradient", "path")})
                self._last = (key, rec)
            return rec
        t0 = time.perf_counter()
        try:
            path, attempts = self.forward(x)
        except DesignFailure as e:
            self.failures.extend({"evaluation": len(self.records) + 1, "attempt": a, "message": m, "recovered": False}
                                 for a, m in e.attempts)
            raise
        self.failures.extend({"evaluation": len(self.records) + 1, "attempt": a, "message": m, "recovered": True}
                             for a, m in attempts)
        t1 = time.perf_counter()
        g = sens.gradient(path, self.objective, wrt=("rho",))
        grad = self.density.chain(x, g_rho=g["rho"])
        t2 = time.perf_counter()
        if not (math.isfinite(g["value"]) and np.all(np.isfinite(grad))):
            raise DesignFailure(f"design evaluation {len(self.records) + 1}: the objective or its gradient is not "
                                "finite", [("adjoint", "not finite")])
        self._path = path
        rec = {"evaluation": len(self.records) + 1 if record else None, "value": float(g["value"]), "volume": self.density.volume(x),
               "beta": self.density.beta, "forward_s": t1 - t0, "adjoint_s": t2 - t1,
               "newton_iterations": path.newton_iterations, "steps": path.n_steps, "attempts": len(attempts)}
        if record:
            self.records.append(rec)
        out = dict(rec, gradient=grad, path=path)
        self._last = (key, out)
        return out

    def gradient_check(self, x, directions: int = 2, eps: float = 1e-4, seed: int = 0) -> list[dict]:
        """The adjoint's directional derivative dJ/dx . d against the central difference
        (J(x + eps d) - J(x - eps d)) / (2 eps), both runs replaying the load steps of the run at
        x, for ``directions`` random directions d (entries uniform in [-1, 1], seeded by ``seed``,
        shortened where x lies within eps of a bound so that x +- eps d stay in [0, 1]).
        Returns per direction the two numbers, their relative difference and the history points
        whose branch of the max differs between the two runs (a difference across such a switch
        is not a derivative)."""
        x = self.density.check(x)
        ev = self.evaluate(x, record=False)
        path, grad = ev["path"], ev["gradient"]
        rng = np.random.default_rng(seed)
        out = []
        for j in range(int(directions)):
            # entries in [-1, 1], shortened where x is within eps of a bound, so that x +- eps d stay in [0, 1]
            d = rng.uniform(-1.0, 1.0, x.size) * np.minimum(1.0, np.minimum(x, 1.0 - x) / eps)
            runs = [sens.replay(path, rho=self.density.rho(x + sgn * eps * d)) for sgn in (1.0, -1.0)]
            fd = (self.objective.value(runs[0]) - self.objective.value(runs[1])) / (2 * eps)
            adj = float(grad @ d)
            out.append({"direction": j, "adjoint": adj, "finite_difference": fd,
                        "relative_difference": abs(fd - adj) / max(abs(adj), 1e-300),
                        "switches": sens.active_set_changes(runs[0], runs[1])["history"]})
        path.activate()
        return out
