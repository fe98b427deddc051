"""The method of moving asymptotes (Svanberg 1987, 2002) from nlopt (``LD_MMA``), the optimiser of
the topology-optimisation literature, behind one call: :func:`mma` minimises an objective with
its gradient subject to inequality constraints with theirs, within bounds on every variable, and
records every evaluation. nlopt is the ``design`` extra (``pip install ngtmc[design]``)."""
from __future__ import annotations

from dataclasses import dataclass, field
import math
import time
from typing import Callable, Sequence

import numpy as np

__all__ = ["mma", "OptimisationResult"]

#: nlopt's result codes by name
_RESULTS = {1: "success", 2: "stopval reached", 3: "ftol reached", 4: "xtol reached", 5: "maxeval reached",
            6: "maxtime reached", -1: "failure", -2: "invalid arguments", -3: "out of memory",
            -4: "roundoff limited", -5: "forced stop"}


@dataclass
class OptimisationResult:
    """Outcome of :func:`mma`: the best design ``x`` and its ``objective``, the number of
    ``evaluations``, nlopt's ``status``, the wall time ``seconds`` (s), and ``history``: per
    evaluation its objective, constraint values and seconds."""

    x: np.ndarray
    objective: float
    evaluations: int
    status: str
    seconds: float
    history: list = field(default_factory=list)


def mma(objective: Callable, x0, lower=0.0, upper=1.0, constraints: Sequence[Callable] = (),
        max_evaluations: int = 100, xtol_rel: float = 1e-6, ftol_rel: float = 0.0,
        callback: Callable | None = None, initial_step: float | None = None) -> OptimisationResult:
    """Minimise ``objective(x) -> (value, gradient)`` subject to ``c(x) -> (value, gradient) <= 0``
    for every ``c`` of ``constraints``, with ``lower <= x <= upper`` (numbers or arrays), from
    ``x0``, by MMA. Stops after ``max_evaluations`` evaluations, or when the design moves by less
    than ``xtol_rel`` (relative) or the objective by less than ``ftol_rel`` (0: not used).
    ``callback(x, value, record)`` is called after every evaluation. ``initial_step``: the first
    distance of MMA's asymptotes from the design (nlopt's initial step, in the units of x): the
    first iterations move no variable further than about that (a move limit that MMA then adapts). An objective or constraint
    that returns a value or gradient that is not finite (a failed forward run) stops the
    optimisation with a RuntimeError naming the evaluation: a failed run is never accepted."""
    try:
        import nlopt
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("ngtmc.design.mma needs nlopt: pip install ngtmc[design] (or pip install nlopt)") from e
    x0 = np.asarray(x0, dtype=float).ravel().copy()
    n = x0.size
    if n == 0:
        raise ValueError("mma: x0 is empty")
    if int(max_evaluations) < 1:
        raise ValueError(f"mma: max_evaluations = {max_evaluations!r} must be >= 1")
    lo = np.broadcast_to(np.asarray(lower, dtype=float), (n,)).copy()
    hi = np.broadcast_to(np.asarray(upper, dtype=float), (n,)).copy()
    if np.any(lo > hi):
        raise ValueError("mma: a lower bound exceeds its upper bound")
    x0 = np.clip(x0, lo, hi)
    history: list[dict] = []
    best = {"value": math.inf, "x": x0.copy()}
    t0 = time.perf_counter()
    pending: dict = {}

    def checked(name, value, grad_out, grad):
        value = float(value)
        grad = np.asarray(grad, dtype=float).ravel()
        if not math.isfinite(value) or grad.shape != (n,) or not np.all(np.isfinite(grad)):
            raise RuntimeError(f"mma: evaluation {len(history) + 1}: {name} returned a value {value!r} or a "
                               f"gradient that is not finite or not of length {n} (a failed forward run?)")
        if grad_out.size:
            grad_out[:] = grad
        return value

    def f(x, grad_out):
        value, grad = objective(np.array(x))
        value = checked("the objective", value, grad_out, grad)
        record = {"objective": value, "constraints": [], "seconds": time.perf_counter() - t0}
        history.append(record)
        pending["record"] = record
        if value < best["value"]:
            best["value"], best["x"] = value, np.array(x)
        if callback is not None:
            callback(np.array(x), value, record)
        return value

    def wrap(i, c):
        def g(x, grad_out):
            value, grad = c(np.array(x))
            value = checked(f"constraint {i}", value, grad_out, grad)
            if "record" in pending:
                pending["record"]["constraints"].append(value)
            return value
        return g

    opt = nlopt.opt(nlopt.LD_MMA, n)
    opt.set_lower_bounds(lo)
    opt.set_upper_bounds(hi)
    opt.set_min_objective(f)
    for i, c in enumerate(constraints):
        opt.add_inequality_constraint(wrap(i, c), 1e-8)
    opt.set_maxeval(int(max_evaluations))
    if initial_step is not None:
        if not (math.isfinite(float(initial_step)) and float(initial_step) > 0):
            raise ValueError(f"mma: initial_step = {initial_step!r} must be a finite number > 0")
        opt.set_initial_step(np.full(n, float(initial_step)))
    if xtol_rel:
        opt.set_xtol_rel(float(xtol_rel))
    if ftol_rel:
        opt.set_ftol_rel(float(ftol_rel))
    try:
        x = opt.optimize(x0)
        status = _RESULTS.get(opt.last_optimize_result(), str(opt.last_optimize_result()))
        value = opt.last_optimum_value()
    except nlopt.RoundoffLimited:
        x, value, status = best["x"], best["value"], "roundoff limited"
    return OptimisationResult(x=np.asarray(x), objective=float(value), evaluations=len(history), status=status,
                              seconds=time.perf_counter() - t0, history=history)
