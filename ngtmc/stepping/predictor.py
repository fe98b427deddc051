"""The secant predictor of path following (rule 6 of :mod:`ngtmc.stepping.path`): the last two accepted
states of a run and their loads, and the predictor through them,

    x = x_n + r (x_n - x_{n-1}),        x = (u, alpha), alpha kept in [alpha_n, 1],

with r the ratio of the load or dissipation increments (at most 2), damped to r/2 or r/4 where
the full secant would invert an element (:data:`ngtmc.stepping.secant.SECANT_DAMPING`).

Units: mm (loads and u).
"""
from __future__ import annotations

import numpy as np

from ngtmc.stepping.secant import secant_displacement

__all__ = ["SecantPredictor"]


class SecantPredictor:
    """The last two accepted states (u, alpha) of a :class:`ngtmc.simulation.loop.Simulation` and
    their loads (mm), and the secant predictor through them. Starts from the solver's current
    state, with no state before it (no secant yet)."""

    def __init__(self, sim):
        self.sim = sim
        s = sim.solver
        #: the last accepted state (u, alpha) and its load, mm
        self.x_n = (s.u.vec.FV().NumPy().copy(), s.alpha.vec.FV().NumPy().copy())
        self.load_n = s.load
        #: the accepted state before it and its load (None before the second state)
        self.x_prev, self.load_prev = None, None

    def accepted(self):
        """The solver's current state was accepted: it becomes x_n, x_n becomes x_{n-1}."""
        s = self.sim.solver
        self.x_prev, self.load_prev = self.x_n, self.load_n
        self.x_n = (s.u.vec.FV().NumPy().copy(), s.alpha.vec.FV().NumPy().copy())
        self.load_n = s.load

    def last_load_increment(self) -> float:
        """lambda_n - lambda_{n-1} (mm); 0 before the second accepted state."""
        return self.load_n - self.load_prev if self.x_prev is not None else 0.0

    def set(self, ratio: float, load: float | None = None) -> float | None:
        """Set the solver's u and alpha to the secant predictor x_n + ratio (x_n - x_{n-1}) (alpha
        kept in [alpha_n, 1]), with the boundary values of ``load`` (default: the secant load
        lambda_n + ratio (lambda_n - lambda_{n-1})). Returns the load, or None (state unchanged)
        when there is no previous state, the ratio is outside (0, 2], or an element would invert."""
        if self.x_prev is None:
            return None
        s = self.sim.solver
        u_n, a_n = self.x_n
        u_p, a_p = self.x_prev
        if load is None:
            load = self.load_n + ratio * (self.load_n - self.load_prev)
        f = secant_displacement(s, u_n, u_p, ratio, load)
        if f is None:
            return None
        s.alpha.vec.FV().NumPy()[:] = np.clip(a_n + f * (a_n - a_p), a_n, 1.0)
        return load

    def chord(self, end: dict, end_load: float, fraction: float) -> float | None:
        """Set the solver's u and alpha on the chord from the last accepted state x_n to ``end``
        (a converged state of the same step whose load moved too far, with its load ``end_load``,
        mm): x_n + fraction (end - x_n), alpha kept in [alpha_n, 1], with the boundary values of
        the load on that chord. Returns that load, or None (state unchanged) where ``fraction`` is
        outside (0, 1) or an element would invert.

        Why: rule 3 of :mod:`ngtmc.stepping.path` solves such a step again at a smaller dD; from
        the secant predictor the quick 3D hemisphere's re-solves took up to 15 Newton iterations
        and a displacement relaxation each, the converged long step lies on the path it follows."""
        if not 0.0 < fraction < 1.0 or np.shape(end["u"]) != self.x_n[0].shape:
            return None
        s = self.sim.solver
        u_n, a_n = self.x_n
        uN = s.u.vec.FV().NumPy()
        keep = uN.copy()
        load = self.load_n + fraction * (float(end_load) - self.load_n)
        uN[:] = u_n + fraction * (np.asarray(end["u"]) - u_n)
        uN[s._dir_np] = s.dirichlet_target(load)[s._dir_np]
        if not (s.ranks.all_finite(uN) and s.min_J() > 0.0):
            uN[:] = keep
            return None
        s._r_valid = False
        s.alpha.vec.FV().NumPy()[:] = np.clip(a_n + fraction * (np.asarray(end["alpha"]) - a_n), a_n, 1.0)
        return load

    def states(self) -> list[dict]:
        """The accepted state before the last one, (u, alpha), as a partial state that a
        refinement transfers to the new mesh (:func:`ngtmc.adapt.bisection.refine`,
        :func:`ngtmc.adapt.remesh.move`); [] if none."""
        if self.x_prev is None:
            return []
        return [{"u": self.x_prev[0], "alpha": self.x_prev[1]}]

    def mesh_changed(self, before: dict, previous: list[dict] = ()):
        """After a refinement: ``before`` (the last accepted state) and ``previous`` (the
        :meth:`states`), both on the new mesh. The secant goes on through them; without
        ``previous`` it restarts from ``before``. The load of ``before`` is the caller's to set
        (it may have been settled below its own, :func:`ngtmc.adapt.carried_state.settle`)."""
        self.x_n = (np.array(before["u"], dtype=float), np.array(before["alpha"], dtype=float))
        if previous and self.x_prev is not None:
            self.x_prev = (np.array(previous[0]["u"], dtype=float), np.array(previous[0]["alpha"], dtype=float))
        else:
            self.x_prev, self.load_prev = None, None

    def get_state(self) -> dict:
        """The loads (JSON-able); the states are :meth:`get_arrays`."""
        return {"load_n": self.load_n, "load_prev": self.load_prev}

    def get_arrays(self) -> dict:
        """The last two accepted states (numpy arrays by name)."""
        out = {"path_u_n": self.x_n[0], "path_alpha_n": self.x_n[1]}
        if self.x_prev is not None:
            out.update(path_u_prev=self.x_prev[0], path_alpha_prev=self.x_prev[1])
        return out

    def set_state(self, st: dict, arrays: dict | None = None):
        """Restore :meth:`get_state` and :meth:`get_arrays`; without the arrays the predictor
        starts from the solver's current state, with no state before it."""
        arrays = arrays or {}
        s = self.sim.solver
        if "path_u_n" in arrays:
            self.x_n = (np.array(arrays["path_u_n"], dtype=float), np.array(arrays["path_alpha_n"], dtype=float))
            self.load_n = float(st["load_n"])
        else:
            self.x_n = (s.u.vec.FV().NumPy().copy(), s.alpha.vec.FV().NumPy().copy())
            self.load_n = s.load
        if "path_u_prev" in arrays:
            self.x_prev = (np.array(arrays["path_u_prev"], dtype=float), np.array(arrays["path_alpha_prev"], dtype=float))
            self.load_prev = float(st["load_prev"])
        else:
            self.x_prev, self.load_prev = None, None
