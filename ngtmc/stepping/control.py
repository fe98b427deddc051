"""Load schedules and the adaptive displacement control of Eqs. 19-20.

A :class:`Schedule` is a piecewise-linear history of the imposed displacement (mm) through
turning points, e.g. ``Schedule([0, 6.3, 6.0, 7.0])`` loads to 6.3 mm, unloads to 6 mm and reloads
to 7 mm. It is parametrised by a pseudo-time t, the accumulated |change of load| (mm), so that a
step size is a load increment on every segment and every turning point is a value of t that the
stepping lands on exactly.

:class:`AdaptiveStepControl` chooses the next increment

    du = s * du_max * exp(-k_u (W_f^i - W_f^{i-1}))                      (Eq. 20)

with W_f of Eq. 19 per unit thickness (N mm / mm = N), k_u in 1/N, a floor du_min, and a scale s
that halves on a failed step (down to du_min) and doubles back towards 1 after ``n_s`` successful
steps in a row.

The rule keeps no run state: its scale and count of successes are a :class:`ControlState` that
the simulation keeps and passes in.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Sequence

import numpy as np
from ngtmc.model import check_number

__all__ = ["Schedule", "AdaptiveStepControl", "ControlState", "attempt_info", "add_solve"]


class Schedule:
    """Piecewise-linear imposed displacement through turning points (mm), starting at 0.

    >>> Schedule([0, 6.3, 6, 7]).total_time  # 6.3 + 0.3 + 1.0
    7.6
    """

    def __init__(self, points: Sequence[float]):
        pts = np.asarray([float(p) for p in points], dtype=float)
        if pts.ndim != 1 or pts.size < 2:
            raise ValueError(f"Schedule needs at least two points (start 0 and an end), got {list(points)!r}")
        if not np.all(np.isfinite(pts)):
            raise ValueError(f"Schedule points must be finite numbers (mm), got {list(points)!r}")
        if pts[0] != 0.0:
            raise ValueError(f"Schedule must start at 0 mm (the unloaded state); it starts at {pts[0]!r}")
        if np.any(np.diff(pts) == 0.0):
            raise ValueError(f"Schedule has two equal consecutive points: {list(points)!r}")
        self.points = pts
        self.times = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(pts)))])

    @classmethod
    def monotonic(cls, final: float) -> "Schedule":
        """Load from 0 to ``final`` mm."""
        return cls([0.0, final])

    @property
    def total_time(self) -> float:
        """Total pseudo-time, mm of accumulated load change."""
        return float(self.times[-1])

    @property
    def turning_times(self) -> np.ndarray:
        return self.times[1:]

    def load(self, t: float) -> float:
        """Imposed displacement (mm) at pseudo-time t. Exact at every turning point."""
        i = int(np.searchsorted(self.times, t, side="right") - 1)
        i = min(max(i, 0), len(self.times) - 2)
        if t >= self.times[i + 1]:
            return float(self.points[i + 1])
        frac = (t - self.times[i]) / (self.times[i + 1] - self.times[i])
        return float(self.points[i] + frac * (self.points[i + 1] - self.points[i]))

    def next_turning_time(self, t: float, eps: float = 1e-14) -> float:
        for tt in self.turning_times:
            if tt > t + eps * max(1.0, abs(tt)):
                return float(tt)
        return self.total_time

    def __repr__(self):
        return f"Schedule({self.points.tolist()})"


@dataclass(frozen=True)
class ControlState:
    """Run state of :class:`AdaptiveStepControl`: the scale s of Eq. 20 (dimensionless, in
    (0, 1]) and the successful steps in a row since it last changed. A simulation owns it (and
    checkpoints it); the control is a settings object and keeps none."""

    scale: float = 1.0
    successes: int = 0

    def as_dict(self) -> dict:
        return {"scale": self.scale, "successes": self.successes}

    @classmethod
    def from_dict(cls, d: dict) -> "ControlState":
        return cls(scale=float(d["scale"]), successes=int(d["successes"]))


@dataclass(frozen=True)
class AdaptiveStepControl:
    """Step-size rule of Eq. 20 with halving on failure and doubling after successes.

    A settings object: it holds no run state, so one control may serve any number of simulations.
    The scale and the count of successes live in a :class:`ControlState` that the caller (the
    :class:`ngtmc.Simulation`) keeps and passes in; :meth:`accepted` and :meth:`failed` return the
    new state.

    Parameters
    ----------
    du_max : float
        Largest load increment, mm (> 0).
    k_u : float
        Sensitivity to the fracture-energy increment, 1/N (W_f per unit thickness); >= 0, 0 gives
        constant steps du_max.
    du_min : float
        Smallest increment, mm (> 0, <= du_max): the floor of Eq. 20, and the size below which a
        failing step gives up.
    n_s : int
        Successful steps after which the scale doubles again (>= 1). Under path following the scale
        doubles after every successful step (:data:`ngtmc.stepping.path.N_S`).
    """

    du_max: float
    k_u: float = 0.0
    du_min: float = 1e-8
    n_s: int = 5

    def __post_init__(self):
        for name, unit in (("du_max", "mm"), ("k_u", "1/N"), ("du_min", "mm"), ("n_s", "steps")):
            check_number(f"AdaptiveStepControl {name}", getattr(self, name), unit)
        if not (math.isfinite(self.du_max) and self.du_max > 0):
            raise ValueError(f"du_max = {self.du_max!r} mm is outside the allowed range: > 0")
        if not (math.isfinite(self.k_u) and self.k_u >= 0):
            raise ValueError(f"k_u = {self.k_u!r} 1/N is outside the allowed range: >= 0")
        if not (math.isfinite(self.du_min) and 0 < self.du_min <= self.du_max):
            raise ValueError(f"du_min = {self.du_min!r} mm is outside the allowed range (0, du_max = {self.du_max}]")
        if int(self.n_s) < 1:
            raise ValueError(f"n_s = {self.n_s!r} is outside the allowed range: >= 1")

    @staticmethod
    def initial_state() -> ControlState:
        """The state a run starts from: scale 1, no successes."""
        return ControlState()

    def proposal(self, delta_wf: float, state: ControlState = ControlState()) -> float:
        """Increment (mm) after an accepted step that raised W_f by ``delta_wf`` (N, per unit
        thickness), at the scale of ``state``."""
        du = state.scale * self.du_max * math.exp(-self.k_u * max(float(delta_wf), 0.0))
        return max(du, self.du_min)

    def accepted(self, state: ControlState, n_s: int | None = None) -> ControlState:
        """The state after a successful step: the scale doubles (up to 1) after ``n_s`` (default:
        the control's) successes in a row."""
        successes = state.successes + 1
        if successes >= (self.n_s if n_s is None else int(n_s)) and state.scale < 1.0:
            return ControlState(scale=min(1.0, 2.0 * state.scale), successes=0)
        return ControlState(scale=state.scale, successes=successes)

    def failed(self, state: ControlState, attempted: float) -> tuple[ControlState, float | None]:
        """The state after a failed attempt of size ``attempted`` (mm) (scale halved, successes
        reset), and the halved size to try next, or None when it would fall below du_min (the run
        cannot go on)."""
        new = ControlState(scale=max(state.scale / 2.0, 1e-300), successes=0)
        smaller = attempted / 2.0
        if smaller < self.du_min * (1 - 1e-12):
            return new, None
        return new, smaller


def attempt_info() -> dict:
    """A step attempt's ``info`` before any solve: Newton iterations, solve and assembly times
    (s), staggered passes and alpha projections, all zero."""
    return {"newton_iterations": 0, "solve_time": 0.0, "assembly_time": 0.0, "staggered_iterations": 0,
            "projected": 0}


def add_solve(info: dict, res):
    """Add a Newton result's iterations and times to a step's ``info``."""
    info["newton_iterations"] += res.iterations
    info["solve_time"] += res.solve_time
    info["assembly_time"] += res.assembly_time
